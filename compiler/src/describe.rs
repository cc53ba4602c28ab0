//! Task sheets: a compiled task rendered as plain text for people (instruction, parameters,
//! randomisation, plan, checks, time limits), and the catalogue of labware kinds and primitives.
//! Generated from the task and the catalogues only, so it never disagrees with what runs.

use crate::params::{Domain, format_number};
use crate::predicates::Check;
use crate::primitives::CATALOGUE;
use crate::task::{Scoring, Task};
use std::fmt::Write;

/// The task sheet of a compiled task. Long on purpose: one block per section of the sheet, in the
/// order the sheet prints them, each a few lines of `writeln!` that read best in sequence.
pub fn describe(task: &Task) -> String {
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(w, "{} (v{}, {})", task.id, task.version, task.level);
    let _ = writeln!(w, "  instruction: {}", task.instruction);
    let _ = writeln!(w, "  source:      {}", task.source);
    let _ = writeln!(
        w,
        "  time limit:  {} s ({} Hz physics, {} Hz control)",
        format_number(task.time_limit_s),
        format_number(1.0 / task.physics.timestep_s),
        format_number(task.physics.control_hz())
    );
    let _ = writeln!(w, "\nscene");
    for r in &task.robots {
        let p = labware::frame::position(&r.base);
        let (_, _, yaw) = r.base.rotation.euler_angles();
        let turned = if yaw.abs() > 1e-9 {
            format!(", yaw {:.1} deg", yaw.to_degrees())
        } else {
            String::new()
        };
        let _ = writeln!(
            w,
            "  robot {:<10} {} at ({:.3}, {:.3}, {:.3}) m{turned}",
            r.name, r.model, p[0], p[1], p[2]
        );
    }
    for l in &task.labware {
        let kind = labware::kind(&l.kind);
        let mut state: Vec<String> = l.initial.iter().map(|(k, v)| format!("{k} {v}")).collect();
        if let Some(v) = &l.volume {
            match &l.liquid {
                Some(liquid) => state.push(format!("volume {v} of {liquid}")),
                None => state.push(format!("volume {v}")),
            }
        }
        state.extend(l.panel.iter().map(|(k, v)| format!("{k} {v}")));
        let place = match (&l.at, &l.held_by) {
            (Some(at), _) => format!("in {at}"),
            (None, Some(robot)) => format!("in {robot}'s hand"),
            (None, None) => {
                let p = labware::frame::position(&l.placement);
                format!("at ({:.3}, {:.3}, {:.3}) m", p[0], p[1], p[2])
            }
        };
        let sim = if kind.is_some_and(|k| k.simulated()) {
            ""
        } else {
            " [no simulation model yet]"
        };
        let _ = writeln!(
            w,
            "  labware {:<8} {} {place}{}{sim}",
            l.name,
            l.kind,
            if state.is_empty() {
                String::new()
            } else {
                format!(", {}", state.join(", "))
            }
        );
        for (part, pose) in &l.parts {
            let p = labware::frame::position(pose);
            let _ = writeln!(
                w,
                "    {part} lies apart at ({:.3}, {:.3}, {:.3}) m",
                p[0], p[1], p[2]
            );
        }
    }
    let _ = writeln!(w, "\nrandomisation (per episode, from the seed)");
    let mut any = false;
    for r in &task.robots {
        if let Some(j) = &r.joint_jitter {
            any = true;
            let ranges: Vec<String> = j
                .low
                .iter()
                .zip(&j.high)
                .map(|(l, h)| format!("[{l}, {h}]"))
                .collect();
            let _ = writeln!(w, "  {} joints + U{} rad", r.name, ranges.join(" "));
        }
    }
    for l in &task.labware {
        if l.xy_jitter_m > 0.0 || l.yaw_jitter_rad > 0.0 {
            any = true;
            let _ = writeln!(
                w,
                "  {} xy ± {} mm, yaw ± {:.1} deg",
                l.name,
                format_number(l.xy_jitter_m * 1000.0),
                l.yaw_jitter_rad.to_degrees()
            );
        }
        for (role, j) in &l.joint_jitter {
            any = true;
            let _ = writeln!(w, "  {}.{role} ± {} rad", l.name, format_number(*j));
        }
        if l.parts_radius_m > 0.0 {
            any = true;
            for part in l.parts.keys() {
                let _ = writeln!(
                    w,
                    "  {}.{part} in a disc of {} mm about where it lies",
                    l.name,
                    format_number(l.parts_radius_m * 1000.0)
                );
            }
        }
    }
    for p in &task.params {
        any = true;
        let domain = match &p.domain {
            Domain::Choice { values } => format!("one of {}", values.join(", ")),
            Domain::Int { low, high, step } if *step == 1 => format!("integer {low}..={high}"),
            Domain::Int { low, high, step } => format!("integer {low}..={high} step {step}"),
            Domain::Real { low, high, unit } => {
                format!(
                    "uniform {}..{} {unit}",
                    format_number(*low),
                    format_number(*high)
                )
            }
            Domain::Slot { holder, slots } => {
                format!("a slot of {holder} ({} candidates)", slots.len())
            }
            Domain::Opposite {
                holder, of, tubes, ..
            } => match tubes {
                2 => format!("the slot of {holder} opposite {{{of}}}"),
                k => format!("the slot of {holder} after {{{of}}} in a balanced load of {k}"),
            },
        };
        let excl = if p.exclude.is_empty() {
            String::new()
        } else {
            format!(", never {}", p.exclude.join(", "))
        };
        let _ = writeln!(w, "  {{{}}} {domain}{excl}", p.name);
    }
    if !any {
        let _ = writeln!(w, "  none");
    }
    for (i, s) in task.stages.iter().enumerate() {
        let _ = writeln!(
            w,
            "\nstage {} `{}` ({} s, {} scoring)",
            i + 1,
            s.id,
            format_number(s.time_limit_s),
            match s.scoring {
                Scoring::Binary => "binary",
                Scoring::Progress => "progress",
            }
        );
        let _ = writeln!(w, "  instruction: {}", s.instruction);
        let _ = writeln!(w, "  plan:");
        for (k, step) in s.plan.iter().enumerate() {
            let args: Vec<String> = step
                .args
                .iter()
                .map(|(a, v)| format!("{a} = {v}"))
                .collect();
            // As the scene marks kinds without a model: a step the expert cannot run yet.
            let expert = match crate::primitives::primitive(&step.primitive) {
                Some(p) if p.motions.is_none() => " [no expert motions yet]",
                _ => "",
            };
            let _ = writeln!(
                w,
                "    {}. {}({}) with {}{}{expert}",
                k + 1,
                step.primitive,
                args.join(", "),
                step.robot,
                if step.together {
                    format!(", together with step {k}")
                } else {
                    String::new()
                }
            );
        }
        let _ = writeln!(
            w,
            "  checks (every one held for {} s):",
            format_number(s.settle_s)
        );
        for p in &s.success {
            let tol = match &p.check {
                Check::State {
                    tolerance: Some(t), ..
                } => format!(" [{} = {}]", t.name, format_number(t.value)),
                Check::InSlot { tolerance: t, .. }
                | Check::Volume { tolerance: t, .. }
                | Check::Panel { tolerance: t, .. }
                | Check::Position { tolerance: t, .. } => {
                    format!(" [{} = {}]", t.name, format_number(t.value))
                }
                _ => String::new(),
            };
            let weight = if s.scoring == Scoring::Progress {
                format!(" (weight {})", format_number(p.weight))
            } else {
                String::new()
            };
            let _ = writeln!(w, "    - {}{tol}{weight}", p.text);
        }
    }
    out
}

