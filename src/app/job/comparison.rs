//! Comparing methods ([`ComparisonWork`]): its progress, its nominal figures and each method's
//! outcome fill the comparison view as they arrive.

use super::{Flow, Job, JobContext, Lane};
use crate::analysis::Analysis;
use crate::app::compare;
use crate::app::session::Session;
use crate::app::task::{BackgroundTask, Step, TaskContext, Work};
use crate::app::work::Reporter;
use crate::comparison::{
    Comparison, ComparisonEvent, MethodEntry, MethodError, MethodOutcome, MethodRun,
};
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::solver::{CalibrationEvent, CalibrationRun, CalibrationSettings, Calibrator, Progress};
use nalgebra::Isometry3;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// What a comparison reports.
pub enum CompareEvent {
    /// The running method's stages and iterations.
    Progress(CalibrationEvent),
    /// A method starts or ends.
    Method(ComparisonEvent),
    /// Its nominal figures (its first step).
    Nominal(Box<Analysis>),
    /// A compared method ended (ran, failed, or was cancelled).
    MethodEnded(Box<MethodOutcome>),
    /// It ended (its last event): `Ok(cancelled)`, or why it could not run at all.
    Ended(Result<bool, String>),
}

impl From<CalibrationEvent> for CompareEvent {
    fn from(event: CalibrationEvent) -> Self {
        CompareEvent::Progress(event)
    }
}

/// The comparison as a task: the nominal figures (first step), then each method — set up, one outer
/// iteration per step, its figures — reporting each method's outcome as it ends. A method that cannot
/// run is recorded with its error and the others go on. Cancel stops the running method (its row
/// says "cancelled") and skips the rest.
pub struct ComparisonWork {
    dataset: Arc<Dataset>,
    nominal: DualArmModel,
    body_from_left_base: Isometry3<f64>,
    entries: Vec<MethodEntry>,
    common: CalibrationSettings,
    nominal_done: bool,
    next: usize,
    run: Option<CalibrationRun>,
}

impl ComparisonWork {
    pub fn new(session: &Session, entries: Vec<MethodEntry>, common: CalibrationSettings) -> Self {
        Self {
            dataset: session.dataset.clone(),
            nominal: session.nominal.model.clone(),
            body_from_left_base: session.body_from_left_base(),
            entries,
            common: session.with_gravity(common),
            nominal_done: false,
            next: 0,
            run: None,
        }
    }

    fn finish_method(
        &mut self,
        task: &TaskContext<CompareEvent>,
        outcome: Result<MethodRun, MethodError>,
    ) {
        let entry = self.entries[self.next];
        task.report(CompareEvent::Method(ComparisonEvent::MethodFinished {
            index: self.next,
            key: entry.key,
            converged: outcome.as_ref().is_ok_and(|r| r.result.is_converged()),
            error: outcome.as_ref().err().map(ToString::to_string),
        }));
        task.report(CompareEvent::MethodEnded(Box::new(MethodOutcome {
            entry,
            outcome,
        })));
        self.next += 1;
    }
}

impl Work for ComparisonWork {
    type Event = CompareEvent;

