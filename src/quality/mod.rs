//! Screening the measurements for suspect configurations, before and after a fit, and leaving them
//! out.
//!
//! The minimax objective is, by construction, steered by its single worst point, so one misread
//! reflector can spoil a calibration. Three kinds of evidence, each per configuration (arm and row):
//!
//! - **the reflector triangle** ([`triangle`]): the three reflectors are rigid on the flange, so every
//!   configuration's measured triangle must have the same side lengths, whatever the robot model.
//!   A side that differs from the arm's median by more than [`ScreenSettings::triangle_k`] robust
//!   standard deviations (never less than the tracker's noise) flags the configuration; the two
//!   deviating sides name the misread reflector, and a permutation of the labels that restores the
//!   triangle says the labels were swapped in that row.
//! - **the distances to the other configurations** ([`residual`]): given a model (the nominal one before
//!   fitting, the calibrated one after), each configuration's reflector `k` gets a robust (Huber)
//!   estimate of the displacement `e` that explains its distance errors to all the other
//!   configurations, `Δd_ij ≈ w_ij · e_i` (the tracker-frame misread, mm). `|e|` beyond
//!   [`ScreenSettings::residual_k`] robust standard deviations of the arm's `|e|` flags it. For a flagged
//!   row, swapped labels, two swapped joint columns and "a row of the other arm" are tried, and one that
//!   makes the row fit is named.
//! - **whole-file checks** ([`frames`]): a nominal model that disagrees with the data by more than a
//!   robot can be off (joint order, units, wrong robot: an error), the two arms not in one tracker
//!   frame (collaborative errors far above relative ones before fitting, or a base far from the
//!   robot description's after), and a tracker that moved within one arm's measurements (distances
//!   across one row far worse than on either side).
//!
//! [`screen`] runs them before fitting, [`screen_model`] after (with the fitted model); one round of
//! the documented exclusion rule (`docs/reliability.md`) is [`exclusion_round`]. The screening is pure:
//! it never runs the solver; the loop that fits, screens and fits again is
//! [`crate::exclusion::auto_exclude`], above both. Configurations are left out of a calibration through
//! [`crate::solver::CalibrationSettings::exclude`], and out of accuracy figures through
//! [`crate::dataset::Dataset::excluding`].

pub mod frames;
pub mod residual;
pub mod triangle;

use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::par::prelude::*;
use crate::side::{ConfigId, PerSide, Side};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What makes a configuration suspect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FlagKind {
    /// Its reflector triangle differs from the rigid triangle of the other configurations: a
    /// reflector misread, re-seated or occluded and re-measured.
    Triangle,
    /// Its reflector labels look permuted (the triangle, or the distances, fit after relabelling).
    LabelsSwapped,
    /// Its distances to the other configurations do not fit the model.
    Residual,
    /// Two of its joint columns look swapped (the distances fit after swapping them back).
    JointsSwapped,
    /// It fits the other arm's measurements: a row of the other arm's file.
    OtherArm,
}

impl FlagKind {
    /// A short name for tables.
    pub fn label(self) -> &'static str {
        match self {
            FlagKind::Triangle => "triangle",
            FlagKind::LabelsSwapped => "labels swapped",
            FlagKind::Residual => "residual",
            FlagKind::JointsSwapped => "joints swapped",
            FlagKind::OtherArm => "other arm",
        }
    }
}

/// A suspect configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flag {
    pub config: ConfigId,
    /// The row's id and CSV line.
    pub id: String,
    pub line: usize,
    pub split: Split,
    pub kind: FlagKind,
    /// How large the problem is, mm: the triangle's largest side deviation, or the largest estimated
    /// reflector displacement.
    pub size_mm: f64,
    /// The threshold `size_mm` exceeded, mm.
    pub threshold_mm: f64,
    /// The reflector implicated (0 = a, 1 = b, 2 = c), when one is.
    pub reflector: Option<usize>,
    /// One sentence: what was found and what it suggests.
    pub reason: String,
}

impl Flag {
    /// How far beyond its threshold (≥ 1): orders flags by severity.
    pub fn severity(&self) -> f64 {
        self.size_mm / self.threshold_mm.max(1e-12)
    }
}

