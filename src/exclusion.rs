//! Leaving suspect configurations out: the screening of a calibration's result, and the
//! `--auto-exclude` loop (screen, fit, screen again). This module sits above both the screening
//! ([`crate::quality`], pure: it never fits) and the solver ([`crate::solver`]); the command line's
//! `--auto-exclude` and the workbench's Auto-exclude both run [`auto_exclude`].

use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::quality::{self, Flag, ScreenSettings, Screening};
use crate::solver::{CalibrationError, CalibrationResult, CalibrationSettings, Calibrator};

/// Screen a dataset with a calibration's result: [`quality::screen_model`] of its calibrated model
/// (and the nominal one it started from).
pub fn screen_result(
    dataset: &Dataset,
    result: &CalibrationResult,
    settings: &ScreenSettings,
) -> Screening {
    quality::screen_model(dataset, &result.nominal, &result.calibrated, settings)
}

/// [`screen_result`], taking the arms' part from `arms` (computed beside step 2 with the arms of
/// step 1: [`quality::screen_arms`]) where it was made with the result's arms; the whole screening
/// otherwise.
pub fn screen_result_reusing(
    dataset: &Dataset,
    result: &CalibrationResult,
    settings: &ScreenSettings,
    arms: Option<quality::ArmsScreening>,
) -> Screening {
    match arms.filter(|a| a.is_for(&result.calibrated)) {
        Some(arms) => arms.finish(dataset, &result.nominal, &result.calibrated),
        None => screen_result(dataset, result, settings),
    }
}

/// What [`auto_exclude`] did.
#[derive(Clone, Debug)]
pub struct AutoExclusion {
    /// The configurations left out, with the flag that removed each (most severe), in order.
    pub excluded: Vec<Flag>,
    /// The calibration without them.
    pub result: CalibrationResult,
    /// The screening of that calibration (flags of the excluded configurations included).
    pub screening: Screening,
    /// Fits run (1 when nothing was suspect after the first).
    pub rounds: usize,
    /// Why the rule stopped before every suspect was excluded (too many suspects in an arm), if it
    /// did.
    pub stopped: Option<String>,
}

/// The `--auto-exclude` rule: screen with the nominal model and leave the flagged configurations out;
/// fit; screen with the fitted model and leave the newly flagged out; repeat until nothing new is
/// flagged or [`ScreenSettings::max_rounds`] fits have run. At most
/// [`ScreenSettings::max_excluded_fraction`] of an arm's configurations are excluded: when a round
/// would exclude more, it excludes none of its new suspects and the rule stops and says so (a moved
/// tracker or a wrong robot is not cured by exclusion) — [`quality::exclusion_round`].
/// `settings.exclude` (the user's own exclusions) is kept.
///
/// `nominal_screening` is the screening of `nominal` on `dataset` when the caller has it already
/// (the load pipeline's, [`crate::workspace::Workspace::screening`]); `None` screens here.
pub fn auto_exclude(
    dataset: &Dataset,
    nominal: &DualArmModel,
    nominal_screening: Option<&Screening>,
    settings: &CalibrationSettings,
    screen_settings: &ScreenSettings,
) -> Result<AutoExclusion, CalibrationError> {
    let mut excluded: Vec<Flag> = Vec::new();
    let mut settings = settings.clone();
    let mut round = |screening: &Screening, settings: &mut CalibrationSettings| {
        take(dataset, screening, settings, &mut excluded, screen_settings)
    };
    let mut stopped = match nominal_screening {
        Some(s) => round(s, &mut settings),
        None => round(
            &quality::screen(dataset, nominal, screen_settings),
            &mut settings,
        ),
    };
    let mut rounds = 0;
    loop {
        let result = Calibrator::new(dataset, nominal)
            .settings(settings.clone())
            .run()?;
        rounds += 1;
        let screening = screen_result(dataset, &result, screen_settings);
        let before = settings.exclude.len();
        if stopped.is_none() && rounds < screen_settings.max_rounds {
            stopped = round(&screening, &mut settings);
        }
        if settings.exclude.len() == before {
            crate::sort::sort_by_key(&mut excluded, |f| f.config);
            return Ok(AutoExclusion {
                excluded,
                result,
                screening,
                rounds,
                stopped,
            });
        }
    }
}

/// One round of the rule: its new suspects added to the exclusions (and their flags to `excluded`);
/// why it stopped short, if it did.
fn take(
    dataset: &Dataset,
    screening: &Screening,
    settings: &mut CalibrationSettings,
    excluded: &mut Vec<Flag>,
    screen_settings: &ScreenSettings,
) -> Option<String> {
    let round = quality::exclusion_round(
        dataset,
        screening,
        &settings.exclude,
        excluded,
        screen_settings,
    );
    for f in round.new {
        settings.exclude.push(f.config);
        excluded.push(f);
    }
    round.stopped
}
