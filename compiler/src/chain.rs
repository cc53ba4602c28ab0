//! Chains: several protocols run in order on the first one's scene, compiled into one
//! long-horizon task with a stage per protocol. Later stages must declare the same robots and
//! labware where the first puts them (E0034); their own initial states, randomisation and camera
//! are ignored, because the proof carries the state over from the stage before and the scene is
//! drawn once (W0008 where they differ). Not here: the state proof itself (`proof`).

use crate::check::{self, Lowered};
use crate::params::ParamSpec;
use crate::physics;
use crate::proof::{self, ProofScene, ProofStage};
use crate::report::Cx;
use crate::scene_file::{self, Merged};
use crate::stage_files::{StageError, StageLoader};
use crate::task::*;
use dsl::ast::{Chain, Document, Protocol};
use dsl::{Code, Diagnostic, Span};

/// Compiles a chain; every diagnostic that points into a stage file carries a note naming the
/// chain line that included it.
pub(crate) fn compile_chain(
    c: &Chain,
    file: &str,
    source: &str,
    load: &dyn StageLoader,
) -> (Option<Task>, Vec<Diagnostic>) {
    let mut included: Vec<(String, String)> = Vec::new();
    let mut scenes: Vec<Merged> = Vec::new();
    let (task, mut diags) = compile_stages(c, file, source, load, &mut included, &mut scenes);
    for m in &scenes {
        m.remap(&mut diags);
    }
    if !scenes.is_empty() {
        scene_file::dedupe(&mut diags);
    }
    for d in &mut diags {
        if let Some(f) = &d.file
            && let Some((_, note)) = included.iter().find(|(p, _)| p == f)
        {
            d.notes.push(note.clone());
        }
    }
    (task, diags)
}

/// Why a chain's stage file is not a protocol file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
enum NotAProtocol {
    #[error("it is a scene file (protocols name it with `scene = \"..\"`)")]
    SceneFile,
    /// Broken TOML without a `[protocol]` or `[chain]` header line (1-based line and column).
    #[error("it is not valid TOML (line {line}, column {column})")]
    BadToml { line: usize, column: usize },
    #[error("it has no `[protocol]` table")]
    NoProtocolTable,
}

/// A stage's diagnostics are shown only if it is a protocol file: text from any other file is
/// never echoed. A protocol file is valid TOML with a `[protocol]` or `[chain]` table, or, when its
/// TOML is broken (a protocol with a typo), has a `[protocol]` or `[chain]` header line.
fn looks_like_protocol(text: &str) -> Result<(), NotAProtocol> {
    if scene_file::has_scene_header(text) {
        return Err(NotAProtocol::SceneFile);
    }
    let header =
        scene_file::has_header(text, "[protocol]") || scene_file::has_header(text, "[chain]");
    let (doc, errors) = toml::de::DeTable::parse_recoverable(text);
    if let Some(e) = errors.first() {
        if header {
            return Ok(());
        }
        let at = e.span().map(|s| s.start).unwrap_or(0);
        let (line, column) = dsl::render::line_col(text, at);
        return Err(NotAProtocol::BadToml { line, column });
    }
    let doc = doc.get_ref();
    let table = |name: &str| {
        doc.iter()
            .any(|(k, v)| k.get_ref() == name && matches!(v.get_ref(), toml::de::DeValue::Table(_)))
    };
    if table("protocol") || table("chain") {
        Ok(())
    } else {
        Err(NotAProtocol::NoProtocolTable)
    }
}

