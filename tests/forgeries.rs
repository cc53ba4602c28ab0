//! Forged bundles, verified as a stranger would: from a folder outside the checkout, with no
//! `--suites` (the shipped suites compiled into the binary). The bundle is a genuine expert run
//! of the shipped `smoke` suite (one episode of the thermal cycler's close-then-open chain);
//! each test repacks it unchanged (the control: it verifies) and with one member forged, and
//! the verifier must refuse it with exactly its own reason, one per forgery, for every figure the
//! site publishes (stages, outcome, times, verdict, results) and every member kind (journal,
//! results, recording, manifest, index, the archive itself).

use crate::common::{self, scratch, text};
use crate::leaderboard::{members, pack, rewrite};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

const TASK: &str = "thermal_cycler.close_then_open";
const JOURNAL: &str = "runs/0/thermal_cycler.close_then_open.journal.jsonl";
const MANIFEST: &str = "runs/0/thermal_cycler.close_then_open.manifest.json";
const RESULTS: &str = "runs/0/thermal_cycler.close_then_open.results.json";
const RECORDING: &str = "runs/0/thermal_cycler.close_then_open_seed0.mcap";
const WHO: &str = "thermal_cycler.close_then_open seed 0 (run 0)";

struct Fixture {
    /// A folder outside the checkout: verify runs here.
    away: PathBuf,
    bundle: PathBuf,
    members: BTreeMap<String, Vec<u8>>,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let root = scratch("forgeries");
        let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("suites/smoke.toml");
        let run = root.join("run");
        common::eval_suite(&suite, &run, &["--policy", "expert"]);
        let bundle = root.join("expert.tar.zst");
        common::submit(&run, "scripted expert", &bundle, &[]);
        let away = root.join("elsewhere");
        std::fs::create_dir_all(&away).unwrap();
        Fixture {
            away,
            members: members(&bundle),
            bundle,
        }
    })
}

/// `verify BUNDLE` (extra arguments after it) run from the fixture's folder outside the checkout:
/// its exit code, its refusals (each `refused: ` line) and all it said.
fn verify_away(bundle: &Path, extra: &[&str]) -> (i32, Vec<String>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["leaderboard", "verify", bundle.to_str().unwrap()])
        .args(extra)
        .current_dir(&fixture().away)
        .output()
        .unwrap();
    let said = text(&out.stdout) + &text(&out.stderr);
    let refusals = said
        .lines()
        .filter_map(|l| l.strip_prefix("refused: "))
        .map(str::to_string)
        .collect();
    (out.status.code().unwrap(), refusals, said)
}

/// The control: the genuine members repacked by the same repacker (rehashed) verify.
fn control() {
    static OK: OnceLock<String> = OnceLock::new();
    let said = OK.get_or_init(|| {
        let out = scratch("forgery-control").join("same.tar.zst");
        pack(&fixture().members, &out, true);
        let (code, refusals, said) = verify_away(&out, &[]);
        assert_eq!((code, refusals.len()), (0, 0), "{said}");
        said
    });
    assert!(said.contains("\naccepted"), "{said}");
}

/// The genuine members with `forge` applied, packed (rehashed as a forger would), verified
/// away: exactly `reasons` are the refusals, and the control verifies.
fn refused_exactly(
    name: &str,
    forge: impl FnOnce(&mut BTreeMap<String, Vec<u8>>),
    reasons: &[String],
) {
    control();
    let mut m = fixture().members.clone();
    forge(&mut m);
    let out = scratch(name).join("forged.tar.zst");
    pack(&m, &out, true);
    let (code, refusals, said) = verify_away(&out, &[]);
    assert_eq!(code, 1, "{said}");
    assert_eq!(refusals, reasons, "{said}");
}

fn json(m: &BTreeMap<String, Vec<u8>>, member: &str) -> Value {
    serde_json::from_slice(&m[member]).unwrap()
}

fn set_json(m: &mut BTreeMap<String, Vec<u8>>, member: &str, v: &Value) {
    m.insert(member.into(), serde_json::to_vec_pretty(v).unwrap());
}

/// The journal's one line, parsed.
fn line(m: &BTreeMap<String, Vec<u8>>) -> Value {
    serde_json::from_slice(text(&m[JOURNAL]).lines().next().unwrap().as_bytes()).unwrap()
}

