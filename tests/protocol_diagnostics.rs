//! Malformed protocol files: each gives its diagnostic code with a span on the right text, and
//! nothing panics. Also checks `autobio check` end to end as a process.

use std::path::Path;
use std::process::Command;

fn diagnose(file: &str) -> (String, Vec<dsl::Diagnostic>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/bad")
        .join(file);
    let source = std::fs::read_to_string(&path).unwrap();
    let (task, diags) = compiler::compile_source(&source, file);
    assert!(task.is_none(), "{file} must not compile");
    (source, diags)
}

/// (file, code, text the span must cover, line)
const CASES: &[(&str, &str, &str, usize)] = &[
    ("bad_toml.toml", "E0001", "", 10),
    ("unknown_kind.toml", "E0010", "\"thermal_cycle\"", 17),
    ("unknown_primitive.toml", "E0012", "\"shut_lid\"", 25),
    ("unit_unknown.toml", "E0020", "\"31.5 kg\"", 10),
    ("unit_dimension.toml", "E0020", "\"31.5 deg\"", 10),
    ("unit_missing.toml", "E0020", "31.5", 10),
    ("unknown_reference.toml", "E0013", "\"cyclr\"", 26),
    ("precondition.toml", "E0031", "\"close_lid\"", 25),
    ("bad_predicate.toml", "E0030", "\"cycler.lid is ajar\"", 30),
    ("unknown_key.toml", "E0003", "levle", 8),
    ("unknown_robot.toml", "E0011", "\"ur10\"", 13),
];

#[test]
fn each_malformed_file_gets_its_code_and_span() {
    for &(file, code, text, line) in CASES {
        let (source, diags) = diagnose(file);
        let d = diags
            .iter()
            .find(|d| d.code.as_str() == code)
            .unwrap_or_else(|| panic!("{file}: no {code} in {diags:#?}"));
        let (l, _) = dsl::render::line_col(&source, d.span.start);
        assert_eq!(
            l, line,
            "{file}: {code} on line {l}, expected {line}: {d:?}"
        );
        if !text.is_empty() {
            assert_eq!(
                &source[d.span.start..d.span.end],
                text,
                "{file}: span of {code}"
            );
        }
        assert!(
            d.message.chars().next().is_some_and(|c| !c.is_uppercase()),
            "{file}: message must be lowercase: {}",
            d.message
        );
    }
}

#[test]
fn hints_suggest_the_closest_name() {
    let (_, diags) = diagnose("unknown_kind.toml");
    assert_eq!(
        diags[0].hint.as_deref(),
        Some("did you mean `thermal_cycler`?")
    );
    let (_, diags) = diagnose("unknown_primitive.toml");
    assert!(
        diags[0].hint.as_deref().unwrap().contains("close_lid"),
        "{:?}",
        diags[0].hint
    );
}

/// Every prefix of a good file, and every single-byte corruption of it, either compiles or is
/// refused with an error whose span lies inside the text (so it can be shown at file:line:col):
/// never a panic, never a silent "no task and no error".
#[test]
fn truncated_and_mangled_files_compile_or_say_why() {
    let good = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/thermal_cycler/close_lid.toml"),
    )
    .unwrap();
    let (mut compiled, mut refused) = (0, 0);
    let mut judge = |src: &str, name: &str| {
        let (task, diags) = compiler::compile_source(src, name);
        for d in &diags {
            assert!(
                d.file.is_some() || (d.span.start <= d.span.end && d.span.end <= src.len()),
                "{name}: {} at {:?} outside {} bytes",
                d.code,
                d.span,
                src.len()
            );
        }
        match task {
            Some(_) => compiled += 1,
            None => {
                assert!(
                    diags.iter().any(|d| d.is_error()),
                    "{name}: no task and no error for {src:?}"
                );
                refused += 1;
            }
        }
    };
    for end in (0..good.len()).filter(|&i| good.is_char_boundary(i)) {
        judge(&good[..end], "prefix.toml");
    }
    for i in (0..good.len())
        .step_by(3)
        .filter(|&i| good.is_char_boundary(i) && good.is_char_boundary(i + 1))
    {
        for c in ["\"", "[", "=", "\n", "x", "0", "]"] {
            let mangled = format!("{}{}{}", &good[..i], c, &good[i + 1..]);
            judge(&mangled, "mangled.toml");
        }
    }
    // Both outcomes happen: the whole file compiles, the empty prefix does not.
    assert!(
        compiled > 0 && refused > 0,
        "{compiled} compiled, {refused} refused"
    );
}