// Long on purpose: the stages are compiled, carried over and checked against the scene rule in one
// pass over them, whose state (the scene so far, each stage's end world) the steps share.
fn compile_stages(
    c: &Chain,
    file: &str,
    source: &str,
    load: &dyn StageLoader,
    included: &mut Vec<(String, String)>,
    scenes: &mut Vec<Merged>,
) -> (Option<Task>, Vec<Diagnostic>) {
    let mut cx = Cx::new(None);
    for stage in &c.stages {
        if let Some(t) = &stage.time_limit {
            check::time_limit_warning(&mut cx, t);
        }
    }
    // Parse every stage first: the lowered stages borrow their ASTs.
    let mut parsed: Vec<(usize, String, Protocol)> = Vec::new();
    let mut texts: std::collections::BTreeMap<String, String> = Default::default();
    for (i, stage) in c.stages.iter().enumerate() {
        let Some(proto) = &stage.protocol else {
            continue;
        };
        let loaded = match load.load(file, &proto.value) {
            Ok(s) => s,
            Err(e) => {
                refuse(&mut cx, proto, &e);
                continue;
            }
        };
        if let Err(why) = looks_like_protocol(&loaded.text) {
            cx.err(
                Code::E0006,
                proto.span,
                format!("stage `{}` is not a protocol file: {why}", proto.value),
                Some(format!(
                    "run `autobio check {}` on it to see its problems",
                    loaded.path
                )),
            );
            continue;
        }
        let path = loaded.path;
        if !included.iter().any(|(p, _)| *p == path) {
            let (line, col) = dsl::render::line_col(source, proto.span.start);
            let note = format!("in stage {}, included from {file}:{line}:{col}", i + 1);
            included.push((path.clone(), note));
        }
        let (doc, diags) = dsl::parse(&loaded.text);
        cx.file = Some(path.clone());
        for d in diags {
            cx.push(d);
        }
        let doc = match doc {
            Document::Protocol(mut p) => {
                scenes.extend(scene_file::merge(
                    &mut cx,
                    &mut p,
                    &path,
                    &loaded.text,
                    load,
                ));
                crate::loops::expand(&mut cx, &mut p);
                Document::Protocol(p)
            }
            other => other,
        };
        // A chain's perturbations are its runs' (`--perturb`, a suite): a stage's own are not
        // read.
        if let Document::Protocol(p) = &doc
            && let Some(t) = &p.perturb
        {
            cx.push(
                Diagnostic::new(
                    Code::W0008,
                    t.span,
                    "a chain stage's `[perturb]` is not read: the chain's episodes are perturbed by `--perturb` or a suite's presets",
                )
                .with_hint("remove the table, or perturb the chain with `--perturb` or a suite"),
            );
        }
        texts.insert(path.clone(), loaded.text);
        cx.file = None;
        match doc {
            Document::Protocol(p) => parsed.push((i, path, *p)),
            Document::Scene(_) => cx.err(
                Code::E0006,
                proto.span,
                format!("stage `{}` is a scene file, not a protocol", proto.value),
                Some("name the protocols that use it".into()),
            ),
            Document::Chain(_) => cx.err(
                Code::E0006,
                proto.span,
                format!("stage `{}` is itself a chain", proto.value),
                Some("list its protocols in this chain instead".into()),
            ),
        }
    }
    if cx.has_errors() {
        return (None, cx.diags);
    }
    let mut lowered: Vec<(usize, String, Lowered)> = Vec::new();
    for (i, path, p) in &parsed {
        cx.file = Some(path.clone());
        if let Some(low) = check::lower(&mut cx, p, path) {
            lowered.push((*i, path.clone(), low));
        }
    }
    cx.file = None;
    if cx.has_errors() || lowered.is_empty() || lowered.len() != c.stages.len() {
        return (None, cx.diags);
    }
    let first = &lowered[0].2;
    let mut params: Vec<ParamSpec> = first.params.clone();
    let mut param_places = first_places(&lowered[0].1, parsed_protocol(&parsed, &lowered[0].1));
    for (_, path, low) in &lowered[1..] {
        cx.file = Some(path.clone());
        let ast = parsed_protocol(&parsed, path);
        same_scene(&mut cx, first, low, ast);
        for p in &low.params {
            let declared = ast
                .params
                .iter()
                .find(|x| x.name.value == p.name)
                .map(|x| x.name.span)
                .unwrap_or_default();
            match params.iter().find(|x| x.name == p.name) {
                Some(x) if x != p => {
                    let earlier = match param_places.get(&p.name) {
                        Some((Some(f), span)) => {
                            let text = texts.get(f).map(String::as_str).unwrap_or_default();
                            let (line, col) = dsl::render::line_col(text, span.start);
                            format!("{f}:{line}:{col}")
                        }
                        _ => String::new(),
                    };
                    cx.push(
                        Diagnostic::new(
                            Code::E0034,
                            declared,
                            format!("parameter `{}` differs from the earlier stage's", p.name),
                        )
                        .with_note(format!("it is first declared at {earlier}"))
                        .with_hint("a chain draws each parameter once; declare it identically"),
                    )
                }
                Some(_) => {}
                None => {
                    params.push(p.clone());
                    param_places.insert(p.name.clone(), (Some(path.clone()), declared));
                }
            }
        }
    }
    cx.file = None;
    if cx.has_errors() {
        return (None, cx.diags);
    }
    let stages: Vec<ProofStage> = lowered
        .iter()
        .enumerate()
        .map(|(k, (_, path, low))| ProofStage {
            id: low.id.clone(),
            file: Some(path.clone()),
            steps: &low.steps,
            predicates: &low.predicates,
            declared: (k > 0).then(|| parsed_protocol(&parsed, path)),
            time_limit_s: c.stages[lowered[k].0]
                .time_limit
                .as_ref()
                .map_or(low.stage.time_limit_s, |t| t.value),
        })
        .collect();
    let scene = ProofScene {
        labware: &first.labware,
        kinds: &first.kinds,
        robots: first.robots.iter().map(|r| r.name.clone()).collect(),
        labware_spans: &first.labware_spans,
        file: Some(lowered[0].1.clone()),
        param_places,
    };
    proof::prove(&mut cx, &scene, &stages, &params);
    if cx.has_errors() {
        return (None, cx.diags);
    }
    let task = lower_chain(c, file, &lowered, params);
    (task, cx.diags)
}

