//! Leaderboard submissions with real files: a suite run by `autobio eval --suite` (the scripted
//! expert, and a model server on loopback), packed by `autobio leaderboard submit`, verifies;
//! each way a submitter or a stranger's file can lie is refused by `verify` with its own message:
//! a flipped verdict, an edited journal (with and without its index hash updated), a recording
//! whose states were forged so that plain replay scores it a success, an action changed by 1e-9,
//! a changed protocol, a missing or duplicated seed, and archives with a path that climbs out,
//! a link, a truncated end, a decompression bomb or an unknown schema.

use crate::common;

use common::{Server, autobio, scratch, text};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const TASK: &str = "thermal_cycler.close_lid";

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(path)
        .display()
        .to_string()
}

/// A folder of shipped suites holding `mini`: `protocol`, 2 episodes from seed 0, 1 run.
fn suites(name: &str, protocol: &str) -> PathBuf {
    let dir = scratch(name);
    std::fs::write(
        dir.join("mini.toml"),
        format!(
            "format = 1\n[suite]\nname = \"mini\"\nepisodes = 2\nseed = 0\nruns = 1\ntasks = [\"{protocol}\"]\n"
        ),
    )
    .unwrap();
    dir
}

/// The shipped suites, an expert run of them, its bundle; made once.
struct Fixture {
    suites: PathBuf,
    run: PathBuf,
    hold: PathBuf,
    bundle: PathBuf,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let suites = suites(
            "lb-suites",
            &repo("protocols/thermal_cycler/close_lid.toml"),
        );
        let suite = suites.join("mini.toml");
        let root = scratch("lb-runs");
        let (run, hold) = (root.join("expert"), root.join("hold"));
        for (dir, policy) in [(&run, "expert"), (&hold, "hold")] {
            common::eval_suite(&suite, dir, &["--policy", policy]);
        }
        let bundle = root.join("expert.tar.zst");
        let said = common::submit(&run, "scripted expert", &bundle, &["--training", "none"]);
        assert!(said.contains("for suite mini"), "{said}");
        Fixture {
            suites,
            run,
            hold,
            bundle,
        }
    })
}

/// `verify`'s exit code and output.
fn verify(bundle: &Path, suites: &Path) -> (i32, String) {
    let out = autobio(&[
        "leaderboard",
        "verify",
        bundle.to_str().unwrap(),
        "--suites",
        suites.to_str().unwrap(),
    ]);
    (
        out.status.code().unwrap(),
        text(&out.stdout) + &text(&out.stderr),
    )
}

/// `verify` refuses the bundle for exactly `reasons`, in the verifier's own words.
fn refused<S: AsRef<str>>(bundle: &Path, suites: &Path, reasons: &[S]) -> String {
    let (code, said) = verify(bundle, suites);
    assert_eq!(code, 1, "{said}");
    let found: Vec<&str> = said
        .lines()
        .filter_map(|l| l.strip_prefix("refused: "))
        .collect();
    let want: Vec<&str> = reasons.iter().map(AsRef::as_ref).collect();
    assert_eq!(found, want, "{said}");
    assert!(!said.contains("\naccepted"), "{said}");
    said
}

/// The control: the bundle's members repacked unchanged by [`pack`] (rehashed) verify.
fn repacked_verifies(bundle: &Path, suites: &Path) {
    let out = scratch("lb-control").join("same.tar.zst");
    pack(&members(bundle), &out, true);
    let (code, said) = verify(&out, suites);
    assert_eq!(code, 0, "{said}");
}

/// `WHO: re-enacted from its seed and recorded actions, WHAT`: the verifier's words for an
/// episode whose re-enactment differs from its claim.
fn reenacted(who: &str, what: &str) -> String {
    format!("{who}: re-enacted from its seed and recorded actions, {what}")
}

/// Every member of a bundle, by name.
pub(crate) fn members(bundle: &Path) -> BTreeMap<String, Vec<u8>> {
    let file = std::fs::File::open(bundle).unwrap();
    let mut archive = tar::Archive::new(zstd::Decoder::new(file).unwrap());
    let mut out = BTreeMap::new();
    for e in archive.entries().unwrap() {
        let mut e = e.unwrap();
        let name = e.path().unwrap().display().to_string();
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut e, &mut bytes).unwrap();
        out.insert(name, bytes);
    }
    out
}

fn sha256(bytes: &[u8]) -> String {
    results::run::record::sha256_hex(bytes)
}

/// Writes `members` as a bundle; with `rehash`, the index lists each member's SHA-256 as a
/// forger would.
pub(crate) fn pack(members: &BTreeMap<String, Vec<u8>>, out: &Path, rehash: bool) {
    let mut members = members.clone();
    if rehash {
        let mut index: Value = serde_json::from_slice(&members["index.json"]).unwrap();
        let files: serde_json::Map<String, Value> = members
            .iter()
            .filter(|(k, _)| *k != "index.json")
            .map(|(k, v)| (k.clone(), Value::from(sha256(v))))
            .collect();
        index["files"] = Value::Object(files);
        members.insert("index.json".into(), serde_json::to_vec(&index).unwrap());
    }
    let file = std::fs::File::create(out).unwrap();
    let mut tar = tar::Builder::new(zstd::Encoder::new(file, 1).unwrap().auto_finish());
    for (name, bytes) in &members {
        let mut h = tar::Header::new_gnu();
        h.set_size(bytes.len() as u64);
        h.set_mode(0o644);
        tar.append_data(&mut h, name, &bytes[..]).unwrap();
    }
    tar.into_inner().unwrap();
}

