//! The paper's Algorithm I: minimax of the three reflectors' summed squared distance errors, by SQP.

use super::set_up::{ArmSetUp, ArmStage, sqp_solver};
use super::{MethodSpec, Observes, SolverKind};
use crate::solver::CalibrationError;

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
    min_configurations: crate::solver::min_configurations,
    identifies_tracker_frame: false,
    takes_reflector: false,
    solver: SolverKind::Sqp,
    set_up,
};

fn set_up(s: &ArmSetUp) -> Result<ArmStage, CalibrationError> {
    let start = s.all_distances()?;
    Ok(ArmStage {
        solver: sqp_solver(start.problem, s.stage(), start.h0, s.settings)?,
        identifiability: start.report,
        reflector: None,
    })
}
