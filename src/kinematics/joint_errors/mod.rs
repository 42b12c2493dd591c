//! Errors no geometry explains: joints that give under gravity, and gears that do not turn exactly as
//! commanded (issue 21). Both are modelled as configuration-dependent increments of the arm's own
//! geometric parameters, so every step-1 method identifies them jointly with the geometry and the
//! Jacobians stay exact.
//!
//! **Joint elasticity.** A revolute joint `j` deflects about its axis by `δ = κ·τ`, `τ` the gravity
//! torque about that axis of everything beyond the joint and `κ` its compliance (mrad/(N·m)); with
//! [`ErrorTerms::bending`] it also deflects about the two axes across it (a chain joint's aligned `x`,
//! `y`; a DH row's α axis `x_j`, as DLR's model of Agile Justin bends) with compliances of their own.
//! The deflection about the axis is added to the joint's zero offset (`rz`, DH `θ`), the bending to
//! `rx`, `ry` (DH `α`): the arm at that configuration is the geometric model with those parameters
//! moved.
//!
//! The torque is that of **lumped masses**, one per link: the link after movable joint `k` carries a
//! mass `m_k` (kg) whose first moment about the next joint frame's origin is `s_k = m_k·c_k`
//! (kg·mm, in that frame). For a hinge with pivot `p` and unit axis `e`, gravity `g·ĝ`:
//!
//! ```text
//! τ = g/1000 · Σ_{k ≥ j} [ m_k (o_{k+1} − p)·(ĝ × e) + s_k·(R_{k+1}ᵀ (ĝ × e)) ]      (N·m)
//! ```
//!
//! (`o_{k+1}`, `R_{k+1}` the frame after link k: the next joint's, or the tip). This is a
//! **mass-free** form: a robot given only as a DH table (DLR's Justin) has no masses, and only the
//! products `κ·m`, `κ·s` reach the data. The masses are **held** — part of the model, not of its
//! parameters: the URDF's inertials where it has them (`RobotDescription::lumped_masses`), else 1 kg
//! per link at the next joint's origin (`s = 0`); [`JointErrorModel::with_masses`] — and each hinge's
//! compliance is identified: a
//! linear parameter, zero at the start (the start model is the geometric one exactly). The compliances
//! are therefore those *of this mass distribution*: compare them between joints of one calibration,
//! not with a datasheet. Identifying the masses too (`κ` and `m, s` bilinear; the mass scale a gauge)
//! was tried on DLR's Agile Justin and left alone: from compliances near zero the masses' columns
//! vanish, and Levenberg–Marquardt walked a joint origin 100 mm off while the cost fell
//! (docs/real-data.md).
//!
//! **A torso both arms share**, measured together: the torso joints carry both arms, so each arm's
//! model adds the other arm's lumped masses at the same instant to its torso hinges' torques
//! ([`OtherArm`], attached by `DualArmModel::with_torso_instants` from the dataset's rows of one id).
//! A configuration that is no instant of the data gets this arm's masses only. The torso's error
//! parameters are the robot's: `SharedJoints` pairs them between the arms by name, so a tree fit
//! identifies them once and both arms' models carry the same values.
//!
//! The torques are computed on the **reference geometry** (the nominal kinematics the error model was
//! attached to), not on the calibrated one: the two differ by millimetres, which changes a torque by
//! well under 0.1 %; in exchange the increments do not depend on the geometric parameters, so the
//! geometric Jacobians at the moved parameters are exact and the error columns are the chain rule of
//! them. The deflection's own effect on the torques (DLR iterates a fixed point) is of the order of the
//! deflection, ~10⁻³ relative, and is not modelled.
//!
//! **Transmission errors.** With [`ErrorTerms::harmonics`] = 1 or 2, each revolute joint's angle is off
//! by `c₁ cos θ + s₁ sin θ (+ c₂ cos 2θ + s₂ sin 2θ)` (rad), `θ` the joint's value (a mimic joint's
//! own). A constant offset is the geometry's `rz`/`θ` and is not repeated. Where a joint's **gear
//! ratio** `r` is given (a URDF `<transmission>`'s `mechanicalReduction`, `calibrate --gear-ratio`), the
//! motor's harmonics are added too: `m₁ cos rθ + n₁ sin rθ (+ m₂ cos 2rθ + n₂ sin 2rθ)` — the error a
//! motor-side encoder or an eccentric motor gear makes once (twice) per motor turn, seen at the joint
//! through the reduction. A ratio of ±1 (what many descriptions write) adds nothing: those are the
//! joint's own harmonics.
//!
//! Prismatic joints carry neither (their links carry masses for the joints before them).
//! Compliances are in mrad/(N·m): in µrad a wrist joint's column (a torque of 1 N·m) fell below the
//! identifiability analysis' negligible-column threshold.

