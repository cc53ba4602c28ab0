//! Chains: several protocols run in order on the first one's scene, compiled into one
//! long-horizon task with a stage per protocol. Later stages must declare the same robots and
//! labware; their own initial states are ignored, because the proof carries the state over from
//! the stage before.

use crate::check::{self, Cx, Lowered};
use crate::params::ParamSpec;
use crate::proof::{self, ProofScene, ProofStage};
use crate::task::*;
use crate::{Loader, physics};
use dsl::ast::{Chain, Document, Protocol};
use dsl::{Code, Diagnostic, Span};
use std::path::Path;

/// The stage file's path as the chain names it, resolved against the chain file's folder.
fn stage_path(chain_file: &str, protocol: &str) -> String {
    let dir = Path::new(chain_file).parent().unwrap_or(Path::new(""));
    dir.join(protocol).to_string_lossy().into_owned()
}

pub(crate) fn compile_chain(
    c: &Chain,
    file: &str,
    load: Loader,
) -> (Option<Task>, Vec<Diagnostic>) {
    let mut cx = Cx::new(None);
    // Parse every stage first: the lowered stages borrow their ASTs.
    let mut parsed: Vec<(usize, String, Protocol)> = Vec::new();
    for (i, stage) in c.stages.iter().enumerate() {
        let Some(proto) = &stage.protocol else {
            continue;
        };
        let path = stage_path(file, &proto.value);
        let source = match load(&path) {
            Ok(s) => s,
            Err(e) => {
                cx.err(
                    Code::E0006,
                    proto.span,
                    format!("cannot read stage `{}`: {e}", proto.value),
                    Some("paths are relative to the chain file".into()),
                );
                continue;
            }
        };
        let (doc, diags) = dsl::parse(&source);
        cx.file = Some(path.clone());
        for d in diags {
            cx.push(d);
        }
        cx.file = None;
        match doc {
            Document::Protocol(p) => parsed.push((i, path, *p)),
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
    for (_, path, low) in &lowered[1..] {
        cx.file = Some(path.clone());
        same_scene(&mut cx, first, low, parsed_protocol(&parsed, path));
        for p in &low.params {
            match params.iter().find(|x| x.name == p.name) {
                Some(x) if x != p => cx.err(
                    Code::E0034,
                    Span::default(),
                    format!("parameter `{}` differs from the earlier stage's", p.name),
                    Some("a chain draws each parameter once; declare it identically".into()),
                ),
                Some(_) => {}
                None => params.push(p.clone()),
            }
        }
    }
    cx.file = None;
    if cx.has_errors() {
        return (None, cx.diags);
    }
    let stages: Vec<ProofStage> = lowered
        .iter()
        .map(|(_, path, low)| ProofStage {
            id: low.id.clone(),
            file: Some(path.clone()),
            steps: &low.steps,
            predicates: &low.predicates,
        })
        .collect();
    let scene = ProofScene {
        labware: &first.labware,
        kinds: &first.kinds,
        robots: first.robots.iter().map(|r| r.name.clone()).collect(),
        labware_spans: &first.labware_spans,
        file: Some(lowered[0].1.clone()),
    };
    proof::prove(&mut cx, &scene, &stages, &params);
    if cx.has_errors() {
        return (None, cx.diags);
    }
    let task = lower_chain(c, file, &lowered, params);
    (task, cx.diags)
}

fn parsed_protocol<'a>(parsed: &'a [(usize, String, Protocol)], path: &str) -> &'a Protocol {
    &parsed
        .iter()
        .find(|(_, p, _)| p == path)
        .expect("every lowered stage was parsed")
        .2
}

/// A later stage must name the same robots and labware, of the same models and kinds.
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
            Some(_) => {}
        }
    }
    for r in &ast.robots {
        let model = later
            .robots
            .iter()
            .find(|x| x.name == r.name.value)
            .map(|x| &x.model);
        match first.robots.iter().find(|x| x.name == r.name.value) {
            None => cx.err(
                Code::E0034,
                r.name.span,
                format!("robot `{}` is not in the chain's scene", r.name.value),
                None,
            ),
            Some(x) if Some(&x.model) != model => cx.err(
                Code::E0034,
                r.name.span,
                format!(
                    "robot `{}` is a different model than in the first stage",
                    r.name.value
                ),
                None,
            ),
            Some(_) => {}
        }
    }
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
    Some(Task {
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
        cameras: check::default_cameras(&first.robots),
        params,
        stages,
    })
}
