//! `autobio bench`'s import figure: `autobio import` of the largest Opentrons file it is given
//! here, a Protocol Designer file (schema 8) filling a whole 96-well PCR plate on the
//! thermocycler from a tube, a fresh tip each well (680 commands, the installed labware
//! definitions inside, as Protocol Designer saves them): the import's wall time (read, realise,
//! write) and the written protocol's check (proof and lowering). And the same plate as an
//! Autoprotocol document as autoprotocol-python's default transfer writes it (each well's
//! liquid handling with its prime, ten mixing cycles, air gaps and blow-out: 38 transports), then
//! thermocycled: its import, and the export of the protocol it gives.

use anyhow::{Context, Result};
use serde_json::{Value, json};
use std::time::Instant;

const PLATE: &str = "opentrons/nest_96_wellplate_100ul_pcr_full_skirt/2";
const RACK: &str = "opentrons/opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap/1";
const TIPS: &str = "opentrons/opentrons_96_tiprack_300ul/1";

fn definition(uri: &str) -> Result<Value> {
    let installed = labware::definition::Installed::under(&runtime::deps::deps_dir());
    let path = installed.path(uri)?;
    let text = std::fs::read_to_string(&path).with_context(|| path.display().to_string())?;
    Ok(serde_json::from_str(&text)?)
}

/// The file: a whole plate filled, 20 µL a well, from two 1.5 mL tubes of master mix.
fn largest_file() -> Result<String> {
    let tc = "tc:thermocyclerModuleType";
    let load = |id: &str, uri: &str, location: Value| {
        let p: Vec<&str> = uri.split('/').collect();
        json!({"commandType": "loadLabware", "params": {"labwareId": id, "loadName": p[1],
            "namespace": p[0], "version": p[2].parse::<u32>().unwrap_or(1), "location": location}})
    };
    let mut commands = vec![
        json!({"commandType": "loadPipette", "params": {"pipetteId": "p", "pipetteName": "p300_single_gen2", "mount": "left"}}),
        json!({"commandType": "loadModule", "params": {"moduleId": tc, "model": "thermocyclerModuleV1", "location": {"slotName": "7"}}}),
        load("tips", TIPS, json!({"slotName": "1"})),
        load("plate", PLATE, json!({"moduleId": tc})),
        load("rack", RACK, json!({"slotName": "2"})),
        json!({"commandType": "loadLiquid", "params": {"liquidId": "mm", "labwareId": "rack", "volumeByWell": {"A1": 1500, "A2": 1500}}}),
        json!({"commandType": "thermocycler/openLid", "params": {"moduleId": tc}}),
    ];
    for (i, row) in "ABCDEFGH".chars().enumerate() {
        for col in 1..=12 {
            let well = format!("{row}{col}");
            let source = if i < 4 { "A1" } else { "A2" };
            commands.extend([
                json!({"commandType": "pickUpTip", "params": {"pipetteId": "p", "labwareId": "tips", "wellName": well}}),
                json!({"commandType": "aspirate", "params": {"pipetteId": "p", "labwareId": "rack", "wellName": source, "volume": 20, "flowRate": 46.43}}),
                json!({"commandType": "dispense", "params": {"pipetteId": "p", "labwareId": "plate", "wellName": well, "volume": 20, "flowRate": 46.43}}),
                json!({"commandType": "blowout", "params": {"pipetteId": "p", "labwareId": "plate", "wellName": well, "flowRate": 46.43}}),
                json!({"commandType": "touchTip", "params": {"pipetteId": "p", "labwareId": "plate", "wellName": well}}),
                json!({"commandType": "moveToAddressableAreaForDropTip", "params": {"pipetteId": "p", "addressableAreaName": "fixedTrash"}}),
                json!({"commandType": "dropTipInPlace", "params": {"pipetteId": "p"}}),
            ]);
        }
    }
    commands.push(json!({"commandType": "thermocycler/closeLid", "params": {"moduleId": tc}}));
    let file = json!({
        "$otSharedSchema": "#/protocol/schemas/8", "schemaVersion": 8,
        "metadata": {"protocolName": "a whole plate"},
        "robot": {"model": "OT-2 Standard", "deckId": "ot2_standard"},
        "labwareDefinitions": {PLATE: definition(PLATE)?, RACK: definition(RACK)?, TIPS: definition(TIPS)?},
        "liquids": {"mm": {"displayName": "master mix"}},
        "commands": commands,
    });
    Ok(serde_json::to_string_pretty(&file)?)
}