fn journal_member() -> String {
    format!("runs/0/{TASK}.journal.jsonl")
}

/// The journal with `edit` applied to its lines.
fn edit_journal(m: &mut BTreeMap<String, Vec<u8>>, edit: impl FnOnce(Vec<String>) -> Vec<String>) {
    edit_journal_of(TASK, m, edit)
}

/// Task `task`'s journal with `edit` applied to its lines.
fn edit_journal_of(
    task: &str,
    m: &mut BTreeMap<String, Vec<u8>>,
    edit: impl FnOnce(Vec<String>) -> Vec<String>,
) {
    let key = format!("runs/0/{task}.journal.jsonl");
    let lines: Vec<String> = text(&m[&key]).lines().map(str::to_string).collect();
    let edited = edit(lines).join("\n") + "\n";
    m.insert(key, edited.into_bytes());
}

/// A copy of recording `src` with each message's data passed through `edit(topic, data)`.
pub(crate) fn rewrite(
    src: &Path,
    dst: &Path,
    mut edit: impl FnMut(&str, &[u8]) -> Option<Vec<u8>>,
) {
    let mut w = results::recording::Recorder::create(dst).unwrap();
    results::recording::for_each_message(src, |m| match edit(&m.channel.topic, &m.data) {
        Some(data) => w.pass(&mcap::Message {
            data: std::borrow::Cow::Owned(data),
            ..m.clone()
        }),
        None => w.pass(m),
    })
    .unwrap();
    w.finish().unwrap();
}

#[test]
fn an_honest_bundle_verifies() {
    let f = fixture();
    let (code, said) = verify(&f.bundle, &f.suites);
    assert_eq!(code, 0, "{said}");
    assert!(said.contains("accepted"), "{said}");
    assert!(
        said.contains("(1 tasks, 2 episodes); 2 episodes re-enacted"),
        "{said}"
    );
    // The index lists every file with its hash, the model and the suite.
    let m = members(&f.bundle);
    let index: Value = serde_json::from_slice(&m["index.json"]).unwrap();
    assert_eq!(index["schema_version"], 1);
    assert_eq!(index["model"]["name"], "scripted expert");
    assert_eq!(index["model"]["training"], "none");
    assert_eq!(index["suite"]["name"], "mini");
    for (name, bytes) in &m {
        if name != "index.json" {
            assert_eq!(index["files"][name], sha256(bytes), "{name}");
        }
    }
    assert!(m.contains_key(&format!("runs/0/{TASK}_seed1.mcap")));
    // Packing the same runs again gives the same bytes.
    let again = scratch("lb-again").join("b.tar.zst");
    common::submit(&f.run, "scripted expert", &again, &["--training", "none"]);
    assert_eq!(
        std::fs::read(&again).unwrap(),
        std::fs::read(&f.bundle).unwrap()
    );
}

#[test]
fn a_flipped_verdict_is_refused() {
    let f = fixture();
    let mut m = members(&f.bundle);
    edit_journal(&mut m, |mut lines| {
        let mut e: Value = serde_json::from_str(&lines[0]).unwrap();
        e["success"] = Value::Bool(false);
        e["outcome"] = Value::from("time_limit");
        lines[0] = e.to_string();
        lines
    });
    let out = scratch("lb-flipped").join("b.tar.zst");
    pack(&m, &out, true);
    repacked_verifies(&f.bundle, &f.suites);
    refused(
        &out,
        &f.suites,
        &[reenacted(
            &format!("{TASK} seed 0 (run 0)"),
            "outcome: \"time_limit\" (derived \"success\")",
        )],
    );
}

#[test]
fn an_edited_journal_is_refused_with_or_without_its_hash_updated() {
    let f = fixture();
    let mut m = members(&f.bundle);
    let steps = common::journal(&f.run, TASK)[1]["control_steps"].clone();
    edit_journal(&mut m, |mut lines| {
        lines[1] = lines[1].replace("\"control_steps\":", "\"control_steps\":1");
        lines
    });
    let dir = scratch("lb-edited");
    let edited = reenacted(
        &format!("{TASK} seed 1 (run 0)"),
        &format!("control_steps: 1{steps} (derived {steps})"),
    );
    pack(&m, &dir.join("a.tar.zst"), false);
    refused(
        &dir.join("a.tar.zst"),
        &f.suites,
        &[
            format!("{}: its SHA-256 is not the index's", journal_member()),
            edited.clone(),
        ],
    );
    pack(&m, &dir.join("b.tar.zst"), true);
    repacked_verifies(&f.bundle, &f.suites);
    refused(&dir.join("b.tar.zst"), &f.suites, &[edited]);
}

