//! The geometric model of the robot: each arm's kinematics and reflectors, and the right-arm base in
//! the left-arm base frame.
//!
//! An arm's kinematics take one of two forms ([`ArmKinematics`]):
//!
//! - **DH** — the built-in ABB IRB 14000: the paper's standard Denavit–Hartenberg table (Table 3),
//!   seven joints, 28 values ([`dh`]). Its calibrations are exactly those of earlier releases.
//! - **Chain** — any other robot: the serial chain of a URDF between a base link and a tip link
//!   ([`SerialChain`]), with however many revolute joints it has, its joint origins as the URDF writes
//!   them, and a small correction of each joint origin as the calibration parameters ([`chain`]).
//!
//! Either way the model's base frame is the arm's *model base* (the DH frame 0, or the chain's base
//! link), its tip the flange (DH frame 7) or the tip link, and its reflectors (one or more, named:
//! `t_a, t_b, t_c` in the paper's set-up) are constant points in the tip frame. Lengths in mm, angles
//! in rad; joint values in chain order.
//!
//! The parameter vector of an arm ([`ArmModel::to_vector`]) is the kinematic parameters followed by
//! three coordinates per reflector; [`ArmModel::param_name`] names them and [`ArmModel::with_vector`]
//! builds the model back.

pub mod chain;
pub mod dh;
pub mod joint_errors;
mod per_reflector;
pub mod shared;
#[cfg(test)]
pub(crate) mod tests;

use crate::side::{PerSide, Side};
pub use chain::{
    ArmLinks, CORRECTION_NAMES, ChainError, ChainJoint, ChainVariable, JointDrive, MovableKind,
    PARAMS_PER_JOINT, SerialChain, correction_transform, minimal_parameter_count,
    rpy_from_rotation,
};
pub use dh::{
    ABB_AXIS_OF_CHAIN, DhRow, IRB14000_NOMINAL_DH, JOINT_LIMITS_DEG, N_DH, N_JOINTS, N_PARAMS,
    ParamVector, PointJacobian, joint_limits_rad, param_is_angle, param_name,
};
pub use joint_errors::{ErrorTerms, JointErrorModel, JointErrors};
use nalgebra::{DVector, Isometry3, Matrix3xX, Matrix6xX, Vector3};
pub use per_reflector::{MAX_REFLECTORS, PerReflector};
pub use shared::SharedJoints;
use std::sync::Arc;

/// Reflector labels of the paper's set-up, in file order.
pub const REFLECTOR_NAMES: [&str; 3] = ["a", "b", "c"];

/// The pairs of `n` reflectors whose distances the data and the constraints use: the triangle's sides
/// `ab, bc, ca` for three (the paper's constraints (14), in this order), every pair `i < j` otherwise
/// (none for one reflector).
pub fn reflector_pairs(n: usize) -> Vec<(usize, usize)> {
    if n == 3 {
        vec![(0, 1), (1, 2), (2, 0)]
    } else {
        (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .collect()
    }
}

/// Distances between the reflectors, in the order of [`reflector_pairs`] (|ab|, |bc|, |ca| for
/// three), mm; none for one reflector.
pub fn reflector_sides(p: &[Vector3<f64>]) -> Vec<f64> {
    reflector_pairs(p.len())
        .into_iter()
        .map(|(i, j)| (p[i] - p[j]).norm())
        .collect()
}

/// The sides of the reflectors `p` minus `reference` (a model's sides, or an arm's median triangle),
/// mm, with the largest |difference| first (0 for one reflector).
pub fn side_deviations(p: &[Vector3<f64>], reference: &[f64]) -> (f64, Vec<f64>) {
    let d: Vec<f64> = reflector_sides(p)
        .iter()
        .zip(reference)
        .map(|(s, r)| s - r)
        .collect();
    (d.iter().fold(0.0, |m, x| m.max(x.abs())), d)
}

/// The default names of `n` reflectors: `a`, `b`, `c`, … (`r27`, … beyond the alphabet).
pub fn default_reflector_names(n: usize) -> Arc<[String]> {
    (0..n)
        .map(|k| match u8::try_from(k) {
            Ok(k) if k < 26 => char::from(b'a' + k).to_string(),
            _ => format!("r{}", k + 1),
        })
        .collect()
}

/// The kinematic part of one arm's model.
#[derive(Clone, Debug, PartialEq)]
// On wasm32 (4-byte pointers) the `Chain` variant is 16 bytes, and its difference to the DH table's
// 224 passes clippy's 200-byte limit (natively 192): the same table as natively, kept unboxed (no
// allocation per model copy in the solver).
#[cfg_attr(target_arch = "wasm32", allow(clippy::large_enum_variant))]
pub enum ArmKinematics {
    /// Standard DH, seven joints in chain order (ABB axes 1, 2, 7, 3, 4, 5, 6): the built-in IRB 14000.
    Dh([DhRow; N_JOINTS]),
    /// A URDF serial chain and the correction of each of its movable joints' origins
    /// (`[tx, ty, tz, rx, ry, rz]`, mm and rad, see [`chain`]).
    Chain {
        chain: Arc<SerialChain>,
        corrections: Vec<[f64; PARAMS_PER_JOINT]>,
    },
}

/// The geometric model of one arm: its kinematics and the reflector coordinates in its tip frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmModel {
    pub kinematics: ArmKinematics,
    /// Reflector coordinates (`t_a, t_b, t_c` in the paper's set-up; one or more) in the tip frame
    /// (the flange, DH frame 7, for the built-in robot; the tip link for a chain), mm.
    pub reflectors_mm: Vec<Vector3<f64>>,
    /// The reflectors' names, one per entry of `reflectors_mm` (the dataset's `[reflectors]` keys).
    pub reflector_names: Arc<[String]>,
    /// Errors no geometry explains (joint elasticity, transmission harmonics; [`joint_errors`]): none
    /// in the paper's geometric model. Their parameters follow the reflector coordinates.
    pub errors: JointErrors,
}

