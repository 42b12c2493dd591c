//! [`Report::build`]: the report's figures, from the parameter file's records and the engine.

use super::{
    ArmDataSummary, ArmSummary, BaseChange, DatasetSummary, Figures, MethodSummary, ParamRow,
    Report, ReportError, ReportInput, RobotSummary, ScreeningSummary, SplitAccuracy,
    UncertaintySource, WorstRow, shown_split, warnings,
};
use crate::analysis::{Analysis, Indicator};
use crate::comparison::BoxStats;
use crate::dataset::{Dataset, Split};
use crate::kinematics::{ArmModel, DualArmModel};
use crate::metrics;
use crate::params::{MethodRecord, ParamsFile, StatisticsRecord, utc_timestamp};
use crate::quality::{self, Flag, QualityRecord};
use crate::robot::RobotDescription;
use crate::side::{ConfigId, PerSide, Side};
use crate::solver::StageSummary;
use crate::solver::uncertainty::{self, ArmUncertainty};
use crate::workspace::Workspace;
use nalgebra::Vector3;
use std::path::Path;

/// How many of each arm's worst configurations the report lists.
pub const WORST_ROWS: usize = 10;

/// The position indicators the figures show, per pair kind.
const POSITION_INDICATORS: [Indicator; 3] = [
    Indicator::RelativePosition(Side::Left),
    Indicator::RelativePosition(Side::Right),
    Indicator::CollaborativePosition,
];

impl Report {
    /// The report of the parameters `params` (read from `params_path`) on the loaded dataset `ws`.
    pub fn build(
        ws: &Workspace,
        params: &ParamsFile,
        params_path: &Path,
    ) -> Result<Report, ReportError> {
        Self::build_from(
            ReportInput {
                dataset: &ws.dataset,
                robot: &ws.robot,
                nominal: &ws.nominal,
            },
            params,
            params_path,
        )
    }

    /// [`Report::build`] from the parts of a workspace (the workbench keeps them apart);
    /// `params_path` is where the parameters are said to come from.
    pub fn build_from(
        input: ReportInput<'_>,
        params: &ParamsFile,
        params_path: &Path,
    ) -> Result<Report, ReportError> {
        let ws = input;
        let ds = ws.dataset;
        let calibrated = params
            .to_model_for(ws.robot)
            .map_err(|error| ReportError::Model {
                path: params_path.to_path_buf(),
                error,
            })?
            .with_torso_instants(&ds.instants());
        let method = method_summary(params);
        let excluded = excluded_configs(ds, params, method.record.as_ref().ok());
        let kept = ds.excluding(&excluded);
        let accuracy = accuracy(&kept, ws.nominal, &calibrated)?;
        let split = shown_split(&accuracy);
        let body = ws.robot.body_from_arm_base(Side::Left);
        let analysis = |model: &DualArmModel| {
            Analysis::compute_excluding(ds, model, &body, &excluded).map_err(|source| {
                ReportError::Analysis {
                    path: ds.dir.clone(),
                    error: source,
                }
            })
        };
        let (before, after) = (analysis(ws.nominal)?, analysis(&calibrated)?);
        let screening = screening(ds, params, ws.nominal, &calibrated, &excluded);
        let arms = PerSide::from_fn(|side| {
            arm_summary(
                side,
                (ws.nominal.arm(side), calibrated.arm(side)),
                params,
                &method,
                &kept,
            )
        });
        let mut report = Report {
            generated_utc: utc_timestamp(web_time::SystemTime::now()),
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            params_path: params_path.to_path_buf(),
            provenance: params.provenance.clone(),
            dataset: dataset_summary(ds, &excluded),
            robot: robot_summary(ws.robot),
            method,
            arms,
            base: BaseChange {
                nominal: ws.nominal.left_base_from_right_base,
                calibrated: calibrated.left_base_from_right_base,
            },
            figures: figures(&before, &after, split),
            worst: PerSide::from_fn(|side| worst_rows(side, &before, &after, &screening.record)),
            noise: PerSide::default(),
            accuracy,
            screening,
            warnings: Vec::new(),
        };
        report.noise = warnings::noise_checks(&report.accuracy, &report.dataset.mpe_mm);
        report.warnings = warnings::of(&report);
        Ok(report)
    }
}

