//! A calibration as an overlay robot software can apply to its own description: the calibrated
//! `<origin>` of every joint the calibration changes (with the original one and the size of the
//! change) and the reflector links it adds. URDF units: metres and radians, `rpy` as URDF reads it.
//! Written as YAML or JSON (`dualcal-urdf-overlay/1`, see `docs/formats.md`).

use super::{calibrated_urdf, export_err};
use crate::kinematics::DualArmModel;
use crate::robot::{RobotDescription, RobotError, isometry_from_urdf_pose};
use serde::Serialize;

/// The format tag of an overlay.
pub const OVERLAY_FORMAT: &str = "dualcal-urdf-overlay/1";

/// A URDF `<origin>`: metres and radians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OriginOverlay {
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
}

impl OriginOverlay {
    /// As the URDF writes it.
    fn of(pose: &urdf_rs::Pose) -> Self {
        Self {
            xyz: pose.xyz.0,
            rpy: pose.rpy.0,
        }
    }
}

/// One joint whose origin the calibration changes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointOverlay {
    pub name: String,
    /// The calibrated origin: replace the joint's `<origin>` with it.
    pub origin: OriginOverlay,
    /// The origin in the description the calibration started from.
    pub nominal_origin: OriginOverlay,
    /// Size of the change: translation, mm, and rotation angle, mrad.
    pub change_mm: f64,
    pub change_mrad: f64,
}

/// A reflector added as a fixed link.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReflectorOverlay {
    pub link: String,
    pub parent: String,
    /// Position in the parent (tip) link's frame, m.
    pub xyz: [f64; 3],
}

/// One arm's errors beyond geometry (`dualcal calibrate --model`): what a URDF cannot hold, for the
/// software that compensates with the full model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ErrorsOverlay {
    pub arm: String,
    pub model: String,
    /// Gravity's direction in the arm's model base frame.
    pub gravity_in_base: [f64; 3],
    /// Harmonics (rad) and compliances (mrad/(N·m)), by name, in the model's order.
    pub parameters: Vec<(String, f64)>,
    /// The held lumped masses: per link (`after_<joint>`) kg and first moment kg·mm.
    pub masses: Vec<(String, f64, [f64; 3])>,
    /// The gear ratios given (motor turns per joint turn), by joint: the motor harmonics' ratios.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gear_ratios: Vec<(String, f64)>,
}

/// The whole overlay.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CalibrationOverlay {
    pub format: String,
    /// The description it applies to.
    pub robot: String,
    pub joints: Vec<JointOverlay>,
    pub reflectors: Vec<ReflectorOverlay>,
    /// The errors beyond geometry of each arm that has them (none for the geometric model).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub beyond_geometry: Vec<ErrorsOverlay>,
}

/// Each arm's errors beyond geometry, for the overlay (one arm once for a single robot).
fn errors_overlay(model: &DualArmModel) -> Vec<ErrorsOverlay> {
    let sides: &[crate::side::Side] = if model.is_one_arm() {
        &[crate::side::Side::Left]
    } else {
        &crate::side::Side::BOTH
    };
    sides
        .iter()
        .filter_map(|&side| {
            let arm = model.arm(side);
            let m = arm.errors.model.as_ref()?;
            let off = arm.error_offset();
            Some(ErrorsOverlay {
                arm: side.name().to_string(),
                model: m.terms.name(),
                gravity_in_base: m.gravity_in_base.into(),
                parameters: arm
                    .errors
                    .values
                    .iter()
                    .enumerate()
                    .map(|(i, v)| (arm.param_name(off + i), *v))
                    .collect(),
                masses: m
                    .link_masses()
                    .iter()
                    .enumerate()
                    .map(|(k, (mass, s))| (m.link_name(k), *mass, [s.x, s.y, s.z]))
                    .collect(),
                gear_ratios: m.gear_ratios(),
            })
        })
        .collect()
}

/// The overlay of `model` on `robot`: the joints whose origins differ between `robot` and its
/// calibrated URDF ([`calibrated_urdf`]), and the reflector links that file adds.
pub fn calibrated_overlay(
    robot: &RobotDescription,
    model: &DualArmModel,
) -> Result<CalibrationOverlay, RobotError> {
    let text = calibrated_urdf(robot, model)?;
    let calibrated = urdf_rs::read_from_string(&text)
        .map_err(|e| export_err(format!("the calibrated URDF does not parse: {e}")))?;
    let mut joints = Vec::new();
    let mut reflectors = Vec::new();
    for j in &calibrated.joints {
        let origin = isometry_from_urdf_pose(&j.origin);
        match robot.urdf.joints.iter().find(|o| o.name == j.name) {
            Some(original) => {
                let nominal = isometry_from_urdf_pose(&original.origin);
                let change = nominal.inverse() * origin;
                let (change_mm, change_mrad) = (
                    change.translation.vector.norm(),
                    change.rotation.angle() * 1000.0,
                );
                if change_mm > 1e-9 || change_mrad > 1e-9 {
                    joints.push(JointOverlay {
                        name: j.name.clone(),
                        origin: OriginOverlay::of(&j.origin),
                        nominal_origin: OriginOverlay::of(&original.origin),
                        change_mm,
                        change_mrad,
                    });
                }
            }
            None if j.child.link.starts_with("reflector_") => reflectors.push(ReflectorOverlay {
                link: j.child.link.clone(),
                parent: j.parent.link.clone(),
                xyz: j.origin.xyz.0,
            }),
            None => {}
        }
    }
    Ok(CalibrationOverlay {
        format: OVERLAY_FORMAT.into(),
        robot: robot.name(),
        joints,
        reflectors,
        beyond_geometry: errors_overlay(model),
    })
}

