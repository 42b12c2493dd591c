//! Least squares of all three reflectors' distance errors by Levenberg–Marquardt: the baseline the
//! minimax objective is compared with (it bounds the sum, not the worst reflector, and ignores the
//! reflector-triangle constraints).

use super::set_up::{ArmSetUp, ArmStage, TreeSetUp, TreeStage, least_squares_solver};
use super::spec::{MethodSpec, Observes, SolverKind};
use crate::solver::algorithms::least_squares::{DistanceLeastSquares, LsqAlgorithm};
use crate::solver::error::CalibrationError;

pub const LSQ: MethodSpec = MethodSpec {
    name: "lsq",
    objective: "LeastSquares",
    aliases: &["leastsquares"],
    label: "least squares",
    summary: "Minimises the sum of all three reflectors' squared distance errors \
              (Levenberg–Marquardt). Distances only, like minimax; bounds the sum, not the worst \
              reflector.",
    fits: "least squares of the distance errors",
    table_label: "least squares",
    paper: None,
    observes: Observes::ThreeReflectors,
    count_rule: "9n − 18 independent distances",
    min_configurations: crate::solver::types::min_configurations,
    identifies_tracker_frame: false,
    takes_reflector: false,
    solver: SolverKind::LeastSquares,
    set_up,
    tree_set_up: Some(tree_set_up),
};

fn set_up(s: &ArmSetUp) -> Result<ArmStage, CalibrationError> {
    let start = s.all_distances()?;
    let problem = DistanceLeastSquares {
        reflectors: vec![true; s.start.reflector_count()],
        problem: start.problem,
    };
    Ok(ArmStage {
        solver: least_squares_solver(problem, LsqAlgorithm::LevenbergMarquardt, &s.options),
        identifiability: start.report,
        reflector: None,
    })
}

/// Both arms at once (shared joints): least squares of both arms' distance errors.
fn tree_set_up(s: &TreeSetUp) -> Result<TreeStage, CalibrationError> {
    let start = s.all_distances()?;
    let problem = DistanceLeastSquares {
        reflectors: vec![true; s.start.arm(crate::side::Side::Left).reflector_count()],
        problem: start.problem,
    };
    Ok(TreeStage {
        solver: least_squares_solver(problem, LsqAlgorithm::LevenbergMarquardt, &s.options),
        identifiability: start.reports,
    })
}