fn set_line(m: &mut BTreeMap<String, Vec<u8>>, v: &Value) {
    m.insert(JOURNAL.into(), (v.to_string() + "\n").into_bytes());
}

/// The journal line and the results file's episode both with `edit` applied (a forger keeps
/// them consistent).
fn forge_episode(m: &mut BTreeMap<String, Vec<u8>>, edit: impl Fn(&mut Value)) {
    let mut l = line(m);
    edit(&mut l);
    set_line(m, &l);
    let mut r = json(m, RESULTS);
    edit(&mut r["episodes"][0]);
    set_json(m, RESULTS, &r);
}

fn reenacted(difference: &str) -> Vec<String> {
    vec![format!(
        "{WHO}: re-enacted from its seed and recorded actions, {difference}"
    )]
}

#[test]
fn a_genuine_bundle_of_a_shipped_suite_verifies_from_any_folder() {
    let f = fixture();
    assert!(!f.away.join("suites").exists());
    let (code, refusals, said) = verify_away(&f.bundle, &[]);
    assert_eq!((code, refusals.len()), (0, 0), "{said}");
    assert!(
        said.contains("on suite smoke (1 tasks, 1 episodes)"),
        "{said}"
    );
    control();
    // The chain's two stages are what the forgeries below move.
    let stages = line(&f.members)["verdict"]["stages"].clone();
    assert_eq!(stages.as_array().unwrap().len(), 2, "{stages}");
}

#[test]
fn a_moved_stage_is_refused_though_success_and_score_are_kept() {
    let stages = line(&fixture().members)["verdict"]["stages"].clone();
    let t = stages[0]["completed_at_s"].clone();
    let moved = Value::from(t.as_f64().unwrap() + 1.0);
    refused_exactly(
        "forged-stage-time",
        |m| {
            forge_episode(m, |e| {
                e["verdict"]["stages"][0]["completed_at_s"] = moved.clone()
            })
        },
        &reenacted(&format!(
            "verdict.stages[0].completed_at_s: {moved} (derived {t})"
        )),
    );
    // Swapped: compared by index, stage 0's first field (alphabetical) that differs.
    let (a, b) = (&stages[0], &stages[1]);
    let first = if a["completed_at_s"] != b["completed_at_s"] {
        format!(
            "verdict.stages[0].completed_at_s: {} (derived {})",
            b["completed_at_s"], a["completed_at_s"]
        )
    } else {
        format!("verdict.stages[0].id: {} (derived {})", b["id"], a["id"])
    };
    refused_exactly(
        "forged-stage-order",
        |m| {
            forge_episode(m, |e| {
                e["verdict"]["stages"].as_array_mut().unwrap().swap(0, 1)
            })
        },
        &reenacted(&first),
    );
    refused_exactly(
        "forged-stage-dropped",
        |m| {
            forge_episode(m, |e| {
                e["verdict"]["stages"].as_array_mut().unwrap().pop();
            })
        },
        &reenacted("verdict.stages: 1 entries (derived 2)"),
    );
}

#[test]
fn a_forged_predicate_value_outcome_or_time_is_refused() {
    let l = line(&fixture().members);
    let value = l["verdict"]["stages"][1]["predicates"][0]["value"].clone();
    let forged = Value::from(value.as_f64().unwrap() + 0.5);
    refused_exactly(
        "forged-predicate",
        |m| {
            forge_episode(m, |e| {
                e["verdict"]["stages"][1]["predicates"][0]["value"] = forged.clone()
            })
        },
        &reenacted(&format!(
            "verdict.stages[1].predicates[0].value: {forged} (derived {value})"
        )),
    );
    refused_exactly(
        "forged-outcome",
        |m| forge_episode(m, |e| e["outcome"] = "time_limit".into()),
        &reenacted("outcome: \"time_limit\" (derived \"success\")"),
    );
    let sim = l["sim_time_s"].clone();
    refused_exactly(
        "forged-sim-time",
        |m| forge_episode(m, |e| e["sim_time_s"] = Value::from(1.0)),
        &reenacted(&format!("sim_time_s: 1.0 (derived {sim})")),
    );
    refused_exactly(
        "forged-wall-time",
        |m| forge_episode(m, |e| e["wall_time_s"] = Value::from(-1.0)),
        &reenacted("wall time -1 s and policy time 0 s (times are finite and not negative)")
            .into_iter()
            .map(|r| {
                r.replace(
                    "policy time 0 s",
                    &format!("policy time {} s", l["policy_time_s"]),
                )
            })
            .collect::<Vec<_>>(),
    );
    refused_exactly(
        "forged-extra-field",
        |m| {
            let mut e = line(m);
            e["leaderboard_note"] = "best model".into();
            set_line(m, &e);
        },
        &[format!(
            "{JOURNAL}: line 1 is not an episode result: leaderboard_note: not a field of it"
        )],
    );
}

