//! The faulty-protocol corpus: every file under tests/corpus/faulty declares, on its first line,
//! the diagnostic it must produce (`# expect: CODE at [FILE:]LINE:COL on `TEXT``). Each must fail
//! to compile with that code, at that place, covering exactly that text, with a lowercase message;
//! none may panic. Files under tests/corpus/warnings compile, with the warning they declare.
//! Files under tests/corpus/fuzz are fuzzer findings, kept as regressions. Chains are checked
//! with the repository as their protocol root (`--root`), so that they can name shipped
//! protocols; tests/corpus/faulty/stages holds stage files for chains, not cases. Files under
//! tests/corpus/multi hold several independent mistakes, one `# expect:` line each: one `check`
//! must report exactly those, each at its place.

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
    parse_expect(path, first)
}

/// One `# expect: CODE at [FILE:]LINE:COL on `TEXT`` line.
fn parse_expect(path: &Path, line: &str) -> Expect {
    let rest = line
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

/// Checks `path` as `autobio check --root <repository>` does.
fn check(path: &Path) -> compiler::Checked {
    let mut checked =
        compiler::check_file(path, Some(Path::new(env!("CARGO_MANIFEST_DIR")))).unwrap();
    // As `autobio check` does: the reach of each step's robot (E0036).
    expert::reach::check(&mut checked, &expert::reach::Store::none());
    checked
}

/// Asserts that `checked` has the expected diagnostic at its place; returns it.
fn assert_expected(path: &Path, checked: &compiler::Checked) -> dsl::Diagnostic {
    let name = path.display().to_string();
    let source = std::fs::read(path).unwrap();
    let want = expectation(path, &String::from_utf8_lossy(&source));
    let diags = &checked.diagnostics;
    let d = diags
        .iter()
        .find(|d| d.code.as_str() == want.code)
        .unwrap_or_else(|| panic!("{name}: no {} in {diags:#?}", want.code));
    let (file, text) = checked
        .text_of(d)
        .unwrap_or_else(|| panic!("{name}: {d:?} points into a file that was not shown"));
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
    // Spans are byte ranges of the file as read; a span on a byte that is not UTF-8 reads back
    // as U+FFFD.
    let bytes = if d.file.is_none() {
        source.clone()
    } else {
        text.as_bytes().to_vec()
    };
    let covered = String::from_utf8_lossy(&bytes[d.span.start..d.span.end]);
    assert_eq!(covered, want.text, "{name}: span");
    assert!(
        d.message.chars().next().is_some_and(|c| !c.is_uppercase()),
        "{name}: message must be lowercase: {}",
        d.message
    );
    assert!(
        d.hint.as_ref().is_none_or(|h| !h.trim().is_empty()),
        "{name}: a blank hint"
    );
    d.clone()
}

#[test]
fn every_faulty_file_gets_its_diagnostic_at_its_place() {
    let corpus = files("tests/corpus/faulty");
    assert!(corpus.len() >= 80, "the corpus has {} files", corpus.len());
    let mut codes = std::collections::BTreeSet::new();
    for path in corpus {
        let checked = check(&path);
        assert!(
            checked.task.is_none(),
            "{} must not compile",
            path.display()
        );
        let d = assert_expected(&path, &checked);
        codes.insert(d.code);
    }
    // Every error code has a case (the importer's codes, about the files it reads, have theirs
    // in tests/import.rs).
    let errors: std::collections::BTreeSet<dsl::Code> = dsl::Code::ALL
        .into_iter()
        .filter(|c| !c.is_warning() && !c.is_import())
        .collect();
    assert_eq!(codes, errors, "error codes with a case");
}

/// Files under tests/corpus/warnings compile, with the expected warning at its place, checked as
/// `autobio check` checks them (the reach pass included: it leaves a unit slip, W0003, alone).
#[test]
fn every_warning_file_compiles_with_its_warning_at_its_place() {
    let corpus = files("tests/corpus/warnings");
    let mut codes = std::collections::BTreeSet::new();
    for path in corpus {
        let checked = check(&path);
        assert!(
            checked.task.is_some(),
            "{} must compile: {:#?}",
            path.display(),
            checked.diagnostics
        );
        let d = assert_expected(&path, &checked);
        assert!(!d.is_error(), "{}: {d:?}", path.display());
        codes.insert(d.code);
    }
    // W0007 (a start state a model cannot set up) has no case while every shipped model sets up
    // every start the language allows: its last one, a tube whose cap starts off, is now built
    // open. It stays for the next model that cannot.
    let want: std::collections::BTreeSet<dsl::Code> = dsl::Code::ALL
        .into_iter()
        .filter(|c| c.is_warning() && *c != dsl::Code::W0007 && !c.is_import())
        .collect();
    assert_eq!(codes, want, "every warning has a case");
}

#[test]
fn fuzzer_findings_stay_fixed() {
    let findings = files("tests/corpus/fuzz");
    assert!(
        !findings.is_empty(),
        "no fuzzer finding under tests/corpus/fuzz"
    );
    for path in findings {
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

/// Files with several independent mistakes get every one of them in one pass: exactly the
/// diagnostics their `# expect:` lines list, each at its place covering its text.
#[test]
fn every_mistake_of_a_multi_mistake_file_is_found_in_one_pass() {
    let corpus = files("tests/corpus/multi");
    assert!(!corpus.is_empty());
    for path in corpus {
        let name = path.display().to_string();
        let source = std::fs::read_to_string(&path).unwrap();
        let wants: Vec<Expect> = source
            .lines()
            .take_while(|l| l.starts_with("# expect: "))
            .map(|l| parse_expect(&path, l))
            .collect();
        assert!(
            wants.len() >= 2,
            "{name}: a multi-mistake file lists its mistakes"
        );
        let checked = check(&path);
        let found: Vec<(String, usize, usize, String)> = checked
            .diagnostics
            .iter()
            .map(|d| {
                let (line, col) = dsl::render::line_col(&source, d.span.start);
                let text = source[d.span.start..d.span.end].to_string();
                (d.code.as_str().to_string(), line, col, text)
            })
            .collect();
        let mut want: Vec<(String, usize, usize, String)> = wants
            .into_iter()
            .map(|e| (e.code, e.line, e.col, e.text))
            .collect();
        let mut got = found.clone();
        want.sort();
        got.sort();
        assert_eq!(got, want, "{name}: {:#?}", checked.diagnostics);
    }
}