/// Reflector positions and tip pose of one configuration.
#[derive(Clone, Debug)]
pub struct ReflectorFk {
    /// Reflector positions in the arm's model base frame, mm (one per reflector of the model).
    pub points_mm: Vec<Vector3<f64>>,
    /// Tip (flange) pose in the model base frame.
    pub base_from_flange: Isometry3<f64>,
}

/// Reflector positions and their Jacobians with respect to every parameter of the arm.
#[derive(Clone, Debug)]
pub struct ArmJacobians {
    pub fk: ReflectorFk,
    /// `∂p_k/∂x`, 3 × [`ArmModel::param_count`] each, one per reflector.
    pub jacobians: Vec<Matrix3xX<f64>>,
}

impl ArmModel {
    /// The nominal IRB 14000 arm (Table 3) with the given reflector coordinates.
    pub fn nominal_irb14000(reflectors_mm: impl Into<Vec<Vector3<f64>>>) -> Self {
        let reflectors_mm = reflectors_mm.into();
        Self {
            kinematics: ArmKinematics::Dh(IRB14000_NOMINAL_DH),
            reflector_names: default_reflector_names(reflectors_mm.len()),
            reflectors_mm,
            errors: JointErrors::default(),
        }
    }

    /// The same model with the reflectors named `names` (as many as it has reflectors).
    pub fn with_reflector_names(mut self, names: Arc<[String]>) -> Self {
        debug_assert_eq!(names.len(), self.reflectors_mm.len());
        self.reflector_names = names;
        self
    }

    /// Number of reflectors.
    pub fn reflector_count(&self) -> usize {
        self.reflectors_mm.len()
    }

    /// The nominal model of a chain (no corrections) with the given reflector coordinates.
    pub fn nominal_chain(
        chain: Arc<SerialChain>,
        reflectors_mm: impl Into<Vec<Vector3<f64>>>,
    ) -> Self {
        let reflectors_mm = reflectors_mm.into();
        let corrections = vec![[0.0; PARAMS_PER_JOINT]; chain.joint_count()];
        Self {
            kinematics: ArmKinematics::Chain { chain, corrections },
            reflector_names: default_reflector_names(reflectors_mm.len()),
            reflectors_mm,
            errors: JointErrors::default(),
        }
    }

    /// The DH table, for the DH form.
    pub fn dh(&self) -> Option<&[DhRow; N_JOINTS]> {
        match &self.kinematics {
            ArmKinematics::Dh(dh) => Some(dh),
            ArmKinematics::Chain { .. } => None,
        }
    }

    /// The DH table, mutably, for the DH form.
    pub fn dh_mut(&mut self) -> Option<&mut [DhRow; N_JOINTS]> {
        match &mut self.kinematics {
            ArmKinematics::Dh(dh) => Some(dh),
            ArmKinematics::Chain { .. } => None,
        }
    }

