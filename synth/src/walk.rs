//! The random walk that makes one protocol: a start drawn from what the bench's sources start
//! with, then step after step drawn from the bench's step shapes, each kept only if its
//! primitive's own precondition holds on the abstract world (the state proof's rule, run forward)
//! and it leads somewhere new; a walk that cannot go on backs up and tries another shape (a
//! bounded depth-first search). A walk never comes back to a state it has been in (so no step
//! undoes the one before, and the protocol ends somewhere other than its start), and it ends
//! with every hand empty (an item carried is put down before the last step is out). All draws
//! come from the one generator it is given.
//!
//! It knows nothing of geometry: reach is the caller's check on the written protocol.

use super::vocabulary::{Bench, Start, Template, panel_value, world_at};
use compiler::params::{draw_all, render};
use compiler::primitives::{ArgKind, BoundStep, Env};
use compiler::world::{Hand, Location, World};
use labware::LabwareKind;
use rand_chacha::ChaCha8Rng;
use rand_core::RngCore;
use std::collections::BTreeMap;

/// One drawn step: its shape and arguments as they will be written.
#[derive(Clone, Debug)]
pub(crate) struct Step {
    pub template: Template,
    pub args: BTreeMap<String, String>,
}

/// A finished walk.
#[derive(Clone, Debug)]
pub(crate) struct Walk {
    pub start: Start,
    pub first: World,
    pub steps: Vec<Step>,
    pub last: World,
}

/// Why a walk stopped short.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Stuck {
    /// No step shape could go on from where the walk was.
    NoStep,
    /// No start could be drawn (a holder with no free slot for an item).
    NoStart,
}

/// Tries per step shape at one point of the walk (each draws its values and slot anew).
const TRIES_PER_SHAPE: usize = 4;

/// Step shapes a walk may try in all, backtracking included, before it gives up on its start.
const EXPANSIONS: usize = 400;

pub(crate) fn walk(bench: &Bench, n: usize, rng: &mut ChaCha8Rng) -> Result<Walk, Stuck> {
    let start = draw_start(bench, rng).ok_or(Stuck::NoStart)?;
    let first = world_at(&bench.kinds, &bench.robots, &start);
    let mut search = Search {
        bench,
        env: Env {
            kinds: &bench.kinds,
            robots: &bench.robots,
        },
        n,
        seen: vec![first.clone()],
        steps: Vec::with_capacity(n),
        left: EXPANSIONS,
    };
    let last = search.extend(first.clone(), rng).ok_or(Stuck::NoStep)?;
    Ok(Walk {
        start,
        first,
        steps: search.steps,
        last,
    })
}

/// A depth-first walk: at each point the shapes in a random order, each taken if it can go on
/// from where it leads, else the next (a walk that would end with a hand full or nowhere new
/// backs up instead of giving up).
struct Search<'a> {
    bench: &'a Bench,
    env: Env<'a>,
    n: usize,
    seen: Vec<World>,
    steps: Vec<Step>,
    left: usize,
}

impl Search<'_> {
    /// Extends the walk from `world` to `n` steps; the world it ends in.
    fn extend(&mut self, world: World, rng: &mut ChaCha8Rng) -> Option<World> {
        if self.steps.len() == self.n {
            return Some(world);
        }
        let mut order: Vec<usize> = (0..self.bench.templates.len()).collect();
        shuffle(&mut order, rng);
        for t in order {
            self.left = self.left.checked_sub(1)?;
            let Some((taken, after)) = self.take(&self.bench.templates[t], &world, rng) else {
                continue;
            };
            let size = taken.len();
            self.seen.push(after.clone());
            self.steps.extend(taken);
            if let Some(last) = self.extend(after, rng) {
                return Some(last);
            }
            self.steps.truncate(self.steps.len() - size);
            self.seen.pop();
        }
        None
    }

    /// The steps shape `template` makes from `world` (it and its follow-ups) and the world they
    /// lead to, if they may be taken there.
    fn take(
        &self,
        template: &Template,
        world: &World,
        rng: &mut ChaCha8Rng,
    ) -> Option<(Vec<Step>, World)> {
        let size = 1 + template.then.len();
        let left = (self.n - self.steps.len()).checked_sub(size)?;
        // A step on an item standing in a holder is taken only where its sources showed it
        // there (a tube is picked from the rack it was shown picked from, not from a rotor
        // sleeve it was only ever put into).
        let on_holder = template
            .args
            .get("on")
            .and_then(|on| match world.locations.get(on) {
                Some(Location::Slot { holder, .. }) => Some(holder),
                _ => None,
            });
        if on_holder.is_some_and(|h| !template.from.contains(h)) {
            return None;
        }
        (0..TRIES_PER_SHAPE).find_map(|_| {
            let args = instantiate(self.bench, template, world, rng)?;
            let mut after = world.clone();
            let mut taken = vec![Step {
                template: template.clone(),
                args,
            }];
            taken.extend(template.follow_ups().map(|template| Step {
                template,
                args: BTreeMap::new(),
            }));
            for step in &taken {
                let bound = BoundStep {
                    primitive: step.template.primitive,
                    robot: &step.template.robot,
                    args: &step.args,
                };
                compiler::primitives::apply(&mut after, &self.env, &bound).ok()?;
            }
            let new = !self
                .seen
                .iter()
                .any(|w| same_state(&self.bench.kinds, w, &after));
            (new && busy_hands(&after) <= left).then_some((taken, after))
        })
    }
}