#[test]
fn a_results_file_is_the_report_of_its_journal_and_nothing_else() {
    refused_exactly(
        "forged-results-rate",
        |m| {
            let mut r = json(m, RESULTS);
            r["summary"]["success_rate"] = Value::from(0.5);
            set_json(m, RESULTS, &r);
        },
        &[format!(
            "{RESULTS}: not the report of its verified journal: summary.success_rate: 0.5 (derived 1.0)"
        )],
    );
    refused_exactly(
        "forged-results-episode",
        |m| {
            let mut r = json(m, RESULTS);
            r["episodes"][0]["control_steps"] = Value::from(3);
            set_json(m, RESULTS, &r);
        },
        &[format!(
            "{RESULTS}: not the report of its verified journal: episodes[0].control_steps: 3 (derived {})",
            line(&fixture().members)["control_steps"]
        )],
    );
    // Numbers JSON does not have, and nesting past the parser's depth, are refused at parse.
    let nan = String::from_utf8(fixture().members[RESULTS].clone())
        .unwrap()
        .replacen("\"success_rate\": 1.0", "\"success_rate\": NaN", 1);
    let why = serde_json::from_str::<Value>(&nan).unwrap_err().to_string();
    refused_exactly(
        "forged-results-nan",
        |m| {
            m.insert(RESULTS.into(), nan.clone().into_bytes());
        },
        &[format!("{RESULTS}: not a results file: {why}")],
    );
    let mut deep = json(&fixture().members, RESULTS);
    let nested = "[".repeat(5000) + &"]".repeat(5000);
    deep["note"] = Value::Null;
    let deep_text = serde_json::to_string(&deep)
        .unwrap()
        .replace("\"note\":null", &format!("\"note\":{nested}"));
    let why = serde_json::from_str::<Value>(&deep_text)
        .unwrap_err()
        .to_string();
    assert!(why.contains("recursion limit"), "{why}");
    refused_exactly(
        "forged-results-deep",
        |m| {
            m.insert(RESULTS.into(), deep_text.clone().into_bytes());
        },
        &[format!("{RESULTS}: not a results file: {why}")],
    );
}

/// The fixture's recording with `edit(topic, data)` applied to its messages.
fn forge_recording(
    m: &mut BTreeMap<String, Vec<u8>>,
    edit: impl FnMut(&str, &[u8]) -> Option<Vec<u8>>,
) {
    let dir = scratch("forged-recording");
    let (src, dst) = (dir.join("in.mcap"), dir.join("out.mcap"));
    std::fs::write(&src, &m[RECORDING]).unwrap();
    rewrite(&src, &dst, edit);
    m.insert(RECORDING.into(), std::fs::read(&dst).unwrap());
}

