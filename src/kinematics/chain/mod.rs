//! An arm as the serial chain of a URDF between a base link and a tip link, its forward kinematics,
//! and its calibration parametrisation.
//!
//! **The chain.** The joints on the path from `base_link` down to `tip_link`, in chain order. Each
//! revolute, continuous or prismatic joint is a *movable joint*; fixed joints are folded into the
//! origin of the next movable joint, or into [`SerialChain::last_from_tip`] after the last one. A
//! movable joint is driven ([`JointDrive`]) by its own *variable* (the CSV's `q1 … qN` count the
//! variables, in chain order: rad for a revolute joint, mm for a prismatic one — the URDF joint's own
//! variable in the program's units), or, with a URDF `<mimic joint multiplier offset>`, by another
//! joint (`value = multiplier · leader + offset`, a leader that mimics another followed to the joint
//! that mimics none; no CSV column). A leader *off the chain* (a lifting column's measured joint on a
//! side branch, followed by the column's real stages on the chain) is a variable of its own
//! ([`ChainVariable`]), standing where its first follower stands in chain order, with its own limits;
//! it has no correction (its origin moves nothing on the chain), its followers have theirs. A leader
//! off the chain that no joint of the chain follows is no variable. Floating, planar and spherical
//! joints, a mimic of a joint the description lacks or of a fixed one, a mimic loop, a missing link
//! and a tip that is not below the base are refused with a [`ChainError`] naming the link or joint.
//! The joint origins are taken as they are: no DH form is needed. Lengths in mm, angles in rad.
//!
//! **The parametrisation.** Every movable joint k gets a small correction `Δ_k` of its origin,
//! inserted between the URDF origin and the joint rotation and expressed in the joint's *aligned
//! frame* (the joint frame turned by a constant rotation `C_k` so that its z axis is the joint axis;
//! `C_k = I` when the URDF axis is +z):
//!
//! ```text
//! prev_from_child_k(q) = P_k · O_k · C_k · Δ_k · Rz(q_k) · C_kᵀ     (revolute, continuous)
//! prev_from_child_k(q) = P_k · O_k · C_k · Δ_k · Tz(q_k) · C_kᵀ     (prismatic)
//! Δ_k = T(tx, ty, tz) · Rx(rx) · Ry(ry) · Rz(rz)
//! ```
//!
//! (For a prismatic joint `tz` is its zero offset, `rx, ry` tilt its direction, and `tx, ty, rz` move
//! what follows as the next joint's origin does — the identifiability analysis finds which.)
//!
//! (`P_k` the fixed joints folded before joint k, `O_k` its URDF `<origin>`), so `rz` is the joint's
//! zero offset, `tz` a shift along its axis, and `tx, ty, rx, ry` move the axis line. Six per joint and
//! the three reflector coordinates in the tip frame: `6n + 9` parameters, of which distance data
//! identify `4n + 3` ([`minimal_parameter_count`]); the identifiability analysis picks which, in the
//! order of [`SerialChain::preference_order`]. The corrected URDF origin is `O_k · C_k Δ_k C_kᵀ`
//! ([`SerialChain::corrected_origins`]): a change of the joint's own origin by exactly the
//! correction, in the URDF's own frames.
//!
//! **Jacobians** (exact at any correction, [`SerialChain::reflector_jacobians`]): with `R`, `o` the
//! aligned frame before the correction and `o' = o + R t` its corrected origin, a translation moves a
//! point along its axis (`R e_x` …), a rotation about axis `w` through `o'` moves point p by
//! `w × (p − o')` (`w` = `R e_x`, `R Rx(rx) e_y`, `R Rx(rx) Ry(ry) e_z` for the three elementary
//! rotations), and the reflector coordinates move with the tip rotation.

mod build;
#[cfg(test)]
pub(crate) mod tests;

use super::{ArmJacobians, REFLECTOR_NAMES, ReflectorFk};
pub(crate) use build::finite_pose;
pub use build::{isometry_from_urdf_pose, rpy_from_rotation};
use nalgebra::{Isometry3, Matrix3xX, Translation3, Unit, UnitQuaternion, Vector3};

/// Correction parameters per movable joint: `tx, ty, tz` (mm), `rx, ry, rz` (rad).
pub const PARAMS_PER_JOINT: usize = 6;
/// Names of the six correction parameters of a joint, in parameter order.
pub const CORRECTION_NAMES: [&str; PARAMS_PER_JOINT] = ["tx", "ty", "tz", "rx", "ry", "rz"];