/// One episode of the task as `seed` draws it: every robot's start joints, every item's
/// placement and jittered joints, the parameter values and the instructions.
pub fn example(task: &Task, seed: u64) -> String {
    let inst = task.sample(seed);
    let mut out = format!("\nepisode with seed {seed}\n");
    for (r, q) in task.robots.iter().zip(&inst.robot_q) {
        let joints: Vec<String> = q.iter().map(|v| format!("{v:.3}")).collect();
        let _ = writeln!(out, "  robot {} joints [{}] rad", r.name, joints.join(", "));
    }
    for (l, pose) in task.labware.iter().zip(&inst.labware_placement) {
        if let Some(at) = &l.at {
            let at = crate::params::render(at, &inst.params).unwrap_or_else(|_| at.clone());
            let _ = writeln!(out, "  labware {} in {at}", l.name);
            continue;
        }
        let t = pose.translation.vector;
        let (_, _, yaw) = pose.rotation.euler_angles();
        let _ = writeln!(
            out,
            "  labware {} at ({:.3}, {:.3}, {:.3}) m, yaw {:.1} deg",
            l.name,
            t.x,
            t.y,
            t.z,
            yaw.to_degrees()
        );
        if let Some(joints) = inst.labware_joints.get(&l.name) {
            for (role, offset) in joints {
                let _ = writeln!(
                    out,
                    "    {role} starts {offset:+.4} rad off its declared angle"
                );
            }
        }
    }
    for (k, v) in &inst.params {
        let _ = writeln!(out, "  {{{k}}} = {v}");
    }
    let _ = writeln!(out, "  instruction: {}", inst.instruction);
    if task.stages.len() > 1 {
        for (i, s) in inst.stage_instructions.iter().enumerate() {
            let _ = writeln!(out, "  stage {}: {s}", i + 1);
        }
    }
    out
}

