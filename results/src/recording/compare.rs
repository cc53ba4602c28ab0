//! Two recordings compared message by message: what a verifier does with a submitted recording
//! and the one its own re-enactment wrote. Each topic's messages (schema, encoding, log time,
//! bytes) must be the same, in the same order; a file must be exactly one MCAP file (nothing
//! after its closing magic) with no attachment, metadata or record of an unknown kind (nothing a
//! reader may show that the comparison did not see).
//!
//! It compares; it neither writes nor re-enacts recordings.

use super::RecordError;
use std::collections::BTreeMap;
use std::path::Path;

/// One topic's messages: its schema name and encoding, and each message's log time and bytes.
#[derive(Default)]
struct Topic {
    schema: String,
    encoding: String,
    messages: Vec<(u64, Vec<u8>)>,
}

/// A recording's messages by topic, skipping the topics `skip` names.
fn topics(path: &Path, skip: &dyn Fn(&str) -> bool) -> Result<BTreeMap<String, Topic>, String> {
    let buf = std::fs::read(path).map_err(|e| RecordError::Read(e).to_string())?;
    if !buf.ends_with(mcap::MAGIC) {
        return Err(
            "it does not end with MCAP's closing magic (truncated, or bytes after it)".into(),
        );
    }
    let reader = mcap::read::LinearReader::new(&buf).map_err(|e| e.to_string())?;
    for record in reader {
        match record.map_err(|e| format!("not a readable MCAP file: {e}"))? {
            mcap::records::Record::Attachment { header, .. } => {
                return Err(format!("it carries an attachment `{}`", header.name));
            }
            mcap::records::Record::Metadata(m) => {
                return Err(format!("it carries a metadata record `{}`", m.name));
            }
            mcap::records::Record::Unknown { opcode, .. } => {
                return Err(format!(
                    "it carries a record of unknown kind (opcode {opcode:#x})"
                ));
            }
            _ => {}
        }
    }
    let mut out: BTreeMap<String, Topic> = BTreeMap::new();
    for m in mcap::MessageStream::new(&buf).map_err(|e| e.to_string())? {
        let m = m.map_err(|e| format!("not a readable MCAP file: {e}"))?;
        if skip(&m.channel.topic) {
            continue;
        }
        let t = out.entry(m.channel.topic.clone()).or_default();
        // The schema with its definition, and the channel's encoding and metadata: what a
        // viewer decodes and shows the messages by.
        t.schema = m
            .channel
            .schema
            .as_ref()
            .map(|s| {
                format!(
                    "{} ({}, definition {})",
                    s.name,
                    s.encoding,
                    crate::run::record::sha256_hex(&s.data)
                )
            })
            .unwrap_or_default();
        t.encoding = format!("{} {:?}", m.channel.message_encoding, m.channel.metadata);
        t.messages.push((m.log_time, m.data.into_owned()));
    }
    Ok(out)
}

/// The first way the recording `found` differs from `want` (topics `skip` names aside), as a
/// sentence, or `None` where they hold the same messages. `want` is trusted to read.
pub fn first_difference(
    found: &Path,
    want: &Path,
    skip: &dyn Fn(&str) -> bool,
) -> Result<Option<String>, RecordError> {
    let found = match topics(found, skip) {
        Ok(t) => t,
        Err(why) => return Ok(Some(why)),
    };
    let want =
        topics(want, skip).map_err(|why| RecordError::Bad(want.display().to_string(), why))?;
    for name in want.keys() {
        if !found.contains_key(name) {
            return Ok(Some(format!("it has no `{name}` messages")));
        }
    }
    for (name, f) in &found {
        let Some(w) = want.get(name) else {
            return Ok(Some(format!(
                "it has a `{name}` topic the episode does not write"
            )));
        };
        if (&f.schema, &f.encoding) != (&w.schema, &w.encoding) {
            return Ok(Some(format!(
                "`{name}` is {} in {}; the episode writes {} in {}",
                f.schema, f.encoding, w.schema, w.encoding
            )));
        }
        for (k, (a, b)) in f.messages.iter().zip(&w.messages).enumerate() {
            if a.0 != b.0 {
                return Ok(Some(format!(
                    "`{name}` message {k} is at {} s; the episode's is at {} s",
                    a.0 as f64 * 1e-9,
                    b.0 as f64 * 1e-9
                )));
            }
            if a.1 != b.1 {
                return Ok(Some(format!(
                    "`{name}` message {k} (at {} s) is not the episode's",
                    a.0 as f64 * 1e-9
                )));
            }
        }
        if f.messages.len() != w.messages.len() {
            return Ok(Some(format!(
                "it has {} `{name}` messages; the episode writes {}",
                f.messages.len(),
                w.messages.len()
            )));
        }
    }
    Ok(None)
}