/// Why a chain cannot be built from a robot description, or does not fit the data.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChainError {
    #[error("{role} link `{link}` is not a link of the robot description")]
    UnknownLink { role: &'static str, link: String },
    #[error("tip link `{tip}` is not below base link `{base}` in the robot description")]
    NoPath { base: String, tip: String },
    #[error(
        "joint `{joint}` between `{base}` and `{tip}` is {kind}; an arm chain may only hold revolute, \
         continuous, prismatic and fixed joints"
    )]
    UnsupportedJoint {
        joint: String,
        kind: &'static str,
        base: String,
        tip: String,
    },
    #[error(
        "joint `{joint}` mimics `{mimicked}`, which is not a joint of the robot description: its \
         value cannot follow from the arm's joint columns"
    )]
    MimicOutsideChain { joint: String, mimicked: String },
    #[error(
        "joint `{joint}` mimics `{leader}`, which is {kind}: a leader off the arm's chain must be a \
         revolute, continuous or prismatic joint (its value is the arm's joint column)"
    )]
    LeaderNotMovable {
        joint: String,
        leader: String,
        kind: &'static str,
    },
    #[error("joint `{joint}`: its <mimic> leads back to itself ({cycle}): a mimic loop")]
    MimicLoop { joint: String, cycle: String },
    #[error(
        "joint `{joint}`: its <mimic> multiplier or offset is not finite, or the multiplier is 0"
    )]
    BadMimic { joint: String },
    #[error("joint `{joint}`: its axis {axis:?} has zero length or is not finite")]
    BadAxis { joint: String, axis: [f64; 3] },
    #[error("joint `{joint}`: its origin is not finite")]
    NonFiniteOrigin { joint: String },
    #[error("joint `{joint}`: lower limit {lower} is above upper limit {upper}, or not finite")]
    BadLimits {
        joint: String,
        lower: f64,
        upper: f64,
    },
    #[error(
        "no revolute, continuous or prismatic joint driven by its own value between `{base}` and `{tip}`"
    )]
    NoMovableJoint { base: String, tip: String },
}

impl ChainError {
    /// The joint or link the error is about.
    pub fn subject(&self) -> Option<&str> {
        match self {
            ChainError::UnknownLink { .. } | ChainError::NoPath { .. } => None,
            ChainError::NoMovableJoint { .. } => None,
            ChainError::UnsupportedJoint { joint, .. }
            | ChainError::MimicOutsideChain { joint, .. }
            | ChainError::LeaderNotMovable { joint, .. }
            | ChainError::MimicLoop { joint, .. }
            | ChainError::BadMimic { joint }
            | ChainError::BadAxis { joint, .. }
            | ChainError::NonFiniteOrigin { joint }
            | ChainError::BadLimits { joint, .. } => Some(joint),
        }
    }
}

/// The two links that delimit an arm's chain.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ArmLinks {
    pub base_link: String,
    pub tip_link: String,
}

impl ArmLinks {
    pub fn new(base_link: impl Into<String>, tip_link: impl Into<String>) -> Self {
        Self {
            base_link: base_link.into(),
            tip_link: tip_link.into(),
        }
    }

    /// Parse `BASE:TIP` (the command line's `--left`/`--right`).
    pub fn parse(text: &str) -> Result<Self, String> {
        match text.split_once(':') {
            Some((base, tip)) if !base.trim().is_empty() && !tip.trim().is_empty() => {
                Ok(Self::new(base.trim(), tip.trim()))
            }
            _ => Err(format!(
                "`{text}` is not BASE:TIP (the arm's base link and tip link, e.g. yumi_body:yumi_link_7_l)"
            )),
        }
    }
}

impl std::fmt::Display for ArmLinks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} → {}", self.base_link, self.tip_link)
    }
}

/// Revolute (limited), continuous (unlimited) or prismatic (a linear axis: a torso lift) joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MovableKind {
    Revolute,
    Continuous,
    Prismatic,
}

impl MovableKind {
    /// A linear joint: its value is a length (mm), not an angle (rad).
    pub fn is_linear(self) -> bool {
        self == MovableKind::Prismatic
    }

