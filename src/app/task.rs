//! Work done off the frame: loading a dataset and calibrating are [`BackgroundTask`]s.
//!
//! A task's [`Work`] advances in steps (each job's own, [`super::job`]: a load is one step, a calibration one outer
//! iteration per step) and reports events of its own type ([`Work::Event`]) on the app's event
//! channel. A native build runs
//! each task on its own thread; where there are no threads (a browser build) the same work is stepped
//! from the frame loop ([`Execution::InFrames`], [`BackgroundTask::step_in_frame`]), and a step that
//! reported something to show ([`Step::Show`]: a calibration's live view) ends the frame's slice.
//! Cancel is an `Arc<AtomicBool>` the work polls.

use super::events::{AppEvent, EventSender};
pub use super::events::{TaskId, TaskReport};
use std::marker::PhantomData;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;
use web_time::Instant;

/// What a step of work says about the next one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// There is more to do.
    More,
    /// There is more to do, after the UI has shown what this step reported: work stepped in frames
    /// ends the frame's slice here (a live view is drawn before the run goes on).
    Show,
    /// The work is done (its final event sent).
    Done,
}

/// A task's work, in steps.
pub trait Work: Send + 'static {
    /// What it reports (its own type: the job that started it reads it).
    type Event: Send + 'static;

    /// Do the next piece of work, reporting through `task`.
    fn step(&mut self, task: &TaskContext<Self::Event>) -> Step;
}

/// What a step of work sees: where to report its events, and the task's cancel flag.
pub struct TaskContext<E> {
    id: TaskId,
    events: EventSender,
    cancel: Arc<AtomicBool>,
    event: PhantomData<fn(E)>,
}

impl<E: Send + 'static> TaskContext<E> {
    pub fn report(&self, event: E) {
        self.events
            .send(AppEvent::Task(self.id, TaskReport::Event(Box::new(event))));
    }

    /// Report progress that may be dropped while the UI is behind.
    pub fn report_progress(&self, event: E) {
        self.events
            .send_droppable(AppEvent::Task(self.id, TaskReport::Event(Box::new(event))));
    }

    fn report_failed(&self, message: String) {
        self.events
            .send(AppEvent::Task(self.id, TaskReport::Failed(message)));
    }

    pub fn cancel_flag(&self) -> &Arc<AtomicBool> {
        &self.cancel
    }
}

/// Where tasks run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Execution {
    /// Each task on its own thread.
    Thread,
    /// Stepped from the frame loop, a time slice per frame (for targets without threads).
    InFrames,
}

impl Default for Execution {
    fn default() -> Self {
        if cfg!(target_arch = "wasm32") {
            Execution::InFrames
        } else {
            Execution::Thread
        }
    }
}

/// Work with its context, its event type hidden (for the frame loop).
trait Stepped {
    fn step(&mut self) -> Step;
    fn failed(&self, message: String);
}

struct Bound<W: Work> {
    work: W,
    context: TaskContext<W::Event>,
}

impl<W: Work> Stepped for Bound<W> {
    fn step(&mut self) -> Step {
        self.work.step(&self.context)
    }

    fn failed(&self, message: String) {
        self.context.report_failed(message);
    }
}

enum Runner {
    /// The thread reports by itself; it is not joined (a dropped task's thread ends on its own).
    Thread,
    InFrames {
        work: Box<dyn Stepped>,
        done: bool,
    },
}

/// How long work stepped in frames may take of the next frame: as long as the rest of the last frame
/// took (building the UI, painting, waiting for the display), between [`FrameBudget::MIN`] and
/// [`FrameBudget::MAX`]. On a fast GPU at 60 Hz that is about half of each frame; on a slow renderer
/// (a software WebGL2 takes ~350 ms a frame) the work gets up to `MAX` per frame instead of a few ms,
/// so it ends in a few frames while the page keeps drawing (a frame at most `MAX` longer).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameBudget {
    /// A fixed budget instead (a browser test's `?budget_ms=N`).
    fixed: Option<Duration>,
    /// When the last slice ended (`None`: no work was stepped in the last frame).
    last_slice_end: Option<Instant>,
}

impl FrameBudget {
    pub const MIN: Duration = Duration::from_millis(8);
    pub const MAX: Duration = Duration::from_millis(100);

    /// Always `budget` (0: one step per frame).
    pub fn fixed(budget: Duration) -> Self {
        Self {
            fixed: Some(budget),
            last_slice_end: None,
        }
    }

    /// The budget of a slice starting `now`.
    pub fn next(&self, now: Instant) -> Duration {
        match (self.fixed, self.last_slice_end) {
            (Some(fixed), _) => fixed,
            (None, Some(end)) => now
                .saturating_duration_since(end)
                .clamp(Self::MIN, Self::MAX),
            (None, None) => Self::MIN,
        }
    }