    fn step(&mut self, task: &TaskContext<CompareEvent>) -> Step {
        if !self.nominal_done {
            self.nominal_done = true;
            return match Analysis::compute(&self.dataset, &self.nominal, &self.body_from_left_base)
            {
                Ok(figures) => {
                    task.report(CompareEvent::Nominal(Box::new(figures)));
                    Step::Show
                }
                Err(e) => {
                    task.report(CompareEvent::Ended(Err(format!("nominal figures: {e}"))));
                    Step::Done
                }
            };
        }
        if let Some(run) = &mut self.run {
            let outcome = match run.step(&mut [&mut Reporter { task, live: None }]) {
                Ok(Progress::Running) => return Step::More,
                Ok(Progress::Finished(result)) => {
                    Analysis::compute(&self.dataset, &result.calibrated, &self.body_from_left_base)
                        .map(|figures| MethodRun {
                            result: *result,
                            figures,
                        })
                        .map_err(MethodError::Figures)
                }
                Err(e) => Err(e.into()),
            };
            self.run = None;
            self.finish_method(task, outcome);
            return Step::Show;
        }
        let cancelled = task.cancel_flag().load(Ordering::Relaxed);
        if cancelled || self.next == self.entries.len() {
            task.report(CompareEvent::Ended(Ok(cancelled)));
            return Step::Done;
        }
        let entry = self.entries[self.next];
        task.report(CompareEvent::Method(ComparisonEvent::MethodStarted {
            index: self.next,
            total: self.entries.len(),
            key: entry.key,
        }));
        let started = Calibrator::new(&self.dataset, &self.nominal)
            .settings(entry.settings(&self.common))
            .cancel(task.cancel_flag().clone())
            .start();
        match started {
            Ok(run) => self.run = Some(run),
            Err(e) => self.finish_method(task, Err(e.into())),
        }
        Step::More
    }
}

pub struct ComparisonJob;

impl ComparisonJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }
}

impl Job for ComparisonJob {
    type Event = CompareEvent;

    fn on_event(
        &mut self,
        cx: &mut JobContext<'_>,
        task: &BackgroundTask,
        event: CompareEvent,
    ) -> Flow {
        let view = &mut *cx.compare;
        let end = match event {
            CompareEvent::Progress(CalibrationEvent::StageStarted { stage, .. }) => {
                if let Some(p) = &mut view.progress {
                    p.stage = Some(stage);
                    p.iteration = 0;
                }
                return Flow::Running;
            }
            CompareEvent::Progress(CalibrationEvent::Iteration(record)) => {
                if let Some(p) = &mut view.progress {
                    p.stage = Some(record.stage);
                    p.iteration = record.iteration;
                }
                return Flow::Running;
            }
            CompareEvent::Progress(CalibrationEvent::StageFinished { .. })
            | CompareEvent::Method(ComparisonEvent::MethodFinished { .. }) => {
                return Flow::Running;
            }
            CompareEvent::Method(ComparisonEvent::MethodStarted { index, total, key }) => {
                view.progress = Some(compare::CompareProgress {
                    index,
                    total,
                    key,
                    stage: None,
                    iteration: 0,
                });
                return Flow::Running;
            }
            CompareEvent::Nominal(figures) => {
                view.comparison = Some(Comparison {
                    nominal: *figures,
                    truth: None,
                    methods: Vec::new(),
                    cancelled: false,
                });
                return Flow::Running;
            }
            CompareEvent::MethodEnded(outcome) => {
                if let Some(c) = &mut view.comparison {
                    c.methods.push(*outcome);
                }
                return Flow::Running;
            }
            CompareEvent::Ended(end) => end,
        };
        comparison_ended(cx, task, end);
        Flow::Ended
    }

    fn on_failed(&mut self, cx: &mut JobContext<'_>, task: &BackgroundTask, message: String) {
        comparison_ended(cx, task, Err(message));
    }
}

fn comparison_ended(cx: &mut JobContext<'_>, task: &BackgroundTask, end: Result<bool, String>) {
    let view = &mut *cx.compare;
    view.progress = None;
    match end {
        Ok(cancelled) => {
            if let Some(c) = &mut view.comparison {
                c.cancelled = cancelled;
            }
            let (ran, failed) = view.comparison.as_ref().map_or((0, 0), |c| {
                (
                    c.methods.len(),
                    c.methods.iter().filter(|m| m.run().is_none()).count(),
                )
            });
            cx.status.idle(format!(
                "Comparison {} after {:.1} s: {ran} method{} ran{}.",
                if cancelled { "cancelled" } else { "done" },
                task.elapsed_secs(),
                if ran == 1 { "" } else { "s" },
                match failed {
                    0 => String::new(),
                    n => format!(", {n} could not (see its row)"),
                }
            ));
        }
        Err(message) => {
            cx.errors.push(format!("comparison: {message}"));
            cx.status.idle("Comparison failed.");
        }
    }
}