    /// The unit of the joint's value inside the program.
    pub fn unit(self) -> &'static str {
        if self.is_linear() { "mm" } else { "rad" }
    }
}

/// Where a movable joint's value comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointDrive {
    /// Its own variable `q[index]` (the CSV's `q{index + 1}`).
    Variable(usize),
    /// A URDF `<mimic>`: `multiplier · q[leader] + offset`, converted to the program's units (the
    /// offset in this joint's unit, the multiplier from the leader's unit to this joint's).
    Mimic {
        leader: usize,
        multiplier: f64,
        offset: f64,
    },
}

impl JointDrive {
    /// The joint's value at the variables `q` (a missing variable counts as zero).
    #[inline]
    pub fn value(&self, q: &[f64]) -> f64 {
        match *self {
            JointDrive::Variable(i) => q.get(i).copied().unwrap_or(0.0),
            JointDrive::Mimic {
                leader,
                multiplier,
                offset,
            } => multiplier * q.get(leader).copied().unwrap_or(0.0) + offset,
        }
    }

    /// The variable of a joint driven by its own.
    pub fn variable(&self) -> Option<usize> {
        match *self {
            JointDrive::Variable(i) => Some(i),
            JointDrive::Mimic { .. } => None,
        }
    }

    /// The variable a mimic joint follows.
    pub fn leader(&self) -> Option<usize> {
        match *self {
            JointDrive::Variable(_) => None,
            JointDrive::Mimic { leader, .. } => Some(leader),
        }
    }
}

/// A joint value a configuration gives (a CSV column, `q[i]`), in chain order: a movable joint of the
/// chain driven by its own value, or a *leader off the chain* — a joint on a side branch that joints
/// of the chain follow by their `<mimic>` (a lifting column's measured joint, a virtual joint whose
/// followers are the column's real stages). A leader off the chain stands where its first follower
/// stands in chain order; its origin moves nothing on the chain, so it has no correction.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainVariable {
    /// The URDF joint's name.
    pub name: String,
    pub kind: MovableKind,
    /// `(lower, upper)` as the URDF gives them, in the joint's unit (rad; mm for a prismatic joint);
    /// `None` for a continuous joint. A leader's limits are its column's.
    pub limits: Option<(f64, f64)>,
    /// The chain joint (index into [`SerialChain::joints`]) this is the own value of; `None` for a
    /// leader off the chain.
    pub joint: Option<usize>,
}

impl ChainVariable {
    /// The range the value may take, in its unit: its limits, or ±π for a continuous joint.
    pub fn range(&self) -> (f64, f64) {
        self.limits
            .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI))
    }

    /// A leader off the chain (only followed by joints of the chain)?
    pub fn is_off_chain(&self) -> bool {
        self.joint.is_none()
    }
}

/// One movable joint of a chain.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainJoint {
    /// The URDF joint's name.
    pub name: String,
    pub kind: MovableKind,
    /// The URDF `<origin>` of this joint (mm), i.e. `parent_link_from_joint`.
    pub parent_from_joint: Isometry3<f64>,
    /// The fixed joints between the previous movable joint's child link (or the base link) and this
    /// joint's parent link, folded: `prev_from_parent` (identity when there are none).
    pub prev_from_parent: Isometry3<f64>,
    /// Names of those fixed joints, in chain order.
    pub folded_fixed: Vec<String>,
    /// Unit joint axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
    /// `(lower, upper)` as the URDF gives them, in the joint's unit (rad; mm for a prismatic joint);
    /// `None` for a continuous joint.
    pub limits: Option<(f64, f64)>,
    /// Its own variable, or the joint it mimics.
    pub drive: JointDrive,
    /// The URDF joint it mimics (its `<mimic joint>`), if any.
    pub mimics: Option<String>,
    /// `C_k`: the joint frame's rotation to the aligned frame (whose z axis is the joint axis).
    pub joint_from_aligned: UnitQuaternion<f64>,
    /// The joint's parent and child links.
    pub parent_link: String,
    pub child_link: String,
}

