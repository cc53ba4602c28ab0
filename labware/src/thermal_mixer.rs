//! The thermal mixer (Eppendorf ThermoMixer C proportions and panel logic,
//! `../shared/reference/upstream-autobio.md` §5.2 and §11): a white housing with a silver
//! 24-well thermoblock on top and a sloped front panel carrying three pairs of up/down buttons
//! (time, temperature, speed, left to right as the user faces the panel) above a display. The
//! buttons sit up the slope so that a hand pressing them does not hide the display from a camera
//! in front.
//!
//! Buttons are bodies on sprung slide joints into the panel. A button registers a press while its
//! spring force (stiffness x travel) exceeds the press force; held for the repeat time, the press
//! steps its value once and starts counting again (so holding a button auto-repeats). Values stay
//! within the catalogue's ranges. The display is a texture this model draws (`display.rs` cells)
//! from the panel values; the runtime redraws it when they change.
//!
//! Frame of the instrument: origin at the centre of the footprint, +y the front (the panel's
//! side), +z up.

use crate::display::{Canvas, Cell, Field, Rgb};
use crate::frame::{Pose, Rot, Vec3, from_axes, pose, translation, x_turn};
use crate::mjcf::{Fragment, pose_attrs, rgba, v3};
use crate::model::{
    Affordance, Display, Effects, Instrument, Joints, LabwareState, Logic, Reset, Symmetry, set,
};
use crate::run::Programme;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One panel value and its buttons: catalogue range and step, where its buttons sit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    pub param: String,
    pub unit: String,
    pub min: f64,
    pub max: f64,
    pub step: f64,
    pub initial: f64,
    /// Across the panel (instrument x) of the button pair.
    pub x: f64,
}

/// Every dimension and gain of the instrument (metres, radians, kilograms, newtons, seconds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Half extents of the housing.
    pub half: Vec3,
    /// The panel slopes from the top at `panel_back_y` down to the front edge at `panel_front_z`.
    pub panel_back_y: f64,
    pub panel_front_z: f64,
    /// The display: centre along the panel (from its middle, down-slope positive), half extents.
    pub display_y: f64,
    pub display_half: [f64; 2],
    /// Texture size in pixels.
    pub display_px: [usize; 2],
    /// Up and down buttons: along the panel, radius, how far they stand out, travel.
    pub up_y: f64,
    pub down_y: f64,
    pub button_radius: f64,
    pub button_height: f64,
    pub button_travel: f64,
    /// Spring stiffness (N/m) and damping of a button, the force that counts as a press, and how
    /// long a press is held before it steps the value (and again, while held).
    pub button_stiffness: f64,
    pub button_damping: f64,
    pub press_force: f64,
    pub repeat_s: f64,
    pub settings: Vec<Setting>,
    /// The thermoblock on the deck behind the panel: 4 x 6 wells for 1.5 mL tubes (slots `A1` ..
    /// `D6`, rows towards the panel, column 1 at the instrument's +x), built as a rack of wells.
    pub block: crate::rack::Params,
    /// The incubations the protocol runs ([`crate::run`]), each started by the start key
    /// (built only for a mixer that incubates, at the panel's edge beside the time buttons).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub programmes: Vec<Programme>,
}

/// Across the panel (instrument x) of the start key: beside the time buttons, at the edge.
const START_X: f64 = 0.088;
/// The start key's role and affordance name.
const START: &str = "start";

