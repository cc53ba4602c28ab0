//! Instruments that act, on the real MuJoCo: the vortex mixer's logic drives its own motor from
//! its power switch at its speed knob's notch. Powered on, the eccentric drive spins at the knob's
//! speed and the cup orbits; off, or on with the knob at its stop, the motor is commanded to rest
//! and the drive stays still. The robot holds still in all three.

use runtime::{Env, EnvOptions};

/// A mixer starting in `state` (a TOML table's body), and a press of its switch to do.
fn vortex_protocol(state: &str) -> compiler::Task {
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
state = {{ {state} }}

[[steps]]
do = "press"
on = "vortex"
button = "switch"
with = "arm"

[success]
all = ["vortex.power is {goal}"]
"#,
        goal = if state.contains(r#"power = "on""#) {
            "off"
        } else {
            "on"
        }
    );
    let (task, diags) = compiler::compile_source(&text, "vortex.toml");
    task.unwrap_or_else(|| panic!("{diags:#?}"))
}

/// The drive's angle after `seconds` of the robot holding still, and the motor's command.
fn spin(state: &str, seconds: f64) -> (f64, f64) {
    let task = vortex_protocol(state);
    let mut env = Env::make(&task, 0, EnvOptions::default()).unwrap();
    let hold = env.episode().ctrl();
    let period = task.physics.timestep_s * task.physics.substeps as f64;
    for _ in 0..(seconds / period).round() as usize {
        env.step(&hold).unwrap();
    }
    let state = env.episode().labware_state();
    let motor = env.scene().labware[0].actuators[0].1;
    (state[0].joint("drive"), env.episode().data.ctrl()[motor])
}

#[test]
fn the_mixers_logic_drives_its_motor_from_the_power_switch_at_the_knobs_speed() {
    // The knob starts turned to the notch nearest 2,000 rpm, the sixth: 600 + 5/9 of 2,600 rpm.
    let (on_angle, on_command) = spin(r#"power = "on", speed = "2000 rpm""#, 1.0);
    let speed = physics::eccentric::rpm_to_rad_s(600.0 + 2600.0 * 5.0 / 9.0);
    assert!((on_command - speed).abs() < 1e-9, "{on_command}");
    // 2,044 rpm is 214 rad/s: after a second's spin-up the drive has turned many times.
    assert!(on_angle > 20.0 * std::f64::consts::TAU, "{on_angle} rad");
    let (off_angle, off_command) = spin(r#"power = "off", speed = "2000 rpm""#, 1.0);
    assert_eq!(off_command, 0.0);
    assert!(off_angle.abs() < 1e-3, "{off_angle} rad");
    // Switched on with the knob at its stop (where it starts unless told), the motor rests.
    let (stopped_angle, stopped_command) = spin(r#"power = "on""#, 1.0);
    assert_eq!(stopped_command, 0.0);
    assert!(stopped_angle.abs() < 1e-3, "{stopped_angle} rad");
}