    /// The serial chain, for the chain form.
    pub fn chain(&self) -> Option<&Arc<SerialChain>> {
        match &self.kinematics {
            ArmKinematics::Chain { chain, .. } => Some(chain),
            ArmKinematics::Dh(_) => None,
        }
    }

    /// The joint-origin corrections, for the chain form.
    pub fn corrections(&self) -> Option<&[[f64; PARAMS_PER_JOINT]]> {
        match &self.kinematics {
            ArmKinematics::Chain { corrections, .. } => Some(corrections),
            ArmKinematics::Dh(_) => None,
        }
    }

    /// Number of movable joints (the CSV's `q1 … qN`).
    pub fn joint_count(&self) -> usize {
        match &self.kinematics {
            ArmKinematics::Dh(_) => N_JOINTS,
            ArmKinematics::Chain { chain, .. } => chain.dof(),
        }
    }

    /// Which joint values are lengths (prismatic joints, mm): one flag per joint value.
    pub fn linear_joints(&self) -> Vec<bool> {
        match &self.kinematics {
            ArmKinematics::Dh(_) => vec![false; N_JOINTS],
            ArmKinematics::Chain { chain, .. } => chain
                .variables()
                .iter()
                .map(|j| j.kind.is_linear())
                .collect(),
        }
    }

    /// `(lower, upper)` of every joint in chain order, rad: Table 3's limits for DH (ABB's), the URDF's
    /// for a chain (±π for a continuous joint).
    pub fn joint_limits_rad(&self) -> Vec<(f64, f64)> {
        match &self.kinematics {
            ArmKinematics::Dh(_) => joint_limits_rad().to_vec(),
            ArmKinematics::Chain { chain, .. } => chain.variable_ranges(),
        }
    }

    /// Number of parameters: the kinematic ones, three coordinates per reflector, then the error
    /// parameters (none in the geometric model).
    pub fn param_count(&self) -> usize {
        self.error_offset() + self.errors.count()
    }

    /// Index of the first error parameter (after the reflector coordinates).
    pub fn error_offset(&self) -> usize {
        self.reflector_offset() + 3 * self.reflector_count()
    }

    /// The same model with the error terms `terms` at their start values on this model's geometry as
    /// the reference (gravity along `gravity_in_base`); the geometric model for
    /// [`ErrorTerms::GEOMETRIC`].
    pub fn with_error_terms(mut self, terms: ErrorTerms, gravity_in_base: Vector3<f64>) -> Self {
        self.errors = JointErrors::new(&self.kinematics, terms, gravity_in_base);
        self
    }

    /// The same model with these gear ratios (motor turns per joint turn, by joint name) in its error
    /// model: motor-side harmonics for the joints whose ratio is not ±1 when the terms have
    /// harmonics. The error values restart (the layout changes): call it before a fit, not after.
    /// Unchanged without an error model or without ratios.
    pub fn with_gear_ratios(mut self, ratios: &[(String, f64)]) -> Self {
        if let Some(m) = &self.errors.model
            && !ratios.is_empty()
        {
            let with = m.with_gear_ratios(ratios);
            self.errors = JointErrors {
                values: with.start_values(),
                model: Some(Arc::new(with)),
            };
        }
        self
    }

    /// The geometric part of the model (its errors dropped).
    pub fn geometric(&self) -> Self {
        Self {
            errors: JointErrors::default(),
            ..self.clone()
        }
    }