impl ChainJoint {
    /// The range a joint may take, in its unit: its limits, or ±π for a continuous joint.
    pub fn range(&self) -> (f64, f64) {
        self.limits
            .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI))
    }

    /// The joint's displacement at value `v` (rad or mm) after its correction's `Rx Ry` and `rz`:
    /// `T(t) Rx(rx) Ry(ry) Rz(rz + v)` for a revolute joint, `T(t) Rx(rx) Ry(ry) Rz(rz) Tz(v)` for a
    /// prismatic one.
    #[inline]
    fn moved(&self, c: &[f64; PARAMS_PER_JOINT], v: f64) -> Isometry3<f64> {
        if self.kind.is_linear() {
            let r = rot_x(c[3]) * rot_y(c[4]) * rot_z(c[5]);
            let t = Vector3::new(c[0], c[1], c[2]) + r * Vector3::new(0.0, 0.0, v);
            Isometry3::from_parts(Translation3::from(t), r)
        } else {
            Isometry3::from_parts(
                Translation3::new(c[0], c[1], c[2]),
                rot_x(c[3]) * rot_y(c[4]) * rot_z(c[5] + v),
            )
        }
    }
}

/// The serial chain of a robot description between two links.
#[derive(Clone, Debug, PartialEq)]
pub struct SerialChain {
    pub base_link: String,
    pub tip_link: String,
    pub joints: Vec<ChainJoint>,
    /// The variables (the CSV's joint columns), in chain order: the movable joints that mimic none,
    /// and the leaders off the chain that joints of the chain mimic.
    variables: Vec<ChainVariable>,
    /// The fixed joints after the last movable joint, folded: `last_child_from_tip`.
    pub last_from_tip: Isometry3<f64>,
    /// Things the user should know (a revolute joint without limits, …).
    pub warnings: Vec<String>,
    /// `B_k = C_{k−1}ᵀ · prev_from_parent · parent_from_joint · C_k` (C_0 = I): the aligned frame of
    /// joint k in the rotated aligned frame of joint k − 1 (or the base link).
    prev_aligned_from_aligned: Vec<Isometry3<f64>>,
    /// `C_nᵀ · last_from_tip`.
    last_aligned_from_tip: Isometry3<f64>,
}

fn rot_x(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a)
}
fn rot_y(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a)
}
fn rot_z(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
}

/// `Δ = T(tx, ty, tz) Rx(rx) Ry(ry) Rz(rz)`.
pub fn correction_transform(c: &[f64; PARAMS_PER_JOINT]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(c[0], c[1], c[2]),
        rot_x(c[3]) * rot_y(c[4]) * rot_z(c[5]),
    )
}

/// The angles `(a, b, c)` with `q = Rx(a) · Ry(b) · Rz(c)` (the rotation of [`correction_transform`]).
pub fn xyz_angles(q: &UnitQuaternion<f64>) -> [f64; 3] {
    let m = q.to_rotation_matrix().into_inner();
    let b = m[(0, 2)].clamp(-1.0, 1.0).asin();
    let a = (-m[(1, 2)]).atan2(m[(2, 2)]);
    let c = (-m[(0, 1)]).atan2(m[(0, 0)]);
    [a, b, c]
}

/// The number of parameters distance-only data can identify for an arm of `revolute` revolute
/// joints measured at three points: the axes at q = 0 are lines (4 each, the product-of-exponentials
/// count), the three points add 9, and a rigid motion of everything (6) leaves every distance alone:
/// `4R + 9 − 6 = 4R + 3` (31 for the 7-joint YuMi arm = 37 DH+reflector parameters − 6 fixed).
pub const fn minimal_parameter_count(revolute: usize) -> usize {
    4 * revolute + 3
}

impl SerialChain {
    /// Number of variables: the joint values a configuration gives (the CSV's `q1 … qN`), one per
    /// movable joint that mimics none and one per leader off the chain.
    pub fn dof(&self) -> usize {
        self.variables.len()
    }

    /// Number of movable joints (mimic joints included): the correction blocks.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// The variables, in variable order (the CSV's `q1 … qN`).
    pub fn variables(&self) -> &[ChainVariable] {
        &self.variables
    }

    /// Names of the variables' joints (the CSV's `q1 … qN`).
    pub fn variable_names(&self) -> Vec<&str> {
        self.variables.iter().map(|v| v.name.as_str()).collect()
    }

    /// `(lower, upper)` of every variable, in its unit (rad; mm for a prismatic joint).
    pub fn variable_ranges(&self) -> Vec<(f64, f64)> {
        self.variables.iter().map(ChainVariable::range).collect()
    }

