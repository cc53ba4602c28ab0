//! What synthesis may recombine: the benches the source protocols stand on and, for each bench,
//! the steps its protocols show the expert doing there. A bench is a scene file (robots and
//! labware where they stand); protocols that name the same scene file share one. A step shape
//! (primitive, robot, the item acted on, the panel value set) is taken from its first source,
//! with the source's parameters, which say what values that step was shown with (a panel target's
//! range and grid). Where an item may start is where the sources start it, and where it may be
//! put is where they put it, each apart: a holder's slots are those a source draws for that use
//! (the author's statement of which slots work: a rotor's balancing slots are where a tube goes,
//! its other slots where the loaded one starts), or every slot of a holder no source draws from
//! for that use (the reach check then drops the slots an arm cannot reach).
//!
//! A step that takes no arguments (`retract`) changes nothing in the abstract world, so no walk
//! would choose it for itself; yet a source that follows a step with one needs it (the loading
//! arm stands back before the lid swings shut). Such steps travel with the step they follow in
//! their source, as its follow-ups, and are written after it.
//!
//! It does not read protocols whose scene is written inline (no file to share), chains (their
//! stage files are read as sources instead), or steps that start together with the step before
//! (a pair the walk could split).

use compiler::params::{Domain, ParamSpec, draw_all, render};
use compiler::primitives::{ArgKind, BoundStep, Env, LabPrimitive, apply, primitive};
use compiler::world::{Hand, Location, World};
use compiler::{PlannedStep, Task};
use labware::LabwareKind;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One scene file and what the sources on it do.
#[derive(Clone, Debug)]
pub struct Bench {
    /// The scene file's stem, made unique across benches.
    pub name: String,
    pub scene: PathBuf,
    pub kinds: BTreeMap<String, &'static LabwareKind>,
    pub robots: Vec<String>,
    pub templates: Vec<Template>,
    /// Start states the sources declare per item (each a full map of part -> state).
    pub starts: BTreeMap<String, Vec<BTreeMap<String, String>>>,
    /// Holders each movable item starts in.
    pub holders: BTreeMap<String, BTreeSet<String>>,
    /// Holders each movable item is put into.
    pub places: BTreeMap<String, BTreeSet<String>>,
    /// The slots of each holder an item may start in.
    pub start_slots: BTreeMap<String, Vec<String>>,
    /// The slots of each holder an item may be put into: those the sources draw for a place
    /// (a rotor's balancing slots, not the slots its loaded tube starts in).
    pub place_slots: BTreeMap<String, Vec<String>>,
    /// The source protocols' files.
    pub sources: Vec<String>,
}

/// One step shape a source shows.
#[derive(Clone, Debug)]
pub struct Template {
    pub primitive: &'static LabPrimitive,
    pub robot: String,
    /// Arguments as the source writes them (templates over `params`).
    pub args: BTreeMap<String, String>,
    /// The source's parameters.
    pub params: Vec<ParamSpec>,
    /// The source's time limit per step (s): what the step is given in a synthesised protocol.
    pub budget_s: f64,
    /// The argument-less steps that follow it in its source: (primitive, robot).
    pub then: Vec<(&'static LabPrimitive, String)>,
    /// The holders its `on` item stood in when a source took the step.
    pub from: BTreeSet<String>,
}

impl Template {
    /// Its follow-ups as steps of their own (no arguments, the step's budget each).
    pub fn follow_ups(&self) -> impl Iterator<Item = Template> + '_ {
        self.then.iter().map(|(primitive, robot)| Template {
            primitive,
            robot: robot.clone(),
            args: BTreeMap::new(),
            params: Vec::new(),
            budget_s: self.budget_s,
            then: Vec::new(),
            from: BTreeSet::new(),
        })
    }

    fn kind_of(&self, arg: &str) -> Option<ArgKind> {
        self.primitive
            .args
            .iter()
            .find(|a| a.name == arg)
            .map(|a| a.kind)
    }

    /// What makes two steps the same shape: the primitive, robot, item, the holder it goes to
    /// and the panel value or button named; not the target value or slot, which synthesis draws.
    fn shape(&self) -> String {
        let fixed: Vec<String> = self
            .args
            .iter()
            .filter(|(k, _)| {
                self.primitive
                    .args
                    .iter()
                    .find(|a| a.name == k.as_str())
                    .is_some_and(|a| a.kind != ArgKind::PanelValue)
            })
            .map(|(k, v)| match self.kind_of(k) {
                // Where to is the holder; the slot is drawn.
                Some(ArgKind::Location) => {
                    format!("{k}={}.*", v.split_once('.').map_or(v.as_str(), |(h, _)| h))
                }
                _ => format!("{k}={v}"),
            })
            .collect();
        let then: Vec<String> = self
            .then
            .iter()
            .map(|(p, r)| format!("then {} {r}", p.name))
            .collect();
        format!(
            "{} {} {} {}",
            self.primitive.name,
            self.robot,
            fixed.join(" "),
            then.join(" ")
        )
    }
}

