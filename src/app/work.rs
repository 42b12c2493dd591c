//! What the runs share: their observer ([`Reporter`]: progress events for the status bar and the
//! curves, of a calibration and of a comparison) and the live view's schedule ([`LiveRate`],
//! [`LiveSchedule`]: how often a running calibration evaluates the model it has reached). Each job's
//! own work is in its file ([`super::job`]).

use super::task::{Execution, TaskContext};
use crate::kinematics::DualArmModel;
use crate::solver::{
    CalibrationEvent, CalibrationRun, IterationRecord, Observer, Stage, StageSummary, Termination,
};
use std::time::Duration;
use web_time::Instant;

/// How often a running calibration publishes the model it has reached: not sooner than
/// `min_interval` after the last publication, nor sooner than `cost_factor` times the time its
/// evaluation took (so evaluating takes at most `1 / (1 + cost_factor)` of the worker's time, however
/// large the dataset), and at the end of every stage but the last (whose result follows at once).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveRate {
    pub min_interval: Duration,
    pub cost_factor: u32,
}

impl LiveRate {
    /// On a worker thread: ten times a second on paper-size data; at 2 × 1000 configurations, as
    /// often as keeps the evaluation under a third of the worker's time.
    pub const THREAD: LiveRate = LiveRate {
        min_interval: Duration::from_millis(100),
        cost_factor: 2,
    };
    /// Stepped in frames (no threads): the evaluation is a step of its own and may take a frame past
    /// its budget, so at most every 250 ms and at most a tenth of the work time.
    pub const IN_FRAMES: LiveRate = LiveRate {
        min_interval: Duration::from_millis(250),
        cost_factor: 10,
    };

    pub fn for_execution(execution: Execution) -> Self {
        match execution {
            Execution::Thread => Self::THREAD,
            Execution::InFrames => Self::IN_FRAMES,
        }
    }
}

/// A model to evaluate for the live view.
pub struct Snapshot {
    pub stage: Stage,
    pub iteration: usize,
    pub stage_finished: bool,
    pub model: DualArmModel,
}

/// When the next live view is due, and the one waiting to be evaluated.
pub struct LiveSchedule {
    rate: LiveRate,
    /// When the last live view was sent (or the run started).
    pub last: Instant,
    /// How long its evaluation took.
    pub last_cost: Duration,
    /// The snapshot waiting to be evaluated.
    pub pending: Option<Snapshot>,
}

impl LiveSchedule {
    pub fn new(rate: LiveRate) -> Self {
        Self {
            rate,
            last: Instant::now(),
            last_cost: Duration::ZERO,
            pending: None,
        }
    }

    fn due(&self) -> bool {
        let wait = self
            .rate
            .min_interval
            .max(self.last_cost * self.rate.cost_factor);
        self.pending.is_none() && self.last.elapsed() >= wait
    }
}

/// A run's observer: progress events for the status bar and the curves (a calibration's and a
/// comparison's), and — given a schedule — the live snapshots.
pub struct Reporter<'a, E> {
    pub task: &'a TaskContext<E>,
    pub live: Option<&'a mut LiveSchedule>,
}

impl<E: From<CalibrationEvent> + Send + 'static> Observer for Reporter<'_, E> {
    fn stage_started(&mut self, stage: Stage, n_configs: usize, n_pairs: usize) {
        self.task.report(
            CalibrationEvent::StageStarted {
                stage,
                n_configs,
                n_pairs,
            }
            .into(),
        );
    }

    /// Iterations arrive when the UI keeps up (they are many); a snapshot when one is due.
    fn iteration(&mut self, record: &IterationRecord, run: &CalibrationRun) {
        self.task
            .report_progress(CalibrationEvent::Iteration(record.clone()).into());
        if let Some(live) = &mut self.live
            && live.due()
        {
            live.pending = Some(Snapshot {
                stage: record.stage,
                iteration: record.iteration,
                stage_finished: false,
                model: run.current_model(),
            });
        }
    }

    /// Stage boundaries always arrive, with the stage's final model (unless it was cancelled).
    fn stage_finished(&mut self, summary: &StageSummary, run: &CalibrationRun) {
        self.task.report(
            CalibrationEvent::StageFinished {
                stage: summary.stage,
                termination: summary.termination,
            }
            .into(),
        );
        if summary.termination != Termination::Cancelled
            && let Some(live) = &mut self.live
        {
            live.pending = Some(Snapshot {
                stage: summary.stage,
                iteration: summary.iterations,
                stage_finished: true,
                model: run.current_model(),
            });
        }
    }
}
