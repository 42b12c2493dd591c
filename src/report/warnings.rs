//! What a reader of the report should distrust, computed from the data: a residual far above the
//! tracker's noise, unidentifiable or poorly determined parameters, a run that did not converge,
//! suspect configurations kept, and the like.

use super::{Report, SplitAccuracy, UncertaintySource};
use crate::dataset::Split;
use crate::params::Provenance;
use crate::side::{PerSide, Side};
use std::path::Path;

/// A calibrated residual above this many times the tracker's noise is reported: the geometric model
/// does not explain the data.
///
/// The noise figure is the tracker's MPE at the arm's mean measuring distance,
/// `mpe_um + mpe_um_per_m · L̄` (`[tracker]` of the dataset; the figure the screening uses). With the
/// convention of the simulator — a point's error has σ = MPE/2 per axis — a distance between two
/// points has an error of RMS MPE/√2 ≈ 0.71 MPE, so a model that explains the data leaves a residual
/// near 0.7–1 × the MPE; 3 × leaves room for a tracker somewhat worse than its specification.
pub const NOISE_RATIO_THRESHOLD: f64 = 3.0;

/// Above this condition number single parameters are poorly determined (docs/solver.md).
pub const POOR_CONDITION: f64 = 1e3;

/// How serious a warning is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WarningLevel {
    /// Distrust the result, or part of it, until it is explained.
    Warning,
    /// Worth knowing; not a fault.
    Note,
}

/// One line of the warnings section.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub level: WarningLevel,
    pub text: String,
}

fn warning(text: String) -> Warning {
    Warning {
        level: WarningLevel::Warning,
        text,
    }
}

fn note(text: String) -> Warning {
    Warning {
        level: WarningLevel::Note,
        text,
    }
}

/// One arm's calibrated residual against the tracker's noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseCheck {
    /// The split the residual is of: verification where there is one.
    pub split: Split,
    /// Relative positioning RMS of the calibrated model (the largest reflector's), mm.
    pub rms_mm: f64,
    /// The tracker's MPE at the arm's mean measuring distance, mm.
    pub mpe_mm: f64,
    /// `rms_mm / mpe_mm`.
    pub ratio: f64,
}

impl NoiseCheck {
    pub fn exceeded(&self) -> bool {
        self.ratio > NOISE_RATIO_THRESHOLD
    }
}

/// Each arm's calibrated residual (verification, else calibration) against its MPE.
pub fn noise_checks(
    accuracy: &[SplitAccuracy],
    mpe_mm: &PerSide<f64>,
) -> PerSide<Option<NoiseCheck>> {
    let chosen = accuracy
        .iter()
        .find(|a| a.split == Split::Ver)
        .or_else(|| accuracy.first());
    PerSide::from_fn(|side| {
        let a = chosen?;
        let rms_mm = a.after.relative(side)?.pos_rms_mm;
        let mpe = mpe_mm[side];
        (mpe > 0.0 && rms_mm.is_finite()).then_some(NoiseCheck {
            split: a.split,
            rms_mm,
            mpe_mm: mpe,
            ratio: rms_mm / mpe,
        })
    })
}

/// The warnings and notes of a report (every other field filled in).
pub fn of(report: &Report) -> Vec<Warning> {
    let mut out = Vec::new();
    noise_warnings(report, &mut out);
    convergence_warnings(report, &mut out);
    for side in Side::BOTH {
        identifiability_warnings(report, side, &mut out);
    }
    screening_warnings(report, &mut out);
    if let Some(other) = other_dataset(report.provenance.as_ref(), &report.dataset.dir) {
        out.push(warning(format!(
            "the parameters were identified from another dataset ({other}) than the one this \
             report evaluates them on ({})",
            report.dataset.dir.display()
        )));
    }
    crate::sort::sort_by_key(&mut out, |w| w.level == WarningLevel::Note);
    out
}

