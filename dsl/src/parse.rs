//! TOML text to [`Protocol`]: walks toml's spanned document tree, checking the shape (tables, keys,
//! types, units) and collecting every problem instead of stopping at the first.

use crate::ast::*;
use crate::quantity::{Dimension, parse_quantity, unit};
use crate::{Code, Diagnostic, Span, did_you_mean};
use toml::de::{DeTable, DeValue};

mod perturb;

pub use perturb::dimension_names as perturb_dimensions;

type Value<'i> = toml::Spanned<DeValue<'i>>;
type Key<'i> = toml::Spanned<std::borrow::Cow<'i, str>>;

/// Parses a protocol or chain file. Never fails and never panics: the AST holds whatever could be
/// read, and the diagnostics say what could not. A file with a top-level `[chain]` table is a chain.
pub fn parse(source: &str) -> (Document, Vec<Diagnostic>) {
    let mut p = Parser {
        diags: Vec::new(),
        kindless: Vec::new(),
    };
    let (doc, errors) = DeTable::parse_recoverable(source);
    if !errors.is_empty() {
        let mut unclosed = crate::source::unclosed_string(source);
        for e in errors {
            let mut span = e.span().map(Span::from).unwrap_or(Span::new(0, 0));
            // toml reports an unclosed string where it gave up looking for its end (the end of
            // the line, or of the file for a multi-line one); the mistake is where it opens.
            // Only the first such error is the unclosed string's; later ones are their own.
            if let Some(u) =
                unclosed.take_if(|u| e.message().contains("string") && u.span.start <= span.start)
            {
                p.diags.push(
                    Diagnostic::error(Code::E0001, u.span, format!("unclosed {}", u.what))
                        .with_hint(format!(
                            "the string that opens here never closes: end it with `{}`",
                            u.delimiter
                        )),
                );
                continue;
            }
            // An error reported at the start of a line belongs to the end of the line before.
            if span.start == span.end
                && span.start > 0
                && source.as_bytes().get(span.start - 1) == Some(&b'\n')
            {
                span = Span::new(span.start - 1, span.start - 1);
            }
            let msg = e.message().trim().trim_end_matches('.').to_string();
            let msg = lowercase_first(&msg);
            p.diags.push(
                Diagnostic::error(Code::E0001, span, format!("invalid toml: {msg}")).with_hint(
                    "fix the syntax here; the rest of the file is checked once it parses",
                ),
            );
        }
        return (Document::Protocol(Box::default()), p.diags);
    }
    let doc = doc.get_ref();
    p.greek_mu(source, doc);
    let scene_table = doc
        .iter()
        .any(|(k, v)| k.get_ref() == "scene" && matches!(v.get_ref(), DeValue::Table(_)));
    let document = if doc.iter().any(|(k, _)| k.get_ref() == "chain") {
        Document::Chain(Box::new(p.chain(doc)))
    } else if scene_table && !doc.iter().any(|(k, _)| k.get_ref() == "protocol") {
        Document::Scene(Box::new(p.scene_file(doc)))
    } else {
        Document::Protocol(Box::new(p.protocol(doc)))
    };
    (document, p.diags)
}

/// A table's entries in document order (toml's map is sorted by key).
fn ordered<'a, 'i>(t: &'a DeTable<'i>) -> Vec<(&'a Key<'i>, &'a Value<'i>)> {
    let mut v: Vec<_> = t.iter().collect();
    v.sort_by_key(|(k, _)| k.span().start);
    v
}