/// The `method`, `termination`, `converged` and `statistics` records.
fn method_summary(params: &ParamsFile) -> MethodSummary {
    let record = match params.method_record() {
        Some(Ok(r)) => Ok(r),
        Some(Err(e)) => Err(format!("the `method` record does not read: {e}")),
        None => Err(match &params.method {
            Some(v) => format!("the `method` record is free-form: {v}"),
            None => "the parameter file has no `method` record".into(),
        }),
    };
    let stages: Option<Vec<StageSummary>> = params
        .termination
        .clone()
        .and_then(|v| serde_json::from_value(v).ok());
    let converged = params.converged != Some(false)
        && stages
            .iter()
            .flatten()
            .all(|s| s.termination.is_converged());
    MethodSummary {
        record,
        stages,
        converged,
        statistics: params
            .statistics
            .clone()
            .and_then(|v| serde_json::from_value::<StatisticsRecord>(v).ok()),
    }
}

/// The configurations the calibration left out: the `method` record's and the `quality` record's.
fn excluded_configs(
    ds: &Dataset,
    params: &ParamsFile,
    record: Option<&MethodRecord>,
) -> Vec<ConfigId> {
    let quality: Option<QualityRecord> = params
        .quality
        .clone()
        .and_then(|v| serde_json::from_value(v).ok());
    let from_method = record
        .into_iter()
        .flat_map(|r| r.excluded.iter().map(|c| (c.arm, c.id.clone())));
    let from_quality = quality
        .into_iter()
        .flat_map(|q| q.excluded.into_iter().map(|c| (c.arm, c.id)));
    let mut out: Vec<ConfigId> = Vec::new();
    for (side, id) in from_method.chain(from_quality) {
        let index = ds.arm(side).measurements.iter().position(|m| m.id == id);
        if let Some(index) = index {
            let config = ConfigId::new(side, index);
            if !out.contains(&config) {
                out.push(config);
            }
        }
    }
    out
}

/// Nominal and calibrated accuracy ([`metrics::evaluate`]) on each split with enough configurations.
fn accuracy(
    kept: &Dataset,
    nominal: &DualArmModel,
    calibrated: &DualArmModel,
) -> Result<Vec<SplitAccuracy>, ReportError> {
    let mut out = Vec::new();
    for split in [Split::Cal, Split::Ver] {
        if !metrics::has_split(kept, split) {
            continue;
        }
        let evaluate = |model| {
            metrics::evaluate(kept, model, split).map_err(|error| ReportError::Metrics {
                path: kept.dir.clone(),
                error,
            })
        };
        out.push(SplitAccuracy {
            split,
            before: evaluate(nominal)?,
            after: evaluate(calibrated)?,
        });
    }
    Ok(out)
}

fn dataset_summary(ds: &Dataset, excluded: &[ConfigId]) -> DatasetSummary {
    let names = ds.reflector_names.iter().cloned();
    DatasetSummary {
        dir: ds.dir.clone(),
        arms: PerSide::from_fn(|side| {
            let arm = ds.arm(side);
            let count = |split| arm.measurements.iter().filter(|m| m.split == split).count();
            ArmDataSummary {
                file: arm.file.clone(),
                station: arm.station.clone(),
                joints: arm.joint_count(),
                cal: count(Split::Cal),
                ver: count(Split::Ver),
                excluded: excluded.iter().filter(|c| c.side == side).count(),
            }
        }),
        reflectors: names
            .zip(ds.nominal_reflectors_mm.iter().copied())
            .collect(),
        tracker: ds.tracker,
        mpe_mm: PerSide::from_fn(|side| quality::mpe_mm(ds, side)),
        one_station: ds.one_tracker_frame(),
        measured: PerSide::from_fn(|side| ds.arm(side).is_measured()),
    }
}

