//! The faulty-protocol corpus: every file under tests/corpus/faulty declares, on its first line,
//! the diagnostic it must produce (`# expect: CODE at [FILE:]LINE:COL on `TEXT``). Each must fail
//! to compile with that code, at that place, covering exactly that text, with a lowercase message;
//! none may panic. Files under tests/corpus/fuzz are fuzzer findings, kept as regressions.

use std::path::{Path, PathBuf};

struct Expect {
    code: String,
    file: Option<String>,
    line: usize,
    col: usize,
    text: String,
}

fn expectation(path: &Path, source: &str) -> Expect {
    let first = source.lines().next().unwrap_or_default();
    let rest = first
        .strip_prefix("# expect: ")
        .unwrap_or_else(|| panic!("{}: first line must be `# expect: ..`", path.display()));
    let (code, rest) = rest.split_once(" at ").expect("`CODE at ..`");
    let (place, text) = rest.split_once(" on `").expect("`.. on `TEXT``");
    let text = text.strip_suffix('`').expect("text ends with a backtick");
    let mut parts: Vec<&str> = place.rsplitn(3, ':').collect();
    parts.reverse();
    let (file, line, col) = match parts.as_slice() {
        [f, l, c] => (Some(f.to_string()), l, c),
        [l, c] => (None, l, c),
        _ => panic!("{}: bad place `{place}`", path.display()),
    };
    Expect {
        code: code.to_string(),
        file,
        line: line.parse().unwrap(),
        col: col.parse().unwrap(),
        text: text.to_string(),
    }
}

fn files(dir: &str) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut out: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    out.sort();
    out
}

#[test]
fn every_faulty_file_gets_its_diagnostic_at_its_place() {
    let corpus = files("tests/corpus/faulty");
    assert!(corpus.len() >= 40, "the corpus has {} files", corpus.len());
    let mut codes = std::collections::BTreeSet::new();
    for path in corpus {
        let source = std::fs::read_to_string(&path).unwrap();
        let want = expectation(&path, &source);
        let name = path.display().to_string();
        let (task, diags) = compiler::compile_source(&source, &name);
        assert!(task.is_none(), "{name} must not compile");
        let d = diags
            .iter()
            .find(|d| d.code.as_str() == want.code)
            .unwrap_or_else(|| panic!("{name}: no {} in {diags:#?}", want.code));
        let (file, text) = match &d.file {
            Some(f) => (f.clone(), std::fs::read_to_string(f).unwrap()),
            None => (name.clone(), source.clone()),
        };
        if let Some(f) = &want.file {
            let expected = path.parent().unwrap().join(f);
            assert_eq!(
                Path::new(&file),
                expected,
                "{name}: the file it points into"
            );
        } else {
            assert!(d.file.is_none(), "{name}: points into {file}");
        }
        let (line, col) = dsl::render::line_col(&text, d.span.start);
        assert_eq!((line, col), (want.line, want.col), "{name}: place of {d:?}");
        assert_eq!(&text[d.span.start..d.span.end], want.text, "{name}: span");
        assert!(
            d.message.chars().next().is_some_and(|c| !c.is_uppercase()),
            "{name}: message must be lowercase: {}",
            d.message
        );
        assert!(d.hint.is_some() || !d.message.is_empty());
        codes.insert(want.code);
    }
    // The corpus exercises most of the error codes.
    assert!(codes.len() >= 20, "codes covered: {codes:?}");
}

#[test]
fn fuzzer_findings_stay_fixed() {
    for path in files("tests/corpus/fuzz") {
        let source = std::fs::read_to_string(&path).unwrap();
        let name = path.display().to_string();
        let (_, diags) = compiler::compile_source(&source, &name);
        for d in &diags {
            assert!(
                d.span.end <= source.len() || d.file.is_some(),
                "{name}: {d:?}"
            );
        }
    }
}
