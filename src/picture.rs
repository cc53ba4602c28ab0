//! `autobio render`: a seed's initial scene as one PNG (every task camera, then the view from
//! above, side by side), drawn without the expert or any episode, so an author sees the layout a
//! seed draws before an evaluation. A perturbed task (its own `[perturb]` or `--perturb`) is drawn
//! twice, the clean scene above the perturbed one; `--renderer blender` adds Blender's frames of
//! the task cameras in a last row. The drawing is `runtime::picture`'s.

use crate::front::Front;
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct RenderArgs {
    /// The protocol or chain file
    file: PathBuf,
    /// The episode seed whose initial scene is drawn
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where to write the PNG
    #[arg(long)]
    png: PathBuf,
    /// Each view's size WxH
    #[arg(long, value_parser = crate::replay::parse_size, default_value = "320x240")]
    size: [usize; 2],
    #[command(flatten)]
    perturb: crate::front::PerturbArgs,
    /// With `--renderer blender`, the task cameras drawn by Blender in a row below the
    /// rasteriser's (the scene as the task gives it, perturbed when it is)
    #[command(flatten)]
    renderer: crate::front::RendererArgs,
}

pub(crate) fn run(front: &Front, a: &RenderArgs) -> Result<ExitCode> {
    let task = a.perturb.apply(front.load(&a.file)?)?;
    let clean = compiler::Task {
        perturb: None,
        ..task.clone()
    };
    let frames = runtime::picture::initial_scene(&clean, a.seed, a.size)?;
    let mut sheet = runtime::picture::side_by_side(&frames);
    let drawn = task.sample(a.seed).perturbation;
    if drawn.is_some() {
        let perturbed = runtime::picture::initial_scene(&task, a.seed, a.size)?;
        sheet = runtime::picture::stacked(&[sheet, runtime::picture::side_by_side(&perturbed)]);
    }
    let renderer = a.renderer.renderer(1);
    if renderer != runtime::cameras::Renderer::Raster {
        let photoreal = runtime::picture::initial_frames(&task, a.seed, a.size, renderer)?;
        sheet = runtime::picture::stacked(&[sheet, runtime::picture::side_by_side(&photoreal)]);
    }
    let png = sheet.to_png().context("encoding the PNG")?;
    std::fs::write(&a.png, png).with_context(|| format!("writing {}", a.png.display()))?;
    let params: Vec<String> = task
        .sample(a.seed)
        .params
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    let views = frames
        .iter()
        .map(|f| f.camera.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    outln!(
        "{}: {} seed {} ({views}){}",
        a.png.display(),
        task.id,
        a.seed,
        if params.is_empty() {
            String::new()
        } else {
            format!("; drew {}", params.join(", "))
        }
    );
    if let Some(d) = drawn {
        let json = serde_json::to_string(&d).context("describing the perturbation")?;
        outln!("clean above, perturbed below: {json}");
        let (said, told) = (
            clean.sample(a.seed).instruction,
            task.sample(a.seed).instruction,
        );
        if said != told {
            outln!("instruction: {said:?} -> {told:?}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
