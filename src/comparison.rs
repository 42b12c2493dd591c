//! Calibration methods side by side on one dataset: the comparison of the paper's Tables 4–8 and
//! Figs. 6–8, which `dualcal reproduce paper` runs on simulated data and the workbench's comparison
//! view runs on the loaded dataset.
//!
//! Every method is driven the same way — [`CalibrationSettings`] through [`Calibrator`] — and the
//! methods compared are the rows of [`METHODS`], read from the methods' own table
//! ([`crate::solver::methods`]): a method added there takes part in every comparison (the CLI's
//! tables and figures, the workbench's view). Each method's calibrated model
//! is evaluated as every model is, [`Analysis::compute_excluding`] (the paper's eqs. 5–8 on both
//! splits, with every pair's residuals kept as samples for the histograms and box plots), on the
//! configurations it was calibrated on.

use crate::analysis::{Analysis, AnalysisError, Histogram, Indicator};
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::solver::{
    BaseMethod, CalibrationError, CalibrationResult, CalibrationSettings, Calibrator, Method,
};
use nalgebra::Isometry3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

/// Which of the paper's comparisons a method takes part in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A step-1 method (each arm's geometry) with the paper's minimax step 2: Tables 4, 5, 7, 8 and
    /// Figs. 4, 6, 8.
    Arms,
    /// A step-2 method (the right-arm base in the left-arm base) on the paper's minimax arms: Table 6
    /// and Fig. 7.
    Base,
    /// The paper's own method, in both comparisons.
    Both,
}

impl Role {
    /// Whether the method takes part in the step-1 comparison.
    pub fn compares_arms(self) -> bool {
        matches!(self, Role::Arms | Role::Both)
    }

    /// Whether the method takes part in the step-2 comparison.
    pub fn compares_base(self) -> bool {
        matches!(self, Role::Base | Role::Both)
    }
}

pub use crate::solver::Observes;

/// One compared method: a name, its column in the paper, and the step-1 and step-2 methods that
/// select it in [`CalibrationSettings`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodEntry {
    /// Short name: `reproduce paper --methods`, the CSV files' `column`.
    pub key: &'static str,
    /// What it is, for tables and legends.
    pub label: &'static str,
    /// The paper's column heading for it (`Our method`, `[26]`, …), if the paper compares it.
    pub paper: Option<&'static str>,
    pub role: Role,
    pub observes: Observes,
    /// Step 1's method (the paper's minimax for a step-2 method).
    pub method: Method,
    /// Step 2's method (the paper's minimax for a step-1 method).
    pub base_method: BaseMethod,
}

impl MethodEntry {
    /// Its settings on top of `common` (split, iteration limits, QP; the reflector is left to the
    /// method's default choice).
    pub fn settings(&self, common: &CalibrationSettings) -> CalibrationSettings {
        CalibrationSettings {
            method: self.method,
            base_method: self.base_method,
            reflector: None,
            ..common.clone()
        }
    }

    /// The label with the paper's column: `minimax (Our method)`, `distance, one reflector [26]`.
    pub fn title(&self) -> String {
        match self.paper {
            Some(p) if p.starts_with('[') => format!("{} {p}", self.label),
            Some(p) => format!("{} ({p})", self.label),
            None => self.label.to_owned(),
        }
    }
}

/// The compared methods, read from the methods' tables ([`Method::ALL`], [`BaseMethod::ALL`]): every
/// step-1 method on the paper's step 2 — the paper's columns first, in the table's order, then the
/// others — and every step-2 method compared on its own, on the paper's step 1. The paper's own
/// method (the default of both steps) takes part in both comparisons.
pub static METHODS: LazyLock<Vec<MethodEntry>> = LazyLock::new(|| {
    let (paper, others): (Vec<Method>, Vec<Method>) =
        Method::ALL.iter().partition(|m| m.spec().paper.is_some());
    let arms = paper.into_iter().chain(others).map(|method| {
        let spec = method.spec();
        MethodEntry {
            key: spec.name,
            label: spec.table_label,
            paper: spec.paper,
            role: if method == Method::default() {
                Role::Both
            } else {
                Role::Arms
            },
            observes: spec.observes,
            method,
            base_method: BaseMethod::default(),
        }
    });
    let bases = BaseMethod::ALL.iter().filter_map(|&base_method| {
        let spec = base_method.spec();
        Some(MethodEntry {
            key: spec.compared_as?,
            label: spec.table_label,
            paper: spec.paper,
            role: Role::Base,
            observes: Observes::ThreeReflectors,
            method: Method::default(),
            base_method,
        })
    });
    arms.chain(bases).collect()
});