impl Default for Params {
    fn default() -> Self {
        let kind = crate::kind("thermal_mixer").expect("the catalogue has the thermal mixer");
        // As the user faces the panel (looking along -y), left is +x: time, temperature, speed.
        let xs = [("time", 0.05), ("temperature", 0.0), ("speed", -0.05)];
        let settings = xs
            .iter()
            .map(|(name, x)| {
                let p = kind.panel_param(name).expect("catalogue panel value");
                Setting {
                    param: p.name.to_string(),
                    unit: p.unit.to_string(),
                    min: p.min,
                    max: p.max,
                    step: p.step,
                    initial: p.initial,
                    x: *x,
                }
            })
            .collect();
        Params {
            half: [0.102, 0.1505, 0.0735],
            panel_back_y: 0.06,
            panel_front_z: 0.0763,
            display_y: 0.029,
            display_half: [0.085, 0.0227],
            display_px: [360, 96],
            up_y: -0.044,
            down_y: -0.02,
            button_radius: 0.009,
            button_height: 0.004,
            button_travel: 0.003,
            button_stiffness: 250.0,
            button_damping: 0.5,
            press_force: 0.5,
            // The catalogue's panel auto-repeat, which the compiler times set_parameter steps by.
            repeat_s: kind.panel[0].repeat_s,
            settings,
            // The SmartBlock 1.5 mL's well grid (17.69 x 18.14 mm pitch) in a 22 mm deep block:
            // a seated tube stands 18 mm proud of it, for a gripper to take.
            block: crate::rack::Params {
                size: [0.132, 0.104, 0.022],
                rows: 4,
                cols: 6,
                col_pitch: 0.01769,
                row_pitch: 0.01814,
                hole: 0.0112,
                plate: 0.003,
                rgba: BLOCK,
                grid_offset: [0.0, 0.0],
                base: None,
                definition: None,
            },
            programmes: Vec::new(),
        }
    }
}

/// The panel's frame and length: origin mid-panel on its surface, z its outward normal, y down the
/// slope towards the front edge.
struct Panel {
    frame: Pose,
    length: f64,
}

const DISPLAY_INK: Rgb = [20, 24, 28];
const DISPLAY_PAPER: Rgb = [236, 240, 236];

impl Params {
    /// Centre of the thermoblock in the instrument's frame: on the deck, behind the panel.
    fn block_centre(&self) -> Vec3 {
        let h = self.half;
        [
            0.0,
            (self.panel_back_y - h[1]) / 2.0 - 0.005,
            2.0 * h[2] + self.block.size[2] / 2.0,
        ]
    }

    fn panel(&self) -> Panel {
        let top = 2.0 * self.half[2];
        let (dy, dz) = (self.half[1] - self.panel_back_y, top - self.panel_front_z);
        let slope = dz.atan2(dy);
        let mid = [
            0.0,
            (self.half[1] + self.panel_back_y) / 2.0,
            (top + self.panel_front_z) / 2.0,
        ];
        Panel {
            frame: pose(mid, x_turn(-slope)),
            length: dy.hypot(dz),
        }
    }

    fn setting(&self, param: &str) -> Option<&Setting> {
        self.settings.iter().find(|s| s.param == param)
    }

    /// Every button: name, its setting, direction (+1 up, -1 down) and its top's centre on the
    /// panel (panel frame).
    fn buttons(&self) -> Vec<(String, &Setting, i8, Pose)> {
        self.settings
            .iter()
            .flat_map(|s| {
                [(1i8, "up", self.up_y), (-1, "down", self.down_y)].map(|(sign, word, y)| {
                    let top = translation([s.x, y, self.button_height]);
                    (format!("{}_{word}", s.param), s, sign, top)
                })
            })
            .collect()
    }

    /// The start key's top on the panel (panel frame), for a mixer that incubates.
    fn start_key(&self) -> Option<Pose> {
        (!self.programmes.is_empty()).then(|| {
            translation([
                START_X,
                (self.up_y + self.down_y) / 2.0,
                self.button_height,
            ])
        })
    }

    /// Travel at which the spring pushes back with the press force.
    fn press_travel(&self) -> f64 {
        self.press_force / self.button_stiffness
    }

