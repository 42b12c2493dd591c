//! Compensated joint targets: the joint values with which the calibrated robot reaches the pose its
//! controller's nominal model meant.
//!
//! A controller runs its own (nominal) kinematics; link lengths and joint-origin errors cannot be typed
//! into it. So each target is moved instead: for a nominal joint target `q` the pose meant is
//! `world_from_flange = B_ctrl · F_nominal(q)`, with `B_ctrl` the arm's base in the world (the left
//! arm's model base, see [`super`]) as the controller has it — nominal, or the calibrated one once the
//! base frames of [`super::abb`] are loaded — and the compensated target `q'` solves
//! `B_cal · F_calibrated(q') = world_from_flange`. A Cartesian target (a flange pose in the arm's
//! model base frame, as the controller's nominal model places it) is the same with `F_nominal(q)`
//! replaced by the pose.
//!
//! The solver: damped Newton (Levenberg–Marquardt) steps on the analytic joint Jacobian
//! ([`crate::kinematics::ArmModel::flange_jacobian`]), rotations weighted 1 mm per mrad, started at
//! the nominal target (or the seed). Each step is the damped minimum-norm solution, so a 7-joint arm
//! stays near its start; once the pose is reached, steps of self-motion (the Jacobian's null space)
//! towards the start, each followed by the Newton steps again, bring it to the nearest joint values
//! that reach the pose — the arm angle kept. Near a singular configuration (two axes nearly aligned:
//! the YuMi's shoulder at q2 ≈ 0, its elbow stretched, its wrist at q6 ≈ 0) a millimetre needs a large
//! joint motion: [`Compensated::largest_change`] says how large, and beyond
//! [`CompensationSettings::max_change_rad`] (20°; 50 mm for a prismatic joint) the target is refused. The result is accepted when the pose
//! error is below the tolerances (checked on the forward kinematics, not on the linearisation) and
//! every joint is within its limits; otherwise the target is refused with the reason.
//!
//! Joints both arms share (a torso, [`crate::kinematics::SharedJoints`]) are held at the target's
//! values: moving them for one arm's target would move the other arm. The arm's own joints reach the
//! pose alone, or the target is refused.

use crate::kinematics::DualArmModel;
use crate::side::Side;
use nalgebra::{DVector, Isometry3, Matrix6, Vector6};

/// The base frame the controller uses for the arm (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ControllerBase {
    /// The controller's base frames are the nominal ones: the calibration's base error is compensated
    /// in the joints too.
    #[default]
    Nominal,
    /// The calibrated base frames were loaded into the controller ([`super::abb`]): only the arm's own
    /// errors are compensated.
    Calibrated,
}

/// How targets are compensated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensationSettings {
    /// The base frames the controller uses (nominal, or the calibrated ones loaded into it).
    pub controller_base: ControllerBase,
    /// Newton steps at most per target.
    pub max_iterations: usize,
    /// Largest position error accepted, mm.
    pub tolerance_mm: f64,
    /// Largest rotation error accepted, rad.
    pub tolerance_rad: f64,
    /// Largest joint change accepted, rad for a revolute joint and mm for a prismatic one: a larger
    /// one means a target near a singular configuration, where the compensated motion would differ
    /// from the programmed one by more than a correction (the target is refused).
    pub max_change_rad: f64,
    /// [`Self::max_change_rad`] for a prismatic joint, mm.
    pub max_change_mm: f64,
}

impl Default for CompensationSettings {
    fn default() -> Self {
        Self {
            controller_base: ControllerBase::Nominal,
            max_iterations: 100,
            tolerance_mm: 1e-6,
            tolerance_rad: 1e-9,
            max_change_rad: 20f64.to_radians(),
            max_change_mm: 50.0,
        }
    }
}

/// A target of one arm.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// Nominal joint values (rad; mm for a prismatic joint), chain order.
    Joints(Vec<f64>),
    /// A flange pose in the arm's model base frame (mm) as the nominal model places it, and the joint
    /// values to start from (the program's own, or the previous target's).
    Pose {
        /// The flange pose in the arm's model base frame, mm.
        base_from_flange: Isometry3<f64>,
        /// The joint values to start from (empty: the previous target's result).
        seed: Vec<f64>,
    },
    /// A flange pose where it is physically wanted, in the world (the left arm's model base frame;
    /// from a tracker-frame pose through the tracker's registration), and the joint values to start
    /// from. The controller's base frame plays no part.
    WorldPose {
        /// The flange pose in the left arm's model base frame, mm.
        left_base_from_flange: Isometry3<f64>,
        /// The joint values to start from (empty: the previous target's result).
        seed: Vec<f64>,
    },
}