    /// Is variable `i` a length (a prismatic joint's, mm) rather than an angle (rad)?
    pub fn variable_is_linear(&self, i: usize) -> bool {
        self.variables.get(i).is_some_and(|v| v.kind.is_linear())
    }

    /// Every movable joint's value (rad or mm) at the variables `q`.
    pub fn joint_values(&self, q: &[f64]) -> Vec<f64> {
        self.joints.iter().map(|j| j.drive.value(q)).collect()
    }

    /// Number of parameters with `reflectors` reflectors: six corrections per movable joint and three
    /// coordinates per reflector.
    pub fn param_count(&self, reflectors: usize) -> usize {
        PARAMS_PER_JOINT * self.joint_count() + 3 * reflectors
    }

    /// Index of the first reflector coordinate in the parameter vector.
    pub fn reflector_offset(&self) -> usize {
        PARAMS_PER_JOINT * self.joint_count()
    }

    /// Name of parameter `k`: `<joint>.tx` … `<joint>.rz`, `t_a.x` … `t_c.z`.
    pub fn param_name(&self, k: usize) -> String {
        let off = self.reflector_offset();
        if k < off {
            format!(
                "{}.{}",
                self.joints[k / PARAMS_PER_JOINT].name,
                CORRECTION_NAMES[k % PARAMS_PER_JOINT]
            )
        } else if k < off + 3 * REFLECTOR_NAMES.len() {
            format!(
                "t_{}.{}",
                REFLECTOR_NAMES[(k - off) / 3],
                ["x", "y", "z"][(k - off) % 3]
            )
        } else {
            format!("p{k}")
        }
    }

    /// Is parameter `k` an angle (rad) rather than a length (mm)?
    pub fn param_is_angle(&self, k: usize) -> bool {
        k < self.reflector_offset() && k % PARAMS_PER_JOINT >= 3
    }

    /// Names of the movable joints in chain order (mimic joints included: one correction block each).
    pub fn joint_names(&self) -> Vec<&str> {
        self.joints.iter().map(|j| j.name.as_str()).collect()
    }

    /// `base → tip` with the joint count, for messages.
    pub fn describe(&self) -> String {
        format!(
            "{} → {} ({} joints)",
            self.base_link,
            self.tip_link,
            self.dof()
        )
    }

    /// Tip pose in the base link's frame (mm) with the given corrections (one block per movable
    /// joint); `q_rad` the variables in chain order (rad, mm for a prismatic joint; missing values
    /// count as zero, extra ones are ignored).
    pub fn base_from_tip(
        &self,
        corrections: &[[f64; PARAMS_PER_JOINT]],
        q_rad: &[f64],
    ) -> Isometry3<f64> {
        debug_assert_eq!(q_rad.len(), self.dof());
        let mut f = Isometry3::identity();
        for ((b, c), j) in self
            .prev_aligned_from_aligned
            .iter()
            .zip(corrections)
            .zip(&self.joints)
        {
            // Δ · Rz(q) = T(t) Rx Ry Rz(rz + q), or Δ · Tz(q) for a prismatic joint.
            f = f * b * j.moved(c, j.drive.value(q_rad));
        }
        f * self.last_aligned_from_tip
    }

    /// The nominal tip pose (all corrections zero).
    pub fn nominal_base_from_tip(&self, q_rad: &[f64]) -> Isometry3<f64> {
        self.base_from_tip(&vec![[0.0; PARAMS_PER_JOINT]; self.joint_count()], q_rad)
    }

    /// The aligned frame of every movable joint (z = its axis, after its correction's translation
    /// and tilt) in the base link's frame, then the tip frame.
    pub fn joint_frames(
        &self,
        corrections: &[[f64; PARAMS_PER_JOINT]],
        q_rad: &[f64],
    ) -> Vec<Isometry3<f64>> {
        let mut out = Vec::with_capacity(self.joint_count() + 1);
        let mut f = Isometry3::identity();
        for ((b, c), j) in self
            .prev_aligned_from_aligned
            .iter()
            .zip(corrections)
            .zip(&self.joints)
        {
            f *= b;
            out.push(
                f * Isometry3::from_parts(
                    Translation3::new(c[0], c[1], c[2]),
                    rot_x(c[3]) * rot_y(c[4]),
                ),
            );
            f *= j.moved(c, j.drive.value(q_rad));
        }
        out.push(f * self.last_aligned_from_tip);
        out
    }

