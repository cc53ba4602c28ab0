//! The closed catalogue of labware kinds the language knows, with their parts and the states each
//! part can be in (for initial states and success predicates).

/// A state a part can be declared in or checked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartState {
    pub part: &'static str,
    pub states: &'static [&'static str],
    /// States allowed as an initial state (`state = { lid = "open" }`).
    pub initial: &'static [&'static str],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabwareKind {
    pub name: &'static str,
    pub description: &'static str,
    pub parts: &'static [PartState],
    /// Lab primitives this kind has affordances for.
    pub primitives: &'static [&'static str],
}

pub const KINDS: &[LabwareKind] = &[LabwareKind {
    name: "thermal_cycler",
    description: "thermal cycler with a hinged lid and a lock lever (Bio-Rad C1000 proportions)",
    parts: &[PartState {
        part: "lid",
        states: &["open", "closed", "locked", "unlocked"],
        initial: &["open", "closed", "locked"],
    }],
    primitives: &["open_lid", "close_lid"],
}];

pub fn kind(name: &str) -> Option<&'static LabwareKind> {
    KINDS.iter().find(|k| k.name == name)
}
