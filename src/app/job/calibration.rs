//! A calibration as a job: a plain calibration ([`CalibrationWork`]), Auto-exclude
//! ([`AutoExcludeWork`]), or a compared result being adopted ([`crate::app::compare::AdoptWork`]) —
//! one lane, so each replaces the other. Its progress fills the status bar and the convergence
//! curves, the model it reaches is shown live, and its end becomes the session's calibration.
//!
//! The convergence history has one owner at a time ([`history`]): the running job holds the
//! iterations reported so far; a finished run's result holds its whole history, and the session's
//! calibration is that result.

use super::super::session::{Calibrated, LiveFigures, Session};
use super::super::status::{RunTiming, Status};
use super::super::task::{BackgroundTask, Work};
use super::super::work::{Outcome, RunEvent};
use super::super::{WorkbenchApp, compare};
use super::{Flow, Job, Jobs, Lane};
use crate::solver::{CalibrationEvent, IterationRecord};

/// Which kind of run it is (the status line says so at the end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunKind {
    Calibration,
    /// A compared method's result, adopted.
    Adopt,
}

pub struct CalibrationJob {
    pub kind: RunKind,
    /// The iterations reported so far (the convergence curves while it runs).
    history: Vec<IterationRecord>,
}

impl CalibrationJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }

    /// Its stages and iterations: the status line, the plotted stage, the live history.
    fn on_progress(&mut self, app: &mut WorkbenchApp, event: CalibrationEvent) {
        match event {
            CalibrationEvent::StageStarted { stage, .. } => {
                app.status = Status::Running {
                    stage: Some(stage),
                    iteration: 0,
                };
                app.plots.stage = stage;
            }
            CalibrationEvent::Iteration(record) => {
                app.status = Status::Running {
                    stage: Some(record.stage),
                    iteration: record.iteration,
                };
                self.history.push(record);
            }
            CalibrationEvent::StageFinished { .. } => {}
        }
    }
}

/// The convergence history to show: the running calibration's iterations so far, else the whole
/// history of the session's calibration (none before the first).
pub fn history<'a>(jobs: &'a Jobs, session: Option<&'a Session>) -> &'a [IterationRecord] {
    match jobs.get::<CalibrationJob>() {
        Some(job) => &job.history,
        None => session
            .and_then(|s| s.calibrated.as_ref())
            .map_or(&[], |c| &c.result.history),
    }
}

impl Job for CalibrationJob {
    type Event = RunEvent;

    fn on_event(&mut self, app: &mut WorkbenchApp, task: &BackgroundTask, event: RunEvent) -> Flow {
        match event {
            RunEvent::Progress(progress) => self.on_progress(app, progress),
            RunEvent::Live(live) => app.on_live(*live),
            RunEvent::Nominal(analysis) => {
                if let Some(session) = app.scene_mut() {
                    session.nominal = *analysis;
                }
            }
            RunEvent::Geometric(analysis) => {
                if let Some(session) = app.scene_mut() {
                    session.geometric = analysis.map(|a| *a);
                }
            }
            RunEvent::AutoExcluded(summary) => {
                if let Some(session) = &mut app.session {
                    session.auto_exclusion = Some(summary);
                }
            }
            RunEvent::Calibrated(outcome) => {
                app.on_calibration_end(outcome, task, self.kind);
                return Flow::Ended;
            }
        }
        Flow::Running
    }

    fn on_failed(&mut self, app: &mut WorkbenchApp, task: &BackgroundTask, message: String) {
        app.on_calibration_end(Outcome::Failed(message), task, self.kind);
    }
}

impl WorkbenchApp {
    /// Start a run of `kind`; a running one is replaced (its events are ignored from now on).
    pub(in crate::app) fn start_run(&mut self, kind: RunKind, work: impl Work<Event = RunEvent>) {
        // Dropping a running task cancels it.
        self.jobs.stop(CalibrationJob::lane());
        self.discard_live();
        // A calibration beyond geometry reports its geometric reference again; any other run has none.
        if self.session.as_ref().is_some_and(|s| s.geometric.is_some())
            && let Some(session) = self.scene_mut()
        {
            session.geometric = None;
        }
        let name = match kind {
            RunKind::Calibration => "calibration",
            RunKind::Adopt => "adopt",
        };
        let job = CalibrationJob {
            kind,
            history: Vec::new(),
        };
        match self.start_job(name, job, work) {
            Ok(()) => {
                self.status = Status::Running {
                    stage: None,
                    iteration: 0,
                };
            }
            Err(e) => self
                .errors
                .push(format!("cannot start the calibration thread: {e}")),
        }
    }

