//! `dualcal calibrate`: load and screen the dataset, settle the settings, fit, print the summary,
//! write the parameter file (and the exports asked for); a run that did not converge ends with its
//! own exit status.

use super::args::CalibrateArgs;
use super::fit::fit_and_screen;
use super::outputs::{refuse_overwrites, write_robot_exports};
use super::settings::{add_exclusions, model_settings, settings_from};
use super::summary::{
    comparison_table, print_flags, print_identifiability, print_uncertainty, warn_suspects_kept,
};
use super::timings;
use crate::cli::common::{describe_robot, load_workspace};
use crate::params::{ParamsFile, StatisticsRecord};
use crate::quality;
use crate::solver::CalibrationResult;
use crate::workspace::Workspace;
use anyhow::{Result, bail};

/// A calibration that ran but did not converge (a stage hit the iteration limit, stalled or was
/// cancelled). The command exits with [`NotConverged::EXIT_CODE`] after printing its summary and
/// writing the requested files, marked `"converged": false`.
#[derive(Debug, thiserror::Error)]
#[error("the calibration did not converge ({0}); the parameters written are those reached")]
pub struct NotConverged(pub String);

impl NotConverged {
    /// Exit status of a run that did not converge (1 is for errors).
    pub const EXIT_CODE: u8 = 2;
}

/// Print the nominal screening's whole-file findings as warnings; `Err` with the refusals among them.
fn report_findings(ws: &Workspace) -> Result<()> {
    for f in &ws.screening.findings {
        if f.severity == quality::Severity::Warning {
            eprintln!("warning: {f}");
        }
    }
    let errors: Vec<&str> = ws.refusals().iter().map(|f| f.message.as_str()).collect();
    if errors.is_empty() {
        Ok(())
    } else {
        bail!("{}", errors.join("\nerror: "))
    }
}

/// `dualcal calibrate`.
pub(crate) fn run(a: &CalibrateArgs) -> Result<()> {
    let mut phases = timings::Phases::new();
    let ws = load_workspace(&a.dataset)?;
    phases.end("load, checks, nominal model, screening");
    refuse_overwrites(a, &ws.dataset)?;
    if !a.quiet {
        eprintln!("{}", describe_robot(&ws.robot));
    }
    let (mut settings, by_default) = settings_from(a, &ws.dataset)?;
    model_settings(a, &ws, &mut settings)?;
    if let Some(why) = by_default {
        outln!(
            "method: step 1 `{}` by default for this data ({why}); --method minimax fits the \
             distances alone",
            settings.method.name()
        );
    }
    add_exclusions(a, &ws.dataset, &mut settings)?;
    report_findings(&ws)?;
    let Workspace {
        dataset: ds,
        robot,
        nominal,
        screening: before,
    } = ws;
    // The parameter file's figures and the accuracy tables (the calibrated model's figures are the
    // ones the file records: computed once), beside the screening of the result.
    let tables = |result: &CalibrationResult| {
        let file = ParamsFile::from_calibration(result, &ds);
        let recorded: Option<StatisticsRecord> = file
            .statistics
            .clone()
            .and_then(|v| serde_json::from_value(v).ok());
        let table = comparison_table(
            &ds.excluding(&result.settings.exclude),
            result,
            recorded.as_ref(),
        );
        (file, table)
    };
    let (result, after, uncertainty, (mut file, table)) =
        fit_and_screen(a, &ds, &nominal, settings, &before, tables)?;
    phases.end("calibration, the screening of its result, its uncertainty, the accuracy tables");
    phases.done.push((
        "  of which the calibration (two steps, re-checks)",
        std::time::Duration::from_secs_f64(result.elapsed_secs),
    ));
    print_identifiability(&result);
    print_uncertainty(&uncertainty);
    let excluded = &result.settings.exclude;
    file.record_uncertainty(&uncertainty);
    outln!("\n{}", table?);
    print_flags(
        "Suspect configurations with the calibrated model",
        &after,
        excluded,
    );
    warn_suspects_kept(&after, excluded);
    file.quality = serde_json::to_value(quality::QualityRecord::new(&ds, &after, excluded)).ok();
    phases.end("the parameter file's quality record");
    file.write(&a.out)?;
    outln!("parameters written to {}", a.out.display());
    write_robot_exports(a, &robot, &result)?;
    phases.end("writing");
    if a.timings {
        phases.print();
    }
    if !result.is_converged() {
        let how: Vec<String> = result
            .stages
            .iter()
            .filter(|s| !s.termination.is_converged())
            .map(|s| format!("{}: {}", s.stage, s.termination))
            .collect();
        return Err(NotConverged(how.join("; ")).into());
    }
    Ok(())
}