    /// A slice ended `now`; `None`: this frame stepped nothing (the next slice starts afresh).
    pub fn slice_done(&mut self, now: Option<Instant>) {
        self.last_slice_end = now;
    }
}

/// Time a task stepped in frames spent working.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SliceStats {
    /// Frames that stepped it.
    pub slices: usize,
    /// Time in its steps, s.
    pub busy_secs: f64,
    /// The longest slice, s.
    pub longest_slice_secs: f64,
}

/// A running task: the handle the app keeps. Dropping it cancels the work.
pub struct BackgroundTask {
    id: TaskId,
    name: String,
    started: Instant,
    slices: SliceStats,
    cancel: Arc<AtomicBool>,
    cancel_requested: Option<Instant>,
    runner: Runner,
}

static NEXT_TASK_ID: AtomicU64 = AtomicU64::new(1);

impl BackgroundTask {
    /// Start `work`; its events go to `events`. `name` names its thread.
    pub fn start<W: Work>(
        name: &str,
        work: W,
        events: &EventSender,
        execution: Execution,
    ) -> std::io::Result<Self> {
        let id = NEXT_TASK_ID.fetch_add(1, Ordering::Relaxed);
        let cancel = Arc::new(AtomicBool::new(false));
        let context = TaskContext::<W::Event> {
            id,
            events: events.clone(),
            cancel: cancel.clone(),
            event: PhantomData,
        };
        let runner = match execution {
            Execution::Thread => {
                let what = name.to_string();
                std::thread::Builder::new()
                    .name(format!("dualcal-{name}"))
                    .spawn(move || run_to_end(work, &context, &what))?;
                Runner::Thread
            }
            Execution::InFrames => Runner::InFrames {
                work: Box::new(Bound { work, context }),
                done: false,
            },
        };
        Ok(Self {
            id,
            name: name.to_string(),
            started: Instant::now(),
            slices: SliceStats::default(),
            cancel,
            cancel_requested: None,
            runner,
        })
    }

    pub fn id(&self) -> TaskId {
        self.id
    }

    /// The name it was started with.
    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn elapsed_secs(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Time spent in the frame loop's slices (zero for a thread's work).
    pub fn slice_stats(&self) -> SliceStats {
        self.slices
    }

    /// Ask the work to stop; it still reports its end.
    pub fn cancel(&mut self) {
        self.cancel_requested.get_or_insert_with(Instant::now);
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelling(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Time since [`cancel`](Self::cancel) was first called.
    pub fn since_cancel(&self) -> Option<Duration> {
        self.cancel_requested.map(|t| t.elapsed())
    }

    /// Whether the frame loop must keep stepping this task.
    pub fn needs_frames(&self) -> bool {
        matches!(self.runner, Runner::InFrames { done: false, .. })
    }

    /// Advance work that runs in frames for about `budget`, or until a step has something to show
    /// (nothing for a thread's).
    pub fn step_in_frame(&mut self, budget: Duration) {
        if let Runner::InFrames { work, done } = &mut self.runner {
            let started = Instant::now();
            // At least one step, however small the budget.
            loop {
                // A panic in the work ends the task with a message; the frame loop goes on.
                let step = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work.step()));
                match step {
                    Ok(Step::More) => {}
                    Ok(Step::Show) => break,
                    Ok(Step::Done) => *done = true,
                    Err(payload) => {
                        work.failed(panic_message(&self.name, &*payload));
                        *done = true;
                    }
                }
                if *done || started.elapsed() >= budget {
                    break;
                }
            }
            let slice = started.elapsed().as_secs_f64();
            self.slices.slices += 1;
            self.slices.busy_secs += slice;
            self.slices.longest_slice_secs = self.slices.longest_slice_secs.max(slice);
        }
    }
}

impl Drop for BackgroundTask {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// A task thread's body: every step, then — if the work panicked — a final event saying so.
fn run_to_end<W: Work>(mut work: W, context: &TaskContext<W::Event>, name: &str) {
    let ran = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        while work.step(context) != Step::Done {}
    }));
    if let Err(payload) = ran {
        context.report_failed(panic_message(name, &*payload));
    }
}

