//! Scene files: the robots, labware, randomisation and camera that several protocols stand in,
//! written once (`[scene]`) and named with `scene = "<file>"`, so that the stages of a chain (or
//! any family of tasks on one bench) share one scene instead of copying it. A scene file is read
//! like a chain's stage, under the same access rules (`stage_files`), and merged into the
//! protocol before it is checked: the scene's tables first, then the protocol's own additions; a
//! protocol's `[labware.<name>]` with only `state` or `at` for an item of the scene gives that
//! item's start in this protocol. The scene's spans are moved past the protocol's text and mapped
//! back to the scene file afterwards ([`Merged::remap`]), so every diagnostic points into the file
//! that says it. Not here: what a scene may contain (the parser), or any checking (`check`).

use crate::report::Cx;
use crate::stage_files::{StageError, StageLoader};
use dsl::ast::{Document, Protocol};
use dsl::{Code, Diagnostic};

/// A scene file merged into a protocol: where its spans went, and how to say where it came from.
pub(crate) struct Merged {
    /// The protocol's file as its diagnostics carry it (`None`: the file being checked).
    pub owner: Option<String>,
    pub offset: usize,
    pub path: String,
    /// `scene of <file>, named at <file>:<line>:<col>`, added to the scene's diagnostics.
    pub note: String,
}

impl Merged {
    /// Points the diagnostics that fell into the scene's tables back into the scene file.
    pub(crate) fn remap(&self, diags: &mut [Diagnostic]) {
        for d in diags {
            if d.file == self.owner && d.span.start >= self.offset {
                d.file = Some(self.path.clone());
                d.span.start -= self.offset;
                d.span.end -= self.offset;
                d.notes.push(self.note.clone());
            }
        }
    }
}