    /// The kinematics at configuration `q`: the geometric parameters moved by the error model's
    /// increments there (borrowed as they are for the geometric model).
    fn kinematics_at(&self, q_rad: &[f64]) -> std::borrow::Cow<'_, ArmKinematics> {
        match self.errors.increment_values(q_rad) {
            Some(inc) => {
                std::borrow::Cow::Owned(joint_errors::moved_kinematics(&self.kinematics, &inc))
            }
            None => std::borrow::Cow::Borrowed(&self.kinematics),
        }
    }

    /// Unit of parameter `k`: `mm` or `rad` for the geometry and reflectors, the error parameters'
    /// own (`mrad/(N·m)`, `kg`, `kg·mm`, `rad`).
    pub fn param_unit(&self, k: usize) -> &'static str {
        let off = self.error_offset();
        match &self.errors.model {
            Some(m) if k >= off => m.param_unit(k - off),
            _ if self.param_is_angle(k) => "rad",
            _ => "mm",
        }
    }

    /// Index of the first reflector coordinate in the parameter vector.
    pub fn reflector_offset(&self) -> usize {
        match &self.kinematics {
            ArmKinematics::Dh(_) => N_DH,
            ArmKinematics::Chain { chain, .. } => chain.reflector_offset(),
        }
    }

    /// Name of parameter `k`: `a1 … alpha7` (DH) or `<joint>.tx … <joint>.rz` (chain), then
    /// `t_a.x … t_c.z`.
    pub fn param_name(&self, k: usize) -> String {
        let eoff = self.error_offset();
        if let Some(m) = &self.errors.model
            && k >= eoff
        {
            return m.param_name(k - eoff);
        }
        let off = self.reflector_offset();
        if k >= off && k < self.param_count() {
            return format!(
                "t_{}.{}",
                self.reflector_names[(k - off) / 3],
                ["x", "y", "z"][(k - off) % 3]
            );
        }
        match &self.kinematics {
            ArmKinematics::Dh(_) => param_name(k),
            ArmKinematics::Chain { chain, .. } => chain.param_name(k),
        }
    }

    /// Is parameter `k` an angle (rad) rather than a length (mm)?
    pub fn param_is_angle(&self, k: usize) -> bool {
        let eoff = self.error_offset();
        if let Some(m) = &self.errors.model
            && k >= eoff
        {
            return m.param_is_angle(k - eoff);
        }
        match &self.kinematics {
            ArmKinematics::Dh(_) => param_is_angle(k),
            ArmKinematics::Chain { chain, .. } => chain.param_is_angle(k),
        }
    }

    /// The parameter vector: kinematic parameters, then `t_a, t_b, t_c`.
    pub fn to_vector(&self) -> DVector<f64> {
        let off = self.reflector_offset();
        let mut v = DVector::zeros(self.param_count());
        match &self.kinematics {
            ArmKinematics::Dh(dh) => dh::write_dh(dh, v.as_mut_slice()),
            ArmKinematics::Chain { corrections, .. } => {
                for (k, c) in corrections.iter().enumerate() {
                    for (i, x) in c.iter().enumerate() {
                        v[PARAMS_PER_JOINT * k + i] = *x;
                    }
                }
            }
        }
        for (r, t) in self.reflectors_mm.iter().enumerate() {
            for c in 0..3 {
                v[off + 3 * r + c] = t[c];
            }
        }
        let eoff = self.error_offset();
        for (i, e) in self.errors.values.iter().enumerate() {
            v[eoff + i] = *e;
        }
        v
    }

    /// The model of the same form (and chain) with the parameters `x` ([`ArmModel::to_vector`]'s
    /// layout; missing trailing values are taken as zero).
    pub fn with_vector(&self, x: &DVector<f64>) -> Self {
        let at = |k: usize| x.get(k).copied().unwrap_or(0.0);
        let off = self.reflector_offset();
        let reflectors_mm = (0..self.reflector_count())
            .map(|r| Vector3::new(at(off + 3 * r), at(off + 3 * r + 1), at(off + 3 * r + 2)))
            .collect();
        let kinematics = match &self.kinematics {
            ArmKinematics::Dh(_) => ArmKinematics::Dh(std::array::from_fn(|i| {
                DhRow::new(at(4 * i), at(4 * i + 1), at(4 * i + 2), at(4 * i + 3))
            })),
            ArmKinematics::Chain { chain, .. } => ArmKinematics::Chain {
                chain: chain.clone(),
                corrections: (0..chain.joint_count())
                    .map(|k| std::array::from_fn(|i| at(PARAMS_PER_JOINT * k + i)))
                    .collect(),
            },
        };
        let eoff = self.error_offset();
        let errors = JointErrors {
            model: self.errors.model.clone(),
            values: (0..self.errors.count()).map(|i| at(eoff + i)).collect(),
        };
        Self {
            kinematics,
            reflectors_mm,
            reflector_names: self.reflector_names.clone(),
            errors,
        }
    }

    /// The first parameter that is not finite, by name.
    pub fn first_non_finite(&self) -> Option<String> {
        self.to_vector()
            .iter()
            .position(|v| !v.is_finite())
            .map(|k| self.param_name(k))
    }

    /// Tip pose in the model base frame (the flange for DH). `q_rad` in chain order; it must have
    /// [`ArmModel::joint_count`] values (missing ones count as zero, extra ones are ignored).
    pub fn base_from_flange(&self, q_rad: &[f64]) -> Isometry3<f64> {
        match self.kinematics_at(q_rad).as_ref() {
            ArmKinematics::Dh(dh) => dh::base_from_flange(dh, q_rad),
            ArmKinematics::Chain { chain, corrections } => chain.base_from_tip(corrections, q_rad),
        }
    }

    /// Reflector positions (model base frame, mm) and tip pose (paper eq. 3).
    pub fn reflector_fk(&self, q_rad: &[f64]) -> ReflectorFk {
        let base_from_flange = self.base_from_flange(q_rad);
        let points_mm = self
            .reflectors_mm
            .iter()
            .map(|t| base_from_flange.transform_point(&(*t).into()).coords)
            .collect();
        ReflectorFk {
            points_mm,
            base_from_flange,
        }
    }

    /// Reflector positions and their analytic Jacobians with respect to every parameter (eq. 4 for
    /// DH; see [`chain`] for the chain form).
    pub fn reflector_jacobians(&self, q_rad: &[f64]) -> ArmJacobians {
        let Some(inc) = self.errors.increments(q_rad) else {
            return geometric_jacobians(&self.kinematics, &self.reflectors_mm, q_rad);
        };
        // The geometric Jacobians at the moved parameters are exact (the increments do not depend on
        // the geometry); an error parameter's column is the chain rule through the slots it moves.
        let moved = joint_errors::moved_kinematics(&self.kinematics, &inc);
        let mut out = geometric_jacobians(&moved, &self.reflectors_mm, q_rad);
        let eoff = self.error_offset();
        let n = self.param_count();
        for jac in &mut out.jacobians {
            let mut full = Matrix3xX::zeros(n);
            full.columns_mut(0, eoff).copy_from(jac);
            for (slot, _, row) in &inc.slots {
                let col = jac.column(*slot).into_owned();
                for &(i, d) in row {
                    full.column_mut(eoff + i).axpy(d, &col, 1.0);
                }
            }
            *jac = full;
        }
        out
    }

    /// One frame per movable joint, in the model base frame, whose z axis is that joint's axis and
    /// whose origin lies on it (DH frames 0 … 6, or the chain's aligned joint frames), then the tip.
    pub fn joint_frames(&self, q_rad: &[f64]) -> Vec<Isometry3<f64>> {
        match self.kinematics_at(q_rad).as_ref() {
            ArmKinematics::Dh(dh) => dh::frames(dh, q_rad).to_vec(),
            ArmKinematics::Chain { chain, corrections } => chain.joint_frames(corrections, q_rad),
        }
    }

    /// Tip pose in the model base frame and its Jacobian with respect to the joint values: 6 ×
    /// [`ArmModel::joint_count`], rows the tip's velocity (mm per unit) then its angular velocity (rad
    /// per unit), both in the base frame; a revolute joint's column is per rad, a prismatic one's per
    /// mm. A mimic joint adds its multiplier times its own column to its leader's.
    pub fn flange_jacobian(&self, q_rad: &[f64]) -> (Isometry3<f64>, Matrix6xX<f64>) {
        let frames = self.joint_frames(q_rad);
        let (tip, axes) = frames.split_last().expect("joint frames end with the tip");
        let p_tip = tip.translation.vector;
        let mut jac = Matrix6xX::zeros(self.joint_count());
        // (kind is linear, column, coefficient) of each movable joint, in chain order.
        let drives: Vec<(bool, usize, f64)> = match &self.kinematics {
            ArmKinematics::Dh(_) => (0..N_JOINTS).map(|i| (false, i, 1.0)).collect(),
            ArmKinematics::Chain { chain, .. } => chain
                .joints
                .iter()
                .map(|j| match j.drive {
                    chain::JointDrive::Variable(i) => (j.kind.is_linear(), i, 1.0),
                    chain::JointDrive::Mimic {
                        leader, multiplier, ..
                    } => (j.kind.is_linear(), leader, multiplier),
                })
                .collect(),
        };
        for (frame, (linear, column, coefficient)) in axes.iter().zip(drives) {
            let z = frame.rotation * Vector3::z();
            let (v, w) = if linear {
                (z, Vector3::zeros())
            } else {
                (z.cross(&(p_tip - frame.translation.vector)), z)
            };
            let mut col = jac.column_mut(column);
            col.fixed_rows_mut::<3>(0).axpy(coefficient, &v, 1.0);
            col.fixed_rows_mut::<3>(3).axpy(coefficient, &w, 1.0);
        }
        (*tip, jac)
    }

    /// The order in which the identifiability analysis considers the parameters (the preferred ones
    /// first): the reflector coordinates, then for DH joints 2 … 6, joint 1 and joint 7, for a chain
    /// base first (see [`SerialChain::preference_order`]).
    pub fn identifiability_order(&self) -> Vec<usize> {
        let mut order = match &self.kinematics {
            ArmKinematics::Dh(_) => dh::preference_order(self.reflector_count()),
            ArmKinematics::Chain { chain, .. } => chain.preference_order(self.reflector_count()),
        };
        if let Some(m) = &self.errors.model {
            let eoff = self.error_offset();
            order.extend(m.preference_order().into_iter().map(|i| eoff + i));
        }
        order
    }

    /// Why parameter `k` cannot be identified from distances, when physics says so.
    pub fn unidentifiable_reason(&self, k: usize) -> Option<String> {
        if k >= self.error_offset() {
            return None;
        }
        match &self.kinematics {
            ArmKinematics::Dh(_) => dh::physical_reason(k).map(str::to_string),
            ArmKinematics::Chain { chain, .. } => chain.physical_reason(k),
        }
    }
}

