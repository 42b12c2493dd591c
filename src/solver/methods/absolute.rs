//! The step-1 methods that fit absolute (tracker-frame) measurements, the tracker-from-base transform
//! identified with the arm: ref. [19]'s full poses (Gauss–Newton by QR) and ref. [18]'s absolute
//! positions (Levenberg–Marquardt). Each is set up like the paper's: an identifiability analysis of
//! its own Jacobian at the start (the transform's six columns first), column scaling, and the solver
//! on the identifiable parameters.

use super::set_up::{ArmSetUp, ArmStage, column_scales, least_squares_solver, require_kinematics};
use super::{MethodSpec, Observes, SolverKind};
use crate::solver::CalibrationError;
use crate::solver::absolute_problem::{AbsoluteData, AbsoluteProblem, transform_param_name};
use crate::solver::identifiability::{self, IdentifiabilityReport, ParameterInfo};
use crate::solver::least_squares::LsqAlgorithm;
use nalgebra::DVector;

pub const POSE: MethodSpec = MethodSpec {
    name: "pose",
    objective: "Pose",
    aliases: &[],
    label: "pose [19]",
    summary: "Minimises the pose error of a tool frame built from the three measured reflectors \
              (linearised model, QR), identifying the tracker-to-base transform with the arm.",
    fits: "full-pose errors (ref. [19])",
    table_label: "full pose",
    paper: Some("[19]"),
    observes: Observes::ThreeReflectors,
    count_rule: "6n pose components, 6 of them for the tracker frame",
    min_configurations: |p| (p + 6).div_ceil(6),
    identifies_tracker_frame: true,
    takes_reflector: false,
    solver: SolverKind::LeastSquares,
    set_up: |s| {
        let data = AbsoluteData::Pose {
            rotation_weight_mm: AbsoluteProblem::rotation_weight_mm(&s.start.reflectors_mm),
        };
        set_up(s, data, "poses", LsqAlgorithm::GaussNewtonQr)
    },
    tree_set_up: None,
};

pub const POSITION: MethodSpec = MethodSpec {
    name: "position",
    objective: "Position",
    aliases: &[],
    label: "position [18]",
    summary: "Minimises the three reflectors' absolute positioning errors in the tracker frame \
              (Levenberg–Marquardt), the tracker-to-base transform identified jointly. Needs \
              absolute tracker coordinates.",
    fits: "absolute positioning errors (ref. [18])",
    table_label: "positions",
    paper: Some("[18]"),
    observes: Observes::ThreeReflectors,
    count_rule: "9n coordinates, 6 of them for the tracker frame",
    min_configurations: |p| (p + 6).div_ceil(9),
    identifies_tracker_frame: true,
    takes_reflector: false,
    solver: SolverKind::LeastSquares,
    set_up: |s| {
        set_up(
            s,
            AbsoluteData::Position,
            "absolute positions",
            LsqAlgorithm::LevenbergMarquardt,
        )
    },
    tree_set_up: None,
};

/// The stage of an absolute method fitting `data` (`what`, for the reasons) by `algorithm`.
fn set_up(
    s: &ArmSetUp,
    data: AbsoluteData,
    what: &str,
    algorithm: LsqAlgorithm,
) -> Result<ArmStage, CalibrationError> {
    let (stage, side) = (s.stage(), s.data.side);
    let start = s.start;
    let n_params = start.param_count();
    let probe = s
        .data
        .absolute_probe(data, start, (0..n_params).collect())?;
    let gram = probe.gram();
    // The transform first: what it absorbs (a rigid motion of the whole arm) is fixed in the arm.
    let mut order: Vec<usize> = (n_params..n_params + 6).collect();
    order.extend(start.identifiability_order());
    let report = identifiability::analyse(
        &gram,
        &ParameterInfo {
            order: &order,
            allowed: &vec![true; n_params + 6],
            name: &|p| {
                if p < n_params {
                    start.param_name(p)
                } else {
                    transform_param_name(side, p - n_params)
                }
            },
            reason: &|p| {
                if p < n_params {
                    start.unidentifiable_reason(p)
                } else {
                    None
                }
            },
            data: what,
            not_allowed: ParameterInfo::FIXED_BY_USER,
        },
    );
    if let Some(f) = report.fixed.iter().find(|f| f.index >= n_params) {
        return Err(CalibrationError::RankDeficient {
            stage,
            detail: format!(
                "the tracker-from-base transform is not identifiable from these configurations \
                 ({}: {})",
                f.name, f.reason
            ),
        });
    }
    let free: Vec<usize> = report
        .free
        .iter()
        .copied()
        .filter(|&p| p < n_params)
        .collect();
    let arm_report = IdentifiabilityReport {
        free: free.clone(),
        fixed: report.fixed.clone(),
        ..report
    };
    require_kinematics(stage, start, &arm_report)?;
    let scale = DVector::from_vec(column_scales(
        &gram,
        free.iter().copied().chain(n_params..n_params + 6),
    ));
    Ok(ArmStage {
        solver: least_squares_solver(probe.with_free(free, scale), algorithm, s.settings),
        identifiability: arm_report,
        reflector: None,
    })
}
