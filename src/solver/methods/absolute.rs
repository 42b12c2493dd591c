//! The step-1 methods that fit absolute (tracker-frame) measurements, the tracker-from-base transform
//! identified with the arm: ref. [19]'s full poses (Gauss–Newton by QR) and ref. [18]'s absolute
//! positions (Levenberg–Marquardt). Each is set up like the paper's: an identifiability analysis of
//! its own Jacobian at the start (the transform's six columns first), column scaling, and the solver
//! on the identifiable parameters.

use super::set_up::{
    ArmSetUp, ArmStage, TreeSetUp, TreeStage, column_scales, least_squares_solver,
    require_kinematics,
};
use super::spec::{MethodSpec, Observes, SolverKind};
use crate::side::{PerSide, Side};
use crate::solver::algorithms::least_squares::LsqAlgorithm;
use crate::solver::analysis::identifiability::{
    Analysis, Columns, IdentifiabilityReport, ParameterInfo, analyse_columns,
};
use crate::solver::error::CalibrationError;
use crate::solver::problems::absolute_problem::{AbsoluteData, AbsoluteProblem, moore_penrose_fit};
use crate::solver::problems::tree_absolute::TreeAbsoluteProblem;
use crate::solver::problems::tree_problem::TreeLayout;
use crate::solver::types::Stage;
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

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
    tree_set_up: Some(|s| tree_set_up(s, "absolute positions", LsqAlgorithm::LevenbergMarquardt)),
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
    // Held kinematics: only the reflector coordinates and the transform are free.
    let hold = s.options.hold_kinematics;
    let allowed: Vec<bool> = (0..n_params + 6)
        .map(|p| !hold || p >= start.reflector_offset())
        .collect();
    let columns = Columns::Arm {
        arm: start,
        transform: Some(side),
    };
    let report = analyse_columns(&gram, &columns, &analysis(&allowed, what));
    require_transform(stage, &report, n_params)?;
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
    if !hold {
        require_kinematics(stage, start, &arm_report)?;
    }
    let scale = DVector::from_vec(column_scales(
        &gram,
        free.iter().copied().chain(n_params..n_params + 6),
    ));
    Ok(ArmStage {
        solver: least_squares_solver(probe.with_free(free, scale), algorithm, &s.options),
        identifiability: arm_report,
        reflector: None,
    })
}

/// What the analysis of an absolute method fitting `what` is told.
fn analysis<'a>(allowed: &'a [bool], what: &'a str) -> Analysis<'a> {
    Analysis {
        allowed,
        data: what,
        not_allowed: ParameterInfo::FIXED_BY_USER,
    }
}

/// `RankDeficient` when the analysis fixed a parameter of the tracker-from-base transform (the
/// columns from `n` on).
fn require_transform(
    stage: Stage,
    report: &IdentifiabilityReport,
    n: usize,
) -> Result<(), CalibrationError> {
    match report.fixed.iter().find(|f| f.index >= n) {
        Some(f) => Err(CalibrationError::RankDeficient {
            stage,
            detail: format!(
                "the tracker-from-base transform is not identifiable from these configurations \
                 ({}: {})",
                f.name, f.reason
            ),
        }),
        None => Ok(()),
    }
}

/// Both arms at once (a robot whose arms share joints) with one tracker frame: the positions of both
/// arms' reflectors (`solver::tree_absolute`). The identifiability analysis runs on the tree's
/// parameters and the transform (transform first, then each arm's preference order interleaved, a
/// shared joint once), on both arms' Gram matrices summed.
fn tree_set_up(
    s: &TreeSetUp,
    what: &str,
    algorithm: LsqAlgorithm,
) -> Result<TreeStage, CalibrationError> {
    let arms = &s.start.arms;
    let layout = TreeLayout::new(&arms.left, &arms.right, s.shared);
    let t0 = tree_tracker_start(s)?;
    let probes = PerSide::try_from_fn(|side| {
        let n = arms[side].param_count();
        s.data[side].absolute_problem(AbsoluteData::Position, &arms[side], t0, (0..n).collect())
    })?;
    let n_x = layout.len;
    let transform = n_x..n_x + 6;
    let gram = tree_gram(&probes, &layout);
    let hold = s.options.hold_kinematics;
    let allowed: Vec<bool> = (0..n_x + 6)
        .map(|x| {
            !hold || x >= n_x || {
                let (side, k) = layout.owner(x);
                k >= arms[side].reflector_offset()
            }
        })
        .collect();
    let columns = Columns::Tree {
        layout: &layout,
        arms,
        transform: true,
    };
    let report = analyse_columns(&gram, &columns, &analysis(&allowed, what));
    require_transform(Stage::Arms, &report, n_x)?;
    let free: Vec<usize> = report.free.iter().copied().filter(|&x| x < n_x).collect();
    let tree_report = IdentifiabilityReport {
        free: free.clone(),
        ..report
    };
    let reports = layout.split_report(&tree_report, arms);
    if !hold {
        for side in Side::BOTH {
            require_kinematics(Stage::Arms, &arms[side], &reports[side])?;
        }
    }
    let scale = DVector::from_vec(column_scales(&gram, free.iter().copied().chain(transform)));
    Ok(TreeStage {
        solver: least_squares_solver(
            TreeAbsoluteProblem::new(probes, &layout, &free, &scale),
            algorithm,
            &s.options,
        ),
        identifiability: reports,
    })
}

/// The one start of the tracker frame of both arms' chains, from both arms' points; refused unless
/// the chains start at one link.
fn tree_tracker_start(s: &TreeSetUp) -> Result<Isometry3<f64>, CalibrationError> {
    let arms = &s.start.arms;
    let base = &s.start.left_base_from_right_base;
    if base.translation.vector.norm() > 1e-9 || base.rotation.angle() > 1e-12 {
        return Err(CalibrationError::InvalidSettings(
            "the absolute positions of arms that share joints are fitted with one tracker frame, \
             which needs both arms' chains to start at one link (their base_link)"
                .into(),
        ));
    }
    let (mut model, mut measured): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) = (vec![], vec![]);
    for side in Side::BOTH {
        let d = &s.data[side];
        model.extend(
            d.qs.iter()
                .flat_map(|q| arms[side].reflector_fk(q).points_mm),
        );
        measured.extend(d.measured.iter().flatten().copied());
    }
    moore_penrose_fit(&model, &measured).ok_or_else(|| CalibrationError::NonFinite {
        stage: Stage::Arms,
        detail: "the tracker-from-base fit of the start model".into(),
    })
}

/// Both arms' Gram matrices summed on the tree's parameters (`layout`) and the transform's six after
/// them.
fn tree_gram(probes: &PerSide<AbsoluteProblem>, layout: &TreeLayout) -> DMatrix<f64> {
    let n_x = layout.len;
    let mut gram = DMatrix::zeros(n_x + 6, n_x + 6);
    for side in Side::BOTH {
        let g = probes[side].gram();
        let index: Vec<usize> = layout.index[side]
            .iter()
            .copied()
            .chain(n_x..n_x + 6)
            .collect();
        for (a, &ia) in index.iter().enumerate() {
            for (b, &ib) in index.iter().enumerate() {
                gram[(ia, ib)] += g[(a, b)];
            }
        }
    }
    gram
}