/// A copy of the recording `bytes` written message by message with mcap's own writer (schemas,
/// channels and times kept), leaving out the messages `keep` refuses, with `extra` written last
/// (an attachment): what a forger with the mcap library makes.
fn copy_mcap(
    bytes: &[u8],
    mut keep: impl FnMut(&mcap::Message) -> bool,
    extra: impl FnOnce(&mut mcap::Writer<&mut std::io::Cursor<Vec<u8>>>),
) -> Vec<u8> {
    let src = scratch("copy-mcap").join("in.mcap");
    std::fs::write(&src, bytes).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::Writer::new(&mut out).unwrap();
        let mut channels = BTreeMap::new();
        results::recording::for_each_message(&src, |msg| {
            if !keep(msg) {
                return Ok(());
            }
            let schema = msg.channel.schema.clone();
            let id = *channels
                .entry(msg.channel.topic.clone())
                .or_insert_with(|| {
                    let sid = schema
                        .map(|s| w.add_schema(&s.name, &s.encoding, &s.data).unwrap())
                        .unwrap_or(0);
                    w.add_channel(
                        sid,
                        &msg.channel.topic,
                        &msg.channel.message_encoding,
                        &msg.channel.metadata,
                    )
                    .unwrap()
                });
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: msg.sequence,
                    log_time: msg.log_time,
                    publish_time: msg.publish_time,
                },
                &msg.data,
            )
            .unwrap();
            Ok(())
        })
        .unwrap();
        extra(&mut w);
        w.finish().unwrap();
    }
    out.into_inner()
}

/// The log time (s) of message `k` on `topic` in the fixture's recording.
fn log_time(topic: &str, k: usize) -> f64 {
    let dir = scratch("recording-times");
    let src = dir.join("in.mcap");
    std::fs::write(&src, &fixture().members[RECORDING]).unwrap();
    let mut times = Vec::new();
    results::recording::for_each_message(&src, |msg| {
        if msg.channel.topic == topic {
            times.push(msg.log_time);
        }
        Ok(())
    })
    .unwrap();
    times[k] as f64 * 1e-9
}

fn not_the_episodes(d: &str) -> Vec<String> {
    vec![format!(
        "{WHO}: its recording {RECORDING} is not the re-enacted episode's: {d}"
    )]
}

#[test]
fn a_recording_is_the_re_enacted_episodes_message_for_message() {
    // The verdict recorded inside the recording, with the journal left honest.
    refused_exactly(
        "forged-recorded-verdict",
        |m| {
            forge_recording(m, |topic, data| {
                (topic == "/verdict").then(|| {
                    let mut v: Value = serde_json::from_slice(data).unwrap();
                    v["verdict"]["stages"][0]["completed_at_s"] = Value::from(0.5);
                    serde_json::to_vec(&v).unwrap()
                })
            })
        },
        &not_the_episodes(&format!(
            "`/verdict` message 0 (at {} s) is not the episode's",
            log_time("/verdict", 0)
        )),
    );
    // A state the site draws frames from, moved.
    let mut k = 0;
    refused_exactly(
        "forged-recorded-labware",
        |m| {
            forge_recording(m, |topic, data| {
                if topic != "/labware/state" {
                    return None;
                }
                k += 1;
                (k == 40).then(|| {
                    let mut v: Value = serde_json::from_slice(data).unwrap();
                    v["labware"][0]["pose"]["pos"][2] = Value::from(0.9);
                    serde_json::to_vec(&v).unwrap()
                })
            })
        },
        &not_the_episodes(&format!(
            "`/labware/state` message 39 (at {} s) is not the episode's",
            log_time("/labware/state", 39)
        )),
    );
    // The policy's stage labels are its own: a recording without them still verifies.
    let mut m = fixture().members.clone();
    forge_recording(&mut m, |_, _| None);
    let out = scratch("relabelled").join("b.tar.zst");
    pack(&m, &out, true);
    let (code, refusals, said) = verify_away(&out, &[]);
    assert_eq!((code, refusals.len()), (0, 0), "{said}");
}

