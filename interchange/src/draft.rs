//! A protocol being written by an importer: robots, labware, steps and success as plain values,
//! and the protocol file they make (format 1). Each step may say which source command it came
//! from; the file carries that as a comment above the step, so a diagnostic `autobio check` gives
//! on the written file leads back to the command. Nothing here checks the protocol: the written
//! text is compiled and proven like any protocol file.

use std::fmt::Write as _;

/// A protocol to be written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Draft {
    /// Comment lines at the top of the file (what it was imported from).
    pub header: Vec<String>,
    pub id: String,
    pub level: &'static str,
    pub instruction: String,
    /// The source file's name, format and SHA-256 (`[protocol] imported_from`).
    pub imported_from: Option<(String, String, String)>,
    pub time_limit_s: f64,
    pub robots: Vec<Robot>,
    pub labware: Vec<Item>,
    pub steps: Vec<Step>,
    pub success: Vec<String>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    pub name: String,
    pub model: String,
    pub base: [f64; 3],
    /// The uniform offsets drawn per episode on the arm's joints (rad), low and high.
    pub joints_rad: Option<([f64; 6], [f64; 6])>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Item {
    pub name: String,
    pub kind: String,
    /// Where it stands: position (m) and yaw (degrees); none when `at` or `held_by` places it.
    pub pose: Option<([f64; 3], f64)>,
    pub at: Option<String>,
    pub held_by: Option<String>,
    /// Start states, in order (`cap = "off"`, `volume = "100 µL"`).
    pub state: Vec<(String, String)>,
    /// A comment above the table (what the item stands for in the source).
    pub comment: Option<String>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub primitive: String,
    /// The primitive's arguments, in order (`on`, `volume` ...).
    pub args: Vec<(String, String)>,
    pub with: String,
    /// The source command it realises (`commands[12] aspirate`).
    pub from: Option<String>,
}

impl Draft {
    /// The protocol file.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        for line in &self.header {
            let _ = writeln!(s, "# {}", comment(line));
        }
        let _ = writeln!(s, "format = 1\n\n[protocol]");
        let _ = writeln!(s, "id = {}", quoted(&self.id));
        let _ = writeln!(s, "level = {}", quoted(self.level));
        let _ = writeln!(s, "instruction = {}", quoted(&self.instruction));
        let _ = writeln!(s, "time_limit = \"{} s\"", number(self.time_limit_s));
        if let Some((file, format, sha256)) = &self.imported_from {
            let _ = writeln!(
                s,
                "imported_from = {{ file = {}, format = {}, sha256 = {} }}",
                quoted(file),
                quoted(format),
                quoted(sha256)
            );
        }
        for r in &self.robots {
            let _ = writeln!(
                s,
                "\n[robots.{}]\nmodel = {}\nbase = {{ pos_m = {} }}",
                r.name,
                quoted(&r.model),
                vector(&r.base)
            );
        }
        for l in &self.labware {
            s.push('\n');
            if let Some(c) = &l.comment {
                let _ = writeln!(s, "# {}", comment(c));
            }
            let _ = writeln!(s, "[labware.{}]\nkind = {}", l.name, quoted(&l.kind));
            if let Some((pos, yaw)) = &l.pose {
                if *yaw == 0.0 {
                    let _ = writeln!(s, "pose = {{ pos_m = {} }}", vector(pos));
                } else {
                    let _ = writeln!(
                        s,
                        "pose = {{ pos_m = {}, yaw_deg = {} }}",
                        vector(pos),
                        number(*yaw)
                    );
                }
            }
            if let Some(at) = &l.at {
                let _ = writeln!(s, "at = {}", quoted(at));
            }
            if let Some(robot) = &l.held_by {
                let _ = writeln!(s, "held_by = {}", quoted(robot));
            }
            if !l.state.is_empty() {
                let fields: Vec<String> = l
                    .state
                    .iter()
                    .map(|(k, v)| format!("{k} = {}", quoted(v)))
                    .collect();
                let _ = writeln!(s, "state = {{ {} }}", fields.join(", "));
            }
        }
        for r in &self.robots {
            if let Some((lo, hi)) = &r.joints_rad {
                let _ = writeln!(
                    s,
                    "\n[randomise.{}]\njoints_rad = {{ low = {}, high = {} }}",
                    r.name,
                    vector(lo),
                    vector(hi)
                );
            }
        }
        for step in &self.steps {
            s.push('\n');
            if let Some(from) = &step.from {
                let _ = writeln!(s, "# {}", comment(from));
            }
            let _ = writeln!(s, "[[steps]]\ndo = {}", quoted(&step.primitive));
            for (k, v) in &step.args {
                let _ = writeln!(s, "{k} = {}", quoted(v));
            }
            let _ = writeln!(s, "with = {}", quoted(&step.with));
        }
        let _ = writeln!(s, "\n[success]\nall = [");
        for p in &self.success {
            let _ = writeln!(s, "  {},", quoted(p));
        }
        s.push_str("]\n");
        s
    }
}

/// Text for one comment line: control characters (a line break among them) become spaces, so
/// nothing from a source file can end the comment and start a table.
pub fn comment(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// Whether a name can stand as a bare TOML key (`[robots.<name>]`).
pub fn bare_key(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// A TOML basic string.
pub fn quoted(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A number as the language reads it: no trailing zeros, at most six decimals.
pub fn number(x: f64) -> String {
    let text = format!("{x:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

fn vector(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| number(*x)).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_are_escaped_and_numbers_are_short() {
        assert_eq!(quoted("a \"b\" \\ c\n"), r#""a \"b\" \\ c\n""#);
        assert_eq!(quoted("bell\u{7}"), r#""bell\u0007""#);
        assert_eq!(number(25.0), "25");
        assert_eq!(number(0.83173), "0.83173");
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(1.0 / 3.0), "0.333333");
        assert_eq!(comment("OT-2\n[protocol]\r"), "OT-2 [protocol] ");
        assert!(bare_key("left_2") && !bare_key("a b") && !bare_key("x]\n[y"));
    }
}