#[test]
fn forged_recorded_states_do_not_pass_where_plain_replay_is_fooled() {
    // Seed 1's recording keeps the expert's states (the lid shut, the episode a success) but its
    // actions are the no-motion run's: replay re-scores it a success from the states; the
    // verifier re-enacts the actions and finds the lid never moved.
    let f = fixture();
    let dir = scratch("lb-forged");
    let expert = f.run.join(format!("{TASK}_seed1.mcap"));
    let hold = f.hold.join(format!("{TASK}_seed1.mcap"));
    let mut hold_actions = Vec::new();
    results::recording::for_each_message(&hold, |m| {
        if m.channel.topic.ends_with("/action") {
            hold_actions.push(m.data.to_vec());
        }
        Ok(())
    })
    .unwrap();
    let forged = dir.join(format!("{TASK}_seed1.mcap"));
    let mut k = 0;
    rewrite(&expert, &forged, |topic, _| {
        topic.ends_with("/action").then(|| {
            k += 1;
            // The hold control's episode is shorter (its still scene jumps to the deadline);
            // its action never changes, so the last one stands for the rest.
            hold_actions[(k - 1).min(hold_actions.len() - 1)].clone()
        })
    });
    let replay = text(&autobio(&["replay", forged.to_str().unwrap()]).stdout);
    assert!(
        replay.contains("re-scored: success"),
        "plain replay: {replay}"
    );
    let mut m = members(&f.bundle);
    m.insert(
        format!("runs/0/{TASK}_seed1.mcap"),
        std::fs::read(&forged).unwrap(),
    );
    let out = dir.join("b.tar.zst");
    pack(&m, &out, true);
    repacked_verifies(&f.bundle, &f.suites);
    refused(
        &out,
        &f.suites,
        &[reenacted(
            &format!("{TASK} seed 1 (run 0)"),
            "the actions run out before the episode ends, outcome: \"success\" (derived \"time_limit\")",
        )],
    );
}

#[test]
fn an_action_changed_by_a_nanoradian_is_refused() {
    let f = fixture();
    let dir = scratch("lb-nudged");
    let src = f.run.join(format!("{TASK}_seed0.mcap"));
    let nudged = dir.join("nudged.mcap");
    let mut k = 0;
    rewrite(&src, &nudged, |topic, data| {
        if !topic.ends_with("/action") {
            return None;
        }
        k += 1;
        (k == 40).then(|| {
            let mut v: Value = serde_json::from_slice(data).unwrap();
            let a = v["action"][0].as_f64().unwrap();
            v["action"][0] = Value::from(a + 1e-9);
            serde_json::to_vec(&v).unwrap()
        })
    });
    let mut m = members(&f.bundle);
    m.insert(
        format!("runs/0/{TASK}_seed0.mcap"),
        std::fs::read(&nudged).unwrap(),
    );
    let out = dir.join("b.tar.zst");
    pack(&m, &out, true);
    repacked_verifies(&f.bundle, &f.suites);
    let claimed = common::journal(&f.run, TASK)[0]["trajectory_hash"].clone();
    let (code, said) = verify(&out, &f.suites);
    assert_eq!(code, 1, "{said}");
    let found: Vec<&str> = said
        .lines()
        .filter_map(|l| l.strip_prefix("refused: "))
        .collect();
    let words = reenacted(
        &format!("{TASK} seed 0 (run 0)"),
        &format!("trajectory_hash: {claimed} (derived \""),
    );
    // One reason: the hash (the derived one is whatever the nudged actions make).
    assert!(
        found.len() == 1 && found[0].starts_with(&words) && found[0].ends_with("\")"),
        "{said}"
    );
}

#[test]
fn results_for_a_changed_protocol_are_refused() {
    // The submitter ran the suite with the protocol edited in place (a longer time limit), then
    // put it back: the suite file is the shipped one, the compiled task is not.
    let dir = scratch("lb-changed");
    let protocol = dir.join("close_lid.toml");
    let original = std::fs::read_to_string("protocols/thermal_cycler/close_lid.toml").unwrap();
    std::fs::write(&protocol, original.replace("\"31.5 s\"", "\"60 s\"")).unwrap();
    let suites = suites("lb-changed-suites", protocol.to_str().unwrap());
    let run = dir.join("run");
    common::eval_suite(&suites.join("mini.toml"), &run, &[]);
    std::fs::write(&protocol, &original).unwrap();
    let bundle = dir.join("b.tar");
    common::submit(&run, "x", &bundle, &[]);
    refused(
        &bundle,
        &suites,
        &[format!(
            "runs/0/{TASK}.manifest.json: the results are for a modified task (its compiled \
             content differs from the shipped {})",
            suites.join(&protocol).display()
        )],
    );
}

#[test]
fn a_missing_or_duplicated_seed_is_refused() {
    let f = fixture();
    let dir = scratch("lb-seeds");
    let mut m = members(&f.bundle);
    edit_journal(&mut m, |lines| vec![lines[0].clone()]);
    pack(&m, &dir.join("missing.tar.zst"), true);
    repacked_verifies(&f.bundle, &f.suites);
    refused(
        &dir.join("missing.tar.zst"),
        &f.suites,
        &[format!("{TASK}: seed 1 (run 0) is missing")],
    );
    let mut m = members(&f.bundle);
    edit_journal(&mut m, |lines| {
        vec![lines[0].clone(), lines[1].clone(), lines[1].clone()]
    });
    pack(&m, &dir.join("twice.tar.zst"), true);
    refused(
        &dir.join("twice.tar.zst"),
        &f.suites,
        &[format!("{TASK}: seed 1 (run 0) is in the journals 2 times")],
    );
}

/// A plain tar with `build` adding its members.
fn raw_tar(out: &Path, build: impl FnOnce(&mut tar::Builder<std::fs::File>)) {
    let mut tar = tar::Builder::new(std::fs::File::create(out).unwrap());
    build(&mut tar);
    tar.into_inner().unwrap();
}