#[test]
fn a_recording_with_an_attachment_padding_or_a_cut_end_is_refused() {
    refused_exactly(
        "forged-attachment",
        |m| {
            let forged = copy_mcap(
                &m[RECORDING],
                |_| true,
                |w| {
                    w.attach(&mcap::Attachment {
                        log_time: 0,
                        create_time: 0,
                        name: "notes.txt".into(),
                        media_type: "text/plain".into(),
                        data: std::borrow::Cow::Borrowed(b"the best model"),
                    })
                    .unwrap();
                },
            );
            m.insert(RECORDING.into(), forged);
        },
        &not_the_episodes("it carries an attachment `notes.txt`"),
    );
    let padded = {
        let mut b = fixture().members[RECORDING].clone();
        b.extend_from_slice(&[0u8; 64]);
        b
    };
    let dir = scratch("padded");
    std::fs::write(dir.join("p.mcap"), &padded).unwrap();
    let padded_reads = results::recording::read_recording(&dir.join("p.mcap"));
    let want = match &padded_reads {
        Ok(_) => not_the_episodes(
            "it does not end with MCAP's closing magic (truncated, or bytes after it)",
        ),
        Err(e) => vec![format!(
            "{WHO}: its recording {RECORDING} does not read: {e}"
        )],
    };
    refused_exactly(
        "forged-padded",
        |m| {
            m.insert(RECORDING.into(), padded.clone());
        },
        &want,
    );
    let cut = {
        let b = &fixture().members[RECORDING];
        b[..b.len() - 100].to_vec()
    };
    std::fs::write(dir.join("c.mcap"), &cut).unwrap();
    let Err(why) = results::recording::read_recording(&dir.join("c.mcap")) else {
        panic!("a recording cut short reads")
    };
    refused_exactly(
        "forged-cut",
        |m| {
            m.insert(RECORDING.into(), cut.clone());
        },
        &[format!(
            "{WHO}: its recording {RECORDING} does not read: {why}"
        )],
    );
}

/// The manifest with `edit` applied.
fn forge_manifest(m: &mut BTreeMap<String, Vec<u8>>, edit: impl FnOnce(&mut Value)) {
    let mut v = json(m, MANIFEST);
    edit(&mut v);
    set_json(m, MANIFEST, &v);
}

#[test]
fn every_manifest_field_is_what_verification_derives() {
    let m0 = json(&fixture().members, MANIFEST);
    let index = json(&fixture().members, "index.json");
    let (version, commit) = (m0["autobio_version"].clone(), m0["git_commit"].clone());
    let other = "0123456789abcdef0123456789abcdef01234567";
    refused_exactly(
        "forged-manifest-commit",
        |m| forge_manifest(m, |v| v["git_commit"] = other.into()),
        &[format!(
            "{MANIFEST}: autobio {} at commit {other}; the index says {} at {}",
            version.as_str().unwrap(),
            version.as_str().unwrap(),
            commit.as_str().unwrap()
        )],
    );
    assert_eq!(
        index["git_commit"], commit,
        "the index names the runs' commit"
    );
    refused_exactly(
        "forged-index-commit",
        |m| {
            let mut i = json(m, "index.json");
            i["git_commit"] = other.into();
            set_json(m, "index.json", &i);
        },
        &[format!(
            "{MANIFEST}: autobio {} at commit {}; the index says {} at {other}",
            version.as_str().unwrap(),
            commit.as_str().unwrap(),
            version.as_str().unwrap(),
        )],
    );
    refused_exactly(
        "forged-manifest-schema",
        |m| forge_manifest(m, |v| v["results_schema_version"] = 3.into()),
        &[format!(
            "{MANIFEST}: results schema version 3; this autobio writes and reads version {}",
            results::run::RESULTS_SCHEMA_VERSION
        )],
    );
    let zeros = "0".repeat(64);
    refused_exactly(
        "forged-manifest-task-sha",
        |m| forge_manifest(m, |v| v["task_sha256"] = zeros.clone().into()),
        &[format!(
            "{MANIFEST}: compiled task SHA-256 {zeros}; the shipped task compiled from its paths is {}",
            m0["task_sha256"].as_str().unwrap()
        )],
    );
    refused_exactly(
        "forged-manifest-protocol-sha",
        |m| forge_manifest(m, |v| v["protocol_sha256"] = zeros.clone().into()),
        &[format!(
            "{MANIFEST}: protocol SHA-256 {zeros}; the shipped file's is {}",
            m0["protocol_sha256"].as_str().unwrap()
        )],
    );
    let protocol = m0["protocol"].as_str().unwrap().to_string();
    let moved = protocol.replace("close_then_open", "open_then_close");
    refused_exactly(
        "forged-manifest-protocol-path",
        |m| forge_manifest(m, |v| v["protocol"] = moved.clone().into()),
        &[format!(
            "{MANIFEST}: protocol `{moved}` is not the suite's `../protocols/thermal_cycler/close_then_open.toml`"
        )],
    );
    let files = m0["protocol_files"].as_object().unwrap().clone();
    let (first, sha) = files.iter().next().unwrap();
    refused_exactly(
        "forged-manifest-protocol-files",
        |m| forge_manifest(m, |v| v["protocol_files"][first] = zeros.clone().into()),
        &[format!(
            "{MANIFEST}: protocol files: {first}: \"{zeros}\" (derived {sha})"
        )],
    );
    let limit = m0["conditions"]["time_limit_s"].clone();
    refused_exactly(
        "forged-manifest-conditions",
        |m| forge_manifest(m, |v| v["conditions"]["time_limit_s"] = 999.0.into()),
        &[format!(
            "{MANIFEST}: conditions: time_limit_s: 999.0 (derived {limit})"
        )],
    );
    refused_exactly(
        "forged-manifest-extra",
        |m| forge_manifest(m, |v| v["verified_by"] = "us".into()),
        &[format!(
            "{MANIFEST}: not a manifest: verified_by: not a field of it"
        )],
    );
}

