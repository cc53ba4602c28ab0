//! The closed catalogue of labware kinds the protocol language knows: for each kind its parts and
//! their states, slots, liquid capacity, instrument panel, buttons, joints and named tolerances.
//!
//! This is declarative data, read by the compiler (name resolution, state tracing, predicates) and
//! by the docs. Whether a kind can be *simulated* is derived from [`crate::registry`]: only kinds
//! with a model run in the runtime; the others compile, are described and checked, and are refused
//! by the runtime with a clear error until their model lands.
//! Dimensions and ranges follow `upstream-autobio.md` §3, §5 and §11.

/// A discrete part state, e.g. a lid that is `open`, `closed` or `locked`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartState {
    pub part: &'static str,
    /// States a predicate may check for.
    pub states: &'static [&'static str],
    /// States a protocol may declare as initial (`state = { lid = "open" }`); the first is the default.
    pub initial: &'static [&'static str],
}

/// How a holder's slots are named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotLayout {
    /// Rows `A..` by columns `1..`, named like plate wells: `A1`, `B5`.
    Grid { rows: u32, cols: u32 },
    /// `n` positions around a rotor, named `1..n`; slot `i` is opposite `i + n/2`.
    Ring { n: u32 },
    /// One named position (the vortex mixer's cup).
    Single { name: &'static str },
}

impl SlotLayout {
    /// Every slot name, in order.
    pub fn names(&self) -> Vec<String> {
        match *self {
            SlotLayout::Grid { rows, cols } => (0..rows)
                .flat_map(|r| (1..=cols).map(move |c| format!("{}{c}", (b'A' + r as u8) as char)))
                .collect(),
            SlotLayout::Ring { n } => (1..=n).map(|i| i.to_string()).collect(),
            SlotLayout::Single { name } => vec![name.to_string()],
        }
    }

    /// The slot diametrically opposite `slot` on a ring.
    pub fn opposite(&self, slot: &str) -> Option<String> {
        let SlotLayout::Ring { n } = *self else {
            return None;
        };
        let i: u32 = slot.parse().ok().filter(|i| (1..=n).contains(i))?;
        Some(((i - 1 + n / 2) % n + 1).to_string())
    }

    pub fn describe(&self) -> String {
        match *self {
            SlotLayout::Grid { rows, cols } => format!(
                "{rows}x{cols} grid, A1..{}{cols}",
                (b'A' + rows as u8 - 1) as char
            ),
            SlotLayout::Ring { n } => format!("ring of {n}, 1..{n}"),
            SlotLayout::Single { name } => format!("one slot, `{name}`"),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slots {
    pub layout: SlotLayout,
    /// Kinds that fit a slot.
    pub accepts: &'static [&'static str],
}

/// A value shown on an instrument's display (or dial) and set by its buttons or by turning its dial.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PanelParam {
    pub name: &'static str,
    /// Canonical unit symbol of the value (see the language reference): `rpm`, `°C`, `s`.
    pub unit: &'static str,
    pub min: f64,
    pub max: f64,
    /// One button press changes the value by this much.
    pub step: f64,
    pub initial: f64,
    /// A held button steps the value once every this many seconds (the panel's auto-repeat).
    pub repeat_s: f64,
    /// The knob (its joint role and affordance name) whose notches set the value, for a value
    /// set with a dial rather than buttons: `step` is then the speed between notches, any target
    /// in range is turned to the nearest notch, and `initial` is the dial's rest (its stop may lie
    /// below `min`).
    pub dial: Option<&'static str>,
}

impl PanelParam {
    /// The value a set `target` leaves the panel at: a dial rests in the notch nearest it (half
    /// way between two, the higher), within its range; buttons step to the target itself. The
    /// one rule the compiler's world and the dial's model (`Instrument::dial_toward`) share.
    pub fn set_value(&self, target: f64) -> f64 {
        match self.dial {
            Some(_) => {
                let notches = ((self.max - self.min) / self.step).round();
                let k = ((target - self.min) / self.step)
                    .round()
                    .clamp(0.0, notches);
                self.min + k * self.step
            }
            None => target,
        }
    }