/// Reflector positions and Jacobians of the geometric kinematics `kinematics`.
fn geometric_jacobians(
    kinematics: &ArmKinematics,
    reflectors_mm: &[Vector3<f64>],
    q_rad: &[f64],
) -> ArmJacobians {
    match kinematics {
        ArmKinematics::Dh(dh) => dh::reflector_jacobians(dh, reflectors_mm, q_rad),
        ArmKinematics::Chain { chain, corrections } => {
            chain.reflector_jacobians(corrections, reflectors_mm, q_rad)
        }
    }
}

/// The geometric model of the whole dual-arm robot: both arms and the right-arm base in the left-arm
/// base.
#[derive(Clone, Debug, PartialEq)]
pub struct DualArmModel {
    pub arms: PerSide<ArmModel>,
    /// The right arm's model base frame in the left arm's (DH frames 0 for the built-in robot, the
    /// chains' base links otherwise).
    pub left_base_from_right_base: Isometry3<f64>,
}

impl DualArmModel {
    pub fn arm(&self, side: Side) -> &ArmModel {
        &self.arms[side]
    }

    pub fn arm_mut(&mut self, side: Side) -> &mut ArmModel {
        &mut self.arms[side]
    }

    /// Transform taking points of `side`'s base frame into the left-arm base frame.
    pub fn left_base_from(&self, side: Side) -> Isometry3<f64> {
        match side {
            Side::Left => Isometry3::identity(),
            Side::Right => self.left_base_from_right_base,
        }
    }