use super::chain::PARAMS_PER_JOINT;
#[cfg(test)]
mod tests;
use super::ArmKinematics;
use super::dh::{self, DhRow, N_JOINTS};
use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Held lumped masses of an arm, one per movable joint: mass (kg) and first moment (kg·mm) in the
/// next joint's frame, as files and settings carry them.
pub type LinkMasses = Vec<(f64, [f64; 3])>;

/// Standard gravity, m/s².
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;
/// The lumped mass of each link, kg, at the next joint's origin (its first moment 0): held.
pub const START_MASS_KG: f64 = 1.0;

/// Which non-geometric errors the model has (none: the paper's geometric model).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorTerms {
    /// Each revolute joint deflects about its axis under the gravity torque.
    #[serde(default)]
    pub elastic: bool,
    /// … and about the two axes across it (DH: its α axis).
    #[serde(default)]
    pub bending: bool,
    /// Harmonics of each revolute joint's angle: 0 (none), 1 or 2.
    #[serde(default)]
    pub harmonics: u8,
}

impl ErrorTerms {
    /// The paper's geometric model.
    pub const GEOMETRIC: ErrorTerms = ErrorTerms {
        elastic: false,
        bending: false,
        harmonics: 0,
    };

    /// The named models, for the command line and the workbench: name, terms, description.
    pub const NAMED: [(&'static str, ErrorTerms, &'static str); 5] = [
        (
            "geometric",
            ErrorTerms::GEOMETRIC,
            "joint origins and reflectors only (the paper's model)",
        ),
        (
            "elastic-axis",
            ErrorTerms {
                elastic: true,
                bending: false,
                harmonics: 0,
            },
            "geometry + each joint giving about its axis under gravity (lumped masses)",
        ),
        (
            "elastic",
            ErrorTerms {
                elastic: true,
                bending: true,
                harmonics: 0,
            },
            "geometry + each joint giving about its axis and across it under gravity",
        ),
        (
            "harmonic",
            ErrorTerms {
                elastic: false,
                bending: false,
                harmonics: 2,
            },
            "geometry + first and second harmonics of each joint's angle",
        ),
        (
            "full",
            ErrorTerms {
                elastic: true,
                bending: true,
                harmonics: 2,
            },
            "elastic and harmonic together",
        ),
    ];

    pub fn is_geometric(&self) -> bool {
        !self.elastic && !self.bending && self.harmonics == 0
    }

    /// The terms of a named model (`geometric`, `elastic-axis`, `elastic`, `harmonic`, `full`).
    pub fn from_name(name: &str) -> Result<ErrorTerms, String> {
        Self::NAMED
            .iter()
            .find(|(n, ..)| n.eq_ignore_ascii_case(name.trim()))
            .map(|&(_, t, _)| t)
            .ok_or_else(|| {
                format!(
                    "unknown model `{name}`: expected one of {}",
                    Self::NAMED.map(|(n, ..)| n).join(", ")
                )
            })
    }

    /// The model's name (one of [`ErrorTerms::NAMED`], or a description of another combination).
    pub fn name(&self) -> String {
        match Self::NAMED.iter().find(|(_, t, _)| t == self) {
            Some((n, ..)) => (*n).to_string(),
            None => format!(
                "elastic {}, bending {}, harmonics {}",
                self.elastic, self.bending, self.harmonics
            ),
        }
    }