fn header(size: u64) -> tar::Header {
    let mut h = tar::Header::new_gnu();
    h.set_size(size);
    h.set_mode(0o644);
    h
}

#[test]
fn hostile_archives_are_refused_and_write_nothing_outside() {
    let f = fixture();
    let dir = scratch("lb-hostile");
    let index = members(&f.bundle)["index.json"].clone();
    let work = dir.join("work");
    let verify_in = |bundle: &Path| {
        let _ = std::fs::remove_dir_all(&work);
        let out = autobio(&[
            "leaderboard",
            "verify",
            bundle.to_str().unwrap(),
            "--suites",
            f.suites.to_str().unwrap(),
            "--work",
            work.to_str().unwrap(),
        ]);
        (out.status.code().unwrap(), text(&out.stdout))
    };

    // A member whose path climbs out of the work folder (written raw: the tar crate refuses to).
    let climbing = dir.join("climbing.tar");
    raw_tar(&climbing, |t| {
        t.append_data(&mut header(index.len() as u64), "index.json", &index[..])
            .unwrap();
        let mut h = header(5);
        h.as_gnu_mut().unwrap().name[..13].copy_from_slice(b"../escaped.tx");
        h.set_cksum();
        t.append(&h, &b"owned"[..]).unwrap();
    });
    let (code, said) = verify_in(&climbing);
    assert_eq!(code, 1, "{said}");
    assert!(
        said.contains("`../escaped.tx` is refused: its path climbs out with `..`"),
        "{said}"
    );
    assert!(
        !dir.join("escaped.tx").exists(),
        "a file was written outside the work folder"
    );

    // A symbolic link.
    let linked = dir.join("linked.tar");
    raw_tar(&linked, |t| {
        let mut h = header(0);
        h.set_entry_type(tar::EntryType::Symlink);
        t.append_link(&mut h, "runs/0/link", "/etc/passwd").unwrap();
    });
    let (code, said) = verify_in(&linked);
    assert_eq!(code, 1, "{said}");
    assert!(
        said.contains("`runs/0/link` is refused: it is a link"),
        "{said}"
    );

    // Cut short.
    let bytes = std::fs::read(&f.bundle).unwrap();
    let cut = dir.join("cut.tar.zst");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (code, said) = verify_in(&cut);
    assert_eq!(code, 1, "{said}");
    assert!(
        said.contains("the archive is truncated or corrupt"),
        "{said}"
    );

    // A decompression bomb: 256 MiB of zeros in a few hundred kilobytes.
    let bomb = dir.join("bomb.tar.zst");
    {
        let file = std::fs::File::create(&bomb).unwrap();
        let mut t = tar::Builder::new(zstd::Encoder::new(file, 3).unwrap().auto_finish());
        let size = 256u64 << 20;
        t.append_data(
            &mut header(size),
            "runs/0/zeros.mcap",
            std::io::Read::take(std::io::repeat(0), size),
        )
        .unwrap();
        t.into_inner().unwrap();
    }
    assert!(std::fs::metadata(&bomb).unwrap().len() < 1 << 20);
    let (code, said) = verify_in(&bomb);
    assert_eq!(code, 1, "{said}");
    assert!(said.contains("a decompression bomb"), "{said}");

    // Two members of one name, and an index of an unknown schema.
    let twice = dir.join("twice.tar");
    raw_tar(&twice, |t| {
        for _ in 0..2 {
            t.append_data(&mut header(index.len() as u64), "index.json", &index[..])
                .unwrap();
        }
    });
    let (code, said) = verify_in(&twice);
    assert_eq!(code, 1, "{said}");
    assert!(said.contains("two members of that name"), "{said}");
    let future = dir.join("future.tar");
    let mut v: Value = serde_json::from_slice(&index).unwrap();
    v["schema_version"] = Value::from(9);
    let v = serde_json::to_vec(&v).unwrap();
    raw_tar(&future, |t| {
        t.append_data(&mut header(v.len() as u64), "index.json", &v[..])
            .unwrap();
    });
    let (code, said) = verify_in(&future);
    assert_eq!(code, 1, "{said}");
    assert!(said.contains("schema version 9"), "{said}");
}

#[test]
fn a_model_servers_suite_run_verifies() {
    // The reference openpi server answering with the expert's recorded actions, through
    // `eval --suite --model`: recorded by default, packed, verified.
    let f = fixture();
    let server = Server::start(
        "openpi_server.py",
        &["--recordings", f.run.to_str().unwrap()],
    );
    let dir = scratch("lb-model");
    let run = dir.join("run");
    // pi0's layout with a reset frame per episode (how the reference server tells episodes).
    let profile = dir.join("pi0.toml");
    let pi0 = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    std::fs::write(
        &profile,
        pi0.replace("reset_frame = false", "reset_frame = true"),
    )
    .unwrap();
    common::eval_suite(
        &f.suites.join("mini.toml"),
        &run,
        &[
            "--model",
            &server.url,
            "--profile",
            profile.to_str().unwrap(),
        ],
    );
    let outcomes: Vec<Value> = common::journal(&run, TASK)
        .iter()
        .map(|e| e["outcome"].clone())
        .collect();
    assert_eq!(outcomes, ["success", "success"]);
    let bundle = dir.join("pi0.tar.zst");
    common::submit(&run, "reference server", &bundle, &[]);
    let index: Value = serde_json::from_slice(&members(&bundle)["index.json"]).unwrap();
    assert_eq!(index["model"]["wire"], "openpi");
    assert_eq!(index["model"]["profile"], "pi0");
    let (code, said) = verify(&bundle, &f.suites);
    assert_eq!(code, 0, "{said}");
    assert!(said.contains("accepted"), "{said}");
}