impl std::fmt::Display for Flag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} arm `{}` (line {}, {}): {}",
            self.config.side,
            self.id,
            self.line,
            self.split.name(),
            self.reason
        )
    }
}

/// How serious a whole-file finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Severity {
    /// The data may still be usable; the user should know.
    Warning,
    /// The data cannot give a meaningful calibration as they are; the command line refuses.
    Error,
}

/// A finding about a whole file or arm, not one configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    pub severity: Severity,
    /// The arm concerned, if one.
    pub side: Option<Side>,
    pub message: String,
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Thresholds of the screening. The defaults are those of `docs/reliability.md`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScreenSettings {
    /// A triangle side deviating by more than this many robust standard deviations flags the
    /// configuration (the standard deviation is never taken below the tracker's side noise).
    pub triangle_k: f64,
    /// An estimated reflector displacement beyond this many robust standard deviations of the arm's
    /// displacements flags the configuration.
    pub residual_k: f64,
    /// Neither threshold is taken below this many times the tracker's MPE at the measuring distance.
    pub mpe_floor: f64,
    /// Largest fraction of an arm's configurations [`crate::exclusion::auto_exclude`] removes; beyond
    /// it the data are not "a few outliers" and need a look instead.
    pub max_excluded_fraction: f64,
    /// Rounds of fit and screen in [`crate::exclusion::auto_exclude`].
    pub max_rounds: usize,
}

impl Default for ScreenSettings {
    fn default() -> Self {
        Self {
            triangle_k: 6.0,
            residual_k: 5.0,
            mpe_floor: 3.0,
            max_excluded_fraction: 0.1,
            max_rounds: 3,
        }
    }
}

/// The outcome of a screening.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Screening {
    /// Suspect configurations (a configuration may carry several flags), arm by arm, in row order.
    pub flags: Vec<Flag>,
    /// Whole-file findings.
    pub findings: Vec<Finding>,
}

impl Screening {
    /// The suspect configurations, each once, in order.
    pub fn suspects(&self) -> Vec<ConfigId> {
        let mut v: Vec<ConfigId> = self.flags.iter().map(|f| f.config).collect();
        crate::sort::sort(&mut v);
        v.dedup();
        v
    }

    /// The flags of each suspect configuration, most severe first.
    pub fn by_config(&self) -> BTreeMap<ConfigId, Vec<&Flag>> {
        let mut map: BTreeMap<ConfigId, Vec<&Flag>> = BTreeMap::new();
        for f in &self.flags {
            map.entry(f.config).or_default().push(f);
        }
        for flags in map.values_mut() {
            crate::sort::sort_by(flags, |a, b| b.severity().total_cmp(&a.severity()));
        }
        map
    }

    /// The most severe flag of each suspect configuration.
    pub fn worst_per_config(&self) -> Vec<&Flag> {
        self.by_config().into_values().map(|v| v[0]).collect()
    }

    /// The rows of `side` that carry a flag.
    pub fn suspect_rows(&self, side: Side) -> Vec<usize> {
        self.suspects()
            .into_iter()
            .filter(|c| c.side == side)
            .map(|c| c.index)
            .collect()
    }

    /// Is there a finding of [`Severity::Error`]?
    pub fn has_errors(&self) -> bool {
        self.errors().next().is_some()
    }

    /// The findings of [`Severity::Error`]: data that cannot give a meaningful calibration as they
    /// are; the command line refuses to go on with them.
    pub fn errors(&self) -> impl Iterator<Item = &Finding> {
        self.findings
            .iter()
            .filter(|f| f.severity == Severity::Error)
    }

    fn sort(&mut self) {
        crate::sort::sort_by_key(&mut self.flags, |f| (f.config, f.kind as u8));
    }
}

/// Visit a regular sample of at most about `most` of the pairs `(i, j)` of `n_a` configurations with
/// `n_b` others (`same`: one set, pairs `i < j`): every `stride`-th pair in row order, `stride` the
/// smallest that keeps the sample within `most`. Jumps from sampled pair to sampled pair (no loop
/// over the pairs left out).
pub(crate) fn sampled_pairs(
    n_a: usize,
    n_b: usize,
    same: bool,
    most: usize,
    mut visit: impl FnMut(usize, usize),
) {
    let total = if same {
        n_a * n_a.saturating_sub(1) / 2
    } else {
        n_a * n_b
    };
    let stride = total.div_ceil(most.max(1)).max(1);
    // `idx`: the running index of row i's first pair.
    let mut idx = 0usize;
    for i in 0..n_a {
        let first_j = if same { i + 1 } else { 0 };
        let row = n_b.saturating_sub(first_j);
        let end = idx + row;
        let mut t = idx.next_multiple_of(stride);
        while t < end {
            visit(i, first_j + (t - idx));
            t += stride;
        }
        idx = end;
    }
}