    /// Reflector positions, tip pose and the analytic Jacobians with respect to all parameters
    /// (corrections of every joint, then the reflector coordinates).
    pub fn reflector_jacobians(
        &self,
        corrections: &[[f64; PARAMS_PER_JOINT]],
        reflectors_mm: &[Vector3<f64>],
        q_rad: &[f64],
    ) -> ArmJacobians {
        let n = self.joint_count();
        // Per joint: the three translation directions, the three rotation axes and the corrected
        // origin o' through which they pass.
        let mut dirs: Vec<[Vector3<f64>; 6]> = Vec::with_capacity(n);
        let mut origins: Vec<Vector3<f64>> = Vec::with_capacity(n);
        let mut f = Isometry3::identity();
        for ((b, c), j) in self
            .prev_aligned_from_aligned
            .iter()
            .zip(corrections)
            .zip(&self.joints)
        {
            let q = j.drive.value(q_rad);
            f *= b;
            let r = f.rotation;
            let rx = rot_x(c[3]);
            let rxy = rx * rot_y(c[4]);
            let t = Vector3::new(c[0], c[1], c[2]);
            origins.push(f.translation.vector + r * t);
            dirs.push([
                r * Vector3::x(),
                r * Vector3::y(),
                r * Vector3::z(),
                r * Vector3::x(),
                r * (rx * Vector3::y()),
                r * (rxy * Vector3::z()),
            ]);
            // A rotation of the correction turns everything after it about o', the prismatic
            // joint's travel included: the columns above hold for both kinds.
            f *= if j.kind.is_linear() {
                let r = rxy * rot_z(c[5]);
                Isometry3::from_parts(Translation3::from(t + r * Vector3::new(0.0, 0.0, q)), r)
            } else {
                Isometry3::from_parts(Translation3::from(t), rxy * rot_z(c[5] + q))
            };
        }
        let tip = f * self.last_aligned_from_tip;
        let points_mm: Vec<Vector3<f64>> = reflectors_mm
            .iter()
            .map(|t| tip.transform_point(&(*t).into()).coords)
            .collect();
        let rot_tip = tip.rotation.to_rotation_matrix().into_inner();
        let cols = self.param_count(reflectors_mm.len());
        let off = self.reflector_offset();
        let jacobians = (0..points_mm.len())
            .map(|k| {
                let p = points_mm[k];
                let mut j = Matrix3xX::zeros(cols);
                for (i, (d, o)) in dirs.iter().zip(&origins).enumerate() {
                    let lever = p - o;
                    let base = PARAMS_PER_JOINT * i;
                    for c in 0..3 {
                        j.set_column(base + c, &d[c]);
                        j.set_column(base + 3 + c, &d[3 + c].cross(&lever));
                    }
                }
                j.fixed_view_mut::<3, 3>(0, off + 3 * k).copy_from(&rot_tip);
                j
            })
            .collect();
        ArmJacobians {
            fk: ReflectorFk {
                points_mm,
                base_from_flange: tip,
            },
            jacobians,
        }
    }

    /// The corrected URDF `<origin>` of every movable joint (mm): `O_k · C_k Δ_k C_kᵀ`.
    pub fn corrected_origins(
        &self,
        corrections: &[[f64; PARAMS_PER_JOINT]],
    ) -> Vec<(String, Isometry3<f64>)> {
        self.joints
            .iter()
            .zip(corrections)
            .map(|(j, c)| {
                let cj = Isometry3::from_parts(Translation3::identity(), j.joint_from_aligned);
                (
                    j.name.clone(),
                    j.parent_from_joint * cj * correction_transform(c) * cj.inverse(),
                )
            })
            .collect()
    }

    /// The URDF origin of this chain's first movable joint that puts its base frame where step 2 of
    /// the calibration found it: the chain is measured in another frame F (the first arm's base),
    /// `f_from_base_nominal` is the base link in F from the URDF tree and `f_from_base_calibrated` the
    /// calibrated one. The base link itself stays where the tree puts it; only joint 1's origin moves
    /// by the (small) base correction: `O₁' = P⁻¹ N⁻¹ C P O₁` with P the fixed joints folded before
    /// joint 1, N nominal, C calibrated.
    pub fn first_origin_with_base_correction(
        &self,
        first_origin: &Isometry3<f64>,
        f_from_base_nominal: &Isometry3<f64>,
        f_from_base_calibrated: &Isometry3<f64>,
    ) -> Isometry3<f64> {
        let p = self.joints[0].prev_from_parent;
        p.inverse() * f_from_base_nominal.inverse() * f_from_base_calibrated * p * first_origin
    }