fn lowercase_first(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

struct Parser {
    diags: Vec<Diagnostic>,
    /// Labware entries without `kind`, reported unless the protocol names a scene file.
    kindless: Vec<Diagnostic>,
}

const TOP_KEYS: &[&str] = &[
    "format",
    "scene",
    "protocol",
    "robots",
    "labware",
    "params",
    "randomise",
    "steps",
    "success",
    "tolerances",
    "camera",
    "perturb",
];
const CHAIN_TOP_KEYS: &[&str] = &["format", "chain", "stages"];
const SCENE_TOP_KEYS: &[&str] = &[
    "format",
    "scene",
    "robots",
    "labware",
    "randomise",
    "camera",
    "perturb",
];
const SCENE_KEYS: &[&str] = &["description"];
const CHAIN_KEYS: &[&str] = &["id", "version", "level", "instruction"];
const STAGE_KEYS: &[&str] = &["protocol", "instruction", "time_limit"];
const PARAM_KEYS: &[&str] = &[
    "choice", "int", "step", "real", "slot", "free", "opposite", "balances", "tubes", "exclude",
];
const PROTOCOL_KEYS: &[&str] = &[
    "id",
    "version",
    "level",
    "instruction",
    "time_limit",
    "imported_from",
    "paraphrases",
];
const IMPORTED_KEYS: &[&str] = &["file", "format", "sha256"];
const ROBOT_KEYS: &[&str] = &["model", "base"];
const LABWARE_KEYS: &[&str] = &["kind", "pose", "at", "held_by", "state", "parts"];
const POSE_KEYS: &[&str] = &["pos", "yaw"];
const RANDOM_KEYS: &[&str] = &["joints", "xy", "yaw", "parts_radius"];
const SUCCESS_KEYS: &[&str] = &["all", "scoring", "weights", "settle"];
const CAMERA_KEYS: &[&str] = &["pos", "look_at", "fovy"];
const SCORINGS: &[&str] = &["binary", "progress"];
const LEVELS: &[&str] = &["easy", "medium", "hard"];
const MAX_ID_LEN: usize = 128;

fn span_of<T>(v: &toml::Spanned<T>) -> Span {
    Span::from(v.span())
}

fn type_name(v: &DeValue<'_>) -> &'static str {
    match v {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a datetime",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

/// Keys other tools name a step's action with, taken for a misspelt `do` when a step has none.
const DO_SYNONYMS: &[&str] = &[
    "action",
    "primitive",
    "op",
    "operation",
    "verb",
    "command",
    "type",
    "step",
];

/// Splits a unit-suffixed key (`yaw_deg`) into its base and unit; plain keys have no unit.
fn split_unit(key: &str) -> (&str, Option<(&str, Dimension, f64)>) {
    if let Some((base, sym)) = key.rsplit_once('_')
        && let Some((dim, factor)) = unit(sym)
    {
        return (base, Some((sym, dim, factor)));
    }
    (key, None)
}

impl Parser {
    /// A settings table's entries in document order, without a setting given a second time under
    /// another spelling (`time_limit` and `time_limit_s`, `pos_m` and `pos_mm`): that is an error,
    /// and neither spelling silently wins over the other; the first is kept for further checks.
    fn settings<'a, 'i>(&mut self, t: &'a DeTable<'i>) -> Vec<(&'a Key<'i>, &'a Value<'i>)> {
        let mut seen: std::collections::HashMap<&str, &Key<'i>> = Default::default();
        let mut out = Vec::new();
        for (key, value) in ordered(t) {
            let base = split_unit(key.get_ref()).0;
            if let Some(first) = seen.get(base) {
                let msg = format!(
                    "`{}` sets `{base}` again: it is already given as `{}`",
                    key.get_ref(),
                    first.get_ref()
                );
                let hint = format!(
                    "keep one of `{}` and `{}`; a setting is given once",
                    first.get_ref(),
                    key.get_ref()
                );
                self.err(Code::E0007, span_of(key), msg, Some(hint));
                continue;
            }
            seen.insert(base, key);
            out.push((key, value));
        }
        out
    }

    /// W0006 for every `μL` written with the Greek mu in a string value or a key: it looks like
    /// the micro sign `µL` is written with, and is read as one.
    fn greek_mu(&mut self, source: &str, t: &DeTable<'_>) {
        fn look(p: &mut Parser, source: &str, span: Span) {
            let Some(raw) = source.get(span.start..span.end) else {
                return;
            };
            for (i, _) in raw.match_indices("\u{3bc}L") {
                let at = span.start + i;
                p.diags.push(
                    Diagnostic::new(
                        Code::W0006,
                        Span::new(at, at + 2),
                        "`μ` here is the Greek letter mu (U+03BC), not the micro sign".to_string(),
                    )
                    .with_hint("it is read as microlitres; write `µL` (U+00B5) or `uL`"),
                );
            }
        }
        fn walk(p: &mut Parser, source: &str, v: &Value<'_>) {
            match v.get_ref() {
                DeValue::String(_) => look(p, source, span_of(v)),
                DeValue::Array(items) => {
                    for item in items.iter() {
                        walk(p, source, item);
                    }
                }
                DeValue::Table(t) => p.greek_mu(source, t),
                _ => {}
            }
        }
        for (k, v) in ordered(t) {
            look(self, source, span_of(k));
            walk(self, source, v);
        }
    }

    fn err(&mut self, code: Code, span: Span, msg: String, hint: Option<String>) {
        let mut d = Diagnostic::error(code, span, msg);
        d.hint = hint;
        self.diags.push(d);
    }

    fn unknown_key(&mut self, key: &Key<'_>, allowed: &[&str], table: &str) {
        let (base, _) = split_unit(key.get_ref());
        // A known key with a misspelt unit suffix (`time_limit_sec`): the suffix it means.
        let suffixed = key.get_ref().rsplit_once('_').and_then(|(b, sym)| {
            let unit = crate::quantity::suggest_unit(sym)?;
            allowed
                .contains(&b)
                .then(|| format!("did you mean `{b}_{unit}`? (a unit suffix is the unit's symbol)"))
        });
        let hint = suffixed
            .or_else(|| {
                did_you_mean(base, allowed.iter().copied()).map(|s| format!("did you mean `{s}`?"))
            })
            .or_else(|| Some(format!("keys allowed in {table}: {}", allowed.join(", "))));
        self.err(
            Code::E0003,
            span_of(key),
            format!("unknown key `{}` in {table}", key.get_ref()),
            hint,
        );
    }

    fn table<'a, 'i>(&mut self, v: &'a Value<'i>, what: &str) -> Option<&'a DeTable<'i>> {
        match v.get_ref() {
            DeValue::Table(t) => Some(t),
            other => {
                let msg = format!("{what} must be a table, found {}", type_name(other));
                self.err(Code::E0004, span_of(v), msg, None);
                None
            }
        }
    }

    fn string(&mut self, v: &Value<'_>, what: &str) -> Option<Spanned<String>> {
        match v.get_ref() {
            DeValue::String(s) => Some(Spanned::new(s.to_string(), span_of(v))),
            other => {
                let msg = format!("`{what}` must be a string, found {}", type_name(other));
                self.err(Code::E0004, span_of(v), msg, None);
                None
            }
        }
    }

    fn integer(&mut self, v: &Value<'_>, what: &str) -> Option<Spanned<i64>> {
        if let DeValue::Integer(i) = v.get_ref()
            && let Ok(n) = i64::from_str_radix(&i.as_str().replace('_', ""), i.radix())
        {
            return Some(Spanned::new(n, span_of(v)));
        }
        let msg = format!(
            "`{what}` must be an integer, found {}",
            type_name(v.get_ref())
        );
        self.err(Code::E0004, span_of(v), msg, None);
        None
    }

    fn number(&mut self, v: &Value<'_>, what: &str) -> Option<f64> {
        let parsed = match v.get_ref() {
            DeValue::Integer(i) => i64::from_str_radix(&i.as_str().replace('_', ""), i.radix())
                .ok()
                .map(|n| n as f64),
            DeValue::Float(f) => f
                .as_str()
                .replace('_', "")
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite()),
            _ => None,
        };
        if parsed.is_none() {
            let msg = format!(
                "`{what}` must be a finite number, found {}",
                type_name(v.get_ref())
            );
            self.err(Code::E0004, span_of(v), msg, None);
        }
        parsed
    }

    /// A scalar quantity of `dim`, from either `key_<unit> = number` or `key = "number unit"`.
    fn quantity(&mut self, key: &str, v: &Value<'_>, dim: Dimension) -> Option<Spanned<f64>> {
        let (base, suffix) = split_unit(key);
        let span = span_of(v);
        match (suffix, v.get_ref()) {
            (Some((sym, d, factor)), _) => {
                if d != dim {
                    let msg = format!(
                        "`{key}` uses unit `{sym}` ({}), but `{base}` is a {}",
                        d.name(),
                        dim.name()
                    );
                    let hint = format!("use one of: {}", dim.example_units());
                    self.err(Code::E0020, span, msg, Some(hint));
                    return None;
                }
                self.number(v, key).map(|x| Spanned::new(x * factor, span))
            }
            (None, DeValue::String(s)) => match parse_quantity(s) {
                Ok(q) if q.dimension == dim => Some(Spanned::new(q.si, span)),
                Ok(q) => {
                    let msg = format!(
                        "`{s}` is a {}, but `{key}` is a {}",
                        q.dimension.name(),
                        dim.name()
                    );
                    let hint = format!("use one of: {}", dim.example_units());
                    self.err(Code::E0020, span, msg, Some(hint));
                    None
                }
                Err(e) => {
                    let hint = format!(
                        "write a number and a unit of {}: e.g. \"{}\"",
                        dim.name(),
                        example(dim)
                    );
                    self.err(Code::E0020, span, e.to_string(), Some(hint));
                    None
                }
            },
            (None, DeValue::Integer(_) | DeValue::Float(_)) => {
                let msg = format!("`{key}` is a {} but has no unit", dim.name());
                let hint = format!(
                    "write \"{}\" or use a suffixed key such as `{key}_{}`",
                    example(dim),
                    unit_of(dim)
                );
                self.err(Code::E0020, span, msg, Some(hint));
                None
            }
            (None, other) => {
                let msg = format!(
                    "`{key}` must be a quantity such as \"{}\", found {}",
                    example(dim),
                    type_name(other)
                );
                self.err(Code::E0004, span, msg, None);
                None
            }
        }
    }

    /// An array of numbers in the unit given by the key's suffix (required for arrays).
    fn quantity_array(
        &mut self,
        key: &str,
        v: &Value<'_>,
        dim: Dimension,
        len: Option<usize>,
    ) -> Option<Spanned<Vec<f64>>> {
        let (base, suffix) = split_unit(key);
        let span = span_of(v);
        let Some((sym, d, factor)) = suffix else {
            let msg = format!(
                "`{key}` is an array of {}s but its key names no unit",
                dim.name()
            );
            let hint = format!("name the unit in the key, e.g. `{key}_{}`", unit_of(dim));
            self.err(Code::E0020, span_of(v), msg, Some(hint));
            return None;
        };
        if d != dim {
            let msg = format!(
                "`{key}` uses unit `{sym}` ({}), but `{base}` is a {}",
                d.name(),
                dim.name()
            );
            self.err(
                Code::E0020,
                span,
                msg,
                Some(format!("use one of: {}", dim.example_units())),
            );
            return None;
        }
        let DeValue::Array(items) = v.get_ref() else {
            let msg = format!("`{key}` must be an array, found {}", type_name(v.get_ref()));
            self.err(Code::E0004, span, msg, None);
            return None;
        };
        let mut out = Vec::new();
        for item in items.iter() {
            out.push(self.number(item, key)? * factor);
        }
        if let Some(n) = len
            && out.len() != n
        {
            let msg = format!("`{key}` must have {n} elements, found {}", out.len());
            self.err(Code::E0004, span, msg, None);
            return None;
        }
        Some(Spanned::new(out, span))
    }

    fn protocol(&mut self, doc: &DeTable<'_>) -> Protocol {
        let mut p = Protocol {
            meta: Meta {
                span: Span::new(0, 0),
                ..Meta::default()
            },
            ..Protocol::default()
        };
        for (key, value) in ordered(doc) {
            match key.get_ref().as_ref() {
                "format" => p.format = self.integer(value, "format"),
                "scene" => p.scene = self.string(value, "scene"),
                "protocol" => p.meta = self.meta(value),
                k if self.scene_part(k, value, &mut p) => {}
                "params" => {
                    p.params = self.named_tables(value, "[params]", |s, n, t| s.param(n, t))
                }
                "steps" => p.steps = self.steps(value),
                "success" => p.success = self.success(value),
                "tolerances" => p.tolerances = self.tolerances(value),
                _ => self.unknown_key(key, TOP_KEYS, "the top level"),
            }
        }
        let kindless = std::mem::take(&mut self.kindless);
        if p.scene.is_none() {
            self.diags.extend(kindless);
        }
        self.check_format(p.format.as_ref());
        if !doc.iter().any(|(k, _)| k.get_ref() == "protocol") {
            self.err(
                Code::E0002,
                Span::new(0, 0),
                "missing table `[protocol]`".into(),
                Some("add `[protocol]` with id, instruction and time_limit".into()),
            );
        }
        if p.steps.is_empty() && !self.diags.iter().any(|d| d.code == Code::E0004) {
            self.err(
                Code::E0002,
                Span::new(0, 0),
                "the protocol has no `[[steps]]`".into(),
                Some("add at least one `[[steps]]` with `do`, `on` and `with`".into()),
            );
        }
        if p.success.all.is_empty() && !doc.iter().any(|(k, _)| k.get_ref() == "success") {
            self.err(
                Code::E0002,
                Span::new(0, 0),
                "missing table `[success]`".into(),
                Some("add `[success]` with `all = [\"<labware>.<part> is <state>\", ...]`".into()),
            );
        }
        p
    }

    /// A scene file: `format`, a `[scene]` table (with an optional `description`), and the
    /// tables a protocol's scene is made of. Steps, success, parameters and the like belong in
    /// the protocols that use it.
    fn scene_file(&mut self, doc: &DeTable<'_>) -> Protocol {
        let mut p = Protocol::default();
        for (key, value) in ordered(doc) {
            match key.get_ref().as_ref() {
                "format" => p.format = self.integer(value, "format"),
                "scene" => {
                    if let Some(t) = self.table(value, "`[scene]`") {
                        for (k, v) in self.settings(t) {
                            match k.get_ref().as_ref() {
                                "description" => {
                                    self.string(v, "scene.description");
                                }
                                _ => self.unknown_key(k, SCENE_KEYS, "`[scene]`"),
                            }
                        }
                    }
                }
                k if self.scene_part(k, value, &mut p) => {}
                _ => self.unknown_key(key, SCENE_TOP_KEYS, "a scene file"),
            }
        }
        let kindless = std::mem::take(&mut self.kindless);
        self.diags.extend(kindless);
        self.check_format(p.format.as_ref());
        p
    }

    /// The tables a scene is made of, read the same in a protocol and in a scene file; whether
    /// `key` was one of them.
    fn scene_part(&mut self, key: &str, value: &Value<'_>, p: &mut Protocol) -> bool {
        match key {
            "robots" => p.robots = self.named_tables(value, "[robots]", |s, n, t| s.robot(n, t)),
            "labware" => {
                p.labware = self.named_tables(value, "[labware]", |s, n, t| s.labware(n, t))
            }
            "randomise" => {
                p.randomise = self.named_tables(value, "[randomise]", |s, n, t| s.randomise(n, t))
            }
            "camera" => p.camera = self.camera(value),
            "perturb" => p.perturb = self.perturb(value),
            _ => return false,
        }
        true
    }

    fn meta(&mut self, v: &Value<'_>) -> Meta {
        let mut m = Meta {
            span: span_of(v),
            ..Meta::default()
        };
        let Some(t) = self.table(v, "`[protocol]`") else {
            return m;
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "id" => m.id = self.id(value, "protocol.id"),
                "version" => m.version = self.integer(value, "protocol.version"),
                "level" => m.level = self.level(value),
                "instruction" => m.instruction = self.prompt(value, "protocol.instruction"),
                "time_limit" => m.time_limit = self.time_limit(k, value),
                "imported_from" => m.imported_from = self.imported_from(value),
                "paraphrases" => {
                    m.paraphrases = self
                        .texts(value, "protocol.paraphrases")
                        .unwrap_or_default()
                }
                _ => self.unknown_key(key, PROTOCOL_KEYS, "`[protocol]`"),
            }
        }
        let present = |name: &str| t.iter().any(|(k, _)| split_unit(k.get_ref()).0 == name);
        for name in ["id", "instruction", "time_limit"] {
            if !present(name) {
                self.err(
                    Code::E0002,
                    m.span,
                    format!("`[protocol]` has no `{name}`"),
                    None,
                );
            }
        }
        m
    }

    fn named_tables<T>(
        &mut self,
        v: &Value<'_>,
        what: &str,
        mut each: impl FnMut(&mut Self, Spanned<String>, &DeTable<'_>) -> T,
    ) -> Vec<T> {
        let mut out = Vec::new();
        let Some(t) = self.table(v, &format!("`{what}`")) else {
            return out;
        };
        for (key, value) in ordered(t) {
            let name = Spanned::new(key.get_ref().to_string(), span_of(key));
            self.name(&name);
            if let Some(inner) = self.table(value, &format!("`{}` in {what}", name.value)) {
                out.push(each(self, name, inner));
            }
        }
        out
    }

    fn robot(&mut self, name: Spanned<String>, t: &DeTable<'_>) -> Robot {
        let mut r = Robot {
            name,
            model: None,
            base: Pose::default(),
        };
        for (key, value) in self.settings(t) {
            match key.get_ref().as_ref() {
                "model" => r.model = self.string(value, "model"),
                "base" => r.base = self.pose(value),
                _ => self.unknown_key(key, ROBOT_KEYS, "a robot"),
            }
        }
        if !t.iter().any(|(k, _)| k.get_ref() == "model") {
            self.err(
                Code::E0002,
                r.name.span,
                format!("robot `{}` has no `model`", r.name.value),
                Some("e.g. model = \"ur5e_2f85\"".into()),
            );
        }
        r
    }

    fn labware(&mut self, name: Spanned<String>, t: &DeTable<'_>) -> Labware {
        let mut l = Labware {
            name,
            kind: None,
            pose: Pose::default(),
            at: None,
            held_by: None,
            state: Vec::new(),
            parts: Vec::new(),
        };
        for (key, value) in self.settings(t) {
            match key.get_ref().as_ref() {
                "kind" => l.kind = self.string(value, "kind"),
                "pose" => l.pose = self.pose(value),
                "at" => l.at = self.string(value, "at"),
                "held_by" => l.held_by = self.string(value, "held_by"),
                "state" => {
                    if let Some(st) = self.table(value, "`state`") {
                        for (part, s) in ordered(st) {
                            if let Some(s) = self.scalar(s, part.get_ref()) {
                                l.state.push((
                                    Spanned::new(part.get_ref().to_string(), span_of(part)),
                                    s,
                                ));
                            }
                        }
                    }
                }
                "parts" => {
                    if let Some(parts) = self.table(value, "`parts`") {
                        for (part, pose) in ordered(parts) {
                            let name = Spanned::new(part.get_ref().to_string(), span_of(part));
                            let pose = self.pose(pose);
                            l.parts.push((name, pose));
                        }
                    }
                }
                _ => self.unknown_key(key, LABWARE_KEYS, "a labware entry"),
            }
        }
        if !t.iter().any(|(k, _)| k.get_ref() == "kind") {
            // Said once the file is read: in a protocol that names a scene file, an entry with
            // no kind gives the start of the scene's item of that name (the compiler checks it).
            self.kindless.push(
                Diagnostic::error(
                    Code::E0002,
                    l.name.span,
                    format!("labware `{}` has no `kind`", l.name.value),
                )
                .with_hint("e.g. kind = \"thermal_cycler\""),
            );
        }
        l
    }

    fn pose(&mut self, v: &Value<'_>) -> Pose {
        let mut p = Pose::default();
        let Some(t) = self.table(v, "a pose") else {
            return p;
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "pos" => {
                    p.pos = self
                        .quantity_array(k, value, Dimension::Length, Some(3))
                        .map(|s| Spanned::new([s.value[0], s.value[1], s.value[2]], s.span))
                }
                "yaw" => p.yaw = self.quantity(k, value, Dimension::Angle),
                _ => self.unknown_key(key, POSE_KEYS, "a pose"),
            }
        }
        p
    }

    /// `imported_from = { file = "..", format = "..", sha256 = ".." }`: every key a string, the
    /// hash 64 hex digits.
    fn imported_from(&mut self, v: &Value<'_>) -> Option<ImportedFrom> {
        let t = self.table(v, "`imported_from`")?;
        let mut out = ImportedFrom {
            span: span_of(v),
            ..ImportedFrom::default()
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            let text = |p: &mut Self| p.string(value, &format!("imported_from.{k}"));
            match k {
                "file" => out.file = text(self)?.value,
                "format" => out.format = text(self)?.value,
                "sha256" => {
                    let s = text(self)?;
                    if s.value.len() != 64 || !s.value.bytes().all(|b| b.is_ascii_hexdigit()) {
                        self.err(
                            Code::E0021,
                            s.span,
                            format!("`imported_from.sha256` `{}` is not 64 hex digits", s.value),
                            Some(
                                "the SHA-256 of the source file, as `autobio import` writes it"
                                    .into(),
                            ),
                        );
                        return None;
                    }
                    out.sha256 = s.value.to_ascii_lowercase();
                }
                _ => self.unknown_key(key, IMPORTED_KEYS, "`imported_from`"),
            }
        }
        for name in IMPORTED_KEYS {
            if !t.iter().any(|(k, _)| k.get_ref() == *name) {
                self.err(
                    Code::E0002,
                    out.span,
                    format!("`imported_from` has no `{name}`"),
                    Some(
                        "`imported_from = { file = \"..\", format = \"..\", sha256 = \"..\" }`"
                            .into(),
                    ),
                );
                return None;
            }
        }
        Some(out)
    }

    fn camera(&mut self, v: &Value<'_>) -> Option<Camera> {
        let t = self.table(v, "`[camera]`")?;
        let mut c = Camera {
            pos: None,
            look_at: None,
            fovy: None,
            span: span_of(v),
        };
        let point = |p: &mut Self, k: &str, value: &Value<'_>| {
            p.quantity_array(k, value, Dimension::Length, Some(3))
                .map(|s| Spanned::new([s.value[0], s.value[1], s.value[2]], s.span))
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "pos" => c.pos = point(self, k, value),
                "look_at" => c.look_at = point(self, k, value),
                "fovy" => c.fovy = self.quantity(k, value, Dimension::Angle),
                _ => self.unknown_key(key, CAMERA_KEYS, "`[camera]`"),
            }
        }
        for (needed, example) in [
            ("pos", "pos_m = [0.0, -0.6, 1.3]"),
            ("look_at", "look_at_m = [0.0, 0.0, 0.9]"),
        ] {
            if !t.iter().any(|(k, _)| split_unit(k.get_ref()).0 == needed) {
                self.err(
                    Code::E0002,
                    c.span,
                    format!("`[camera]` has no `{needed}`"),
                    Some(format!("e.g. {example}")),
                );
            }
        }
        Some(c)
    }

    fn randomise(&mut self, target: Spanned<String>, t: &DeTable<'_>) -> Randomisation {
        let mut r = Randomisation {
            target,
            items: Vec::new(),
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "joints" => {
                    let Some(jt) = self.table(value, "`joints`") else {
                        continue;
                    };
                    // Arrays (`low`/`high`): a robot's joints; `role = angle` pairs: an item's.
                    // The form is the values' shape, so a misspelt `low` stays a robot's typo.
                    let robot_form = ordered(jt)
                        .iter()
                        .any(|(_, jv)| matches!(jv.get_ref(), DeValue::Array(_)));
                    if ordered(jt).is_empty() {
                        self.err(
                            Code::E0002,
                            span_of(value),
                            "`joints` is empty".into(),
                            Some(
                                "a robot's: `{ low = [..], high = [..] }`; an item's: `{ rotor = \"0.1 rad\" }`"
                                    .into(),
                            ),
                        );
                        continue;
                    }
                    if !robot_form {
                        let mut joints = Vec::new();
                        for (jk, jv) in self.settings(jt) {
                            // `joints_rad = { rotor = 0.1 }`: the outer key's unit covers a
                            // value whose own key names none (`rotor_deg = 5` keeps its own).
                            let key = jk.get_ref().as_ref();
                            let unit_key =
                                if split_unit(key).1.is_none() && split_unit(k).1.is_some() {
                                    k
                                } else {
                                    key
                                };
                            if let Some(q) = self.quantity(unit_key, jv, Dimension::Angle) {
                                let role = split_unit(key).0.to_string();
                                joints.push((Spanned::new(role, span_of(jk)), q));
                            }
                        }
                        if !joints.is_empty() {
                            r.items.push(RandomItem::LabwareJoints {
                                joints,
                                span: span_of(value),
                            });
                        }
                        continue;
                    }
                    let (mut low, mut high) = (None, None);
                    for (jk, jv) in ordered(jt) {
                        match jk.get_ref().as_ref() {
                            "low" => low = self.quantity_array(k, jv, Dimension::Angle, None),
                            "high" => high = self.quantity_array(k, jv, Dimension::Angle, None),
                            _ => self.unknown_key(jk, &["low", "high"], "`joints`"),
                        }
                    }
                    match (low, high) {
                        (Some(low), Some(high)) => {
                            if low.value.len() != high.value.len() {
                                self.err(
                                    Code::E0021,
                                    span_of(value),
                                    "`low` and `high` have different lengths".into(),
                                    None,
                                );
                            } else if let Some(i) =
                                low.value.iter().zip(&high.value).position(|(l, h)| l > h)
                            {
                                self.err(
                                    Code::E0021,
                                    span_of(value),
                                    format!("joint {i}: `low` exceeds `high`"),
                                    None,
                                );
                            } else {
                                r.items.push(RandomItem::Joints {
                                    low,
                                    high,
                                    span: span_of(value),
                                });
                            }
                        }
                        (l, h)
                            if l.is_none()
                                && h.is_none()
                                && self.diags.iter().any(|d| {
                                    d.span.start >= span_of(value).start
                                        && d.span.end <= span_of(value).end
                                }) => {}
                        _ => self.err(
                            Code::E0002,
                            span_of(value),
                            "`joints` needs both `low` and `high`".into(),
                            None,
                        ),
                    }
                }
                "xy" => {
                    if let Some(q) = self.quantity(k, value, Dimension::Length) {
                        r.items.push(RandomItem::Xy(q))
                    }
                }
                "yaw" => {
                    if let Some(q) = self.quantity(k, value, Dimension::Angle) {
                        r.items.push(RandomItem::Yaw(q))
                    }
                }
                "parts_radius" => {
                    if let Some(q) = self.quantity(k, value, Dimension::Length) {
                        r.items.push(RandomItem::PartsRadius(q))
                    }
                }
                _ => self.unknown_key(key, RANDOM_KEYS, "a randomisation"),
            }
        }
        r
    }

    /// The tables of an array of tables (`[[key]]`), each with its span; reports anything else.
    fn array_of_tables<'a, 'i>(
        &mut self,
        v: &'a Value<'i>,
        key: &str,
    ) -> Vec<(&'a DeTable<'i>, Span)> {
        let DeValue::Array(items) = v.get_ref() else {
            let msg = format!(
                "`{key}` must be an array of tables (`[[{key}]]`), found {}",
                type_name(v.get_ref())
            );
            self.err(Code::E0004, span_of(v), msg, None);
            return Vec::new();
        };
        items
            .iter()
            .filter_map(|item| {
                let t = self.table(item, &format!("each `[[{key}]]` entry"))?;
                Some((t, span_of(item)))
            })
            .collect()
    }

    fn steps(&mut self, v: &Value<'_>) -> Vec<Step> {
        let mut out = Vec::new();
        for (t, span) in self.array_of_tables(v, "steps") {
            let mut s = Step {
                primitive: None,
                with: None,
                together: None,
                args: Vec::new(),
                span,
                repeat: None,
                for_each: Vec::new(),
                body: Vec::new(),
                id: None,
                within: None,
                after: None,
            };
            for (key, value) in self.settings(t) {
                let k = key.get_ref().as_ref();
                match k {
                    "do" => s.primitive = self.string(value, "do"),
                    "repeat" => s.repeat = self.integer(value, "repeat"),
                    "for_each" => s.for_each = self.for_each(value),
                    "body" => s.body = self.steps(value),
                    "id" => s.id = self.string(value, "id"),
                    "within" => s.within = self.string(value, "within"),
                    "after" => s.after = self.string(value, "after"),
                    "with" => s.with = self.string(value, "with"),
                    "together" => {
                        s.together = self
                            .boolean(value, "together")
                            .map(|b| Spanned::new(b, span_of(value)))
                    }
                    // Arguments are checked against the primitive's signature by the compiler.
                    _ => {
                        if let Some(v) = self.scalar(value, k) {
                            s.args.push((Spanned::new(k.to_string(), span_of(key)), v));
                        }
                    }
                }
            }
            if s.is_loop() {
                self.check_loop(&s);
            } else if s.primitive.is_none() {
                // A key another tool names the action with (`action = "close_lid"`) is named at
                // its place, with the key this language uses.
                let mut hint = "e.g. do = \"close_lid\"".to_string();
                for (k, v) in &s.args {
                    if DO_SYNONYMS.contains(&k.value.as_str()) {
                        let value = v.value.text();
                        self.err(
                            Code::E0003,
                            k.span,
                            format!("unknown key `{}` in a step", k.value),
                            Some(format!("did you mean `do`? write do = \"{value}\"")),
                        );
                        hint = format!("the step's action is its `do`: do = \"{value}\"");
                    }
                }
                self.err(Code::E0002, s.span, "step has no `do`".into(), Some(hint));
            }
            out.push(s);
        }
        out
    }

    /// `for_each = { var = [..], other = [..] }` or `{ var = "<holder>.slots" }`.
    fn for_each(&mut self, v: &Value<'_>) -> Vec<(Spanned<String>, Spanned<LoopValues>)> {
        let Some(t) = self.table(v, "`for_each`") else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (key, value) in self.settings(t) {
            let name = Spanned::new(key.get_ref().to_string(), span_of(key));
            let values = match value.get_ref() {
                DeValue::String(s) => match s.strip_suffix(".slots") {
                    Some(holder) if !holder.is_empty() && !holder.contains('.') => {
                        LoopValues::Slots(holder.to_string())
                    }
                    _ => {
                        self.err(
                            Code::E0004,
                            span_of(value),
                            format!("`for_each.{}` must be a list of values or `\"<holder>.slots\"`, found `\"{s}\"`", name.value),
                            Some(format!("e.g. {} = [\"a\", \"b\"] or {} = \"rack.slots\"", name.value, name.value)),
                        );
                        continue;
                    }
                },
                _ => LoopValues::List(self.scalars(value, &format!("for_each.{}", name.value))),
            };
            out.push((name, Spanned::new(values, span_of(value))));
        }
        out
    }

    /// A loop step: a body, a count of at least one or a `for_each` (not both), no `do`, `with`
    /// or arguments of its own (they belong in its body's steps).
    fn check_loop(&mut self, s: &Step) {
        for key in [&s.id, &s.within, &s.after].into_iter().flatten() {
            self.err(
                Code::E0003,
                key.span,
                "a loop step has no outcome of its own to name or time".into(),
                Some("put `id`, `within` and `after` on a step of its body".into()),
            );
        }
        if s.body.is_empty() {
            self.err(
                Code::E0002,
                s.span,
                "a loop step has no `[[steps.body]]`".into(),
                Some("put the steps it repeats under `[[steps.body]]` after it".into()),
            );
        }
        match (&s.repeat, s.for_each.is_empty()) {
            (Some(r), false) => self.err(
                Code::E0021,
                r.span,
                "a loop step has both `repeat` and `for_each`".into(),
                Some("nest one loop in the other's body".into()),
            ),
            (Some(r), true) if r.value < 1 || r.value > 1000 => self.err(
                Code::E0021,
                r.span,
                format!("`repeat = {}` is outside 1..1000", r.value),
                None,
            ),
            (None, true) => self.err(
                Code::E0002,
                s.span,
                "a step with a `body` needs `repeat` or `for_each`".into(),
                Some("e.g. repeat = 3, or for_each = { tube = [\"a\", \"b\"] }".into()),
            ),
            _ => {}
        }
        let own = s
            .primitive
            .as_ref()
            .map(|p| p.span)
            .or(s.with.as_ref().map(|w| w.span))
            .or(s.args.first().map(|(k, _)| k.span));
        if let Some(span) = own {
            self.err(
                Code::E0003,
                span,
                "a loop step takes no `do`, `with` or arguments of its own".into(),
                Some("move them into the steps of its `[[steps.body]]`".into()),
            );
        }
    }

    /// A string, integer, float or boolean, kept as written.
    fn scalar(&mut self, v: &Value<'_>, what: &str) -> Option<Spanned<Scalar>> {
        let span = span_of(v);
        let value = match v.get_ref() {
            DeValue::String(s) => Scalar::Str(s.to_string()),
            DeValue::Boolean(b) => Scalar::Bool(*b),
            DeValue::Integer(_) => Scalar::Int(self.integer(v, what)?.value),
            DeValue::Float(_) => Scalar::Float(self.number(v, what)?),
            other => {
                let msg = format!(
                    "`{what}` must be a string, number or boolean, found {}",
                    type_name(other)
                );
                self.err(Code::E0004, span, msg, None);
                return None;
            }
        };
        Some(Spanned::new(value, span))
    }

    fn scalars(&mut self, v: &Value<'_>, what: &str) -> Vec<Spanned<Scalar>> {
        match v.get_ref() {
            DeValue::Array(items) => items.iter().filter_map(|i| self.scalar(i, what)).collect(),
            other => {
                let msg = format!("`{what}` must be an array, found {}", type_name(other));
                self.err(Code::E0004, span_of(v), msg, None);
                Vec::new()
            }
        }
    }

    fn boolean(&mut self, v: &Value<'_>, what: &str) -> Option<bool> {
        match v.get_ref() {
            DeValue::Boolean(b) => Some(*b),
            other => {
                let msg = format!("`{what}` must be a boolean, found {}", type_name(other));
                self.err(Code::E0004, span_of(v), msg, None);
                None
            }
        }
    }

    // Long on purpose: one arm per domain form a `[params.x]` table may take (choice, int, real,
    // slot, opposite), each reporting its own mistakes at their spans, in the order they are read.
    fn param(&mut self, name: Spanned<String>, t: &DeTable<'_>) -> Param {
        let mut domains: Vec<(Span, ParamDomain)> = Vec::new();
        let mut exclude = Vec::new();
        let (mut step, mut free, mut opposite) = (None, None, None);
        let mut tubes = None;
        let mut opposite_key: Option<(&str, Span)> = None;
        let mut extras: Vec<(&str, Span)> = Vec::new();
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match k {
                "choice" => {
                    let items = self.scalars(value, "choice");
                    if items.is_empty() && matches!(value.get_ref(), DeValue::Array(_)) {
                        self.err(
                            Code::E0022,
                            span_of(value),
                            format!("`{}` has an empty `choice`", name.value),
                            Some("list at least one value".into()),
                        );
                    }
                    domains.push((span_of(key), ParamDomain::Choice(items)));
                }
                "int" => {
                    let bounds = self.scalars(value, "int");
                    let ints: Vec<Spanned<i64>> = bounds
                        .into_iter()
                        .filter_map(|b| match b.value {
                            Scalar::Int(i) => Some(Spanned::new(i, b.span)),
                            _ => {
                                self.err(
                                    Code::E0004,
                                    b.span,
                                    "`int` bounds must be integers".into(),
                                    None,
                                );
                                None
                            }
                        })
                        .collect();
                    if let [low, high] = &ints[..] {
                        domains.push((
                            span_of(key),
                            ParamDomain::Int {
                                low: low.clone(),
                                high: high.clone(),
                                step: None,
                            },
                        ));
                    } else if matches!(value.get_ref(), DeValue::Array(a) if a.len() != 2) {
                        self.err(
                            Code::E0004,
                            span_of(value),
                            "`int` must be `[low, high]`".into(),
                            Some("e.g. int = [1, 5] (both ends included)".into()),
                        );
                    }
                }
                "real" => {
                    let bounds = self.scalars(value, "real");
                    let strs: Vec<Spanned<String>> = bounds
                        .into_iter()
                        .filter_map(|b| match b.value {
                            Scalar::Str(s) => Some(Spanned::new(s, b.span)),
                            _ => {
                                self.err(
                                    Code::E0020,
                                    b.span,
                                    "`real` bounds are quantities with units".into(),
                                    Some("e.g. real = [\"10 mm\", \"20 mm\"]".into()),
                                );
                                None
                            }
                        })
                        .collect();
                    if let [low, high] = &strs[..] {
                        domains.push((
                            span_of(key),
                            ParamDomain::Real {
                                low: low.clone(),
                                high: high.clone(),
                            },
                        ));
                    } else if matches!(value.get_ref(), DeValue::Array(a) if a.len() != 2) {
                        self.err(
                            Code::E0004,
                            span_of(value),
                            "`real` must be `[low, high]`".into(),
                            None,
                        );
                    }
                }
                "slot" => {
                    if let Some(of) = self.string(value, "slot") {
                        domains.push((
                            span_of(key),
                            ParamDomain::Slot {
                                of,
                                free: false,
                                opposite: None,
                                tubes: None,
                            },
                        ));
                    }
                }
                "step" => {
                    step = self.integer(value, "step");
                    extras.push(("step", span_of(key)));
                }
                "free" => {
                    free = self.boolean(value, "free");
                    extras.push(("free", span_of(key)));
                }
                "opposite" | "balances" => {
                    let k = if k == "opposite" {
                        "opposite"
                    } else {
                        "balances"
                    };
                    if let Some((first, _)) = opposite_key {
                        self.err(
                            Code::E0007,
                            span_of(key),
                            format!("`{k}` given beside `{first}`: they are one setting"),
                            Some("keep one: `balances` reads better with `tubes`".into()),
                        );
                    }
                    opposite_key = Some((k, span_of(key)));
                    opposite = self.string(value, k);
                    extras.push(("opposite", span_of(key)));
                }
                "tubes" => {
                    tubes = self.integer(value, "tubes");
                    extras.push(("tubes", span_of(key)));
                }
                "exclude" => exclude = self.scalars(value, "exclude"),
                _ => self.unknown_key(key, PARAM_KEYS, "a parameter"),
            }
        }
        if domains.len() > 1 {
            self.err(
                Code::E0022,
                domains[1].0,
                format!("parameter `{}` has more than one domain", name.value),
                Some("use exactly one of `choice`, `int`, `real`, `slot`".into()),
            );
        }
        let mut domain = domains.into_iter().next().map(|(_, d)| d);
        match &mut domain {
            Some(ParamDomain::Int { step: s, .. }) => *s = step.clone(),
            Some(ParamDomain::Slot {
                free: f,
                opposite: o,
                tubes: t,
                ..
            }) => {
                *f = free.unwrap_or(false);
                *o = opposite.clone();
                *t = tubes.clone();
            }
            _ => {}
        }
        if let (Some(t), None) = (&tubes, &opposite) {
            self.err(
                Code::E0002,
                t.span,
                "`tubes` is the size of the load `balances` completes, and there is no `balances`"
                    .into(),
                Some("add `balances = \"<an earlier slot parameter of the rotor>\"`".into()),
            );
        }
        for (extra, span) in extras {
            let fits = matches!(
                (&domain, extra),
                (Some(ParamDomain::Int { .. }), "step")
                    | (
                        Some(ParamDomain::Slot { .. }),
                        "free" | "opposite" | "tubes"
                    )
            );
            if !fits && domain.is_some() {
                let needs = if extra == "step" { "int" } else { "slot" };
                self.err(
                    Code::E0003,
                    span,
                    format!("`{extra}` applies only to `{needs}` parameters"),
                    None,
                );
            }
        }
        if domain.is_none() && !self.diags.iter().any(|d| d.span.start >= name.span.start) {
            self.err(
                Code::E0002,
                name.span,
                format!("parameter `{}` has no domain", name.value),
                Some("add one of `choice = [..]`, `int = [low, high]`, `real = [\"..\", \"..\"]`, `slot = \"<holder>\"`".into()),
            );
        }
        Param {
            span: name.span,
            name,
            domain,
            exclude,
        }
    }

    fn tolerances(&mut self, v: &Value<'_>) -> Vec<(Spanned<String>, Spanned<String>)> {
        let mut out = Vec::new();
        let Some(t) = self.table(v, "`[tolerances]`") else {
            return out;
        };
        for (key, value) in ordered(t) {
            let name = Spanned::new(key.get_ref().to_string(), span_of(key));
            match value.get_ref() {
                DeValue::String(s) => out.push((name, Spanned::new(s.to_string(), span_of(value)))),
                DeValue::Integer(_) | DeValue::Float(_) => self.err(
                    Code::E0020,
                    span_of(value),
                    format!("tolerance `{}` has no unit", name.value),
                    Some("write it with a unit, e.g. \"5 mm\" or \"0.02 rad\"".into()),
                ),
                other => {
                    let msg = format!(
                        "tolerance `{}` must be a quantity, found {}",
                        name.value,
                        type_name(other)
                    );
                    self.err(Code::E0004, span_of(value), msg, None);
                }
            }
        }
        out
    }

    fn chain(&mut self, doc: &DeTable<'_>) -> Chain {
        let mut c = Chain::default();
        for (key, value) in ordered(doc) {
            match key.get_ref().as_ref() {
                "format" => c.format = self.integer(value, "format"),
                "chain" => c.meta = self.chain_meta(value),
                "stages" => c.stages = self.stages(value),
                _ => self.unknown_key(key, CHAIN_TOP_KEYS, "a chain file"),
            }
        }
        self.check_format(c.format.as_ref());
        if c.stages.is_empty() && !self.diags.iter().any(|d| d.code == Code::E0004) {
            self.err(
                Code::E0002,
                c.meta.span,
                "the chain has no `[[stages]]`".into(),
                Some("add `[[stages]]` with `protocol = \"<file>.toml\"` for each stage".into()),
            );
        }
        c
    }

    fn chain_meta(&mut self, v: &Value<'_>) -> Meta {
        let mut m = Meta {
            span: span_of(v),
            ..Meta::default()
        };
        let Some(t) = self.table(v, "`[chain]`") else {
            return m;
        };
        for (key, value) in self.settings(t) {
            match key.get_ref().as_ref() {
                "id" => m.id = self.id(value, "chain.id"),
                "version" => m.version = self.integer(value, "chain.version"),
                "level" => m.level = self.level(value),
                "instruction" => m.instruction = self.prompt(value, "chain.instruction"),
                _ => self.unknown_key(key, CHAIN_KEYS, "`[chain]`"),
            }
        }
        if m.id.is_none() && !t.iter().any(|(k, _)| k.get_ref() == "id") {
            self.err(Code::E0002, m.span, "`[chain]` has no `id`".into(), None);
        }
        m
    }

    fn stages(&mut self, v: &Value<'_>) -> Vec<StageRef> {
        let mut out = Vec::new();
        for (t, span) in self.array_of_tables(v, "stages") {
            let mut s = StageRef {
                protocol: None,
                instruction: None,
                time_limit: None,
                span,
            };
            for (key, value) in self.settings(t) {
                let k = key.get_ref().as_ref();
                match split_unit(k).0 {
                    "protocol" => s.protocol = self.string(value, "protocol"),
                    "instruction" => s.instruction = self.prompt(value, "instruction"),
                    "time_limit" => s.time_limit = self.time_limit(k, value),
                    _ => self.unknown_key(key, STAGE_KEYS, "a stage"),
                }
            }
            if s.protocol.is_none() {
                self.err(
                    Code::E0002,
                    s.span,
                    "stage has no `protocol`".into(),
                    Some("e.g. protocol = \"open_lid.toml\" (relative to this file)".into()),
                );
            }
            out.push(s);
        }
        out
    }

    /// A robot, labware or parameter name: an identifier, because names are read back out of
    /// predicates (`<name>.<part>`), templates (`{name}`), locations and recording topics.
    fn name(&mut self, name: &Spanned<String>) {
        let n = &name.value;
        let ok = n.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
            && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && n.len() <= MAX_ID_LEN;
        if !ok {
            self.err(
                Code::E0021,
                name.span,
                format!(
                    "name `{}` is not an identifier (letters, digits and `_`, not starting with a digit)",
                    n.escape_default()
                ),
                Some("names are read back from predicates (`<name>.<part>`) and templates (`{name}`)".into()),
            );
        }
    }

    /// Text a policy is shown (an instruction): not empty or blank.
    fn prompt(&mut self, value: &Value<'_>, what: &str) -> Option<Spanned<String>> {
        let s = self.string(value, what)?;
        if s.value.trim().is_empty() {
            self.err(
                Code::E0021,
                s.span,
                format!("`{what}` is empty"),
                Some("the instruction is the prompt the policy is given; say what to do".into()),
            );
            return None;
        }
        Some(s)
    }

    /// A task id: it names the task in results, recordings and file names, so it is a non-empty
    /// word of letters, digits, `.`, `_` and `-` that starts with a letter or digit.
    fn id(&mut self, value: &Value<'_>, what: &str) -> Option<Spanned<String>> {
        let id = self.string(value, what)?;
        let hint =
            "an id names the task in results and file names, e.g. \"thermal_cycler.close_lid\"";
        let bad = id
            .value
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')));
        let problem = if id.value.is_empty() {
            Some(format!("`{what}` is empty"))
        } else if let Some(c) = bad {
            Some(format!(
                "`{what}` may hold only letters, digits, `.`, `_` and `-`, found `{}`",
                c.escape_default()
            ))
        } else if !id.value.starts_with(|c: char| c.is_ascii_alphanumeric()) {
            Some(format!("`{what}` must start with a letter or a digit"))
        } else if id.value.len() > MAX_ID_LEN {
            Some(format!("`{what}` is longer than {MAX_ID_LEN} characters"))
        } else {
            None
        };
        match problem {
            Some(msg) => {
                self.err(Code::E0021, id.span, msg, Some(hint.into()));
                None
            }
            None => Some(id),
        }
    }

    fn level(&mut self, value: &Value<'_>) -> Option<Spanned<String>> {
        let level = self.string(value, "level")?;
        if !LEVELS.contains(&level.value.as_str()) {
            let hint = did_you_mean(&level.value, LEVELS.iter().copied())
                .map(|s| format!("did you mean `{s}`?"));
            self.err(
                Code::E0021,
                level.span,
                format!("unknown level `{}`", level.value),
                hint.or(Some("levels: easy, medium, hard".into())),
            );
        }
        Some(level)
    }

    fn time_limit(&mut self, key: &str, value: &Value<'_>) -> Option<Spanned<f64>> {
        let tl = self.quantity(key, value, Dimension::Time)?;
        if tl.value <= 0.0 {
            self.err(
                Code::E0021,
                tl.span,
                "`time_limit` must be positive".into(),
                None,
            );
        }
        Some(tl)
    }

    fn check_format(&mut self, format: Option<&Spanned<i64>>) {
        if let Some(f) = format
            && f.value != crate::FORMAT_VERSION
        {
            let msg = format!("unsupported format `{}`", f.value);
            self.err(
                Code::E0005,
                f.span,
                msg,
                Some(format!(
                    "this autobio reads format = {}",
                    crate::FORMAT_VERSION
                )),
            );
        }
    }

    fn success(&mut self, v: &Value<'_>) -> Success {
        let mut out = Success {
            span: span_of(v),
            ..Success::default()
        };
        let Some(t) = self.table(v, "`[success]`") else {
            return out;
        };
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "settle" => {
                    out.settle = self.quantity(k, value, Dimension::Time);
                    if let Some(s) = &out.settle
                        && !(0.0..=60.0).contains(&s.value)
                    {
                        self.err(
                            Code::E0021,
                            s.span,
                            format!("`settle` of {} s: it must be between 0 and 60 s", s.value),
                            Some("how long the checks must go on holding: \"0.5 s\"".into()),
                        );
                    }
                }
                "all" => match value.get_ref() {
                    DeValue::Array(items) => {
                        for item in items.iter() {
                            if let Some(s) = self.string(item, "success.all") {
                                out.all.push(s);
                            }
                        }
                    }
                    other => {
                        let msg = format!(
                            "`success.all` must be an array of predicates, found {}",
                            type_name(other)
                        );
                        self.err(Code::E0004, span_of(value), msg, None);
                    }
                },
                "scoring" => {
                    out.scoring = self.string(value, "scoring");
                    if let Some(sc) = &out.scoring
                        && !SCORINGS.contains(&sc.value.as_str())
                    {
                        let hint = did_you_mean(&sc.value, SCORINGS.iter().copied())
                            .map(|s| format!("did you mean `{s}`?"))
                            .unwrap_or_else(|| "scoring is `binary` or `progress`".into());
                        self.err(
                            Code::E0021,
                            sc.span,
                            format!("unknown scoring `{}`", sc.value),
                            Some(hint),
                        );
                    }
                }
                "weights" => {
                    let items = self.scalars(value, "weights");
                    let mut ws = Vec::new();
                    for w in &items {
                        match w.value {
                            Scalar::Int(i) if i >= 0 => ws.push(i as f64),
                            Scalar::Float(f) if f >= 0.0 => ws.push(f),
                            _ => self.err(
                                Code::E0021,
                                w.span,
                                "a weight must be a non-negative number".into(),
                                None,
                            ),
                        }
                    }
                    if ws.len() == items.len() {
                        out.weights = Some(Spanned::new(ws, span_of(value)));
                    }
                }
                _ => self.unknown_key(key, SUCCESS_KEYS, "`[success]`"),
            }
        }
        if out.all.is_empty()
            && !self
                .diags
                .iter()
                .any(|d| d.span.start >= span_of(v).start && d.span.end <= span_of(v).end)
        {
            self.err(
                Code::E0002,
                span_of(v),
                "`[success]` lists no predicates".into(),
                Some("add `all = [\"cycler.lid is closed\"]`".into()),
            );
        }
        out
    }
}

