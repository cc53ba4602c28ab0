//! Issue 50: Autoprotocol, and the lab languages' own tools. Documents written by
//! autoprotocol-python (Strateos' library, installed by `make setup`) import through the real
//! CLI, check, and the expert carries them out; one that spins and incubates is refused at those
//! instructions. `autobio export --to autoprotocol` writes an imported protocol back, and the
//! round trip import -> export -> import gives the same protocol and the same task. The complete
//! documents among the library's own documentation examples import or are refused with a
//! diagnostic naming the instruction or ref. Opentrons protocols written with its Python API and
//! analysed by Opentrons' own analyzer import the same way. Faulty Autoprotocol files give their
//! code and place; thousands of mutated ones never panic.

use super::import::{At, body, import_mutated, path, refused};
use crate::common;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs one of tests/lab_languages' scripts with the lab languages' Python.
fn lab_script(script: &str, args: &[&str]) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = Command::new(common::lab_python())
        .arg(root.join("tests/lab_languages").join(script))
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{script}: {}", common::text(&o.stderr));
    common::text(&o.stdout)
}

/// The documents autoprotocol-python writes (tests/lab_languages/autoprotocol_protocols.py).
fn library_documents(dir: &Path) -> PathBuf {
    let out = dir.join("autoprotocol");
    lab_script("autoprotocol_protocols.py", &[&out.display().to_string()]);
    out
}

fn import(file: &Path, out: &Path, id: &str) -> (bool, String, String) {
    import_with(file, out, id, &[])
}

fn import_with(file: &Path, out: &Path, id: &str, extra: &[&str]) -> (bool, String, String) {
    let (file, out) = (file.display().to_string(), out.display().to_string());
    let mut args = vec![
        "--color", "never", "import", &file, "--out", &out, "--id", id,
    ];
    args.extend_from_slice(extra);
    let o = common::autobio(&args);
    (
        o.status.success(),
        common::text(&o.stdout),
        common::text(&o.stderr),
    )
}

fn export(protocol: &Path, out: &Path) -> String {
    common::autobio_ok(&[
        "export",
        &protocol.display().to_string(),
        "--to",
        "autoprotocol",
        "--out",
        &out.display().to_string(),
    ]);
    std::fs::read_to_string(out).unwrap()
}