    /// The correction of joint `k` that puts the part of the chain from joint `k` on where a base
    /// correction puts it, the joints before `k` at their values for all-zero joint values: for a
    /// chain whose first joints are shared with the other arm (a torso), whose base cannot move on its
    /// own. With `A` joint `k`'s aligned frame before its correction (in the base frame), `N` and `C`
    /// the base in F nominal and calibrated: `Δ'ₖ = A⁻¹ N⁻¹ C A Δₖ`. Exact for every configuration
    /// where the base correction commutes with the motion of the joints before `k` (a turn about and a
    /// shift along a shared joint's axis — what the arm's own distances cannot see); at the shared
    /// joints' zero otherwise.
    pub fn correction_with_base_correction(
        &self,
        corrections: &[[f64; PARAMS_PER_JOINT]],
        k: usize,
        f_from_base_nominal: &Isometry3<f64>,
        f_from_base_calibrated: &Isometry3<f64>,
    ) -> [f64; PARAMS_PER_JOINT] {
        let q0 = vec![0.0; self.dof()];
        let mut a = Isometry3::identity();
        for ((b, c), j) in self
            .prev_aligned_from_aligned
            .iter()
            .zip(corrections)
            .zip(&self.joints)
            .take(k)
        {
            a *= b;
            a *= j.moved(c, j.drive.value(&q0));
        }
        a *= self.prev_aligned_from_aligned[k];
        let delta = a.inverse()
            * f_from_base_nominal.inverse()
            * f_from_base_calibrated
            * a
            * correction_transform(&corrections[k]);
        let t = delta.translation.vector;
        let [rx, ry, rz] = xyz_angles(&delta.rotation);
        [t.x, t.y, t.z, rx, ry, rz]
    }

    /// Is joint `k`'s axis parallel to joint `k − 1`'s (at q = 0, within 1e-6 rad)?
    pub fn parallel_to_previous(&self, k: usize) -> bool {
        if k == 0 || k >= self.joint_count() {
            return false;
        }
        // Joint k's axis in the aligned frame of joint k − 1 (whose z is that joint's axis).
        let axis = self.prev_aligned_from_aligned[k].rotation * Vector3::z();
        axis.cross(&Vector3::z()).norm() < 1e-6
    }

    /// Greedy preference order of the identifiability analysis, *base first*: the reflector
    /// coordinates, then joints 1 … n, each `rz` (the joint offset), `tz` (a shift along the axis),
    /// then the axis line `tx, ty, rx, ry`. Joint offsets and shifts stay where they are; of each axis
    /// line only what the previous joint's offset and shift cannot explain is kept (for an axis
    /// parallel to the previous one, Hayati's tilt instead of the shift). Joint 1's six are a rigid
    /// motion of the arm and are fixed, the last joint's offset and shift go to the reflectors. Real
    /// robots' largest errors are joint offsets (encoder zeros): this order keeps them as offsets.
    pub fn preference_order(&self, reflectors: usize) -> Vec<usize> {
        let off = self.reflector_offset();
        let mut out: Vec<usize> = (off..off + 3 * reflectors).collect();
        for (k, j) in self.joints.iter().enumerate() {
            let b = PARAMS_PER_JOINT * k;
            if j.kind.is_linear() {
                // A linear axis: its zero offset, its direction, then what the next joint's origin
                // would otherwise hold.
                out.extend([b + 2, b + 3, b + 4, b + 5, b, b + 1]);
            } else {
                out.extend([b + 5, b + 2, b, b + 1, b + 3, b + 4]);
            }
        }
        out
    }

