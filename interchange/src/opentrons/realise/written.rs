//! The realised run as a protocol draft: the robots at their bases, the cycler, the holders at
//! the bench's places in load order, the tubes, the pipette in the first hand, the steps, and
//! success as what the run leaves in each tube it touched; the time limit from the steps' budgets.

use super::*;

impl Walk<'_> {
    pub(super) fn draft(&self) -> Draft {
        let cycler = !self.cyclers.is_empty();
        let n_robots = if cycler { 2 } else { 1 };
        let robots = (0..n_robots)
            .map(|i| Robot {
                name: self.robot(i),
                model: self
                    .options
                    .robots
                    .get(i)
                    .map_or(["ur5e_inspire", "ur5e_2f85"][i].to_string(), |(_, m)| {
                        m.clone()
                    }),
                base: BASES[i],
                joints_rad: Some(JITTER[i]),
            })
            .collect();
        let mut labware = Vec::new();
        if cycler {
            let (pos, yaw) = CYCLER_AT;
            labware.push(Item {
                name: "cycler".into(),
                kind: "thermal_cycler_96".into(),
                pose: Some((pos, yaw)),
                at: None,
                held_by: None,
                state: vec![("lid".into(), self.first_lid.unwrap_or("open").into())],
                comment: Some("the thermocycler module".into()),
            });
        }
        let places = self.places();
        // More holders than places are refused in `finish`.
        for (i, l) in self.standing().iter().enumerate() {
            let kind = match l.holder {
                Holder::Kind { kind, .. } => kind,
                _ => "aluminium_block_96_pcr",
            };
            let [x, y] = places[i.min(places.len() - 1)];
            let z = BENCH_TOP + labware::rack::Params::defined(kind).size[2] / 2.0;
            labware.push(Item {
                name: l.name.clone(),
                kind: kind.into(),
                pose: Some(([x, y, z], 0.0)),
                at: None,
                held_by: None,
                state: vec![],
                comment: Some(match &self.src.commands[l.command].origin {
                    Some((_, label)) => label.clone(),
                    None => format!(
                        "commands[{}]{}",
                        l.command,
                        l.slot
                            .as_ref()
                            .map(|s| format!(", deck slot {s}"))
                            .unwrap_or_default()
                    ),
                }),
            });
        }
        let mut tubes: Vec<&Tube> = self.tubes.values().collect();
        tubes.sort_by(|a, b| a.name.cmp(&b.name));
        for t in &tubes {
            let mut state = vec![("cap".to_string(), "off".to_string())];
            let start = t.volume(&t.start);
            if start > 0.0 {
                state.push(("volume".into(), format!("{} µL", draft::number(start))));
                if let Some(l) = t.start.keys().next() {
                    state.push(("liquid".into(), l.clone()));
                }
            }
            labware.push(Item {
                name: t.name.clone(),
                kind: t.kind.into(),
                pose: None,
                at: Some(t.at.clone()),
                held_by: None,
                state,
                comment: Some(t.comment.clone()),
            });
        }
        if let Some((id, set, _)) = &self.pipette {
            let name = &self.pipettes[id].1;
            let kind = PIPETTES
                .iter()
                .find(|(_, lo, hi)| (lo..=hi).contains(&set))
                .map(|(k, _, _)| *k);
            labware.push(Item {
                name: "pipette".into(),
                kind: kind.unwrap_or("pipette").into(),
                pose: None,
                at: None,
                held_by: Some(self.robot(0)),
                state: vec![("set_volume".into(), format!("{} µL", draft::number(*set)))],
                comment: Some(format!("the run's `{name}`, held by hand")),
            });
        }
        let mut success = Vec::new();
        for t in &tubes {
            if !t.touched {
                continue;
            }
            let total = t.volume(&t.now);
            let named: Vec<(&String, &f64)> = t.now.iter().filter(|(_, v)| **v > 1e-9).collect();
            if t.dispensed_into && named.len() == 1 && (named[0].1 - total).abs() < 1e-6 {
                success.push(format!(
                    "{}.volume of {} = {} µL",
                    t.name,
                    named[0].0,
                    draft::number(total)
                ));
            } else {
                success.push(format!("{}.volume = {} µL", t.name, draft::number(total)));
            }
            if t.at.starts_with("cycler.") {
                success.push(format!("{} in {}", t.name, t.at));
            }
        }
        if cycler {
            if self.ran_profile {
                success.push("cycler.run is done".into());
            }
            match self.lid_state {
                Some("open") => success.push("cycler.lid is open".into()),
                Some("closed") => success.push("cycler.lid is locked".into()),
                _ => {}
            }
        }
        let n_pipetting = self
            .steps
            .iter()
            .filter(|s| s.primitive == "aspirate" || s.primitive == "dispense")
            .count() as f64;
        let n_lid = self
            .steps
            .iter()
            .filter(|s| s.primitive.ends_with("_lid") || s.primitive == "retract")
            .count() as f64;
        // A profile's ramps come on top of its holds (docs: a 2,730 s profile lasts about
        // 3,880 s): half again, plus ten minutes.
        let profile = if self.ran_profile {
            self.profile_s * 1.5 + 600.0
        } else {
            0.0
        };
        let time_limit =
            SLACK_S + PIPETTING_S * n_pipetting + LID_S * n_lid + self.waits_s + profile;
        Draft {
            header: Vec::new(),
            id: self.names.id.clone(),
            level: "hard",
            instruction: self.names.instruction.clone(),
            imported_from: None,
            time_limit_s: (time_limit / 10.0).ceil() * 10.0,
            robots,
            labware,
            steps: self.steps.clone(),
            success,
        }
    }
}
