//! The eccentric drive of an orbital (vortex) mixer, as the paper decomposes it: a hinge `pivot` on
//! the drive axis carries, at the throw `t`, a parallel hinge `orbit` held at minus the pivot's
//! angle by a joint equality. The cup on the orbit hinge then moves on a circle of radius `t`
//! without turning. Pure MJCF generation (no plugin needed); the drive is a velocity actuator.

/// An eccentric drive: throw (m), the cup it carries, and the drive's limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eccentric {
    /// Radius of the cup's orbit (m); the Vortex-Genie 2 uses 2 mm.
    pub throw: f64,
    /// Cup radius and half height (m), and its mass (kg).
    pub cup_radius: f64,
    pub cup_half_height: f64,
    pub cup_mass: f64,
    /// A ring of bumps on the cup's top that keeps what stands on it from sliding off, as a
    /// mixer's rubber cup does: ring radius (m), bump radius (m) and count; none when the count
    /// is 0.
    pub rim: (f64, f64, usize),
    /// Velocity actuator gain and the largest drive speed (rad/s).
    pub kv: f64,
    pub max_speed: f64,
}

impl Default for Eccentric {
    fn default() -> Self {
        Eccentric {
            throw: 0.002,
            cup_radius: 0.02,
            cup_half_height: 0.01,
            cup_mass: 0.05,
            rim: (0.0, 0.0, 0),
            kv: 1.0,
            max_speed: 400.0,
        }
    }
}

/// The MJCF pieces of one drive; names are prefixed with `<prefix>/`.
#[derive(Clone, Debug, PartialEq)]
pub struct EccentricMjcf {
    /// A body to put inside `<worldbody>` (or a parent body).
    pub body: String,
    pub equality: String,
    pub actuator: String,
}

impl Eccentric {
    /// The drive at `pos` (world or parent frame).
    pub fn mjcf(&self, prefix: &str, pos: [f64; 3]) -> EccentricMjcf {
        let body = format!(
            r#"<body name="{prefix}/drive" pos="{} {} {}">
  <joint name="{prefix}/pivot" type="hinge" axis="0 0 1" damping="0.01" armature="0.1"/>
  <geom name="{prefix}/crank" type="cylinder" size="{} 0.002" mass="0.02" rgba="0.3 0.3 0.3 1" contype="0" conaffinity="0"/>
  <body name="{prefix}/carrier" pos="{} 0 0">
    <joint name="{prefix}/orbit" type="hinge" axis="0 0 1" armature="0.001"/>
    <body name="{prefix}/cup" pos="0 0 {}">
      <geom name="{prefix}/cup" type="cylinder" size="{} {}" mass="{}" rgba="0.15 0.15 0.15 1"/>
      <site name="{prefix}/cup_centre" pos="0 0 0"/>
{}    </body>
  </body>
</body>"#,
            pos[0],
            pos[1],
            pos[2],
            self.throw * 2.0,
            self.throw,
            self.cup_half_height + 0.002,
            self.cup_radius,
            self.cup_half_height,
            self.cup_mass,
            self.rim_geoms(prefix),
        );
        let equality = format!(
            r#"<joint name="{prefix}/counter_rotation" joint1="{prefix}/orbit" joint2="{prefix}/pivot" polycoef="0 -1 0 0 0" solref="0.002 1"/>"#
        );
        let actuator = format!(
            r#"<velocity name="{prefix}/motor" joint="{prefix}/pivot" kv="{}" ctrlrange="0 {}"/>"#,
            self.kv, self.max_speed
        );
        EccentricMjcf {
            body,
            equality,
            actuator,
        }
    }
}

impl Eccentric {
    /// The rim's bumps: spheres on the cup's top face, evenly around the ring.
    fn rim_geoms(&self, prefix: &str) -> String {
        let (ring, r, n) = self.rim;
        (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                format!(
                    "      <geom name=\"{prefix}/rim{i}\" type=\"sphere\" size=\"{r}\" pos=\"{} {} {}\" mass=\"0.001\" rgba=\"0.15 0.15 0.15 1\"/>\n",
                    ring * a.cos(),
                    ring * a.sin(),
                    self.cup_half_height
                )
            })
            .collect()
    }
}

/// Drive speed in rad/s from revolutions per minute.
pub fn rpm_to_rad_s(rpm: f64) -> f64 {
    rpm * std::f64::consts::TAU / 60.0
}
