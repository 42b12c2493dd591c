//! The step-2 methods (the right-arm base in the left-arm base, step 1's arms held): the paper's
//! Algorithm II, ref. [26]'s collaborative distances by Gauss–Newton, and ref. [28]'s bases in the
//! tracker frame combined through the Moore–Penrose inverse.

use super::set_up::{BaseSetUp, column_scales, least_squares_solver, sqp_solver};
use super::spec::{BaseMethodSpec, SolverKind};
use crate::side::PerSide;
use crate::solver::algorithms::least_squares::{DistanceLeastSquares, LsqAlgorithm};
use crate::solver::algorithms::stage::StageSolver;
use crate::solver::error::CalibrationError;
use crate::solver::problems::absolute_problem::{AbsoluteData, BaseAbsoluteProblem};
use crate::solver::types::Stage;
use nalgebra::DVector;

pub const MINIMAX: BaseMethodSpec = BaseMethodSpec {
    name: "minimax",
    aliases: &[],
    label: "minimax (paper, Algorithm II)",
    summary: "Minimises the largest collaborative distance error of left/right configuration pairs \
              (SQP). Distances only.",
    fits: "minimax (paper Algorithm II)",
    // Compared through step 1's minimax: the paper's own method takes part in both comparisons.
    compared_as: None,
    table_label: "minimax",
    paper: Some("Our method"),
    identifies_tracker_frames: false,
    solver: SolverKind::Sqp,
    set_up: |s| {
        let (problem, h0) = s.collaborative_distances()?;
        let options = crate::solver::types::StageOptions {
            hessian: s.options.hessian.resolved(None),
            ..s.options
        };
        sqp_solver(problem, Stage::Base, h0, &options)
    },
};

pub const DISTANCE: BaseMethodSpec = BaseMethodSpec {
    name: "distance",
    aliases: &[],
    label: "distance [26]",
    summary: "Minimises the sum of squared collaborative distance errors (Gauss–Newton). Distances \
              only; bounds the sum, not the worst pair.",
    fits: "collaborative distance errors (ref. [26])",
    compared_as: Some("base-distance"),
    table_label: "base by distances",
    paper: Some("[26]"),
    identifies_tracker_frames: false,
    solver: SolverKind::LeastSquares,
    set_up: |s| {
        let (problem, _) = s.collaborative_distances()?;
        let problem = DistanceLeastSquares {
            problem,
            reflectors: vec![true; s.model.arm(crate::side::Side::Left).reflector_count()],
        };
        Ok(least_squares_solver(
            problem,
            LsqAlgorithm::GaussNewton,
            &s.options,
        ))
    },
};

pub const ABSOLUTE: BaseMethodSpec = BaseMethodSpec {
    name: "absolute",
    aliases: &[],
    label: "absolute [28]",
    summary: "Locates each arm's base in the tracker frame from its absolute positioning errors \
              (step 1's arms held) and combines the two (Moore–Penrose inverse). Sees only what \
              each arm's absolute errors show; never fits the collaborative distances themselves.",
    fits: "bases in the tracker frame (ref. [28])",
    compared_as: Some("base-absolute"),
    table_label: "base by positions",
    paper: Some("[28]"),
    identifies_tracker_frames: true,
    solver: SolverKind::LeastSquares,
    set_up: absolute,
};

/// Each arm's base in the tracker frame from its absolute positioning errors (step 1's arms held),
/// combined through the Moore–Penrose inverse.
fn absolute(s: &BaseSetUp) -> Result<Box<dyn StageSolver>, CalibrationError> {
    let arms = PerSide::try_from_fn(|side| {
        let arm = s.model.arm(side).clone();
        let probe = s.data[side].absolute_probe(AbsoluteData::Position, &arm, Vec::new())?;
        let gram = probe.gram();
        let sv = gram.singular_values();
        if sv.min() <= sv.max() * 1e-12 {
            return Err(CalibrationError::RankDeficient {
                stage: Stage::Base,
                detail: format!(
                    "{side} arm: the tracker-from-base Jacobian's Gram matrix has singular values \
                     {:?}",
                    sv.as_slice()
                ),
            });
        }
        let scale = DVector::from_vec(column_scales(&gram, 0..6));
        Ok(probe.with_free(Vec::new(), scale))
    })?;
    Ok(least_squares_solver(
        BaseAbsoluteProblem { arms },
        LsqAlgorithm::GaussNewton,
        &s.options,
    ))
}
