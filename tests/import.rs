//! Issue 50: `autobio import` of Opentrons files. A PCR set-up on the thermocycler written as a
//! Protocol Designer file (schema 8) and as an analysis, each carrying the published labware
//! definitions installed by `make setup` (as the files Opentrons' tools save carry them), imports
//! through the real CLI to the same protocol, which checks and which the expert runs; a faulty
//! file of each kind gives its code, a message naming the command, and the file's line and
//! column, and writes nothing.

use crate::common;
use interchange::json_span::Key;
use serde_json::{Value, json};
use std::path::Path;

/// An installed labware definition, as a file would carry it.
fn definition(uri: &str) -> Value {
    let installed = labware::definition::Installed::under(&runtime::deps::deps_dir());
    let path = installed.path(uri).unwrap();
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

const PLATE: &str = "opentrons/nest_96_wellplate_100ul_pcr_full_skirt/2";
const RACK: &str = "opentrons/opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap/1";
const TIPS: &str = "opentrons/opentrons_96_tiprack_300ul/1";

fn load_labware(id: &str, uri: &str, location: Value) -> Value {
    let parts: Vec<&str> = uri.split('/').collect();
    json!({"commandType": "loadLabware", "key": format!("k-{id}"), "params": {
        "labwareId": id, "loadName": parts[1], "namespace": parts[0],
        "version": parts[2].parse::<u32>().unwrap(), "location": location}})
}

/// The commands of a PCR set-up on the thermocycler: the lid opened, 25 µL of master mix from a
/// 1.5 mL tube into three wells of a PCR plate in the cycler (a fresh tip each), the lid shut, a
/// profile run (NEB's Taq routine, shortened to 3 cycles), the lid opened.
fn commands() -> Vec<Value> {
    let mut c = vec![
        json!({"commandType": "loadPipette", "key": "k-p", "params": {
            "pipetteId": "p300", "pipetteName": "p300_single_gen2", "mount": "left"}}),
        json!({"commandType": "loadModule", "key": "k-tc", "params": {
            "moduleId": "tc:thermocyclerModuleType", "model": "thermocyclerModuleV1",
            "location": {"slotName": "7"}}}),
        load_labware("tips", TIPS, json!({"slotName": "1"})),
        load_labware(
            "plate",
            PLATE,
            json!({"moduleId": "tc:thermocyclerModuleType"}),
        ),
        load_labware("rack", RACK, json!({"slotName": "2"})),
        json!({"commandType": "loadLiquid", "key": "k-l", "params": {
            "liquidId": "mm", "labwareId": "rack", "volumeByWell": {"B2": 1000}}}),
        json!({"commandType": "thermocycler/openLid", "key": "k-o", "params": {
            "moduleId": "tc:thermocyclerModuleType"}}),
    ];
    for (i, well) in ["A5", "B5", "C5"].iter().enumerate() {
        let tip = ["A1", "B1", "C1"][i];
        c.push(
            json!({"commandType": "pickUpTip", "key": format!("k-t{i}"), "params": {
            "pipetteId": "p300", "labwareId": "tips", "wellName": tip}}),
        );
        c.push(
            json!({"commandType": "aspirate", "key": format!("k-a{i}"), "params": {
            "pipetteId": "p300", "labwareId": "rack", "wellName": "B2", "volume": 25,
            "flowRate": 46.43, "wellLocation": {"origin": "bottom", "offset": {"z": 1}}}}),
        );
        c.push(
            json!({"commandType": "dispense", "key": format!("k-d{i}"), "params": {
            "pipetteId": "p300", "labwareId": "plate", "wellName": well, "volume": 25,
            "flowRate": 46.43, "wellLocation": {"origin": "bottom", "offset": {"z": 1}}}}),
        );
        c.push(
            json!({"commandType": "dropTip", "key": format!("k-x{i}"), "params": {
            "pipetteId": "p300", "labwareId": "fixedTrash", "wellName": "A1"}}),
        );
    }
    c.extend([
        json!({"commandType": "thermocycler/closeLid", "key": "k-c", "params": {
            "moduleId": "tc:thermocyclerModuleType"}}),
        json!({"commandType": "thermocycler/setTargetLidTemperature", "key": "k-lt", "params": {
            "moduleId": "tc:thermocyclerModuleType", "celsius": 105}}),
        json!({"commandType": "thermocycler/runProfile", "key": "k-r", "params": {
            "moduleId": "tc:thermocyclerModuleType", "blockMaxVolumeUl": 25, "profile": [
                {"celsius": 95, "holdSeconds": 30}, {"celsius": 95, "holdSeconds": 15},
                {"celsius": 55, "holdSeconds": 30}, {"celsius": 68, "holdSeconds": 60},
                {"celsius": 95, "holdSeconds": 15}, {"celsius": 55, "holdSeconds": 30},
                {"celsius": 68, "holdSeconds": 60}, {"celsius": 68, "holdSeconds": 300},
                {"celsius": 4, "holdSeconds": 60}]}}),
        json!({"commandType": "thermocycler/openLid", "key": "k-o2", "params": {
            "moduleId": "tc:thermocyclerModuleType"}}),
    ]);
    c
}

/// The set-up as Protocol Designer saves it (schema 8).
fn protocol_file() -> Value {
    json!({
        "$otSharedSchema": "#/protocol/schemas/8",
        "schemaVersion": 8,
        "metadata": {"protocolName": "PCR set-up on the thermocycler", "author": "autobio tests"},
        "robot": {"model": "OT-2 Standard", "deckId": "ot2_standard"},
        "labwareDefinitionSchemaId": "opentronsLabwareSchemaV2",
        "labwareDefinitions": {PLATE: definition(PLATE), RACK: definition(RACK), TIPS: definition(TIPS)},
        "liquidSchemaId": "opentronsLiquidSchemaV1",
        "liquids": {"mm": {"displayName": "Master Mix", "description": "2X Taq", "displayColor": "#b925ff"}},
        "commandSchemaId": "opentronsCommandSchemaV8",
        "commands": commands(),
        "commandAnnotationSchemaId": "opentronsCommandAnnotationSchemaV1",
        "commandAnnotations": []
    })
}

/// The same run as `opentrons analyze --json-output` writes it: ids in each load's result, the
/// definitions in the loads' results, liquids as a list, every command succeeded.
fn analysis_file() -> Value {
    let commands: Vec<Value> = commands()
        .into_iter()
        .enumerate()
        .map(|(i, mut c)| {
            let mut result = json!({});
            if c["commandType"] == "loadLabware" {
                let p = &c["params"];
                let uri = format!(
                    "{}/{}/{}",
                    p["namespace"].as_str().unwrap(),
                    p["loadName"].as_str().unwrap(),
                    p["version"]
                );
                result = json!({"labwareId": p["labwareId"], "definition": definition(&uri)});
                c["params"].as_object_mut().unwrap().remove("labwareId");
            }
            json!({"id": format!("cmd-{i}"), "createdAt": "2026-11-29T12:00:00Z",
                   "commandType": c["commandType"], "key": c["key"], "status": "succeeded",
                   "params": c["params"], "result": result, "notes": []})
        })
        .collect();
    json!({
        "createdAt": "2026-11-29T12:00:00Z",
        "files": [{"name": "pcr.json", "role": "main"}],
        "config": {"protocolType": "json", "schemaVersion": 8},
        "metadata": {"protocolName": "PCR set-up on the thermocycler"},
        "robotType": "OT-2 Standard",
        "commands": commands,
        "labware": [], "pipettes": [], "modules": [],
        "liquids": [{"id": "mm", "displayName": "Master Mix", "description": "2X Taq", "displayColor": "#b925ff"}],
        "errors": [], "result": "ok"
    })
}

fn write(dir: &Path, name: &str, v: &Value) -> String {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    path.display().to_string()
}

/// The protocol's body: the file less its header comments and its source's name and hash.
pub(crate) fn body(text: &str) -> String {
    text.lines()
        .skip_while(|l| l.starts_with('#'))
        .filter(|l| !l.starts_with("imported_from = "))
        .collect::<Vec<_>>()
        .join("\n")
}

fn hex_of(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn an_opentrons_pcr_set_up_imports_from_either_file_checks_and_the_expert_runs_it() {
    let dir = common::scratch("import");
    let pd = write(&dir, "pcr.json", &protocol_file());
    let out = dir.join("pcr.toml");
    let out_s = out.display().to_string();
    let o = common::autobio(&[
        "--color",
        "never",
        "import",
        &pd,
        "--out",
        &out_s,
        "--id",
        "imported.pcr",
    ]);
    let (said, warned) = (common::text(&o.stdout), common::text(&o.stderr));
    assert!(o.status.success(), "{said}{warned}");
    assert!(
        said.contains("Opentrons protocol JSON, schema 8") && said.contains("ok"),
        "{said}"
    );
    // The tips are dropped, said once for the three pick-ups, at the first.
    assert!(
        warned.contains("warning[W0011]: 3 `pickUpTip` dropped") && warned.contains("pcr.json:"),
        "{warned}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    // The plate in the cycler is three PCR tubes in its block; the rack's tube holds the mix.
    for line in [
        "kind = \"thermal_cycler_96\"",
        "at = \"cycler.A5\"",
        "at = \"rack.B2\"",
        "state = { cap = \"off\", volume = \"1000 µL\", liquid = \"master_mix\" }",
        "kind = \"pipette_p200\"",
        "state = { set_volume = \"25 µL\" }",
        "do = \"retract\"",
        "profile = \"95 °C 30 s, 95 °C 15 s, 55 °C 30 s, 68 °C 60 s, 95 °C 15 s, 55 °C 30 s, 68 °C 60 s, 68 °C 300 s, 4 °C 60 s\"",
        "\"plate_a5.volume of master_mix = 25 µL\",",
        "\"rack_b2.volume = 925 µL\",",
        "\"cycler.run is done\",",
        "\"cycler.lid is open\",",
        "# commands[8] aspirate",
    ] {
        assert!(text.contains(line), "{line} not in:\n{text}");
    }
    let sha = {
        use sha2::Digest;
        hex_of(&sha2::Sha256::digest(std::fs::read(&pd).unwrap()))
    };
    assert!(
        text.contains(&format!(
            "imported_from = {{ file = \"pcr.json\", format = \"Opentrons protocol JSON, schema 8\", sha256 = \"{sha}\" }}"
        )),
        "{text}"
    );

    // The analysis of the same run gives the same protocol.
    let analysis = write(&dir, "pcr.analysis.json", &analysis_file());
    let out2 = dir.join("pcr2.toml");
    let said = common::autobio_ok(&[
        "import",
        &analysis,
        "--out",
        &out2.display().to_string(),
        "--id",
        "imported.pcr",
    ]);
    assert!(said.contains("Opentrons analysis JSON"), "{said}");
    assert_eq!(body(&std::fs::read_to_string(&out2).unwrap()), body(&text));

    // A run's manifest names the source: its file, format and hash.
    let run = dir.join("run");
    common::autobio_ok(&[
        "eval",
        "--protocol",
        &out_s,
        "--policy",
        "hold",
        "--episodes",
        "1",
        "--out",
        &run.display().to_string(),
    ]);
    let manifest: Value = serde_json::from_str(
        &std::fs::read_to_string(run.join("imported.pcr.manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        manifest["imported_from"]["sha256"],
        json!(sha),
        "{manifest}"
    );
    assert_eq!(manifest["imported_from"]["file"], json!("pcr.json"));

    // The expert carries it out: the mix in each tube, the profile run, the lid open again.
    let task = common::compile(&out_s);
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    let hold = common::run(&task, 0, "hold");
    assert!(!hold.success);
}

/// Where a finding must point: a JSON path into the file (its line and column computed from the
/// file's text), or text the location must hold.
pub(crate) enum At {
    Path(Vec<Key>),
    Text(&'static str),
}

pub(crate) fn path(keys: &[&str]) -> At {
    At::Path(
        keys.iter()
            .map(|k| match k.parse::<usize>() {
                Ok(i) => Key::Index(i),
                Err(_) => Key::field(k),
            })
            .collect(),
    )
}

/// A faulty file: the code, a message naming what is wrong, the place in the file (`file:line:col`
/// as the CLI prints it) and nothing written.
pub(crate) fn refused(dir: &Path, name: &str, v: &str, code: &str, says: &str, at: At) -> String {
    let line = match at {
        At::Text(t) => t.to_string(),
        At::Path(path) => {
            let span = interchange::json_span::locate(v, &path)
                .unwrap_or_else(|| panic!("{name}: no {path:?} in the file"));
            let (l, c) = dsl::render::line_col(v, span.start);
            format!("{name}:{l}:{c}")
        }
    };
    let path = dir.join(name);
    std::fs::write(&path, v).unwrap();
    let out = dir.join(format!("{name}.toml"));
    let o = common::autobio(&[
        "--color",
        "never",
        "import",
        &path.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]);
    let err = common::text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{name}: {err}");
    assert!(err.contains(&format!("error[{code}]")), "{name}: {err}");
    assert!(err.contains(says), "{name}: `{says}` not in {err}");
    assert!(err.contains(&line), "{name}: `{line}` not in {err}");
    assert!(!out.exists(), "{name}: a refused import wrote its protocol");
    code.to_string()
}

#[test]
fn faulty_opentrons_files_are_refused_with_the_command_and_its_place() {
    let dir = common::scratch("import-faults");
    let mut codes = std::collections::BTreeSet::new();
    let good = serde_json::to_string_pretty(&protocol_file()).unwrap();
    // Truncated: the parser's line and column.
    let cut = &good[..good.len() / 2];
    let last_line = cut.lines().count();
    codes.insert(refused(
        &dir,
        "truncated.json",
        cut,
        "E0040",
        "not JSON",
        At::Text(Box::leak(
            format!("truncated.json:{last_line}:").into_boxed_str(),
        )),
    ));
    // Neither an Opentrons file nor Autoprotocol.
    codes.insert(refused(
        &dir,
        "other.json",
        r#"{"steps": [], "labware": {}}"#,
        "E0040",
        "neither an Opentrons analysis or protocol (schema 8) nor an Autoprotocol document",
        At::Text("other.json:1:1"),
    ));
    // Another schema version.
    let v6 = good.replace("#/protocol/schemas/8", "#/protocol/schemas/6");
    codes.insert(refused(
        &dir,
        "v6.json",
        &v6,
        "E0040",
        "schemas/6",
        path(&["$otSharedSchema"]),
    ));

    let edit = |f: &dyn Fn(&mut Value)| {
        let mut v = protocol_file();
        f(&mut v);
        serde_json::to_string_pretty(&v).unwrap()
    };
    let index = |v: &Value, key: &str| {
        v["commands"]
            .as_array()
            .unwrap()
            .iter()
            .position(|c| c["key"] == key)
            .unwrap()
    };
    // An unknown command type, named with its index.
    let unknown = edit(&|v| v["commands"][6]["commandType"] = json!("thermocycler/frobnicate"));
    codes.insert(refused(
        &dir,
        "unknown.json",
        &unknown,
        "E0042",
        "commands[6] thermocycler/frobnicate",
        path(&["commands", "6"]),
    ));
    // A magnet: no realisation here.
    let magnet = edit(&|v| {
        v["commands"].as_array_mut().unwrap().insert(
            1,
            json!({"commandType": "loadModule", "params": {"moduleId": "mag", "model": "magneticModuleV2", "location": {"slotName": "4"}}}),
        )
    });
    codes.insert(refused(
        &dir,
        "magnet.json",
        &magnet,
        "E0042",
        "module `magneticModuleV2`",
        path(&["commands", "1", "params", "model"]),
    ));
    // Labware nobody has a definition of.
    let nowhere = edit(&|v| {
        let i = index(v, "k-rack");
        v["commands"][i]["params"]["loadName"] = json!("acme_7_wellplate_12ml");
    });
    codes.insert(refused(
        &dir,
        "nowhere.json",
        &nowhere,
        "E0043",
        "opentrons/acme_7_wellplate_12ml/1",
        path(&["commands", "4", "params", "loadName"]),
    ));
    // More liquid than the well's tube holds, pointed at in `volumeByWell`.
    let flood = edit(&|v| v["commands"][5]["params"]["volumeByWell"]["B2"] = json!(5000));
    codes.insert(refused(
        &dir,
        "flood.json",
        &flood,
        "E0044",
        "5000 µL in well `B2`",
        path(&["commands", "5", "params", "volumeByWell", "B2"]),
    ));
    // Labware standing on itself (a cycle of references).
    let cycle = edit(&|v| {
        let i = index(v, "k-rack");
        v["commands"][i]["params"]["location"] = json!({"labwareId": "rack"});
    });
    codes.insert(refused(
        &dir,
        "cycle.json",
        &cycle,
        "E0041",
        "stands on itself",
        path(&["commands", "4", "params", "location"]),
    ));
    // Two loads giving one id.
    let twice = edit(&|v| {
        let i = index(v, "k-tips");
        v["commands"][i]["params"]["labwareId"] = json!("rack");
    });
    codes.insert(refused(
        &dir,
        "twice.json",
        &twice,
        "E0041",
        "`labwareId` `rack` is already",
        path(&["commands", "4", "params", "labwareId"]),
    ));
    // A volume that is not a number.
    let words = edit(&|v| v["commands"][8]["params"]["volume"] = json!("25 uL"));
    codes.insert(refused(
        &dir,
        "words.json",
        &words,
        "E0041",
        "commands[8] aspirate: its parameters cannot be read",
        path(&["commands", "8", "params"]),
    ));
    // Volumes no hand-held pipette sets.
    let tiny = good.replace("\"volume\": 25,", "\"volume\": 2,");
    codes.insert(refused(
        &dir,
        "tiny.json",
        &tiny,
        "E0044",
        "2 µL",
        path(&["commands", "8", "params", "volume"]),
    ));
    // Drawing more than a well holds then.
    let dry = edit(&|v| v["commands"][5]["params"]["volumeByWell"]["B2"] = json!(40));
    codes.insert(refused(
        &dir,
        "dry.json",
        &dry,
        "E0044",
        "25 µL from well `B2`, which holds 15 µL then",
        path(&["commands", "12", "params", "volume"]),
    ));
    // A hold the cycler cannot keep.
    let cold = edit(&|v| {
        let i = index(v, "k-r");
        v["commands"][i]["params"]["profile"][2]["celsius"] = json!(-20);
    });
    codes.insert(refused(
        &dir,
        "cold.json",
        &cold,
        "E0044",
        "a hold at -20 °C",
        path(&["commands", "21", "params"]),
    ));
    // Every error code of the importer has a case here.
    let want: std::collections::BTreeSet<String> = dsl::Code::ALL
        .into_iter()
        .filter(|c| c.is_import() && !c.is_warning())
        .map(|c| c.to_string())
        .collect();
    assert_eq!(codes, want);
}

/// Seeded mutations of the good file (bytes flipped, ranges cut or doubled, numbers made huge,
/// negative or strings, command types swapped, the file truncated anywhere), each imported in
/// process: nothing panics, every finding points inside the file, and whatever is written is a
/// protocol file that parses. CI's bounded fuzzing of the importer (`fuzz/` has the unbounded
/// `cargo fuzz` target).
#[test]
fn mutated_opentrons_files_never_panic_and_point_inside_themselves() {
    use rand_chacha::ChaCha8Rng;
    use rand_core::{RngCore, SeedableRng};
    let good = serde_json::to_string_pretty(&protocol_file()).unwrap();
    let options = interchange::Options {
        id: Some("fuzz.case".into()),
        instruction: None,
        robots: vec![],
        deps: runtime::deps::deps_dir(),
        file_name: "case.json".into(),
        keep_instrument_steps: false,
    };
    let types = [
        "\"aspirate\"",
        "\"dispense\"",
        "\"loadLabware\"",
        "\"thermocycler/runExtendedProfile\"",
        "\"moveLabware\"",
        "\"loadLiquid\"",
        "\"nope\"",
    ];
    let numbers = [
        "1e308",
        "-25",
        "0",
        "\"25\"",
        "null",
        "[]",
        "{}",
        "4294967296",
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(50);
    let mut below = |n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    let (mut written, mut refused) = (0, 0);
    for case in 0..4000 {
        let mut text = good.clone().into_bytes();
        for _ in 0..1 + below(3) {
            let len = text.len();
            let at = below(len);
            match below(6) {
                0 => text[at] = b"{}[]\",:0a \\"[below(11)],
                1 => {
                    let end = (at + below(200)).min(len);
                    text.drain(at..end);
                }
                2 => {
                    let end = (at + below(200)).min(len);
                    let piece = text[at..end].to_vec();
                    text.splice(at..at, piece);
                }
                3 => text.truncate(at),
                4 => {
                    // A command type swapped for another.
                    let s = String::from_utf8_lossy(&text).into_owned();
                    let from = types[below(types.len())];
                    let to = types[below(types.len())];
                    text = s.replacen(from, to, 1 + below(3)).into_bytes();
                }
                _ => {
                    // A number made something else.
                    let s = String::from_utf8_lossy(&text).into_owned();
                    let with = numbers[below(numbers.len())];
                    text = s
                        .replacen("\"volume\": 25", &format!("\"volume\": {with}"), 1)
                        .replacen(
                            "\"holdSeconds\": 30",
                            &format!("\"holdSeconds\": {with}"),
                            1,
                        )
                        .into_bytes();
                }
            }
        }
        let Ok(text) = String::from_utf8(text) else {
            continue;
        };
        match import_mutated(case, &text, &options) {
            Some(_) => written += 1,
            None => refused += 1,
        }
    }
    // The mutations reach both ends: some still import, most are refused.
    assert!(
        written > 50 && refused > 1500,
        "{written} written, {refused} refused"
    );
}

/// Imports a mutated file: it must not panic, every finding must lie inside it, a written
/// protocol must be TOML and a refusal must say why. The written protocol, if any.
pub(crate) fn import_mutated(
    case: usize,
    text: &str,
    options: &interchange::Options,
) -> Option<String> {
    let imported = std::panic::catch_unwind(|| interchange::import(text, options))
        .unwrap_or_else(|_| panic!("case {case} panicked on:\n{text}"));
    for d in &imported.diagnostics {
        assert!(
            d.span.start <= d.span.end && d.span.end <= text.len(),
            "case {case}: {d:?} outside {} bytes",
            text.len()
        );
    }
    match imported.protocol {
        Some(p) => {
            let (_, diags) = dsl::parse(&p);
            assert!(
                !diags.iter().any(|d| d.code == dsl::Code::E0001),
                "case {case}: the written file is not TOML:\n{p}"
            );
            Some(p)
        }
        None => {
            assert!(
                imported.diagnostics.iter().any(|d| d.is_error()),
                "case {case}"
            );
            None
        }
    }
}

/// A holder loaded by its own definition is that holder (the cycler whose block has the same
/// wells is not it), and a protocol name with braces stays text, not a placeholder.
#[test]
fn an_aluminium_block_is_a_block_and_a_braced_name_is_text() {
    let mut v = protocol_file();
    let commands = v["commands"].as_array_mut().unwrap();
    // The plate's wells become an aluminium block's on the deck, with no cycler.
    commands.retain(|c| {
        let t = c["commandType"].as_str().unwrap();
        !t.starts_with("thermocycler/") && t != "loadModule"
    });
    for c in commands.iter_mut() {
        if c["key"] == "k-plate" {
            c["params"]["loadName"] = json!("opentrons_96_aluminumblock_generic_pcr_strip_200ul");
            c["params"]["version"] = json!(2);
            c["params"]["location"] = json!({"slotName": "3"});
        }
    }
    v["metadata"]["protocolName"] = json!("PCR {v2}");
    let text = serde_json::to_string_pretty(&v).unwrap();
    let imported = interchange::import(
        &text,
        &interchange::Options {
            id: Some("imported.block".into()),
            instruction: None,
            robots: vec![],
            deps: runtime::deps::deps_dir(),
            file_name: "block.json".into(),
            keep_instrument_steps: false,
        },
    );
    let protocol = imported
        .protocol
        .unwrap_or_else(|| panic!("{:#?}", imported.diagnostics));
    assert!(
        protocol.contains("kind = \"aluminium_block_96_pcr\""),
        "{protocol}"
    );
    assert!(!protocol.contains("thermal_cycler"), "{protocol}");
    assert!(protocol.contains("at = \"block.A5\""), "{protocol}");
    let (task, diags) = compiler::compile_source(&protocol, "block.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    assert_eq!(task.instruction, "carry out the protocol \"PCR {{v2}}\"");
}