/// The tracker's MPE at the arm's mean measuring distance, mm.
pub(crate) fn mpe_mm(dataset: &Dataset, side: Side) -> f64 {
    let ms = &dataset.arm(side).measurements;
    let n = (3 * ms.len()).max(1) as f64;
    let mean_m = ms
        .iter()
        .flat_map(|m| m.tracker_points_mm.iter())
        .map(|p| p.norm())
        .sum::<f64>()
        / n
        / 1000.0;
    (dataset.tracker.mpe_um + dataset.tracker.mpe_um_per_m * mean_m) / 1000.0
}

/// Screen a dataset before fitting, with the nominal model: triangle flags, gross residual flags
/// (the nominal model is millimetres off, so only gross errors show), and the whole-file checks.
pub fn screen(dataset: &Dataset, nominal: &DualArmModel, settings: &ScreenSettings) -> Screening {
    let mut out = Screening::default();
    let fits = residual::fits(dataset, nominal);
    let (flags, nominal_findings) = crate::par::join(
        || {
            per_measured_side(dataset, |side| {
                let mut flags = triangle::flags(dataset, side, settings);
                flags.extend(residual::flags_with(
                    dataset, nominal, &fits, side, settings,
                ));
                flags
            })
        },
        || frames::nominal_findings(dataset, nominal),
    );
    out.flags.extend(flags.into_iter().flatten());
    out.findings.extend(nominal_findings);
    let moved = per_measured_side(dataset, |side| {
        frames::tracker_moved_with(dataset, &fits[side], &out.suspect_rows(side), settings)
    });
    out.findings.extend(moved.into_iter().flatten());
    out.sort();
    out
}

/// `f` of each measured side, the sides side by side on the work pool, in side order.
fn per_measured_side<T: Send>(dataset: &Dataset, f: impl Fn(Side) -> T + Sync + Send) -> Vec<T> {
    dataset.measured_sides().into_par_iter().map(f).collect()
}

/// Screen a dataset with a fitted `model` (and the `nominal` one it started from): triangle and
/// residual flags, a tracker that moved within an arm, and a right-arm base far from the robot
/// description's (the arms not in one tracker frame). The screening of a calibration's result is
/// [`crate::exclusion::screen_result`].
pub fn screen_model(
    dataset: &Dataset,
    nominal: &DualArmModel,
    model: &DualArmModel,
    settings: &ScreenSettings,
) -> Screening {
    screen_arms(dataset, model, settings).finish(dataset, nominal, model)
}

/// The part of [`screen_model`] that depends on the arms' models alone (not on the base): each
/// measured arm's triangle and residual flags and its moved-tracker findings — what can run as soon
/// as the arms are fitted, beside step 2.
pub fn screen_arms(
    dataset: &Dataset,
    model: &DualArmModel,
    settings: &ScreenSettings,
) -> ArmsScreening {
    let fits = residual::fits(dataset, model);
    let per_side = per_measured_side(dataset, |side| {
        let mut side_out = Screening::default();
        side_out
            .flags
            .extend(triangle::flags(dataset, side, settings));
        side_out
            .flags
            .extend(residual::flags_with(dataset, model, &fits, side, settings));
        let suspects = side_out.suspect_rows(side);
        side_out.findings.extend(frames::tracker_moved_with(
            dataset,
            &fits[side],
            &suspects,
            settings,
        ));
        side_out
    });
    ArmsScreening {
        arms: PerSide::from_fn(|side| model.arm(side).clone()),
        per_side,
    }
}

/// The arms' part of a screening ([`screen_arms`]) and the arm models it was made with.
pub struct ArmsScreening {
    arms: PerSide<crate::kinematics::ArmModel>,
    per_side: Vec<Screening>,
}

