//! Instruments that act, on the real MuJoCo: the vortex mixer's logic drives its own motor from
//! its power switch at its speed knob's notch. Powered on, the eccentric drive spins at the knob's
//! speed and the cup orbits; off, or on with the knob at its stop, the motor is commanded to rest
//! and the drive stays still. The robot holds still in all three.

use runtime::{Episode, Scene};
use std::sync::Arc;

fn vortex_protocol(power: &str) -> compiler::Task {
    let text = format!(
        r#"format = 1

[protocol]
id = "vortex.switch"
version = 1
level = "easy"
instruction = "switch the vortex mixer"
time_limit = "10 s"

[robots.arm]
model = "ur5e_2f85"
base = {{ pos_m = [0.0, 0.5, 0.824] }}

[labware.vortex]
kind = "vortex_mixer"
pose = {{ pos_m = [0.0, 0.0, 0.824] }}
state = {{ power = "{power}" }}

[[steps]]
do = "press"
on = "vortex"
button = "switch"
with = "arm"

[success]
all = ["vortex.power is {goal}"]
"#,
        goal = if power == "on" { "off" } else { "on" }
    );
    let (task, diags) = compiler::compile_source(&text, "vortex.toml");
    task.unwrap_or_else(|| panic!("{diags:#?}"))
}

/// The drive's angle after `seconds` of the robot holding still with the speed knob in `notch`,
/// and the motor's command.
fn spin(power: &str, notch: f64, seconds: f64) -> (f64, f64) {
    let task = vortex_protocol(power);
    let instance = task.sample(0);
    let scene = Arc::new(Scene::build(&task, &instance).unwrap());
    let mut episode = Episode::new(scene.clone(), &task, &instance);
    // The knob as a hand leaves it, in its notch (the notches are 0.46 rad apart); the state's
    // first value is the time, then qpos.
    let vortex = &scene.labware[0];
    let knob = vortex
        .joints
        .iter()
        .find(|(role, _)| *role == "knob")
        .unwrap()
        .1;
    let mut state = episode.physics_state();
    state[1 + knob] = notch * 0.46;
    let logic = episode.logic().to_vec();
    episode.restore(&state, logic).unwrap();
    let hold = episode.ctrl();
    let period = task.physics.timestep_s * task.physics.substeps as f64;
    for _ in 0..(seconds / period).round() as usize {
        episode.apply(&hold).unwrap();
        episode.control_step().unwrap();
    }
    let state = episode.labware_state();
    let motor = vortex.actuators[0].1;
    (state[0].joint("drive"), episode.data.ctrl()[motor])
}

#[test]
fn the_mixers_logic_drives_its_motor_from_the_power_switch_at_the_knobs_speed() {
    // The sixth notch: 600 + 5/9 of 2,600 rpm.
    let (on_angle, on_command) = spin("on", 6.0, 1.0);
    let speed = physics::eccentric::rpm_to_rad_s(600.0 + 2600.0 * 5.0 / 9.0);
    assert!((on_command - speed).abs() < 1e-9, "{on_command}");
    // 2,044 rpm is 214 rad/s: after a second's spin-up the drive has turned many times.
    assert!(on_angle > 20.0 * std::f64::consts::TAU, "{on_angle} rad");
    let (off_angle, off_command) = spin("off", 6.0, 1.0);
    assert_eq!(off_command, 0.0);
    assert!(off_angle.abs() < 1e-3, "{off_angle} rad");
    // Switched on with the knob at its stop, the motor is commanded to rest.
    let (stopped_angle, stopped_command) = spin("on", 0.0, 1.0);
    assert_eq!(stopped_command, 0.0);
    assert!(stopped_angle.abs() < 1e-3, "{stopped_angle} rad");
}