#[test]
fn index_membership_is_checked_both_ways_and_an_unknown_index_field_is_refused() {
    // A run file the index does not list (packed without rehashing).
    control();
    let mut m = fixture().members.clone();
    let extra = "runs/0/thermal_cycler.close_then_open_seed7.mcap";
    m.insert(extra.into(), m[RECORDING].clone());
    let out = scratch("forged-unlisted").join("b.tar.zst");
    pack(&m, &out, false);
    let (code, refusals, said) = verify_away(&out, &[]);
    assert_eq!(code, 1, "{said}");
    assert_eq!(refusals, [format!("{extra} is not in the index")], "{said}");
    // A listed member the archive lacks.
    let mut m = fixture().members.clone();
    m.remove(RESULTS);
    let out = scratch("forged-missing").join("b.tar.zst");
    pack(&m, &out, false);
    let (code, refusals, said) = verify_away(&out, &[]);
    assert_eq!(code, 1, "{said}");
    assert_eq!(
        refusals,
        [format!("{RESULTS} is in the index but not in the archive")],
        "{said}"
    );
    // An index that does not parse, and one of another schema version.
    let unpacked = |name: &str, index: &[u8]| -> Vec<String> {
        let mut m = fixture().members.clone();
        m.insert("index.json".into(), index.to_vec());
        let out = scratch(name).join("b.tar.zst");
        pack(&m, &out, false);
        let (code, refusals, said) = verify_away(&out, &[]);
        assert_eq!(code, 1, "{said}");
        refusals
            .iter()
            .map(|r| r.replacen(&format!("{}: ", out.display()), "", 1))
            .collect()
    };
    let why = serde_json::from_slice::<Value>(b"{").unwrap_err();
    assert_eq!(
        unpacked("forged-index-cut", b"{"),
        [format!("index.json does not read: {why}")]
    );
    let mut i = json(&fixture().members, "index.json");
    i["schema_version"] = 2.into();
    assert_eq!(
        unpacked("forged-index-schema", &serde_json::to_vec(&i).unwrap()),
        ["index.json is schema version 2; this autobio reads version 1"]
    );
    refused_exactly(
        "forged-index-extra",
        |m| {
            let mut i = json(m, "index.json");
            i["rank"] = 1.into();
            set_json(m, "index.json", &i);
        },
        &["index.json: rank: not a field of it".to_string()],
    );
}

#[test]
fn journals_without_manifests_and_unplanned_seeds_are_refused() {
    refused_exactly(
        "forged-no-manifest",
        |m| {
            m.remove(MANIFEST);
        },
        &[
            format!("{TASK}: no run of this suite task in the bundle"),
            format!("{JOURNAL}: a journal without its manifest"),
        ],
    );
    refused_exactly(
        "forged-unplanned-seed",
        |m| {
            let first = text(&m[JOURNAL]);
            let mut other = line(m);
            other["seed"] = 5.into();
            let both = first + &other.to_string() + "\n";
            m.insert(JOURNAL.into(), both.into_bytes());
        },
        &[format!("{TASK}: seed 5 (run 0) is not one the suite plans")],
    );
    // A recording no journal line claims (a seed spelt with a leading zero), listed in the index.
    let stray = "runs/0/thermal_cycler.close_then_open_seed00.mcap";
    refused_exactly(
        "forged-stray-recording",
        |m| {
            m.insert(stray.into(), m[RECORDING].clone());
        },
        &[format!(
            "{stray} is the recording of no episode verified here (a planned seed of a suite task \
             in this run folder's journal)"
        )],
    );
    refused_exactly(
        "forged-cut-journal",
        |m| {
            let j = text(&m[JOURNAL]);
            m.insert(JOURNAL.into(), j.trim_end().as_bytes().to_vec());
        },
        &[format!("{JOURNAL}: line 1 is cut short")],
    );
}