/// What the user is told of a panic in a task: which task, and the panic's own message (a bug to
/// report; the window and the last good state stay).
fn panic_message(name: &str, payload: &(dyn std::any::Any + Send)) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into());
    format!(
        "the {name} worker stopped unexpectedly (internal error: {}); please report it",
        crate::textfile::excerpt_n(&what, 200)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::events::EventChannel;

    /// Counts to `n`, one step at a time, then reports its end.
    struct Counter {
        n: usize,
        panic_at: Option<usize>,
    }

    /// The counter's events: a tick, then the end.
    #[derive(Debug, PartialEq)]
    enum Count {
        Tick,
        Done,
    }

    impl Work for Counter {
        type Event = Count;

        fn step(&mut self, task: &TaskContext<Count>) -> Step {
            assert_ne!(Some(self.n), self.panic_at, "the work failed");
            if self.n == 0 || task.cancel_flag().load(Ordering::Relaxed) {
                task.report(Count::Done);
                return Step::Done;
            }
            self.n -= 1;
            task.report_progress(Count::Tick);
            Step::More
        }
    }

    fn is_final(report: &TaskReport) -> bool {
        match report {
            TaskReport::Event(event) => event.downcast_ref::<Count>() == Some(&Count::Done),
            TaskReport::Failed(_) => true,
        }
    }

    fn events_of(channel: &EventChannel, id: TaskId) -> Vec<TaskReport> {
        channel
            .drain()
            .into_iter()
            .filter_map(|e| match e {
                AppEvent::Task(task, event) if task == id => Some(event),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn work_stepped_in_frames_reports_like_a_thread() {
        let channel = EventChannel::new(None);
        let mut task = BackgroundTask::start(
            "count",
            Counter {
                n: 3,
                panic_at: None,
            },
            channel.sender(),
            Execution::InFrames,
        )
        .unwrap();
        while task.needs_frames() {
            task.step_in_frame(Duration::from_millis(1));
        }
        let events = events_of(&channel, task.id());
        assert_eq!(events.len(), 4);
        assert!(is_final(&events[3]) && !is_final(&events[0]));
    }

    #[test]
    fn the_frame_budget_follows_the_rest_of_the_frame_within_its_bounds() {
        let t0 = Instant::now();
        let mut budget = FrameBudget::default();
        assert_eq!(budget.next(t0), FrameBudget::MIN);
        budget.slice_done(Some(t0));
        // A fast frame: the floor; a 30 ms frame: 30 ms; a software renderer's 400 ms: the cap.
        assert_eq!(budget.next(t0 + Duration::from_millis(2)), FrameBudget::MIN);
        assert_eq!(
            budget.next(t0 + Duration::from_millis(30)),
            Duration::from_millis(30)
        );
        assert_eq!(
            budget.next(t0 + Duration::from_millis(400)),
            FrameBudget::MAX
        );
        // A frame without work starts afresh.
        budget.slice_done(None);
        assert_eq!(budget.next(t0 + Duration::from_secs(5)), FrameBudget::MIN);
        let fixed = FrameBudget::fixed(Duration::ZERO);
        assert_eq!(fixed.next(t0), Duration::ZERO);
    }

    #[test]
    fn a_zero_budget_still_takes_one_step_per_frame() {
        let channel = EventChannel::new(None);
        let mut task = BackgroundTask::start(
            "count",
            Counter {
                n: 3,
                panic_at: None,
            },
            channel.sender(),
            Execution::InFrames,
        )
        .unwrap();
        task.step_in_frame(Duration::ZERO);
        assert_eq!(events_of(&channel, task.id()).len(), 1);
        let stats = task.slice_stats();
        assert_eq!(stats.slices, 1);
        assert!(stats.busy_secs >= 0.0 && stats.longest_slice_secs == stats.busy_secs);
    }

    #[test]
    fn a_panic_in_work_stepped_in_frames_ends_the_task_not_the_frame_loop() {
        let channel = EventChannel::new(None);
        let mut task = BackgroundTask::start(
            "count",
            Counter {
                n: 3,
                panic_at: Some(1),
            },
            channel.sender(),
            Execution::InFrames,
        )
        .unwrap();
        while task.needs_frames() {
            task.step_in_frame(Duration::from_millis(1));
        }
        match events_of(&channel, task.id()).last() {
            Some(TaskReport::Failed(message)) => {
                assert!(message.contains("the count worker stopped"), "{message}");
                assert!(message.contains("the work failed"), "{message}");
            }
            _ => panic!("no final event"),
        }
    }

    #[test]
    fn a_panicking_thread_reports_that_it_stopped() {
        let channel = EventChannel::new(None);
        let task = BackgroundTask::start(
            "count",
            Counter {
                n: 3,
                panic_at: Some(1),
            },
            channel.sender(),
            Execution::Thread,
        )
        .unwrap();
        let deadline = Instant::now() + Duration::from_secs(20);
        let mut events = Vec::new();
        while !events.last().is_some_and(is_final) && Instant::now() < deadline {
            events.extend(events_of(&channel, task.id()));
            std::thread::sleep(Duration::from_millis(5));
        }
        match events.last() {
            Some(TaskReport::Failed(message)) => {
                assert!(message.contains("stopped unexpectedly"), "{message}");
                assert!(message.contains("the work failed"), "{message}");
            }
            _ => panic!("no final event"),
        }
    }
}
