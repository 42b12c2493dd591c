//! `dualcal calibrate`'s fit: the calibration with `--auto-exclude` or with progress lines, and what
//! runs beside it (the arms' screening and, where the run kept no pair sums, each arm's uncertainty
//! beside step 2; the screening of the result, its uncertainty and the caller's tables side by side).

use super::args::CalibrateArgs;
use super::progress::ProgressLines;
use super::summary::print_flags;
use crate::dataset::Dataset;
use crate::quality;
use crate::side::{PerSide, Side};
use crate::solver::{CalibrationResult, CalibrationSettings, Calibrator};
use anyhow::Result;

/// Calibrate, with `--auto-exclude` or with progress lines: the result, its screening, its uncertainty
/// and what `tables` makes of it (computed beside the screening).
pub(super) fn fit_and_screen<T: Send>(
    a: &CalibrateArgs,
    ds: &Dataset,
    nominal: &crate::kinematics::DualArmModel,
    settings: CalibrationSettings,
    before: &quality::Screening,
    tables: impl FnOnce(&CalibrationResult) -> T + Send,
) -> Result<(CalibrationResult, quality::Screening, Uncertainties, T)> {
    let screen_settings = quality::ScreenSettings::default();
    Ok(if a.auto_exclude {
        if !a.quiet {
            eprintln!(
                "--auto-exclude: screening, fitting and screening again (progress not shown)"
            );
        }
        let auto =
            crate::exclusion::auto_exclude(ds, nominal, Some(before), &settings, &screen_settings)?;
        outln!(
            "--auto-exclude: {} configuration(s) left out after {} fit(s){}",
            auto.excluded.len(),
            auto.rounds,
            if auto.excluded.is_empty() { "" } else { ":" }
        );
        for f in &auto.excluded {
            outln!("  {f}");
        }
        if let Some(why) = &auto.stopped {
            eprintln!("warning: --auto-exclude stopped: {why}");
        }
        let (uncertainty, tables) = crate::par::join(
            || crate::solver::uncertainty::for_result(ds, &auto.result),
            || tables(&auto.result),
        );
        (auto.result, auto.screening, uncertainty, tables)
    } else {
        print_flags(
            "Suspect configurations before fitting (nominal model)",
            before,
            &settings.exclude,
        );
        let mut progress = ProgressLines {
            reflectors: &ds.reflector_names,
        };
        // The arms' screening, and each arm's uncertainty where the run kept no pair sums for it, are
        // computed beside step 2 (which does not change the arms), taken below where the result's
        // arms are those they were computed for.
        let early = std::sync::Mutex::new(PerSide::default());
        let arms_screened = std::sync::Mutex::new(None);
        let result = crate::par::scope(|scope| {
            let mut beside = BesideStep2 {
                dataset: ds,
                settings: settings.clone(),
                screen_settings: &screen_settings,
                scope,
                early: &early,
                arms_screened: &arms_screened,
            };
            let calibrator = Calibrator::new(ds, nominal).settings(settings);
            let calibrator = if a.quiet {
                calibrator
            } else {
                calibrator.observer(&mut progress)
            };
            calibrator.observer(&mut beside).run()
        })?;
        let early = early.into_inner().unwrap_or_default();
        let arms_screened = arms_screened.into_inner().unwrap_or_default();
        // The screening of the result, its uncertainty (both mostly done beside step 2) and the
        // tables need nothing of each other: side by side.
        let ((after, uncertainty), tables) = crate::par::join(
            || {
                (
                    crate::exclusion::screen_result_reusing(
                        ds,
                        &result,
                        &screen_settings,
                        arms_screened,
                    ),
                    crate::solver::uncertainty::for_result_reusing(ds, &result, early),
                )
            },
            || tables(&result),
        );
        (result, after, uncertainty, tables)
    })
}

/// Starts the arms' part of the result's screening and (where the run kept no pair sums for the
/// arm) each arm's uncertainty on the work pool when step 1 has ended (the right arm's stage is
/// step 1's last), so that they run beside step 2 (which does not change the arms); each is taken
/// afterwards where the result's arms are those it was computed for.
struct BesideStep2<'s, 'd> {
    dataset: &'d Dataset,
    settings: CalibrationSettings,
    screen_settings: &'d quality::ScreenSettings,
    scope: &'s crate::par::Scope<'d>,
    early: &'d std::sync::Mutex<PerSide<Option<crate::solver::uncertainty::EarlyArmUncertainty>>>,
    arms_screened: &'d std::sync::Mutex<Option<quality::ArmsScreening>>,
}

impl crate::solver::Observer for BesideStep2<'_, '_> {
    fn stage_finished(
        &mut self,
        summary: &crate::solver::StageSummary,
        run: &crate::solver::CalibrationRun,
    ) {
        if summary.stage != crate::solver::Stage::Arm(Side::Right)
            || summary.termination == crate::solver::Termination::Cancelled
        {
            return;
        }
        let model = run.current_model();
        let (dataset, screen_settings, arms_screened) =
            (self.dataset, self.screen_settings, self.arms_screened);
        let screened_model = model.clone();
        self.scope.spawn(move |_| {
            let screened = quality::screen_arms(dataset, &screened_model, screen_settings);
            if let Ok(mut slot) = arms_screened.lock() {
                *slot = Some(screened);
            }
        });
        // The absolute methods' uncertainty comes from their own problem (`uncertainty::for_result`).
        if self.settings.method.is_absolute() {
            return;
        }
        for side in Side::BOTH {
            // An arm whose pair sums the run kept gets its σ from them at the end (`for_result`):
            // nothing to start here.
            let Some(report) = run
                .identifiability(side)
                .filter(|_| run.pair_sums(side).is_none())
            else {
                continue;
            };
            let (dataset, settings, early) = (self.dataset, self.settings.clone(), self.early);
            let (arm, free) = (model.arm(side).clone(), report.free.clone());
            self.scope.spawn(move |_| {
                let value = crate::solver::uncertainty::EarlyArmUncertainty::new(
                    dataset, &settings, side, arm, free,
                );
                if let Ok(mut early) = early.lock() {
                    early[side] = Some(value);
                }
            });
        }
    }
}

/// Each arm's uncertainty of its step-1 parameters (`None`: not covered for its method).
pub(super) type Uncertainties =
    crate::side::PerSide<Option<crate::solver::uncertainty::ArmUncertainty>>;