#[test]
fn archives_past_the_limits_are_refused() {
    let f = fixture();
    let bundle = f.bundle.to_str().unwrap();
    let members = f.members.len() as u64;
    let biggest = f.members.values().map(|b| b.len() as u64).max().unwrap();
    let total: u64 = f.members.values().map(|b| b.len() as u64).sum();
    let big = (u64::MAX / 4).to_string();
    // The control: limits the bundle is within.
    let (code, _, said) = verify_away(
        &f.bundle,
        &["--limits", &members.to_string(), &biggest.to_string(), &big],
    );
    assert_eq!(code, 0, "{said}");
    let limited = |lim: [String; 3]| {
        let (code, refusals, said) =
            verify_away(&f.bundle, &["--limits", &lim[0], &lim[1], &lim[2]]);
        assert_eq!(code, 1, "{said}");
        assert_eq!(refusals.len(), 1, "{said}");
        refusals[0]
            .strip_prefix(&format!("{bundle}: "))
            .unwrap()
            .to_string()
    };
    let why = limited([(members - 1).to_string(), big.clone(), big.clone()]);
    assert!(
        why.ends_with(&format!(
            "is refused: the archive has more than {} members",
            members - 1
        )),
        "{why}"
    );
    let why = limited([members.to_string(), (biggest - 1).to_string(), big.clone()]);
    assert_eq!(
        why,
        format!(
            "the archive member `{RECORDING}` is refused: it is {biggest} bytes; a member may be at most {}",
            biggest - 1
        )
    );
    let why = limited([members.to_string(), big.clone(), (total / 2).to_string()]);
    assert_eq!(
        why,
        format!(
            "the archive is refused: it unpacks to more than {} bytes",
            total / 2
        )
    );
}

/// The paper suite's two-robot tasks, one expert episode each, in a suite of their own (the
/// shipped paper suite plans 300 episodes a task): the run, its bundle and the suites folder.
struct TwoRobots {
    suites: PathBuf,
    run: PathBuf,
    bundle: PathBuf,
}

const TWO_ROBOT_TASKS: [(&str, &str); 3] = [
    ("pipette.aspirate", "protocols/pipette/aspirate.toml"),
    ("tube.unscrew_cap", "protocols/tube/unscrew_cap.toml"),
    ("tube.screw_cap", "protocols/tube/screw_cap.toml"),
];

fn two_robots() -> &'static TwoRobots {
    static F: OnceLock<TwoRobots> = OnceLock::new();
    F.get_or_init(|| {
        let root = scratch("two-robots");
        let suites = root.join("suites");
        std::fs::create_dir_all(&suites).unwrap();
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let tasks: Vec<String> = TWO_ROBOT_TASKS
            .iter()
            .map(|(_, p)| format!("{:?}", repo.join(p).display().to_string()))
            .collect();
        std::fs::write(
            suites.join("two.toml"),
            format!(
                "format = 1\n[suite]\nname = \"two\"\nepisodes = 1\nseed = 0\nruns = 1\ntasks = [{}]\n",
                tasks.join(", ")
            ),
        )
        .unwrap();
        let run = root.join("run");
        common::eval_suite(&suites.join("two.toml"), &run, &["--policy", "expert"]);
        let bundle = root.join("two.tar.zst");
        common::submit(&run, "scripted expert", &bundle, &[]);
        TwoRobots { suites, run, bundle }
    })
}

/// The robots of a two-robot task's recording, in its channels' order, and its action count.
fn robots_of(recording: &[u8]) -> (Vec<String>, usize) {
    let path = scratch("robots-of").join("r.mcap");
    std::fs::write(&path, recording).unwrap();
    let s = results::recording::read_recording(&path).unwrap();
    let robots: Vec<String> = s.actions.keys().cloned().collect();
    let steps = s.actions.values().next().unwrap().len();
    (robots, steps)
}