    /// Deflections under gravity at all (about the axis or across it)?
    pub fn has_elasticity(&self) -> bool {
        self.elastic || self.bending
    }
}

/// About which axis a hinge turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum HingeAxis {
    /// The joint's own axis (the zero-offset slot).
    Axis,
    /// The chain joint's aligned x / y (slots `rx`, `ry`).
    CrossX,
    CrossY,
    /// A DH row's α axis: `x` of the frame after the row, through its origin.
    Alpha,
}

impl HingeAxis {
    fn suffix(self) -> &'static str {
        match self {
            HingeAxis::Axis => "k_axis",
            HingeAxis::CrossX => "k_x",
            HingeAxis::CrossY => "k_y",
            HingeAxis::Alpha => "k_alpha",
        }
    }
}

/// One compliance: a joint, the axis it gives about, and the geometric parameter it moves.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hinge {
    joint: usize,
    axis: HingeAxis,
    slot: usize,
}

/// The structure of one arm's non-geometric errors: which terms, gravity, the reference geometry, and
/// the parameters' layout. The values live in [`JointErrors`].
#[derive(Debug, PartialEq)]
pub struct JointErrorModel {
    pub terms: ErrorTerms,
    /// Unit vector of gravity in the arm's model base frame.
    pub gravity_in_base: Vector3<f64>,
    /// The geometry the torques are computed on.
    reference: ArmKinematics,
    /// Movable joints' names (DH: `j1 … j7`), chain order.
    joint_names: Vec<String>,
    /// The revolute joints with harmonics.
    harmonic_joints: Vec<usize>,
    /// Each movable joint's gear ratio (motor turns per joint turn), where given.
    gear_ratios: Vec<Option<f64>>,
    /// The revolute joints with motor-side harmonics (a gear ratio other than ±1) and their ratios.
    motor_joints: Vec<(usize, f64)>,
    hinges: Vec<Hinge>,
    /// Each link's lumped mass (kg) and first moment (kg·mm, in the next joint frame): one per movable
    /// joint, none without elasticity. Held: part of the model, not of its parameters.
    masses: Vec<(f64, Vector3<f64>)>,
    /// Each hinge's torque row `∂τ/∂(masses)` per configuration: it depends on the configuration and
    /// the reference geometry only, so a fit computes it once per configuration.
    torque_rows: TorqueCache,
    /// On a torso both arms share, measured together: the other arm at the same instants, whose
    /// lumped masses load the shared joints too.
    other: Option<OtherArm>,
}

/// The other arm of a torso, at the instants this arm was measured (its configurations by this
/// arm's joint values): its held lumped masses beyond the torso load this arm's torso hinges.
#[derive(Clone, Debug, PartialEq)]
pub struct OtherArm {
    reference: ArmKinematics,
    /// Its links beyond the torso (after its own joints) and their lumped masses (kg) and first
    /// moments (kg·mm, in the next joint frame).
    links: Vec<(usize, f64, Vector3<f64>)>,
    /// This arm's shared (torso) joints.
    shared: Vec<usize>,
    /// This arm's joint values (bits) → the other arm's joint values at that instant.
    configs: std::collections::HashMap<Vec<u64>, Vec<f64>>,
}