/// Where the first stage declares its parameters.
fn first_places(
    path: &str,
    ast: &Protocol,
) -> std::collections::BTreeMap<String, (Option<String>, Span)> {
    ast.params
        .iter()
        .map(|x| (x.name.value.clone(), (Some(path.to_string()), x.name.span)))
        .collect()
}

/// A stage file the loader refused, reported at the chain's stage line.
fn refuse(cx: &mut Cx, proto: &dsl::ast::Spanned<String>, e: &StageError) {
    let hint = match e {
        StageError::OutsideRoot { .. } => {
            "stage paths stay inside the chain's folder; widen it with `--root DIR`"
        }
        StageError::NotAFile { .. } | StageError::TooLarge { .. } => {
            "a stage is a protocol file: a regular file of at most 1 MiB"
        }
        StageError::NotUtf8 { .. } => "save the stage file as UTF-8",
        StageError::Unreadable { .. } => "paths are relative to the chain file",
    };
    cx.push(Diagnostic::new(e.code(), proto.span, e.to_string()).with_hint(hint));
}

fn parsed_protocol<'a>(parsed: &'a [(usize, String, Protocol)], path: &str) -> &'a Protocol {
    &parsed
        .iter()
        .find(|(_, p, _)| p == path)
        .expect("every lowered stage was parsed")
        .2
}

