//! An Opentrons run's thermocycler: its lid opened and shut by the second arm (the pipetting arm
//! retracted first) and its profile, checked against the cycler's range, run as `thermocycle`.

use super::*;

impl Walk<'_> {
    pub(super) fn cycler(&mut self, c: &Command, module_id: &str) -> Option<String> {
        let name = self.cyclers.get(module_id).cloned();
        if name.is_none() && !self.refused.contains(module_id) {
            self.error(
                Code::E0041,
                c.param_path("moduleId"),
                format!(
                    "{}: module `{module_id}` is no loaded thermocycler",
                    c.label()
                ),
                "a `loadModule` of a thermocycler must load it first",
            );
        }
        name
    }

    pub(super) fn lid(&mut self, c: &Command) {
        let Some(p) = self.params::<ModuleRef>(c) else {
            return;
        };
        let Some(cycler) = self.cycler(c, &p.module_id) else {
            return;
        };
        let close = c.command_type.ends_with("closeLid");
        let state = if close { "closed" } else { "open" };
        if self.first_lid.is_none() {
            self.first_lid = Some(if close { "open" } else { "closed" });
        }
        if self.lid_state == Some(state) {
            return;
        }
        if close && self.pipetted_since_lid {
            // The pipetting arm stands back first: the lid swings over where it worked.
            self.steps.push(Step {
                primitive: "retract".into(),
                args: vec![],
                with: self.robot(0),
                from: Some(format!(
                    "before {}: the pipetting arm out of the lid's way",
                    c.label()
                )),
            });
        }
        self.pipetted_since_lid = false;
        self.lid_state = Some(state);
        self.steps.push(Step {
            primitive: if close { "close_lid" } else { "open_lid" }.into(),
            args: vec![("on".into(), cycler)],
            with: self.robot(1),
            from: Some(c.label()),
        });
    }

    pub(super) fn profile(&mut self, c: &Command, module_id: &str, elements: &[ProfileElement]) {
        let Some(cycler) = self.cycler(c, module_id) else {
            return;
        };
        // Profiles run back to back (an analysis writes each `execute_profile` as its own)
        // are one profile to our cycler: the holds of the second follow the first's.
        let follows = self.ran_profile
            && self.steps.last().is_some_and(|s| {
                s.primitive == "thermocycle" && s.args.first().is_some_and(|(_, on)| *on == cycler)
            });
        if self.ran_profile && !follows {
            self.error(
                Code::E0042,
                c.path(),
                format!("{}: a second profile on the cycler", c.label()),
                "our cycler runs one profile per protocol (profiles back to back are one): put every hold and cycle in one",
            );
            return;
        }
        let mut bad = None;
        for e in elements {
            let (steps, repetitions) = match e {
                ProfileElement::Step(s) => (std::slice::from_ref(s), 1),
                ProfileElement::Cycle { steps, repetitions } => (steps.as_slice(), *repetitions),
            };
            if steps.is_empty() || repetitions == 0 || repetitions > 1000 {
                bad = Some(format!(
                    "a cycle of {} holds repeated {repetitions} times",
                    steps.len()
                ));
            }
            for s in steps {
                if !(s.hold_seconds.is_finite()
                    && s.hold_seconds > 0.0
                    && s.hold_seconds <= 86_400.0)
                {
                    bad = Some(format!("a hold of {} s", s.hold_seconds));
                } else if !(s.celsius.is_finite() && (4.0..=99.0).contains(&s.celsius)) {
                    bad = Some(format!("a hold at {} °C", s.celsius));
                }
            }
        }
        if let Some(what) = bad {
            self.error(
                Code::E0044,
                c.param_path(""),
                format!("{}: {what}", c.label()),
                "holds last more than 0 s and up to a day, at 4 to 99 °C (the cycler's block); cycles repeat 1 to 1,000 times and hold something",
            );
            return;
        }
        self.ran_profile = true;
        let holds: f64 = elements
            .iter()
            .map(|e| match e {
                ProfileElement::Step(s) => s.hold_seconds,
                ProfileElement::Cycle { steps, repetitions } => {
                    f64::from(*repetitions) * steps.iter().map(|s| s.hold_seconds).sum::<f64>()
                }
            })
            .sum();
        self.profile_s += holds;
        if follows {
            let last = self.steps.last_mut().expect("checked above");
            if let Some((_, text)) = last.args.iter_mut().find(|(k, _)| k == "profile") {
                text.push_str(", ");
                text.push_str(&commands::profile_text(elements));
            }
            if let Some(from) = &mut last.from {
                from.push_str(&format!(" and {}", c.label()));
            }
            return;
        }
        self.steps.push(Step {
            primitive: "thermocycle".into(),
            args: vec![
                ("on".into(), cycler),
                ("profile".into(), commands::profile_text(elements)),
            ],
            with: self.robot(1),
            from: Some(c.label()),
        });
    }
}