impl Target {
    /// The joint values the solution starts from: the nominal target or the seed.
    pub fn start(&self) -> &[f64] {
        match self {
            Target::Joints(q) => q,
            Target::Pose { seed, .. } | Target::WorldPose { seed, .. } => seed,
        }
    }
}

/// A compensated target.
#[derive(Clone, Debug, PartialEq)]
pub struct Compensated {
    /// Joint values (rad; mm for a prismatic joint), chain order.
    pub q: Vec<f64>,
    /// The largest change from the start (the nominal target or the seed), per joint in its unit.
    pub largest_change: f64,
    /// The remaining position error of the calibrated model, mm.
    pub residual_mm: f64,
    /// The remaining rotation error, rad.
    pub residual_rad: f64,
    /// The Newton steps taken.
    pub iterations: usize,
}

/// Why a target was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Refusal {
    #[error(
        "not reached: after {iterations} steps the calibrated robot is {residual_mm:.3e} mm and \
         {residual_rad:.3e} rad from the pose (out of reach, or a singular configuration)"
    )]
    /// The pose was not reached within the tolerances (out of reach, or a singular configuration).
    NotReached {
        /// The steps taken.
        iterations: usize,
        /// The remaining position error, mm.
        residual_mm: f64,
        /// The remaining rotation error, rad.
        residual_rad: f64,
    },
    #[error(
        "joint {joint} would be at {value:.6} {unit}, beyond its limits [{lower:.6}, {upper:.6}] {unit}"
    )]
    /// The solution puts a joint beyond its limits.
    JointLimit {
        /// The joint's name.
        joint: String,
        /// Its value, in `unit`.
        value: f64,
        /// Its lower limit, in `unit`.
        lower: f64,
        /// Its upper limit, in `unit`.
        upper: f64,
        /// `rad` or `mm`.
        unit: &'static str,
    },
    #[error(
        "joint {joint} would move by {change:.6} {unit} (more than {limit:.6} {unit}): the target is \
         near a singular configuration, where a correction becomes a large motion; move it away from \
         the singularity (or allow larger changes)"
    )]
    /// A joint would move by more than the largest change allowed (near a singular configuration).
    LargeChange {
        /// The joint's name.
        joint: String,
        /// Its change, in `unit`.
        change: f64,
        /// The largest change allowed, in `unit`.
        limit: f64,
        /// `rad` or `mm`.
        unit: &'static str,
    },
    /// The target has another number of joint values than the arm.
    #[error("expected {expected} joint values, found {found}")]
    JointCount {
        /// The arm's joints.
        expected: usize,
        /// The target's values.
        found: usize,
    },
}

/// Rotation error weight: 1 mm per mrad.
const MM_PER_RAD: f64 = 1000.0;

/// The pose a target means, in the world (the left arm's model base frame).
pub fn world_from_flange(
    nominal: &DualArmModel,
    calibrated: &DualArmModel,
    side: Side,
    target: &Target,
    settings: &CompensationSettings,
) -> Isometry3<f64> {
    let base = match settings.controller_base {
        ControllerBase::Nominal => nominal.left_base_from(side),
        ControllerBase::Calibrated => calibrated.left_base_from(side),
    };
    match target {
        Target::Joints(q) => base * nominal.arm(side).base_from_flange(q),
        Target::Pose {
            base_from_flange, ..
        } => base * base_from_flange,
        Target::WorldPose {
            left_base_from_flange,
            ..
        } => *left_base_from_flange,
    }
}