/// The entry of `key`.
pub fn method(key: &str) -> Option<&'static MethodEntry> {
    METHODS.iter().find(|m| m.key == key)
}

/// Why a compared method has no figures.
#[derive(Clone, Debug, thiserror::Error)]
pub enum MethodError {
    /// The calibration could not run (too few configurations for its model, degenerate data).
    #[error(transparent)]
    Calibration(Arc<CalibrationError>),
    /// The calibrated model's figures could not be computed.
    #[error("the calibrated model's figures: {0}")]
    Figures(AnalysisError),
}

impl From<CalibrationError> for MethodError {
    fn from(e: CalibrationError) -> Self {
        MethodError::Calibration(Arc::new(e))
    }
}

/// How one method fared: its calibration and the figures of its model, or why it could not run.
#[derive(Clone, Debug)]
pub struct MethodOutcome {
    pub entry: MethodEntry,
    pub outcome: Result<MethodRun, MethodError>,
}

/// A method's calibration and the figures of the model it reached, on the configurations it was
/// calibrated on (without its excluded ones).
#[derive(Clone, Debug)]
pub struct MethodRun {
    pub result: CalibrationResult,
    pub figures: Analysis,
}

impl MethodOutcome {
    /// The run, if the method ran.
    pub fn run(&self) -> Option<&MethodRun> {
        self.outcome.as_ref().ok()
    }

    /// The figures of its model, if it ran.
    pub fn figures(&self) -> Option<&Analysis> {
        self.run().map(|r| &r.figures)
    }
}

/// Several methods on one dataset, with the nominal model's figures (and, on simulated data, the true
/// parameters': the noise floor).
#[derive(Clone, Debug)]
pub struct Comparison {
    pub nominal: Analysis,
    /// The true model's figures, where it is known (simulation).
    pub truth: Option<Analysis>,
    pub methods: Vec<MethodOutcome>,
    /// Whether the run was cancelled before every method had run (those missing are not listed).
    pub cancelled: bool,
}

impl Comparison {
    /// The outcome of the method `key`.
    pub fn method(&self, key: &str) -> Option<&MethodOutcome> {
        self.methods.iter().find(|m| m.entry.key == key)
    }
}

/// What a comparison reports while it runs.
#[derive(Clone, Debug, PartialEq)]
pub enum ComparisonEvent {
    /// Method `index` of `total` starts.
    MethodStarted {
        index: usize,
        total: usize,
        key: &'static str,
    },
    /// Method `index` finished: `Ok` with its verification (or calibration) report, or why it failed.
    MethodFinished {
        index: usize,
        key: &'static str,
        converged: bool,
        error: Option<String>,
    },
}

/// What a comparison runs on.
#[derive(Clone, Copy, Debug)]
pub struct CompareInput<'a> {
    pub dataset: &'a Dataset,
    /// The model every method starts from.
    pub nominal: &'a DualArmModel,
    /// The true model, where it is known (simulation): its figures are the noise floor.
    pub truth: Option<&'a DualArmModel>,
    /// The robot's body frame from the left arm's model base (where the figures' rows are drawn,
    /// [`Analysis::compute`]).
    pub body_from_left_base: Isometry3<f64>,
}

/// Run `methods` on `input.dataset` one after another from `input.nominal`, each with its settings
/// on top of `common`. Every model's figures — the nominal, the true and each method's — are computed
/// without `common.exclude`, the configurations the methods are calibrated without. A method that
/// cannot run (too few configurations for its model, degenerate data) is recorded with its error and
/// the others go on; the figures of the nominal model failing (no pairs to evaluate) is the error of
/// the whole comparison. `cancel` stops the running method (its partial result is kept) and skips
/// the rest.
pub fn compare(
    input: &CompareInput<'_>,
    methods: &[MethodEntry],
    common: &CalibrationSettings,
    cancel: &Arc<AtomicBool>,
    progress: &mut dyn FnMut(ComparisonEvent),
) -> Result<Comparison, AnalysisError> {
    let figures = |model: &DualArmModel| {
        Analysis::compute_excluding(
            input.dataset,
            model,
            &input.body_from_left_base,
            &common.exclude,
        )
    };
    let nominal_figures = figures(input.nominal)?;
    let truth = input.truth.map(figures).transpose()?;
    let mut out = Vec::with_capacity(methods.len());
    let mut cancelled = false;
    for (index, entry) in methods.iter().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        progress(ComparisonEvent::MethodStarted {
            index,
            total: methods.len(),
            key: entry.key,
        });
        let outcome = run_method(input, entry, common, cancel);
        progress(ComparisonEvent::MethodFinished {
            index,
            key: entry.key,
            converged: outcome.as_ref().is_ok_and(|r| r.result.is_converged()),
            error: outcome.as_ref().err().map(ToString::to_string),
        });
        out.push(MethodOutcome {
            entry: *entry,
            outcome,
        });
    }
    Ok(Comparison {
        nominal: nominal_figures,
        truth,
        methods: out,
        cancelled: cancelled || cancel.load(Ordering::Relaxed),
    })
}