    /// The value after one step from `v` in direction `sign`. Time steps grow with the time set,
    /// chosen from the value before the step (upstream's rule): 5 s below 5 min, 15 s below 20
    /// min, 1 min below 1 h, 5 min below 10 h, else 30 min.
    fn stepped(&self, s: &Setting, v: f64, sign: i8) -> f64 {
        let step = if s.param == "time" {
            match v {
                v if v < 300.0 => 5.0,
                v if v < 1200.0 => 15.0,
                v if v < 3600.0 => 60.0,
                v if v < 36000.0 => 300.0,
                _ => 1800.0,
            }
        } else {
            s.step
        };
        (v + f64::from(sign) * step).clamp(s.min, s.max)
    }

    /// The display's fields: time (m:ss), temperature (°C), speed (rpm), left to right.
    pub fn fields(&self) -> [Field; 3] {
        let scale = 5;
        let advance = 30;
        let y = 26;
        let cell = |x| Cell { x, y, scale };
        [
            Field {
                name: "time",
                first: cell(12),
                len: 4,
                advance,
            },
            Field {
                name: "temperature",
                first: cell(150),
                len: 2,
                advance,
            },
            Field {
                name: "speed",
                first: cell(228),
                len: 4,
                advance,
            },
        ]
    }

    /// What a field shows for a value.
    pub fn field_text(field: &str, v: f64) -> String {
        let v = v.round() as i64;
        match field {
            "time" if v < 600 => format!("{}:{:02}", v / 60, v % 60),
            "time" if v < 36000 => format!("{}:{:02}", v / 3600, (v / 60) % 60),
            "time" => "----".into(),
            _ => v.to_string(),
        }
    }

    fn value(&self, logic: &Logic, param: &str) -> f64 {
        logic
            .get(param)
            .copied()
            .or_else(|| self.setting(param).map(|s| s.initial))
            .unwrap_or(f64::NAN)
    }

    /// Draws the display for the panel values in `logic` (RGB, top row first).
    pub fn draw(&self, logic: &Logic, rgb: &mut [u8]) {
        let [w, h] = self.display_px;
        let mut c = Canvas {
            width: w,
            height: h,
            rgb,
        };
        c.fill(DISPLAY_PAPER);
        // A status bar rule and the units under each value, as the instrument shows them.
        c.rect(6, 14, w - 12, 2, DISPLAY_INK);
        for field in self.fields() {
            for (cell, ch) in
                field.cells(&Self::field_text(field.name, self.value(logic, field.name)))
            {
                c.glyph(cell, ch, DISPLAY_INK);
            }
        }
        let small = |x| Cell { x, y: 72, scale: 2 };
        c.text(small(44), 12, "min", DISPLAY_INK);
        c.text(small(162), 12, "°C", DISPLAY_INK);
        c.text(small(274), 12, "rpm", DISPLAY_INK);
    }
}

struct Names {
    base: String,
    display: String,
}

impl Names {
    fn new(prefix: &str) -> Names {
        Names {
            base: format!("{prefix}/base"),
            display: format!("{prefix}/display"),
        }
    }

    fn button(prefix: &str, button: &str) -> String {
        format!("{prefix}/{button}")
    }
}

const HOUSING: [f64; 4] = [0.94, 0.94, 0.92, 1.0];
const PANEL: [f64; 4] = [0.62, 0.64, 0.67, 1.0];
const BLOCK: [f64; 4] = [0.76, 0.77, 0.8, 1.0];
const ACCENT: [f64; 4] = [0.12, 0.32, 0.62, 1.0];
const KEY: [f64; 4] = [0.3, 0.32, 0.36, 1.0];
const MARK: [f64; 4] = [0.95, 0.95, 0.95, 1.0];