/// A source protocol, compiled, with the scene file it names.
pub struct Source {
    pub file: String,
    pub scene: PathBuf,
    pub task: Task,
}

/// Groups the sources into benches by scene file (in the order first seen) and gathers each
/// bench's vocabulary.
pub fn benches(sources: &[Source]) -> Vec<Bench> {
    let mut out: Vec<Bench> = Vec::new();
    for s in sources {
        let i = match out.iter().position(|b| b.scene == s.scene) {
            Some(i) => i,
            None => {
                out.push(new_bench(s, &out));
                out.len() - 1
            }
        };
        gather(&mut out[i], s);
    }
    for b in &mut out {
        let kinds = b.kinds.clone();
        fill(&kinds, &b.holders, &mut b.start_slots);
        fill(&kinds, &b.places, &mut b.place_slots);
    }
    out
}

/// Every slot (that takes the item) of each holder in `holders` no source draws slots of.
fn fill(
    kinds: &BTreeMap<String, &'static LabwareKind>,
    holders: &BTreeMap<String, BTreeSet<String>>,
    slots: &mut BTreeMap<String, Vec<String>>,
) {
    for (item, hs) in holders {
        let Some(kind) = kinds.get(item) else {
            continue;
        };
        for h in hs {
            if slots.contains_key(h) {
                continue;
            }
            let all = kinds
                .get(h)
                .and_then(|k| k.slots)
                .filter(|s| s.accepts.contains(&kind.name))
                .map(|s| s.layout.names())
                .unwrap_or_default();
            slots.insert(h.clone(), all);
        }
    }
}

fn new_bench(s: &Source, others: &[Bench]) -> Bench {
    let stem = s
        .scene
        .file_stem()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let name = if others.iter().any(|b| b.name == stem) {
        format!("{stem}_{}", others.len() + 1)
    } else {
        stem
    };
    Bench {
        name,
        scene: s.scene.clone(),
        kinds: s
            .task
            .labware
            .iter()
            .filter_map(|l| Some((l.name.clone(), labware::catalogue::kind(&l.kind)?)))
            .collect(),
        robots: s.task.robots.iter().map(|r| r.name.clone()).collect(),
        templates: Vec::new(),
        starts: BTreeMap::new(),
        holders: BTreeMap::new(),
        places: BTreeMap::new(),
        start_slots: BTreeMap::new(),
        place_slots: BTreeMap::new(),
        sources: Vec::new(),
    }
}

fn gather(b: &mut Bench, s: &Source) {
    b.sources.push(s.file.clone());
    let task = &s.task;
    // Every source's labware: one may declare an item the others do not.
    for l in &task.labware {
        if let Some(kind) = labware::catalogue::kind(&l.kind) {
            b.kinds.entry(l.name.clone()).or_insert(kind);
        }
    }
    let bound = draw_all(&task.params, &mut ChaCha8Rng::seed_from_u64(0)).unwrap_or_default();
    let mut start = Start::default();
    for l in &task.labware {
        if !l.initial.is_empty() {
            start.states.insert(l.name.clone(), l.initial.clone());
            let seen = b.starts.entry(l.name.clone()).or_default();
            if !seen.contains(&l.initial) {
                seen.push(l.initial.clone());
            }
        }
        if let Some(at) = &l.at {
            note_place(b, &l.name, at, &task.params, false);
            start.at.insert(
                l.name.clone(),
                render(at, &bound).unwrap_or_else(|_| at.clone()),
            );
        }
    }
    let [stage] = task.stages.as_slice() else {
        return;
    };
    // The source's own run, traced as the proof traces it (its first draw of parameters), so
    // that each step is known with where its item stood.
    let mut world = world_at(&b.kinds, &b.robots, &start);
    let budget_s = stage.time_limit_s / stage.plan.len().max(1) as f64;
    for (i, step) in stage.plan.iter().enumerate() {
        let from = step
            .labware
            .as_ref()
            .and_then(|on| match world.locations.get(on) {
                Some(Location::Slot { holder, .. }) => Some(holder.clone()),
                _ => None,
            });
        if let Some(p) = primitive(&step.primitive) {
            let args: BTreeMap<String, String> = step
                .args
                .iter()
                .map(|(k, v)| (k.clone(), render(v, &bound).unwrap_or_else(|_| v.clone())))
                .collect();
            let env = Env {
                kinds: &b.kinds,
                robots: &b.robots,
            };
            let bound_step = BoundStep {
                primitive: p,
                robot: &step.robot,
                args: &args,
            };
            // The source is proven; a step it cannot take here leaves the trace as it was.
            let _ = apply(&mut world, &env, &bound_step);
        }
        // A step that starts together with the next, or with the one before, is half of a
        // pair the walk could split: neither is recombined.
        let paired = step.together || stage.plan.get(i + 1).is_some_and(|n| n.together);
        if is_follow_up(step) || paired {
            continue;
        }
        let Some(mut t) = template(step, &task.params, budget_s) else {
            continue;
        };
        t.then = stage.plan[i + 1..]
            .iter()
            .take_while(|s| is_follow_up(s))
            .filter_map(|s| Some((primitive(&s.primitive)?, s.robot.clone())))
            .collect();
        t.from.extend(from);
        if let (Some(item), Some(to)) = (&step.labware, step_location(&t)) {
            note_place(b, item, &to, &task.params, true);
        }
        match b.templates.iter_mut().find(|o| o.shape() == t.shape()) {
            Some(same) => same.from.extend(t.from),
            None => b.templates.push(t),
        }
    }
}

