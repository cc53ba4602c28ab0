//! The robot catalogue: models a protocol may name, with their home pose and joint layout.

pub struct RobotModel {
    pub name: &'static str,
    pub description: &'static str,
    /// Home joint angles of the arm (rad).
    pub home: &'static [f64],
    /// Number of arm joints (the gripper is one more action element).
    pub dof: usize,
}

pub const MODELS: &[RobotModel] = &[RobotModel {
    name: "ur5e_2f85",
    description: "Universal Robots UR5e with a Robotiq 2F-85 gripper (MuJoCo Menagerie models)",
    home: &[
        0.0,
        -std::f64::consts::FRAC_PI_2,
        std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
    ],
    dof: 6,
}];

pub fn model(name: &str) -> Option<&'static RobotModel> {
    MODELS.iter().find(|m| m.name == name)
}