/// The expert carries the protocol out on seed 0, and a motionless robot does not.
fn expert_wins_and_hold_fails(protocol: &Path) {
    let task = common::compile(&protocol.display().to_string());
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{}: {:#?}", protocol.display(), r.verdict);
    assert!(
        !common::run(&task, 0, "hold").success,
        "{}",
        protocol.display()
    );
}

/// The task a protocol compiles to, less where it came from (its file and source hash).
fn task_of(protocol: &Path) -> compiler::Task {
    let mut t = common::compile(&protocol.display().to_string());
    t.imported_from = None;
    t.source.clear();
    for s in &mut t.stages {
        s.source.clear();
    }
    t
}

#[test]
fn autoprotocol_from_its_library_imports_checks_and_the_expert_carries_it_out() {
    let dir = common::scratch("import-autoprotocol");
    let docs = library_documents(&dir);

    // A PCR set-up with the library's default transfer (prime, mixing, air gaps, blow-out), the
    // plate sealed and thermocycled within 30 minutes of the last transfer.
    let pcr = dir.join("pcr.toml");
    let (ok, said, warned) = import(&docs.join("pcr_setup.json"), &pcr, "imported.ap_pcr");
    assert!(ok, "{said}{warned}");
    assert!(
        said.contains("Autoprotocol JSON") && said.contains("ok"),
        "{said}"
    );
    for w in [
        "`liquid_handle air` dropped",
        "`liquid_handle mixing` dropped",
        "1 `seal` dropped",
        // The constraint's `from` is pipetting, which no check times.
        "time_constraints[0] not carried: instructions[3]",
        "pcr_setup.json:",
    ] {
        assert!(warned.contains(w), "`{w}` not in {warned}");
    }
    let text = std::fs::read_to_string(&pcr).unwrap();
    for line in [
        "kind = \"thermal_cycler_96\"",
        "[labware.master_mix]",
        "at = \"tube_rack.A1\"",
        "state = { cap = \"off\", volume = \"1000 µL\", liquid = \"taq_master_mix\" }",
        "[labware.pcr_plate_b1]",
        "at = \"cycler.B1\"",
        "state = { set_volume = \"25 µL\" }",
        "do = \"retract\"",
        "profile = \"95 °C 30 s, 30 x [95 °C 15 s, 55 °C 30 s, 68 °C 60 s], 68 °C 300 s\"",
        "\"pcr_plate_c1.volume of taq_master_mix = 25 µL\",",
        "\"master_mix.volume = 925 µL\",",
        "\"cycler.run is done\",",
        "# instructions[5] thermocycle",
    ] {
        assert!(text.contains(line), "{line} not in:\n{text}");
    }
    expert_wins_and_hold_fails(&pcr);

    // A stock tube aliquoted into three tubes.
    let aliquots = dir.join("aliquots.toml");
    let (ok, said, warned) = import(
        &docs.join("tube_aliquots.json"),
        &aliquots,
        "imported.ap_aliquots",
    );
    assert!(ok, "{said}{warned}");
    let text = std::fs::read_to_string(&aliquots).unwrap();
    for line in [
        "[labware.aliquot_3]",
        "at = \"tube_rack.A3\"",
        "\"aliquot_2.volume of buffer_te = 150 µL\",",
        "\"stock.volume = 450 µL\",",
    ] {
        assert!(text.contains(line), "{line} not in:\n{text}");
    }
    expert_wins_and_hold_fails(&aliquots);

    // Spinning and incubating are refused at their instructions, and nothing is written.
    let file = docs.join("spin_incubate.json");
    let source = std::fs::read_to_string(&file).unwrap();
    let out = dir.join("spin.toml");
    let (ok, _, warned) = import(&file, &out, "imported.ap_spin");
    assert!(!ok && !out.exists(), "{warned}");
    for (op, index) in [("spin", 2), ("incubate", 3)] {
        let span = interchange::json_span::locate(
            &source,
            &[
                interchange::json_span::Key::field("instructions"),
                interchange::json_span::Key::Index(index),
            ],
        )
        .unwrap();
        let (l, c) = dsl::render::line_col(&source, span.start);
        assert!(
            warned.contains(&format!(
                "error[E0042]: instructions[{index}] {op} has no realisation yet"
            )) && warned.contains(&format!("spin_incubate.json:{l}:{c}")),
            "{warned}"
        );
    }
    // Kept on request as instrument-only steps: the robots stand by for each one's duration.
    let (ok, said, warned) = import_with(
        &file,
        &out,
        "imported.ap_spin",
        &["--keep-instrument-steps"],
    );
    assert!(ok, "{said}{warned}");
    let text = std::fs::read_to_string(&out).unwrap();
    for line in [
        "do = \"external\"\nwhat = \"spin tube\"\nduration = \"60 s\"",
        "what = \"incubate tube\"\nduration = \"600 s\"",
        "\"tube.volume of culture = 100 µL\",",
    ] {
        assert!(text.contains(line), "{line} not in:\n{text}");
    }
    expert_wins_and_hold_fails(&out);
    // Its export writes the kept instructions back as they were.
    let back: serde_json::Value =
        serde_json::from_str(&export(&out, &dir.join("spin.exported.json"))).unwrap();
    let runs = |doc: &serde_json::Value| -> Vec<serde_json::Value> {
        doc["instructions"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|i| i["op"] == "spin" || i["op"] == "incubate")
            .cloned()
            .collect()
    };
    assert_eq!(runs(&back), runs(&serde_json::from_str(&source).unwrap()));
}

#[test]
fn an_imported_autoprotocol_exports_and_imports_again_to_the_same_task() {
    let dir = common::scratch("autoprotocol-round-trip");
    let docs = library_documents(&dir);
    for name in ["pcr_setup", "tube_aliquots"] {
        let first = dir.join(format!("{name}.toml"));
        let (ok, said, warned) = import(
            &docs.join(format!("{name}.json")),
            &first,
            "imported.round_trip",
        );
        assert!(ok, "{said}{warned}");
        let exported = dir.join(format!("{name}.exported.json"));
        let document = export(&first, &exported);
        // The lab's steps only: no robot motion is an instruction.
        let doc: serde_json::Value = serde_json::from_str(&document).unwrap();
        let ops: Vec<&str> = doc["instructions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i["op"].as_str().unwrap())
            .collect();
        assert!(
            ops.iter()
                .all(|o| ["provision", "liquid_handle", "thermocycle"].contains(o)),
            "{ops:?}"
        );
        let second = dir.join(format!("{name}.again.toml"));
        let (ok, said, warned) = import(&exported, &second, "imported.round_trip");
        assert!(ok, "{said}{warned}");
        let again = std::fs::read_to_string(&second).unwrap();
        // The same protocol (less the comments naming instructions and the source's hash) ...
        let strip = |t: &str| {
            body(t)
                .lines()
                .filter(|l| !l.starts_with('#'))
                .collect::<Vec<_>>()
                .join("\n")
        };
        assert_eq!(
            strip(&again),
            strip(&std::fs::read_to_string(&first).unwrap()),
            "{name}"
        );
        // ... the same task ...
        assert_eq!(task_of(&first), task_of(&second), "{name}");
        // ... and exporting it again writes the same document, byte for byte.
        let twice = export(&second, &dir.join(format!("{name}.twice.json")));
        assert_eq!(twice, document, "{name}");
    }
    let pcr: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("pcr_setup.exported.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(pcr["refs"]["pcr_plate"]["new"], "96-pcr", "{pcr}");
    assert_eq!(pcr["refs"]["master_mix"]["new"], "micro-1.5", "{pcr}");
    let thermocycle = pcr["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["op"] == "thermocycle")
        .unwrap();
    assert_eq!(thermocycle["object"], "pcr_plate");
    assert_eq!(thermocycle["groups"][1]["cycles"], 30);
    assert_eq!(thermocycle["volume"], "25:microliter");
}

#[test]
fn a_shipped_protocol_exports_its_lab_steps_and_its_timing() {
    let dir = common::scratch("autoprotocol-export");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // lab.pcr: the fills, the profile on the tubes in the cycler's block; the lid's motions dropped.
    let doc: serde_json::Value = serde_json::from_str(&export(
        &root.join("protocols/lab/pcr.toml"),
        &dir.join("pcr.json"),
    ))
    .unwrap();
    let ops: Vec<&str> = doc["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["op"].as_str().unwrap())
        .collect();
    assert_eq!(
        ops,
        [
            "provision",
            "liquid_handle",
            "liquid_handle",
            "liquid_handle",
            "thermocycle"
        ]
    );
    assert_eq!(doc["refs"]["cycler"]["new"], "96-pcr", "{doc}");
    // lab.miniprep_spins: each spin of the tubes in the rotor, at the force its speed makes there.
    let doc: serde_json::Value = serde_json::from_str(&export(
        &root.join("protocols/lab/spin.toml"),
        &dir.join("spin.json"),
    ))
    .unwrap();
    let spins: Vec<&serde_json::Value> = doc["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["op"] == "spin")
        .collect();
    assert!(!spins.is_empty(), "{doc}");
    assert!(
        spins
            .iter()
            .all(|s| s["acceleration"].as_str().unwrap().ends_with(":g")),
        "{doc}"
    );
    // Step timing between two runs is a time constraint between their instructions.
    let series = std::fs::read_to_string(root.join("protocols/lab/incubation_series.toml"))
        .unwrap()
        .replacen(
            "do = \"incubate\"",
            "do = \"incubate\"\nid = \"first_run\"",
            1,
        );
    let at = series.rfind("do = \"incubate\"").unwrap() + "do = \"incubate\"".len();
    let timed = format!(
        "{}\nwithin = \"3 h\"\nafter = \"first_run\"{}",
        &series[..at],
        &series[at..]
    );
    let timed_file = dir.join("series.toml");
    std::fs::write(&timed_file, timed).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&export(&timed_file, &dir.join("series.json"))).unwrap();
    let runs: Vec<usize> = doc["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, i)| i["op"] == "incubate")
        .map(|(n, _)| n)
        .collect();
    assert_eq!(runs.len(), 2, "{doc}");
    assert_eq!(
        doc["time_constraints"],
        serde_json::json!([{"from": {"instruction_end": runs[0]},
                            "to": {"instruction_start": runs[1]},
                            "less_than": "10800:second"}]),
        "{doc}"
    );
    // A 50 mL tube has no Autoprotocol type: refused, naming it.
    let o = common::autobio(&[
        "export",
        &root
            .join("protocols/pipette/transfer.toml")
            .display()
            .to_string(),
        "--to",
        "autoprotocol",
        "--out",
        &dir.join("transfer.json").display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        common::text(&o.stderr).contains("a `tube_50ml`, which has no Autoprotocol container type"),
        "{}",
        common::text(&o.stderr)
    );
    assert!(!dir.join("transfer.json").exists());
}

#[test]
fn the_documented_examples_of_autoprotocol_python_import_or_say_why_not() {
    let dir = common::scratch("autoprotocol-docs");
    let docs = dir.join("docs");
    let found: usize = lab_script("autoprotocol_docs.py", &[&docs.display().to_string()])
        .trim()
        .parse()
        .unwrap();
    assert!(
        found >= 5,
        "{found} documents in the library's documentation"
    );
    let mut files: Vec<PathBuf> = std::fs::read_dir(&docs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert_eq!(files.len(), found);
    for f in files {
        let out = f.with_extension("toml");
        let (ok, said, warned) = import(&f, &out, "imported.doc");
        if ok {
            continue;
        }
        // Refused: each error names an instruction (its index and op) or a ref, in the file.
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let errors: Vec<&str> = warned.lines().filter(|l| l.starts_with("error[")).collect();
        assert!(!errors.is_empty(), "{name}: {said}{warned}");
        for e in errors {
            assert!(
                e.contains("instructions[") || e.contains("ref `"),
                "{name}: {e}"
            );
        }
        assert!(warned.contains(&format!("{name}:")), "{name}: {warned}");
    }
}

#[test]
fn opentrons_protocols_analysed_by_opentrons_import_and_the_expert_carries_them_out() {
    let dir = common::scratch("import-analysed");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = dir.join("opentrons-config");
    std::fs::create_dir_all(&config).unwrap();
    let analyse = |name: &str| -> PathBuf {
        let out = dir.join(format!("{name}.json"));
        let o = Command::new(common::lab_python())
            .args(["-m", "opentrons.cli", "analyze", "--json-output"])
            .arg(&out)
            .arg(root.join(format!("tests/lab_languages/opentrons/{name}.py")))
            .env("OT_API_CONFIG_DIR", &config)
            .output()
            .unwrap();
        assert!(o.status.success(), "{name}: {}", common::text(&o.stderr));
        out
    };
    for (name, says) in [
        (
            "tube_aliquots",
            vec!["\"rack_d1.volume of te_buffer = 100 µL\",", "do = \"wait\""],
        ),
        (
            "pcr_on_thermocycler",
            vec![
                "profile = \"95 °C 30 s, 30 x [95 °C 15 s, 55 °C 30 s, 68 °C 60 s], 68 °C 300 s\"",
                "\"cycler.run is done\",",
            ],
        ),
    ] {
        let analysis = analyse(name);
        let out = dir.join(format!("{name}.toml"));
        let (ok, said, warned) = import(&analysis, &out, &format!("imported.{name}"));
        assert!(ok, "{name}: {said}{warned}");
        assert!(said.contains("Opentrons analysis JSON"), "{said}");
        let text = std::fs::read_to_string(&out).unwrap();
        for s in says {
            assert!(text.contains(s), "{s} not in:\n{text}");
        }
        expert_wins_and_hold_fails(&out);
    }
    // A magnetic module's commands: refused, or kept as instrument-only steps on request.
    let analysis = analyse("magnet_steps");
    let out = dir.join("magnet.toml");
    let (ok, _, warned) = import(&analysis, &out, "imported.magnet");
    assert!(!ok && !out.exists(), "{warned}");
    assert!(
        warned.contains("module `magneticModuleV2` has no realisation here")
            && warned.contains("magneticModule/engage has no realisation here")
            && warned.contains("`--keep-instrument-steps`"),
        "{warned}"
    );
    let (ok, said, warned) = import_with(
        &analysis,
        &out,
        "imported.magnet",
        &["--keep-instrument-steps"],
    );
    assert!(ok, "{said}{warned}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("do = \"external\"\nwhat = \"magneticModule/engage {{\\\"height\\\":5.0}}\"")
            && text.contains("what = \"magneticModule/disengage\""),
        "{text}"
    );
    expert_wins_and_hold_fails(&out);
    // Reagent kept cold on a temperature module: refused at the module's commands.
    let analysis = analyse("cold_block_transfer");
    let out = dir.join("cold.toml");
    let (ok, _, warned) = import(&analysis, &out, "imported.cold");
    assert!(!ok && !out.exists(), "{warned}");
    assert!(
        warned.contains("loadModule: module `temperatureModuleV2` has no realisation here")
            && warned.contains("temperatureModule/setTargetTemperature has no realisation here"),
        "{warned}"
    );
}

/// A small good document the faulty cases are edited from.
const GOOD: &str = r#"{
  "refs": {
    "mix": {"new": "micro-1.5", "discard": true},
    "plate": {"new": "96-pcr", "discard": true}
  },
  "instructions": [
    {"op": "provision", "resource_id": "water", "to": [{"well": "mix/0", "volume": "500:microliter"}]},
    {"op": "liquid_handle", "locations": [
      {"location": "mix/0", "transports": [{"volume": "-50:microliter"}]},
      {"location": "plate/0", "transports": [{"volume": "50:microliter"}]}
    ]},
    {"op": "thermocycle", "object": "plate", "volume": "50:microliter",
     "groups": [{"cycles": 1, "steps": [{"temperature": "95:celsius", "duration": "30:second"}]}]}
  ],
  "time_constraints": [
    {"from": {"instruction_start": 2}, "to": {"instruction_end": 2}, "less_than": "2:hour"}
  ]
}
"#;

#[test]
fn faulty_autoprotocol_files_are_refused_with_the_instruction_and_its_place() {
    let dir = common::scratch("autoprotocol-faults");
    // The good one imports.
    let good = dir.join("good.json");
    std::fs::write(&good, GOOD).unwrap();
    let (ok, said, warned) = import(&good, &dir.join("good.toml"), "imported.good");
    assert!(ok, "{said}{warned}");
    let cases: Vec<(&str, String, &str, &str, At)> = vec![
        (
            "truncated.json",
            GOOD[..GOOD.len() / 2].to_string(),
            "E0040",
            "the file is not JSON",
            At::Text("truncated.json:"),
        ),
        (
            "unknown_op.json",
            GOOD.replace("\"op\": \"thermocycle\"", "\"op\": \"teleport\""),
            "E0042",
            "instructions[2] teleport: `teleport` is an op the importer does not know",
            path(&["instructions", "2", "op"]),
        ),
        (
            "plate_reader.json",
            GOOD.replace("\"op\": \"thermocycle\"", "\"op\": \"absorbance\""),
            "E0042",
            "instructions[2] absorbance has no realisation here",
            path(&["instructions", "2"]),
        ),
        (
            "container_type.json",
            GOOD.replace("\"96-pcr\"", "\"384-echo\""),
            "E0043",
            "ref `plate`: container type `384-echo` has no kind here",
            path(&["refs", "plate"]),
        ),
        (
            "no_type.json",
            GOOD.replace(
                "{\"new\": \"micro-1.5\", \"discard\": true}",
                "{\"id\": \"ct1abc\"}",
            ),
            "E0043",
            "ref `mix` is an existing container (`id`) of no stated type",
            path(&["refs", "mix"]),
        ),
        (
            "unit.json",
            GOOD.replace("-50:microliter", "-50:furlong"),
            "E0044",
            "`furlong` is not a volume unit",
            path(&[
                "instructions",
                "1",
                "locations",
                "0",
                "transports",
                "0",
                "volume",
            ]),
        ),
        (
            "no_quantity.json",
            GOOD.replace("\"30:second\"", "\"30 seconds\""),
            "E0044",
            "`30 seconds` is no quantity",
            path(&["instructions", "2", "groups", "0", "steps", "0", "duration"]),
        ),
        (
            "overfull.json",
            GOOD.replace("500:microliter", "2:milliliter"),
            "E0044",
            "2000 µL in well `A1`, whose tube here (`tube_1_5ml`) holds 1500 µL",
            path(&["instructions", "0", "to", "0", "volume"]),
        ),
        (
            "unknown_ref.json",
            GOOD.replace("\"plate/0\"", "\"plat/0\""),
            "E0041",
            "`plat/0` names ref `plat`, which `refs` does not have",
            path(&["instructions", "1", "locations", "1", "location"]),
        ),
        (
            "well.json",
            GOOD.replace("\"plate/0\"", "\"plate/96\""),
            "E0041",
            "a 96-pcr plate has wells 0 to 95",
            path(&["instructions", "1", "locations", "1", "location"]),
        ),
        (
            "two_points.json",
            GOOD.replace(
                "{\"instruction_start\": 2}",
                "{\"instruction_start\": 2, \"ref_end\": \"plate\"}",
            ),
            "E0041",
            "time_constraints[0].from names 2 points, not one",
            path(&["time_constraints", "0", "from"]),
        ),
        (
            "multichannel.json",
            GOOD.replace(
                "{\"op\": \"liquid_handle\",",
                "{\"op\": \"liquid_handle\", \"shape\": {\"rows\": 8, \"columns\": 1},",
            ),
            "E0042",
            "a 8 x 1 head",
            path(&["instructions", "1", "shape"]),
        ),
        (
            "gradient.json",
            GOOD.replace(
                "\"temperature\": \"95:celsius\"",
                "\"gradient\": {\"top\": \"65:celsius\", \"bottom\": \"55:celsius\"}",
            ),
            "E0042",
            "a gradient step",
            path(&["instructions", "2", "groups", "0", "steps", "0"]),
        ),
        (
            "not_autoprotocol.json",
            "{\"refs\": [], \"instructions\": {}}".to_string(),
            "E0040",
            "`refs` is not an object of containers by name",
            path(&["refs"]),
        ),
    ];
    for (name, text, code, says, at) in cases {
        refused(&dir, name, &text, code, says, at);
    }
    // Constraints that cannot be carried are said, and the file still imports: one running
    // backwards (a cycle of two constraints), a lower bound.
    let cyclic = GOOD.replace(
        "\"less_than\": \"2:hour\"}",
        "\"less_than\": \"2:hour\"}, {\"from\": {\"instruction_end\": 2}, \"to\": {\"instruction_start\": 2}, \"less_than\": \"1:hour\", \"more_than\": \"1:minute\"}",
    );
    let file = dir.join("cyclic.json");
    std::fs::write(&file, &cyclic).unwrap();
    let out = dir.join("cyclic.toml");
    let (ok, said, warned) = import(&file, &out, "imported.cyclic");
    assert!(ok, "{said}{warned}");
    assert!(
        warned.contains("time_constraints[1] not carried: its `to` comes before its `from`")
            && warned.contains("time_constraints[1]: `more_than` and `ideal` not carried"),
        "{warned}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    // The one that runs forwards is carried: the lid's closing to its opening, in 2 h.
    assert!(
        text.contains("within = \"7200 s\"") && text.contains("after = \"step_"),
        "{text}"
    );
    // It survives an export and an import again: from the thermocycle's start to its end.
    let good_toml = dir.join("good.toml");
    let back = dir.join("good.exported.json");
    let doc: serde_json::Value = serde_json::from_str(&export(&good_toml, &back)).unwrap();
    let at = doc["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .position(|i| i["op"] == "thermocycle")
        .unwrap();
    assert_eq!(
        doc["time_constraints"],
        serde_json::json!([{"from": {"instruction_start": at}, "to": {"instruction_end": at},
                            "less_than": "7200:second"}]),
        "{doc}"
    );
    let again = dir.join("good.again.toml");
    let (ok, said, warned) = import(&back, &again, "imported.good");
    assert!(ok, "{said}{warned}");
    assert_eq!(task_of(&good_toml), task_of(&again));
    // A kept instruction names its ref under the item's name, and its ref is exported.
    let kept = GOOD
        .replace("\"mix\"", "\"2x-mix\"")
        .replace("mix/0", "2x-mix/0")
        .replace(
            "{\"op\": \"thermocycle\"",
            "{\"op\": \"absorbance\", \"object\": \"2x-mix\", \"wavelength\": \"600:nanometer\"},\n    {\"op\": \"thermocycle\"",
        );
    let file = dir.join("kept.json");
    std::fs::write(&file, &kept).unwrap();
    let first = dir.join("kept.toml");
    let (ok, said, warned) =
        import_with(&file, &first, "imported.kept", &["--keep-instrument-steps"]);
    assert!(ok, "{said}{warned}");
    let text = std::fs::read_to_string(&first).unwrap();
    assert!(
        text.contains("[labware.ref_2x_mix]") && text.contains("what = \"absorbance ref_2x_mix\""),
        "{text}"
    );
    let back = dir.join("kept.exported.json");
    let doc: serde_json::Value = serde_json::from_str(&export(&first, &back)).unwrap();
    let read = doc["instructions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["op"] == "absorbance")
        .unwrap();
    assert_eq!(read["object"], "ref_2x_mix", "{doc}");
    assert_eq!(doc["refs"]["ref_2x_mix"]["new"], "micro-1.5", "{doc}");
    let again = dir.join("kept.again.toml");
    let (ok, said, warned) =
        import_with(&back, &again, "imported.kept", &["--keep-instrument-steps"]);
    assert!(ok, "{said}{warned}");
    assert_eq!(task_of(&first), task_of(&again));
}

#[test]
fn mutated_autoprotocol_files_never_panic_and_point_inside_themselves() {
    use rand_chacha::ChaCha8Rng;
    use rand_core::{RngCore, SeedableRng};
    let options = interchange::Options {
        id: Some("fuzz.case".into()),
        instruction: None,
        robots: vec![],
        deps: runtime::deps::deps_dir(),
        file_name: "case.json".into(),
        keep_instrument_steps: false,
    };
    let ops = [
        "\"liquid_handle\"",
        "\"thermocycle\"",
        "\"provision\"",
        "\"pipette\"",
        "\"spin\"",
        "\"seal\"",
        "\"nope\"",
    ];
    let quantities = [
        "\"1e308:microliter\"",
        "\"-0:second\"",
        "\"5:\"",
        "\":\"",
        "null",
        "25",
        "\"nan:celsius\"",
        "\"99999:celsius\"",
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    let mut below = |n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    let (mut written, mut refused) = (0, 0);
    for case in 0..3000 {
        let mut text = GOOD.to_string().into_bytes();
        for _ in 0..1 + below(3) {
            let len = text.len();
            let at = below(len);
            match below(6) {
                0 => text[at] = b"{}[]\",:0a/\\"[below(11)],
                1 => {
                    let end = (at + below(120)).min(len);
                    text.drain(at..end);
                }
                2 => {
                    let end = (at + below(120)).min(len);
                    let piece = text[at..end].to_vec();
                    text.splice(at..at, piece);
                }
                3 => text.truncate(at),
                4 => {
                    let s = String::from_utf8_lossy(&text).into_owned();
                    let (from, to) = (ops[below(ops.len())], ops[below(ops.len())]);
                    text = s.replacen(from, to, 1 + below(2)).into_bytes();
                }
                _ => {
                    let s = String::from_utf8_lossy(&text).into_owned();
                    let with = quantities[below(quantities.len())];
                    let which = [
                        "\"-50:microliter\"",
                        "\"30:second\"",
                        "\"95:celsius\"",
                        "\"2:hour\"",
                    ];
                    text = s.replacen(which[below(which.len())], with, 1).into_bytes();
                }
            }
        }
        let Ok(text) = String::from_utf8(text) else {
            continue;
        };
        // Every other case keeps what has no realisation as instrument-only steps.
        let options = interchange::Options {
            keep_instrument_steps: case % 2 == 0,
            ..options.clone()
        };
        match import_mutated(case, &text, &options) {
            Some(p) => {
                written += 1;
                // What it writes compiles or says why, and a task exports without a panic.
                if let (Some(task), _) = compiler::compile_source(&p, "case.toml") {
                    let _ = interchange::autoprotocol::export::export(&task, 0);
                }
            }
            None => refused += 1,
        }
    }
    assert!(
        written > 50 && refused > 1000,
        "{written} written, {refused} refused"
    );
}