fn robot_summary(robot: &RobotDescription) -> RobotSummary {
    RobotSummary {
        name: robot.name(),
        builtin: robot.is_builtin(),
        nominal_model: if robot.is_builtin() {
            "Table 3 of the paper (DH)".into()
        } else {
            "the URDF's joint origins".into()
        },
        arms: PerSide::from_fn(|side| {
            let arm = robot.arm(side);
            (arm.links.to_string(), arm.joint_names())
        }),
    }
}

/// One arm's parameters, fixed parameters, conditioning and σ.
fn arm_summary(
    side: Side,
    (nominal, calibrated): (&ArmModel, &ArmModel),
    params: &ParamsFile,
    method: &MethodSummary,
    kept: &Dataset,
) -> ArmSummary {
    let fixed = params
        .fixed_parameters
        .as_ref()
        .map(|f| match side {
            Side::Left => f.left.clone(),
            Side::Right => f.right.clone(),
        })
        .unwrap_or_default();
    let (uncertainty, uncertainty_source) =
        arm_uncertainty(side, calibrated, params, method, kept, &fixed);
    let (x0, x1) = (nominal.to_vector(), calibrated.to_vector());
    // The errors beyond geometry (after the geometric ones) have no nominal value: it is 0 (the start).
    let parameters = (0..x1.len())
        .map(|k| {
            let name = calibrated.param_name(k);
            ParamRow {
                sigma: uncertainty
                    .as_ref()
                    .and_then(|u| u.parameters.iter().find(|p| p.name == name))
                    .map(|p| p.sigma),
                fixed: fixed
                    .iter()
                    .find(|f| f.name == name)
                    .map(|f| f.reason.clone()),
                angle: calibrated.param_is_angle(k),
                unit: calibrated.param_unit(k),
                nominal: x0.get(k).copied().unwrap_or(0.0),
                calibrated: x1[k],
                name,
            }
        })
        .collect();
    let weak = params
        .weak_parameters
        .as_ref()
        .map(|w| match side {
            Side::Left => w.left.clone(),
            Side::Right => w.right.clone(),
        })
        .unwrap_or_default();
    ArmSummary {
        parameters,
        fixed,
        weak,
        conditioning: method
            .statistics
            .as_ref()
            .and_then(|s| s.identifiability[side].clone()),
        uncertainty,
        uncertainty_source,
    }
}

/// The arm's σ: the parameter file's record, else computed as `dualcal calibrate` does
/// ([`uncertainty::arm_uncertainty_weighted`] with the method's weighting on the fitted
/// configurations, the fixed parameters left out).
fn arm_uncertainty(
    side: Side,
    calibrated: &ArmModel,
    params: &ParamsFile,
    method: &MethodSummary,
    kept: &Dataset,
    fixed: &[crate::params::FixedParameter],
) -> (Option<ArmUncertainty>, UncertaintySource) {
    if let Some(value) = &params.uncertainty {
        let recorded: Option<PerSide<Option<ArmUncertainty>>> =
            serde_json::from_value(value.clone()).ok();
        return match recorded.and_then(|r| r[side].clone()) {
            Some(u) => (Some(u), UncertaintySource::Recorded),
            None => (
                None,
                UncertaintySource::NotAvailable(
                    "the parameter file records none for this arm (the single-reflector and \
                     absolute methods have none)"
                        .into(),
                ),
            ),
        };
    }
    let Ok(record) = &method.record else {
        return (
            None,
            UncertaintySource::NotAvailable(
                "not recorded, and without a `method` record the fitted configurations are unknown"
                    .into(),
            ),
        );
    };
    let m = record.method();
    if m.is_absolute() || m.spec().takes_reflector {
        return (
            None,
            UncertaintySource::NotAvailable(format!(
                "not recorded; not computed for the `{}` method",
                m.name()
            )),
        );
    }
    let free: Vec<usize> = (0..calibrated.param_count())
        .filter(|&k| {
            let name = calibrated.param_name(k);
            !fixed.iter().any(|f| f.name == name)
        })
        .collect();
    let ms = kept.arm(side).select(record.split);
    let qs: Vec<Vec<f64>> = ms.iter().map(|m| m.q_rad.clone()).collect();
    let measured: Vec<Vec<Vector3<f64>>> = ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
    // The method's own weighting of the reflectors (the minimax's multipliers), as `calibrate` does.
    let Some(weighting) = uncertainty::Weighting::of(m, None) else {
        return (
            None,
            UncertaintySource::NotAvailable(format!(
                "not recorded; not computed for the `{}` method",
                m.name()
            )),
        );
    };
    match uncertainty::arm_uncertainty_weighted(calibrated, &qs, &measured, &free, &weighting) {
        Some(u) => (Some(u), UncertaintySource::Computed),
        None => (
            None,
            UncertaintySource::NotAvailable(
                "not recorded, and the fit is singular or has too few configurations".into(),
            ),
        ),
    }
}