/// Examples of the lab vocabulary, each a passage of a shipped protocol that compiles (the test
/// below finds each in its file; the goldens compile the files): primitive or language word, the
/// protocol, the passage.
pub const EXAMPLES: &[(&str, &str, &str)] = &[
    (
        "spin",
        "protocols/lab/spin.toml",
        "do = \"spin\"\non = \"centrifuge\"\nspeed = \"12000 rpm\"\nduration = \"10 min\"\nwith = \"arm\"",
    ),
    (
        "thermocycle",
        "protocols/lab/pcr_run.toml",
        "do = \"thermocycle\"\non = \"cycler\"\nprofile = \"95 °C 30 s, 30 x [95 °C 15 s, 55 °C 30 s, 68 °C 1 min], 68 °C 5 min, 4 °C 1 min\"\nwith = \"arm\"",
    ),
    (
        "incubate",
        "protocols/lab/incubation_series.toml",
        "do = \"incubate\"\non = \"mixer\"\ntemperature = \"56 °C\"\nspeed = \"1400 rpm\"\nduration = \"10 min\"\nwith = \"arm\"",
    ),
    (
        "wait",
        "protocols/lab/heat_shock.toml",
        "do = \"wait\"\nduration = \"30 s\"\nwith = \"arm\"",
    ),
    (
        "for_each",
        "protocols/lab/miniprep_spins.toml",
        "[[steps]]\nfor_each = { tube = [\"lysate\", \"counterweight\"], slot = [\"{first}\", \"{balance}\"] }\n\n[[steps.body]]\ndo = \"pick\"\non = \"{tube}\"\nwith = \"arm\"",
    ),
    (
        "repeat",
        "protocols/lab/miniprep_spins.toml",
        "[[steps]]\nrepeat = 2\n\n[[steps.body]]\ndo = \"spin\"",
    ),
    (
        "time constraint",
        "protocols/lab/heat_shock.toml",
        "\"cells in mixer.{well} for 30 s to 45 s\"",
    ),
    (
        "balances",
        "protocols/lab/miniprep_spins.toml",
        "[params.balance]\nslot = \"centrifuge\"\nbalances = \"first\"",
    ),
    (
        "within",
        "protocols/lab/heat_shock.toml",
        "to = \"ice.A1\"\nwithin = \"60 s\"\nafter = \"shock\"",
    ),
    (
        "x g",
        "protocols/lab/miniprep_spins.toml",
        "speed = \"17900 x g\"",
    ),
    (
        "run state",
        "protocols/lab/pcr_run.toml",
        "\"cycler.run is done\"",
    ),
    (
        "invert",
        "protocols/lab/mix_by_inversion.toml",
        "do = \"invert\"\non = \"lysate\"\ntimes = 4\nwith = \"arm\"",
    ),
    (
        "inverted",
        "protocols/lab/mix_by_inversion.toml",
        "\"lysate inverted 4 times\"",
    ),
    (
        "liquid",
        "protocols/lab/dilution.toml",
        "state = { cap = \"off\", volume = \"20 mL\", liquid = \"pbs_10x\" }",
    ),
    (
        "volume of",
        "protocols/lab/dilution.toml",
        "\"diluted.volume of pbs_10x = 500 µL\"",
    ),
];