    /// The model the running calibration has reached: shown instead of the last finished calibration
    /// (the table, the Accuracy and Summary tabs, the viewport) until the run ends. The display scale
    /// stays, so the error vectors visibly shrink; it follows the errors again at the end.
    fn on_live(&mut self, live: LiveFigures) {
        if let Some(session) = self.scene_mut() {
            session.live = Some(live);
        }
    }

    /// Drop the running calibration's live model (the last finished one is shown again).
    fn discard_live(&mut self) {
        if self.session.as_ref().is_some_and(|s| s.live.is_some())
            && let Some(session) = self.scene_mut()
        {
            session.live = None;
        }
    }

    /// A run ended: record its timing, drop its live model, and take its result (or say why there is
    /// none) — the status line tells which.
    fn on_calibration_end(&mut self, outcome: Outcome, task: &BackgroundTask, kind: RunKind) {
        self.last_run = Some(RunTiming {
            wall_secs: task.elapsed_secs(),
            slices: task.slice_stats(),
        });
        self.discard_live();
        let kept = self.kept_model();
        let status = match outcome {
            Outcome::Calibrated(calibrated) => {
                let status = done_status(&calibrated, task, kind);
                self.take_calibration(*calibrated);
                status
            }
            Outcome::Cancelled { stage, iterations } => {
                let latency = task
                    .since_cancel()
                    .map(|t| format!(", {:.0} ms after Cancel", t.as_secs_f64() * 1e3))
                    .unwrap_or_default();
                format!(
                    "Calibration cancelled after iteration {iterations} of {stage}{latency}; the model \
                     it reached is discarded and {kept}."
                )
            }
            Outcome::Failed(message) => {
                self.errors.push(format!("calibration: {message}"));
                format!("Calibration failed; {kept}.")
            }
        };
        self.status = Status::Idle(status);
    }

    /// What is shown when a run ends without a result.
    fn kept_model(&self) -> &'static str {
        if self
            .session
            .as_ref()
            .is_some_and(|s| s.calibrated.is_some())
        {
            "the previous calibration is shown again"
        } else {
            "the nominal model is shown again"
        }
    }

    /// A finished run becomes the session's calibration: its result with its whole history (the one
    /// shown from now on, complete even if progress events were dropped), the exclusions it ran with
    /// (Auto-exclude adds its own), its model.
    fn take_calibration(&mut self, calibrated: Calibrated) {
        if let Some(session) = self.scene_mut() {
            session.exclude = calibrated.result.settings.exclude.clone();
            session.calibrated = Some(calibrated);
        }
        if let Some(session) = &self.session {
            self.viewport.auto_scale(session);
        }
    }
}

/// The status line of a run that ended with a result.
fn done_status(calibrated: &Calibrated, task: &BackgroundTask, kind: RunKind) -> String {
    let result = &calibrated.result;
    let terms: Vec<String> = result
        .stages
        .iter()
        .map(|s| format!("{}: {} after {}", s.stage, s.termination, s.iterations))
        .collect();
    let warnings: String = result
        .warnings()
        .iter()
        .map(|w| format!(" Warning: {w}."))
        .collect();
    let excluded = match result.settings.exclude.len() {
        0 => String::new(),
        n => format!(" {n} configuration(s) left out."),
    };
    let advice = excluded + &warnings;
    let method = compare::method_used(result);
    match kind {
        RunKind::Adopt => format!(
            "Adopted the compared result ({method}; it took {:.1} s: {}).{advice}",
            result.elapsed_secs,
            terms.join(", ")
        ),
        RunKind::Calibration => format!(
            "Calibration done in {:.1} s ({method}; {}).{advice}",
            task.elapsed_secs(),
            terms.join(", ")
        ),
    }
}
