//! One episode being captured for a dataset: an observer of the episode's environment. Every control step's
//! state and action are kept; every camera's frame streams into its own staged video and
//! histogram. Nothing reaches the dataset until the writer commits the capture.

use crate::DatasetError;
use crate::parquet::Frame;
use crate::stats::ImageStats;
use crate::video::{Codec, VideoWriter};
use results::Image;
use results::environment_state::EnvironmentState;
use runtime::{Env, ObserveError, Observer};
use std::path::PathBuf;

pub struct Capture {
    pub(crate) dir: PathBuf,
    pub(crate) task_id: String,
    pub(crate) seed: u64,
    pub(crate) rows: Vec<Frame>,
    /// Capture the task's environment state too (made from the env's task on the first step).
    environment_state: Option<Option<EnvironmentState>>,
    pub(crate) videos: Vec<VideoWriter>,
    pub(crate) images: Vec<ImageStats>,
    size: [usize; 2],
    error: Option<DatasetError>,
    /// What the episode's perturbations drew (`compiler::perturb::Drawn` as JSON), if any.
    pub(crate) perturbation: Option<serde_json::Value>,
    /// Who drew the frames and with what settings, when not the rasteriser
    /// (`runtime::cameras::Renderer::describe`).
    pub(crate) renderer: Option<serde_json::Value>,
}

impl Capture {
    pub(crate) fn new(
        dir: PathBuf,
        cameras: usize,
        size: [usize; 2],
        fps: u32,
        codec: Codec,
        environment_state: bool,
    ) -> Result<Capture, DatasetError> {
        if dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|e| DatasetError::io("clear", &dir, e))?;
        }
        std::fs::create_dir_all(&dir).map_err(|e| DatasetError::io("create", &dir, e))?;
        let videos = (0..cameras)
            .map(|k| {
                VideoWriter::create(
                    &dir.join(format!("camera{k}.mp4")),
                    size[0],
                    size[1],
                    fps,
                    codec,
                )
            })
            .collect::<Result<_, _>>()?;
        Ok(Capture {
            dir,
            task_id: String::new(),
            seed: 0,
            rows: Vec::new(),
            environment_state: environment_state.then_some(None),
            videos,
            images: vec![ImageStats::default(); cameras],
            size,
            error: None,
            perturbation: None,
            renderer: None,
        })
    }

    /// The first failure while capturing (a video that could not be written), if any.
    pub(crate) fn take_error(&mut self) -> Option<DatasetError> {
        self.error.take()
    }

    /// Throws the capture away (a failed episode).
    pub fn discard(self) {
        for v in self.videos {
            v.finish().ok();
        }
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

impl Capture {
    /// One control step: the state the action acts on (the robots', and the environment's
    /// when the dataset has it, else empty), the action, every camera's frame.
    pub fn push(
        &mut self,
        state: &[f64],
        environment_state: &[f64],
        action: &[f64],
        images: &[Image],
    ) -> Result<(), DatasetError> {
        let f = |v: &[f64]| v.iter().map(|&x| x as f32).collect();
        self.rows.push(Frame {
            state: f(state),
            environment_state: f(environment_state),
            action: f(action),
        });
        for (k, img) in images.iter().enumerate() {
            self.images[k].add(&img.rgb);
            self.videos[k].push(&img.rgb)?;
        }
        Ok(())
    }

    /// Records what the episode's perturbations drew, for the dataset's commit record.
    pub fn set_perturbation(&mut self, drawn: Option<&compiler::perturb::Drawn>) {
        self.perturbation = drawn.and_then(|d| serde_json::to_value(d).ok());
    }

    /// Records who draws the frames (Blender and its settings), for the dataset's commit record;
    /// the rasteriser is recorded as nothing, as datasets before photoreal frames were.
    pub fn set_renderer(&mut self, renderer: &runtime::cameras::Renderer) {
        self.renderer = match renderer {
            runtime::cameras::Renderer::Raster => None,
            r => Some(r.describe()),
        };
    }

    /// Whether this capture keeps the environment state.
    pub fn wants_environment_state(&self) -> bool {
        self.environment_state.is_some()
    }

    /// The frame size this capture's videos take.
    pub fn image_size(&self) -> [usize; 2] {
        self.size
    }
}

/// A capture watches an episode: every control step's state, action and frames.
impl Observer for Capture {
    fn before_step(&mut self, env: &mut Env, action: &[f64]) -> Result<(), ObserveError> {
        if self.rows.is_empty() {
            self.set_perturbation(env.instance().perturbation.as_ref());
        }
        let state = env.episode().state();
        let environment = match &mut self.environment_state {
            Some(layout) => env
                .environment_state(layout.get_or_insert_with(|| EnvironmentState::of(env.task()))),
            None => Vec::new(),
        };
        // A dataset without cameras (state observations only) draws nothing.
        let frames = if self.videos.is_empty() {
            &[]
        } else {
            env.frames()?
        };
        if let Err(e) = self.push(&state, &environment, action, frames) {
            let why = e.to_string();
            self.error.get_or_insert(e);
            return Err(ObserveError::Own(why.into()));
        }
        Ok(())
    }
}
