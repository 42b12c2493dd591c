//! The workbench's background jobs, held in one collection ([`Jobs`]).
//!
//! A job is a [`Work`] (what runs off the frame, reporting events of its own type) and a [`Job`]
//! (what the app does with those events), started with [`JobContext::start_job`]. A job handles its
//! events with a [`JobContext`], what it may change of the workbench, never the whole app. The collection
//! routes each task's events to its job, steps the tasks that run in frames, and drops the jobs of a
//! dataset when another one loads. One job runs per [`Lane`]; starting one replaces the job running in
//! its lane (dropping a task cancels it).
//!
//! A new background job is one file here: its event type, its `Work` and its `Job` impl, and a
//! function that starts it (given the [`JobContext`]), which the command (or event) that starts it calls.

pub mod calibration;
pub mod comparison;
pub mod context;
pub mod load;
pub mod meshes;
pub mod plan;

use super::events::EventSender;
use super::task::{BackgroundTask, Execution, TaskId, TaskReport, Work};
pub use context::JobContext;
use std::any::{Any, TypeId};
use std::time::Duration;

/// Which jobs replace each other: one job runs per lane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lane(TypeId);

impl Lane {
    /// The lane of the job type `J`.
    pub fn of<J: 'static>() -> Self {
        Lane(TypeId::of::<J>())
    }
}

/// Whether a job goes on after an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    Running,
    Ended,
}

/// What the app does with a job's events.
pub trait Job: Sized + 'static {
    /// What its work reports.
    type Event: Send + 'static;

    /// Its lane (default: its own type's).
    fn lane(&self) -> Lane {
        Lane::of::<Self>()
    }

    /// Whether it goes on when another dataset loads (default: no, it is of the dataset it started on).
    fn survives_load(&self) -> bool {
        false
    }

    /// One of its work's events; [`Flow::Ended`] after its last.
    fn on_event(
        &mut self,
        cx: &mut JobContext<'_>,
        task: &BackgroundTask,
        event: Self::Event,
    ) -> Flow;

    /// The work stopped without reporting its end (a panic); the job has ended.
    fn on_failed(&mut self, cx: &mut JobContext<'_>, task: &BackgroundTask, message: String);
}

/// A job with its event type hidden.
trait AnyJob {
    /// The job itself, to be told apart by its type ([`Jobs::get`]).
    fn as_any(&self) -> &dyn Any;

    fn on_report(
        &mut self,
        cx: &mut JobContext<'_>,
        task: &BackgroundTask,
        report: TaskReport,
    ) -> Flow;
}

impl<J: Job> AnyJob for J {
    fn as_any(&self) -> &dyn Any {
        self
    }

    fn on_report(
        &mut self,
        cx: &mut JobContext<'_>,
        task: &BackgroundTask,
        report: TaskReport,
    ) -> Flow {
        match report {
            TaskReport::Event(event) => match event.downcast::<J::Event>() {
                Ok(event) => self.on_event(cx, task, *event),
                // Not its work's (cannot happen: a task reports its work's type).
                Err(_) => Flow::Running,
            },
            TaskReport::Failed(message) => {
                self.on_failed(cx, task, message);
                Flow::Ended
            }
        }
    }
}

struct Running {
    lane: Lane,
    survives_load: bool,
    task: BackgroundTask,
    job: Box<dyn AnyJob>,
}

/// The running jobs.
#[derive(Default)]
pub struct Jobs {
    running: Vec<Running>,
}

impl Jobs {
    /// The task of the job running in `lane`.
    pub fn task(&self, lane: Lane) -> Option<&BackgroundTask> {
        self.running
            .iter()
            .find(|r| r.lane == lane)
            .map(|r| &r.task)
    }

    /// The running job of type `J` (its own state: a calibration's live history, say).
    pub fn get<J: Job>(&self) -> Option<&J> {
        self.running
            .iter()
            .find_map(|r| r.job.as_any().downcast_ref::<J>())
    }

    pub fn is_running(&self, lane: Lane) -> bool {
        self.task(lane).is_some()
    }

    /// Ask the job running in `lane` to stop; it still reports its end.
    pub fn cancel(&mut self, lane: Lane) {
        if let Some(r) = self.running.iter_mut().find(|r| r.lane == lane) {
            r.task.cancel();
        }
    }

    /// Drop the job running in `lane` (its task is cancelled, its events are ignored from now on).
    pub fn stop(&mut self, lane: Lane) {
        self.running.retain(|r| r.lane != lane);
    }

    /// Another dataset loaded: drop the jobs of the last one.
    pub fn dataset_replaced(&mut self) {
        self.running.retain(|r| r.survives_load);
    }

    /// Step the tasks that run in frames, each for `budget()`; whether any was stepped.
    pub fn step_in_frame(&mut self, mut budget: impl FnMut() -> Duration) -> bool {
        let mut stepped = false;
        for r in &mut self.running {
            if r.task.needs_frames() {
                r.task.step_in_frame(budget());
                stepped = true;
            }
        }
        stepped
    }
}

impl Jobs {
    /// Start `work` on a background task reporting to `events`, its events handled by `job`; the job
    /// running in the same lane is replaced.
    pub fn start<J: Job, W: Work<Event = J::Event>>(
        &mut self,
        name: &str,
        job: J,
        work: W,
        events: &EventSender,
        execution: Execution,
    ) -> std::io::Result<()> {
        let lane = job.lane();
        self.stop(lane);
        let task = BackgroundTask::start(name, work, events, execution)?;
        self.running.push(Running {
            lane,
            survives_load: job.survives_load(),
            task,
            job: Box::new(job),
        });
        Ok(())
    }
}

/// Hand a task's report to its job; reports of a task that was replaced or dropped are ignored.
/// The job is out of the collection while it handles the report (and stays out once it ended).
pub fn on_task_report(cx: &mut JobContext<'_>, id: TaskId, report: TaskReport) {
    let Some(at) = cx.jobs.running.iter().position(|r| r.task.id() == id) else {
        return;
    };
    let mut running = cx.jobs.running.remove(at);
    let flow = running.job.on_report(cx, &running.task, report);
    // Unless it ended, or a job was started in its lane meanwhile.
    if flow == Flow::Running && !cx.jobs.is_running(running.lane) {
        let at = at.min(cx.jobs.running.len());
        cx.jobs.running.insert(at, running);
    }
}
