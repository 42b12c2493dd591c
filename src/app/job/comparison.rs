//! Comparing methods ([`ComparisonWork`]): its progress, its nominal figures and each method's
//! outcome fill the comparison view as they arrive.

use super::super::WorkbenchApp;
use super::super::compare::{self, CompareEvent};
use super::super::status::Status;
use super::{Flow, Job, Lane};
use crate::app::task::BackgroundTask;
use crate::comparison::{Comparison, ComparisonEvent};
use crate::solver::CalibrationEvent;

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
        app: &mut WorkbenchApp,
        task: &BackgroundTask,
        event: CompareEvent,
    ) -> Flow {
        let view = &mut app.compare;
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
        comparison_ended(app, task, end);
        Flow::Ended
    }

    fn on_failed(&mut self, app: &mut WorkbenchApp, task: &BackgroundTask, message: String) {
        comparison_ended(app, task, Err(message));
    }
}

fn comparison_ended(app: &mut WorkbenchApp, task: &BackgroundTask, end: Result<bool, String>) {
    let view = &mut app.compare;
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
            app.status = Status::Idle(format!(
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
            app.errors.push(format!("comparison: {message}"));
            app.status = Status::Idle("Comparison failed.".into());
        }
    }
}
