//! `autobio replay`: what a recording says (re-scored offline from its labware series), and on
//! request a re-simulation from its recorded state (`--simulate`) or its cameras redrawn from it
//! (`--render`). The work is `scoring::replay`; this prints it.

use anyhow::{Context, Result};
use scoring::replay::{self, FrameOptions, Recording};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `--detail` of `replay --render`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum DetailArg {
    /// Simplified meshes up to 320 pixels a side, full meshes above.
    Auto,
    Full,
    Simplified,
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct ReplayArgs {
    recording: PathBuf,
    /// Re-simulate the recorded actions from the recorded state and check every state and the
    /// trajectory hash (exit 1 if they differ)
    #[arg(long)]
    simulate: bool,
    /// The control step to re-simulate from (its recorded MuJoCo and instrument state)
    #[arg(long, default_value_t = 0, value_name = "K", requires = "simulate")]
    from_step: usize,
    /// Redraw the cameras from the recorded state into a new recording (no simulation)
    #[arg(long)]
    render: bool,
    /// Image size WxH (default: the recorded frames' size, else 224x224)
    #[arg(long, value_parser = parse_size, requires = "render")]
    size: Option<[usize; 2]>,
    /// Level of detail of the robots' meshes
    #[arg(long, value_enum, default_value = "auto", requires = "render")]
    detail: DetailArg,
    /// Draw every N-th control step (default: the recorded frames' cadence, else every step)
    #[arg(long, value_name = "N", requires = "render")]
    every: Option<usize>,
    /// The new recording (default: <recording>.render.mcap)
    #[arg(long, requires = "render")]
    out: Option<PathBuf>,
    /// Also write every frame as PNG into this folder
    #[arg(long, value_name = "DIR", requires = "render")]
    png: Option<PathBuf>,
    #[command(flatten)]
    renderer: crate::front::RendererArgs,
}

pub(crate) fn parse_size(s: &str) -> Result<[usize; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT (e.g. 224x224)"))?;
    let side = |v: &str| match v.parse::<usize>() {
        Ok(n) if (16..=4096).contains(&n) => Ok(n),
        _ => Err(format!("`{v}` is not a side between 16 and 4096 pixels")),
    };
    Ok([side(w)?, side(h)?])
}

pub(crate) fn run(a: &ReplayArgs) -> Result<ExitCode> {
    let doing = || format!("cannot replay {}", a.recording.display());
    let rec = Recording::open(&a.recording).with_context(doing)?;
    let mut ok = rescore(&rec);
    if a.simulate {
        ok &= simulate(&rec, a.from_step).with_context(doing)?;
    }
    if a.render {
        render(&rec, a).with_context(doing)?;
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn rescore(rec: &Recording) -> bool {
    let s = &rec.summary;
    let verdict =
        results::verdict::Judge::replay(&rec.task, &rec.instance.params, &s.labware_series);
    outln!(
        "{}: {} messages over {:.2} s",
        rec.path.display(),
        s.messages,
        s.duration_s
    );
    for (topic, n) in &s.topics {
        outln!("  {topic:<28} {n}");
    }
    outln!(
        "re-scored: {} (score {:.3})",
        if verdict.success {
            "success"
        } else {
            "failure"
        },
        verdict.score
    );
    for (i, st) in verdict.stages.iter().enumerate() {
        let done = st
            .completed_at_s
            .map(|t| format!("done at {t:.2} s"))
            .unwrap_or_else(|| "not done".into());
        outln!("  stage {} `{}`: {done}", i + 1, st.id);
        for p in &st.predicates {
            outln!(
                "    [{}] {:<28} value {:+.4} target {:+.4} tol {}",
                if p.holds { "x" } else { " " },
                p.text,
                p.value,
                p.target,
                p.tolerance
            );
        }
    }
    if let Some(v) = &s.verdict {
        let recorded = v["verdict"]["success"].as_bool();
        if recorded != Some(verdict.success) {
            outln!("note: the recorded verdict was {recorded:?}");
        }
    }
    verdict.success
}

fn simulate(rec: &Recording, from: usize) -> Result<bool> {
    let r = replay::resimulate(rec, from)?;
    outln!(
        "re-simulated: control steps {}..{} from the recorded state at step {from}",
        r.from_step,
        r.steps
    );
    outln!("  trajectory hash  {}", r.hash);
    outln!(
        "  recorded hash    {}",
        r.recorded_hash.as_deref().unwrap_or("(none)")
    );
    match r.first_divergence {
        None => outln!("  every state equal to the recorded one, bit for bit"),
        Some(k) => outln!("  the state first differs at control step {k}"),
    }
    outln!(
        "  {} (re-judged: {}, score {:.3})",
        if r.reproduced() {
            "reproduced"
        } else {
            "NOT reproduced"
        },
        if r.verdict.success {
            "success"
        } else {
            "failure"
        },
        r.verdict.score
    );
    Ok(r.reproduced())
}

fn default_out(recording: &Path) -> PathBuf {
    recording.with_extension("render.mcap")
}

fn render(rec: &Recording, a: &ReplayArgs) -> Result<()> {
    let out = a.out.clone().unwrap_or_else(|| default_out(&a.recording));
    if out == a.recording {
        anyhow::bail!("--out is the recording itself; choose another file");
    }
    let opts = FrameOptions {
        size: a.size,
        detail: match a.detail {
            DetailArg::Auto => None,
            DetailArg::Full => Some(robots::Detail::Full),
            DetailArg::Simplified => Some(robots::Detail::Simplified),
        },
        every: a.every,
        renderer: a.renderer.renderer(1),
    };
    // A bar on a terminal (indicatif draws nothing elsewhere): Blender takes seconds a frame.
    let bar = indicatif::ProgressBar::new(rec.steps() as u64).with_style(
        indicatif::ProgressStyle::with_template(
            "rendering {bar:30} {pos}/{len} steps, {per_sec}, {eta} left",
        )
        .expect("a valid template"),
    );
    let r = replay::render(rec, &opts, &out, a.png.as_deref(), |k, _| {
        bar.set_position(k as u64)
    })?;
    bar.finish_and_clear();
    outln!(
        "rendered: {} frames at {}x{} into {}{}",
        r.frames,
        r.size[0],
        r.size[1],
        r.out.display(),
        r.png_dir
            .map(|d| format!(" (PNG in {})", d.display()))
            .unwrap_or_default()
    );
    Ok(())
}
