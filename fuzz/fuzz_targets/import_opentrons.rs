//! Fuzzes `autobio import` on arbitrary bytes read as an Opentrons file: nothing may panic, every
//! finding must point inside the input, and a written protocol must parse as TOML. Seed it with
//! Opentrons analysis and Protocol Designer files (`fuzz/run.sh import_opentrons DIR`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let options = interchange::Options {
        id: Some("fuzz.case".into()),
        instruction: None,
        robots: vec![],
        deps: std::path::PathBuf::from("../.deps"),
        file_name: "case.json".into(),
        keep_instrument_steps: false,
    };
    let imported = interchange::import(text, &options);
    for d in &imported.diagnostics {
        assert!(d.span.start <= d.span.end && d.span.end <= text.len(), "{d:?}");
    }
    if let Some(p) = &imported.protocol {
        let (_, diags) = dsl::parse(p);
        assert!(!diags.iter().any(|d| d.code == dsl::Code::E0001), "{p}");
    }
});
