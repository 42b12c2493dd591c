//! The stages of the paper's comparison methods (its Table 1; docs/solver.md): the single-reflector
//! distances of ref. [26], the full poses of ref. [19] and the absolute positions of ref. [18] in
//! step 1, and the bases in the tracker frame of ref. [28] in step 2. Each stage is set up like the
//! paper's: an identifiability analysis of the method's own Jacobian at the start (what the method's
//! data can see), column scaling, and a [`StageSolver`] on the identifiable parameters.

use super::super::absolute_problem::{
    AbsoluteData, AbsoluteProblem, BaseAbsoluteProblem, moore_penrose_fit, transform_param_name,
    triangle_area_mm2,
};
use super::super::arm_problem::ArmProblem;
use super::super::identifiability::{self, IdentifiabilityReport, ParameterInfo};
use super::super::least_squares::{DistanceLeastSquares, LsqAlgorithm, LsqState};
use super::super::{CalibrationError, Method, Reflector, Stage, StageSolver};
use super::{CalibrationRun, IDENTIFIABILITY_PAIRS};
use crate::kinematics::ArmModel;
use crate::side::{PerSide, Side};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

/// The reflector `distance-single` uses by default: the one whose distance errors the nominal model
/// fits worst (largest F_k), as ref. [26] is compared in the paper.
pub fn worst_reflector(objectives_mm2: [f64; 3]) -> Reflector {
    let k = (0..3)
        .max_by(|&a, &b| objectives_mm2[a].total_cmp(&objectives_mm2[b]))
        .unwrap_or(0);
    Reflector::from_index(k).unwrap_or(Reflector::A)
}

/// `RankDeficient` unless some kinematic parameter (not a reflector coordinate) is free: data in
/// which every configuration is the same show nothing of the arm.
fn require_kinematics(
    stage: Stage,
    arm: &ArmModel,
    report: &IdentifiabilityReport,
) -> Result<(), CalibrationError> {
    if report.free.iter().any(|&k| k < arm.reflector_offset()) {
        return Ok(());
    }
    Err(CalibrationError::RankDeficient {
        stage,
        detail:
            "no kinematic parameter is identifiable from these configurations (are they all the \
                 same?)"
                .into(),
    })
}

/// Scales `1/√G_kk` of the columns `idx` of a mean Gram matrix.
fn column_scales(gram: &DMatrix<f64>, idx: impl Iterator<Item = usize>) -> Vec<f64> {
    idx.map(|k| 1.0 / gram[(k, k)].max(0.0).sqrt().max(1e-12))
        .collect()
}

impl CalibrationRun {
    /// Step 1 by ref. [26]: Gauss–Newton on the distance errors of one reflector.
    pub(super) fn distance_single_solver(
        &mut self,
        side: Side,
    ) -> Result<Box<dyn StageSolver>, CalibrationError> {
        let stage = Stage::Arm(side);
        let input = &self.inputs[side];
        let start = self.nominal.arm(side);
        let n_params = start.param_count();
        let probe = ArmProblem::new(
            input.qs.clone(),
            &input.measured,
            start,
            (0..n_params).collect(),
            DVector::from_element(n_params, 1.0),
            input.side_tolerance_mm,
        );
        let reflector = self
            .settings
            .reflector
            .unwrap_or_else(|| worst_reflector(probe.start_objectives_mm2()));
        let k = reflector.index();
        let mask = std::array::from_fn(|r| r == k);
        let probe = probe.with_reflectors(mask);
        let columns = probe.sample_pair_jacobian(&DVector::zeros(n_params), IDENTIFIABILITY_PAIRS);
        let gram = identifiability::gram_by_product(&columns);
        // The other reflectors' coordinates do not enter reflector k's distances at all.
        let off = start.reflector_offset();
        let allowed: Vec<bool> = (0..n_params)
            .map(|p| p < off || (p - off) / 3 == k)
            .collect();
        let not_allowed = format!(
            "not observed: distance-single fits reflector {reflector}'s distances only; kept at its \
             nominal value"
        );
        let order = start.identifiability_order();
        let report = identifiability::analyse(
            &gram,
            &ParameterInfo {
                order: &order,
                allowed: &allowed,
                name: &|p| start.param_name(p),
                reason: &|p| start.unidentifiable_reason(p),
                data: "one reflector's distances",
                not_allowed: &not_allowed,
            },
        );
        require_kinematics(stage, start, &report)?;
        let scale = DVector::from_vec(column_scales(&gram, report.free.iter().copied()));
        let problem = probe.with_free(report.free.clone(), scale);
        self.identifiability[side] = Some(report);
        self.reflector_used[side] = Some(reflector);
        Ok(Box::new(LsqState::new(
            DistanceLeastSquares {
                problem,
                reflectors: mask,
            },
            LsqAlgorithm::GaussNewton,
            self.settings.step_tolerance,
        )))
    }