    /// Seconds a button must be held to step the value from `from` to `to` (none for a dial).
    pub fn hold_seconds(&self, from: f64, to: f64) -> f64 {
        if self.dial.is_some() {
            return 0.0;
        }
        ((to - from).abs() / self.step).round() * self.repeat_s
    }
}

/// What pressing a button does to the abstract state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ButtonEffect {
    /// Toggles a part between two states.
    Toggle {
        part: &'static str,
        a: &'static str,
        b: &'static str,
    },
    /// Steps a panel value by `sign` steps.
    Step { param: &'static str, sign: i8 },
    /// Releases a latch: a part in state `from` goes to `to` (in any other state, nothing
    /// happens). A centrifuge's lid key unlocks its lid without opening it.
    Release {
        part: &'static str,
        from: &'static str,
        to: &'static str,
    },
    /// Starts the instrument's next run ([`crate::run`]): what a run step (`spin`, `incubate`)
    /// presses, never a `press` of its own (the run's programme comes from the step).
    Start,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Button {
    pub name: &'static str,
    pub effect: ButtonEffect,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabwareKind {
    pub name: &'static str,
    pub description: &'static str,
    pub parts: &'static [PartState],
    pub slots: Option<Slots>,
    /// Liquid capacity in µL, for containers.
    pub capacity_ul: Option<f64>,
    /// Can be picked up and placed.
    pub movable: bool,
    pub panel: &'static [PanelParam],
    pub buttons: &'static [Button],
    /// Joints a predicate may range-check, with their unit (`rad` or `m`).
    pub joints: &'static [(&'static str, &'static str)],
    /// Default named tolerances, in the canonical unit of what they bound.
    pub tolerances: &'static [(&'static str, f64)],
    /// Lab primitives this kind has affordances for (as the object `on` a step).
    pub primitives: &'static [&'static str],
    /// A liquid-handling tool a robot carries (a pipette): what `aspirate` and `dispense` draw
    /// into and expel from.
    pub liquid_tool: bool,
    /// The published labware definition (`namespace/loadName/version`, embedded from
    /// `embedded-definitions.txt`) the kind's geometry comes from: its footprint, where its wells
    /// stand and how deep they are ([`crate::definition`]); `None`: the kind is drawn from our own
    /// parameters.
    pub definition: Option<&'static str>,
}

impl LabwareKind {
    pub fn part(&self, name: &str) -> Option<&'static PartState> {
        self.parts.iter().find(|p| p.part == name)
    }

    pub fn panel_param(&self, name: &str) -> Option<&'static PanelParam> {
        self.panel.iter().find(|p| p.name == name)
    }

    pub fn button(&self, name: &str) -> Option<&'static Button> {
        self.buttons.iter().find(|b| b.name == name)
    }

    /// The button that releases `part`'s latch, when a key (not the part's own handle) does.
    pub fn release_key(&self, part: &str) -> Option<&'static Button> {
        self.buttons
            .iter()
            .find(|b| matches!(b.effect, ButtonEffect::Release { part: p, .. } if p == part))
    }

    pub fn tolerance(&self, name: &str) -> Option<f64> {
        self.tolerances
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
    }

    pub fn supports(&self, primitive: &str) -> bool {
        self.primitives.contains(&primitive)
    }

    /// A simulation model exists in [`crate::registry`] (the runtime can build it).
    pub fn simulated(&self) -> bool {
        crate::Model::for_kind(self.name).is_some()
    }
}

