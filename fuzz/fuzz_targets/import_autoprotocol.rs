//! Fuzzes `autobio import` on arbitrary bytes read as an Autoprotocol document, and the export of
//! what it writes: nothing may panic, every finding must point inside the input, a written
//! protocol must parse as TOML, and one that compiles must export. Seed it with Autoprotocol
//! files (`fuzz/run.sh import_autoprotocol SECONDS DIR`).
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
        keep_instrument_steps: true,
    };
    let imported = interchange::import(text, &options);
    for d in &imported.diagnostics {
        assert!(d.span.start <= d.span.end && d.span.end <= text.len(), "{d:?}");
    }
    if let Some(p) = &imported.protocol {
        let (_, diags) = dsl::parse(p);
        assert!(!diags.iter().any(|d| d.code == dsl::Code::E0001), "{p}");
        if let (Some(task), _) = compiler::compile_source(p, "case.toml") {
            let _ = interchange::autoprotocol::export::export(&task, 0);
        }
    }
});
