//! An Opentrons run's liquids and pipetting: `loadLiquid` as start volumes of named liquids (one
//! name per source liquid), and `aspirate`/`dispense` as steps of the hand-held pipette set to the
//! run's one volume, with each tube's liquids booked in proportion as the pipetting process moves
//! them (the written success is what the run leaves).

use super::*;

impl Walk<'_> {
    pub(super) fn load_liquid(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadLiquid>(c) else {
            return;
        };
        let Some(info) = self.src.liquids.get(&p.liquid_id) else {
            self.error(
                Code::E0041,
                c.param_path("liquidId"),
                format!(
                    "{}: liquid `{}` is not among the file's liquids",
                    c.label(),
                    p.liquid_id
                ),
                "declare it under `liquids`",
            );
            return;
        };
        let liquid = self.liquid(&info.display_name, &p.liquid_id);
        for (well, volume) in &p.volume_by_well {
            let Some(key) = self.tube(c, &p.labware_id, well) else {
                continue;
            };
            let capacity = labware::kind(self.tubes[&key].kind)
                .and_then(|k| k.capacity_ul)
                .unwrap_or(0.0);
            let before = self.tubes[&key].volume(&self.tubes[&key].start);
            if !(volume.is_finite() && *volume >= 0.0 && before + *volume <= capacity) {
                let mut at = c.param_path("volumeByWell");
                at.push(Key::field(well));
                self.error(
                    Code::E0044,
                    at,
                    format!(
                        "{}: {volume} µL in well `{well}`, whose tube here (`{}`) holds {} µL",
                        c.label(),
                        self.tubes[&key].kind,
                        draft::number(capacity)
                    ),
                    "a well starts with 0 µL up to what its tube holds",
                );
                continue;
            }
            let t = self.tubes.get_mut(&key).expect("made above");
            if t.start.keys().any(|l| *l != liquid) {
                let mut at = c.param_path("volumeByWell");
                at.push(Key::field(well));
                self.error(
                    Code::E0042,
                    at,
                    format!("{}: a second liquid loaded into well `{well}`", c.label()),
                    "a tube here starts with one named liquid",
                );
                continue;
            }
            *t.start.entry(liquid.clone()).or_default() += volume;
            *t.now.entry(liquid.clone()).or_default() += volume;
        }
    }

    /// A liquid's name in our language, one per source liquid: a name two liquids would share gets
    /// the second one's id appended.
    pub(super) fn liquid(&mut self, display: &str, id: &str) -> String {
        if let Some(name) = self.liquid_names.get(id) {
            return name.clone();
        }
        let mut name = liquid_name(display, id);
        if self.liquid_names.values().any(|n| *n == name) {
            let suffix: String = id.chars().filter(|c| c.is_ascii_alphanumeric()).collect();
            name = format!(
                "{}_{}",
                &name[..name.len().min(30)],
                suffix.chars().take(8).collect::<String>()
            );
            let mut n = 2;
            while self.liquid_names.values().any(|x| *x == name) {
                name = format!("{}_{n}", &name[..name.len().min(36)]);
                n += 1;
            }
        }
        self.liquid_names.insert(id.to_string(), name.clone());
        name
    }

    pub(super) fn pipetting(&mut self, c: &Command) {
        let Some(p) = self.params::<Pipetting>(c) else {
            return;
        };
        let Some((_, name)) = self.pipettes.get(&p.pipette_id).cloned() else {
            self.error(
                Code::E0041,
                c.param_path("pipetteId"),
                format!("{}: pipette `{}` was never loaded", c.label(), p.pipette_id),
                "a `loadPipette` must load it first",
            );
            return;
        };
        if name.contains("multi") || name.contains("_96") {
            self.error(
                Code::E0042,
                c.param_path("pipetteId"),
                format!("{}: `{name}` is a multi-channel pipette", c.label()),
                "a hand holds a single-channel pipette here: use a single-channel one",
            );
            return;
        }
        if !(p.volume.is_finite() && p.volume > 0.0) {
            self.error(
                Code::E0044,
                c.param_path("volume"),
                format!("{}: {} µL is no volume to move", c.label(), p.volume),
                "a volume is a positive number of microlitres",
            );
            return;
        }
        match &self.pipette {
            None if !PIPETTES
                .iter()
                .any(|(_, lo, hi)| (lo..=hi).contains(&&p.volume)) =>
            {
                self.error(
                    Code::E0044,
                    c.param_path("volume"),
                    format!(
                        "{}: {} µL, which no hand-held pipette here sets",
                        c.label(),
                        draft::number(p.volume)
                    ),
                    "the P200 sets 20-200 µL, the P1000 100-1000 µL",
                );
                return;
            }
            None => self.pipette = Some((p.pipette_id.clone(), p.volume, c.index)),
            Some((id, _, first)) if *id != p.pipette_id => {
                let first = *first;
                self.error(
                    Code::E0042,
                    c.param_path("pipetteId"),
                    format!(
                        "{}: a second pipette (commands[{first}] pipetted with another)",
                        c.label()
                    ),
                    "one hand-held pipette per protocol here",
                );
                return;
            }
            Some((_, set, first)) if (*set - p.volume).abs() > 1e-9 => {
                let (set, first) = (*set, *first);
                // Each other volume is said once, at its first command.
                if !self.other_volumes.insert(p.volume.to_bits()) {
                    return;
                }
                self.error(
                    Code::E0042,
                    c.param_path("volume"),
                    format!(
                        "{}: {} µL, but the pipette is set to {} µL (commands[{first}])",
                        c.label(),
                        draft::number(p.volume),
                        draft::number(set)
                    ),
                    "the hand-held pipette has no knob: every aspirate and dispense moves the one volume it is set to",
                );
                return;
            }
            _ => {}
        }
        let aspirate = c.command_type == "aspirate";
        let Some(key) = self.tube(c, &p.labware_id, &p.well_name) else {
            // What was refused is said at its load; the tip's contents go on as the run has them.
            self.in_tip = aspirate.then(|| (BTreeMap::new(), c.index));
            return;
        };
        match (&self.in_tip, aspirate) {
            (Some((_, at)), true) => {
                let at = *at;
                self.error(
                    Code::E0042,
                    c.path(),
                    format!(
                        "{}: a second aspirate before commands[{at}]'s is dispensed",
                        c.label()
                    ),
                    "each aspirate is followed by its dispense here (no multi-dispense)",
                );
                return;
            }
            (None, false) => {
                self.error(
                    Code::E0042,
                    c.path(),
                    format!("{}: a dispense with nothing aspirated", c.label()),
                    "aspirate the volume first",
                );
                return;
            }
            _ => {}
        }
        let t = self.tubes.get_mut(&key).expect("made by tube()");
        t.touched = true;
        if aspirate {
            let have = t.volume(&t.now);
            if have + 1e-6 < p.volume {
                let msg = format!(
                    "{}: {} µL from well `{}`, which holds {} µL then",
                    c.label(),
                    draft::number(p.volume),
                    p.well_name,
                    draft::number(have)
                );
                self.in_tip = Some((BTreeMap::new(), c.index));
                self.error(
                    Code::E0044,
                    c.param_path("volume"),
                    msg,
                    "a well is drawn from only what a `loadLiquid` put there (or a dispense since)",
                );
                return;
            }
            let share: BTreeMap<String, f64> = t
                .now
                .iter()
                .map(|(l, v)| {
                    (
                        l.clone(),
                        if have > 0.0 { v * p.volume / have } else { 0.0 },
                    )
                })
                .collect();
            for (l, v) in &share {
                *t.now.get_mut(l).expect("present") -= v;
            }
            self.in_tip = Some((share, c.index));
        } else {
            let (tip, _) = self.in_tip.take().expect("checked above");
            for (l, v) in tip {
                *t.now.entry(l).or_default() += v;
            }
            t.dispensed_into = true;
        }
        let (item, primitive) = (t.name.clone(), c.command_type.clone());
        self.pipetted_since_lid = true;
        self.steps.push(Step {
            primitive,
            args: vec![
                ("on".into(), item),
                ("volume".into(), format!("{} µL", draft::number(p.volume))),
            ],
            with: self.robot(0),
            from: Some(c.label()),
        });
    }
}

/// A liquid's name as our language writes it: its display name in lower case, other characters
/// as `_`, starting with a letter (else `liquid_<id>`).
pub(super) fn liquid_name(display: &str, id: &str) -> String {
    let mut s: String = display
        .trim()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    while s.contains("__") {
        s = s.replace("__", "_");
    }
    let s = s.trim_matches('_').to_string();
    let ok = s.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && s.len() <= 40
        && !dsl::PREDICATE_WORDS.contains(&s.as_str());
    if ok {
        s
    } else {
        let id: String = id
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .take(30)
            .collect();
        format!("liquid_{id}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liquid_names_are_ours() {
        assert_eq!(liquid_name("Master Mix (2X)", "0"), "master_mix_2x");
        assert_eq!(liquid_name("H2O", "1"), "h2o");
        assert_eq!(liquid_name("10x buffer", "b-1"), "liquid_b1");
        assert_eq!(liquid_name("in", "2"), "liquid_2");
    }
}
