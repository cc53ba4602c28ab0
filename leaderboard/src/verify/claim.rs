//! One claimed episode against its re-enactment: the recording's actions replayed on the
//! shipped task from the seed's scene, then the journal's line re-derived field by field and the
//! recording message by message.
//!
//! What the re-enactment cannot know is taken from the claim: the wall times (checked finite and
//! not negative), the text of an error a policy or model server ended the episode with (only
//! where no action was refused; its outcome must then be one of those two), the recording's path
//! on the submitter's machine (it must name the recording), and the policy's `/stage` labels.

use super::{Claim, Reenact, ReenactOptions, differ, rel};
use compiler::Task;
use results::end::EpisodeEnd;
use results::episode::EpisodeResult;
use std::path::Path;

/// Re-enacts one claimed episode of `task` (as its run compiled it), writing the re-enactment's
/// recording to `out`; what differs from the claim, if anything.
pub(super) fn check(
    task: &Task,
    c: &Claim,
    root: &Path,
    out: &Path,
    reenact: &Reenact,
) -> Option<String> {
    let e = &c.claimed;
    let what = format!("{} seed {} (run {})", task.id, e.seed, e.run);
    let name = format!("{}_seed{}.mcap", task.id, e.seed);
    let path = c.run_dir.join(&name);
    let summary = match results::recording::read_recording(&path) {
        Ok(s) => s,
        Err(err) => {
            return Some(format!(
                "{what}: its recording {} does not read: {err}",
                rel(root, &path)
            ));
        }
    };
    // The actions, in the shipped task's robot order; nothing else of the recording is used.
    let steps = summary.actions.values().map(Vec::len).max().unwrap_or(0);
    let mut actions = vec![Vec::new(); steps];
    for r in &task.robots {
        let mine = summary.actions.get(&r.name).map_or(&[][..], Vec::as_slice);
        if mine.len() != steps {
            return Some(format!(
                "{what}: the recording has {} actions for robot `{}` and {steps} for another",
                mine.len(),
                r.name
            ));
        }
        for (k, a) in actions.iter_mut().enumerate() {
            a.extend_from_slice(&mine[k]);
        }
    }
    if let Some(other) = summary
        .actions
        .keys()
        .find(|k| !task.robots.iter().any(|r| &r.name == *k))
    {
        return Some(format!(
            "{what}: the recording has actions for `{other}`, no robot of the task"
        ));
    }
    let (image_every, image_size) = match frames_of(task, &summary) {
        Ok(f) => f,
        Err(why) => return Some(format!("{what}: its recording's camera frames: {why}")),
    };
    let ask = ReenactOptions {
        record: Some(out.to_path_buf()),
        image_every,
        image_size,
        claimed: e
            .error
            .clone()
            .map(|why| EpisodeEnd::claimed(e.outcome, why)),
    };
    let got = match reenact(task, e.seed, &actions, &ask) {
        Ok(g) => g,
        Err(err) => return Some(format!("{what}: cannot be re-enacted: {}", err.why)),
    };
    let mut differs = Vec::new();
    if e.error.is_none() {
        match &got.end {
            None => differs.push("the actions run out before the episode ends".into()),
            Some(end) => {
                if let Some(why) = end.error() {
                    differs.push(format!("the simulation refused an action: {why}"));
                }
            }
        }
    }
    if got.unused_actions > 0 {
        differs.push(format!(
            "{} actions recorded after the episode ended",
            got.unused_actions
        ));
    }
    if let Some(d) = journal_line(e, &got, &name) {
        differs.push(d);
    }
    if differs.is_empty() {
        // The journal agrees: the recording must be the one the episode writes.
        let stage = |topic: &str| topic == "/stage";
        match results::recording::compare::first_difference(&path, out, &stage) {
            Ok(None) => {}
            Ok(Some(d)) => {
                return Some(format!(
                    "{what}: its recording {} is not the re-enacted episode's: {d}",
                    rel(root, &path)
                ));
            }
            Err(err) => return Some(format!("{what}: the re-enacted recording: {err}")),
        }
        return None;
    }
    Some(format!(
        "{what}: re-enacted from its seed and recorded actions, {}",
        differs.join(", ")
    ))
}

/// The journal's line against the one the re-enactment derives; the first difference, by field.
fn journal_line(e: &EpisodeResult, got: &super::Reenacted, name: &str) -> Option<String> {
    // The re-enactment's end (a refused action's, else the claimed error, a policy's or a
    // server's, else the judge's), read as the harness reads an end.
    let end = got
        .end
        .clone()
        .unwrap_or_else(|| EpisodeEnd::judged(&got.verdict));
    let outcome = end.outcome();
    let error = end.error().map(str::to_string);
    let fine = |x: f64| x.is_finite() && x >= 0.0;
    if !fine(e.wall_time_s) || !fine(e.policy_time_s) {
        return Some(format!(
            "wall time {} s and policy time {} s (times are finite and not negative)",
            e.wall_time_s, e.policy_time_s
        ));
    }
    let recording = e
        .recording
        .clone()
        // The submitter's path, on whatever system ran it (either separator).
        .filter(|r| r.rsplit(['/', '\\']).next() == Some(name))
        .or_else(|| Some(name.to_string()));
    let derived = EpisodeResult {
        seed: e.seed,
        run: e.run,
        success: got.verdict.success,
        outcome,
        verdict: got.verdict.clone(),
        error,
        sim_time_s: got.time_s,
        control_steps: got.control_steps,
        wall_time_s: e.wall_time_s,
        policy_time_s: e.policy_time_s,
        trajectory_hash: got.hash.clone(),
        recording,
    };
    differ::first_difference(&differ::as_json(e), &differ::as_json(&derived))
}

/// The recording's camera cadence (control steps between frames) and size, as the re-enactment
/// must draw them: none, or every camera of the task at one size from step 0.
fn frames_of(
    task: &Task,
    s: &results::recording::RecordingSummary,
) -> Result<(u32, Option<[usize; 2]>), String> {
    let Some((_, first)) = s.images.iter().next() else {
        return Ok((0, None));
    };
    let Some((_, png)) = first.first() else {
        return Ok((0, None));
    };
    // The size from the PNG header, before anything is decoded or drawn at it.
    let (width, height) = png_size(png).ok_or("the first frame is not a PNG")?;
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "{width}x{height}; a camera frame is at most {MAX_SIDE} pixels a side"
        ));
    }
    let period = task.physics.timestep_s * task.physics.substeps as f64;
    let every = match first.as_slice() {
        [(a, _), (b, _), ..] => ((b - a) / period).round().clamp(1.0, u32::MAX as f64) as u32,
        _ => u32::MAX,
    };
    Ok((every, Some([width as usize, height as usize])))
}

/// The largest camera frame side a re-enactment draws (pixels): twice a 1080p frame's width,
/// far past any model's input, small enough that a forged size cannot exhaust the verifier.
const MAX_SIDE: u32 = 4096;

/// A PNG's width and height, read from its header (`IHDR`, the first chunk).
fn png_size(png: &[u8]) -> Option<(u32, u32)> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    let rest = png.strip_prefix(SIGNATURE)?;
    let ihdr = rest.get(4..16)?;
    if &ihdr[..4] != b"IHDR" {
        return None;
    }
    let side = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    Some((side(&ihdr[4..8]), side(&ihdr[8..12])))
}