/// The screening of the calibrated model: the `quality` record, else [`quality::screen_model`].
fn screening(
    ds: &Dataset,
    params: &ParamsFile,
    nominal: &DualArmModel,
    calibrated: &DualArmModel,
    excluded: &[ConfigId],
) -> ScreeningSummary {
    let recorded: Option<QualityRecord> = params
        .quality
        .clone()
        .and_then(|v| serde_json::from_value(v).ok());
    let (recorded, record) = match recorded {
        Some(r) => (true, r),
        None => {
            let settings = quality::ScreenSettings::default();
            let s = quality::screen_model(ds, nominal, calibrated, &settings);
            (false, QualityRecord::new(ds, &s, excluded))
        }
    };
    // The most severe flag of each configuration the calibration kept.
    let mut kept_suspects: Vec<Flag> = Vec::new();
    for f in record
        .flags
        .iter()
        .filter(|f| !excluded.contains(&f.config))
    {
        match kept_suspects.iter_mut().find(|k| k.config == f.config) {
            Some(k) if k.severity() < f.severity() => *k = f.clone(),
            Some(_) => {}
            None => kept_suspects.push(f.clone()),
        }
    }
    crate::sort::sort_by(&mut kept_suspects, |a, b| {
        b.severity().total_cmp(&a.severity())
    });
    ScreeningSummary {
        recorded,
        record,
        kept_suspects,
    }
}

/// Histograms and box plots of the position errors on `split`, nominal and calibrated.
fn figures(before: &Analysis, after: &Analysis, split: Split) -> Figures {
    let hist = |a: &Analysis, i| a.figures(split).and_then(|f| f.histogram(i)).cloned();
    let boxes = |a: &Analysis, i| a.samples(split, i).and_then(BoxStats::of);
    Figures {
        split,
        histograms: POSITION_INDICATORS
            .iter()
            .map(|&i| (i, hist(before, i), hist(after, i)))
            .collect(),
        boxes: POSITION_INDICATORS
            .iter()
            .map(|&i| (i, boxes(before, i), boxes(after, i)))
            .collect(),
    }
}

/// The arm's configurations with the largest |Δd| under the calibrated model.
fn worst_rows(
    side: Side,
    before: &Analysis,
    after: &Analysis,
    quality: &QualityRecord,
) -> Vec<WorstRow> {
    let mut rows: Vec<WorstRow> = after
        .configs
        .iter()
        .filter(|c| c.config.side == side && c.worst_pos_mm.is_finite())
        .map(|c| WorstRow {
            id: c.id.clone(),
            split: c.split,
            worst_pos_mm: c.worst_pos_mm,
            nominal_worst_pos_mm: before
                .configs
                .iter()
                .find(|b| b.config == c.config)
                .map(|b| b.worst_pos_mm),
            worst_ori_rad: c.worst_ori_rad,
            rigidity_mm: c.rigidity_mm,
            excluded: c.excluded,
            flag: quality
                .flags
                .iter()
                .filter(|f| f.config == c.config)
                .max_by(|a, b| a.severity().total_cmp(&b.severity()))
                .map(|f| f.kind.label()),
        })
        .collect();
    crate::sort::sort_by(&mut rows, |a, b| b.worst_pos_mm.total_cmp(&a.worst_pos_mm));
    rows.truncate(WORST_ROWS);
    rows
}