impl OtherArm {
    /// `reference`: the other arm's geometry; `shared`: (this joint, other joint) of the torso;
    /// `instants`: (this arm's joint values, the other's) of each instant; `masses`: the other arm's
    /// lumped mass and first moment of each link ([`JointErrorModel::link_masses`]; 1 kg at the next
    /// joint where it has no error model).
    pub fn new(
        reference: &ArmKinematics,
        shared: &[(usize, usize)],
        instants: impl IntoIterator<Item = (Vec<f64>, Vec<f64>)>,
        masses: Option<Vec<(f64, Vector3<f64>)>>,
    ) -> Self {
        let n = match reference {
            ArmKinematics::Dh(_) => N_JOINTS,
            ArmKinematics::Chain { chain, .. } => chain.joint_count(),
        };
        let mass = |k: usize| {
            masses
                .as_ref()
                .and_then(|m| m.get(k).copied())
                .unwrap_or((START_MASS_KG, Vector3::zeros()))
        };
        Self {
            reference: reference.clone(),
            links: (0..n)
                .filter(|k| !shared.iter().any(|s| s.1 == *k))
                .map(|k| {
                    let (m, s) = mass(k);
                    (k, m, s)
                })
                .collect(),
            shared: shared.iter().map(|s| s.0).collect(),
            configs: instants
                .into_iter()
                .map(|(q, other)| (q.iter().map(|v| v.to_bits()).collect(), other))
                .collect(),
        }
    }

    /// The other arm's contribution to hinge `h`'s torque (N·m) at this arm's `q`, if it is an
    /// instant of the data and `h` a torso hinge.
    fn torque(&self, h: &Hinge, pivot: &Vector3<f64>, gxe: &Vector3<f64>, key: &[u64]) -> f64 {
        if !self.shared.contains(&h.joint) {
            return 0.0;
        }
        let Some(q) = self.configs.get(key) else {
            return 0.0;
        };
        let frames = match &self.reference {
            ArmKinematics::Dh(dh) => dh::frames(dh, q).to_vec(),
            ArmKinematics::Chain { chain, corrections } => chain.joint_frames(corrections, q),
        };
        self.links
            .iter()
            .map(|&(k, m, s)| {
                let f = &frames[k + 1];
                m * (f.translation.vector - pivot).dot(gxe)
                    + s.dot(&f.rotation.inverse_transform_vector(gxe))
            })
            .sum()
    }
}

/// Every hinge's gravity torque at one configuration, N·m (the other arm's included, on a shared
/// torso measured together).
type TorqueRows = Arc<[f64]>;

/// The configurations' torque rows, by the bits of the joint values (bounded: cleared when full).
#[derive(Default)]
struct TorqueCache(std::sync::RwLock<std::collections::HashMap<Vec<u64>, TorqueRows>>);

/// Configurations whose torque rows are kept (a few hundred kilobytes each at most).
const TORQUE_CACHE_CONFIGS: usize = 20_000;

impl std::fmt::Debug for TorqueCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TorqueCache")
    }
}

impl PartialEq for TorqueCache {
    /// A cache of values that follow from the rest of the model: never a difference.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// One geometric parameter's increment: its index, the increment, and `(error parameter,
/// ∂increment/∂it)` for every error parameter it depends on.
pub type SlotIncrement = (usize, f64, Vec<(usize, f64)>);

/// The increments of the geometric parameters at one configuration and their derivatives with respect
/// to the error parameters.
#[derive(Clone, Debug, Default)]
pub struct Increments {
    /// Geometric parameter index, increment, and `(error parameter, ∂increment/∂it)`.
    pub slots: Vec<SlotIncrement>,
}

impl Increments {
    fn add(&mut self, slot: usize, value: f64, row: Vec<(usize, f64)>) {
        match self.slots.iter_mut().find(|(s, ..)| *s == slot) {
            Some((_, v, r)) => {
                *v += value;
                r.extend(row);
            }
            None => self.slots.push((slot, value, row)),
        }
    }
}

impl JointErrorModel {
    /// The error model of an arm whose geometry is `reference`, with `terms`, gravity along
    /// `gravity_in_base` (any length; normalised; −z when zero or not finite).
    pub fn new(
        reference: &ArmKinematics,
        terms: ErrorTerms,
        gravity_in_base: Vector3<f64>,
    ) -> Self {
        Self::build(reference, terms, gravity_in_base, Vec::new())
    }