/// A start: each item's part states from one of the starts its sources declare, and each
/// movable item with holders in a free slot of one of them.
fn draw_start(bench: &Bench, rng: &mut ChaCha8Rng) -> Option<Start> {
    let mut start = Start {
        states: BTreeMap::new(),
        at: BTreeMap::new(),
    };
    for (item, seen) in &bench.starts {
        start
            .states
            .insert(item.clone(), seen[below(rng, seen.len())].clone());
    }
    for (item, holders) in &bench.holders {
        let holders: Vec<&String> = holders.iter().collect();
        let holder = holders[below(rng, holders.len())];
        let taken: Vec<&str> = start
            .at
            .values()
            .filter_map(|a| a.strip_prefix(&format!("{holder}.")))
            .collect();
        let free: Vec<&String> = bench
            .start_slots
            .get(holder)?
            .iter()
            .filter(|s| !taken.contains(&s.as_str()))
            .collect();
        if free.is_empty() {
            return None;
        }
        let slot = free[below(rng, free.len())];
        start.at.insert(item.clone(), format!("{holder}.{slot}"));
    }
    Some(start)
}

/// A template's arguments for one step: its source's parameters drawn and rendered in, and a
/// place's slot drawn among its holder's free slots.
fn instantiate(
    bench: &Bench,
    t: &Template,
    world: &World,
    rng: &mut ChaCha8Rng,
) -> Option<BTreeMap<String, String>> {
    let bound = draw_all(&t.params, rng)?;
    let mut args = BTreeMap::new();
    for (name, text) in &t.args {
        let kind = t.primitive.args.iter().find(|a| a.name == name.as_str());
        let value = render(text, &bound).ok()?;
        let value = match kind.map(|a| a.kind) {
            Some(ArgKind::Location) => {
                let (holder, _) = value.split_once('.')?;
                let free: Vec<&String> = bench
                    .place_slots
                    .get(holder)?
                    .iter()
                    .filter(|s| world.occupant(holder, s).is_none())
                    .collect();
                if free.is_empty() {
                    return None;
                }
                format!("{holder}.{}", free[below(rng, free.len())])
            }
            _ => value,
        };
        args.insert(name.clone(), value);
    }
    Some(args)
}

/// Whether two worlds hold the same facts: the bookkeeping of panel holding time aside, and a
/// panel value not yet set the same as one set to its starting value.
fn same_state(kinds: &BTreeMap<String, &'static LabwareKind>, a: &World, b: &World) -> bool {
    a.parts == b.parts
        && a.locations == b.locations
        && a.volumes == b.volumes
        && a.hands == b.hands
        && a.panel
            .keys()
            .chain(b.panel.keys())
            .all(|k| panel_value(kinds, a, k) == panel_value(kinds, b, k))
}

fn busy_hands(w: &World) -> usize {
    w.hands.values().filter(|h| **h != Hand::Empty).count()
}

/// Uniform in `0..n` (`n > 0`), by 128-bit multiply (bias below 2^-64).
pub(super) fn below(rng: &mut ChaCha8Rng, n: usize) -> usize {
    ((rng.next_u64() as u128 * n as u128) >> 64) as usize
}

fn shuffle<T>(v: &mut [T], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        v.swap(i, below(rng, i + 1));
    }
}
