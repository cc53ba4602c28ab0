//! Fuzzes the whole front end: parse, check, state proof and lowering, on arbitrary text, as a
//! protocol and as a chain whose stages are a known-good protocol. Nothing may panic, every
//! diagnostic must point inside its file, and a compiled task must serialise.
#![no_main]

use libfuzzer_sys::fuzz_target;

const STAGE: &str = include_str!("../../protocols/thermal_cycler/close_lid.toml");

fuzz_target!(|data: &[u8]| {
    let source = match dsl::source::decode(data) {
        Ok(s) => s,
        Err(d) => {
            // Not UTF-8: located at the first bad byte, inside the input.
            assert!(d.span.start < data.len() && d.span.end <= data.len(), "{d:?}");
            return;
        }
    };
    let load = |path: &str| -> Result<String, compiler::stage_files::StageError> {
        if path.ends_with("self.toml") {
            Ok(source.to_string())
        } else {
            Ok(STAGE.to_string())
        }
    };
    let (task, diags) = compiler::compile_source_with(source, "fuzz/input.toml", &load);
    for d in &diags {
        let len = if d.file.is_some() {
            STAGE.len().max(source.len())
        } else {
            source.len()
        };
        assert!(d.span.start <= d.span.end && d.span.end <= len, "{d:?}");
        let _ = dsl::render::line_col(source, d.span.start.min(source.len()));
    }
    if let Some(t) = task {
        assert!(!diags.iter().any(|d| d.is_error()));
        let json = serde_json::to_string(&t).expect("a task serialises");
        assert!(!json.is_empty());
        let _ = compiler::describe::describe(&t);
        let _ = t.sample(7);
    }
});