    /// [`JointErrorModel::new`] with each movable joint's gear ratio (`None`: not given; a shorter
    /// list: the rest not given).
    fn build(
        reference: &ArmKinematics,
        terms: ErrorTerms,
        gravity_in_base: Vector3<f64>,
        mut gear_ratios: Vec<Option<f64>>,
    ) -> Self {
        let g = gravity_in_base
            .try_normalize(1e-12)
            .filter(|g| g.iter().all(|v| v.is_finite()))
            .unwrap_or(-Vector3::z());
        // (name, revolute, axis slot, cross slots) per movable joint.
        let joints: Vec<(String, bool, usize)> = match reference {
            ArmKinematics::Dh(_) => (0..N_JOINTS)
                .map(|j| (format!("j{}", j + 1), true, 4 * j + 2))
                .collect(),
            ArmKinematics::Chain { chain, .. } => chain
                .joints
                .iter()
                .enumerate()
                .map(|(j, cj)| {
                    (
                        cj.name.clone(),
                        !cj.kind.is_linear(),
                        PARAMS_PER_JOINT * j + 5,
                    )
                })
                .collect(),
        };
        let revolute: Vec<usize> = (0..joints.len()).filter(|&j| joints[j].1).collect();
        let harmonic_joints = if terms.harmonics > 0 {
            revolute.clone()
        } else {
            Vec::new()
        };
        gear_ratios.resize(joints.len(), None);
        let motor_joints = harmonic_joints
            .iter()
            .filter_map(|&j| {
                gear_ratios[j]
                    .filter(|r| r.is_finite() && (r.abs() - 1.0).abs() > 1e-9 && *r != 0.0)
                    .map(|r| (j, r))
            })
            .collect();
        let dh_form = matches!(reference, ArmKinematics::Dh(_));
        let mut hinges = Vec::new();
        for &j in &revolute {
            let axis = joints[j].2;
            if terms.elastic {
                hinges.push(Hinge {
                    joint: j,
                    axis: HingeAxis::Axis,
                    slot: axis,
                });
            }
            if terms.bending {
                if dh_form {
                    hinges.push(Hinge {
                        joint: j,
                        axis: HingeAxis::Alpha,
                        slot: 4 * j + 3,
                    });
                } else {
                    hinges.push(Hinge {
                        joint: j,
                        axis: HingeAxis::CrossX,
                        slot: axis - 2,
                    });
                    hinges.push(Hinge {
                        joint: j,
                        axis: HingeAxis::CrossY,
                        slot: axis - 1,
                    });
                }
            }
        }
        let masses = if hinges.is_empty() {
            Vec::new()
        } else {
            vec![(START_MASS_KG, Vector3::zeros()); joints.len()]
        };
        Self {
            terms,
            gravity_in_base: g,
            reference: reference.clone(),
            joint_names: joints.into_iter().map(|j| j.0).collect(),
            harmonic_joints,
            gear_ratios,
            motor_joints,
            hinges,
            masses,
            torque_rows: TorqueCache::default(),
            other: None,
        }
    }

    /// The same model with the other arm of a shared torso (see [`OtherArm`]).
    pub fn with_other_arm(&self, other: OtherArm) -> Self {
        let mut out = self.rebuilt(&self.reference);
        out.masses = self.masses.clone();
        out.other = Some(other);
        out
    }

    /// The same model with these lumped masses (kg) and first moments (kg·mm, in the next joint
    /// frame), one per link (a robot's own; the file's). Refused unless one per link.
    pub fn with_masses(&self, masses: Vec<(f64, Vector3<f64>)>) -> Option<Self> {
        if masses.len() != self.masses.len() {
            return None;
        }
        let mut out = self.rebuilt(&self.reference);
        out.masses = masses;
        out.other = self.other.clone();
        Some(out)
    }

    /// Each link's lumped mass (kg) and first moment (kg·mm); empty without elasticity.
    pub fn link_masses(&self) -> &[(f64, Vector3<f64>)] {
        &self.masses
    }

    /// The name of link `k` (after movable joint `k`): `after_<joint>`.
    pub fn link_name(&self, k: usize) -> String {
        format!("after_{}", self.joint_names[k])
    }

    /// The geometry the torques are computed on.
    pub fn reference(&self) -> &ArmKinematics {
        &self.reference
    }