const LID_LOCKING: PartState = PartState {
    part: "lid",
    states: &["open", "closed", "locked", "unlocked"],
    initial: &["open", "closed", "locked"],
};
const LID_PLAIN: PartState = PartState {
    part: "lid",
    states: &["open", "closed"],
    initial: &["open", "closed"],
};
/// A screw cap: on its tube, off it (a tube made open, or a cap taken off), or lying apart from
/// the tube where the protocol's `parts` puts it (a cap a robot picks up to screw on).
const CAP: PartState = PartState {
    part: "cap",
    states: &["on", "off", "apart"],
    initial: &["on", "off", "apart"],
};
/// What a lid takes, by its latch: none (opened and shut), a latch locked and unlocked by hand
/// (a lever), or a latch that catches as the lid shuts and a panel key releases (no `lock`).
/// An instrument's run ([`crate::run`]): idle until its first run starts, running, done once a
/// run has finished (until the next starts).
const RUN_PART: PartState = PartState {
    part: crate::run::RUN,
    states: &crate::run::STATES,
    initial: &["idle"],
};
/// The key that starts a run.
const START_KEY: Button = Button {
    name: "start",
    effect: ButtonEffect::Start,
};
const PLAIN_LID_PRIMITIVES: &[&str] = &["open_lid", "close_lid"];
const LID_PRIMITIVES: &[&str] = &["open_lid", "close_lid", "lock", "unlock"];
const KEYED_LID_PRIMITIVES: &[&str] = &["open_lid", "close_lid", "unlock", "press"];
/// The key on a centrifuge's panel that releases its lid's latch (the lid stays shut).
const OPEN_KEY: Button = Button {
    name: "open",
    effect: ButtonEffect::Release {
        part: "lid",
        from: "locked",
        to: "closed",
    },
};
const LID_KEY: &[Button] = &[OPEN_KEY];
const TUBE_PRIMITIVES: &[&str] = &[
    "invert",
    "pick",
    "place",
    "hold",
    "hand_over",
    "unscrew_cap",
    "pick_cap",
    "screw_cap",
    "aspirate",
    "dispense",
];
/// Slot tolerances (m): in-plane distance to the slot centre, height above its seat.
const SLOT_TOLERANCES: &[(&str, f64)] = &[("slot_xy", 0.015), ("slot_z", 0.005)];
/// The vortex mixer's cup, and its dial read to half a notch (144.4 rpm, rounded up): a speed of
/// `x rpm` holds in the notch nearest `x`.
const VORTEX_TOLERANCES: &[(&str, f64)] =
    &[("slot_xy", 0.015), ("slot_z", 0.005), ("display", 145.0)];
/// `cap_on`: how far (m) a cap may stand from its seat, along the tube's axis, and count as on.
const TUBE_TOLERANCES: &[(&str, f64)] = &[
    ("cap_on", 0.002),
    ("slot_xy", 0.015),
    ("slot_z", 0.005),
    ("volume", 1.0),
    ("position", 0.005),
];
/// Small tubes stand in racks of 12.5 mm pitch: a slot tolerance under half the pitch, so no
/// tube counts as standing in its neighbour's slot.
const MICROTUBE_TOLERANCES: &[(&str, f64)] = &[
    ("cap_on", 0.002),
    ("slot_xy", 0.005),
    ("slot_z", 0.003),
    ("volume", 1.0),
    ("position", 0.005),
];
/// A PCR tube's: a microtube's, in places 9 mm apart (`slot_xy` under half the pitch).
const PCR_TUBE_TOLERANCES: &[(&str, f64)] = &[
    ("cap_on", 0.002),
    ("slot_xy", 0.003),
    ("slot_z", 0.003),
    ("volume", 1.0),
    ("position", 0.005),
];
const TUBE_ACCEPTING_RACK: &[&str] = &["tube_50ml", "tube_15ml"];

const fn tube(
    name: &'static str,
    description: &'static str,
    capacity_ul: f64,
    tolerances: &'static [(&'static str, f64)],
) -> LabwareKind {
    LabwareKind {
        name,
        description,
        parts: &[CAP],
        slots: None,
        capacity_ul: Some(capacity_ul),
        movable: true,
        panel: &[],
        buttons: &[],
        joints: &[],
        tolerances,
        primitives: TUBE_PRIMITIVES,
        liquid_tool: false,
        definition: None,
    }
}

const fn rack(
    name: &'static str,
    description: &'static str,
    layout: SlotLayout,
    accepts: &'static [&'static str],
) -> LabwareKind {
    LabwareKind {
        name,
        description,
        parts: &[],
        slots: Some(Slots { layout, accepts }),
        capacity_ul: None,
        movable: false,
        panel: &[],
        buttons: &[],
        joints: &[],
        tolerances: SLOT_TOLERANCES,
        primitives: &[],
        liquid_tool: false,
        definition: None,
    }
}

/// A rack whose footprint and places come from a published definition; the places must be its
/// wells' grid (a test compares them).
const fn defined_rack(
    name: &'static str,
    description: &'static str,
    layout: SlotLayout,
    accepts: &'static [&'static str],
    definition: &'static str,
) -> LabwareKind {
    LabwareKind {
        definition: Some(definition),
        ..rack(name, description, layout, accepts)
    }
}

/// A pipette's set volume (µL): the volume its plunger's first stop displaces, set for the
/// episode between `min` and `max` (no knob to turn).
const fn set_volume(min: f64, max: f64) -> PanelParam {
    PanelParam {
        name: "set_volume",
        unit: "µL",
        min,
        max,
        step: 1.0,
        initial: max,
        repeat_s: 0.0,
        dial: None,
    }
}
const P1000_PANEL: &[PanelParam] = &[set_volume(100.0, 1000.0)];
const P200_PANEL: &[PanelParam] = &[set_volume(20.0, 200.0)];