fn template(step: &PlannedStep, params: &[ParamSpec], budget_s: f64) -> Option<Template> {
    let p = primitive(&step.primitive)?;
    (p.motions.is_some() && !step.together).then(|| Template {
        primitive: p,
        robot: step.robot.clone(),
        args: step.args.clone(),
        params: params.to_vec(),
        budget_s,
        then: Vec::new(),
        from: BTreeSet::new(),
    })
}

/// A step that names nothing but its robot: it cannot change the abstract world.
fn is_follow_up(step: &PlannedStep) -> bool {
    primitive(&step.primitive).is_some_and(|p| p.args.is_empty() && p.motions.is_some())
}

/// The step's `<holder>.<slot>` argument, as written.
fn step_location(t: &Template) -> Option<String> {
    t.primitive
        .args
        .iter()
        .find(|a| a.kind == ArgKind::Location)
        .and_then(|a| t.args.get(a.name).cloned())
}

/// Notes that `item` may start in (or, `put`, be put into) `at`'s holder and, where `at` draws
/// its slot from a parameter, which slots the source allows there.
fn note_place(b: &mut Bench, item: &str, at: &str, params: &[ParamSpec], put: bool) {
    let Some((holder, slot)) = at.split_once('.') else {
        return;
    };
    let holders = if put { &mut b.places } else { &mut b.holders };
    holders
        .entry(item.to_string())
        .or_default()
        .insert(holder.to_string());
    let Some(name) = slot.strip_prefix('{').and_then(|s| s.strip_suffix('}')) else {
        return;
    };
    let drawn = drawable_slots(name, params);
    if drawn.is_empty() {
        return;
    }
    let slots = if put {
        &mut b.place_slots
    } else {
        &mut b.start_slots
    };
    let slots = slots.entry(holder.to_string()).or_default();
    for s in drawn {
        if !slots.contains(&s) {
            slots.push(s);
        }
    }
}

/// The slots parameter `name` can draw: its slot list less its exclusions, or the opposites of
/// the slots the parameter it mirrors can draw.
fn drawable_slots(name: &str, params: &[ParamSpec]) -> Vec<String> {
    let Some(p) = params.iter().find(|p| p.name == name) else {
        return Vec::new();
    };
    match &p.domain {
        Domain::Slot { slots, .. } => slots
            .iter()
            .filter(|s| !p.exclude.contains(s))
            .cloned()
            .collect(),
        Domain::Opposite { of, ring, .. } => drawable_slots(of, params)
            .iter()
            .filter_map(|s| compiler::params::opposite(s, *ring))
            .filter(|s| !p.exclude.contains(s))
            .collect(),
        _ => Vec::new(),
    }
}

/// The scene file a protocol's text names (`scene = ".."`), resolved against its folder.
pub fn scene_of(text: &str, file: &Path) -> Option<PathBuf> {
    let doc: toml::Table = text.parse().ok()?;
    let scene = doc.get("scene")?.as_str()?;
    Some(file.parent().unwrap_or(Path::new(".")).join(scene))
}

/// Where an item starts: its part states and, for a movable one, its slot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Start {
    pub states: BTreeMap<String, BTreeMap<String, String>>,
    pub at: BTreeMap<String, String>,
}

/// The abstract world a start stands for (as the proof builds it from the written protocol).
pub(super) fn world_at(
    kinds: &BTreeMap<String, &'static LabwareKind>,
    robots: &[String],
    start: &Start,
) -> World {
    let mut w = World::default();
    for (item, states) in &start.states {
        for (part, state) in states {
            w.set_part(item, part, state);
        }
    }
    for (item, kind) in kinds {
        let location = match start.at.get(item).and_then(|a| a.split_once('.')) {
            Some((holder, slot)) => Location::Slot {
                holder: holder.into(),
                slot: slot.into(),
            },
            None if kind.movable => Location::Bench,
            None => continue,
        };
        w.locations.insert(item.clone(), location);
    }
    for r in robots {
        w.hands.insert(r.clone(), Hand::Empty);
    }
    w
}

/// A panel value as the world shows it: the value set, or its kind's start value while unset.
pub(super) fn panel_value(
    kinds: &BTreeMap<String, &'static LabwareKind>,
    w: &World,
    key: &(String, String),
) -> Option<f64> {
    w.panel.get(key).copied().or_else(|| {
        kinds
            .get(&key.0)
            .and_then(|k| k.panel_param(&key.1))
            .map(|p| p.initial)
    })
}