    /// The same model with error terms `terms` on both arms at their start values, gravity along
    /// `gravity_in_left_base` (in the left arm's model base frame; the right arm's follows from
    /// [`DualArmModel::left_base_from_right_base`]). Each arm's reference geometry is its own current one.
    pub fn with_error_terms(
        mut self,
        terms: ErrorTerms,
        gravity_in_left_base: Vector3<f64>,
    ) -> Self {
        let in_right = self
            .left_base_from_right_base
            .rotation
            .inverse_transform_vector(&gravity_in_left_base);
        let PerSide { left, right } = self.arms;
        self.arms = PerSide::new(
            left.with_error_terms(terms, gravity_in_left_base),
            right.with_error_terms(terms, in_right),
        );
        self
    }

    /// The geometric part of the model (both arms' errors dropped): what a URDF can hold.
    pub fn geometric(&self) -> Self {
        Self {
            arms: self.arms.as_ref().map(|_, a| a.geometric()),
            left_base_from_right_base: self.left_base_from_right_base,
        }
    }

    /// Both arms' error models with these gear ratios (by joint name; a torso's apply to both arms):
    /// [`ArmModel::with_gear_ratios`].
    pub fn with_gear_ratios(mut self, ratios: &[(String, f64)]) -> Self {
        let PerSide { left, right } = self.arms;
        self.arms = PerSide::new(
            left.with_gear_ratios(ratios),
            right.with_gear_ratios(ratios),
        );
        self
    }

