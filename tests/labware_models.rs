//! Every tube kind stands in its rack on real MuJoCo at the task timestep: reset puts it on the
//! seat of its `at` slot with its cap screwed on, and after two seconds without motion it is still
//! seated upright, capped, and the judge's slot check agrees (and refuses another slot).

use labware::model::seated;
use std::sync::Arc;

fn protocol(rack: &str, rack_z: f64, tube: &str) -> String {
    format!(
        r#"format = 1
[protocol]
id = "test.{tube}_in_{rack}"
level = "easy"
instruction = "move the tube to A2"
time_limit = "2 s"

[robots.arm]
model = "ur5e_2f85"
base = {{ pos_m = [-0.1, 0.0, 0.824] }}

[labware.rack]
kind = "{rack}"
pose = {{ pos_m = [0.3, 0.0, {rack_z}], yaw_deg = 30 }}

[labware.tube]
kind = "{tube}"
at = "rack.B1"

[[steps]]
do = "pick"
on = "tube"
with = "arm"

[[steps]]
do = "place"
on = "tube"
to = "rack.A2"
with = "arm"

[success]
all = ["tube in rack.A2"]
"#
    )
}

#[test]
fn every_tube_kind_stands_capped_in_its_rack() {
    for (rack, rack_z, tube) in [
        ("tube_rack", 0.854, "tube_50ml"),
        ("tube_rack", 0.854, "tube_15ml"),
        ("microtube_rack", 0.8345, "tube_1_5ml"),
        ("microtube_rack", 0.8345, "cryovial"),
    ] {
        let source = protocol(rack, rack_z, tube);
        let (task, diags) = compiler::compile_source(&source, "inline.toml");
        let task = task.unwrap_or_else(|| panic!("{tube}: {diags:#?}"));
        let instance = task.sample(0);
        let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
        let mut ep = runtime::Episode::new(scene, &task, &instance);
        let (ri, ti) = (
            task.labware_index("rack").unwrap(),
            task.labware_index("tube").unwrap(),
        );
        let rack_model = task.labware[ri].params.instrument().unwrap();
        let tube_model = task.labware[ti].params.instrument().unwrap();
        let start = ep.labware_state();
        let seat = rack_model.slot_seat("B1", &start[ri]).unwrap();
        assert!(
            seated(&seat, &start[ti].pose, 1e-9, 1e-9, 1e-9).holds,
            "{tube}: reset puts it on the seat"
        );
        for _ in 0..100 {
            ep.control_step().unwrap();
        }
        let end = ep.labware_state();
        let m = seated(&seat, &end[ti].pose, 0.003, 0.002, 0.05);
        assert!(m.holds, "{tube} in {rack}: {m:?} at {:?}", end[ti].pose);
        assert_eq!(tube_model.readout(&end[ti])["cap"], "on", "{tube}");
        // The judge: not in A2, where the task wants it; in B1, where it stands.
        let mut judge = results::verdict::Judge::new(&task, &instance.params, &start);
        // The end state judged as a state: reached at once and held for the settle time.
        judge.update(0.02, &end);
        judge.update(0.02 + task.stages[0].settle_s, &end);
        let v = judge.verdict();
        let p = &v.predicates()[0];
        assert!(!v.success && !p.holds && p.value > 0.01, "{tube}: {p:?}");
        let mut at_b1 = task.clone();
        if let compiler::predicates::Check::InSlot { location, .. } =
            &mut at_b1.stages[0].success[0].check
        {
            *location = "rack.B1".into();
        }
        let mut judge = results::verdict::Judge::new(&at_b1, &instance.params, &start);
        assert!(
            !judge.update(0.02, &end),
            "{tube}: a moment in B1 is not yet a success"
        );
        assert!(
            judge.update(0.02 + at_b1.stages[0].settle_s, &end),
            "{tube}: the B1 check held for the settle time ends the stage"
        );
        assert!(judge.verdict().success, "{tube}: {:?}", judge.verdict());
    }
}

#[test]
fn a_scene_whose_plugin_instances_report_errors_is_refused() {
    // The task carries each item's parameters: a negative detent stiffness reaches the plugin,
    // which marks its instance invalid, and `Scene::build` refuses the scene with the reason.
    let path = "protocols/thermal_cycler/close_lid.toml";
    let (task, diags) = compiler::compile_source(&std::fs::read_to_string(path).unwrap(), path);
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let mut json = serde_json::to_value(&task).unwrap();
    json["labware"][0]["params"]["detent_stiffness"] = serde_json::json!(-1.0);
    let broken: compiler::Task = serde_json::from_value(json).unwrap();
    let err = match runtime::Scene::build(&broken, &broken.sample(0)) {
        Ok(_) => panic!("a scene with an invalid detent was built"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("detent instance") && err.contains("`stiffness` must be a non-negative"),
        "{err}"
    );
    // The unbroken task builds.
    assert!(runtime::Scene::build(&task, &task.sample(0)).is_ok());
}
