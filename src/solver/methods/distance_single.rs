//! Ref. [26]: Gauss–Newton on the distance errors of one reflector (`CalibrationSettings::reflector`,
//! by default the one the nominal model fits worst). It cannot see the flange's orientation: the other
//! two reflectors' coordinates are not identified and stay nominal.

use super::set_up::{
    ArmSetUp, ArmStage, column_scales, distance_identifiability, least_squares_solver,
    require_kinematics, worst_reflector,
};
use super::spec::{MethodSpec, Observes, SolverKind};
use crate::solver::algorithms::least_squares::{DistanceLeastSquares, LsqAlgorithm};
use crate::solver::analysis::identifiability::Analysis;
use crate::solver::error::CalibrationError;
use nalgebra::DVector;

pub const DISTANCE_SINGLE: MethodSpec = MethodSpec {
    name: "distance-single",
    objective: "DistanceSingle",
    aliases: &[],
    label: "distance, one reflector [26]",
    summary: "Minimises one reflector's squared distance errors (Gauss–Newton). Cannot see the \
              flange's orientation: the other two reflectors are not identified and stay nominal.",
    fits: "one reflector's distance errors (ref. [26])",
    table_label: "one reflector",
    paper: Some("[26]"),
    observes: Observes::OneReflector,
    count_rule: "3n − 6 independent distances of one reflector",
    // 3n − 6 distances for the parameters less the other two reflectors' six.
    min_configurations: |p| (p.saturating_sub(6) + 6).div_ceil(3),
    identifies_tracker_frame: false,
    takes_reflector: true,
    solver: SolverKind::LeastSquares,
    set_up,
    tree_set_up: None,
};

fn set_up(s: &ArmSetUp) -> Result<ArmStage, CalibrationError> {
    let start = s.start;
    let n_params = start.param_count();
    let probe = s.data.distance_probe(start);
    let reflector = s
        .options
        .reflector
        .unwrap_or_else(|| worst_reflector(&probe.start_objectives_mm2()));
    let k = reflector.index();
    let count = start.reflector_count();
    if k >= count {
        return Err(CalibrationError::InvalidSettings(format!(
            "distance-single: reflector {reflector} (number {}) was chosen, the data have {count}",
            k + 1
        )));
    }
    let mask: Vec<bool> = (0..count).map(|r| r == k).collect();
    let probe = probe.with_reflectors(mask.clone());
    // The other reflectors' coordinates do not enter reflector k's distances at all.
    let off = start.reflector_offset();
    let allowed: Vec<bool> = (0..n_params)
        .map(|p| p < off || (p - off) / 3 == k)
        .collect();
    let not_allowed = format!(
        "not observed: distance-single fits reflector {reflector}'s distances only; kept at its \
         nominal value"
    );
    let (gram, report) = distance_identifiability(
        &probe,
        start,
        &Analysis {
            allowed: &allowed,
            data: "one reflector's distances",
            not_allowed: &not_allowed,
        },
    );
    require_kinematics(s.stage(), start, &report)?;
    let scale = DVector::from_vec(column_scales(&gram, report.free.iter().copied()));
    let problem = DistanceLeastSquares {
        problem: probe.with_free(report.free.clone(), scale),
        reflectors: mask,
    };
    Ok(ArmStage {
        solver: least_squares_solver(problem, LsqAlgorithm::GaussNewton, &s.options),
        identifiability: report,
        reflector: Some(reflector),
    })
}