/// A single-channel pipette whose tip holds `capacity_ul`, set through `panel`.
const fn pipette(
    name: &'static str,
    description: &'static str,
    capacity_ul: f64,
    panel: &'static [PanelParam],
) -> LabwareKind {
    LabwareKind {
        name,
        description,
        // Where its tip is: out of every container, in one, or under a liquid's surface.
        parts: &[PartState {
            part: "tip",
            states: &["out", "in", "immersed"],
            initial: &["out"],
        }],
        slots: None,
        capacity_ul: Some(capacity_ul),
        movable: true,
        panel,
        buttons: &[],
        joints: &[("plunger", "m"), ("blow_out", "m"), ("ejector", "m")],
        tolerances: &[("volume", 1.0), ("position", 0.005)],
        primitives: &["pick", "place", "hand_over"],
        liquid_tool: true,
        definition: None,
    }
}

/// Whether one of the buttons releases a latch (a key-latched lid: `press` and `unlock` by key).
const fn releases_a_latch(buttons: &[Button]) -> bool {
    let mut i = 0;
    while i < buttons.len() {
        if matches!(buttons[i].effect, ButtonEffect::Release { .. }) {
            return true;
        }
        i += 1;
    }
    false
}

/// Whether any of `parts` has the state `state` (a `const` search: the kinds are constants).
const fn has_state(parts: &[PartState], state: &str) -> bool {
    let mut i = 0;
    while i < parts.len() {
        let mut j = 0;
        while j < parts[i].states.len() {
            if same_text(parts[i].states[j], state) {
                return true;
            }
            j += 1;
        }
        i += 1;
    }
    false
}

