//! The paper's Algorithm I: minimax of the three reflectors' summed squared distance errors, by SQP.

use super::set_up::{ArmSetUp, ArmStage, TreeSetUp, TreeStage, sqp_solver};
use super::spec::{MethodSpec, Observes, SolverKind};
use crate::solver::error::CalibrationError;
use crate::solver::types::{Stage, StageOptions};

pub const MINIMAX: MethodSpec = MethodSpec {
    name: "minimax",
    objective: "Minimax",
    aliases: &[],
    label: "minimax (paper, Algorithm I)",
    summary: "Minimises the largest of the three reflectors' summed squared distance errors (SQP). \
              Distances only: the tracker-to-base transform and the parameters distances cannot \
              see stay nominal.",
    fits: "minimax (paper Algorithm I)",
    table_label: "minimax",
    paper: Some("Our method"),
    observes: Observes::ThreeReflectors,
    count_rule: "9n − 18 independent distances",
    min_configurations: crate::solver::types::min_configurations,
    identifies_tracker_frame: false,
    takes_reflector: false,
    solver: SolverKind::Sqp,
    set_up,
    tree_set_up: Some(tree_set_up),
};

fn set_up(s: &ArmSetUp) -> Result<ArmStage, CalibrationError> {
    let start = s.all_distances()?;
    let options = StageOptions {
        hessian: s
            .options
            .hessian
            .resolved(Some(start.report.condition_after)),
        ..s.options
    };
    Ok(ArmStage {
        solver: sqp_solver(start.problem, s.stage(), start.h0, &options)?,
        identifiability: start.report,
        reflector: None,
    })
}

/// Both arms at once (shared joints): the minimax over the reflectors of both arms' summed squared
/// distance errors ([`crate::solver::tree_problem`]).
fn tree_set_up(s: &TreeSetUp) -> Result<TreeStage, CalibrationError> {
    let start = s.all_distances()?;
    // The tree problem has no Gauss–Newton matrix yet: `auto` is BFGS there (docs/solver.md).
    let options = StageOptions {
        hessian: s.options.hessian.resolved(None),
        ..s.options
    };
    Ok(TreeStage {
        solver: sqp_solver(start.problem, Stage::Arms, start.h0, &options)?,
        identifiability: start.reports,
    })
}