    /// Does the model carry the other arm of a shared torso?
    pub fn has_other_arm(&self) -> bool {
        self.other.is_some()
    }

    fn harmonics_count(&self) -> usize {
        2 * self.terms.harmonics as usize * self.harmonic_joints.len()
    }

    fn motor_harmonics_count(&self) -> usize {
        2 * self.terms.harmonics as usize * self.motor_joints.len()
    }

    fn compliance_offset(&self) -> usize {
        self.harmonics_count() + self.motor_harmonics_count()
    }

    /// Number of error parameters: the joints' harmonics, the motors', then the compliances.
    pub fn param_count(&self) -> usize {
        self.compliance_offset() + self.hinges.len()
    }

    /// The start values: no harmonics, zero compliances: the start model is the geometric one
    /// exactly.
    pub fn start_values(&self) -> Vec<f64> {
        vec![0.0; self.param_count()]
    }

    /// Name of error parameter `i`: `<joint>.h1_cos` … `<joint>.h2_sin` (the joint's harmonics),
    /// `<joint>.m1_cos` … `<joint>.m2_sin` (the motor's, with a gear ratio), `<joint>.k_axis`,
    /// `.k_x`, `.k_y` (`.k_alpha` for a DH row).
    pub fn param_name(&self, i: usize) -> String {
        let (h, c0) = (self.harmonics_count(), self.compliance_offset());
        let per = 2 * self.terms.harmonics as usize;
        let harmonic = |joint: usize, r: usize, prefix: &str| {
            let kind = if r.is_multiple_of(2) { "cos" } else { "sin" };
            format!("{}.{prefix}{}_{kind}", self.joint_names[joint], r / 2 + 1)
        };
        if i < h {
            return harmonic(self.harmonic_joints[i / per], i % per, "h");
        }
        if i < c0 {
            return harmonic(self.motor_joints[(i - h) / per].0, (i - h) % per, "m");
        }
        let hinge = self.hinges[i - c0];
        format!("{}.{}", self.joint_names[hinge.joint], hinge.axis.suffix())
    }

    /// Unit of error parameter `i`.
    pub fn param_unit(&self, i: usize) -> &'static str {
        if i < self.compliance_offset() {
            "rad"
        } else {
            "mrad/(N·m)"
        }
    }

    /// Is error parameter `i` an angle (a harmonic amplitude, the joint's or the motor's)?
    pub fn param_is_angle(&self, i: usize) -> bool {
        i < self.compliance_offset()
    }

    /// Is error parameter `i` a compliance?
    pub fn param_is_compliance(&self, i: usize) -> bool {
        i >= self.compliance_offset() && i < self.param_count()
    }

    /// The identifiability analysis' order of the error parameters: harmonics, then compliances (from
    /// the base).
    pub fn preference_order(&self) -> Vec<usize> {
        (0..self.param_count()).collect()
    }

    /// Joint `j`'s value at `q`.
    fn joint_value(&self, j: usize, q: &[f64]) -> f64 {
        match &self.reference {
            ArmKinematics::Dh(_) => q.get(j).copied().unwrap_or(0.0),
            ArmKinematics::Chain { chain, .. } => chain.joints[j].drive.value(q),
        }
    }