fn write_example(w: &mut String, word: &str) {
    for (_, file, text) in EXAMPLES.iter().filter(|(name, ..)| *name == word) {
        let _ = writeln!(w, "      example ({file}):");
        for line in text.lines() {
            let _ = writeln!(w, "        {line}");
        }
    }
}

/// The catalogues: every labware kind and lab primitive.
pub fn catalogue() -> String {
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(w, "lab primitives (every one also takes `with = <robot>`)");
    for p in CATALOGUE {
        let expert = if p.motions.is_some() {
            ""
        } else {
            " [no expert motions yet]"
        };
        let takes_on = p.args.iter().any(|a| a.name == "on");
        let taken = if takes_on && !labware::KINDS.iter().any(|k| k.supports(p.name)) {
            " [no labware kind takes it yet]"
        } else {
            ""
        };
        let expert = format!("{expert}{taken}");
        let _ = writeln!(w, "  {}{expert}", p.signature());
        let _ = writeln!(w, "      {}", p.description);
        let _ = writeln!(w, "      needs:  {}", p.requires);
        let _ = writeln!(w, "      leaves: {}", p.leaves);
        write_example(w, p.name);
    }
    let _ = writeln!(w, "\nlanguage (docs/protocol-language.md)");
    for (word, what) in [
        (
            "for_each",
            "a step running its `[[steps.body]]` once per value of a list or a holder's slots",
        ),
        ("repeat", "a step running its `[[steps.body]]` N times"),
        (
            "time constraint",
            "a predicate ending `for <t> to <t>`, `for at most <t>` or `for at least <t>`: held that long in total",
        ),
        (
            "balances",
            "a slot parameter completing an evenly spaced rotor load after an earlier one (`tubes = N`, default 2: the slot across)",
        ),
        (
            "within",
            "a step's `within = <t>` (with `after = <step id>`, else of the step before): its outcome at most that long after the other step's",
        ),
        (
            "x g",
            "a spin's `speed` as a force (`16000 x g`), turned into rpm at the rotor's radius",
        ),
        (
            "run state",
            "`<instrument>.run is idle | running | done` (or `was`)",
        ),
        (
            "inverted",
            "`<item> inverted <n> times`: turned upside down and back at least n times in the stage (the judge counts)",
        ),
        (
            "liquid",
            "a container's start `state = { volume = <v>, liquid = <name> }`: a named liquid loaded (Opentrons' `loadLiquid`)",
        ),
        (
            "volume of",
            "`<container>.volume of <liquid> >= <v>`: how much of a named liquid it holds (moved in proportion)",
        ),
    ] {
        let _ = writeln!(w, "  {word}: {what}");
        write_example(w, word);
    }
    let _ = writeln!(w, "\nlabware kinds");
    for k in labware::KINDS {
        let sim = if k.simulated() {
            ""
        } else {
            " [no simulation model yet]"
        };
        let _ = writeln!(w, "  {}{sim}", k.name);
        let _ = writeln!(w, "      {}", k.description);
        if let Some(uri) = k.definition {
            let _ = writeln!(
                w,
                "      geometry from the published definition {uri} (opentrons-shared-data)"
            );
        }
        let model = labware::Model::for_kind(k.name);
        for p in k.parts {
            // The start states the simulation model cannot set up yet (W0007).
            let unsimulated: Vec<&str> = p
                .initial
                .iter()
                .copied()
                .filter(|st| {
                    let one = [(p.part.to_string(), st.to_string())].into_iter().collect();
                    model
                        .clone()
                        .map(|m| m.for_start(&one))
                        .as_ref()
                        .and_then(|m| m.instrument())
                        .is_some_and(|m| m.unsupported_start(&one).is_some())
                })
                .collect();
            let note = if unsimulated.is_empty() {
                String::new()
            } else {
                format!("; not simulated yet: {}", unsimulated.join(" | "))
            };
            let _ = writeln!(
                w,
                "      part {}: {} (may start {}{note})",
                p.part,
                p.states.join(" | "),
                p.initial.join(" | ")
            );
        }
        if let Some(s) = k.slots {
            let _ = writeln!(
                w,
                "      slots: {}, take {}",
                s.layout.describe(),
                s.accepts.join(", ")
            );
        }
        if let Some(c) = k.capacity_ul {
            let _ = writeln!(w, "      holds up to {} µL", format_number(c));
        }
        for p in k.panel {
            let set_by = match p.dial {
                Some(knob) => format!(
                    "set with the dial `{knob}`, its notches {} {} apart (a target goes to the nearest), starts at its stop",
                    format_number((p.step * 10.0).round() / 10.0),
                    p.unit
                ),
                None => format!(
                    "in steps of {}, starts {}",
                    format_number(p.step),
                    format_number(p.initial)
                ),
            };
            let _ = writeln!(
                w,
                "      panel {}: {}..{} {} {set_by}",
                p.name,
                format_number(p.min),
                format_number(p.max),
                p.unit,
            );
        }
        if !k.buttons.is_empty() {
            let names: Vec<&str> = k.buttons.iter().map(|b| b.name).collect();
            let _ = writeln!(w, "      buttons: {}", names.join(", "));
        }
        if !k.tolerances.is_empty() {
            let t: Vec<String> = k
                .tolerances
                .iter()
                .map(|(n, v)| format!("{n} = {}", format_number(*v)))
                .collect();
            let _ = writeln!(w, "      tolerances: {}", t.join(", "));
        }
        if !k.primitives.is_empty() {
            let _ = writeln!(w, "      primitives: {}", k.primitives.join(", "));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_catalogue_says_what_can_be_simulated_and_demonstrated() {
        let text = super::catalogue();
        let line = |start: &str| {
            text.lines()
                .find(|l| l.trim_start().starts_with(start))
                .unwrap_or_else(|| panic!("no `{start}` line"))
                .to_string()
        };
        assert!(!line("pick(").contains("no expert motions"));
        assert!(line("hand_over(").contains("[no expert motions yet]"));
        assert_eq!(line("tube_50ml").trim(), "tube_50ml");
        assert!(!line("thermal_mixer").contains("[no simulation model yet]"));
        assert!(!line("set_parameter(").contains("no expert motions"));
        assert!(!line("vortex_mixer").contains("[no simulation model yet]"));
        assert!(!line("pipette").contains("[no simulation model yet]"));
    }

    /// Every example the catalogue shows is a passage of the shipped protocol it names, which
    /// compiles (the goldens hold every shipped protocol to it).
    #[test]
    fn every_example_is_in_its_shipped_protocol() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for (word, file, text) in super::EXAMPLES {
            let source = std::fs::read_to_string(root.join(file)).unwrap();
            assert!(source.contains(text), "{word}: not in {file}:\n{text}");
            let (task, diags) = crate::compile_source(&source, file);
            assert!(task.is_some(), "{file}: {diags:?}");
        }
        let text = super::catalogue();
        for word in [
            "spin(",
            "thermocycle(",
            "incubate(",
            "wait(",
            "for_each:",
            "repeat:",
            "within:",
            "x g:",
            "balances:",
        ] {
            let at = text.find(word).unwrap_or_else(|| panic!("no {word}"));
            assert!(text[at..].contains("example ("), "{word}");
        }
    }
}
