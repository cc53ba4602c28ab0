//! The CLI as a user meets it, run as a real process: errors that say what was being done, once;
//! outputs that end with a newline; a closed stdout that ends the program quietly; colour only
//! when asked for or on a terminal; diagnostics rendered plain byte for byte as the goldens under
//! tests/golden/diagnostics (regenerate with `UPDATE_GOLDEN=1` and review the diff); and chains
//! that cannot make the tool read, or show, files outside their protocol root.

use crate::common;

use common::{autobio, scratch, text};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn stderr(o: &Output) -> String {
    common::text(&o.stderr)
}

#[test]
fn every_subcommand_says_what_it_was_doing_once_on_a_missing_file() {
    let missing = "no_such_protocol.toml";
    let os = "No such file or directory (os error 2)";
    let cases: &[(&[&str], String)] = &[
        (
            &["check", missing],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["describe", missing],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["compile", missing],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["demo", "--protocol", missing, "--out", "out/never"],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["eval", "--protocol", missing],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["bench", "--protocol", missing],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["synth", "--from", missing, "--out", "out/never"],
            format!("cannot read protocol {missing}: {os}"),
        ),
        (
            &["replay", "no_such_recording.mcap"],
            format!("cannot replay no_such_recording.mcap: cannot read the recording: {os}"),
        ),
        (
            &["export", "no_such_recording.mcap", "--out", "out/never"],
            format!("cannot export no_such_recording.mcap: cannot read the recording: {os}"),
        ),
        (
            &["dataset", "merge", "no_such_shard", "--out", "out/never"],
            format!("cannot read the shard no_such_shard: {os}"),
        ),
    ];
    for (args, message) in cases {
        let out = autobio(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert_eq!(stderr(&out), format!("error: {message}\n"), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    assert!(!Path::new("out/never").exists());
    // `check` reports an unreadable file and still checks the others.
    let out = autobio(&["check", missing, "protocols/thermal_cycler/close_lid.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        format!("error: cannot read protocol {missing}: {os}\n")
    );
    assert_eq!(
        common::text(&out.stdout),
        "ok: protocols/thermal_cycler/close_lid.toml\n"
    );
    // A chain checks clean, and says what the reach pass left to its stage files.
    let out = autobio(&["check", "protocols/thermal_cycler/close_then_open.toml"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        common::text(&out.stdout),
        "ok: protocols/thermal_cycler/close_then_open.toml (reach: not checked across the \
         chain's stages; each stage file is checked alone)\n"
    );
}

#[test]
fn every_output_ends_with_a_newline() {
    let close = "protocols/thermal_cycler/close_lid.toml";
    let chain = "protocols/thermal_cycler/close_then_open.toml";
    let runs: &[&[&str]] = &[
        &["check", close],
        &["describe", close],
        &["describe", close, "--seed", "3"],
        &["describe", chain, "--seed", "11"],
        &["describe", "--catalogue"],
        &["compile", close],
        &["explain", "E0009"],
        &["explain", "--all"],
        &["check", "--json", "tests/corpus/faulty/unknown_level.toml"],
        &["check", "tests/corpus/warnings/greek_mu.toml"],
    ];
    for args in runs {
        let out = autobio(args);
        for (stream, bytes) in [("stdout", &out.stdout), ("stderr", &out.stderr)] {
            assert!(
                bytes.is_empty() || bytes.ends_with(b"\n"),
                "{args:?}: {stream} ends without a newline: {:?}",
                String::from_utf8_lossy(&bytes[bytes.len().saturating_sub(60)..])
            );
        }
        assert!(!stderr(&out).contains("panicked"), "{args:?}");
    }
}

#[test]
fn a_closed_stdout_ends_the_program_quietly() {
    // Enough JSON lines to overflow any pipe buffer, so that the writer meets the closed pipe.
    let faulty: Vec<String> = std::fs::read_dir("tests/corpus/faulty")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| p.display().to_string())
        .collect();
    let mut args = vec!["check".to_string(), "--json".into()];
    for _ in 0..40 {
        args.extend(faulty.iter().cloned());
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with('{'), "{first}");
    // The reader is dropped here, as `| head -1` does.
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(stderr(&out), "", "nothing on stderr");
}

#[test]
fn colour_only_on_request_or_on_a_terminal() {
    let file = "tests/corpus/faulty/unknown_level.toml";
    let escape = "\x1b[";
    let always = autobio(&["check", "--color", "always", file]);
    assert!(stderr(&always).contains(escape), "{}", stderr(&always));
    // Not a terminal: plain.
    let auto = autobio(&["check", file]);
    assert!(!stderr(&auto).contains(escape));
    assert!(stderr(&auto).starts_with("error[E0021]: unknown level"));
    let never = autobio(&["check", "--color", "never", file]);
    assert_eq!(stderr(&never), stderr(&auto));
    // On a terminal (a pseudo-terminal from util-linux's `script`), `auto` colours unless
    // NO_COLOR is set; `always` colours either way, as in cargo.
    let on_terminal = |color: &str, no_color: bool| {
        let mut cmd = Command::new("script");
        cmd.args(["-qec"])
            .arg(format!(
                "{} check --color {color} {file}",
                env!("CARGO_BIN_EXE_autobio")
            ))
            .arg("/dev/null")
            .env_remove("NO_COLOR");
        if no_color {
            cmd.env("NO_COLOR", "1");
        }
        let out = cmd.output().unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let tty = on_terminal("auto", false);
    assert!(tty.contains("unknown level"), "{tty}");
    assert!(tty.contains(escape), "auto on a terminal: {tty}");
    let tty = on_terminal("auto", true);
    assert!(
        tty.contains("unknown level") && !tty.contains(escape),
        "{tty}"
    );
    assert!(on_terminal("always", true).contains(escape));
}

#[test]
fn diagnostics_render_plain_as_their_goldens() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    let cases = [
        "faulty/unclosed_multiline_string",
        "faulty/not_utf8",
        "faulty/chain_param_differs",
        "faulty/chain_stage_absolute_path",
        "faulty/two_spellings_time_limit",
        "faulty/volume_param_without_unit",
        "warnings/greek_mu",
        "warnings/proof_sampled",
    ];
    let mut stale = Vec::new();
    for case in cases {
        let file = format!("tests/corpus/{case}.toml");
        let out = autobio(&["check", "--root", ".", &file]);
        let text = stderr(&out);
        let golden =
            Path::new("tests/golden/diagnostics").join(format!("{}.txt", case.replace('/', "__")));
        if update {
            std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
            std::fs::write(&golden, &text).unwrap();
        }
        let want = std::fs::read_to_string(&golden).unwrap_or_else(|_| {
            panic!("{} is missing: run with UPDATE_GOLDEN=1", golden.display())
        });
        if want != text {
            stale.push(format!("{}:\n{text}", golden.display()));
        }
    }
    // A run that rewrote the goldens compared nothing: it never passes.
    assert!(
        !update,
        "UPDATE_GOLDEN: {} goldens written; review `git diff tests/golden/diagnostics`, then run again without it",
        cases.len()
    );
    assert!(
        stale.is_empty(),
        "rendered diagnostics changed:\n{}",
        stale.join("\n")
    );
}

/// Runs `autobio check` with a deadline: a stage that names a pipe must not block the check.
fn check_within(args: &[&str], seconds: u64) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            child.kill().unwrap();
            panic!("`autobio {args:?}` did not finish in {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A chain in `dir` with one stage.
fn chain_with_stage(dir: &Path, stage: &str) -> String {
    let chain = dir.join("chain.toml");
    std::fs::write(
        &chain,
        format!("format = 1\n\n[chain]\nid = \"c\"\n\n[[stages]]\nprotocol = \"{stage}\"\n"),
    )
    .unwrap();
    chain.display().to_string()
}

#[test]
fn a_chain_cannot_read_or_show_files_outside_its_root() {
    let secret_line = "the content of a private file";
    let outside = scratch("outside");
    let secret = outside.join("secret.toml");
    std::fs::write(&secret, format!("[protocol]\nid = \"{secret_line}\n")).unwrap();
    let root = scratch("root");

    // Climbing out, an absolute path, and a symbolic link inside the root pointing out.
    std::os::unix::fs::symlink(&secret, root.join("link.toml")).unwrap();
    for stage in [
        format!(
            "../{}/secret.toml",
            outside.file_name().unwrap().to_string_lossy()
        ),
        secret.display().to_string(),
        "link.toml".into(),
    ] {
        let chain = chain_with_stage(&root, &stage);
        let out = check_within(&["check", &chain], 20);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains("error[E0009]"), "{stage}: {err}");
        assert!(err.contains(&format!("{chain}:7:12")), "{stage}: {err}");
        assert!(
            !err.contains(secret_line),
            "{stage}: the file's text is shown: {err}"
        );
    }
    // Widening the root lets the chain read it; the stage's own problem is then reported in it,
    // with a note naming the chain line.
    let chain = chain_with_stage(&root, "link.toml");
    let parent = root.parent().unwrap().display().to_string();
    let out = check_within(&["check", "--root", &parent, &chain], 20);
    let err = stderr(&out);
    assert!(err.contains("error[E0001]: unclosed basic string"), "{err}");
    assert!(
        err.contains(&format!("note: in stage 1, included from {chain}:7:12")),
        "{err}"
    );

    // A pipe: refused without being opened (opening it would block).
    let fifo = root.join("pipe.toml");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let chain = chain_with_stage(&root, "pipe.toml");
    let err = stderr(&check_within(&["check", &chain], 20));
    assert!(
        err.contains("error[E0009]: stage `pipe.toml` is not a regular file"),
        "{err}"
    );

    // A file over the size bound: refused without being read.
    let big = std::fs::File::create(root.join("big.toml")).unwrap();
    big.set_len(2 << 20).unwrap();
    let chain = chain_with_stage(&root, "big.toml");
    let err = stderr(&check_within(&["check", &chain], 20));
    assert!(
        err.contains("error[E0009]: stage `big.toml` is 2097152 bytes, more than the 1048576"),
        "{err}"
    );

    // A TOML file inside the root that is not a protocol: named, never echoed.
    std::fs::write(
        root.join("data.toml"),
        format!("note = \"{secret_line}\"\n"),
    )
    .unwrap();
    let chain = chain_with_stage(&root, "data.toml");
    let err = stderr(&check_within(&["check", &chain], 20));
    assert!(
        err.contains("error[E0006]: stage `data.toml` is not a protocol file"),
        "{err}"
    );
    assert!(!err.contains(secret_line), "{err}");
    let _ = std::fs::remove_dir_all(&outside);
    let _ = std::fs::remove_dir_all(&root);
}

/// `autobio tasks --verify-hold --expert-first M` (CI's expert column): a task whose expert now
/// wins fewer of the table's first seeds than its row's Wilson lower bound fails it; the same
/// row passes where the expert still wins, and a row with no interval is a problem too.
#[test]
fn the_expert_column_check_fails_a_task_whose_expert_fell_below_its_row() {
    let dir = scratch("verify-expert");
    let (good, slow) = (dir.join("good"), dir.join("slow"));
    std::fs::create_dir_all(&good).unwrap();
    std::fs::create_dir_all(&slow).unwrap();
    let protocol = std::fs::read_to_string("protocols/tube/transfer.toml").unwrap();
    std::fs::write(good.join("transfer.toml"), &protocol).unwrap();
    // The same task with 4 s to do 10 s of work: the expert can no longer win it (and hold
    // still fails it, to its shorter limit).
    assert!(protocol.contains("time_limit = \"15 s\""));
    std::fs::write(
        slow.join("transfer.toml"),
        protocol.replace("time_limit = \"15 s\"", "time_limit = \"4 s\""),
    )
    .unwrap();
    let table = dir.join("tasks.md");
    std::fs::write(
        &table,
        "# Tasks\n\nGenerated by `autobio tasks x --episodes 100 --seed 0` (`make tasks-doc`).\n\n\
         | task | expert success | hold score |\n|---|---|---|\n\
         | `tube.transfer` | 100/100 (100%, [96, 100]) | 0.000 |\n",
    )
    .unwrap();
    let table = table.display().to_string();
    let args = |dir: &std::path::Path| {
        autobio(&[
            "tasks",
            dir.to_str().unwrap(),
            "--verify-hold",
            &table,
            "--first",
            "1",
            "--expert-first",
            "2",
        ])
    };
    let out = args(&good);
    let said = text(&out.stdout) + &text(&out.stderr);
    assert!(out.status.success(), "{said}");
    assert!(said.contains("tube.transfer: expert 2/2"), "{said}");
    assert!(said.contains("expert column holds"), "{said}");
    let out = args(&slow);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{said}");
    let problems: Vec<&str> = said.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(
        problems,
        [format!(
            "error: tube.transfer ({}): the expert won 0 of the table's first 2 seeds, below its \
             row's Wilson lower bound of 96%",
            slow.join("transfer.toml").display()
        )],
        "{said}"
    );
}

/// `autobio tasks --verify-hold` (CI's hold column): a task a motionless robot passes, a table
/// row for a task that no longer runs and a task with no row each fail it; the honest table passes,
/// on all its seeds or on its first N (`--first`).
#[test]
fn the_hold_column_check_fails_a_task_that_hold_passes_and_a_stale_table() {
    let dir = scratch("verify-hold");
    let (good, bad) = (dir.join("good"), dir.join("bad"));
    std::fs::create_dir_all(good.join("tube")).unwrap();
    std::fs::create_dir_all(&bad).unwrap();
    std::fs::copy(
        "protocols/tube/transfer.toml",
        good.join("tube/transfer.toml"),
    )
    .unwrap();
    // Its success holds at the start: the tube is placed back where it stands.
    std::fs::copy(
        "tests/corpus/warnings/success_holds_at_start.toml",
        bad.join("holds_at_start.toml"),
    )
    .unwrap();
    let table = |rows: &str| {
        format!(
            "# Tasks\n\nGenerated by `autobio tasks x --episodes 2 --seed 5` (`make tasks-doc`).\n\n\
             | task | hold score |\n|---|---|\n{rows}"
        )
    };
    let write = |name: &str, rows: &str| {
        let path = dir.join(name);
        std::fs::write(&path, table(rows)).unwrap();
        path.display().to_string()
    };
    let honest = write("honest.md", "| `tube.transfer` | 0.000 |\n");
    let stale = write(
        "stale.md",
        "| `tube.transfer` | 0.000 |\n| `gone.task` | 0.000 |\n",
    );
    let missing = write("missing.md", "| `other.task` | 0.000 |\n");
    let good = good.display().to_string();
    let bad = bad.display().to_string();

    let out = autobio(&["tasks", &good, "--verify-hold", &honest]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    assert!(text(&out.stdout).contains("every task scored 0 on seeds 5..6"));
    // CI's budget: the first of the table's two seeds only; more than it has is its own count.
    let out = autobio(&["tasks", &good, "--verify-hold", &honest, "--first", "1"]);
    assert!(text(&out.stdout).contains("every task scored 0 on seeds 5..5"));
    let out = autobio(&["tasks", &good, "--verify-hold", &honest, "--first", "9"]);
    assert!(text(&out.stdout).contains("every task scored 0 on seeds 5..6"));

    let out = autobio(&["tasks", &bad, "--verify-hold", &stale]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(
        said.contains("tube.transfer") && said.contains("with no motion it won 2 of 2 episodes"),
        "{said}"
    );
    let out = autobio(&["tasks", &bad, "--verify-hold", &stale, "--first", "1"]);
    assert!(text(&out.stdout).contains("with no motion it won 1 of 1 episodes"));
    assert!(
        said.contains("gone.task is in the table, but no protocol file runs it"),
        "{said}"
    );

    let out = autobio(&["tasks", &good, "--verify-hold", &missing]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(
        said.contains("tube.transfer") && said.contains("runs, but the table has no row for it"),
        "{said}"
    );
    assert!(said.contains("other.task is in the table"), "{said}");
}