    /// The reference geometry's frames at `q`: one per movable joint (before its motion), then the
    /// tip.
    fn reference_frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        match &self.reference {
            ArmKinematics::Dh(dh) => dh::frames(dh, q).to_vec(),
            ArmKinematics::Chain { chain, corrections } => chain.joint_frames(corrections, q),
        }
    }

    /// Hinge `h`'s gravity torque at the reference frames, N·m: this arm's lumped masses beyond it,
    /// and the other arm's on a shared torso at an instant of the data (`key`: the joint values' bits).
    fn torque(&self, h: &Hinge, frames: &[Isometry3<f64>], key: &[u64]) -> f64 {
        let (pivot, axis) = match h.axis {
            HingeAxis::Axis => (frames[h.joint], Vector3::z()),
            HingeAxis::CrossX => (frames[h.joint], Vector3::x()),
            HingeAxis::CrossY => (frames[h.joint], Vector3::y()),
            HingeAxis::Alpha => (frames[h.joint + 1], Vector3::x()),
        };
        let p = pivot.translation.vector;
        let e = pivot.rotation * axis;
        let gxe = self.gravity_in_base.cross(&e) * (STANDARD_GRAVITY_M_S2 / 1000.0);
        let own: f64 = (h.joint..self.masses.len())
            .map(|k| {
                let (m, s) = &self.masses[k];
                let f = &frames[k + 1];
                m * (f.translation.vector - p).dot(&gxe)
                    + s.dot(&f.rotation.inverse_transform_vector(&gxe))
            })
            .sum();
        let other = self
            .other
            .as_ref()
            .map_or(0.0, |o| o.torque(h, &p, &gxe, key));
        own + other
    }

    /// Every hinge's torque at `q`, computed once per configuration.
    fn torque_rows(&self, q: &[f64]) -> TorqueRows {
        let key: Vec<u64> = q.iter().map(|v| v.to_bits()).collect();
        if let Ok(cache) = self.torque_rows.0.read()
            && let Some(rows) = cache.get(&key)
        {
            return Arc::clone(rows);
        }
        let frames = self.reference_frames(q);
        let rows: TorqueRows = self
            .hinges
            .iter()
            .map(|h| self.torque(h, &frames, &key))
            .collect();
        if let Ok(mut cache) = self.torque_rows.0.write() {
            if cache.len() >= TORQUE_CACHE_CONFIGS {
                cache.clear();
            }
            cache.insert(key, Arc::clone(&rows));
        }
        rows
    }

    /// The geometric parameters' increments at `q` and their derivatives with respect to `values`
    /// (`derivatives`: false leaves the rows empty, for the forward kinematics alone).
    pub fn increments(&self, values: &[f64], q: &[f64], derivatives: bool) -> Increments {
        let mut out = Increments::default();
        let per = 2 * self.terms.harmonics as usize;
        // The joint's harmonics of its angle, then the motor's of ratio × angle.
        let joint = self.harmonic_joints.iter().map(|&j| (j, 1.0));
        let motor = self.motor_joints.iter().copied();
        for (n, (j, ratio)) in joint.chain(motor).enumerate() {
            let angle = ratio * self.joint_value(j, q);
            let first = per * n;
            let (mut value, mut row) = (0.0, Vec::with_capacity(if derivatives { per } else { 0 }));
            for order in 0..self.terms.harmonics as usize {
                let (s, c) = ((order + 1) as f64 * angle).sin_cos();
                let i = first + 2 * order;
                value += values[i] * c + values[i + 1] * s;
                if derivatives {
                    row.push((i, c));
                    row.push((i + 1, s));
                }
            }
            out.add(self.axis_slot(j), value, row);
        }
        if !self.hinges.is_empty() {
            let torques = self.torque_rows(q);
            let c0 = self.compliance_offset();
            for (n, (h, &tau)) in self.hinges.iter().zip(torques.iter()).enumerate() {
                let kappa = values[c0 + n] * 1e-3;
                let row = if derivatives {
                    vec![(c0 + n, tau * 1e-3)]
                } else {
                    Vec::new()
                };
                out.add(h.slot, kappa * tau, row);
            }
        }
        out
    }

    fn axis_slot(&self, j: usize) -> usize {
        match &self.reference {
            ArmKinematics::Dh(_) => 4 * j + 2,
            ArmKinematics::Chain { .. } => PARAMS_PER_JOINT * j + 5,
        }
    }

    /// The model with another reference geometry of the same form (a parameter file read for a robot).
    pub fn with_reference(&self, reference: &ArmKinematics) -> Self {
        self.rebuilt(reference)
    }

    /// The model's structure (terms, gravity, gear ratios) on `reference`, the held masses and the
    /// other arm not carried over.
    fn rebuilt(&self, reference: &ArmKinematics) -> Self {
        Self::build(
            reference,
            self.terms,
            self.gravity_in_base,
            self.gear_ratios.clone(),
        )
    }

    /// The same model with these gear ratios (motor turns per joint turn) by joint name; joints not
    /// named keep theirs. Motor-side harmonics are added for the revolute joints whose ratio is not
    /// ±1 (with harmonics in the terms): the parameter layout changes, so this belongs before any
    /// values are set. Names of no joint of this arm are ignored (the other arm's).
    pub fn with_gear_ratios(&self, ratios: &[(String, f64)]) -> Self {
        let mut gear_ratios = self.gear_ratios.clone();
        for (name, r) in ratios {
            if let Some(j) = self.joint_names.iter().position(|n| n == name) {
                gear_ratios[j] = Some(*r);
            }
        }
        let mut out = Self::build(
            &self.reference,
            self.terms,
            self.gravity_in_base,
            gear_ratios,
        );
        out.masses = self.masses.clone();
        out.other = self.other.clone();
        out
    }

    /// The gear ratios given, by joint name (motor turns per joint turn).
    pub fn gear_ratios(&self) -> Vec<(String, f64)> {
        self.gear_ratios
            .iter()
            .zip(&self.joint_names)
            .filter_map(|(r, n)| r.map(|r| (n.clone(), r)))
            .collect()
    }

    /// The names of the movable joints the model was built for.
    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }
}