fn autobio(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn check_command_reports_file_line_col_and_fails() {
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad/unknown_kind.toml");
    let out = autobio(&["check".as_ref(), bad.as_os_str()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("error[E0010]: unknown labware kind `thermal_cycle`"),
        "{err}"
    );
    assert!(err.contains("unknown_kind.toml:17:8"), "{err}");
    assert!(
        err.contains("hint: did you mean `thermal_cycler`?"),
        "{err}"
    );
    let good = Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/thermal_cycler/open_lid.toml");
    let out = autobio(&["check".as_ref(), good.as_os_str()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn explain_documents_every_code() {
    let out = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["explain", "E0031"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("precondition"));
}

/// The key-latched centrifuge: its `open` key releases the latch whether pressed by `press` or by
/// `unlock`, after which `open_lid` compiles; without it the hint names the missing step, and
/// `lock` is refused with the way to latch it.
#[test]
fn a_key_latched_lid_is_released_by_its_key_before_it_opens() {
    let shipped = std::fs::read_to_string("protocols/centrifuge_5430/open_lid.toml").unwrap();
    let compile =
        |source: &str| compiler::compile_source(source, "protocols/centrifuge_5430/open_lid.toml");
    assert!(compile(&shipped).0.is_some(), "unlock, then open_lid");
    let pressed = shipped.replacen("do = \"unlock\"", "do = \"press\"\nbutton = \"open\"", 1);
    assert!(
        compile(&pressed).0.is_some(),
        "press the key, then open_lid"
    );
    let unkeyed = shipped.replacen("do = \"unlock\"", "do = \"press\"\nbutton = \"stop\"", 1);
    let (task, diags) = compile(&unkeyed);
    assert!(task.is_none() && diags.iter().any(|d| d.code.to_string() == "E0013"));
    for (file, says) in [
        (
            "open_a_latched_centrifuge_without_its_key.toml",
            "add an `unlock` step on `centrifuge`",
        ),
        (
            "lock_a_key_latched_centrifuge.toml",
            "`open_lid`, then `close_lid`",
        ),
    ] {
        let path = format!("tests/corpus/faulty/{file}");
        let (task, diags) = compile(&std::fs::read_to_string(path).unwrap());
        assert!(task.is_none(), "{file}");
        let hint = diags[0].hint.clone().unwrap_or_default();
        assert!(hint.contains(says), "{file}: {hint}");
    }
}

/// The rotor protocol with its `[randomise.centrifuge]` line replaced: the task, or the codes.
fn rotor_jitter(line: &str) -> Result<f64, Vec<String>> {
    let path = "protocols/centrifuge/insert_symmetric.toml";
    let source = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
        .unwrap()
        .replace("joints_rad = { rotor = 0.1 }", line);
    let (task, diags) = compiler::compile_source(&source, path);
    match task {
        Some(t) => Ok(t.labware[0].joint_jitter["rotor"]),
        None => Err(diags.iter().map(|d| d.code.to_string()).collect()),
    }
}

#[test]
fn a_labware_joint_offset_takes_its_own_unit_and_is_refused_where_it_cannot_apply() {
    assert_eq!(rotor_jitter("joints_rad = { rotor = 0.1 }"), Ok(0.1));
    assert_eq!(rotor_jitter("joints = { rotor = \"0.1 rad\" }"), Ok(0.1));
    // A value's own unit wins over the table's.
    let five_deg = rotor_jitter("joints_rad = { rotor_deg = 5 }").unwrap();
    assert!((five_deg - 5f64.to_radians()).abs() < 1e-12, "{five_deg}");
    assert!((rotor_jitter("joints = { rotor = \"-5 deg\" }").unwrap() - five_deg).abs() < 1e-12);
    for (line, code) in [
        ("joints_rad = { rotor = 0.1, rotor_deg = 5 }", "E0007"),
        ("joints_rad = {}", "E0002"),
        ("joints_rad = { lid = 0.1 }", "E0003"),
        ("joints_rad = { roter = 0.1 }", "E0003"),
        ("joints_rad = { rotor = 4 }", "E0021"),
        ("joints = { rotor = \"4 kg\" }", "E0020"),
        ("joints_rad = { low = [-0.1], high = [0.1] }", "E0004"),
    ] {
        let codes = rotor_jitter(line).expect_err(line);
        assert!(codes.iter().any(|c| c == code), "{line}: {codes:?}");
    }
}

/// The slots of a lidded instrument are reachable only while its lid is open: taking a tube out
/// of a locked centrifuge's rotor is E0031 at the step (tests/corpus/faulty has it), and the same
/// plan with `unlock` and `open_lid` first proves clean.
#[test]
fn opening_the_lid_first_makes_the_rotor_reachable() {
    let faulty = "tests/corpus/faulty/pick_from_a_locked_centrifuge.toml";
    let text = std::fs::read_to_string(faulty).unwrap();
    let (task, diags) = compiler::compile_source(&text, faulty);
    assert!(task.is_none());
    let d = diags.iter().find(|d| d.code == dsl::Code::E0031).unwrap();
    assert!(d.message.contains("whose lid is locked"), "{}", d.message);
    let opened = text.replacen(
        "[[steps]]\ndo = \"pick\"\non = \"placed\"",
        "[[steps]]\ndo = \"unlock\"\non = \"centrifuge\"\nwith = \"arm\"\n\n[[steps]]\ndo = \"open_lid\"\non = \"centrifuge\"\nwith = \"arm\"\n\n[[steps]]\ndo = \"pick\"\non = \"placed\"",
        1,
    );
    assert_ne!(opened, text);
    let (task, diags) = compiler::compile_source(&opened, faulty);
    assert!(
        task.is_some() && !diags.iter().any(|d| d.is_error()),
        "{diags:#?}"
    );
}

/// A place template no value of its parameter can fill says so once, with why (the rack takes no
/// PCR tube) as its note and what the rack takes as its hint; one that only some values fail lists
/// those, numbers in their order (13 before 100).
#[test]
fn a_place_no_value_fills_says_so_and_failing_values_are_listed_in_order() {
    let source = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/lab/pcr_setup.toml"),
    )
    .unwrap();
    let e0016 = |text: &str| {
        let (task, diags) = compiler::compile_source(text, "pcr_setup.toml");
        assert!(task.is_none(), "{text}");
        diags
            .into_iter()
            .find(|d| d.code == dsl::Code::E0016)
            .expect("an E0016")
    };
    let in_rack = e0016(&source.replace("at = \"block.A{column}\"", "at = \"rack.A{column}\""));
    assert_eq!(
        in_rack.message,
        "`rack.A{column}` names no slot it can use for any value of `column`"
    );
    assert_eq!(in_rack.hint.as_deref(), Some("it takes: tube_1_5ml"));
    assert!(
        in_rack
            .notes
            .iter()
            .any(|n| n.contains("does not take a tube_0_2ml")),
        "{:?}",
        in_rack.notes
    );
    let some = e0016(&source.replace("int = [1, 12]", "choice = [100, 9, 13]")).message;
    assert!(
        some.ends_with("when `column = 13` or `column = 100`"),
        "{some}"
    );
}

/// `[protocol] imported_from` (what `autobio import` writes): the compiled task carries it; a
/// hash that is not 64 hex digits, a missing key and an unknown one are each said.
#[test]
fn imported_from_is_carried_and_checked() {
    let source = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/lab/pcr_setup.toml"),
    )
    .unwrap();
    let sha = "ab".repeat(32);
    let with = |table: &str| {
        source.replacen(
            "time_limit = \"120 s\"\n",
            &format!("time_limit = \"120 s\"\nimported_from = {table}\n"),
            1,
        )
    };
    let good = with(&format!(
        "{{ file = \"pcr.json\", format = \"Opentrons protocol JSON, schema 8\", sha256 = \"{sha}\" }}"
    ));
    let (task, diags) = compiler::compile_source(&good, "pcr_setup.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let from = task.imported_from.expect("carried");
    assert_eq!(
        (from.file.as_str(), from.sha256.as_str()),
        ("pcr.json", sha.as_str())
    );
    for (table, code, says) in [
        (
            "{ file = \"a.json\", format = \"f\", sha256 = \"abc\" }",
            dsl::Code::E0021,
            "not 64 hex digits",
        ),
        (
            "{ file = \"a.json\", format = \"f\" }",
            dsl::Code::E0002,
            "has no `sha256`",
        ),
        (
            &format!("{{ file = \"a.json\", format = \"f\", sha256 = \"{sha}\", by = \"me\" }}"),
            dsl::Code::E0003,
            "unknown key `by`",
        ),
    ] {
        let (task, diags) = compiler::compile_source(&with(table), "pcr_setup.toml");
        assert!(task.is_none(), "{table}");
        assert!(
            diags
                .iter()
                .any(|d| d.code == code && d.message.contains(says)),
            "{table}: {diags:#?}"
        );
    }
}
