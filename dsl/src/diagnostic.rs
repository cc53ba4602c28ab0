//! Diagnostics as data: code, severity, span, message, hint. No formatting for terminals here.

use serde::Serialize;

/// A half-open byte range into the protocol source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Default)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }
}

impl From<std::ops::Range<usize>> for Span {
    fn from(r: std::ops::Range<usize>) -> Self {
        Span::new(r.start, r.end)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
}

/// Stable diagnostic codes. The number never changes meaning once released; `autobio explain`
/// prints [`Code::explanation`]. `E` codes are errors, `W` codes warnings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Code {
    /// The file is not valid TOML.
    E0001,
    /// A required table or key is missing.
    E0002,
    /// A key the language does not define.
    E0003,
    /// A value of the wrong type.
    E0004,
    /// Unsupported format version.
    E0005,
    /// A chain stage cannot be loaded.
    E0006,
    /// The same setting given twice, under two spellings.
    E0007,
    /// The file is not UTF-8 text.
    E0008,
    /// A chain stage path the chain may not read.
    E0009,
    /// Unknown labware kind.
    E0010,
    /// Unknown robot model.
    E0011,
    /// Unknown lab primitive.
    E0012,
    /// A name that refers to nothing declared.
    E0013,
    /// A primitive applied to labware that does not support it.
    E0014,
    /// A name declared twice.
    E0015,
    /// An unknown or unusable start place: a slot, or a hand (`held_by`).
    E0016,
    /// An initial state the labware kind does not have.
    E0017,
    /// A quantity with a missing, unknown or wrong unit.
    E0020,
    /// A value outside its allowed range.
    E0021,
    /// A parameter with no usable domain.
    E0022,
    /// An unknown placeholder.
    E0023,
    /// A pose off the bench and out of every robot's reach.
    E0024,
    /// A success predicate that cannot be read.
    E0030,
    /// A step whose precondition does not hold.
    E0031,
    /// A missing or unknown primitive argument.
    E0032,
    /// The plan does not reach the success condition.
    E0033,
    /// A chain stage that does not fit the chain's scene.
    E0034,
    /// An unknown or ill-typed tolerance.
    E0035,
    /// A step whose robot cannot reach its target.
    E0036,
    /// A centrifuge run with an unbalanced rotor.
    E0037,
    /// An instrument run started while its lid is not shut and latched.
    E0038,
    /// A time the plan cannot keep: a time constraint, or runs and waits past the time limit.
    E0039,
    /// An import source that cannot be read.
    E0040,
    /// A reference in the import source that names nothing, or names two things.
    E0041,
    /// An imported command with no robot realisation here.
    E0042,
    /// Imported labware with no kind here.
    E0043,
    /// An imported value that is out of range.
    E0044,
    /// A perturbation the task cannot take: a paraphrase that drops or adds a parameter, a camera
    /// turned or moved off the work, a camera it names that the task does not have, distractors
    /// on a bench with no free place.
    E0045,
    /// The success condition already holds at the start.
    W0001,
    /// The state proof sampled parameter combinations.
    W0002,
    /// A position far outside any bench.
    W0003,
    /// A time limit no episode can mean.
    W0004,
    /// Weights under binary scoring, which ignores them.
    W0005,
    /// A Greek mu where the micro sign is meant.
    W0006,
    /// A start state the simulator cannot set up yet.
    W0007,
    /// A later chain stage's declaration that the chain ignores.
    W0008,
    /// A panel value the instrument cannot reach within the time limit.
    W0009,
    /// A step its robot reaches in some sampled layouts only.
    W0010,
    /// An imported command dropped.
    W0011,
}