    /// Why correction parameter `k` cannot be identified from distances, when physics says so.
    pub fn physical_reason(&self, k: usize) -> Option<String> {
        if k >= self.reflector_offset() {
            return None;
        }
        let (joint, c) = (k / PARAMS_PER_JOINT, k % PARAMS_PER_JOINT);
        let name = &self.joints[joint].name;
        if self.joints[joint].kind.is_linear() && joint > 0 {
            return match c {
                0 | 1 | 5 => Some(format!(
                    "`{name}` is prismatic: its axis is a direction, so shifting it or turning about it moves what follows as the next joint's origin does"
                )),
                _ => None,
            };
        }
        if joint == 0 {
            return Some(format!(
                "`{name}` is the first joint: moving its origin moves the whole arm rigidly, which the \
                 tracker frame absorbs"
            ));
        }
        match c {
            2 | 5 if joint + 1 == self.joint_count() => Some(format!(
                "`{name}` is the last joint: a {} its axis moves the tip frame alike and is absorbed by \
                 the reflector coordinates",
                if c == 2 { "shift along" } else { "turn about" }
            )),
            2 if self.parallel_to_previous(joint) => Some(format!(
                "`{name}`'s axis is parallel to `{}`'s: a shift along it equals that joint's shift \
                 (the tilt, Hayati's β, is identified instead)",
                self.joints[joint - 1].name
            )),
            0 | 1 | 3 | 4 if self.axis_line_absorbed(joint, c) => Some(format!(
                "moves `{name}`'s axis as `{}`'s offset or shift along its own axis does",
                self.joints[joint - 1].name
            )),
            _ => None,
        }
    }

    /// Whether correction `c` (`tx`, `ty`, `rx` or `ry`) of joint `k` is what joint k − 1's offset
    /// and shift along its axis already do to joint k's axis line. With `a` the previous axis in joint
    /// k's aligned frame, a shift along it is `a.x·tx + a.y·ty + a.z·tz` and a turn about it
    /// `a.x·rx + a.y·ry + a.z·rz` and a shift. The analysis keeps joint k's offset and shift first, then
    /// `tx` before `ty` and `rx` before `ry` ([`Self::preference_order`]), so of each pair it is the
    /// later one with a share of `a` that is absorbed: `ty` and `ry` where `a.y ≠ 0`, else `tx` and
    /// `rx`. (For the joint after the first the two motions are rigid ones of the whole arm, which the
    /// tracker frame absorbs: the same pair.) For an axis parallel to the previous one the shift is
    /// `tz` (Hayati's case) and a turn about the previous axis — through its origin `o` in joint k's
    /// frame — is joint k's offset and the shift `(o.y, −o.x)`: `ty` is absorbed where `o.x ≠ 0`, else
    /// `tx`; the tilts stay. Coincident axes and joints after a prismatic one are left to the analysis'
    /// numbers: physics names only what it is sure of.
    fn axis_line_absorbed(&self, k: usize, c: usize) -> bool {
        if k == 0 || self.joints[k - 1].kind.is_linear() {
            return false;
        }
        let previous_from_this = &self.prev_aligned_from_aligned[k];
        if self.parallel_to_previous(k) {
            let o =
                -(previous_from_this.rotation.inverse() * previous_from_this.translation.vector);
            return if o.x.abs() > 1e-6 {
                c == 1
            } else if o.y.abs() > 1e-6 {
                c == 0
            } else {
                false
            };
        }
        let previous_axis = previous_from_this.rotation.inverse() * Vector3::z();
        let has_y = previous_axis.y.abs() > 1e-6;
        match c {
            1 | 4 => has_y,
            0 | 3 => !has_y,
            _ => false,
        }
    }

    /// The tool axis in the tip frame: the last joint's axis, signed to point away from the previous
    /// joint's origin at q = 0 (the way a flange faces). Used to face simulated reflectors to the
    /// tracker and to place default reflectors.
    pub fn tool_axis(&self) -> Unit<Vector3<f64>> {
        let zero = vec![[0.0; PARAMS_PER_JOINT]; self.joint_count()];
        let q = vec![0.0; self.dof()];
        let frames = self.joint_frames(&zero, &q);
        let n = self.joint_count();
        let tip = frames[n];
        let last = frames[n - 1];
        let axis_base = last.rotation * Vector3::z();
        let from = if n >= 2 {
            frames[n - 2].translation.vector
        } else {
            Vector3::zeros()
        };
        let away = tip.translation.vector - from;
        let signed = if axis_base.dot(&away) < 0.0 {
            -axis_base
        } else {
            axis_base
        };
        Unit::new_normalize(tip.rotation.inverse() * signed)
    }
}
