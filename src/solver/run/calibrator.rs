//! The entry point of a run: [`Calibrator`] sets a [`CalibrationRun`] up and runs it to its end, or
//! hands it to a caller that steps it.

use super::executor::{CalibrationRun, Observer, Progress};
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::solver::error::CalibrationError;
use crate::solver::result::CalibrationResult;
use crate::solver::settings::CalibrationSettings;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// Sets up and runs a calibration:
/// `Calibrator::new(&dataset, &nominal).settings(s).observer(&mut o).cancel(flag).run()`.
pub struct Calibrator<'a> {
    dataset: &'a Dataset,
    nominal: &'a DualArmModel,
    settings: CalibrationSettings,
    observers: Vec<&'a mut dyn Observer>,
    cancel: Arc<AtomicBool>,
}

impl<'a> Calibrator<'a> {
    /// A calibration of `nominal` on `dataset` with the default settings.
    pub fn new(dataset: &'a Dataset, nominal: &'a DualArmModel) -> Self {
        Self {
            dataset,
            nominal,
            settings: CalibrationSettings::default(),
            observers: Vec::new(),
            cancel: Arc::new(AtomicBool::new(false)),
        }
    }

    pub fn settings(mut self, settings: CalibrationSettings) -> Self {
        self.settings = settings;
        self
    }

    /// Add an observer (several may watch one run).
    pub fn observer(mut self, observer: &'a mut dyn Observer) -> Self {
        self.observers.push(observer);
        self
    }

    /// A flag another thread sets to cancel the run; it is polled between outer iterations (each takes
    /// milliseconds on paper-size data) and inside the paper's QP solver (every 256 iterations).
    pub fn cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = flag;
        self
    }

    /// Run every stage to its end. A run that hits the iteration limit or is cancelled returns its
    /// result too; `Err` is for input the calibration cannot use.
    pub fn run(self) -> Result<CalibrationResult, CalibrationError> {
        // Called from a thread outside rayon's pool, every parallel loop of the run would hand its
        // work over and sleep on a latch until it is done (at the paper's size that costs more than
        // the loop saves): the run moves onto a pool thread, whose loops share their work with the
        // other threads directly, and this thread waits for it once.
        if !cfg!(target_arch = "wasm32") && crate::par::current_thread_index().is_none() {
            return crate::par::scope(|_| self.run_here());
        }
        self.run_here()
    }

    fn run_here(mut self) -> Result<CalibrationResult, CalibrationError> {
        let mut observers = std::mem::take(&mut self.observers);
        let mut run = CalibrationRun::new(self.dataset, self.nominal, self.settings, self.cancel)?;
        if !run.arms_at_once(&mut observers)? {
            run.start_next()?;
        }
        loop {
            if let Progress::Finished(result) = run.step(&mut observers)? {
                return Ok(*result);
            }
        }
    }

    /// The run, to be advanced by the caller one outer iteration per [`CalibrationRun::step`] (a UI
    /// frame loop, or the browser, where there are no threads). Observers given to the calibrator are
    /// not used: pass them to each step.
    pub fn start(self) -> Result<CalibrationRun, CalibrationError> {
        let mut run = CalibrationRun::new(self.dataset, self.nominal, self.settings, self.cancel)?;
        run.start_next()?;
        Ok(run)
    }
}
