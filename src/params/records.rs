//! The optional records of a parameter file: provenance, the method, conditioning and statistics,
//! and the file of a calibration.

use super::{
    BaseTransform, FixedParameter, FixedParameters, ParamsError, ParamsFile, TrackerFrames,
    WeakParameters,
};
use crate::dataset::{Dataset, Split};
use crate::metrics::AccuracyReport;
use crate::side::{PerSide, Side};
use crate::solver::{BaseMethod, CalibrationResult, Method, QpMethod, Reflector};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;

/// Where a parameter file came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Program name, `dualcal`.
    pub tool: String,
    /// Program version.
    pub version: String,
    /// The dataset the parameters were identified from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dataset: Option<String>,
    /// UTC time of writing, `YYYY-MM-DDTHH:MM:SSZ`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub date_utc: Option<String>,
    /// Anything else a tool recorded.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, Value>,
}

impl Provenance {
    /// This program, now, with an optional dataset path.
    pub fn now(dataset: Option<&Path>) -> Self {
        Self {
            tool: env!("CARGO_PKG_NAME").to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            dataset: dataset.map(|p| p.display().to_string()),
            date_utc: Some(utc_timestamp(web_time::SystemTime::now())),
            extra: Default::default(),
        }
    }
}

/// `YYYY-MM-DDTHH:MM:SSZ` of a system time (UTC, proleptic Gregorian calendar).
pub fn utc_timestamp(t: web_time::SystemTime) -> String {
    let secs: i64 = match t.duration_since(web_time::UNIX_EPOCH) {
        Ok(d) => i64::try_from(d.as_secs()).unwrap_or(i64::MAX / 2),
        Err(e) => -i64::try_from(e.duration().as_secs()).unwrap_or(i64::MAX / 2),
    };
    let days = secs.div_euclid(86_400);
    let sod = secs.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        sod / 3600,
        (sod / 60) % 60,
        sod % 60
    )
}

/// Calendar date of a day count since 1970-01-01 (the usual era-of-400-years computation, with March
/// as the first month of the computational year so that leap days fall at the end).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468; // days since 0000-03-01
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097; // [0, 146096]
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365; // [0, 399]
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100); // [0, 365]
    let mp = (5 * doy + 2) / 153; // March = 0
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// The `method` record of a calibration's parameter file. Every method, QP solver and split is written
/// and read by one explicit spelling (the ones earlier versions wrote), never by a Rust name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodRecord {
    pub name: String,
    /// Step 1's method by its [`crate::solver::MethodSpec::objective`] spelling: `Minimax`,
    /// `LeastSquares`, `DistanceSingle`, `Pose` or `Position`.
    #[serde(with = "objective_spelling")]
    pub objective: Method,
    /// Step 1's method by its command-line name (`minimax`, `lsq`, `distance-single`, `pose`,
    /// `position`); absent in files of earlier versions (minimax or lsq, as `objective` says).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arm_method: Option<Method>,
    /// Step 2's method (`minimax`, `distance`, `absolute`); absent in files of earlier versions
    /// (the paper's minimax).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_method: Option<BaseMethod>,
    /// The reflector each arm's `distance-single` fit used (`a`, `b` or `c`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflector: Option<PerSide<Option<Reflector>>>,
    /// `Exact` or `Paper`.
    #[serde(with = "qp_spelling")]
    pub qp: QpMethod,
    /// `Cal`, `Ver` or `All`: the configurations used for identification.
    #[serde(with = "split_spelling")]
    pub split: Split,
    pub max_iterations: usize,
    pub step_tolerance: f64,
    pub progress_tolerance: f64,
    /// Configurations left out of the identification (`--exclude`, `--auto-exclude`, the workbench).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excluded: Vec<ConfigRef>,
}

impl MethodRecord {
    /// Step 1's method: `arm_method`, or in files of earlier versions `objective`.
    pub fn method(&self) -> Method {
        self.arm_method.unwrap_or(self.objective)
    }

    /// Step 2's method: `base_method`, or in files of earlier versions the paper's minimax.
    pub fn base_method(&self) -> BaseMethod {
        self.base_method.unwrap_or_default()
    }
}