impl Code {
    pub fn as_str(self) -> &'static str {
        match self {
            Code::E0001 => "E0001",
            Code::E0002 => "E0002",
            Code::E0003 => "E0003",
            Code::E0004 => "E0004",
            Code::E0005 => "E0005",
            Code::E0006 => "E0006",
            Code::E0007 => "E0007",
            Code::E0008 => "E0008",
            Code::E0009 => "E0009",
            Code::E0010 => "E0010",
            Code::E0011 => "E0011",
            Code::E0012 => "E0012",
            Code::E0013 => "E0013",
            Code::E0014 => "E0014",
            Code::E0015 => "E0015",
            Code::E0016 => "E0016",
            Code::E0017 => "E0017",
            Code::E0020 => "E0020",
            Code::E0021 => "E0021",
            Code::E0022 => "E0022",
            Code::E0023 => "E0023",
            Code::E0024 => "E0024",
            Code::E0030 => "E0030",
            Code::E0031 => "E0031",
            Code::E0032 => "E0032",
            Code::E0033 => "E0033",
            Code::E0034 => "E0034",
            Code::E0035 => "E0035",
            Code::E0036 => "E0036",
            Code::E0037 => "E0037",
            Code::E0038 => "E0038",
            Code::E0039 => "E0039",
            Code::E0040 => "E0040",
            Code::E0041 => "E0041",
            Code::E0042 => "E0042",
            Code::E0043 => "E0043",
            Code::E0044 => "E0044",
            Code::E0045 => "E0045",
            Code::W0001 => "W0001",
            Code::W0002 => "W0002",
            Code::W0003 => "W0003",
            Code::W0004 => "W0004",
            Code::W0005 => "W0005",
            Code::W0006 => "W0006",
            Code::W0007 => "W0007",
            Code::W0008 => "W0008",
            Code::W0009 => "W0009",
            Code::W0010 => "W0010",
            Code::W0011 => "W0011",
        }
    }

    pub const ALL: [Code; 49] = [
        Code::E0001,
        Code::E0002,
        Code::E0003,
        Code::E0004,
        Code::E0005,
        Code::E0006,
        Code::E0007,
        Code::E0008,
        Code::E0009,
        Code::E0010,
        Code::E0011,
        Code::E0012,
        Code::E0013,
        Code::E0014,
        Code::E0015,
        Code::E0016,
        Code::E0017,
        Code::E0020,
        Code::E0021,
        Code::E0022,
        Code::E0023,
        Code::E0024,
        Code::E0030,
        Code::E0031,
        Code::E0032,
        Code::E0033,
        Code::E0034,
        Code::E0035,
        Code::E0036,
        Code::E0037,
        Code::E0038,
        Code::E0039,
        Code::E0040,
        Code::E0041,
        Code::E0042,
        Code::E0043,
        Code::E0044,
        Code::E0045,
        Code::W0001,
        Code::W0002,
        Code::W0003,
        Code::W0004,
        Code::W0005,
        Code::W0006,
        Code::W0007,
        Code::W0008,
        Code::W0009,
        Code::W0010,
        Code::W0011,
    ];

    pub fn from_name(name: &str) -> Option<Code> {
        Code::ALL
            .into_iter()
            .find(|c| c.as_str().eq_ignore_ascii_case(name))
    }

    /// One line: what the code means.
    pub fn summary(self) -> &'static str {
        match self {
            Code::E0001 => "the file is not valid TOML",
            Code::E0002 => "a required table or key is missing",
            Code::E0003 => "a key the language does not define",
            Code::E0004 => "a value of the wrong type",
            Code::E0005 => "unsupported format version",
            Code::E0006 => "a chain stage cannot be loaded",
            Code::E0007 => "the same setting given twice, under two spellings",
            Code::E0008 => "the file is not UTF-8 text",
            Code::E0009 => "a chain stage path the chain may not read",
            Code::E0010 => "unknown labware kind",
            Code::E0011 => "unknown robot model",
            Code::E0012 => "unknown lab primitive",
            Code::E0013 => "a name that refers to nothing declared",
            Code::E0014 => "a primitive applied to labware that does not support it",
            Code::E0015 => "a name declared twice",
            Code::E0016 => "an unknown or unusable slot or hand",
            Code::E0017 => "an initial state the labware kind does not have",
            Code::E0020 => "a quantity with a missing, unknown or wrong unit",
            Code::E0021 => "a value outside its allowed range",
            Code::E0022 => "a parameter with no usable domain",
            Code::E0023 => "an unknown placeholder",
            Code::E0024 => "a pose off the bench and out of every robot's reach",
            Code::E0030 => "a success predicate that cannot be read",
            Code::E0031 => "a step whose precondition does not hold",
            Code::E0032 => "a missing or unknown primitive argument",
            Code::E0033 => "the plan does not reach the success condition",
            Code::E0034 => "a chain stage that does not fit the chain's scene",
            Code::E0035 => "an unknown or ill-typed tolerance",
            Code::E0036 => "a step whose robot cannot reach its target",
            Code::E0037 => "a centrifuge run with an unbalanced rotor",
            Code::E0038 => "an instrument run started with its lid not shut and latched",
            Code::E0039 => "a time the plan cannot keep",
            Code::E0040 => "the import source cannot be read",
            Code::E0041 => {
                "a reference in the import source that resolves to nothing or to several things"
            }
            Code::E0042 => "an imported command with no robot realisation here",
            Code::E0043 => "imported labware with no kind here",
            Code::E0044 => "an imported value out of range",
            Code::E0045 => "a perturbation the task cannot take",
            Code::W0001 => "the success condition already holds at the start",
            Code::W0002 => "the state proof sampled parameter combinations",
            Code::W0003 => "a position far outside any bench",
            Code::W0004 => "a time limit no episode can mean",
            Code::W0005 => "weights under binary scoring, which ignores them",
            Code::W0006 => "a Greek mu where the micro sign is meant",
            Code::W0007 => "a start state the simulator cannot set up yet",
            Code::W0008 => "a later chain stage's declaration that the chain ignores",
            Code::W0009 => "a panel value the instrument cannot reach within the time limit",
            Code::W0010 => "a step its robot reaches in some sampled layouts only",
            Code::W0011 => "an imported command dropped",
        }
    }

    /// Long-form documentation, printed by `autobio explain CODE`.
    pub fn explanation(self) -> &'static str {
        match self {
            Code::E0001 => {
                "The protocol file is not valid TOML (an unclosed string or table header, a duplicate key...).\nFix the syntax at the marked place; nothing else in the file is checked until it parses."
            }
            Code::E0002 => {
                "A table or key that every protocol needs is missing: `[protocol]` with `id`, `instruction` and\n`time_limit`, at least one `[[steps]]` with `do`, `[success]` with `all`; in a chain file `[chain]`\nwith `id` and at least one `[[stages]]` with `protocol`."
            }
            Code::E0003 => {
                "The key is not part of the protocol language (format 1). Usually a typo: the hint names the\nclosest known key. See docs/protocol-language.md for every table and key."
            }
            Code::E0004 => {
                "The value has the wrong TOML type, e.g. a number where a string is expected, or a table where\nan array of tables (`[[steps]]`) is expected."
            }
            Code::E0005 => {
                "The file declares a `format` this autobio does not read. Format 1 is the current one. A new\nformat number is issued only when a file valid in the old format would be read differently."
            }
            Code::E0006 => {
                "A chain's `[[stages]]` entry names a file that cannot be read, that is not a protocol (none of\nits text is shown), or that is itself a chain. Errors inside a stage file are reported with their\nown file and line and a note naming the chain line. Paths are relative to the chain file."
            }
            Code::E0007 => {
                "A setting is given twice in one table under two spellings, e.g. `time_limit = \"30 s\"` and\n`time_limit_s = 30`, or `pos_m` and `pos_mm`. Neither wins silently: keep one."
            }
            Code::E0008 => {
                "Protocol files are UTF-8 text. The marked place is the first byte that is not valid UTF-8;\nre-save the file as UTF-8 (most editors offer it under \"encoding\")."
            }
            Code::E0009 => {
                "A chain reads its stage files only from inside its protocol root (the chain's folder, or the\nfolder given with `--root`), and only regular files of at most 1 MiB. A stage path that leaves\nthe root (`../..`, an absolute path, a symbolic link pointing out), names a device, a folder or\na larger file is refused, and nothing of that file is shown."
            }
            Code::E0010 => {
                "`kind` names no labware in the catalogue. `autobio describe --catalogue` lists the kinds with\ntheir parts, slots and primitives."
            }
            Code::E0011 => "`model` names no robot in the catalogue. Known models: ur5e_2f85.",
            Code::E0012 => {
                "`do` names no lab primitive in the catalogue. `autobio describe --catalogue` lists every\nprimitive with its arguments, the states it needs and the states it leaves."
            }
            Code::E0013 => {
                "A step, parameter, randomisation or predicate refers to a name that is not declared under\n`[labware]`, `[robots]` or `[params]`."
            }
            Code::E0014 => {
                "The primitive exists but this labware kind has no affordance for it (e.g. `open_lid` on a\ntube, `unscrew_cap` on a rack). The hint lists what the kind supports."
            }
            Code::E0015 => {
                "Robots, labware and parameters share one namespace: every name must be unique in a protocol."
            }
            Code::E0016 => {
                "A location `<holder>.<slot>` names a holder without slots, a slot the holder does not have, a\nslot that does not accept this kind of item, or a slot two items start in; or `held_by` puts in\na hand an item that cannot be held (a fixed instrument), one that also starts in a slot (`at`),\nor a second item in a hand that already holds one."
            }
            Code::E0017 => {
                "`state = { .. }` sets a part, panel value or volume the kind does not have, or a state the part\ncannot start in (a lid cannot start `unlocked`; declare `closed`)."
            }
            Code::E0020 => {
                "A physical quantity has no unit, an unknown unit, or a unit of the wrong dimension.\nWrite quantities as strings with units (\"30 s\", \"5 deg\", \"10 mm\", \"200 µL\", \"37 °C\",\n\"1200 rpm\") or use a unit-suffixed key (`pos_m`, `yaw_deg`, `xy_mm`)."
            }
            Code::E0021 => {
                "The value is outside the range the language or the instrument allows (a negative time limit, a\nrange whose low end exceeds its high end, a panel value the instrument cannot show, a volume\nlarger than the container)."
            }
            Code::E0022 => {
                "A `[params.<name>]` table must have exactly one domain (`choice`, `int`, `real` or `slot`), and\nits exclusions must leave at least one value to draw."
            }
            Code::E0023 => {
                "A `{name}` placeholder in an instruction, step argument, location or predicate names no\nparameter declared under `[params]` (or one declared after the parameter that uses it)."
            }
            Code::E0024 => {
                "A labware pose that is neither over the bench nor within any robot's reach, or any pose\nhundreds of metres away: no task can use it, and it is almost always millimetres written\nunder `pos_m` (write `pos_mm = [..]`, or the value in metres). Over the bench, or within\na robot's reach (an item on a riser beside its arm), a pose is fine."
            }
            Code::E0030 => {
                "A success predicate must be one of the forms in docs/protocol-language.md, e.g.\n\"cycler.lid is closed\", \"tube in rack.{slot}\", \"tube.volume = 200 µL\",\n\"mixer.speed = {rpm} rpm\", \"arm touches tube\", \"cycler.lid in [-1.95, -1.85] rad\"; the names,\nparts and states must exist for the labware kind."
            }
            Code::E0031 => {
                "Each primitive declares the state it needs; tracing the steps from the declared initial state\n(through every earlier stage of a chain, and for every value of the parameters), this step would\nstart where its precondition does not hold (closing a lid that is already closed, picking with a\nhand that is full, aspirating more than the container holds)."
            }
            Code::E0032 => {
                "The step is missing an argument its primitive requires, or passes one it does not take. The\nhint lists the primitive's signature."
            }
            Code::E0033 => {
                "Traced to its end, the plan leaves a state in which a success predicate is false, so even a\nperfect execution would fail. Fix the steps or the predicate."
            }
            Code::E0034 => {
                "Every stage of a chain runs on the first stage's scene: a later stage must declare the same robots\nand labware, no more and no fewer, with the same models and kinds, where the first stage puts them\n(a robot's base, a labware pose). The bench does not move between stages. What a later stage\nsays about the start (initial states, randomisation, camera) is ignored: see W0008."
            }
            Code::E0035 => {
                "`[tolerances]` names a tolerance no predicate of this protocol uses, or gives it a unit of the\nwrong dimension; a predicate's `within` must match what the predicate measures."
            }
            Code::E0036 => {
                "The robot a step names cannot bring its tool to the step's first target (the grasp, press or\ndial frame the expert aims at): its inverse kinematics, from the robot's start pose and from its\nhome, in either grasp of a symmetric target, find no solution, in the layout the task's first\nseed draws. The hint names the nearest base position, at the same heading, from which every\ntarget checked for that robot, in all eight sampled layouts, solves with 10 cm to spare: at\nthe robot's height first, else raised (a riser). `autobio check` tests each step's first\ntarget and the point the arm comes in from, the path it then follows holding a part (a lid's\narc, a pick's lift) and the slot it places a picked item in. A target the arm reaches only with\na joint past its range names that joint and the angle it would need instead of a distance. The\nnext seven seeds' layouts are W0010's; free-space paths between targets are not tested."
            }
            Code::E0037 => {
                "A centrifuge refuses to spin an unbalanced load, and so does the proof: the tubes in its rotor\nwhen a `spin` starts must balance, each tube's mass (1 g for a 1.5 mL tube, plus its liquid\nat 1 mg/µL) times its slot's direction summing to under 0.1 g. Put tubes in opposite slots\n(`1` and `16` on a 30-place rotor), or three 120° apart, with equal volumes; add a tube of water\nas a counterweight; the hint names the slots that would balance."
            }
            Code::E0038 => {
                "An instrument runs only shut: a centrifuge spins with its lid latched, a thermal cycler runs its\nprofile with its lid closed and locked (that is what starts it). Close (and lock) the lid in a\nstep before the run."
            }
            Code::E0039 => {
                "The plan's own waits and instrument runs take at least the time shown, so no execution can\nkeep the time: a `within` constraint between two steps is broken by what lies between them, or\nthe stage's `time_limit` is shorter than its runs and waits (motions need time on top).\nShorten the waits or runs between the steps, move the constraint, or raise `time_limit`."
            }
            Code::E0040 => {
                "`autobio import` could not read the file as one of the formats it imports: it is not JSON (the\nparser's line and column are shown), or it is JSON of another shape, a protocol schema other than\n8, or a file whose `commands` are missing, or an analysis whose run failed; for Autoprotocol, `refs`\nthat are not an object, `instructions` that are not a list, an instruction with no `op`. Import an\nOpentrons analysis (`opentrons analyze --json-output`), a Protocol Designer file saved as schema 8\nor an Autoprotocol document (`refs`, `instructions`)."
            }
            Code::E0041 => {
                "A command of the imported file refers to an id no earlier `load*` command gave (a labware,\npipette, module or liquid), to a well its labware does not have, to labware standing on itself,\nor an id two load commands both give (an analysis snapshot whose ids were all replaced by\n`UUID` cannot be imported). Its parameters may also not fit the command's schema: the message\nquotes what serde found. In Autoprotocol: an aliquot naming no ref or a well its container does\nnot have, a ref with both `id` and `new`, a time constraint's point naming no point or two."
            }
            Code::E0042 => {
                "The command has no step on our bench: a module we have no model of (magnetic, temperature,\nheater-shaker, plate reader, stacker), moving labware with a gripper, pipetting without a well,\na multi-channel or second pipette, volumes that change between steps (the hand-held pipette has\nno knob), an aspirate not followed by its dispense; in Autoprotocol, `spin` and `incubate` (not yet), an\ninstrument we have no model of, an unknown `op`, a multi-channel `shape`, a gradient. Remove it\nfrom the source, write that part in our language by hand, or (for an instrument we have no model\nof) keep it as an instrument-only step with `autobio import --keep-instrument-steps`.\ndocs/import.md lists what maps to what."
            }
            Code::E0043 => {
                "The `loadLabware`'s definition is neither a kind made from the same published definition (any\nversion), a 96-well PCR plate (realised as PCR tubes in a block), a tip rack nor a trash; or its\ndefinition is neither in the file nor installed by `make setup`; or an Autoprotocol ref whose\ncontainer type has no kind here (`96-pcr` and `micro-1.5` have), or whose type the file does not\nstate (an `id` ref). `autobio describe --catalogue` lists the kinds made from published definitions."
            }
            Code::E0044 => {
                "A number in the imported file cannot be used: a volume larger than the tube a well becomes holds,\na negative or non-finite volume or time, a volume no hand-held pipette here sets (the P200 sets\n20-200 µL, the P1000 100-1000 µL); an Autoprotocol quantity that does not read as `number:unit`\nor whose unit is of the wrong kind (the message lists the units the field takes)."
            }
            Code::E0045 => {
                "A `[perturb]` dimension or a paraphrase would change what the task is, not how it looks or is\nsaid: a paraphrase (`[protocol] paraphrases`) must name every `{param}` the instruction names\nand no other, or an episode would be told a different task; `perturb.camera` may not turn or\nmove a fixed camera so far that what it is aimed at (the clean view's centre) could leave the\ninner half of its shaken view (its field of view at its narrowest, the shift seen from the\nitems' middle), and its `cameras` must name the task's cameras (`table_front`, `<robot>/wrist`);\n`perturb.distractors` needs a free place on the bench (20 cm from every item, 30 cm from\nevery robot's base, 15 cm from the way between them). Narrow `shift_m`, `turn_deg` or\n`fovy_deg`, fix the paraphrase, or leave distractors out of a crowded bench. docs/robustness.md describes every dimension."
            }
            Code::W0001 => {
                "Every success predicate is already true in the initial state, so an episode succeeds before the\nrobot moves. Usually an initial `state` or a predicate is wrong. A round trip (open a lid, then\nclose it) is written with `was` (`cycler.lid was open` beside `cycler.lid is closed`) or as a chain. `eval` and `demo` refuse the task unless `--allow-trivial`."
            }
            Code::W0002 => {
                "The parameters have too many combinations to trace them all; the proof traced a deterministic\nsample of them. Narrow the domains for an exhaustive proof."
            }
            Code::W0003 => {
                "A randomisation moves an item metres across the bench (`xy` over 1 m; the world origin is\nthe bench's centre). Usually millimetres written under a metre key: `xy_m = 20` means 20 m.\nWrite `xy_mm`, or the value in metres. A pose itself that far away is an error, E0024."
            }
            Code::W0004 => {
                "A time limit shorter than one control period (20 ms) ends every episode before the robot\nacts; one longer than a day is almost always a unit slip (`ms` for `s`, `min` for `s`)."
            }
            Code::W0005 => {
                "`[success] weights` apply only under `scoring = \"progress\"`; binary scoring (the default)\nscores 1 when every predicate holds and 0 otherwise, and ignores them."
            }
            Code::W0006 => {
                "`μ` (U+03BC, GREEK SMALL LETTER MU) looks like the micro sign `µ` (U+00B5) that `µL` is\nwritten with. The unit is read as microlitres; write `µL` or `uL` to silence this."
            }
            Code::W0007 => {
                "The language allows this start state, but the item's simulation model cannot set it up yet\n(no shipped model refuses one today: a tube whose cap starts off is built open). The protocol\nchecks and compiles; `eval` and `demo` refuse to build its scene. `autobio describe --catalogue`\nmarks such states."
            }
            Code::W0008 => {
                "A later stage of a chain starts where the stage before it ended: the state is carried over\n(traced by the proof), the scene is drawn once from the first stage's randomisation and seen\nfrom the first stage's camera. This stage file declares a start state that differs from the one\ncarried over to it, or a randomisation or camera that differs from the first stage's; in the\nchain these are ignored. Make them agree, or leave the stage to run alone."
            }
            Code::W0009 => {
                "`set_parameter` sets a panel's target; the instrument then ramps towards it at its own rate\n(a block heats a few degrees a second). The value set here is not reached within the task's\ntime limit even if the step ran at once, so a predicate on the measured value cannot hold.\nThe hint gives the time it needs: raise `time_limit`, or set a value nearer the start."
            }
            Code::W0010 => {
                "The step's robot reaches its targets (as E0036 checks them) in the layout the task's first\nseed draws, but not in some of the next seven: another slot drawn, labware placed elsewhere\nwithin its randomisation. The task checks and runs; those seeds' episodes will fail at\nplanning. The note gives what the first such seed draws; the hint names a base from which\nevery sampled layout is reached, where one is found (as E0036's); or narrow the draws."
            }
            Code::W0011 => {
                "A command of the imported file does what our steps do themselves or what a hand-held pipette\nhas no step for: tips picked up and dropped (the pipette's tip is its own here), homing and moves\nbetween wells (each step moves there), blow-out and touch-tip (our dispense does both), comments\nand pauses for a person. It is dropped; the warning counts them, per type, at the first."
            }
        }
    }

    pub fn is_warning(self) -> bool {
        self.as_str().starts_with('W')
    }

    /// A finding of `autobio import` about the file it reads (E0040..E0044, W0011), not about a
    /// protocol file.
    pub fn is_import(self) -> bool {
        matches!(
            self,
            Code::E0040 | Code::E0041 | Code::E0042 | Code::E0043 | Code::E0044 | Code::W0011
        )
    }
}