#[test]
fn an_audit_passes_the_model_that_made_the_bundle_and_flags_one_far_below_its_claim() {
    // An 8-episode suite run by the expert and packed; two live servers on the audit's seeds
    // (1000-1007): one replaying the expert (consistent), one replaying the no-motion control
    // (0 of 8 against a claimed 8 of 8: p = 1/C(16, 8)).
    let suites = scratch("lb-audit-suites");
    std::fs::write(
        suites.join("mini.toml"),
        format!(
            "format = 1\n[suite]\nname = \"mini\"\nepisodes = 8\nseed = 0\nruns = 1\ntasks = [\"{}\"]\n",
            repo("protocols/thermal_cycler/close_lid.toml")
        ),
    )
    .unwrap();
    let dir = scratch("lb-audit");
    let run = dir.join("run");
    common::eval_suite(&suites.join("mini.toml"), &run, &[]);
    let bundle = dir.join("expert.tar.zst");
    common::submit(&run, "expert", &bundle, &[]);
    let profile = dir.join("pi0.toml");
    let pi0 = std::fs::read_to_string("profiles/pi0.toml").unwrap();
    std::fs::write(
        &profile,
        pi0.replace("reset_frame = false", "reset_frame = true"),
    )
    .unwrap();
    let audit = |policy: &str| {
        let recordings = dir.join(format!("{policy}-recordings"));
        common::autobio_ok(&[
            "eval",
            "--protocol",
            "protocols/thermal_cycler/close_lid.toml",
            "--policy",
            policy,
            "--episodes",
            "8",
            "--seed",
            "1000",
            "--record",
            "--image-every",
            "0",
            "--out",
            recordings.to_str().unwrap(),
        ]);
        let server = Server::start(
            "openpi_server.py",
            &["--recordings", recordings.to_str().unwrap()],
        );
        let out = autobio(&[
            "leaderboard",
            "audit",
            bundle.to_str().unwrap(),
            "--model",
            &server.url,
            "--profile",
            profile.to_str().unwrap(),
            "--episodes",
            "8",
            "--seed",
            "1000",
            "--suites",
            suites.to_str().unwrap(),
        ]);
        (
            out.status.code().unwrap(),
            text(&out.stdout) + &text(&out.stderr),
        )
    };
    let (code, said) = audit("expert");
    assert_eq!(code, 0, "{said}");
    assert!(said.contains("audited: consistent"), "{said}");
    let row = |said: &str| -> Vec<String> {
        said.lines()
            .find(|l| l.starts_with(TASK))
            .unwrap_or_else(|| panic!("no row for the task: {said}"))
            .split_whitespace()
            .map(str::to_string)
            .collect()
    };
    assert_eq!(
        row(&said)[1..],
        ["8/8", "100%", "8/8", "100%", "1.000e0"],
        "{said}"
    );
    let (code, said) = audit("hold");
    assert_eq!(code, 1, "{said}");
    assert!(said.contains("audit failed"), "{said}");
    // p = 1/12870 = 7.770e-5, shown with the rule.
    assert_eq!(
        row(&said)[1..],
        ["8/8", "100%", "0/8", "0%", "7.770e-5"],
        "{said}"
    );
    assert!(said.contains("rule: one-sided Fisher exact test"), "{said}");
}