/// Compensate one target of `side` (module documentation). `joint_names` name the joints in refusals.
pub fn compensate(
    nominal: &DualArmModel,
    calibrated: &DualArmModel,
    side: Side,
    target: &Target,
    joint_names: &[String],
    settings: &CompensationSettings,
) -> Result<Compensated, Refusal> {
    let arm = calibrated.arm(side);
    let n = arm.joint_count();
    let start = target.start();
    if start.len() != n {
        return Err(Refusal::JointCount {
            expected: n,
            found: start.len(),
        });
    }
    let goal = calibrated.left_base_from(side).inverse()
        * world_from_flange(nominal, calibrated, side, target, settings);
    let held: Vec<usize> = calibrated
        .shared_joints()
        .variables
        .iter()
        .map(|&(a, b)| if side == Side::Left { a } else { b })
        .collect();
    let mut solver = PoseSolver {
        arm,
        goal,
        settings,
        lambda: 1e-3,
        iterations: 0,
        held: &held,
    };
    let mut q = DVector::from_column_slice(start);
    let mut residual = solver.solve(&mut q);
    if n - held.len().min(n) > 6 && solver.reached(residual) {
        residual = solver.back_towards(&mut q, start);
    }
    if !solver.reached(residual) {
        return Err(Refusal::NotReached {
            iterations: solver.iterations,
            residual_mm: residual.0,
            residual_rad: residual.1,
        });
    }
    check_joints(arm, q.as_slice(), start, joint_names, settings)?;
    let largest_change = q
        .iter()
        .zip(start)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    Ok(Compensated {
        q: q.as_slice().to_vec(),
        largest_change,
        residual_mm: residual.0,
        residual_rad: residual.1,
        iterations: solver.iterations,
    })
}

/// The damped Newton solver of one target: the calibrated arm, the flange pose wanted in its base.
struct PoseSolver<'a> {
    arm: &'a crate::kinematics::ArmModel,
    goal: Isometry3<f64>,
    settings: &'a CompensationSettings,
    lambda: f64,
    iterations: usize,
    /// Joint values that stay as they are (the joints both arms share).
    held: &'a [usize],
}

impl PoseSolver<'_> {
    /// The weighted pose error at `q` (mm, and rad × [`MM_PER_RAD`]), with its position and angle.
    fn error(&self, q: &DVector<f64>) -> (Vector6<f64>, f64, f64) {
        let f = self.arm.base_from_flange(q.as_slice());
        let dp = self.goal.translation.vector - f.translation.vector;
        let dw = (self.goal.rotation * f.rotation.inverse()).scaled_axis();
        let e = Vector6::new(
            dp.x,
            dp.y,
            dp.z,
            dw.x * MM_PER_RAD,
            dw.y * MM_PER_RAD,
            dw.z * MM_PER_RAD,
        );
        (e, dp.norm(), dw.norm())
    }

    /// The flange Jacobian with the rotation rows weighted alike.
    fn jacobian(&self, q: &DVector<f64>) -> nalgebra::Matrix6xX<f64> {
        let (_, mut jac) = self.arm.flange_jacobian(q.as_slice());
        for r in 3..6 {
            jac.row_mut(r).scale_mut(MM_PER_RAD);
        }
        for &c in self.held {
            if c < jac.ncols() {
                jac.column_mut(c).fill(0.0);
            }
        }
        jac
    }

    fn reached(&self, (mm, rad): (f64, f64)) -> bool {
        mm <= self.settings.tolerance_mm && rad <= self.settings.tolerance_rad
    }

    /// Damped Newton (Levenberg–Marquardt) steps from `q`: a step is kept when the error decreases,
    /// the damping then lowered; raised and the step tried again otherwise. The final error (mm, rad).
    fn solve(&mut self, q: &mut DVector<f64>) -> (f64, f64) {
        let (mut e, mut mm, mut rad) = self.error(q);
        while !self.reached((mm, rad)) && self.iterations < self.settings.max_iterations {
            self.iterations += 1;
            let jac = self.jacobian(q);
            let jt = jac.transpose();
            let mut improved = false;
            for _ in 0..30 {
                let normal = &jac * &jt + Matrix6::identity() * (self.lambda * self.lambda);
                let Some(chol) = normal.cholesky() else {
                    self.lambda *= 4.0;
                    continue;
                };
                let trial = &*q + &jt * chol.solve(&e);
                let (e2, mm2, rad2) = self.error(&trial);
                if e2.norm() < e.norm() {
                    (*q, e, mm, rad) = (trial, e2, mm2, rad2);
                    self.lambda = (self.lambda / 3.0).max(1e-9);
                    improved = true;
                    break;
                }
                self.lambda *= 4.0;
            }
            if !improved {
                break;
            }
        }
        (mm, rad)
    }

    /// A redundant arm on the pose: self-motion (the Jacobian's null space) back towards `start`, then
    /// onto the pose again, while that brings the joints nearer `start`. The final error.
    fn back_towards(&mut self, q: &mut DVector<f64>, start: &[f64]) -> (f64, f64) {
        let q0 = DVector::from_column_slice(start);
        let (_, mut mm, mut rad) = self.error(q);
        for _ in 0..20 {
            let jac = self.jacobian(q);
            let back = &q0 - &*q;
            let Ok(ranged) = jac.clone().svd(true, true).solve(&(&jac * &back), 1e-9) else {
                break;
            };
            let mut self_motion = back - ranged;
            for &c in self.held {
                if c < self_motion.len() {
                    self_motion[c] = 0.0;
                }
            }
            if self_motion.amax() < 1e-10 {
                break;
            }
            let mut trial = &*q + self_motion;
            let before = self.iterations;
            self.iterations = 0;
            let r = self.solve(&mut trial);
            let spent = self.iterations;
            self.iterations = before;
            if self.reached(r) && (&trial - &q0).norm() < (&*q - &q0).norm() {
                (*q, mm, rad) = (trial, r.0, r.1);
                self.iterations += spent;
            } else {
                break;
            }
        }
        (mm, rad)
    }
}