impl std::fmt::Display for Code {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One problem found in a protocol file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnostic {
    pub code: Code,
    pub severity: Severity,
    pub span: Span,
    /// Lowercase, quotes the offending input with backticks.
    pub message: String,
    pub hint: Option<String>,
    /// The file the span points into, when it is not the file being checked (a chain's stage).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Extra context lines (`note: ...`), e.g. which parameter values break a proof.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl Diagnostic {
    pub fn error(code: Code, span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            code,
            severity: if code.is_warning() {
                Severity::Warning
            } else {
                Severity::Error
            },
            span,
            message: message.into(),
            hint: None,
            file: None,
            notes: Vec::new(),
        }
    }

    /// A diagnostic of `code`; the severity follows the code (`W` codes are warnings).
    pub fn new(code: Code, span: Span, message: impl Into<String>) -> Self {
        Diagnostic::error(code, span, message)
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// The closest candidate by edit distance, if it is close enough to be a plausible typo.
pub fn did_you_mean<'a>(
    input: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (levenshtein(input, c), c))
        .filter(|(d, c)| *d <= (c.len().max(input.len()) / 3).max(1) + usize::from(c.len() > 8))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_close_names_only() {
        assert_eq!(
            did_you_mean("thermal_cycle", ["thermal_cycler", "centrifuge"]),
            Some("thermal_cycler")
        );
        assert_eq!(
            did_you_mean("close_lidd", ["open_lid", "close_lid"]),
            Some("close_lid")
        );
        assert_eq!(did_you_mean("zzz", ["thermal_cycler"]), None);
    }

    #[test]
    fn codes_round_trip() {
        for c in Code::ALL {
            assert_eq!(Code::from_name(c.as_str()), Some(c));
            assert!(!c.explanation().is_empty());
        }
    }
}