const fn same_text(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

const fn lidded(
    name: &'static str,
    description: &'static str,
    parts: &'static [PartState],
    slots: Option<Slots>,
    buttons: &'static [Button],
) -> LabwareKind {
    LabwareKind {
        name,
        description,
        parts,
        slots,
        capacity_ul: None,
        movable: false,
        panel: &[],
        buttons,
        joints: &[("lid", "rad")],
        tolerances: &[
            ("lid_closed", 0.01),
            ("lid_locked", 0.01),
            ("lid_open", 0.01),
        ],
        primitives: if releases_a_latch(buttons) {
            KEYED_LID_PRIMITIVES
        } else if has_state(parts, "locked") {
            LID_PRIMITIVES
        } else {
            PLAIN_LID_PRIMITIVES
        },
        liquid_tool: false,
        definition: None,
    }
}

/// The paper's thermal cycler: its block holds nothing.
const THERMAL_CYCLER: LabwareKind = LabwareKind {
    name: "thermal_cycler",
    description: "thermal cycler with a hinged lid and a two-notch lock lever (Bio-Rad C1000 proportions); it runs a thermal profile, started as its lid locks",
    parts: &[LID_LOCKING, RUN_PART],
    slots: None,
    capacity_ul: None,
    movable: false,
    panel: &[],
    buttons: &[],
    joints: &[("lid", "rad"), ("lever", "rad")],
    tolerances: &[
        ("lid_closed", 0.01),
        ("lid_locked", 0.01),
        ("lid_open", 0.003),
        ("lid_unlocked", 0.003),
    ],
    primitives: &["open_lid", "close_lid", "thermocycle"],
    liquid_tool: false,
    definition: None,
};

pub const KINDS: &[LabwareKind] = &[
    THERMAL_CYCLER,
    LabwareKind {
        name: "thermal_cycler_96",
        description: "the thermal cycler with a 96-well block for 0.2 mL PCR tubes sunk under its lid (wells where Opentrons' 96-well aluminium block has them, 8x12 at 9 mm); it runs a thermal profile, started as its lid locks",
        slots: Some(Slots {
            layout: SlotLayout::Grid { rows: 8, cols: 12 },
            accepts: &["tube_0_2ml"],
        }),
        definition: Some("opentrons/opentrons_96_aluminumblock_generic_pcr_strip_200ul/2"),
        ..THERMAL_CYCLER
    },
    LabwareKind {
        // The rotor turns freely: its start angle can be drawn (`[randomise.x] joints`).
        joints: &[("lid", "rad"), ("rotor", "rad")],
        primitives: &["open_lid", "close_lid", "unlock", "press", "spin"],
        ..lidded(
            "centrifuge_5430",
            "benchtop centrifuge with a latched lid, a start key and a 30-place rotor for 1.5 mL tubes (Eppendorf 5430); it spins only latched and balanced",
            &[LID_LOCKING, RUN_PART],
            Some(Slots {
                layout: SlotLayout::Ring { n: 30 },
                accepts: &["tube_1_5ml"],
            }),
            &[OPEN_KEY, START_KEY],
        )
    },
    lidded(
        "centrifuge_5910",
        "floor-standing centrifuge with a latched lid (Eppendorf 5910 Ri)",
        &[LID_LOCKING],
        None,
        LID_KEY,
    ),
    lidded(
        "centrifuge_mini",
        "mini centrifuge with a lid and no latch (Tiangen TGear mini)",
        &[LID_PLAIN],
        None,
        &[],
    ),
    LabwareKind {
        name: "thermal_mixer",
        description: "thermal mixer with a 24-well block for 1.5 mL tubes, whose speed, temperature and time are set with up/down buttons and which incubates from its start key (Eppendorf ThermoMixer C)",
        parts: &[RUN_PART],
        slots: Some(Slots {
            layout: SlotLayout::Grid { rows: 4, cols: 6 },
            accepts: &["tube_1_5ml"],
        }),
        capacity_ul: None,
        movable: false,
        panel: &[
            PanelParam {
                name: "speed",
                unit: "rpm",
                min: 300.0,
                max: 3000.0,
                step: 50.0,
                initial: 900.0,
                repeat_s: 0.25,
                dial: None,
            },
            PanelParam {
                name: "temperature",
                unit: "°C",
                min: 4.0,
                max: 99.0,
                step: 1.0,
                initial: 25.0,
                repeat_s: 0.25,
                dial: None,
            },
            PanelParam {
                name: "time",
                unit: "s",
                min: 5.0,
                max: 300.0,
                step: 5.0,
                initial: 60.0,
                repeat_s: 0.25,
                dial: None,
            },
        ],
        buttons: &[
            Button {
                name: "speed_up",
                effect: ButtonEffect::Step {
                    param: "speed",
                    sign: 1,
                },
            },
            Button {
                name: "speed_down",
                effect: ButtonEffect::Step {
                    param: "speed",
                    sign: -1,
                },
            },
            Button {
                name: "temperature_up",
                effect: ButtonEffect::Step {
                    param: "temperature",
                    sign: 1,
                },
            },
            Button {
                name: "temperature_down",
                effect: ButtonEffect::Step {
                    param: "temperature",
                    sign: -1,
                },
            },
            Button {
                name: "time_up",
                effect: ButtonEffect::Step {
                    param: "time",
                    sign: 1,
                },
            },
            Button {
                name: "time_down",
                effect: ButtonEffect::Step {
                    param: "time",
                    sign: -1,
                },
            },
            START_KEY,
        ],
        joints: &[],
        tolerances: &[("display", 1e-6)],
        primitives: &["press", "set_parameter", "incubate"],
        liquid_tool: false,
        definition: None,
    },
    LabwareKind {
        name: "vortex_mixer",
        description: "vortex mixer with a power switch, a speed knob and one cup (Scientific Industries Vortex-Genie 2)",
        parts: &[PartState {
            part: "power",
            states: &["off", "on"],
            initial: &["off", "on"],
        }],
        slots: Some(Slots {
            layout: SlotLayout::Single { name: "cup" },
            accepts: &["tube_15ml", "tube_50ml", "tube_1_5ml", "cryovial"],
        }),
        capacity_ul: None,
        movable: false,
        // The knob's notches: 0 stops, 1..10 run at 600..3,200 rpm in nine equal steps.
        panel: &[PanelParam {
            name: "speed",
            unit: "rpm",
            min: 600.0,
            max: 3200.0,
            step: 2600.0 / 9.0,
            initial: 0.0,
            repeat_s: 0.0,
            dial: Some("knob"),
        }],
        buttons: &[Button {
            name: "switch",
            effect: ButtonEffect::Toggle {
                part: "power",
                a: "off",
                b: "on",
            },
        }],
        joints: &[],
        tolerances: VORTEX_TOLERANCES,
        primitives: &["press", "set_parameter"],
        liquid_tool: false,
        definition: None,
    },
    rack(
        "tube_rack",
        "rack of 2x5 places for 15 mL and 50 mL tubes, 36 mm pitch",
        SlotLayout::Grid { rows: 2, cols: 5 },
        TUBE_ACCEPTING_RACK,
    ),
    rack(
        "microtube_rack",
        "rack of 6x10 places for 1.5 mL tubes and cryovials",
        SlotLayout::Grid { rows: 6, cols: 10 },
        &["tube_1_5ml", "cryovial"],
    ),
    defined_rack(
        "tuberack_24_1_5ml",
        "Opentrons 4-in-1 rack's 24-place insert for 1.5 mL tubes (4x6, 19.9 mm by 19.3 mm pitch)",
        SlotLayout::Grid { rows: 4, cols: 6 },
        &["tube_1_5ml"],
        "opentrons/opentrons_24_tuberack_eppendorf_1.5ml_safelock_snapcap/3",
    ),
    defined_rack(
        "tuberack_6_50ml",
        "Opentrons 4-in-1 rack's 6-place insert for 50 mL conical tubes (2x3, 35 mm pitch)",
        SlotLayout::Grid { rows: 2, cols: 3 },
        &["tube_50ml"],
        "opentrons/opentrons_6_tuberack_falcon_50ml_conical/2",
    ),
    defined_rack(
        "aluminium_block_96_pcr",
        "Opentrons 96-well aluminium block for 0.2 mL PCR tubes and strips (8x12, 9 mm pitch)",
        SlotLayout::Grid { rows: 8, cols: 12 },
        &["tube_0_2ml"],
        "opentrons/opentrons_96_aluminumblock_generic_pcr_strip_200ul/2",
    ),
    tube(
        "tube_0_2ml",
        "0.2 mL PCR tube (one of a strip's), modelled with a screw cap",
        200.0,
        PCR_TUBE_TOLERANCES,
    ),
    tube(
        "tube_1_5ml",
        "1.5 mL snap-cap microcentrifuge tube, modelled with a screw cap",
        1500.0,
        MICROTUBE_TOLERANCES,
    ),
    tube(
        "tube_15ml",
        "15 mL screw-cap conical tube",
        15_000.0,
        TUBE_TOLERANCES,
    ),
    tube(
        "tube_50ml",
        "50 mL screw-cap conical tube",
        50_000.0,
        TUBE_TOLERANCES,
    ),
    tube(
        "cryovial",
        "2 mL screw-cap cryovial",
        2000.0,
        MICROTUBE_TOLERANCES,
    ),
    pipette(
        "pipette",
        "single-channel air-displacement pipette with a 1000 µL tip (a P1000: 100-1000 µL)",
        1000.0,
        P1000_PANEL,
    ),
    pipette(
        "pipette_p200",
        "single-channel air-displacement pipette with a 200 µL tip (a P200: 20-200 µL)",
        200.0,
        P200_PANEL,
    ),
];

pub fn kind(name: &str) -> Option<&'static LabwareKind> {
    KINDS.iter().find(|k| k.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_names_and_opposites() {
        let grid = SlotLayout::Grid { rows: 2, cols: 5 };
        assert_eq!(grid.names().len(), 10);
        assert_eq!(grid.names()[0], "A1");
        assert_eq!(grid.names()[9], "B5");
        let ring = SlotLayout::Ring { n: 30 };
        assert_eq!(ring.opposite("1").as_deref(), Some("16"));
        assert_eq!(ring.opposite("20").as_deref(), Some("5"));
        assert_eq!(ring.opposite("31"), None);
    }

    #[test]
    fn every_kind_is_consistent() {
        for k in KINDS {
            for p in k.parts {
                assert!(p.initial.iter().all(|s| p.states.contains(s)), "{}", k.name);
            }
            for b in k.buttons {
                match b.effect {
                    ButtonEffect::Toggle { part, .. } => assert!(k.part(part).is_some()),
                    ButtonEffect::Step { param, .. } => assert!(k.panel_param(param).is_some()),
                    ButtonEffect::Release { part, from, to } => {
                        let p = k.part(part).expect("a released part exists");
                        assert!(p.states.contains(&from) && p.states.contains(&to));
                    }
                    ButtonEffect::Start => assert!(k.part(crate::run::RUN).is_some()),
                }
            }
            for p in k.panel {
                // A dial may rest at its stop, below the speeds it sets.
                let floor = if p.dial.is_some() { 0.0 } else { p.min };
                assert!(floor <= p.initial && p.initial <= p.max, "{}", p.name);
            }
        }
    }
}
