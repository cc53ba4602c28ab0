//! An Opentrons file read into one shape: the commands in order with their index and type, the
//! liquids by id, and the labware definitions the file carries. Two files give it:
//!
//! - an **analysis** (what `opentrons analyze --json-output` writes: `robotType`, `commands`
//!   each with `id`, `commandType`, `status`, `params`, `result`; `liquids` as a list; a
//!   `loadLabware`'s definition in its `result.definition`);
//! - a **protocol** of schema 8 (what Protocol Designer saves: `$otSharedSchema`
//!   `#/protocol/schemas/8`, `robot.model`, `labwareDefinitions` keyed by URI, `liquids` keyed by
//!   id, `commands` with `commandType`, `key`, `params`).
//!
//! The commands of both are the same objects (the command schema); their parameters are read
//! into typed structs where a command is realised (`commands.rs`). Nothing is realised here.

use super::super::json_span::Key;
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// Which of the two files it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flavour {
    Analysis,
    /// A Protocol Designer file of this schema version (8).
    Protocol(u32),
    /// An Autoprotocol document lowered into these commands (`crate::autoprotocol::lower`).
    Autoprotocol,
}

impl Flavour {
    pub fn describe(self) -> String {
        match self {
            Flavour::Analysis => "Opentrons analysis JSON".into(),
            Flavour::Protocol(v) => format!("Opentrons protocol JSON, schema {v}"),
            Flavour::Autoprotocol => "Autoprotocol JSON".into(),
        }
    }
}

/// One command as the file has it.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    pub index: usize,
    pub command_type: String,
    pub params: Value,
    /// An analysis's `result` (where a `load*` command's id and definition are).
    pub result: Value,
    /// An analysis whose command failed (`status = "failed"`).
    pub failed: bool,
    /// Where a command lowered from another format stands in its file, and how findings name it
    /// (`instructions[3] liquid_handle`); none for an Opentrons file's own commands.
    pub origin: Option<(Vec<Key>, String)>,
    /// The name the source gives what a `loadLabware` loads (an Autoprotocol ref's), used as the
    /// item's name where it can be one.
    pub name_hint: Option<String>,
}

impl Command {
    /// The path of a field of this command's `params` in the file.
    pub fn param_path(&self, field: &str) -> Vec<Key> {
        if let Some((at, _)) = &self.origin {
            return at.clone();
        }
        let mut p = self.path();
        p.push(Key::field("params"));
        if !field.is_empty() {
            p.push(Key::field(field));
        }
        p
    }

    /// The path of this command in the file.
    pub fn path(&self) -> Vec<Key> {
        match &self.origin {
            Some((at, _)) => at.clone(),
            None => vec![Key::field("commands"), Key::Index(self.index)],
        }
    }