fn run_method(
    input: &CompareInput<'_>,
    entry: &MethodEntry,
    common: &CalibrationSettings,
    cancel: &Arc<AtomicBool>,
) -> Result<MethodRun, MethodError> {
    let result = Calibrator::new(input.dataset, input.nominal)
        .settings(entry.settings(common))
        .cancel(Arc::clone(cancel))
        .run()?;
    let figures = Analysis::compute_excluding(
        input.dataset,
        &result.calibrated,
        &input.body_from_left_base,
        &result.settings.exclude,
    )
    .map_err(MethodError::Figures)?;
    Ok(MethodRun { result, figures })
}

/// A box plot's figures of one set of samples: quartiles by linear interpolation, whiskers at the
/// farthest samples within 1.5 interquartile ranges of the box (Tukey), the extremes and the mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxStats {
    pub min: f64,
    pub whisker_lo: f64,
    pub q1: f64,
    pub median: f64,
    pub q3: f64,
    pub whisker_hi: f64,
    pub max: f64,
    pub mean: f64,
    /// Finite samples.
    pub n: usize,
}

impl BoxStats {
    /// The value range a box plot of `boxes` spans, from the lowest `min` to the highest `max`, widened
    /// by 5 % at both ends; `None` without a finite, non-empty range.
    pub fn padded_range<'a>(boxes: impl IntoIterator<Item = &'a BoxStats>) -> Option<(f64, f64)> {
        let (lo, hi) = boxes
            .into_iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| {
                (lo.min(b.min), hi.max(b.max))
            });
        (lo.is_finite() && hi > lo).then(|| {
            let pad = 0.05 * (hi - lo);
            (lo - pad, hi + pad)
        })
    }

    /// The box plot's strokes at `x` (plot units; the box 0.6 wide): the box, the median, the
    /// whiskers and their caps — what the report and the study figures draw.
    pub fn strokes(&self, x: f64) -> [Vec<(f64, f64)>; 6] {
        let b = self;
        [
            vec![
                (x - 0.3, b.q1),
                (x + 0.3, b.q1),
                (x + 0.3, b.q3),
                (x - 0.3, b.q3),
                (x - 0.3, b.q1),
            ],
            vec![(x - 0.3, b.median), (x + 0.3, b.median)],
            vec![(x, b.q3), (x, b.whisker_hi)],
            vec![(x, b.q1), (x, b.whisker_lo)],
            vec![(x - 0.15, b.whisker_hi), (x + 0.15, b.whisker_hi)],
            vec![(x - 0.15, b.whisker_lo), (x + 0.15, b.whisker_lo)],
        ]
    }

    /// The figures of `samples` (non-finite ones are left out); `None` without a finite sample.
    pub fn of(samples: &[f32]) -> Option<Self> {
        let mut v: Vec<f64> = samples
            .iter()
            .filter(|s| s.is_finite())
            .map(|&s| f64::from(s))
            .collect();
        if v.is_empty() {
            return None;
        }
        crate::sort::sort_f64(&mut v);
        let q = |p: f64| {
            let x = p * (v.len() - 1) as f64;
            let (i, f) = (x.floor() as usize, x.fract());
            let next = v[(i + 1).min(v.len() - 1)];
            v[i] + f * (next - v[i])
        };
        let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
        let reach = 1.5 * (q3 - q1);
        let whisker_lo = v.iter().copied().find(|&x| x >= q1 - reach).unwrap_or(q1);
        let whisker_hi = v
            .iter()
            .rev()
            .copied()
            .find(|&x| x <= q3 + reach)
            .unwrap_or(q3);
        Some(Self {
            min: v[0],
            whisker_lo,
            q1,
            median,
            q3,
            whisker_hi,
            max: v[v.len() - 1],
            mean: v.iter().sum::<f64>() / v.len() as f64,
            n: v.len(),
        })
    }
}

