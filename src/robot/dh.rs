//! The IRB 14000's naming scheme and the DH reading of its description: joint names, the DH base
//! frame of each arm, and the DH table read off the joint origins.

use super::{RobotDescription, RobotError, isometry_from_urdf_pose};
use crate::kinematics::{
    ArmKinematics, ArmModel, DhRow, DualArmModel, IRB14000_NOMINAL_DH, N_JOINTS,
};

use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Distance from the DH base frame (frame 0) up the joint-1 axis to the URDF's link_1 origin, mm.
pub const DH_BASE_BELOW_LINK1_MM: f64 = 66.0;

/// ABB axis numbers of the joints in chain order, as they appear in the joint names.
pub const ARM_JOINT_NUMBERS: [usize; N_JOINTS] = [1, 2, 7, 3, 4, 5, 6];

/// The YuMi's tucked-in home pose (ABB's synchronisation position: axes 1–6 at 0, −130, 30, 0, 40,
/// 0 deg, axis 7 at +135 deg left / −135 deg right) in chain order (axes 1, 2, 7, 3, 4, 5, 6), rad.
/// Collision-free with the built-in geometry.
pub fn home_q_rad(side: Side) -> [f64; N_JOINTS] {
    let axis7_deg = match side {
        Side::Left => 135.0,
        Side::Right => -135.0,
    };
    [0.0, -130.0, axis7_deg, 30.0, 0.0, 40.0, 0.0].map(f64::to_radians)
}

/// Name suffix of an arm in the YuMi naming scheme.
pub fn side_suffix(side: Side) -> &'static str {
    match side {
        Side::Left => "l",
        Side::Right => "r",
    }
}

/// Name of the joint at `chain_pos` (0-based) of `side`, e.g. `yumi_joint_7_l` for chain position 2.
pub fn arm_joint_name(side: Side, chain_pos: usize) -> String {
    format!(
        "yumi_joint_{}_{}",
        ARM_JOINT_NUMBERS[chain_pos],
        side_suffix(side)
    )
}

/// Name of link `k` (1-based chain position) of `side`, e.g. `yumi_link_3_r`.
pub fn arm_link_name(side: Side, k: usize) -> String {
    format!("yumi_link_{k}_{}", side_suffix(side))
}

/// Name of the flange link of `side`.
pub fn flange_link_name(side: Side) -> String {
    format!("yumi_flange_{}", side_suffix(side))
}

/// `DH base frame ← joint-1 frame` offset: `Tz(−66 mm) · Rz(π)`, i.e. `joint1_from_dh_base`.
pub fn joint1_from_dh_base() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -DH_BASE_BELOW_LINK1_MM),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI),
    )
}

/// Read a DH row off a transform `Rz(θ) Tz(d) Tx(a) Rx(α)` (a joint origin at q = 0); `None` when
/// the transform has no such form (within 1e-6 mm and 1e-9 rad).
pub fn dh_row_from_origin(origin: &Isometry3<f64>) -> Option<DhRow> {
    let m = origin.rotation.to_rotation_matrix().into_inner();
    let t = origin.translation.vector;
    let theta_rad = m[(1, 0)].atan2(m[(0, 0)]);
    let alpha_rad = m[(2, 1)].atan2(m[(2, 2)]);
    let row = DhRow::new(
        t.x * theta_rad.cos() + t.y * theta_rad.sin(),
        t.z,
        theta_rad,
        alpha_rad,
    );
    let back = row.transform(0.0);
    let dt = (back.translation.vector - t).norm();
    let dr = (back.rotation.inverse() * origin.rotation).angle();
    (dt < 1e-6 && dr < 1e-9).then_some(row)
}

impl RobotDescription {
    /// The DH base frame (frame 0) of `side` in the body frame, mm: for the built-in robot its model
    /// base; for a description in the YuMi naming scheme `yumi_joint_1_x`'s frame (at zero) ·
    /// Tz(−66 mm) · Rz(π); otherwise the arm's model base ([`RobotDescription::body_from_arm_base`]).
    pub fn body_from_dh_base(&self, side: Side) -> Isometry3<f64> {
        if self.is_builtin() {
            return self.body_from_arm_base(side);
        }
        let name = arm_joint_name(side, 0);
        let Some(j1) = self.urdf.joints.iter().find(|j| j.name == name) else {
            return self.body_from_arm_base(side);
        };
        let poses = self.kin.body_from_links(&[], &[]);
        let parent = self
            .kin
            .link_names
            .iter()
            .position(|n| *n == j1.parent.link)
            .map_or_else(Isometry3::identity, |i| poses[i]);
        parent * isometry_from_urdf_pose(&j1.origin) * joint1_from_dh_base()
    }