/// A YAML double-quoted string.
fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

fn list(v: &[f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

impl CalibrationOverlay {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).unwrap_or_default();
        s.push('\n');
        s
    }

    /// Block-style YAML (numbers with full precision).
    pub fn to_yaml(&self) -> String {
        let mut s = format!(
            "# Calibrated joint origins of {} (dualcal). URDF units: metres, radians (rpy).\n\
             # Replace each joint's <origin> with `origin`; add each reflector as a fixed link.\n\
             format: {}\nrobot: {}\njoints:\n",
            self.robot,
            quoted(&self.format),
            quoted(&self.robot)
        );
        for j in &self.joints {
            s += &format!(
                "  - name: {}\n    origin: {{xyz: {}, rpy: {}}}\n    nominal_origin: {{xyz: {}, rpy: {}}}\n    \
                 change_mm: {:?}\n    change_mrad: {:?}\n",
                quoted(&j.name),
                list(&j.origin.xyz),
                list(&j.origin.rpy),
                list(&j.nominal_origin.xyz),
                list(&j.nominal_origin.rpy),
                j.change_mm,
                j.change_mrad
            );
        }
        if self.joints.is_empty() {
            s = s.replace("joints:\n", "joints: []\n");
        }
        s += if self.reflectors.is_empty() {
            "reflectors: []\n"
        } else {
            "reflectors:\n"
        };
        for r in &self.reflectors {
            s += &format!(
                "  - link: {}\n    parent: {}\n    xyz: {}\n",
                quoted(&r.link),
                quoted(&r.parent),
                list(&r.xyz)
            );
        }
        if !self.beyond_geometry.is_empty() {
            s += "# Errors beyond geometry (no URDF form): joint compliances in mrad/(N·m) under the held\n\
                  # lumped masses (kg, first moments kg·mm in the next joint frame), harmonics of the joint\n\
                  # angles (and of the motor angles, gear ratio × joint angle: `.m1_cos` …) in rad.\n\
                  # Software that compensates applies them with the geometry above.\n\
                  beyond_geometry:\n";
        }
        for e in &self.beyond_geometry {
            s += &format!(
                "  - arm: {}\n    model: {}\n    gravity_in_base: {}\n    parameters:\n",
                quoted(&e.arm),
                quoted(&e.model),
                list(&e.gravity_in_base)
            );
            for (name, v) in &e.parameters {
                s += &format!("      {}: {v:?}\n", quoted(name));
            }
            s += "    masses:\n";
            for (link, m, moment) in &e.masses {
                s += &format!(
                    "      {}: {{mass: {m:?}, moment: {}}}\n",
                    quoted(link),
                    list(moment)
                );
            }
            if !e.gear_ratios.is_empty() {
                s += "    gear_ratios:\n";
                for (joint, r) in &e.gear_ratios {
                    s += &format!("      {}: {r:?}\n", quoted(joint));
                }
            }
        }
        s
    }

    /// The calibrated origins as a kinematics file a xacro reads (the form the UR description packages
    /// use for their factory calibration): `kinematics: {<joint>: {x, y, z, roll, pitch, yaw}}`, metres
    /// and radians, one entry per joint the calibration changed. A xacro takes them with
    /// `${xacro.load_yaml(file)['kinematics']['<joint>']['x']}`, … (docs/formats.md).
    pub fn to_kinematics_yaml(&self) -> String {
        let mut s = format!(
            "# Calibrated joint origins of {} (dualcal, {}): each joint's <origin xyz=\"x y z\" \
             rpy=\"roll pitch yaw\">,\n# metres and radians, for a xacro that reads them with \
             xacro.load_yaml.\nkinematics:\n",
            self.robot, self.format
        );
        for j in &self.joints {
            let [x, y, z] = j.origin.xyz;
            let [roll, pitch, yaw] = j.origin.rpy;
            s += &format!(
                "  {}:\n    x: {x:?}\n    y: {y:?}\n    z: {z:?}\n    roll: {roll:?}\n    pitch: {pitch:?}\n    \
                 yaw: {yaw:?}\n",
                quoted(&j.name)
            );
        }
        if self.joints.is_empty() {
            s = s.replace("kinematics:\n", "kinematics: {}\n");
        }
        s
    }
}