#[test]
fn the_site_ranks_verified_bundles_beside_the_paper_and_is_the_same_twice() {
    // Three bundles: the expert's (verified here), the no-motion run's (not verified: reported)
    // and a truncated one (refused with its reason, never ranked).
    let f = fixture();
    let dir = scratch("lb-site");
    let bundles = dir.join("bundles");
    std::fs::create_dir_all(&bundles).unwrap();
    let expert = bundles.join("expert.tar.zst");
    std::fs::copy(&f.bundle, &expert).unwrap();
    let (code, said) = verify(&expert, &f.suites);
    assert_eq!(code, 0, "{said}");
    let hold = bundles.join("hold.tar.zst");
    common::submit(&f.hold, "no motion", &hold, &[]);
    let bytes = std::fs::read(&f.bundle).unwrap();
    std::fs::write(bundles.join("cut.tar.zst"), &bytes[..bytes.len() / 3]).unwrap();
    let build = |out: &Path| {
        common::autobio_ok(&[
            "leaderboard",
            "build",
            bundles.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let site = dir.join("site");
    let said = build(&site);
    assert!(said.contains("3 submissions"), "{said}");
    let read = |rel: &str| std::fs::read_to_string(site.join(rel)).unwrap();

    let ranking = read("ranking.md");
    let rows: Vec<&str> = ranking
        .lines()
        .filter(|l| l.starts_with("| 1 ") || l.starts_with("| 2 "))
        .collect();
    assert_eq!(
        rows,
        [
            "| 1 | scripted expert | none | scripted | verified | 100.0 | – | – | 100.0 | – | – | 1.000 |",
            "| 2 | no motion |  | scripted | reported | 0.0 | – | – | 0.0 | – | – | 0.000 |",
        ],
        "{ranking}"
    );
    let index = read("index.html");
    assert!(
        index.contains("Reference: reported by the paper, not re-run"),
        "{index}"
    );
    assert!(
        index.contains("<td>99.7 ± 0.3</td>"),
        "the paper's pi0 at 100 demos"
    );
    assert!(index.contains("class=refused>cut.tar.zst"), "{index}");
    assert!(
        index.contains("the archive is truncated or corrupt"),
        "{index}"
    );
    assert!(index.contains("<svg"), "a chart");
    // Over the suite, paired on its seeds: the expert won both episodes the no-motion run lost
    // (2 discordant pairs: p = 2 * (1/2)^2 = 0.5).
    assert!(
        index.contains("<td class=l>scripted expert</td><td class=l>no motion</td><td>2</td><td>2</td><td>0</td><td>5.000e-1</td><td>not significant</td>"),
        "{index}"
    );

    // The task page: Wilson intervals, the paired test on the same seeds, the paper's row.
    let task = read("tasks/thermal-cycler-close-lid.html");
    assert!(
        task.contains("<td>100.0</td><td>[34.2, 100.0]</td>"),
        "2 of 2: Wilson [34.2, 100]"
    );
    assert!(
        task.contains("<td>2</td><td>2</td><td>0</td><td>5.000e-1</td><td>not significant</td>"),
        "expert vs no motion on seeds 0 and 1: {task}"
    );
    assert!(task.contains("<td>99.7 ± 0.3</td>"));
    let json: Value = serde_json::from_str(&read("tasks/thermal-cycler-close-lid.json")).unwrap();
    assert_eq!(json["rows"][0]["summary"]["successes"], 2);
    // A submission's page lists every episode.
    let page = read("submissions/scripted-expert-none.html");
    assert!(page.contains("standing: <b>verified</b>"));
    // Frames of its best episode, drawn from its recording, beside the page.
    assert!(
        page.contains("best episode: run 0, seed 0, score 1.000"),
        "{page}"
    );
    for k in 0..3 {
        let png = format!("scripted-expert-none/thermal-cycler-close-lid-best-{k}.png");
        assert!(page.contains(&format!("<img src=\"{png}\"")), "{page}");
        let bytes = std::fs::read(site.join("submissions").join(&png)).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
    assert_eq!(page.matches("<td class=l>success</td>").count(), 2);

    // No page asks the network for anything.
    for file in [
        "index.html",
        "tasks/thermal-cycler-close-lid.html",
        "submissions/scripted-expert-none.html",
    ] {
        let text = read(file);
        for pattern in [
            "src=\"http",
            "href=\"http",
            "url(",
            "@import",
            "<script",
            "<link",
        ] {
            assert!(!text.contains(pattern), "{file} has {pattern}");
        }
    }
    // The same inputs build the same bytes.
    let again = dir.join("again");
    build(&again);
    let files = |root: &Path| -> BTreeMap<PathBuf, Vec<u8>> {
        let mut out = BTreeMap::new();
        let mut walk = vec![root.to_path_buf()];
        while let Some(d) = walk.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk.push(p);
                } else {
                    out.insert(
                        p.strip_prefix(root).unwrap().to_path_buf(),
                        std::fs::read(&p).unwrap(),
                    );
                }
            }
        }
        out
    };
    assert!(files(&site) == files(&again), "two builds differ");
}

#[test]
fn claims_the_checks_do_not_cover_are_refused() {
    // What a forger could add beside the checked files, or point the verifier at.
    let f = fixture();
    let dir = scratch("lb-stray");
    // A journal outside the run folders, which a site would otherwise count.
    let mut m = members(&f.bundle);
    m.insert(
        format!("extra/{TASK}.journal.jsonl"),
        m[&journal_member()].clone(),
    );
    pack(&m, &dir.join("stray.tar.zst"), true);
    repacked_verifies(&f.bundle, &f.suites);
    refused(
        &dir.join("stray.tar.zst"),
        &f.suites,
        &[format!(
            "extra/{TASK}.journal.jsonl is not a file of a suite run (runs/<k>/ with suite.toml \
             and each suite task's manifest, journal, results and recordings)"
        )],
    );
    // A manifest claiming another level (the per-level columns).
    let mut m = members(&f.bundle);
    let key = format!("runs/0/{TASK}.manifest.json");
    let mut manifest: Value = serde_json::from_slice(&m[&key]).unwrap();
    manifest["level"] = "hard".into();
    m.insert(key, serde_json::to_vec(&manifest).unwrap());
    pack(&m, &dir.join("level.tar.zst"), true);
    refused(
        &dir.join("level.tar.zst"),
        &f.suites,
        &[format!(
            "runs/0/{TASK}.manifest.json: task `{TASK}` at level hard; the shipped task is \
             `{TASK}` at level easy"
        )],
    );
    // A suite of the bundle's own, named as a path to it: the verifier finds shipped suites by
    // their hash, never by the bundle's name for them.
    let mut m = members(&f.bundle);
    let own = "format = 1\n[suite]\nname = \"mini\"\nepisodes = 1\nseed = 0\nruns = 1\ntasks = [\"x.toml\"]\n";
    let mut index: Value = serde_json::from_slice(&m["index.json"]).unwrap();
    index["suite"]["name"] = "../../runs/0/suite".into();
    index["suite_sha256"] = sha256(own.as_bytes()).into();
    m.insert("index.json".into(), serde_json::to_vec(&index).unwrap());
    m.insert("runs/0/suite.toml".into(), own.as_bytes().to_vec());
    pack(&m, &dir.join("own-suite.tar.zst"), true);
    refused(
        &dir.join("own-suite.tar.zst"),
        &f.suites,
        &[format!(
            "suite `../../runs/0/suite` is not a shipped suite: no file in {} has its SHA-256",
            f.suites.display()
        )],
    );
}

#[test]
fn a_chain_task_page_shows_each_stage_as_the_paper_does() {
    let suites = suites(
        "lb-chain-suites",
        &repo("protocols/thermal_cycler/close_then_open.toml"),
    );
    let dir = scratch("lb-chain");
    let bundles = dir.join("bundles");
    std::fs::create_dir_all(&bundles).unwrap();
    for policy in ["expert", "hold"] {
        let run = dir.join(policy);
        common::eval_suite(&suites.join("mini.toml"), &run, &["--policy", policy]);
        common::submit(&run, policy, &bundles.join(format!("{policy}.tar")), &[]);
    }
    let site = dir.join("site");
    common::autobio_ok(&[
        "leaderboard",
        "build",
        bundles.to_str().unwrap(),
        "--out",
        site.to_str().unwrap(),
    ]);
    let page =
        std::fs::read_to_string(site.join("tasks/thermal-cycler-close-then-open.html")).unwrap();
    assert!(
        page.contains("<th>thermal_cycler.close_lid</th><th>thermal_cycler.open_lid</th>"),
        "{page}"
    );
    assert!(
        page.contains("<td class=l>expert</td><td>100.0</td><td>100.0</td>"),
        "{page}"
    );
    assert!(
        page.contains("<td class=l>hold</td><td>0.0</td><td>0.0</td>"),
        "{page}"
    );
}

/// An episode that ended in an error (here the expert, which has no motions for a hand-over yet)
/// is a failure scoring 0: such a run verifies, and the same run claiming a score for it does not.
#[test]
fn episodes_that_ended_in_an_error_verify_at_score_zero() {
    let dir = scratch("lb-errors");
    let protocol = dir.join("hand_over.toml");
    std::fs::write(&protocol, common::HAND_OVER).unwrap();
    let suites = suites("lb-errors-suites", protocol.to_str().unwrap());
    let run = dir.join("run");
    common::eval_suite(&suites.join("mini.toml"), &run, &["--policy", "expert"]);
    let bundle = dir.join("b.tar.zst");
    common::submit(&run, "expert", &bundle, &[]);
    let m = members(&bundle);
    let journal = m
        .iter()
        .find(|(k, _)| k.ends_with(".journal.jsonl"))
        .map(|(_, v)| String::from_utf8(v.clone()).unwrap())
        .unwrap();
    for line in journal.lines() {
        let e: Value = serde_json::from_str(line).unwrap();
        assert_eq!(e["outcome"], "policy_error", "{e}");
        assert_eq!(e["verdict"]["score"], 0.0, "{e}");
    }
    let (code, said) = verify(&bundle, &suites);
    assert_eq!(code, 0, "{said}");
    let mut forged = m.clone();
    edit_journal_of("tube.hand_over", &mut forged, |mut lines| {
        let mut e: Value = serde_json::from_str(&lines[0]).unwrap();
        e["verdict"]["score"] = Value::from(1.0);
        lines[0] = e.to_string();
        lines
    });
    let out = dir.join("forged.tar.zst");
    pack(&forged, &out, true);
    refused(
        &out,
        &suites,
        &[reenacted(
            "tube.hand_over seed 0 (run 0)",
            "verdict.score: 1.0 (derived 0.0)",
        )],
    );
}

/// A task whose success holds before the first step is run only under `--allow-trivial`, and such
/// a run is not submitted to a leaderboard: exit 2, the warning's place named, no bundle written.
#[test]
fn a_run_of_a_trivial_task_is_not_submitted() {
    let dir = scratch("lb-trivial");
    let protocol = dir.join("open_and_close.toml");
    let shipped = std::fs::read_to_string("protocols/thermal_cycler/open_and_close.toml").unwrap();
    let trivial = shipped.replace("\"cycler.lid was open\", ", "");
    assert_ne!(trivial, shipped, "the round trip's `was` predicate");
    std::fs::write(&protocol, trivial).unwrap();
    let suites = suites("lb-trivial-suites", protocol.to_str().unwrap());
    let suite = suites.join("mini.toml");
    let run = dir.join("run");
    let refused_run = common::autobio(&[
        "eval",
        "--suite",
        suite.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
    ]);
    assert_eq!(refused_run.status.code(), Some(2));
    common::eval_suite(&suite, &run, &["--policy", "hold", "--allow-trivial"]);
    let bundle = dir.join("b.tar.zst");
    let out = common::autobio(&[
        "leaderboard",
        "submit",
        run.to_str().unwrap(),
        "--model-name",
        "hold",
        "--out",
        bundle.to_str().unwrap(),
    ]);
    let said = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(
        said.contains("is trivial") && said.contains("W0001"),
        "{said}"
    );
    assert!(said.contains("open_and_close.toml:"), "{said}");
    assert!(!bundle.exists());
}

/// One run folder per training seed (`eval --checkpoint NAME --training-seed K`, each only run K
/// of a 3-run suite) packed together verify, and the site shows their ± in the column over
/// training seeds, never in the one over evaluation runs; a bundle that mixes the two kinds, or
/// evaluates a checkpoint on another run's episodes, is refused; a training seed past the runs
/// is refused before anything runs.
#[test]
fn training_seed_runs_verify_and_show_their_sem_over_training_seeds() {
    let suites = scratch("lb-seed-suites");
    std::fs::write(
        suites.join("seeds.toml"),
        format!(
            "format = 1\n[suite]\nname = \"seeds\"\nepisodes = 1\nseed = 0\nruns = 3\ntasks = [\"{}\"]\n",
            repo("protocols/thermal_cycler/close_lid.toml")
        ),
    )
    .unwrap();
    let suite = suites.join("seeds.toml");
    let root = scratch("lb-seed-runs");
    let runs: Vec<PathBuf> = (0..3).map(|k| root.join(format!("seed{k}"))).collect();
    for (k, dir) in runs.iter().enumerate() {
        let (name, seed) = (format!("ckpt-{k}"), k.to_string());
        common::eval_suite(
            &suite,
            dir,
            &["--checkpoint", &name, "--training-seed", &seed],
        );
        // Only its own run's episode.
        let journal = common::journal(dir, TASK);
        assert_eq!(journal.len(), 1, "{journal:?}");
        assert_eq!(journal[0]["run"], k as u64);
    }
    let out = autobio(&[
        "eval",
        "--suite",
        suite.to_str().unwrap(),
        "--out",
        root.join("seed3").to_str().unwrap(),
        "--checkpoint",
        "ckpt-3",
        "--training-seed",
        "3",
    ]);
    let said = text(&out.stderr);
    assert!(!out.status.success(), "{said}");
    assert!(
        said.contains("training seed 3 has no run to evaluate: the run has 3"),
        "{said}"
    );
    let bundles = scratch("lb-seed-bundles");
    let bundle = bundles.join("seeds.tar.zst");
    let mut args = vec!["leaderboard", "submit"];
    args.extend(runs.iter().map(|r| r.to_str().unwrap()));
    args.extend([
        "--model-name",
        "three seeds",
        "--out",
        bundle.to_str().unwrap(),
    ]);
    common::autobio_ok(&args);
    let (code, said) = verify(&bundle, &suites);
    assert_eq!(code, 0, "{said}");

    // The site: the ± in the training-seed column of the ranking and of the task's table.
    let site = scratch("lb-seed-site");
    let only = scratch("lb-seed-only");
    std::fs::copy(&bundle, only.join("seeds.tar.zst")).unwrap();
    common::autobio_ok(&[
        "leaderboard",
        "build",
        only.to_str().unwrap(),
        "--out",
        site.to_str().unwrap(),
    ]);
    let ranking = std::fs::read_to_string(site.join("ranking.md")).unwrap();
    assert!(
        ranking.contains("| ± SEM over training seeds | ± SEM over evaluation runs |"),
        "{ranking}"
    );
    let row = ranking.lines().find(|l| l.contains("three seeds")).unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    // | # | model | training | observation | standing | success | ± training seeds | ± evaluation runs | ...
    assert_eq!(cells[4], "scripted", "{row}");
    assert!(cells[7].parse::<f64>().is_ok(), "{row}");
    assert_eq!(cells[8], "–", "{row}");
    let pages: Vec<PathBuf> = std::fs::read_dir(site.join("submissions"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "html"))
        .collect();
    let [page] = &pages[..] else {
        panic!("one submission page: {pages:?}")
    };
    let page = std::fs::read_to_string(page).unwrap();
    assert!(
        page.contains("training seed 0: ckpt-0; training seed 1: ckpt-1; training seed 2: ckpt-2"),
        "{page}"
    );

    // A folder whose manifest names no checkpoint beside two that do.
    let m = members(&bundle);
    let manifest = format!("runs/2/{TASK}.manifest.json");
    let mut bare = m.clone();
    let mut value: Value = serde_json::from_slice(&m[&manifest]).unwrap();
    value.as_object_mut().unwrap().remove("checkpoint");
    bare.insert(manifest.clone(), serde_json::to_vec_pretty(&value).unwrap());
    let forged = bundles.join("bare.tar.zst");
    pack(&bare, &forged, true);
    repacked_verifies(&bundle, &suites);
    refused(
        &forged,
        &suites,
        &[format!(
            "some runs name their training-seed checkpoint and runs/2/{TASK}.journal.jsonl do \
             not: a submission's runs are all training seeds or all evaluation runs of one model"
        )],
    );
    // A checkpoint said to be training seed 1 beside run 2's episode.
    let mut moved = m.clone();
    let mut value: Value = serde_json::from_slice(&m[&manifest]).unwrap();
    value["checkpoint"]["run"] = Value::from(1);
    moved.insert(manifest, serde_json::to_vec_pretty(&value).unwrap());
    let forged = bundles.join("moved.tar.zst");
    pack(&moved, &forged, true);
    refused(
        &forged,
        &suites,
        &[
            format!(
                "runs/2/{TASK}.journal.jsonl: the checkpoint of training seed 1 is evaluated on \
                 run 1 only, but an episode of run 2 is here"
            ),
            format!(
                "runs/2/{TASK}.journal.jsonl: training seed 1 is checkpoint `ckpt-2`, but \
                 `ckpt-1` in runs/1/{TASK}.journal.jsonl"
            ),
        ],
    );
}