fn example(dim: Dimension) -> &'static str {
    match dim {
        Dimension::Length => "10 mm",
        Dimension::Angle => "5 deg",
        Dimension::Time => "30 s",
        Dimension::Volume => "200 µL",
        Dimension::Temperature => "37 °C",
        Dimension::Speed => "1200 rpm",
        Dimension::Acceleration => "16000 x g",
    }
}

fn unit_of(dim: Dimension) -> &'static str {
    match dim {
        Dimension::Length => "m",
        Dimension::Angle => "deg",
        Dimension::Time => "s",
        Dimension::Volume => "ul",
        Dimension::Temperature => "degc",
        Dimension::Speed => "rpm",
        Dimension::Acceleration => "xg",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
format = 1
[protocol]
id = "t"
instruction = "close it"
time_limit = "30 s"
[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [0.0, 0.5, 0.824] }
[labware.cycler]
kind = "thermal_cycler"
pose = { pos_m = [-0.05, 0.0, 0.824], yaw_deg = 0 }
state = { lid = "open" }
[randomise.arm]
joints_rad = { low = [-1.0, 0], high = [0.0, 0.1] }
[[steps]]
do = "close_lid"
on = "cycler"
with = "arm"
[success]
all = ["cycler.lid is closed"]
"#;

    #[test]
    fn parses_a_good_protocol() {
        let (doc, d) = parse(GOOD);
        assert!(d.is_empty(), "{d:?}");
        let Document::Protocol(p) = doc else {
            panic!("a protocol")
        };
        assert_eq!(p.meta.time_limit.unwrap().value, 30.0);
        assert_eq!(
            p.labware[0].pose.pos.as_ref().unwrap().value,
            [-0.05, 0.0, 0.824]
        );
        assert_eq!(p.steps[0].primitive.as_ref().unwrap().value, "close_lid");
        assert_eq!(
            p.steps[0].arg("on").unwrap().value,
            Scalar::Str("cycler".into())
        );
        assert_eq!(p.success.all.len(), 1);
    }

    #[test]
    fn unit_errors_point_at_the_value() {
        let src = GOOD.replace("\"30 s\"", "\"30 deg\"");
        let (_, d) = parse(&src);
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].code, Code::E0020);
        assert_eq!(&src[d[0].span.start..d[0].span.end], "\"30 deg\"");
    }

    #[test]
    fn garbage_is_refused_with_an_error_inside_the_text() {
        for src in [
            "",
            "[[[",
            "a = ",
            "\u{0}",
            "steps = 3",
            "[protocol]\nid = 3",
            "[randomise.x]\njoints = 1",
        ] {
            let (_, d) = parse(src);
            assert!(
                d.iter().any(|d| d.is_error()),
                "{src:?} parsed clean: {d:?}"
            );
            assert!(
                d.iter().all(|d| d.span.end <= src.len()),
                "{src:?}: a span past the text: {d:?}"
            );
        }
    }
}
