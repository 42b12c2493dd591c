//! The "Compare methods" view: the methods of [`crate::comparison::METHODS`] the user picks, run one
//! after another on the loaded dataset in the background ([`ComparisonWork`], one outer iteration per
//! step, so it is stepped in frames where there are no threads), side by side: a summary table
//! (nominal first, the best figure of each column highlighted), a histogram per method and a box plot
//! per method; any method's result can be adopted as the current calibration (then the exports write
//! it). The engine does the work ([`crate::comparison`]: the methods table, the figures, the box
//! statistics); this is the view's state and the task around it (the view is drawn by
//! [`super::panels::compare_ui`]).

use super::session::Session;
use super::task::{Step, TaskContext, Work};
use super::work::{Outcome, Reporter, RunEvent, calibrated_outcome};
use crate::analysis::{Analysis, Indicator};
use crate::comparison::{
    self, Comparison, ComparisonEvent, METHODS, MethodEntry, MethodError, MethodOutcome, MethodRun,
};
use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::side::Side;
use crate::solver::{
    BaseMethod, CalibrationEvent, CalibrationResult, CalibrationRun, CalibrationSettings,
    Calibrator, Method, Progress, Stage,
};
use nalgebra::Isometry3;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// The method a calibration used, for the status line and the comparison: step 1 (with the reflector
/// each arm used, for distance-single) and step 2.
pub fn method_used(result: &CalibrationResult) -> String {
    let s = &result.settings;
    let reflectors: Vec<String> = Side::BOTH
        .iter()
        .filter_map(|&side| result.reflector_used[side].map(|r| format!("{side} {r}")))
        .collect();
    let reflector = if reflectors.is_empty() {
        String::new()
    } else {
        format!(" (reflector {})", reflectors.join(", "))
    };
    format!(
        "method {}{reflector}, base {}",
        s.method.name(),
        s.base_method.name()
    )
}

/// What the view shows and which methods are picked.
pub struct CompareView {
    /// The view replaces the 3D view, the table and the plots.
    pub open: bool,
    /// Per [`METHODS`] entry: whether it is run.
    pub picked: Vec<bool>,
    pub split: Split,
    /// The indicator of the histograms and box plots.
    pub indicator: Indicator,
    /// The running or last comparison (methods are added as they finish).
    pub comparison: Option<Comparison>,
    /// The running comparison's progress.
    pub progress: Option<CompareProgress>,
    /// The entry whose result was adopted last (by key).
    pub adopted: Option<&'static str>,
}

impl Default for CompareView {
    fn default() -> Self {
        Self {
            open: false,
            picked: paper_set(),
            split: Split::Ver,
            indicator: Indicator::CollaborativePosition,
            comparison: None,
            progress: None,
            adopted: None,
        }
    }
}

/// The paper's comparison: every method it has a column for.
pub fn paper_set() -> Vec<bool> {
    METHODS.iter().map(|m| m.paper.is_some()).collect()
}

impl CompareView {
    /// The picked entries, in the table's order.
    pub fn picked_entries(&self) -> Vec<MethodEntry> {
        METHODS
            .iter()
            .zip(&self.picked)
            .filter(|(_, picked)| **picked)
            .map(|(m, _)| *m)
            .collect()
    }

    /// Pick exactly the entries whose keys are given (unknown keys are ignored).
    pub fn pick(&mut self, keys: &[&str]) {
        self.picked = METHODS.iter().map(|m| keys.contains(&m.key)).collect();
    }
}

/// Where a running comparison is.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareProgress {
    pub index: usize,
    pub total: usize,
    pub key: &'static str,
    pub stage: Option<Stage>,
    pub iteration: usize,
}

impl CompareProgress {
    pub fn label(&self) -> String {
        let title = comparison::method(self.key).map_or(self.key.to_string(), |m| m.title());
        let at = match self.stage {
            Some(stage) => format!(", {stage}, iteration {}", self.iteration),
            None => String::new(),
        };
        format!(
            "Comparing: method {} of {} — {title}{at}",
            self.index + 1,
            self.total
        )
    }
}

/// The settings the comparison's methods share: a run's settings (the user's split, limits and
/// tolerances and the session's exclusions: [`Session::run_settings`]); each entry sets its own method
/// on top.
pub fn common_settings(run: &CalibrationSettings) -> CalibrationSettings {
    CalibrationSettings {
        method: Method::Minimax,
        base_method: BaseMethod::Minimax,
        reflector: None,
        ..run.clone()
    }
}

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

/// Make a compared method's result the current calibration: its figures and screening computed off
/// the frame, then it is taken like a finished calibration ([`RunEvent::Calibrated`]).
pub struct AdoptWork {
    dataset: Arc<Dataset>,
    result: Option<CalibrationResult>,
    body_from_left_base: Isometry3<f64>,
}

impl AdoptWork {
    pub fn new(session: &Session, result: CalibrationResult) -> Self {
        Self {
            dataset: session.dataset.clone(),
            result: Some(result),
            body_from_left_base: session.body_from_left_base(),
        }
    }
}

impl Work for AdoptWork {
    type Event = RunEvent;

    fn step(&mut self, task: &TaskContext<RunEvent>) -> Step {
        let Some(result) = self.result.take() else {
            return Step::Done;
        };
        let analysis = Analysis::compute_excluding(
            &self.dataset,
            &result.calibrated,
            &self.body_from_left_base,
            &result.settings.exclude,
        );
        let solver_secs = result.elapsed_secs;
        let outcome: Outcome =
            calibrated_outcome(&self.dataset, result, analysis, None, solver_secs);
        task.report(RunEvent::Calibrated(outcome));
        Step::Done
    }
}
