//! The closed catalogue of lab primitives: for each, the labware kinds it applies to, the part
//! state it needs before it starts and the state it leaves. The compiler traces steps through these
//! to prove a protocol (or a chain) can run; the `primitives` crate expands them into motions.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabPrimitive {
    pub name: &'static str,
    pub description: &'static str,
    pub part: &'static str,
    /// The part must be in one of these states before the step.
    pub requires: &'static [&'static str],
    /// The part's state after the step.
    pub leaves: &'static str,
}

pub const CATALOGUE: &[LabPrimitive] = &[
    LabPrimitive {
        name: "close_lid",
        description: "swing a hinged lid shut by its handle and press its lock lever",
        part: "lid",
        requires: &["open"],
        leaves: "locked",
    },
    LabPrimitive {
        name: "open_lid",
        description: "raise the lock lever and swing the lid open by its handle",
        part: "lid",
        requires: &["closed", "locked"],
        leaves: "open",
    },
];

pub fn primitive(name: &str) -> Option<&'static LabPrimitive> {
    CATALOGUE.iter().find(|p| p.name == name)
}
