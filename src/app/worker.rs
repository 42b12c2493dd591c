//! The calibration worker: a [`CalibrationRun`] stepped on its own thread, progress through a bounded
//! channel.
//!
//! Iteration events are sent with `try_send` and dropped when the UI is behind (the curves only lose
//! points); the final message is always delivered. Cancel is an `Arc<AtomicBool>` the solver polls.
//! The UI drains the channel once per frame and never blocks on it.

use super::session::Calibrated;
use crate::analysis::Analysis;
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::solver::{
    CalibrationEvent, CalibrationRun, CalibrationSettings, Calibrator, IterationRecord, Observer,
    Progress, Stage, StageSummary, Termination,
};
use nalgebra::Isometry3;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError, TrySendError, sync_channel};

/// Channel capacity for progress events.
const CHANNEL_CAPACITY: usize = 512;

/// Messages from the worker.
pub enum WorkerMessage {
    Progress(CalibrationEvent),
    /// The run ended.
    Finished(Outcome),
}

/// How a run ended.
pub enum Outcome {
    /// The calibrated model with its figures.
    Calibrated(Box<Calibrated>),
    /// The cancel flag stopped it.
    Cancelled,
    /// Why it did not succeed.
    Failed(String),
}

/// A running calibration.
pub struct CalibrationJob {
    cancel: Arc<AtomicBool>,
    receiver: Receiver<WorkerMessage>,
    thread: Option<std::thread::JoinHandle<()>>,
    pub started: std::time::Instant,
    /// When Cancel was pressed.
    pub cancel_requested: Option<std::time::Instant>,
    /// The final message has been received.
    pub finished: bool,
}

impl CalibrationJob {
    /// Start a run. `repaint` is called after each message so the UI wakes up.
    pub fn spawn(
        dataset: Arc<Dataset>,
        nominal: DualArmModel,
        settings: CalibrationSettings,
        body_from_left_base: Isometry3<f64>,
        repaint: impl Fn() + Send + 'static,
    ) -> std::io::Result<Self> {
        let cancel = Arc::new(AtomicBool::new(false));
        let (sender, receiver) = sync_channel(CHANNEL_CAPACITY);
        let flag = cancel.clone();
        let thread = std::thread::Builder::new()
            .name("dualcal-calibration".into())
            .spawn(move || {
                run(
                    &dataset,
                    &nominal,
                    &settings,
                    &body_from_left_base,
                    flag,
                    &sender,
                    &repaint,
                )
            })?;
        Ok(Self {
            cancel,
            receiver,
            thread: Some(thread),
            started: std::time::Instant::now(),
            cancel_requested: None,
            finished: false,
        })
    }

    /// Ask the solver to stop; the worker then reports `Finished(Outcome::Cancelled)`.
    pub fn cancel(&mut self) {
        if self.cancel_requested.is_none() {
            self.cancel_requested = Some(std::time::Instant::now());
        }
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelling(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Every message that has arrived, without blocking.
    pub fn drain(&mut self) -> Vec<WorkerMessage> {
        let mut out = Vec::new();
        loop {
            match self.receiver.try_recv() {
                Ok(m) => {
                    if matches!(m, WorkerMessage::Finished(_)) {
                        self.finished = true;
                    }
                    out.push(m);
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    if !self.finished {
                        self.finished = true;
                        out.push(WorkerMessage::Finished(Outcome::Failed(
                            "the calibration thread stopped unexpectedly".into(),
                        )));
                    }
                    break;
                }
            }
        }
        if self.finished
            && let Some(t) = self.thread.take()
        {
            // The thread has sent its last message; it is returning.
            let _ = t.join();
        }
        out
    }
}

impl Drop for CalibrationJob {
    fn drop(&mut self) {
        // A dropped job (new dataset, app closed) stops its worker; it is not joined here.
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// Forwards the run's events to the UI: stage boundaries always (they are few: wait for room),
/// iterations when there is room (the curves only lose points).
struct ChannelObserver<'a> {
    sender: &'a SyncSender<WorkerMessage>,
    repaint: &'a dyn Fn(),
}

impl ChannelObserver<'_> {
    fn send(&self, event: CalibrationEvent) {
        let message = WorkerMessage::Progress(event);
        if matches!(
            message,
            WorkerMessage::Progress(CalibrationEvent::Iteration(_))
        ) {
            match self.sender.try_send(message) {
                Ok(()) | Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => {}
            }
        } else {
            let _ = self.sender.send(message);
        }
        (self.repaint)();
    }
}

impl Observer for ChannelObserver<'_> {
    fn stage_started(&mut self, stage: Stage, n_configs: usize, n_pairs: usize) {
        self.send(CalibrationEvent::StageStarted {
            stage,
            n_configs,
            n_pairs,
        });
    }

    fn iteration(&mut self, record: &IterationRecord, _run: &CalibrationRun) {
        self.send(CalibrationEvent::Iteration(record.clone()));
    }

    fn stage_finished(&mut self, summary: &StageSummary, _run: &CalibrationRun) {
        self.send(CalibrationEvent::StageFinished {
            stage: summary.stage,
            termination: summary.termination,
        });
    }
}

fn run(
    dataset: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
    body_from_left_base: &Isometry3<f64>,
    cancel: Arc<AtomicBool>,
    sender: &SyncSender<WorkerMessage>,
    repaint: &dyn Fn(),
) {
    let mut observer = ChannelObserver { sender, repaint };
    let outcome = Calibrator::new(dataset, nominal)
        .settings(settings.clone())
        .cancel(cancel)
        .start()
        .and_then(|mut run| {
            loop {
                if let Progress::Finished(result) = run.step(&mut [&mut observer])? {
                    break Ok(*result);
                }
            }
        });
    let message = match outcome {
        Ok(result)
            if result
                .stages
                .iter()
                .any(|s| s.termination == Termination::Cancelled) =>
        {
            Outcome::Cancelled
        }
        Ok(result) => match Analysis::compute(dataset, &result.calibrated, body_from_left_base) {
            Ok(analysis) => Outcome::Calibrated(Box::new(Calibrated { result, analysis })),
            Err(e) => Outcome::Failed(format!("calibrated model: {e:#}")),
        },
        Err(e) => Outcome::Failed(e.to_string()),
    };
    let _ = sender.send(WorkerMessage::Finished(message));
    repaint();
}
