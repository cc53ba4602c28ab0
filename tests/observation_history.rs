//! The earlier frame a policy asks for (`Needs::history_steps`, RDT's image history) is the
//! frame of exactly that many control steps before the query: with the history as long as the
//! chunk, it is the last query's frame byte for byte; shorter, it is a later frame.

use crate::common;

use policy::{Needs, Observation, Policy, PolicyError};

/// One query's frames: every camera's current image and earlier image (RGB bytes).
type Frames = (Vec<Vec<u8>>, Vec<Vec<u8>>);

/// The expert's recorded actions, `chunk` at a time, asking for images and `history` steps of history;
/// keeps every query's current and earlier frames.
struct Chunked {
    inner: Box<dyn Policy>,
    buffer: Vec<Vec<f64>>,
    chunk: usize,
    history: u32,
    seen: Vec<Frames>,
}

impl Policy for Chunked {
    fn name(&self) -> String {
        "chunked expert".into()
    }
    fn needs(&self) -> Needs {
        Needs {
            image_size: Some([64, 64]),
            history_steps: self.history,
            environment_state: false,
        }
    }
    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let frames = |imgs: &[results::Image]| imgs.iter().map(|i| i.rgb.clone()).collect();
        self.seen.push((frames(obs.images), frames(obs.previous)));
        if self.buffer.is_empty() {
            self.buffer = self.inner.act(obs)?;
        }
        let n = self.chunk.min(self.buffer.len());
        Ok(self.buffer.drain(..n).collect())
    }
}

fn queries(chunk: usize, history: u32) -> Vec<Frames> {
    let task = common::compile("protocols/thermal_cycler/close_lid.toml");
    let (instance, scene) = common::scene(&task, 0);
    // The expert answers one action per query; its recording replays them all at once, so the
    // chunks here are exactly `chunk` long.
    let dir = common::scratch(&format!("history-{chunk}-{history}"));
    let recording = dir.join("expert.mcap");
    let mut expert = scoring::policies::make("expert", &task, &scene, &instance).unwrap();
    let opts = scoring::episode::EpisodeOptions {
        record: Some(recording.clone()),
        image_every: 0,
        ..Default::default()
    };
    scoring::episode::run_episode(&task, &scene, &instance, expert.as_mut(), &opts).unwrap();
    let mut p = Chunked {
        inner: Box::new(
            scoring::policies::ReplayPolicy::new(&recording, &task, &instance).unwrap(),
        ),
        buffer: Vec::new(),
        chunk,
        history,
        seen: Vec::new(),
    };
    let r = scoring::episode::run_episode(&task, &scene, &instance, &mut p, &Default::default())
        .unwrap();
    assert!(r.success, "{r:?}");
    p.seen
}

#[test]
fn history_as_long_as_the_chunk_is_the_last_querys_frame() {
    let seen = queries(8, 8);
    assert!(seen.len() > 20);
    assert_eq!(
        seen[0].1, seen[0].0,
        "the first query repeats its current frame"
    );
    let mut moved = 0;
    for q in 1..seen.len() {
        assert_eq!(seen[q].1, seen[q - 1].0, "query {q}");
        moved += (seen[q].0 != seen[q - 1].0) as usize;
    }
    assert!(
        moved > 10,
        "the arm must move between queries for this to mean anything"
    );
}

#[test]
fn shorter_history_is_a_later_frame() {
    let seen = queries(8, 1);
    let later = (1..seen.len())
        .filter(|&q| seen[q].1 != seen[q - 1].0)
        .count();
    let moved = (1..seen.len())
        .filter(|&q| seen[q].0 != seen[q - 1].0)
        .count();
    assert!(moved > 10, "the arm must move between queries");
    assert!(
        later >= moved * 9 / 10,
        "one step before the query is not the last query's frame while the arm moves: {later} of {moved}"
    );
    assert!(
        (1..seen.len()).any(|q| seen[q].1 != seen[q].0),
        "nor the current frame"
    );
}