impl ArmsScreening {
    /// Whether this is the arms' screening of `model` (its arms are the ones it was made with).
    pub fn is_for(&self, model: &DualArmModel) -> bool {
        Side::BOTH
            .into_iter()
            .all(|side| self.arms[side] == *model.arm(side))
    }

    /// The whole screening of `model` ([`screen_model`]): the arms' part and the base's finding.
    pub fn finish(
        self,
        dataset: &Dataset,
        nominal: &DualArmModel,
        model: &DualArmModel,
    ) -> Screening {
        let mut out = Screening::default();
        for side_out in self.per_side {
            out.flags.extend(side_out.flags);
            out.findings.extend(side_out.findings);
        }
        if dataset.one_tracker_frame() {
            out.findings.extend(frames::base_deviation(nominal, model));
        }
        out.sort();
        out
    }
}

/// One round of the `--auto-exclude` rule ([`crate::exclusion::auto_exclude`]) on a screening.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExclusionRound {
    /// The newly suspect configurations to leave out, each with its most severe flag: per arm, most
    /// severe first.
    pub new: Vec<Flag>,
    /// Why the round left an arm's new suspects in (too many of them), if it did.
    pub stopped: Option<String>,
}

/// The configurations of `screening` to leave out next: the suspects not already in `exclude`, arm by
/// arm, unless they would take the configurations excluded automatically (`auto_excluded`, the
/// flags of earlier rounds) beyond [`ScreenSettings::max_excluded_fraction`] of the arm — then none of
/// that arm's, and the round says why. Pure: the loop that fits again lives above the solver.
pub fn exclusion_round(
    dataset: &Dataset,
    screening: &Screening,
    exclude: &[ConfigId],
    auto_excluded: &[Flag],
    settings: &ScreenSettings,
) -> ExclusionRound {
    let mut round = ExclusionRound::default();
    for side in Side::BOTH {
        let n = dataset.arm(side).measurements.len();
        let cap = (settings.max_excluded_fraction * n as f64).floor() as usize;
        let mut new: Vec<&Flag> = screening
            .worst_per_config()
            .into_iter()
            .filter(|f| f.config.side == side && !exclude.contains(&f.config))
            .collect();
        crate::sort::sort_by(&mut new, |a, b| b.severity().total_cmp(&a.severity()));
        let already = auto_excluded
            .iter()
            .filter(|f| f.config.side == side)
            .count();
        let room = cap.saturating_sub(already);
        if new.len() > room {
            round.stopped = Some(format!(
                "{side} arm: {} more configurations are suspect, but at most {:.0}% of an arm's {n} \
                 configurations ({cap}) are excluded automatically, so none of them was; so many \
                 suspects suggest a problem with the whole measurement (a moved tracker, a wrong robot \
                 description, wrong units) rather than a few outliers: look at the flags",
                new.len(),
                100.0 * settings.max_excluded_fraction
            ));
            continue;
        }
        round.new.extend(new.into_iter().cloned());
    }
    round
}

/// The `quality` record of a parameter file: the flags of the final screening and the configurations
/// left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QualityRecord {
    pub flags: Vec<Flag>,
    pub findings: Vec<Finding>,
    /// `arm`, `id` and why, for every configuration left out.
    pub excluded: Vec<ExcludedRecord>,
}

/// One excluded configuration in a [`QualityRecord`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExcludedRecord {
    pub arm: Side,
    pub id: String,
    /// The flag's reason, or `"excluded by the user"`.
    pub reason: String,
}

impl QualityRecord {
    /// The record of a screening and the exclusions in `exclude` (reasons from the screening's flags).
    pub fn new(dataset: &Dataset, screening: &Screening, exclude: &[ConfigId]) -> Self {
        let by_config = screening.by_config();
        let excluded = exclude
            .iter()
            .filter_map(|c| {
                let m = dataset.arm(c.side).measurements.get(c.index)?;
                Some(ExcludedRecord {
                    arm: c.side,
                    id: m.id.clone(),
                    reason: by_config
                        .get(c)
                        .map_or_else(|| "excluded by the user".into(), |f| f[0].reason.clone()),
                })
            })
            .collect();
        Self {
            flags: screening.flags.clone(),
            findings: screening.findings.clone(),
            excluded,
        }
    }
}
