//! What every subcommand that reads protocols shares: the chain root and colour choice, and
//! loading a protocol or chain into a task (its diagnostics shown when it has errors). The
//! subcommands that run episodes load through [`Front::load_to_run`], which also shows `check`'s
//! warnings and refuses a trivial task (W0001: its success holds before the first step) unless
//! the user allows it.

use crate::diagnostics;
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

pub(crate) struct Front {
    pub root: Option<PathBuf>,
    pub color: bool,
}

impl Front {
    /// Checks a protocol or chain file and returns its task, or shows its diagnostics and fails.
    pub(crate) fn load(&self, path: &Path) -> Result<compiler::Task> {
        self.checked(path).map(|(_, task)| task)
    }

    /// The file checked, with its task; its diagnostics shown and an error when it has errors.
    fn checked(&self, path: &Path) -> Result<(compiler::Checked, compiler::Task)> {
        let checked = compiler::check_file(path, self.root.as_deref())?;
        let errors = checked.diagnostics.iter().any(|d| d.is_error());
        match checked.task.clone() {
            Some(t) if !errors => Ok((checked, t)),
            None if !errors => bail!(
                "{} is a scene file, not a task: protocols stand in it with `scene = \"..\"`",
                checked.file
            ),
            _ => {
                err!("{}", diagnostics::render_all(&checked, self.color));
                let name = &checked.file;
                bail!("{name} has errors; run `autobio check {name}`")
            }
        }
    }

    /// Loads every file, stopping at the first with errors.
    pub(crate) fn load_all(&self, paths: &[PathBuf]) -> Result<Vec<compiler::Task>> {
        paths.iter().map(|p| self.load(p)).collect()
    }

    /// Loads a protocol to run episodes of: its errors as [`Front::load`]; its warnings shown
    /// (what `check` would print); a task whose success already holds at the start (W0001)
    /// refused unless `allow_trivial`, since a motionless robot would pass it.
    pub(crate) fn load_to_run(&self, path: &Path, allow_trivial: bool) -> Result<compiler::Task> {
        let (checked, task) = self.checked(path)?;
        if checked.diagnostics.is_empty() {
            return Ok(task);
        }
        err!("{}", diagnostics::render_all(&checked, self.color));
        if checked.trivial_at().is_some() && !allow_trivial {
            let name = &checked.file;
            bail!(
                "{name}: its success already holds before the first step (W0001, for the \
                 parameter values its note names), so a robot that does nothing passes it; state \
                 a round trip with `was` (`cycler.lid was open`) or as a chain, or pass \
                 --allow-trivial to run it anyway"
            )
        }
        Ok(task)
    }

    /// [`Front::load_to_run`] for every file, stopping at the first refused.
    pub(crate) fn load_all_to_run(
        &self,
        paths: &[PathBuf],
        allow_trivial: bool,
    ) -> Result<Vec<compiler::Task>> {
        paths
            .iter()
            .map(|p| self.load_to_run(p, allow_trivial))
            .collect()
    }
}

/// `--perturb DIM[:STRENGTH]`, for the subcommands that run or draw episodes.
#[derive(Clone, Debug, Default, clap::Args)]
pub(crate) struct PerturbArgs {
    /// Perturb every episode along a dimension at strength 1 (mild, the default) or 2 (strong):
    /// light, material, camera, noise, language, robot_start, layout or distractors (`--perturb camera:2`;
    /// repeat for more; over the task's own `[perturb]`; docs/robustness.md)
    #[arg(long = "perturb", value_name = "DIM[:STRENGTH]")]
    pub presets: Vec<compiler::perturb::Preset>,
}

impl PerturbArgs {
    /// The task with the presets over its own perturbations, its id naming them
    /// (`tube.pick_up@camera-2+noise-1`, so that its results never mix with the clean task's);
    /// refused where a preset would break it (a camera off the work, no room for distractors).
    pub(crate) fn apply(&self, task: compiler::Task) -> Result<compiler::Task> {
        if self.presets.is_empty() {
            return Ok(task);
        }
        let mut t = task.with_perturb(&compiler::perturb::Preset::combine(&self.presets));
        let named: Vec<String> = self
            .presets
            .iter()
            .map(|p| format!("{}-{}", p.dimension, p.strength))
            .collect();
        t.id = format!("{}@{}", t.id, named.join("+"));
        refuse_problems(&t)?;
        Ok(t)
    }
}

/// Refuses a task whose perturbations would break it (`compiler::perturb::problems`).
pub(crate) fn refuse_problems(task: &compiler::Task) -> Result<()> {
    let problems = compiler::perturb::problems(task);
    if problems.is_empty() {
        return Ok(());
    }
    bail!(
        "{}: its perturbations cannot be run: {}",
        task.id,
        problems.join("; ")
    )
}

/// `--renderer` and Blender's settings, for the subcommands that draw frames into recordings and
/// datasets (docs/photoreal.md).
#[derive(Clone, Debug, clap::Args)]
pub(crate) struct RendererArgs {
    /// Who draws the cameras: `mujoco` (the rasteriser, what models are scored on) or `blender`
    /// (photoreal, Cycles or Eevee through the `bpy` wheel `make setup` installs)
    #[arg(long, value_enum, default_value = "mujoco")]
    pub renderer: RendererArg,
    /// Blender's engine
    #[arg(long, value_enum, default_value = "cycles")]
    pub engine: EngineArg,
    /// Blender's samples a pixel
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub samples: u32,
    /// No OpenImageDenoise after Cycles' samples
    #[arg(long)]
    pub no_denoise: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum RendererArg {
    Mujoco,
    Blender,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum EngineArg {
    Cycles,
    Eevee,
}

impl RendererArgs {
    /// The renderer, Blender's threads shared among `workers` episodes at once.
    pub(crate) fn renderer(&self, workers: usize) -> runtime::cameras::Renderer {
        use runtime::blender::{Engine, Settings};
        match self.renderer {
            RendererArg::Mujoco => runtime::cameras::Renderer::Raster,
            RendererArg::Blender => {
                let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
                runtime::cameras::Renderer::Blender(Settings {
                    engine: match self.engine {
                        EngineArg::Cycles => Engine::Cycles,
                        EngineArg::Eevee => Engine::Eevee,
                    },
                    samples: self.samples,
                    denoise: !self.no_denoise,
                    threads: (cores / workers.max(1)).max(1),
                })
            }
        }
    }
}