    /// The start of `tracker_from_base` for `side`'s arm `arm`: the Moore–Penrose fit of its model
    /// points to the measured ones.
    fn tracker_start(
        &self,
        side: Side,
        arm: &ArmModel,
    ) -> Result<Isometry3<f64>, CalibrationError> {
        let input = &self.inputs[side];
        let model: Vec<Vector3<f64>> = input
            .qs
            .iter()
            .flat_map(|q| arm.reflector_fk(q).points_mm)
            .collect();
        let measured: Vec<Vector3<f64>> = input.measured.iter().flatten().copied().collect();
        moore_penrose_fit(&model, &measured).ok_or_else(|| CalibrationError::NonFinite {
            stage: Stage::Arm(side),
            detail: "the tracker-from-base fit of the start model".into(),
        })
    }

    /// An absolute problem of `side` on `arm` with every parameter free (unit scales), or the typed
    /// error of a configuration whose measured reflectors are collinear (pose data).
    fn absolute_probe(
        &self,
        side: Side,
        data: AbsoluteData,
        arm: &ArmModel,
        free: Vec<usize>,
    ) -> Result<AbsoluteProblem, CalibrationError> {
        let input = &self.inputs[side];
        let t0 = self.tracker_start(side, arm)?;
        let scale = DVector::from_element(free.len() + 6, 1.0);
        AbsoluteProblem::new(
            data,
            side,
            input.qs.clone(),
            input.measured.clone(),
            arm,
            t0,
            free,
            scale,
        )
        .map_err(|i| CalibrationError::DegenerateReflectors {
            side,
            id: input.ids[i].clone(),
            area_mm2: triangle_area_mm2(&input.measured[i]).0,
        })
    }

    /// Step 1 by ref. [19] (full pose, Gauss–Newton by QR) or ref. [18] (absolute positions,
    /// Levenberg–Marquardt), the tracker-from-base transform identified with the arm.
    pub(super) fn absolute_arm_solver(
        &mut self,
        side: Side,
    ) -> Result<Box<dyn StageSolver>, CalibrationError> {
        let stage = Stage::Arm(side);
        let start = self.nominal.arm(side).clone();
        let n_params = start.param_count();
        let (data, what, algorithm) = match self.settings.method {
            Method::Pose => (
                AbsoluteData::Pose {
                    rotation_weight_mm: AbsoluteProblem::rotation_weight_mm(&start.reflectors_mm),
                },
                "poses",
                LsqAlgorithm::GaussNewtonQr,
            ),
            _ => (
                AbsoluteData::Position,
                "absolute positions",
                LsqAlgorithm::LevenbergMarquardt,
            ),
        };
        let probe = self.absolute_probe(side, data, &start, (0..n_params).collect())?;
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
        require_kinematics(stage, &start, &arm_report)?;
        let scale = DVector::from_vec(column_scales(
            &gram,
            free.iter().copied().chain(n_params..n_params + 6),
        ));
        let problem = probe.with_free(free, scale);
        self.identifiability[side] = Some(arm_report);
        Ok(Box::new(LsqState::new(
            problem,
            algorithm,
            self.settings.step_tolerance,
        )))
    }

    /// Step 2 by ref. [28]: each arm's base in the tracker frame from its absolute positioning
    /// errors (step 1's arms held), combined through the Moore–Penrose inverse.
    pub(super) fn absolute_base_solver(
        &mut self,
    ) -> Result<Box<dyn StageSolver>, CalibrationError> {
        let arms = PerSide::try_from_fn(|side| {
            let arm = self.committed.arm(side).clone();
            let probe = self.absolute_probe(side, AbsoluteData::Position, &arm, Vec::new())?;
            let gram = probe.gram();
            let sv = gram.singular_values();
            if sv.min() <= sv.max() * 1e-12 {
                return Err(CalibrationError::RankDeficient {
                    stage: Stage::Base,
                    detail: format!(
                        "{side} arm: the tracker-from-base Jacobian's Gram matrix has singular \
                         values {:?}",
                        sv.as_slice()
                    ),
                });
            }
            let scale = DVector::from_vec(column_scales(&gram, 0..6));
            Ok(probe.with_free(Vec::new(), scale))
        })?;
        Ok(Box::new(LsqState::new(
            BaseAbsoluteProblem { arms },
            LsqAlgorithm::GaussNewton,
            self.settings.step_tolerance,
        )))
    }
}