    /// Each arm's elastic terms with these held lumped masses (per movable joint kg and first moment
    /// kg·mm in the next joint frame; `None`, or a list of another length: unchanged).
    pub fn with_held_masses(mut self, masses: &PerSide<Option<joint_errors::LinkMasses>>) -> Self {
        for side in Side::BOTH {
            let (Some(model), Some(m)) = (self.arms[side].errors.model.clone(), &masses[side])
            else {
                continue;
            };
            let list = m.iter().map(|(kg, s)| (*kg, Vector3::from(*s))).collect();
            if let Some(with) = model.with_masses(list) {
                self.arms[side].errors.model = Some(Arc::new(with));
            }
        }
        self
    }

    /// On a torso both arms share, with errors beyond geometry, measured together: each arm's error
    /// model carries the other arm at the same instants (`instants`: each instant's left and right
    /// joint values), so the other arm's lumped masses load the torso hinges too. Unchanged without
    /// shared joints, without error models or without instants.
    pub fn with_torso_instants(mut self, instants: &[(Vec<f64>, Vec<f64>)]) -> Self {
        let shared = self.shared_joints();
        if shared.is_empty() || instants.is_empty() {
            return self;
        }
        for side in Side::BOTH {
            let Some(model) = self.arms[side].errors.model.clone() else {
                continue;
            };
            let other = &self.arms[side.other()];
            let reference = other
                .errors
                .model
                .as_ref()
                .map_or(&other.kinematics, |m| m.reference());
            let masses = other
                .errors
                .model
                .as_ref()
                .map(|m| m.link_masses().to_vec())
                .filter(|m| !m.is_empty());
            // (this arm's, the other's): joints of the torso, and joint values of each instant.
            let flip = side == Side::Right;
            let pairs: Vec<(usize, usize)> = shared
                .joints
                .iter()
                .map(|&(l, r)| if flip { (r, l) } else { (l, r) })
                .collect();
            let instants = instants.iter().map(|(l, r)| {
                if flip {
                    (r.clone(), l.clone())
                } else {
                    (l.clone(), r.clone())
                }
            });
            let other = joint_errors::OtherArm::new(reference, &pairs, instants, masses);
            self.arms[side].errors.model = Some(Arc::new(model.with_other_arm(other)));
        }
        self
    }

    /// The error terms of the model (the left arm's; both arms carry the same terms).
    pub fn error_terms(&self) -> ErrorTerms {
        self.arms.left.errors.terms()
    }

    /// Are both "arms" one chain (a single-arm robot, its one arm given for both sides: the same
    /// tip link and joints)?
    pub fn is_one_arm(&self) -> bool {
        match (self.arms.left.chain(), self.arms.right.chain()) {
            (Some(l), Some(r)) => l.tip_link == r.tip_link && l.joint_names() == r.joint_names(),
            _ => false,
        }
    }

    /// The joints both arms' chains hold (a torso): identified once, from both arms' data.
    pub fn shared_joints(&self) -> SharedJoints {
        SharedJoints::of(&self.arms.left, &self.arms.right)
    }

    /// A description of the first problem that keeps this model from being used with `joint_counts`
    /// joint values per arm (a different joint count), if any.
    pub fn joint_count_mismatch(&self, joint_counts: PerSide<usize>) -> Option<(Side, usize)> {
        Side::BOTH
            .into_iter()
            .find(|&s| self.arm(s).joint_count() != joint_counts[s])
            .map(|s| (s, self.arm(s).joint_count()))
    }
}

/// Rotation angle of `R` (norm of its logarithm, the vee of `log(R)`), rad.
pub fn rotation_angle_rad(r: &nalgebra::Rotation3<f64>) -> f64 {
    // Robust near 0 and π: atan2 of |sin| and cos.
    let m = r.matrix();
    let cos = ((m.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let s = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    );
    (0.5 * s.norm()).atan2(cos)
}

/// The rotation closest to `m` (Frobenius norm) via the SVD, with the determinant forced to +1.
pub fn nearest_rotation(m: &nalgebra::Matrix3<f64>) -> nalgebra::Rotation3<f64> {
    let svd = m.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => {
            let mut d = nalgebra::Matrix3::identity();
            if (u * v_t).determinant() < 0.0 {
                d[(2, 2)] = -1.0;
            }
            nalgebra::Rotation3::from_matrix_unchecked(u * d * v_t)
        }
        _ => nalgebra::Rotation3::from_matrix(m),
    }
}
