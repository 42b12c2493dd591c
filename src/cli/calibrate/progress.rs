//! `dualcal calibrate`'s progress lines on standard error, an [`Observer`] of the solver: a line as
//! each stage starts and ends, one per outer iteration with each objective by the user's reflector
//! name.

use crate::solver::{CalibrationRun, IterationRecord, Observer, Stage, StageSummary};

/// Prints the progress lines; `reflectors` are the dataset's reflector names (`F_<name>` per
/// objective; a, b, c, … by position where the count differs).
pub(super) struct ProgressLines<'a> {
    pub(super) reflectors: &'a [String],
}

impl Observer for ProgressLines<'_> {
    fn stage_started(&mut self, stage: Stage, n_configs: usize, n_pairs: usize) {
        eprintln!("{stage}: {n_configs} configurations, {n_pairs} pairs per reflector")
    }

    fn iteration(&mut self, r: &IterationRecord, _run: &CalibrationRun) {
        let lambda = match &r.lambda {
            Some(l) => format!(
                "λ {}",
                l.iter()
                    .map(|x| format!("{x:.2}"))
                    .collect::<Vec<_>>()
                    .join("/")
            ),
            None => format!("{:14}", "λ –"),
        };
        // One column per reflector, by the user's name.
        let defaults;
        let names: &[String] = if self.reflectors.len() == r.f_mm2.len() {
            self.reflectors
        } else {
            defaults = crate::kinematics::default_reflector_names(r.f_mm2.len());
            &defaults
        };
        let f = names
            .iter()
            .zip(&r.f_mm2)
            .map(|(n, v)| format!("F_{n} {v:>12.4}"))
            .collect::<Vec<_>>()
            .join("  ");
        eprintln!(
            "  {:>3}  ψ {:>14.6} mm²   {f}   {lambda}   step {:>9.2e}   KKT {:>9.2e}   {:>7.3} s",
            r.iteration, r.psi_mm2, r.step_norm, r.optimality_residual, r.elapsed_secs
        )
    }

    fn stage_finished(&mut self, summary: &StageSummary, _run: &CalibrationRun) {
        eprintln!("{}: {}", summary.stage, summary.termination)
    }
}