/// A histogram of `samples` of `indicator` over a range that shows every sample: `±extent` for
/// positions, `[0, extent]` for orientations.
pub fn histogram(indicator: Indicator, samples: &[f32], extent: f64, bins: usize) -> Histogram {
    let extent = extent.max(1e-12);
    if indicator.is_position() {
        Histogram::of(samples, -extent, extent, bins)
    } else {
        Histogram::of(samples, 0.0, extent, bins)
    }
}

/// The largest magnitude among `samples` (0 for none).
pub fn extent(samples: &[f32]) -> f64 {
    samples
        .iter()
        .filter(|s| s.is_finite())
        .fold(0.0, |m: f64, &s| m.max(f64::from(s.abs())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_keys_are_unique_and_found() {
        for (i, m) in METHODS.iter().enumerate() {
            assert!(METHODS[..i].iter().all(|o| o.key != m.key), "{}", m.key);
            assert_eq!(method(m.key).map(|e| e.key), Some(m.key));
        }
        assert!(method("no such method").is_none());
        // The paper's own method is in both comparisons, and there is something to compare it with.
        assert_eq!(method("minimax").map(|m| m.role), Some(Role::Both));
        assert!(METHODS.iter().filter(|m| m.role.compares_arms()).count() >= 2);
        // The paper's columns, in its order, then the others; the step-2 methods last.
        let keys: Vec<&str> = METHODS.iter().map(|m| m.key).collect();
        assert_eq!(
            keys,
            [
                "minimax",
                "distance-single",
                "pose",
                "position",
                "lsq",
                "base-distance",
                "base-absolute"
            ]
        );
    }

    #[test]
    fn each_entry_selects_its_method() {
        let common = CalibrationSettings {
            max_iterations: 7,
            ..CalibrationSettings::default()
        };
        let lsq = method("lsq").unwrap().settings(&common);
        assert_eq!(lsq.method, Method::LeastSquares);
        assert_eq!(lsq.base_method, BaseMethod::Minimax);
        assert_eq!(lsq.max_iterations, 7, "the common settings are kept");
        assert_eq!(
            method("minimax").unwrap().settings(&common).method,
            Method::Minimax
        );
        for m in METHODS.iter() {
            let s = m.settings(&common);
            // A step-1 method is compared on the paper's step 2, a step-2 method on its step 1.
            if m.role == Role::Arms {
                assert_eq!(s.base_method, BaseMethod::Minimax, "{}", m.key);
            }
            if m.role == Role::Base {
                assert_eq!(s.method, Method::Minimax, "{}", m.key);
            }
        }
    }

    #[test]
    fn box_stats_of_known_samples() {
        let samples: Vec<f32> = (1..=9).map(|k| k as f32).chain([100.0, f32::NAN]).collect();
        let b = BoxStats::of(&samples).unwrap();
        assert_eq!(b.n, 10);
        assert_eq!((b.min, b.max), (1.0, 100.0));
        // Sorted 1..9, 100: quartiles at positions 2.25, 4.5, 6.75.
        assert!((b.q1 - 3.25).abs() < 1e-12 && (b.median - 5.5).abs() < 1e-12);
        assert!((b.q3 - 7.75).abs() < 1e-12);
        // 100 lies beyond q3 + 1.5 IQR = 14.5: the upper whisker ends at 9.
        assert_eq!((b.whisker_lo, b.whisker_hi), (1.0, 9.0));
        assert!((b.mean - 14.5).abs() < 1e-12);
        assert!(BoxStats::of(&[f32::NAN]).is_none());
        assert!(BoxStats::of(&[]).is_none());
    }

    #[test]
    fn histograms_span_every_sample() {
        let samples = [-0.4f32, 0.1, 0.3];
        let e = extent(&samples);
        assert!((e - 0.4).abs() < 1e-6);
        let h = histogram(Indicator::CollaborativePosition, &samples, e, 4);
        assert!((h.lo + e).abs() < 1e-12 && (h.hi - e).abs() < 1e-12);
        let h = histogram(Indicator::CollaborativeOrientation, &samples[1..], 0.3, 3);
        assert_eq!(h.lo, 0.0);
        assert!((h.fractions.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
