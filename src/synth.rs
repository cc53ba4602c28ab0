//! `autobio synth`: random long-horizon protocols from the shipped protocols' steps, each one
//! proven and reach-checked, written as protocol files (the `synth` crate). Prints each file as it
//! is written, then what was found and dropped.

use anyhow::{Result, bail};
use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct SynthArgs {
    /// Protocol files, or folders of them, whose steps are recombined (those naming a scene file)
    #[arg(long, required = true, num_args = 1..)]
    from: Vec<PathBuf>,
    /// Steps per protocol: `N`, or `A..B` (each protocol draws its length, both ends included)
    #[arg(long, default_value = "4..8", value_parser = parse_steps)]
    steps: RangeInclusive<usize>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// How many protocols to write
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    count: u32,
    /// Folder for the protocol files (and a copy of each scene file they stand on)
    #[arg(long)]
    out: PathBuf,
    /// Candidates checked at once
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=256))]
    workers: u32,
}

/// Longest protocol `--steps` may ask for.
const MAX_STEPS: usize = 64;

fn parse_steps(s: &str) -> Result<RangeInclusive<usize>, String> {
    let bad = || format!("`{s}`: expected N or A..B with 1 <= A <= B <= {MAX_STEPS}, e.g. 4..8");
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (a, b.trim_start_matches('=')),
        None => (s, s),
    };
    let (a, b): (usize, usize) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a == 0 || a > b || b > MAX_STEPS {
        return Err(bad());
    }
    Ok(a..=b)
}

pub(crate) fn run(a: &SynthArgs) -> Result<ExitCode> {
    if a.out.is_file() {
        bail!("--out {}: a file, not a folder", a.out.display());
    }
    let opts = synth::Options {
        from: a.from.clone(),
        steps: a.steps.clone(),
        seed: a.seed,
        count: a.count as usize,
        out: a.out.clone(),
        workers: a.workers as usize,
    };
    let report = synth::synthesize(&opts, &|w| {
        errln!(
            "wrote {} ({} steps on {}, candidate {})",
            w.path.display(),
            w.steps,
            w.bench,
            w.tries
        );
    })?;
    for (file, why) in &report.skipped {
        errln!("skipped {file}: {why}");
    }
    for (bench, sources, shapes) in &report.benches {
        outln!("bench {bench}: {sources} source protocols, {shapes} step shapes");
    }
    let tried: usize = report.written.iter().map(|w| w.tries).sum();
    outln!(
        "{} protocols in {} ({} candidates drawn)",
        report.written.len(),
        a.out.display(),
        tried
    );
    for (why, n) in &report.rejected {
        outln!("  dropped {n}: {why}");
    }
    for (index, why) in &report.unmade {
        errln!("error: protocol {index} not made: {why}");
    }
    Ok(if report.unmade.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
