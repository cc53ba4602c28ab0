//! `autobio bench`'s import figure: `autobio import` of the largest Opentrons file it is given
//! here, a Protocol Designer file (schema 8) filling a whole 96-well PCR plate on the
//! thermocycler from a tube, a fresh tip each well (680 commands, the installed labware
//! definitions inside, as Protocol Designer saves them): the import's wall time (read, realise,
//! write) and the written protocol's check (proof and lowering).

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

pub fn figures() -> Result<()> {
    let text = largest_file()?;
    let commands = text.matches("\"commandType\"").count();
    let options = interchange::Options {
        id: Some("bench.import".into()),
        instruction: None,
        robots: vec![],
        deps: runtime::deps::deps_dir(),
        file_name: "plate.json".into(),
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
    Ok(())
}