/// A transport of `volume` µL (negative: drawn), of air when `air`.
fn transport(volume: f64, air: bool) -> Value {
    let mut t = json!({"volume": format!("{volume}:microliter")});
    if air {
        t["mode_params"] = json!({"liquid_class": "air"});
    }
    t
}

/// The plate as Autoprotocol: 20 µL into every well from two 1.5 mL tubes, then thermocycled.
fn largest_autoprotocol() -> Result<String> {
    let mut instructions = vec![
        json!({"op": "provision", "resource_id": "master_mix", "to": [
        {"well": "mix_1/0", "volume": "1000:microliter"}, {"well": "mix_2/0", "volume": "1000:microliter"}]}),
    ];
    for well in 0..96 {
        let source = if well < 48 { "mix_1/0" } else { "mix_2/0" };
        let mut at_source = vec![transport(-15.0, true), json!({}), transport(-5.0, false)];
        at_source.extend([
            transport(-20.0, false),
            transport(5.0, false),
            transport(-2.0, true),
        ]);
        let mut at_well = vec![transport(2.0, true), transport(20.0, false)];
        for _ in 0..10 {
            at_well.extend([transport(-20.0, false), transport(20.0, false)]);
        }
        at_well.push(transport(15.0, true));
        instructions.push(json!({"op": "liquid_handle", "mode": "air_displacement",
            "shape": {"rows": 1, "columns": 1, "format": "SBS96"},
            "locations": [{"location": source, "transports": at_source},
                          {"location": format!("plate/{well}"), "transports": at_well}]}));
    }
    instructions.push(json!({"op": "seal", "object": "plate", "type": "ultra-clear"}));
    instructions.push(json!({"op": "thermocycle", "object": "plate", "volume": "20:microliter",
        "groups": [{"cycles": 1, "steps": [{"temperature": "95:celsius", "duration": "30:second"}]},
                   {"cycles": 30, "steps": [{"temperature": "95:celsius", "duration": "15:second"},
                                            {"temperature": "55:celsius", "duration": "30:second"},
                                            {"temperature": "68:celsius", "duration": "1:minute"}]}]}));
    let doc = json!({"refs": {"mix_1": {"new": "micro-1.5", "discard": true},
                              "mix_2": {"new": "micro-1.5", "discard": true},
                              "plate": {"new": "96-pcr", "discard": true}},
                     "instructions": instructions});
    Ok(serde_json::to_string_pretty(&doc)?)
}

fn autoprotocol_figures(options: &interchange::Options) -> Result<()> {
    let text = largest_autoprotocol()?;
    let instructions = text.matches("\"op\"").count();
    let t = Instant::now();
    let imported = interchange::import(&text, options);
    let import_s = t.elapsed().as_secs_f64();
    let protocol = imported
        .protocol
        .context("the bench's Autoprotocol document was refused")?;
    let (task, _) = compiler::compile_source(&protocol, "plate.toml");
    let task = task.context("the bench's imported Autoprotocol does not compile")?;
    let t = Instant::now();
    let exported = interchange::autoprotocol::export::export(&task, 0)?;
    let export_s = t.elapsed().as_secs_f64();
    outln!(
        "import   Autoprotocol, {instructions} instructions, {:.0} kB {:>8.1} ms   (export of its protocol {:.1} ms, {:.0} kB)",
        text.len() as f64 / 1e3,
        import_s * 1e3,
        export_s * 1e3,
        exported.json.len() as f64 / 1e3
    );
    Ok(())
}

pub(crate) fn figures() -> Result<()> {
    let text = largest_file()?;
    let commands = text.matches("\"commandType\"").count();
    let options = interchange::Options {
        id: Some("bench.import".into()),
        instruction: None,
        robots: vec![],
        deps: runtime::deps::deps_dir(),
        file_name: "plate.json".into(),
        keep_instrument_steps: false,
    };
    let t = Instant::now();
    let imported = interchange::import(&text, &options);
    let import_s = t.elapsed().as_secs_f64();
    let protocol = imported
        .protocol
        .context("the bench's Opentrons file was refused")?;
    let t = Instant::now();
    let (task, _) = compiler::compile_source(&protocol, "plate.toml");
    let check_s = t.elapsed().as_secs_f64();
    outln!(
        "import   Opentrons file, {commands} commands, {:.0} kB {:>8.1} ms   (its protocol's check {:.1} ms{})",
        text.len() as f64 / 1e3,
        import_s * 1e3,
        check_s * 1e3,
        if task.is_some() { "" } else { ", with errors" }
    );
    autoprotocol_figures(&options)
}