/// The chain's scene rule: a later stage must declare the first stage's robots and labware, no
/// more and no fewer, of the same models and kinds and where the first stage puts them (E0034);
/// what it says about the start that the chain ignores, its randomisation and camera, is W0008
/// (a start state that differs from the one carried over is the proof's to say).
fn same_scene(cx: &mut Cx, first: &Lowered, later: &Lowered, ast: &Protocol) {
    for l in &ast.labware {
        let kind = later.kinds.get(&l.name.value).map(|k| k.name);
        match first.kinds.get(&l.name.value) {
            None => cx.err(
                Code::E0034,
                l.name.span,
                format!("labware `{}` is not in the chain's scene", l.name.value),
                Some(format!(
                    "the first stage declares: {}",
                    first.kinds.keys().cloned().collect::<Vec<_>>().join(", ")
                )),
            ),
            Some(k) if Some(k.name) != kind => cx.err(
                Code::E0034,
                l.name.span,
                format!(
                    "`{}` is a {} here but a {} in the first stage",
                    l.name.value,
                    kind.unwrap_or("?"),
                    k.name
                ),
                None,
            ),
            Some(_) => {
                let (Some(a), Some(b)) = (
                    first.labware.iter().find(|x| x.name == l.name.value),
                    later.labware.iter().find(|x| x.name == l.name.value),
                ) else {
                    continue;
                };
                // An item that starts in a slot is where the chain carried it (`proof`'s W0008
                // says when a stage declares otherwise), not at a pose of the bench.
                let placed =
                    a.at.is_some() || b.at.is_some() || a.held_by.is_some() || b.held_by.is_some();
                if !placed && !same_pose(&a.placement, &b.placement) {
                    moved(cx, &l.name, &l.pose, &a.placement, &b.placement);
                }
                let jitter = (a.xy_jitter_m, a.yaw_jitter_rad, &a.joint_jitter);
                if jitter != (b.xy_jitter_m, b.yaw_jitter_rad, &b.joint_jitter) {
                    ignored_randomisation(cx, ast, &l.name);
                }
            }
        }
    }
    for r in &ast.robots {
        let spec = later.robots.iter().find(|x| x.name == r.name.value);
        match first.robots.iter().find(|x| x.name == r.name.value) {
            None => cx.err(
                Code::E0034,
                r.name.span,
                format!("robot `{}` is not in the chain's scene", r.name.value),
                None,
            ),
            Some(x) if Some(&x.model) != spec.map(|s| &s.model) => cx.err(
                Code::E0034,
                r.name.span,
                format!(
                    "robot `{}` is a different model than in the first stage",
                    r.name.value
                ),
                None,
            ),
            Some(x) => {
                let Some(s) = spec else { continue };
                if !same_pose(&x.base, &s.base) {
                    moved(cx, &r.name, &r.base, &x.base, &s.base);
                }
                if x.joint_jitter != s.joint_jitter {
                    ignored_randomisation(cx, ast, &r.name);
                }
            }
        }
    }
    // What the first stage has and this one leaves out: the stage would not stand on its own as
    // the scene the chain runs it in.
    let missing: Vec<String> = first
        .robots
        .iter()
        .filter(|x| !ast.robots.iter().any(|r| r.name.value == x.name))
        .map(|x| format!("robot `{}`", x.name))
        .chain(
            first
                .kinds
                .keys()
                .filter(|n| !ast.labware.iter().any(|l| &l.name.value == *n))
                .map(|n| format!("labware `{n}`")),
        )
        .collect();
    if !missing.is_empty() {
        cx.err(
            Code::E0034,
            ast.meta.span,
            format!(
                "this stage leaves out {} of the chain's scene",
                missing.join(", ")
            ),
            Some(
                "every stage declares the whole scene, as the first stage does: copy its \
                 `[robots.*]` and `[labware.*]` tables"
                    .into(),
            ),
        );
    }
    if later.camera != first.camera {
        let span = ast.camera.as_ref().map(|c| c.span).unwrap_or(ast.meta.span);
        cx.push(
            Diagnostic::new(
                Code::W0008,
                span,
                "this stage's camera differs from the first stage's, which the chain uses",
            )
            .with_hint("a chain is seen from one camera: declare the first stage's `[camera]`"),
        );
    }
}

