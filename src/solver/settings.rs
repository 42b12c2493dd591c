//! The settings of a calibration run: the methods of its two steps, their curvature and tolerances,
//! the configurations left out, the error model.

use crate::dataset::Split;
use crate::kinematics::ErrorTerms;
use crate::side::{ConfigId, PerSide};
use crate::solver::methods::table::{BaseMethod, Method};
use crate::solver::types::{Hessian, QpMethod, Reflector, StageOptions};
use serde::{Deserialize, Serialize};

/// Settings of a calibration run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSettings {
    /// Configurations used for identification (`cal` or `all`).
    pub split: Split,
    /// Step 1's method (each arm).
    pub method: Method,
    /// Step 2's method (the right-arm base); files without it mean the paper's minimax.
    #[serde(default)]
    pub base_method: BaseMethod,
    /// The reflector of [`Method::DistanceSingle`] (`None`: the one with the largest nominal error,
    /// chosen per arm); refused with any other method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflector: Option<Reflector>,
    pub qp: QpMethod,
    /// The SQP's curvature model (files without it were computed with BFGS).
    #[serde(
        default = "Hessian::of_older_files",
        skip_serializing_if = "Hessian::is_bfgs"
    )]
    pub hessian: Hessian,
    /// Outer SQP iterations per stage.
    pub max_iterations: usize,
    /// Stop when the scaled parameter step norm falls below this.
    pub step_tolerance: f64,
    /// Also stop (as converged) when ψ fell by less than this, relative, over the last five outer
    /// iterations; 0 disables the rule and leaves only the step-norm test.
    #[serde(default = "default_progress_tolerance")]
    pub progress_tolerance: f64,
    /// Iterations of the paper's subgradient QP solver per outer iteration.
    pub max_qp_iterations: usize,
    /// Configurations left out of the identification (suspect measurements: see
    /// [`crate::quality`]). Indices refer to the dataset given to the calibration.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub exclude: Vec<ConfigId>,
    /// Fit only the tracker frame and the reflector coordinates, the kinematic parameters held at the
    /// start model's (the absolute methods only; no step 2): the nominal robot's figure with its frame
    /// and markers fitted.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hold_kinematics: bool,
    /// The model's errors beyond geometry, identified with it by step 1's method
    /// ([`crate::kinematics::joint_errors`]); geometric (the paper's) by default.
    #[serde(default, skip_serializing_if = "ErrorTerms::is_geometric")]
    pub model: ErrorTerms,
    /// Gravity's direction in the left arm's model base frame, for the elastic terms (`None`: −z of that
    /// frame; the command line and the workbench give the robot's: −z of its root link).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity_in_left_base: Option<[f64; 3]>,
    /// The elastic terms' held lumped masses per arm — per movable joint kg and first moment kg·mm in
    /// the next joint frame — from the robot description's inertials
    /// ([`crate::robot::RobotDescription::lumped_masses`]); `None`: 1 kg at each next joint.
    #[serde(default, skip_serializing_if = "no_masses")]
    pub held_masses: PerSide<Option<crate::kinematics::joint_errors::LinkMasses>>,
    /// Gear ratios (motor turns per joint turn) by joint name: with harmonics in the model, the
    /// motor's harmonics are identified too for each joint whose ratio is not ±1 (the command line
    /// and the workbench give the URDF's `<transmission>` reductions, `--gear-ratio` overrides).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gear_ratios: Vec<(String, f64)>,
    /// Keep the weak parameters free ([`crate::solver::analysis::weak`]): by default each arm's step
    /// 1 is solved again with them held at their nominal values (`--keep-weak`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_weak: bool,
}

fn no_masses(m: &PerSide<Option<crate::kinematics::joint_errors::LinkMasses>>) -> bool {
    m.left.is_none() && m.right.is_none()
}

fn default_progress_tolerance() -> f64 {
    crate::solver::algorithms::sqp::PROGRESS_RTOL
}

impl CalibrationSettings {
    /// What a stage's solver is told of these settings.
    pub fn stage_options(&self) -> StageOptions {
        StageOptions {
            qp: self.qp,
            hessian: self.hessian,
            step_tolerance: self.step_tolerance,
            progress_tolerance: self.progress_tolerance,
            max_qp_iterations: self.max_qp_iterations,
            hold_kinematics: self.hold_kinematics,
            reflector: self.reflector,
        }
    }
}

impl Default for CalibrationSettings {
    fn default() -> Self {
        Self {
            split: Split::Cal,
            method: Method::Minimax,
            base_method: BaseMethod::Minimax,
            reflector: None,
            qp: QpMethod::Exact,
            hessian: Hessian::Auto,
            // The command line's `--max-iterations` default too, so that the workbench and the
            // library end a stage where `dualcal calibrate` does: a minimax stage at a three-way tie
            // with a vanishing multiplier can crawl for more than 100 iterations before "ψ
            // stationary" (docs/planning.md, *The estimator*: 175 on a public-YuMi simulation).
            max_iterations: 200,
            step_tolerance: 1e-8,
            progress_tolerance: default_progress_tolerance(),
            max_qp_iterations: 2000,
            exclude: Vec::new(),
            hold_kinematics: false,
            model: ErrorTerms::GEOMETRIC,
            gravity_in_left_base: None,
            held_masses: PerSide::default(),
            gear_ratios: Vec::new(),
            keep_weak: false,
        }
    }
}
