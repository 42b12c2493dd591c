//! What a method is, as data: [`MethodSpec`] (a step-1 method: its names, labels, what it fits and
//! cannot see, the configurations it needs, its solver and its set-up functions) and
//! [`BaseMethodSpec`] (a step-2 method).

use super::set_up::{ArmSetUp, ArmStage, BaseSetUp, TreeSetUp, TreeStage};
use crate::solver::algorithms::stage::StageSolver;
use crate::solver::error::CalibrationError;

/// What a step-1 method's model can see of the flange: the comparisons hold a method to the noise
/// floor only on what it can see.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observes {
    /// All three reflectors: their positions and so the flange's orientation.
    ThreeReflectors,
    /// One reflector's distances: its position only, nothing of the orientation or the other two.
    OneReflector,
}

/// How a stage's solver reaches its answer (what a stage that stopped short is told).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverKind {
    /// The paper's SQP on the minimax problem.
    Sqp,
    /// Gauss–Newton or Levenberg–Marquardt on a sum of squares.
    LeastSquares,
}

/// A method's set-up for both arms at once (arms that share joints).
pub type TreeSetUpFn = fn(&TreeSetUp<'_>) -> Result<TreeStage, CalibrationError>;

/// Everything about one step-1 method (each arm's parameters).
pub struct MethodSpec {
    /// Its one name: `--method`, the parameter file's `method.arm_method`, the comparisons' key.
    pub name: &'static str,
    /// Its spelling in the parameter file's `method.objective` (the one earlier versions wrote).
    pub objective: &'static str,
    /// Other names it is read by (settings of earlier versions).
    pub aliases: &'static [&'static str],
    /// The workbench's label for it.
    pub label: &'static str,
    /// What it minimises and what it cannot see: the workbench's hover text, the command line's help.
    pub summary: &'static str,
    /// What it fits, for the parameter file's `method.name` (`… step 1 <fits>, step 2 …`).
    pub fits: &'static str,
    /// Its label in the comparisons' tables and legends.
    pub table_label: &'static str,
    /// The paper's column heading for it (`Our method`, `[26]`, …), if the paper compares it.
    pub paper: Option<&'static str>,
    pub observes: Observes,
    /// How many independent equations n configurations give it, for messages.
    pub count_rule: &'static str,
    /// The configurations it needs per arm for an arm with `p` parameters that distances can identify
    /// ([`crate::solver::identifiable_params`]); at least [`crate::dataset::MIN_CONFIGS`] in any case.
    pub min_configurations: fn(p: usize) -> usize,
    /// Does it fit absolute (tracker-frame) measurements, identifying the tracker-from-base transform
    /// with the arm? (Its arms then get no distance identifiability re-check at the solution.)
    pub identifies_tracker_frame: bool,
    /// Does it fit one reflector, chosen by `CalibrationSettings::reflector`?
    pub takes_reflector: bool,
    pub solver: SolverKind,
    /// Its stage's set-up: identifiability, scaling and the solver on the identifiable parameters.
    pub set_up: fn(&ArmSetUp<'_>) -> Result<ArmStage, CalibrationError>,
    /// Its set-up for both arms at once, where the arms share joints (a torso); `None`: the method
    /// cannot fit such a robot ([`CalibrationError::SharedJointsUnsupported`]).
    pub tree_set_up: Option<TreeSetUpFn>,
}

/// Everything about one step-2 method (the right-arm base in the left-arm base).
pub struct BaseMethodSpec {
    /// Its one name: `--base-method`, the parameter file's `method.base_method`.
    pub name: &'static str,
    /// Other names it is read by.
    pub aliases: &'static [&'static str],
    /// The workbench's label for it.
    pub label: &'static str,
    /// What it minimises and what it cannot see: the workbench's hover text, the command line's help.
    pub summary: &'static str,
    /// What it fits, for the parameter file's `method.name`.
    pub fits: &'static str,
    /// Its key in the comparisons (`None`: it takes part through the step-1 method of the same paper).
    pub compared_as: Option<&'static str>,
    /// Its label in the comparisons' tables and legends.
    pub table_label: &'static str,
    /// The paper's column heading for it.
    pub paper: Option<&'static str>,
    /// Does it identify each arm's base in the tracker frame (overriding step 1's)?
    pub identifies_tracker_frames: bool,
    pub solver: SolverKind,
    /// Its stage's set-up: the problem on step 1's arms, its checks and the solver.
    pub set_up: fn(&BaseSetUp<'_>) -> Result<Box<dyn StageSolver>, CalibrationError>,
}
