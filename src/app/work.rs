//! What the background tasks do: load a dataset into a [`Session`] (one step), and calibrate one (a
//! [`CalibrationRun`], one outer iteration per step).

use super::session::{Calibrated, Session};
use super::task::{TaskContext, TaskEvent, Work};
use crate::analysis::Analysis;
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::solver::{
    CalibrationEvent, CalibrationResult, CalibrationRun, CalibrationSettings, Calibrator, Progress,
    Termination,
};
use anyhow::Context as _;
use nalgebra::Isometry3;
use std::path::PathBuf;
use std::sync::Arc;

/// A dataset and robot loaded.
pub struct Loaded {
    pub session: Session,
    /// The robot description it was loaded with (`None`: the dataset's own or the built-in one).
    pub urdf: Option<PathBuf>,
    pub elapsed_secs: f64,
}

/// Load a dataset (directory or `dataset.toml`), with `urdf` overriding its robot.
pub struct LoadWork {
    pub dataset: PathBuf,
    pub urdf: Option<PathBuf>,
}

impl Work for LoadWork {
    fn step(&mut self, task: &TaskContext) -> bool {
        let started = std::time::Instant::now();
        let result = Session::load(&self.dataset, self.urdf.as_deref())
            .with_context(|| format!("cannot open dataset {}", self.dataset.display()))
            .map(|session| {
                Box::new(Loaded {
                    session,
                    urdf: self.urdf.take(),
                    elapsed_secs: started.elapsed().as_secs_f64(),
                })
            })
            .map_err(|e| format!("{e:#}"));
        task.report(TaskEvent::Loaded(result));
        false
    }
}

/// How a calibration ended.
pub enum Outcome {
    /// The calibrated model with its figures.
    Calibrated(Box<Calibrated>),
    /// The cancel flag stopped it.
    Cancelled,
    /// Why it did not succeed.
    Failed(String),
}

/// The two-step calibration of a session's nominal model. The first step sets the run up (the
/// identifiability analysis); each further step is one outer iteration.
pub struct CalibrationWork {
    dataset: Arc<Dataset>,
    nominal: DualArmModel,
    settings: CalibrationSettings,
    body_from_left_base: Isometry3<f64>,
    run: Option<CalibrationRun>,
}

impl CalibrationWork {
    pub fn new(session: &Session, settings: CalibrationSettings) -> Self {
        Self {
            dataset: session.dataset.clone(),
            nominal: session.nominal.model.clone(),
            settings,
            body_from_left_base: session.body_from_left_base(),
            run: None,
        }
    }

    fn outcome(&self, result: CalibrationResult) -> Outcome {
        if result
            .stages
            .iter()
            .any(|s| s.termination == Termination::Cancelled)
        {
            return Outcome::Cancelled;
        }
        match Analysis::compute(&self.dataset, &result.calibrated, &self.body_from_left_base) {
            Ok(analysis) => Outcome::Calibrated(Box::new(Calibrated { result, analysis })),
            Err(e) => Outcome::Failed(format!("calibrated model: {e:#}")),
        }
    }
}

impl Work for CalibrationWork {
    fn step(&mut self, task: &TaskContext) -> bool {
        let Some(run) = &mut self.run else {
            let started = Calibrator::new(&self.dataset, &self.nominal)
                .settings(self.settings.clone())
                .cancel(task.cancel_flag().clone())
                .start();
            return match started {
                Ok(run) => {
                    self.run = Some(run);
                    true
                }
                Err(e) => {
                    task.report(TaskEvent::Calibrated(Outcome::Failed(e.to_string())));
                    false
                }
            };
        };
        // Stage boundaries always arrive (they are few); iterations when the UI keeps up.
        let mut observer = |event: &CalibrationEvent| {
            let event = TaskEvent::Calibration(event.clone());
            match event {
                TaskEvent::Calibration(CalibrationEvent::Iteration(_)) => {
                    task.report_progress(event)
                }
                _ => task.report(event),
            }
        };
        let outcome = match run.step(&mut [&mut observer]) {
            Ok(Progress::Running) => return true,
            Ok(Progress::Finished(result)) => self.outcome(*result),
            Err(e) => Outcome::Failed(e.to_string()),
        };
        task.report(TaskEvent::Calibrated(outcome));
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::events::{AppEvent, EventChannel};
    use crate::app::task::{BackgroundTask, Execution};
    use std::path::Path;
    use std::time::Duration;

    fn run_in_frames(work: impl Work, channel: &EventChannel) -> Vec<AppEvent> {
        let mut task =
            BackgroundTask::start("work", work, channel.sender(), Execution::InFrames).unwrap();
        while task.needs_frames() {
            task.step_in_frame(Duration::from_millis(5));
        }
        channel.drain()
    }

    /// Without threads: the example loads and calibrates when stepped from a frame loop.
    #[test]
    fn the_example_loads_and_calibrates_stepped_in_frames() {
        let channel = EventChannel::new(None);
        let load = LoadWork {
            dataset: Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example"),
            urdf: None,
        };
        let Some(AppEvent::Task(_, TaskEvent::Loaded(Ok(loaded)))) =
            run_in_frames(load, &channel).pop()
        else {
            panic!("the example did not load");
        };
        let calibration = CalibrationWork::new(&loaded.session, CalibrationSettings::default());
        let events = run_in_frames(calibration, &channel);
        let iterations = events
            .iter()
            .filter(|e| {
                matches!(
                    e,
                    AppEvent::Task(_, TaskEvent::Calibration(CalibrationEvent::Iteration(_)))
                )
            })
            .count();
        match events.last() {
            Some(AppEvent::Task(_, TaskEvent::Calibrated(Outcome::Calibrated(c)))) => {
                assert!(c.result.is_converged());
                assert_eq!(iterations, c.result.history.len());
            }
            _ => panic!("no calibrated result"),
        }
    }
}