/// The parameter file's spelling of a QP solver (the one earlier versions wrote).
pub fn qp_spelling(qp: QpMethod) -> &'static str {
    match qp {
        QpMethod::Exact => "Exact",
        QpMethod::Paper => "Paper",
    }
}

/// The parameter file's spelling of a split (the one earlier versions wrote).
pub fn split_spelling(split: Split) -> &'static str {
    match split {
        Split::Cal => "Cal",
        Split::Ver => "Ver",
        Split::All => "All",
    }
}

/// The value among `values` spelled `text`, or an error listing the spellings.
fn by_spelling<T: Copy, E: serde::de::Error>(
    values: &[T],
    spelling: impl Fn(T) -> &'static str,
    what: &str,
    text: &str,
) -> Result<T, E> {
    values
        .iter()
        .copied()
        .find(|&v| spelling(v) == text)
        .ok_or_else(|| {
            let known: Vec<&str> = values.iter().map(|&v| spelling(v)).collect();
            E::custom(format!(
                "unknown {what} `{text}` (known: {})",
                known.join(", ")
            ))
        })
}

mod qp_spelling {
    use super::*;
    use crate::choice::Choice;

    pub fn serialize<S: serde::Serializer>(qp: &QpMethod, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(qp_spelling(*qp))
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<QpMethod, D::Error> {
        let text = String::deserialize(d)?;
        by_spelling(QpMethod::all(), qp_spelling, "QP solver", &text)
    }
}

mod split_spelling {
    use super::*;
    use crate::choice::Choice;

    pub fn serialize<S: serde::Serializer>(split: &Split, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(split_spelling(*split))
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Split, D::Error> {
        let text = String::deserialize(d)?;
        by_spelling(Split::all(), split_spelling, "split", &text)
    }
}

/// Step 1's method by its [`crate::solver::MethodSpec::objective`] spelling.
mod objective_spelling {
    use super::*;

    pub fn serialize<S: serde::Serializer>(method: &Method, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(method.spec().objective)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Method, D::Error> {
        let text = String::deserialize(d)?;
        by_spelling(Method::ALL, |m| m.spec().objective, "objective", &text)
    }
}

/// A configuration by arm and id, as in the dataset's CSV.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ConfigRef {
    pub arm: Side,
    pub id: String,
}

/// Conditioning of one arm's identification (`statistics.identifiability.<arm>`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConditioningRecord {
    /// Number of identified (free) parameters.
    pub identified: usize,
    /// Condition number of the scaled Jacobian with every parameter; `null` when infinite.
    pub condition_before: Option<f64>,
    /// ... with the fixed parameters removed; `null` when infinite.
    pub condition_after: Option<f64>,
}

/// The `statistics` record of a calibration's parameter file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StatisticsRecord {
    /// Accuracy of the calibrated model on the calibration configurations (`null` if there are too few).
    pub cal: Option<AccuracyReport>,
    /// ... on the verification configurations.
    pub ver: Option<AccuracyReport>,
    /// Per arm; `null` for an arm whose stage did not run.
    pub identifiability: PerSide<Option<ConditioningRecord>>,
    /// Allowed deviation of the reflector triangle's sides (constraint 14), mm.
    pub reflector_side_tolerance_mm: PerSide<f64>,
    pub elapsed_secs: f64,
}

