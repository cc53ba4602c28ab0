//! An Opentrons run's labware, modules and pipettes as they load: each `loadLabware` is a holder
//! here (by its published definition's load name), a PCR plate, or nothing (tip racks, trash);
//! the thermocycler is the cycler; every well the run uses becomes a tube on first use.

use super::*;

impl Walk<'_> {
    pub(super) fn load_labware(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadLabware>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.labware_id.clone(), "labwareId") else {
            return;
        };
        if let Some(first) = self.labware.get(&id).map(|l| l.command) {
            self.duplicate(c, "labwareId", &id, first);
            return;
        }
        let holder = self.holder(c, &p);
        let (on_cycler, slot) = match &p.location {
            Location::Slot { slot_name } => (None, Some(slot_name.clone())),
            Location::Module { module_id } => match self.cyclers.get(module_id) {
                Some(_) if matches!(holder, Some(Holder::Kind { .. })) => {
                    self.error(
                        Code::E0042,
                        c.param_path("location"),
                        format!(
                            "{}: `{}` on the thermocycler: only a 96-well PCR plate stands in the cycler's block here",
                            c.label(),
                            p.load_name
                        ),
                        "load a 96-well PCR plate on the thermocycler",
                    );
                    self.refused.insert(id);
                    return;
                }
                Some(_) => (Some(module_id.clone()), None),
                None if self.kept_modules.contains(module_id) => (None, None),
                None if self.refused.contains(module_id) => {
                    self.refused.insert(id);
                    return;
                }
                None => {
                    if !matches!(holder, Some(Holder::Ignored(_))) {
                        self.error(
                            Code::E0041,
                            c.param_path("location"),
                            format!(
                                "{}: `{}` stands on module `{module_id}`, which no realised `loadModule` loaded",
                                c.label(),
                                p.load_name
                            ),
                            "load the module before its labware; only the thermocycler is realised",
                        );
                    }
                    (None, None)
                }
            },
            Location::OnLabware { labware_id } => {
                let (code, why) = if *labware_id == id {
                    (
                        Code::E0041,
                        format!("{}: `{}` stands on itself", c.label(), p.load_name),
                    )
                } else if !self.labware.contains_key(labware_id) {
                    (
                        Code::E0041,
                        format!(
                            "{}: `{}` stands on `{labware_id}`, which no earlier `loadLabware` loaded",
                            c.label(),
                            p.load_name
                        ),
                    )
                } else {
                    (
                        Code::E0042,
                        format!(
                            "{}: `{}` stands on other labware (`{labware_id}`): adapters and stacks are not realised",
                            c.label(),
                            p.load_name
                        ),
                    )
                };
                if code == Code::E0041 || !matches!(holder, Some(Holder::Ignored(_))) {
                    self.error(
                        code,
                        c.param_path("location"),
                        why,
                        "load it in a deck slot",
                    );
                }
                self.refused.insert(id);
                return;
            }
            Location::Area { .. } | Location::Named(_) => (None, None),
        };
        let Some(holder) = holder else {
            self.refused.insert(id);
            return;
        };
        let base = match holder {
            Holder::Kind { kind, .. } if kind.starts_with("tuberack") => "rack",
            Holder::Kind { .. } => "block",
            Holder::Plate => "plate",
            Holder::Ignored(_) => "ignored",
        };
        let n = self
            .labware
            .values()
            .filter(|l| l.name.starts_with(base))
            .count();
        let name = match &c.name_hint {
            Some(hint) => hint.clone(),
            None if n == 0 => base.to_string(),
            None => format!("{base}{}", n + 1),
        };
        self.labware.insert(
            id,
            Loaded {
                command: c.index,
                name,
                holder,
                on_cycler,
                slot,
            },
        );
    }

    /// What labware is here, from its load name and its definition (the file's, else the
    /// installed package's).
    pub(super) fn holder(&mut self, c: &Command, p: &LoadLabware) -> Option<Holder> {
        // A holder made from the same definition (an instrument whose block has the same wells,
        // the `thermal_cycler_96`, is not that labware).
        if let Some(k) = labware::KINDS.iter().find(|k| {
            k.primitives.is_empty()
                && k.definition
                    .and_then(|uri| uri.split('/').nth(1))
                    .is_some_and(|load| load == p.load_name)
        }) {
            let tube = k.slots.and_then(|s| s.accepts.first().copied())?;
            return Some(Holder::Kind { kind: k.name, tube });
        }
        let uri = p.uri();
        let def = self.definition(c, &uri)?;
        if def.parameters.is_tiprack {
            return Some(Holder::Ignored("a tip rack"));
        }
        if def.metadata.display_category == "trash" || p.load_name.contains("trash") {
            return Some(Holder::Ignored("a trash"));
        }
        let pcr_plate = def
            .grid()
            .is_ok_and(|g| g.rows == 8 && g.cols == 12 && (g.col_pitch - 0.009).abs() < 1e-4)
            && def
                .wells
                .values()
                .all(|w| w.depth <= 21.0 && w.total_liquid_volume <= 200.0);
        if pcr_plate {
            return Some(Holder::Plate);
        }
        self.error(
            Code::E0043,
            c.param_path("loadName"),
            format!(
                "{}: `{uri}` ({}, category `{}`) has no kind here",
                c.label(),
                def.metadata.display_name,
                def.metadata.display_category
            ),
            "the kinds made from published definitions are listed by `autobio describe --catalogue`; a 96-well PCR plate is realised as PCR tubes",
        );
        None
    }

    pub(super) fn definition(&mut self, c: &Command, uri: &str) -> Option<Definition> {
        let from_file = self
            .src
            .definitions
            .get(uri)
            .or_else(|| c.result.get("definition"))
            .map(|v| v.to_string());
        let parsed = match from_file {
            Some(text) => Definition::parse(&text, uri),
            None => Installed::under(&self.options.deps).load(uri),
        };
        match parsed {
            Ok(d) => Some(d),
            Err(e) => {
                self.error(
                    Code::E0043,
                    c.param_path("loadName"),
                    format!("{}: labware `{uri}` cannot be resolved: {e}", c.label()),
                    "a definition must be in the file's `labwareDefinitions` or installed by `make setup` (opentrons-shared-data)",
                );
                None
            }
        }
    }

    pub(super) fn load_module(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadModule>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.module_id.clone(), "moduleId") else {
            return;
        };
        if self.options.keep_instrument_steps && !p.model.starts_with("thermocyclerModule") {
            // Its commands become instrument-only steps; what stands on it, on the bench.
            self.kept_modules.insert(id);
            return;
        }
        if p.model.starts_with("thermocyclerModule") {
            if !self.cyclers.is_empty() {
                self.error(
                    Code::E0042,
                    c.path(),
                    format!("{}: a second thermocycler", c.label()),
                    "our bench has one cycler per protocol",
                );
                return;
            }
            self.cyclers.insert(id, "cycler".into());
        } else {
            self.refused.insert(id);
            self.error(
                Code::E0042,
                c.param_path("model"),
                format!(
                    "{}: module `{}` has no realisation here: {}",
                    c.label(),
                    p.model,
                    "the thermocycler is the one module our bench has"
                ),
                "remove the module and its steps, write them in our language by hand, or keep its commands as instrument-only steps (`--keep-instrument-steps`)",
            );
        }
    }

    pub(super) fn load_pipette(&mut self, c: &Command) {
        let Some(p) = self.params::<LoadPipette>(c) else {
            return;
        };
        let Some(id) = self.load_id(c, p.pipette_id.clone(), "pipetteId") else {
            return;
        };
        if let Some((first, _)) = self.pipettes.get(&id) {
            let first = *first;
            self.duplicate(c, "pipetteId", &id, first);
            return;
        }
        self.pipettes.insert(id, (c.index, p.pipette_name));
    }

    pub(super) fn tube_kind_name(&self, lw: &Loaded) -> Option<(String, &'static str, String)> {
        match &lw.holder {
            Holder::Kind { tube, .. } => Some((lw.name.clone(), tube, lw.name.clone())),
            Holder::Plate => {
                let holder = match &lw.on_cycler {
                    Some(m) => self.cyclers[m].clone(),
                    None => lw.name.clone(),
                };
                Some((lw.name.clone(), "tube_0_2ml", holder))
            }
            Holder::Ignored(_) => None,
        }
    }

    /// The tube a well is, made on first use.
    pub(super) fn tube(
        &mut self,
        c: &Command,
        labware_id: &str,
        well: &str,
    ) -> Option<(String, String)> {
        let Some(lw) = self.labware.get(labware_id).cloned() else {
            if self.refused.contains(labware_id) {
                return None;
            }
            self.error(
                Code::E0041,
                c.param_path("labwareId"),
                format!("{}: labware `{labware_id}` was never loaded", c.label()),
                "a `loadLabware` must load it before it is used",
            );
            return None;
        };
        let Some((base, kind, holder)) = self.tube_kind_name(&lw) else {
            if let Holder::Ignored(what) = lw.holder {
                self.error(
                    Code::E0042,
                    c.param_path("labwareId"),
                    format!("{}: uses {what}, which is not an item here", c.label()),
                    "pipette from and into tubes, racks, blocks or PCR plates",
                );
            }
            return None;
        };
        let slots = if lw.on_cycler.is_some() {
            labware::kind("thermal_cycler_96")
        } else {
            match lw.holder {
                Holder::Kind { kind, .. } => labware::kind(kind),
                _ => labware::kind("aluminium_block_96_pcr"),
            }
        }
        .and_then(|k| k.slots);
        if !slots.is_some_and(|s| s.layout.names().iter().any(|n| n == well)) {
            self.error(
                Code::E0041,
                c.param_path("wellName"),
                format!("{}: `{}` has no well `{well}`", c.label(), lw.name),
                "wells are named as the labware's definition names them (`A1`)",
            );
            return None;
        }
        let key = (labware_id.to_string(), well.to_string());
        let name = match self.src.tube_names.get(&key) {
            Some(name) => name.clone(),
            None => format!("{base}_{}", well.to_ascii_lowercase()),
        };
        self.tubes.entry(key).or_insert_with(|| Tube {
            name: name.clone(),
            kind,
            at: format!("{holder}.{well}"),
            start: BTreeMap::new(),
            now: BTreeMap::new(),
            touched: false,
            dispensed_into: false,
            comment: match &self.src.commands[lw.command].origin {
                Some((_, label)) => format!("well {well} of {label}"),
                None => format!("well {well} of commands[{}]'s labware", lw.command),
            },
        });
        Some((labware_id.to_string(), well.to_string()))
    }
}