/// One arm's non-geometric errors: the model (none: geometric) and its parameter values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointErrors {
    pub model: Option<Arc<JointErrorModel>>,
    pub values: Vec<f64>,
}

impl JointErrors {
    /// The errors of `terms` on `reference` at their start values (none for the geometric model).
    pub fn new(
        reference: &ArmKinematics,
        terms: ErrorTerms,
        gravity_in_base: Vector3<f64>,
    ) -> Self {
        if terms.is_geometric() {
            return Self::default();
        }
        let model = JointErrorModel::new(reference, terms, gravity_in_base);
        Self {
            values: model.start_values(),
            model: Some(Arc::new(model)),
        }
    }

    pub fn count(&self) -> usize {
        self.values.len()
    }

    pub fn is_geometric(&self) -> bool {
        self.model.is_none()
    }

    /// The terms (geometric when there is no model).
    pub fn terms(&self) -> ErrorTerms {
        self.model
            .as_ref()
            .map_or(ErrorTerms::GEOMETRIC, |m| m.terms)
    }

    /// The geometric parameters' increments at `q` and their derivatives (none for the geometric
    /// model).
    pub fn increments(&self, q: &[f64]) -> Option<Increments> {
        self.model
            .as_ref()
            .map(|m| m.increments(&self.values, q, true))
    }

    /// The geometric parameters' increments at `q` without their derivatives (the forward
    /// kinematics).
    pub fn increment_values(&self, q: &[f64]) -> Option<Increments> {
        self.model
            .as_ref()
            .map(|m| m.increments(&self.values, q, false))
    }
}

/// `kinematics` with the geometric parameters moved by `inc`.
pub fn moved_kinematics(kinematics: &ArmKinematics, inc: &Increments) -> ArmKinematics {
    match kinematics {
        ArmKinematics::Dh(rows) => {
            let mut rows: [DhRow; N_JOINTS] = *rows;
            for &(slot, v, _) in &inc.slots {
                let row = &mut rows[slot / 4];
                match slot % 4 {
                    0 => row.a_mm += v,
                    1 => row.d_mm += v,
                    2 => row.theta_rad += v,
                    _ => row.alpha_rad += v,
                }
            }
            ArmKinematics::Dh(rows)
        }
        ArmKinematics::Chain { chain, corrections } => {
            let mut corrections = corrections.clone();
            for &(slot, v, _) in &inc.slots {
                corrections[slot / PARAMS_PER_JOINT][slot % PARAMS_PER_JOINT] += v;
            }
            ArmKinematics::Chain {
                chain: Arc::clone(chain),
                corrections,
            }
        }
    }
}