#[test]
fn two_robot_episodes_re_enact_and_an_action_of_the_second_robot_is_checked() {
    let f = two_robots();
    let suites = f.suites.to_str().unwrap();
    let (code, refusals, said) = verify_away(&f.bundle, &["--suites", suites]);
    assert_eq!((code, refusals.len()), (0, 0), "{said}");
    assert!(said.contains("(3 tasks, 3 episodes)"), "{said}");
    let genuine = members(&f.bundle);
    // Every task's second robot nudged by 1e-9 at step 40: each episode refused.
    let mut m = genuine.clone();
    let mut want = Vec::new();
    for (task, _) in TWO_ROBOT_TASKS {
        let key = format!("runs/0/{task}_seed0.mcap");
        let (robots, _) = robots_of(&m[&key]);
        assert_eq!(robots.len(), 2, "{task}: {robots:?}");
        let topic = format!("/robot/{}/action", robots[1]);
        let dir = scratch("nudge-second");
        let (src, dst) = (dir.join("in.mcap"), dir.join("out.mcap"));
        std::fs::write(&src, &m[&key]).unwrap();
        let mut k = 0;
        rewrite(&src, &dst, |t, data| {
            if t != topic {
                return None;
            }
            k += 1;
            (k == 40).then(|| {
                let mut v: Value = serde_json::from_slice(data).unwrap();
                v["action"][0] = Value::from(v["action"][0].as_f64().unwrap() + 1e-9);
                serde_json::to_vec(&v).unwrap()
            })
        });
        m.insert(key, std::fs::read(&dst).unwrap());
        want.push(format!(
            "{task} seed 0 (run 0): re-enacted from its seed and recorded actions, "
        ));
    }
    let out = scratch("two-nudged").join("b.tar.zst");
    pack(&m, &out, true);
    let (code, refusals, said) = verify_away(&out, &["--suites", suites]);
    assert_eq!((code, refusals.len()), (1, 3), "{said}");
    // Each episode refused once, on what the nudge changed (its hash, or its length where the
    // episode now ends a step sooner).
    for (r, w) in refusals.iter().zip(&want) {
        assert!(r.starts_with(w.as_str()), "{r}\nwanted {w}...");
    }
    // One robot's actions one short of the other's.
    let (task, _) = TWO_ROBOT_TASKS[2];
    let key = format!("runs/0/{task}_seed0.mcap");
    let (robots, steps) = robots_of(&genuine[&key]);
    let topic = format!("/robot/{}/action", robots[1]);
    let mut k = 0;
    let short = copy_mcap(
        &genuine[&key],
        |msg| {
            if msg.channel.topic == topic {
                k += 1;
            }
            !(msg.channel.topic == topic && k == steps)
        },
        |_| {},
    );
    let mut m = genuine.clone();
    m.insert(key, short);
    let out = scratch("two-short").join("b.tar.zst");
    pack(&m, &out, true);
    let (code, refusals, said) = verify_away(&out, &["--suites", suites]);
    assert_eq!(code, 1, "{said}");
    assert_eq!(
        refusals,
        [format!(
            "{task} seed 0 (run 0): the recording has {} actions for robot `{}` and {steps} for another",
            steps - 1,
            robots[1]
        )],
        "{said}"
    );
}

#[test]
fn a_two_robot_recording_re_simulates_bit_for_bit() {
    let f = two_robots();
    for (task, _) in TWO_ROBOT_TASKS {
        let rec = f.run.join(format!("{task}_seed0.mcap"));
        let said = common::autobio_ok(&["replay", rec.to_str().unwrap(), "--simulate"]);
        let hash = common::journal(&f.run, task)[0]["trajectory_hash"]
            .as_str()
            .unwrap()
            .to_string();
        assert!(
            said.contains(&format!("trajectory hash  {hash}")),
            "{task}: {said}"
        );
        assert!(
            said.contains("every state equal to the recorded one, bit for bit"),
            "{task}: {said}"
        );
        assert!(
            said.contains("reproduced (re-judged: success"),
            "{task}: {said}"
        );
    }
}