fn noise_warnings(report: &Report, out: &mut Vec<Warning>) {
    if !report.accuracy.iter().any(|a| a.split == Split::Ver) {
        out.push(warning(
            "no verification configurations (at least two per arm): every accuracy figure is on \
             the configurations the parameters were fitted to, which flatter the model"
                .into(),
        ));
    }
    for (side, check) in report.noise.iter() {
        let Some(c) = check else { continue };
        if !c.exceeded() {
            continue;
        }
        let what = if c.split == Split::Ver {
            "verification"
        } else {
            "calibration"
        };
        out.push(warning(format!(
            "{side} arm: the {what} residual (RMS) is {:.1}× the tracker's noise (MPE): the \
             geometric model does not explain the data ({:.4} mm against an MPE of {:.4} mm at \
             the arm's mean measuring distance; reported above {NOISE_RATIO_THRESHOLD}×). \
             Unmodelled errors — joint compliance, gear errors, temperature — or bad data remain, \
             and the parameters' σ grow with them",
            c.ratio, c.rms_mm, c.mpe_mm
        )));
    }
}

fn convergence_warnings(report: &Report, out: &mut Vec<Warning>) {
    let m = &report.method;
    if !m.converged {
        let how: Vec<String> = m
            .stages
            .iter()
            .flatten()
            .filter(|s| !s.termination.is_converged())
            .map(|s| format!("{}: {}", s.stage, s.termination))
            .collect();
        out.push(warning(format!(
            "the calibration did not converge{}: the parameters are those the solver reached",
            if how.is_empty() {
                String::new()
            } else {
                format!(" ({})", how.join("; "))
            }
        )));
    }
    if m.stages.is_none() {
        out.push(note(
            "the parameter file records no termination: whether the solver converged is unknown"
                .into(),
        ));
    }
    if let Err(why) = &m.record {
        out.push(note(format!(
            "{why}: the method and its settings are unknown"
        )));
    }
}

fn identifiability_warnings(report: &Report, side: Side, out: &mut Vec<Warning>) {
    let arm = &report.arms[side];
    if !arm.fixed.is_empty() {
        let names: Vec<&str> = arm.fixed.iter().map(|f| f.name.as_str()).collect();
        out.push(note(format!(
            "{side} arm: {} parameter(s) cannot be identified from this data and were held at \
             their nominal values: {} (section Identifiability says why)",
            names.len(),
            names.join(", ")
        )));
    }
    let condition = arm
        .uncertainty
        .as_ref()
        .map(|u| u.condition)
        .or_else(|| arm.conditioning.as_ref().and_then(|c| c.condition_after));
    if let Some(c) = condition.filter(|&c| c > POOR_CONDITION || c.is_nan()) {
        out.push(warning(format!(
            "{side} arm: condition number {c:.3e} (above {POOR_CONDITION:.0e}): single parameters \
             are poorly determined even where the accuracy is good; the correlated pairs say \
             which trade off"
        )));
    }
    if let Some(u) = &arm.uncertainty
        && !u.correlations.is_empty()
    {
        out.push(note(format!(
            "{side} arm: {} pair(s) of parameters correlate at ±{} or beyond: the data hardly \
             tell them apart (section Parameters)",
            u.correlations.len(),
            crate::solver::uncertainty::REPORTED_CORRELATION
        )));
    }
    if let UncertaintySource::NotAvailable(why) = &arm.uncertainty_source {
        out.push(note(format!("{side} arm: no standard deviations: {why}")));
    }
}

fn screening_warnings(report: &Report, out: &mut Vec<Warning>) {
    let kept = &report.screening.kept_suspects;
    if !kept.is_empty() {
        let ids: Vec<String> = kept
            .iter()
            .take(10)
            .map(|f| format!("{} `{}`", f.config.side, f.id))
            .collect();
        out.push(warning(format!(
            "{} suspect configuration(s) were kept in the calibration: {}{}; the minimax fit is \
             steered by its worst point — look at them (section Screening), then calibrate with \
             --exclude or --auto-exclude",
            kept.len(),
            ids.join(", "),
            if kept.len() > ids.len() { ", …" } else { "" }
        )));
    }
    for f in &report.screening.record.findings {
        out.push(warning(f.message.clone()));
    }
}

/// Whether the parameter file says it was identified from another dataset than `dir`.
fn other_dataset(provenance: Option<&Provenance>, dir: &Path) -> Option<String> {
    let recorded = provenance?.dataset.as_ref()?;
    let same = match (Path::new(recorded).canonicalize(), dir.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => Path::new(recorded) == dir,
    };
    (!same).then(|| recorded.clone())
}