    /// The dual-arm model this URDF encodes: DH rows read off the arm joints' origins (the inverse
    /// of [`crate::urdf_export::calibrated_urdf`]), reflectors from `reflector_{a,b,c}_{l,r}` links
    /// when present (else `reflectors_mm`), and the base transform of the DH base frames. For the
    /// built-in URDF this is Table 3. Fails when an origin is not of DH form or an axis is not +z.
    pub fn dh_model(
        &self,
        reflectors_mm: impl Into<Vec<Vector3<f64>>>,
    ) -> Result<DualArmModel, RobotError> {
        let reflectors_mm: Vec<Vector3<f64>> = reflectors_mm.into();
        let names = crate::kinematics::default_reflector_names(reflectors_mm.len());
        self.dh_model_named(&names, &reflectors_mm)
    }

    /// [`RobotDescription::dh_model`] with reflectors named `names` (links `reflector_<name>_{l,r}`).
    pub fn dh_model_named(
        &self,
        reflector_names: &std::sync::Arc<[String]>,
        reflectors_mm: &[Vector3<f64>],
    ) -> Result<DualArmModel, RobotError> {
        let file = self
            .source
            .as_ref()
            .map_or_else(|| "<string>".to_string(), |p| p.display().to_string());
        let poses = self.kin.body_from_links(&[], &[]);
        let link_pose = |name: &str| {
            self.kin
                .link_names
                .iter()
                .position(|n| n == name)
                .filter(|&i| self.kin.reachable[i])
                .map(|i| poses[i])
        };
        let arms = PerSide::try_from_fn(|side| {
            let names: Vec<String> = (0..N_JOINTS).map(|k| arm_joint_name(side, k)).collect();
            let bad = |joint: &str, problem: &str| RobotError::BadJoint {
                file: file.clone(),
                line: None,
                joint: joint.to_string(),
                problem: problem.to_string(),
            };
            let mut origins = Vec::with_capacity(N_JOINTS);
            for name in &names {
                let j = self
                    .urdf
                    .joints
                    .iter()
                    .find(|j| &j.name == name)
                    .ok_or_else(|| bad(name, "missing"))?;
                let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
                if (axis - Vector3::z()).norm() > 1e-9 {
                    return Err(bad(name, "axis is not 0 0 1: no DH reading"));
                }
                origins.push(isometry_from_urdf_pose(&j.origin));
            }
            let mut dh = [IRB14000_NOMINAL_DH[0]; N_JOINTS];
            for k in 0..N_JOINTS - 1 {
                let origin = if k == 0 {
                    joint1_from_dh_base().inverse() * origins[1]
                } else {
                    origins[k + 1]
                };
                dh[k] = dh_row_from_origin(&origin)
                    .ok_or_else(|| bad(&names[k + 1], "origin is not of DH form Rz Tz Tx Rx"))?;
            }
            let link7 = link_pose(&arm_link_name(side, N_JOINTS))
                .ok_or_else(|| bad(&names[N_JOINTS - 1], "its child link_7 is missing"))?;
            let flange = poses[self.kin.flange[side]];
            dh[N_JOINTS - 1] =
                dh_row_from_origin(&(link7.inverse() * flange)).ok_or_else(|| {
                    bad(
                        &names[N_JOINTS - 1],
                        "flange is not at a DH offset of link 7",
                    )
                })?;
            let mut reflectors = reflectors_mm.to_vec();
            for (k, r) in reflector_names.iter().enumerate() {
                if let Some(p) = link_pose(&format!("reflector_{r}_{}", side_suffix(side))) {
                    reflectors[k] = (flange.inverse() * p).translation.vector;
                }
            }
            Ok(ArmModel {
                kinematics: ArmKinematics::Dh(dh),
                reflectors_mm: reflectors,
                reflector_names: reflector_names.clone(),
                errors: Default::default(),
            })
        })?;
        let base = PerSide::from_fn(|side| self.body_from_dh_base(side));
        Ok(DualArmModel {
            arms,
            left_base_from_right_base: base.left.inverse() * base.right,
        })
    }
}