/// `Some(v)` for a finite `v` (JSON has no infinity).
fn finite_or_none(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A record as the file's free-form JSON value.
fn record(value: &impl Serialize) -> Option<Value> {
    serde_json::to_value(value).ok()
}

/// What the `method.name` field says of a combination of methods.
fn method_name(method: Method, base: BaseMethod) -> String {
    if method == Method::default() && base == BaseMethod::default() {
        return "two-step minimax calibration (paper Algorithms I and II)".into();
    }
    format!(
        "two-step calibration: step 1 {}, step 2 {}",
        method.spec().fits,
        base.spec().fits
    )
}

impl ParamsFile {
    /// The `method` record of a calibration's file (`None` for a file without one or with a
    /// free-form one that is no object); an error names the field that does not read.
    pub fn method_record(&self) -> Option<Result<MethodRecord, ParamsError>> {
        let value = self.method.as_ref().filter(|v| v.is_object())?;
        Some(
            MethodRecord::deserialize(value).map_err(|e| ParamsError::Invalid {
                path: None,
                field: "method".into(),
                message: e.to_string(),
            }),
        )
    }

    /// Record each arm's parameter uncertainty (`solver::uncertainty`; an arm without one is
    /// `null`, none at all leaves the field out).
    pub fn record_uncertainty(
        &mut self,
        uncertainty: &crate::side::PerSide<Option<crate::solver::uncertainty::ArmUncertainty>>,
    ) {
        self.uncertainty = uncertainty
            .values()
            .any(Option::is_some)
            .then(|| serde_json::to_value(uncertainty).ok())
            .flatten();
    }

    /// The file of a calibration: the calibrated model plus method, fixed parameters and why, per-stage
    /// termination, accuracy on the cal and ver splits of `dataset`, conditioning and provenance, and
    /// `converged: false` when the run did not converge. The command line and the workbench both
    /// export this.
    pub fn from_calibration(result: &CalibrationResult, dataset: &Dataset) -> ParamsFile {
        let settings = &result.settings;
        let mut file = ParamsFile::from_model(&result.calibrated);
        file.method = record(&MethodRecord {
            name: method_name(settings.method, settings.base_method),
            objective: settings.method,
            arm_method: Some(settings.method),
            base_method: Some(settings.base_method),
            reflector: settings
                .method
                .spec()
                .takes_reflector
                .then_some(result.reflector_used),
            qp: settings.qp,
            split: settings.split,
            max_iterations: settings.max_iterations,
            step_tolerance: settings.step_tolerance,
            progress_tolerance: settings.progress_tolerance,
            excluded: settings
                .exclude
                .iter()
                .filter_map(|c| {
                    let m = dataset.arm(c.side).measurements.get(c.index)?;
                    Some(ConfigRef {
                        arm: c.side,
                        id: m.id.clone(),
                    })
                })
                .collect(),
        });
        let fixed = |side: Side| -> Vec<FixedParameter> {
            result.identifiability[side]
                .iter()
                .flat_map(|rep| {
                    rep.fixed.iter().map(|f| FixedParameter {
                        name: f.name.clone(),
                        reason: f.reason.clone(),
                    })
                })
                .collect()
        };
        file.fixed_parameters = Some(FixedParameters {
            left: fixed(Side::Left),
            right: fixed(Side::Right),
        });
        if result.weak.values().any(|w| !w.is_empty()) {
            file.weak_parameters = Some(WeakParameters {
                left: result.weak.left.clone(),
                right: result.weak.right.clone(),
            });
        }
        file.termination = record(&result.stages);
        let frames = result.tracker_from_base;
        if frames.values().any(Option::is_some) {
            file.tracker_frames = Some(TrackerFrames {
                tracker_from_left_base: frames.left.as_ref().map(BaseTransform::from_isometry),
                tracker_from_right_base: frames.right.as_ref().map(BaseTransform::from_isometry),
                identified_by: Some(if settings.base_method.spec().identifies_tracker_frames {
                    format!("step 2 ({})", settings.base_method.name())
                } else {
                    format!("step 1 ({})", settings.method.name())
                }),
            });
        }
        // The figures leave the excluded configurations out, as the solver did.
        let kept = dataset.excluding(&settings.exclude);
        let accuracy = |split| crate::metrics::evaluate(&kept, &result.calibrated, split).ok();
        // The two splits side by side (each figure is computed as alone: the same numbers).
        let (cal, ver) = crate::par::join(|| accuracy(Split::Cal), || accuracy(Split::Ver));
        file.statistics = record(&StatisticsRecord {
            cal,
            ver,
            identifiability: result.identifiability.as_ref().map(|_, rep| {
                rep.as_ref().map(|rep| ConditioningRecord {
                    identified: rep.free.len(),
                    condition_before: finite_or_none(rep.condition_before),
                    condition_after: finite_or_none(rep.condition_after),
                })
            }),
            reflector_side_tolerance_mm: result.side_tolerance_mm,
            elapsed_secs: result.elapsed_secs,
        });
        file.converged = (!result.is_converged()).then_some(false);
        file.provenance = Some(Provenance::now(Some(&dataset.dir)));
        file
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        assert_eq!(civil_from_days(19_723), (2024, 1, 1));
        let t = web_time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
        assert_eq!(utc_timestamp(t), "2023-11-14T22:13:20Z");
    }
}