/// Two placements the same to a micrometre and a microradian.
fn same_pose(a: &labware::Pose, b: &labware::Pose) -> bool {
    (a.translation.vector - b.translation.vector).norm() < 1e-6
        && a.rotation.angle_to(&b.rotation) < 1e-6
}

/// E0034 at a later stage's pose (or name, when the pose is the default) that differs from the
/// first stage's.
fn moved(
    cx: &mut Cx,
    name: &dsl::ast::Spanned<String>,
    pose: &dsl::ast::Pose,
    first: &labware::Pose,
    here: &labware::Pose,
) {
    let span = pose
        .pos
        .as_ref()
        .map(|p| p.span)
        .or(pose.yaw.as_ref().map(|y| y.span))
        .unwrap_or(name.span);
    let show = |p: &labware::Pose| {
        let v = p.translation.vector;
        let (_, _, yaw) = p.rotation.euler_angles();
        format!(
            "[{:.3}, {:.3}, {:.3}] m, yaw {:.0}°",
            v.x,
            v.y,
            v.z,
            yaw.to_degrees()
        )
    };
    cx.push(
        Diagnostic::new(
            Code::E0034,
            span,
            format!(
                "`{}` stands at {} here but at {} in the first stage",
                name.value,
                show(here),
                show(first)
            ),
        )
        .with_note(
            "the bench does not move between stages: a chain runs on the first stage's scene",
        )
        .with_hint("declare the first stage's pose, or run this protocol on its own"),
    );
}

/// W0008 at a later stage's randomisation of `name` that differs from the first stage's.
fn ignored_randomisation(cx: &mut Cx, ast: &Protocol, name: &dsl::ast::Spanned<String>) {
    let span = ast
        .randomise
        .iter()
        .find(|r| r.target.value == name.value)
        .map(|r| r.target.span)
        .unwrap_or(name.span);
    cx.push(
        Diagnostic::new(
            Code::W0008,
            span,
            format!(
                "`{}` is randomised differently here than in the first stage; the chain draws the scene once, from the first stage's ranges",
                name.value
            ),
        )
        .with_hint("declare the first stage's `[randomise]` ranges"),
    );
}

fn lower_chain(
    c: &Chain,
    file: &str,
    lowered: &[(usize, String, Lowered)],
    params: Vec<ParamSpec>,
) -> Option<Task> {
    let first = &lowered[0].2;
    let stages: Vec<Stage> = lowered
        .iter()
        .map(|(i, _, low)| {
            let r = &c.stages[*i];
            let mut s = low.stage.clone();
            if let Some(ins) = &r.instruction {
                s.instruction = ins.value.clone();
            }
            if let Some(t) = &r.time_limit {
                s.time_limit_s = t.value;
            }
            s
        })
        .collect();
    let instruction = match &c.meta.instruction {
        Some(i) => i.value.clone(),
        None => stages
            .iter()
            .map(|s| s.instruction.as_str())
            .collect::<Vec<_>>()
            .join(", then "),
    };
    Some(
        Task {
            schema_version: TASK_SCHEMA_VERSION,
            id: c.meta.id.as_ref()?.value.clone(),
            version: c.meta.version.as_ref().map(|v| v.value).unwrap_or(1),
            level: c
                .meta
                .level
                .as_ref()
                .map(|l| l.value.clone())
                .unwrap_or_else(|| "hard".into()),
            instruction,
            source: file.to_string(),
            time_limit_s: stages.iter().map(|s| s.time_limit_s).sum(),
            physics: physics(),
            robots: first.robots.clone(),
            labware: first.labware.clone(),
            cameras: check::default_cameras(&first.robots, first.camera.as_ref()),
            params,
            stages,
            // A chain is written by hand; its stages' provenance stays in their files.
            imported_from: None,
            paraphrases: Vec::new(),
            perturb: None,
        }
        .with_programmes(),
    )
}