    /// `commands[12] aspirate`: how a finding and the written step name it.
    pub fn label(&self) -> String {
        match &self.origin {
            Some((_, label)) => label.clone(),
            None => format!("commands[{}] {}", self.index, self.command_type),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LiquidInfo {
    #[serde(default)]
    pub display_name: String,
    #[serde(default)]
    pub description: Option<String>,
}

/// The file read into one shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    pub flavour: Flavour,
    /// `OT-2 Standard`, `OT-3 Standard` (the Flex), as the file says.
    pub robot_type: String,
    pub commands: Vec<Command>,
    pub liquids: BTreeMap<String, LiquidInfo>,
    /// Labware definitions the file carries, by URI (`namespace/loadName/version`).
    pub definitions: BTreeMap<String, Value>,
    /// The names the source gives single wells (an Autoprotocol tube ref's), by labware id and
    /// well: the tube's item name in place of `<holder>_<well>`.
    pub tube_names: BTreeMap<(String, String), String>,
}

/// Why a file is not one of the two: the message and where in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct Unreadable {
    pub message: String,
    pub hint: Option<String>,
    pub at: Vec<Key>,
}

fn unreadable(message: impl Into<String>, hint: Option<&str>, at: Vec<Key>) -> Unreadable {
    Unreadable {
        message: message.into(),
        hint: hint.map(str::to_string),
        at,
    }
}

/// Whether a parsed JSON document looks like an Opentrons file at all (an analysis or a
/// protocol), so that a caller can tell it from another format before reading it.
pub fn is_opentrons(doc: &Value) -> bool {
    doc.get("$otSharedSchema").is_some()
        || (doc.get("commands").is_some()
            && (doc.get("robotType").is_some() || doc.get("createdAt").is_some()))
}

/// Reads a parsed document.
pub fn read(doc: &Value) -> Result<Source, Unreadable> {
    let flavour = if let Some(schema) = doc.get("$otSharedSchema") {
        let version = doc.get("schemaVersion").and_then(Value::as_u64);
        match (schema.as_str(), version) {
            (Some("#/protocol/schemas/8"), Some(8)) => Flavour::Protocol(8),
            _ => {
                return Err(unreadable(
                    format!(
                        "protocol schema `{}` (schemaVersion {}) is not read",
                        schema.as_str().unwrap_or("?"),
                        version.map_or("none".to_string(), |v| v.to_string())
                    ),
                    Some(
                        "save it from Protocol Designer 8 (schema 8), or import its analysis (`opentrons analyze --json-output`)",
                    ),
                    vec![Key::field("$otSharedSchema")],
                ));
            }
        }
    } else {
        Flavour::Analysis
    };
    let robot_type = match flavour {
        Flavour::Analysis => doc.get("robotType"),
        Flavour::Protocol(_) => doc.get("robot").and_then(|r| r.get("model")),
        Flavour::Autoprotocol => None,
    }
    .and_then(Value::as_str)
    .unwrap_or("OT-2 Standard")
    .to_string();
    let Some(list) = doc.get("commands").and_then(Value::as_array) else {
        return Err(unreadable(
            "`commands` is missing or not a list",
            None,
            vec![Key::field("commands")],
        ));
    };
    let mut commands = Vec::with_capacity(list.len());
    for (index, c) in list.iter().enumerate() {
        let at = vec![Key::field("commands"), Key::Index(index)];
        let Some(command_type) = c.get("commandType").and_then(Value::as_str) else {
            return Err(unreadable(
                format!("command {index} has no `commandType`"),
                None,
                at,
            ));
        };
        let params = c.get("params").cloned().unwrap_or(Value::Null);
        if !params.is_object() {
            let mut at = at;
            at.push(Key::field("params"));
            return Err(unreadable(
                format!("command {index} ({command_type}) has no `params` object"),
                None,
                at,
            ));
        }
        commands.push(Command {
            index,
            command_type: command_type.to_string(),
            params,
            result: c.get("result").cloned().unwrap_or(Value::Null),
            failed: c.get("status").and_then(Value::as_str) == Some("failed"),
            origin: None,
            name_hint: None,
        });
    }
    let liquids = read_liquids(doc.get("liquids"))?;
    let definitions = match doc.get("labwareDefinitions") {
        Some(Value::Object(m)) => m.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
        _ => BTreeMap::new(),
    };
    Ok(Source {
        flavour,
        robot_type,
        commands,
        liquids,
        definitions,
        tube_names: BTreeMap::new(),
    })
}

/// Liquids: an object by id (a protocol) or a list with `id`s (an analysis).
fn read_liquids(v: Option<&Value>) -> Result<BTreeMap<String, LiquidInfo>, Unreadable> {
    let bad = |what: &str, at: Vec<Key>| {
        unreadable(
            format!("a liquid {what}"),
            Some("each liquid needs a `displayName`"),
            at,
        )
    };
    let mut out = BTreeMap::new();
    match v {
        None | Some(Value::Null) => {}
        Some(Value::Object(m)) => {
            for (id, l) in m {
                let at = vec![Key::field("liquids"), Key::field(id)];
                let info =
                    serde_json::from_value(l.clone()).map_err(|e| bad(&e.to_string(), at))?;
                out.insert(id.clone(), info);
            }
        }
        Some(Value::Array(list)) => {
            for (i, l) in list.iter().enumerate() {
                let at = vec![Key::field("liquids"), Key::Index(i)];
                let Some(id) = l.get("id").and_then(Value::as_str) else {
                    return Err(bad("without an `id`", at));
                };
                let info =
                    serde_json::from_value(l.clone()).map_err(|e| bad(&e.to_string(), at))?;
                out.insert(id.to_string(), info);
            }
        }
        Some(_) => {
            return Err(bad(
                "table that is neither an object by id nor a list",
                vec![Key::field("liquids")],
            ));
        }
    }
    Ok(out)
}