impl Instrument for Params {
    fn footprint_radius(&self) -> f64 {
        self.half[0].hypot(self.half[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let n = Names::new(name);
        let h = self.half;
        let top = 2.0 * h[2];
        let panel = self.panel();
        let p = &panel.frame;
        let plate = 0.01;
        let mut body = String::new();
        let mut geom = |s: String| body.push_str(&s);
        // Housing: a low front part under the panel and the block behind it.
        let front_h = self.panel_front_z / 2.0;
        geom(format!(
            "  <geom name=\"{b}/housing\" type=\"box\" size=\"{}\" pos=\"0 0 {front_h}\" rgba=\"{}\"/>\n",
            v3([h[0], h[1], front_h]),
            rgba(HOUSING),
            b = n.base
        ));
        let back_half = [
            h[0],
            (self.panel_back_y + h[1]) / 2.0,
            (top - self.panel_front_z) / 2.0,
        ];
        geom(format!(
            "  <geom name=\"{b}/deck\" type=\"box\" size=\"{}\" pos=\"0 {} {}\" rgba=\"{}\"/>\n",
            v3(back_half),
            (self.panel_back_y - h[1]) / 2.0,
            self.panel_front_z + back_half[2],
            rgba(HOUSING),
            b = n.base
        ));
        // The sloped panel plate: its top face is the panel surface.
        let plate_pose = p * translation([0.0, 0.0, -plate]);
        geom(format!(
            "  <geom name=\"{b}/panel\" type=\"box\" size=\"{}\" {} rgba=\"{}\"/>\n",
            v3([h[0], panel.length / 2.0, plate]),
            pose_attrs(&plate_pose),
            rgba(PANEL),
            b = n.base
        ));
        // A blue rule along the panel's top edge (the brand stripe).
        let stripe = p * translation([0.0, -panel.length / 2.0 + 0.004, 0.0004]);
        geom(format!(
            "  <geom name=\"{b}/stripe\" type=\"box\" size=\"{} 0.003 0.0004\" {} rgba=\"{}\" contype=\"0\" conaffinity=\"0\"/>\n",
            h[0] - 0.004,
            pose_attrs(&stripe),
            rgba(ACCENT),
            b = n.base
        ));
        // The display, drawn by the runtime into its texture. MuJoCo maps a plane's texture with
        // its first row at the plane's -y edge and first column at -x: turned half a turn, the
        // top row is up the slope and the first column on the user's left.
        let display = p
            * translation([0.0, self.display_y, 0.0006])
            * pose(
                [0.0; 3],
                crate::frame::axis_angle([0.0, 0.0, 1.0], std::f64::consts::PI),
            );
        geom(format!(
            "  <geom name=\"{d}\" type=\"plane\" size=\"{} {} 0.001\" {} material=\"{d}\" contype=\"0\" conaffinity=\"0\"/>\n",
            self.display_half[0],
            self.display_half[1],
            pose_attrs(&display),
            d = n.display
        ));
        let bezel = p * translation([0.0, self.display_y, 0.0002]);
        geom(format!(
            "  <geom name=\"{b}/bezel\" type=\"box\" size=\"{} {} 0.0002\" {} rgba=\"0.15 0.16 0.18 1\" contype=\"0\" conaffinity=\"0\"/>\n",
            self.display_half[0] + 0.004,
            self.display_half[1] + 0.004,
            pose_attrs(&bezel),
            b = n.base
        ));
        // The thermoblock: wells for 1.5 mL tubes, collided with as a rack's plates and bars.
        body.push_str(
            &self
                .block
                .geoms(&format!("{}/block", n.base), self.block_centre()),
        );
        let mut buttons = String::new();
        for (button, _, sign, at) in self.buttons() {
            let b = Names::button(name, &button);
            // The button's body sits on the panel surface below its top; it slides into the panel.
            let frame = p * translation([at.translation.x, at.translation.y, 0.0]);
            let half_h = self.button_height / 2.0;
            let mark_z = self.button_height + 0.0003;
            let mut marks = format!(
                "    <geom name=\"{b}/mark\" type=\"box\" size=\"0.0035 0.0008 0.0003\" pos=\"0 0 {mark_z}\" rgba=\"{}\" contype=\"0\" conaffinity=\"0\"/>\n",
                rgba(MARK)
            );
            if sign > 0 {
                marks += &format!(
                    "    <geom name=\"{b}/mark2\" type=\"box\" size=\"0.0008 0.0035 0.0003\" pos=\"0 0 {mark_z}\" rgba=\"{}\" contype=\"0\" conaffinity=\"0\"/>\n",
                    rgba(MARK)
                );
            }
            buttons += &format!(
                r#"  <body name="{b}" {frame}>
    <joint name="{b}/press" type="slide" axis="0 0 -1" range="0 {travel}" stiffness="{k}" damping="{d}" springref="0" solreflimit="0.004 1"/>
    <geom name="{b}/key" type="cylinder" size="{r} {half_h}" pos="0 0 {half_h}" mass="0.004" rgba="{key}" friction="1.2 0.01 0.001"/>
{marks}  </body>
"#,
                frame = pose_attrs(&frame),
                travel = self.button_travel,
                k = self.button_stiffness,
                d = self.button_damping,
                r = self.button_radius,
                key = rgba(KEY),
            );
        }
        if let Some(top) = self.start_key() {
            let b = Names::button(name, START);
            let frame = p * translation([top.translation.x, top.translation.y, 0.0]);
            let half_h = self.button_height / 2.0;
            buttons += &format!(
                r#"  <body name="{b}" {frame}>
    <joint name="{b}/press" type="slide" axis="0 0 -1" range="0 {travel}" stiffness="{k}" damping="{d}" springref="0" solreflimit="0.004 1"/>
    <geom name="{b}/key" type="cylinder" size="{r} {half_h}" pos="0 0 {half_h}" mass="0.004" rgba="0.2 0.65 0.3 1" friction="1.2 0.01 0.001"/>
  </body>
"#,
                frame = pose_attrs(&frame),
                travel = self.button_travel,
                k = self.button_stiffness,
                d = self.button_damping,
                r = self.button_radius,
            );
        }
        let worldbody = format!(
            "<body name=\"{base}\" {placement}>\n{body}{buttons}</body>\n",
            base = n.base,
            placement = pose_attrs(placement),
        );
        let [w, hpx] = self.display_px;
        let asset = format!(
            "<texture name=\"{d}\" type=\"2d\" builtin=\"flat\" width=\"{w}\" height=\"{hpx}\" rgb1=\"0.92 0.94 0.92\" rgb2=\"0.92 0.94 0.92\"/>\n\
             <material name=\"{d}\" texture=\"{d}\" texrepeat=\"1 1\" texuniform=\"false\" emission=\"0.6\" specular=\"0.1\"/>\n",
            d = n.display
        );
        let contact: String = self
            .buttons()
            .iter()
            .map(|(button, ..)| button.clone())
            .chain(self.start_key().map(|_| START.to_string()))
            .map(|button| {
                format!(
                    "<exclude body1=\"{}\" body2=\"{}\"/>\n",
                    n.base,
                    Names::button(name, &button)
                )
            })
            .collect();
        Fragment {
            asset,
            worldbody,
            equality: String::new(),
            contact,
            ..Default::default()
        }
    }

    fn joints(&self, name: &str) -> Vec<(&'static str, String)> {
        // Roles are static names: the catalogue's button names.
        let kind = crate::kind("thermal_mixer").expect("catalogue");
        kind.buttons
            .iter()
            .map(|b| b.name)
            .filter(|b| *b != START || self.start_key().is_some())
            .map(|b| (b, format!("{}/press", Names::button(name, b))))
            .collect()
    }

    fn reset(&self, _initial: &BTreeMap<String, String>) -> Reset {
        let mut logic = Logic::new();
        for s in &self.settings {
            logic.insert(s.param.clone(), s.initial);
        }
        if !self.programmes.is_empty() {
            self.run().reset(&mut logic);
        }
        Reset {
            joints: Vec::new(),
            logic,
        }
    }

    fn step(&self, dt: f64, joints: &Joints, logic: &mut Logic, _effects: &mut Effects) {
        let travel = self.press_travel();
        for (button, setting, sign, _) in self.buttons() {
            let key = format!("held_s/{button}");
            let pressed = joints.get(&button).is_some_and(|x| *x > travel);
            let mut held = if pressed {
                logic.get(&key).copied().unwrap_or(0.0) + dt
            } else {
                0.0
            };
            if held > self.repeat_s {
                let v = self.value(logic, &setting.param);
                set(logic, &setting.param, self.stepped(setting, v, sign));
                held = 0.0;
            }
            set(logic, &key, held);
        }
        if self.start_key().is_some() {
            let run = self.run();
            run.advance(logic, dt);
            let pressed = joints.get(START).is_some_and(|x| *x > travel);
            let held = if pressed {
                logic.get("held_s/start").copied().unwrap_or(0.0) + dt
            } else {
                0.0
            };
            if held > self.repeat_s {
                run.start(logic);
            }
            set(logic, "held_s/start", held);
        }
    }

    fn programmes(&self) -> &[Programme] {
        &self.programmes
    }

    fn set_programmes(&mut self, programmes: Vec<Programme>) {
        self.programmes = programmes;
    }

    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        self.settings
            .iter()
            .map(|set| {
                let v = self.value(&s.logic, &set.param);
                (set.param.clone(), format!("{v} {}", set.unit))
            })
            .chain((!self.programmes.is_empty()).then(|| self.run().readout(&s.logic)))
            .collect()
    }

    fn slot_seat(&self, slot: &str, s: &LabwareState) -> Option<Pose> {
        let [x, y, z] = self.block.seat_in_rack(slot)?;
        let [cx, cy, cz] = self.block_centre();
        Some(s.pose * translation([cx + x, cy + y, cz + z]))
    }

    fn affordance(&self, name: &str, s: &LabwareState) -> Option<Affordance> {
        let top = match self.buttons().into_iter().find(|(b, ..)| b == name) {
            Some((_, _, _, top)) => top,
            None if name == START => self.start_key()?,
            None => return None,
        };
        // Press along the panel's inward normal, the closed fingers lying along the slope.
        let tool: Rot = from_axes([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
        Some(Affordance {
            pose: s.pose * self.panel().frame * top * pose([0.0; 3], tool),
            symmetry: Symmetry::HalfTurn,
            touch: true,
            lead: 0.0,
        })
    }

    fn panel(&self) -> Option<&dyn crate::model::Panel> {
        Some(self)
    }
}

impl crate::model::Panel for Params {
    fn panel_value(&self, param: &str, s: &LabwareState) -> Option<f64> {
        self.setting(param)?;
        Some(self.value(&s.logic, param))
    }

    fn button_toward(&self, param: &str, target: f64, s: &LabwareState) -> Option<String> {
        let v = self.panel_value(param, s)?;
        let word = if target >= v { "up" } else { "down" };
        Some(format!("{param}_{word}"))
    }

    fn displays(&self, name: &str) -> Vec<Display> {
        vec![Display {
            texture: Names::new(name).display,
            width: self.display_px[0],
            height: self.display_px[1],
            shows: self.settings.iter().map(|s| s.param.clone()).collect(),
        }]
    }

    fn draw_display(&self, _index: usize, logic: &Logic, rgb: &mut [u8]) {
        self.draw(logic, rgb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Panel as _;

    fn state(logic: Logic) -> LabwareState {
        LabwareState {
            name: "mixer".into(),
            pose: Pose::identity(),
            joints: BTreeMap::new(),
            parts: BTreeMap::new(),
            logic,
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    /// Runs the panel logic at 500 Hz with the given button held down for `seconds`.
    fn hold(p: &Params, logic: &mut Logic, button: &str, seconds: f64) {
        let dt = 0.002;
        let pressed = BTreeMap::from([(button.to_string(), p.button_travel)]);
        for _ in 0..(seconds / dt).round() as usize {
            p.step(dt, &pressed, logic, &mut Effects::default());
        }
        p.step(dt, &BTreeMap::new(), logic, &mut Effects::default());
    }

    #[test]
    fn a_held_button_steps_every_repeat_time_and_a_tap_does_nothing() {
        let p = Params::default();
        let mut logic = p.reset(&BTreeMap::new()).logic;
        assert_eq!(logic["speed"], 900.0);
        hold(&p, &mut logic, "speed_up", 0.2);
        assert_eq!(logic["speed"], 900.0, "a tap shorter than the repeat time");
        hold(&p, &mut logic, "speed_up", 1.01);
        assert_eq!(logic["speed"], 1100.0, "four repeats in a second");
        hold(&p, &mut logic, "temperature_down", 0.51);
        assert_eq!(logic["temperature"], 23.0);
        // A touch below the press force does not count.
        let light = BTreeMap::from([("time_up".to_string(), p.press_travel() * 0.9)]);
        for _ in 0..500 {
            p.step(0.002, &light, &mut logic, &mut Effects::default());
        }
        assert_eq!(logic["time"], 60.0);
        // Values stop at the catalogue's range.
        hold(&p, &mut logic, "temperature_down", 30.0);
        assert_eq!(logic["temperature"], 4.0);
    }

    #[test]
    fn time_steps_grow_with_the_time_set() {
        let p = Params::default();
        let time = p.setting("time").unwrap().clone();
        let wide = Setting { max: 1e6, ..time };
        assert_eq!(p.stepped(&wide, 295.0, 1), 300.0);
        assert_eq!(p.stepped(&wide, 300.0, 1), 315.0);
        assert_eq!(p.stepped(&wide, 300.0, -1), 285.0);
        assert_eq!(p.stepped(&wide, 3600.0, 1), 3900.0);
    }

    #[test]
    fn the_display_shows_each_value_in_its_cells() {
        let p = Params::default();
        assert_eq!(Params::field_text("time", 65.0), "1:05");
        assert_eq!(Params::field_text("speed", 1500.0), "1500");
        let [w, h] = p.display_px;
        let mut rgb = vec![0u8; w * h * 3];
        let logic = Logic::from([("speed".to_string(), 1250.0)]);
        p.draw(&logic, &mut rgb);
        let fields = p.fields();
        let speed = fields[2].cells("1250");
        // Every set pixel of each cell's glyph is ink, every clear one paper.
        for (cell, ch) in speed {
            for y in cell.y..cell.y + cell.height() {
                for x in cell.x..cell.x + cell.width() {
                    let px = rgb[3 * (y * w + x)];
                    assert_eq!(
                        px == DISPLAY_INK[0],
                        cell.ink_at(ch, x, y),
                        "{ch} at {x},{y}"
                    );
                }
            }
        }
        // Fields do not overlap and fit the texture.
        let spans: Vec<(usize, usize)> = fields
            .iter()
            .map(|f| (f.first.x, f.cell(f.len - 1).x + f.first.width()))
            .collect();
        assert!(
            spans.windows(2).all(|s| s[0].1 < s[1].0) && spans[2].1 <= w,
            "{spans:?}"
        );
    }

    #[test]
    fn buttons_are_pressed_along_the_panel_normal_and_chosen_toward_the_target() {
        let p = Params::default();
        let s = state(p.reset(&BTreeMap::new()).logic);
        let up = p.affordance("speed_up", &s).unwrap().pose;
        let z = up.rotation * nalgebra::Vector3::z();
        // Into the panel: down and towards the back.
        assert!(z.z < -0.7 && z.y < -0.5, "{z:?}");
        assert_eq!(p.button_toward("speed", 1200.0, &s).unwrap(), "speed_up");
        assert_eq!(
            p.button_toward("temperature", 10.0, &s).unwrap(),
            "temperature_down"
        );
        assert!(p.affordance("speed_sideways", &s).is_none());
        assert_eq!(p.panel_value("time", &s), Some(60.0));
        assert_eq!(p.readout(&s)["speed"], "900 rpm");
    }
}