/// A solution's joints within their limits and changed by no more than the settings allow.
fn check_joints(
    arm: &crate::kinematics::ArmModel,
    q: &[f64],
    start: &[f64],
    joint_names: &[String],
    settings: &CompensationSettings,
) -> Result<(), Refusal> {
    let linear = arm.linear_joints();
    let name = |i: usize| {
        joint_names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("q{}", i + 1))
    };
    for (i, (&(lower, upper), &value)) in arm.joint_limits_rad().iter().zip(q).enumerate() {
        if value < lower - 1e-12 || value > upper + 1e-12 {
            return Err(Refusal::JointLimit {
                joint: name(i),
                value,
                lower,
                upper,
                unit: if linear[i] { "mm" } else { "rad" },
            });
        }
    }
    for (i, (a, b)) in q.iter().zip(start).enumerate() {
        let (limit, unit) = if linear[i] {
            (settings.max_change_mm, "mm")
        } else {
            (settings.max_change_rad, "rad")
        };
        if (a - b).abs() > limit {
            return Err(Refusal::LargeChange {
                joint: name(i),
                change: (a - b).abs(),
                limit,
                unit,
            });
        }
    }
    Ok(())
}

/// Compensate a list of targets in order. A pose without a seed starts from the previous target's
/// result (or, for the first, the middle of every joint's range).
pub fn compensate_all<'t>(
    nominal: &DualArmModel,
    calibrated: &DualArmModel,
    side: Side,
    targets: impl IntoIterator<Item = &'t Target>,
    joint_names: &[String],
    settings: &CompensationSettings,
) -> Vec<Result<Compensated, Refusal>> {
    let mut previous: Vec<f64> = calibrated
        .arm(side)
        .joint_limits_rad()
        .iter()
        .map(|(lo, hi)| 0.5 * (lo + hi))
        .collect();
    let mut out = Vec::new();
    for target in targets {
        let seeded;
        let target = match target {
            Target::Pose {
                base_from_flange,
                seed,
            } if seed.is_empty() => {
                seeded = Target::Pose {
                    base_from_flange: *base_from_flange,
                    seed: previous.clone(),
                };
                &seeded
            }
            Target::WorldPose {
                left_base_from_flange,
                seed,
            } if seed.is_empty() => {
                seeded = Target::WorldPose {
                    left_base_from_flange: *left_base_from_flange,
                    seed: previous.clone(),
                };
                &seeded
            }
            t => t,
        };
        let result = compensate(nominal, calibrated, side, target, joint_names, settings);
        if let Ok(c) = &result {
            previous.clone_from(&c.q);
        }
        out.push(result);
    }
    out
}
