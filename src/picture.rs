//! `autobio render`: a seed's initial scene as one PNG (every task camera, then the view from
//! above, side by side), drawn without the expert or any episode, so an author sees the layout a
//! seed draws before an evaluation. The drawing is `runtime::picture`'s.

use crate::front::Front;
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub struct RenderArgs {
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
}

pub fn run(front: &Front, a: &RenderArgs) -> Result<ExitCode> {
    let task = front.load(&a.file)?;
    let frames = runtime::picture::initial_scene(&task, a.seed, a.size)?;
    let sheet = runtime::picture::side_by_side(&frames);
    let png = sheet.to_png().context("encoding the PNG")?;
    std::fs::write(&a.png, png).with_context(|| format!("writing {}", a.png.display()))?;
    let params = task.sample(a.seed).params;
    let drawn: Vec<String> = params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    outln!(
        "{}: {} seed {} ({}){}",
        a.png.display(),
        task.id,
        a.seed,
        sheet.camera.replace('+', ", "),
        if drawn.is_empty() {
            String::new()
        } else {
            format!("; drew {}", drawn.join(", "))
        }
    );
    Ok(ExitCode::SUCCESS)
}
