//! TOML text to [`Protocol`]: walks toml's spanned document tree, checking the shape (tables, keys,
//! types, units) and collecting every problem instead of stopping at the first.

use crate::ast::*;
use crate::quantity::{Dimension, parse_quantity, unit};
use crate::{Code, Diagnostic, Span, did_you_mean};
use toml::de::{DeTable, DeValue};

type Value<'i> = toml::Spanned<DeValue<'i>>;

/// Parses a protocol. Never fails and never panics: the AST holds whatever could be read, and the
/// diagnostics say what could not.
pub fn parse(source: &str) -> (Protocol, Vec<Diagnostic>) {
    let mut p = Parser { diags: Vec::new() };
    let (doc, errors) = DeTable::parse_recoverable(source);
    if !errors.is_empty() {
        for e in errors {
            let mut span = e.span().map(Span::from).unwrap_or(Span::new(0, 0));
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
        return (Protocol::default(), p.diags);
    }
    let protocol = p.protocol(doc.get_ref());
    (protocol, p.diags)
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
}

const TOP_KEYS: &[&str] = &[
    "format",
    "protocol",
    "robots",
    "labware",
    "randomise",
    "steps",
    "success",
];
const PROTOCOL_KEYS: &[&str] = &["id", "version", "level", "instruction", "time_limit"];
const ROBOT_KEYS: &[&str] = &["model", "base"];
const LABWARE_KEYS: &[&str] = &["kind", "pose", "state"];
const POSE_KEYS: &[&str] = &["pos", "yaw"];
const RANDOM_KEYS: &[&str] = &["joints", "xy", "yaw"];
const STEP_KEYS: &[&str] = &["do", "on", "with"];
const SUCCESS_KEYS: &[&str] = &["all"];
const LEVELS: &[&str] = &["easy", "medium", "hard"];

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
    fn err(&mut self, code: Code, span: Span, msg: String, hint: Option<String>) {
        let mut d = Diagnostic::error(code, span, msg);
        d.hint = hint;
        self.diags.push(d);
    }

    fn unknown_key(
        &mut self,
        key: &toml::Spanned<std::borrow::Cow<'_, str>>,
        allowed: &[&str],
        table: &str,
    ) {
        let (base, _) = split_unit(key.get_ref());
        let hint = did_you_mean(base, allowed.iter().copied())
            .map(|s| format!("did you mean `{s}`?"))
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
                    self.err(Code::E0020, span, e, Some(hint));
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
        for (key, value) in doc.iter() {
            match key.get_ref().as_ref() {
                "format" => p.format = self.integer(value, "format"),
                "protocol" => p.meta = self.meta(value),
                "robots" => {
                    p.robots = self.named_tables(value, "[robots]", |s, n, t| s.robot(n, t))
                }
                "labware" => {
                    p.labware = self.named_tables(value, "[labware]", |s, n, t| s.labware(n, t))
                }
                "randomise" => {
                    p.randomise =
                        self.named_tables(value, "[randomise]", |s, n, t| s.randomise(n, t))
                }
                "steps" => p.steps = self.steps(value),
                "success" => p.success = self.success(value),
                _ => self.unknown_key(key, TOP_KEYS, "the top level"),
            }
        }
        if let Some(f) = &p.format
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
        if p.success.is_empty() && !doc.iter().any(|(k, _)| k.get_ref() == "success") {
            self.err(
                Code::E0002,
                Span::new(0, 0),
                "missing table `[success]`".into(),
                Some("add `[success]` with `all = [\"<labware>.<part> is <state>\", ...]`".into()),
            );
        }
        p
    }

    fn meta(&mut self, v: &Value<'_>) -> Meta {
        let mut m = Meta {
            span: span_of(v),
            ..Meta::default()
        };
        let Some(t) = self.table(v, "`[protocol]`") else {
            return m;
        };
        for (key, value) in t.iter() {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "id" => m.id = self.string(value, "protocol.id"),
                "version" => m.version = self.integer(value, "protocol.version"),
                "level" => {
                    m.level = self.string(value, "protocol.level");
                    if let Some(l) = &m.level
                        && !LEVELS.contains(&l.value.as_str())
                    {
                        let hint = did_you_mean(&l.value, LEVELS.iter().copied())
                            .map(|s| format!("did you mean `{s}`?"));
                        self.err(
                            Code::E0021,
                            l.span,
                            format!("unknown level `{}`", l.value),
                            hint.or(Some("levels: easy, medium, hard".into())),
                        );
                    }
                }
                "instruction" => m.instruction = self.string(value, "protocol.instruction"),
                "time_limit" => {
                    m.time_limit = self.quantity(k, value, Dimension::Time);
                    if let Some(tl) = &m.time_limit
                        && tl.value <= 0.0
                    {
                        self.err(
                            Code::E0021,
                            tl.span,
                            "`time_limit` must be positive".into(),
                            None,
                        );
                    }
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
        for (key, value) in t.iter() {
            let name = Spanned::new(key.get_ref().to_string(), span_of(key));
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
        for (key, value) in t.iter() {
            match key.get_ref().as_ref() {
                "model" => r.model = self.string(value, "model"),
                "base" => r.base = self.pose(value),
                _ => self.unknown_key(key, ROBOT_KEYS, "a robot"),
            }
        }
        if r.model.is_none() {
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
            state: Vec::new(),
        };
        for (key, value) in t.iter() {
            match key.get_ref().as_ref() {
                "kind" => l.kind = self.string(value, "kind"),
                "pose" => l.pose = self.pose(value),
                "state" => {
                    if let Some(st) = self.table(value, "`state`") {
                        for (part, s) in st.iter() {
                            if let Some(s) = self.string(s, part.get_ref()) {
                                l.state.push((
                                    Spanned::new(part.get_ref().to_string(), span_of(part)),
                                    s,
                                ));
                            }
                        }
                    }
                }
                _ => self.unknown_key(key, LABWARE_KEYS, "a labware entry"),
            }
        }
        if l.kind.is_none() {
            self.err(
                Code::E0002,
                l.name.span,
                format!("labware `{}` has no `kind`", l.name.value),
                Some("e.g. kind = \"thermal_cycler\"".into()),
            );
        }
        l
    }

    fn pose(&mut self, v: &Value<'_>) -> Pose {
        let mut p = Pose::default();
        let Some(t) = self.table(v, "a pose") else {
            return p;
        };
        for (key, value) in t.iter() {
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

    fn randomise(&mut self, target: Spanned<String>, t: &DeTable<'_>) -> Randomisation {
        let mut r = Randomisation {
            target,
            items: Vec::new(),
        };
        for (key, value) in t.iter() {
            let k = key.get_ref().as_ref();
            match split_unit(k).0 {
                "joints" => {
                    let Some(jt) = self.table(value, "`joints`") else {
                        continue;
                    };
                    let (mut low, mut high) = (None, None);
                    for (jk, jv) in jt.iter() {
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
                _ => self.unknown_key(key, RANDOM_KEYS, "a randomisation"),
            }
        }
        r
    }

    fn steps(&mut self, v: &Value<'_>) -> Vec<Step> {
        let mut out = Vec::new();
        let DeValue::Array(items) = v.get_ref() else {
            let msg = format!(
                "`steps` must be an array of tables (`[[steps]]`), found {}",
                type_name(v.get_ref())
            );
            self.err(Code::E0004, span_of(v), msg, None);
            return out;
        };
        for item in items.iter() {
            let Some(t) = self.table(item, "each `[[steps]]` entry") else {
                continue;
            };
            let mut s = Step {
                primitive: None,
                on: None,
                with: None,
                span: span_of(item),
            };
            for (key, value) in t.iter() {
                match key.get_ref().as_ref() {
                    "do" => s.primitive = self.string(value, "do"),
                    "on" => s.on = self.string(value, "on"),
                    "with" => s.with = self.string(value, "with"),
                    _ => self.unknown_key(key, STEP_KEYS, "a step"),
                }
            }
            if s.primitive.is_none() {
                self.err(
                    Code::E0002,
                    s.span,
                    "step has no `do`".into(),
                    Some("e.g. do = \"close_lid\"".into()),
                );
            }
            out.push(s);
        }
        out
    }

    fn success(&mut self, v: &Value<'_>) -> Vec<Spanned<String>> {
        let mut out = Vec::new();
        let Some(t) = self.table(v, "`[success]`") else {
            return out;
        };
        for (key, value) in t.iter() {
            match key.get_ref().as_ref() {
                "all" => match value.get_ref() {
                    DeValue::Array(items) => {
                        for item in items.iter() {
                            if let Some(s) = self.string(item, "success.all") {
                                out.push(s);
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
                _ => self.unknown_key(key, SUCCESS_KEYS, "`[success]`"),
            }
        }
        if out.is_empty()
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
    }
}

fn unit_of(dim: Dimension) -> &'static str {
    match dim {
        Dimension::Length => "m",
        Dimension::Angle => "deg",
        Dimension::Time => "s",
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
        let (p, d) = parse(GOOD);
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(p.meta.time_limit.unwrap().value, 30.0);
        assert_eq!(
            p.labware[0].pose.pos.as_ref().unwrap().value,
            [-0.05, 0.0, 0.824]
        );
        assert_eq!(p.steps[0].primitive.as_ref().unwrap().value, "close_lid");
        assert_eq!(p.success.len(), 1);
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
    fn garbage_never_panics() {
        for src in [
            "",
            "[[[",
            "a = ",
            "\u{0}",
            "steps = 3",
            "[protocol]\nid = 3",
            "[randomise.x]\njoints = 1",
        ] {
            let _ = parse(src);
        }
    }
}