/// Reads the scene `p` names, relative to `file` (whose text, `source`, is what the protocol was
/// parsed from), and merges it into `p`. Problems with the scene are reported into `cx`: at the
/// `scene` key when the file cannot be read or is not a scene file, in the scene file for its
/// own. `None` when `p` names no scene or it could not be read.
pub(crate) fn merge(
    cx: &mut Cx,
    p: &mut Protocol,
    file: &str,
    source: &str,
    load: &dyn StageLoader,
) -> Option<Merged> {
    let named = p.scene.take()?;
    let owner = cx.file.clone();
    let loaded = match load.load(file, &named.value) {
        Ok(l) => l,
        Err(e) => {
            let hint = match e {
                StageError::OutsideRoot { .. } => {
                    "a scene file stays inside the protocol's folder; widen it with `--root DIR`"
                }
                StageError::NotUtf8 { .. } => "save the scene file as UTF-8",
                StageError::NotAFile { .. } | StageError::TooLarge { .. } => {
                    "a scene file is a regular file of at most 1 MiB"
                }
                StageError::Unreadable { .. } => "the path is relative to this protocol's file",
            };
            // The loader words its refusals for chain stages.
            let message = e
                .to_string()
                .replacen("stage `", "scene file `", 1)
                .replace("a stage file", "a scene file");
            cx.push(Diagnostic::new(e.code(), named.span, message).with_hint(hint));
            return None;
        }
    };
    let (doc, diags) = dsl::parse(&loaded.text);
    let (line, col) = dsl::render::line_col(source, named.span.start);
    let note = format!("scene of {file}, named at {file}:{line}:{col}");
    // A scene file's own diagnostics are shown in it, with where it was named.
    let report = |cx: &mut Cx, diags: Vec<Diagnostic>| {
        cx.file = Some(loaded.path.clone());
        for d in diags {
            cx.push(d.with_note(note.clone()));
        }
        cx.file = owner.clone();
    };
    let broken = diags.iter().any(|d| d.code == Code::E0001);
    let mut scene = match doc {
        Document::Scene(s) if !broken => s,
        // A scene file with a syntax error parses as nothing: its `[scene]` header says what it
        // was meant to be, and its errors are its own.
        _ if broken && has_scene_header(&loaded.text) => {
            report(cx, diags);
            return None;
        }
        _ => {
            // None of its text is shown: a protocol cannot be used to display another file.
            cx.push(
                Diagnostic::new(
                    Code::E0006,
                    named.span,
                    format!("`{}` is not a scene file", named.value),
                )
                .with_hint("a scene file has a `[scene]` table and only robots, labware, randomisation, a camera and perturbations"),
            );
            return None;
        }
    };
    report(cx, diags);
    let merged = Merged {
        owner,
        offset: source.len() + 1,
        path: loaded.path,
        note,
    };
    scene.shift_scene_spans(merged.offset);
    // The scene's robots and labware come first: a robot's place in the action vector is its
    // place in the scene.
    let own_robots = std::mem::take(&mut p.robots);
    p.robots = scene.robots;
    p.robots.extend(own_robots);
    let own_labware = std::mem::take(&mut p.labware);
    p.labware = scene.labware;
    for l in own_labware {
        let start_only = l.kind.is_none() && l.pose.pos.is_none() && l.pose.yaw.is_none();
        match p.labware.iter_mut().find(|x| x.name.value == l.name.value) {
            Some(x) if start_only => {
                for (k, v) in l.state {
                    x.state.retain(|(kx, _)| kx.value != k.value);
                    x.state.push((k, v));
                }
                if l.at.is_some() {
                    x.at = l.at;
                    x.held_by = None;
                }
                if l.held_by.is_some() {
                    x.held_by = l.held_by;
                    x.at = None;
                }
                for (k, pose) in l.parts {
                    x.parts.retain(|(kx, _)| kx.value != k.value);
                    x.parts.push((k, pose));
                }
            }
            None if l.kind.is_none() => cx.push(
                Diagnostic::new(
                    Code::E0002,
                    l.name.span,
                    format!(
                        "labware `{}` has no `kind`, and the scene file declares no `{}`",
                        l.name.value, l.name.value
                    ),
                )
                .with_hint(format!(
                    "the scene declares: {}; a new item needs its `kind` and `pose`",
                    p.labware
                        .iter()
                        .map(|x| x.name.value.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            ),
            // Anything else is the protocol's own item, or a second declaration of the scene's
            // (E0015, reported at both places by the checker).
            _ => p.labware.push(l),
        }
    }
    let own_randomise = std::mem::take(&mut p.randomise);
    p.randomise = scene.randomise;
    p.randomise.extend(own_randomise);
    match (&p.camera, scene.camera) {
        (Some(own), Some(_)) => cx.push(
            Diagnostic::new(
                Code::E0015,
                own.span,
                "the camera is placed twice: here and in the scene file",
            )
            .with_hint(
                "place it in one of them: the scene's camera serves every protocol that uses it",
            ),
        ),
        (None, Some(c)) => p.camera = Some(c),
        _ => {}
    }
    // The protocol's own setting of a dimension stands over the scene's.
    match (&mut p.perturb, scene.perturb) {
        (Some(own), Some(shared)) => {
            for d in shared.dimensions {
                if !own.dimensions.iter().any(|o| o.name.value == d.name.value) {
                    own.dimensions.push(d);
                }
            }
        }
        (None, Some(shared)) => p.perturb = Some(shared),
        _ => {}
    }
    Some(merged)
}

/// Whether `text` has a `[scene]` header line (a scene file, even one whose TOML is broken).
pub(crate) fn has_scene_header(text: &str) -> bool {
    has_header(text, "[scene]")
}

/// Whether `text` has the table header line `header` (`[scene]`), alone or before a comment.
pub(crate) fn has_header(text: &str, header: &str) -> bool {
    text.lines().any(|l| {
        l.trim()
            .strip_prefix(header)
            .is_some_and(|rest| rest.trim().is_empty() || rest.trim().starts_with('#'))
    })
}

/// One diagnostic per (code, place, message): stages that share a scene file each check it, and
/// its mistakes are said once, with every protocol that named it in the notes.
pub(crate) fn dedupe(diags: &mut Vec<Diagnostic>) {
    let mut out: Vec<Diagnostic> = Vec::with_capacity(diags.len());
    for d in diags.drain(..) {
        match out.iter_mut().find(|o| {
            (o.code, o.span, &o.file, &o.message) == (d.code, d.span, &d.file, &d.message)
        }) {
            Some(o) => {
                for n in d.notes {
                    if !o.notes.contains(&n) {
                        o.notes.push(n);
                    }
                }
            }
            None => out.push(d),
        }
    }
    *diags = out;
}
