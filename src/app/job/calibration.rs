//! A calibration as a job: a plain calibration ([`CalibrationWork`]), Auto-exclude
//! ([`AutoExcludeWork`]), or a compared result being adopted ([`AdoptWork`]) —
//! one lane, so each replaces the other. Its progress fills the status bar and the convergence
//! curves, the model it reaches is shown live, and its end becomes the session's calibration.
//!
//! The convergence history has one owner at a time ([`history`]): the running job holds the
//! iterations reported so far; a finished run's result holds its whole history, and the session's
//! calibration is that result.

use super::{Flow, Job, JobContext, Jobs, Lane};
use crate::analysis::{Analysis, AnalysisError};
use crate::app::compare;
use crate::app::session::{AutoExcludeSummary, Calibrated, LiveFigures, Session};
use crate::app::status::RunTiming;
use crate::app::task::{BackgroundTask, Step, TaskContext, Work};
use crate::app::work::{LiveRate, LiveSchedule, Reporter};
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::quality::{self, ScreenSettings};
use crate::side::ConfigId;
use crate::solver::{
    CalibrationEvent, CalibrationResult, CalibrationRun, CalibrationSettings, Calibrator,
    IterationRecord, Progress, Stage, Termination,
};
use nalgebra::Isometry3;
use std::sync::Arc;
use std::time::Duration;
use web_time::Instant;

/// What a calibration (a plain one, Auto-exclude, or a compared result being adopted) reports.
pub enum RunEvent {
    /// Its progress.
    Progress(CalibrationEvent),
    /// The model it has reached, evaluated.
    Live(Box<LiveFigures>),
    /// The nominal model's figures without the configurations it leaves out.
    Nominal(Box<Analysis>),
    /// Before a calibration with errors beyond geometry: the geometric model's calibration of the same
    /// data and settings, evaluated (`None`: a geometric run, no reference).
    Geometric(Option<Box<Analysis>>),
    /// What Auto-exclude removed (before its [`RunEvent::Calibrated`]).
    AutoExcluded(AutoExcludeSummary),
    /// It ended (its last event).
    Calibrated(Outcome),
}

impl From<CalibrationEvent> for RunEvent {
    fn from(event: CalibrationEvent) -> Self {
        RunEvent::Progress(event)
    }
}

/// How a calibration ended.
pub enum Outcome {
    /// The calibrated model with its figures (every stage ran, converged or not).
    Calibrated(Box<Calibrated>),
    /// The cancel flag stopped it in `stage` after `iterations` of its outer iterations; the model
    /// reached is not kept.
    Cancelled { stage: Stage, iterations: usize },
    /// Why it did not succeed.
    Failed(String),
}

/// The two-step calibration of a session's nominal model. The first step sets the run up (the
/// identifiability analysis; the nominal figures without the excluded configurations, if those
/// changed); each further step is one outer iteration, or the evaluation of a live snapshot
/// ([`RunEvent::Live`]). The end screens the result ([`crate::exclusion::screen_result`]).
pub struct CalibrationWork {
    dataset: Arc<Dataset>,
    nominal: DualArmModel,
    settings: CalibrationSettings,
    body_from_left_base: Isometry3<f64>,
    /// The exclusions of the nominal figures the session shows.
    nominal_excluded: Vec<ConfigId>,
    run: Option<CalibrationRun>,
    live: LiveSchedule,
    /// Time in the solver's steps so far.
    solver: Duration,
    /// Fault injection for tests: panic in the first step.
    #[cfg(test)]
    pub panic_at_start: bool,
}

impl CalibrationWork {
    pub fn new(session: &Session, settings: CalibrationSettings, rate: LiveRate) -> Self {
        Self {
            dataset: session.dataset.clone(),
            nominal: session.nominal.model.clone(),
            settings: session.with_gravity(settings),
            body_from_left_base: session.body_from_left_base(),
            nominal_excluded: session.nominal.excluded.clone(),
            run: None,
            live: LiveSchedule::new(rate),
            solver: Duration::ZERO,
            #[cfg(test)]
            panic_at_start: false,
        }
    }

    /// With a model beyond geometry: the geometric calibration of the same data and settings,
    /// evaluated (run to its end here: as long as one geometric calibration, tens of milliseconds at
    /// the paper's size), for the accuracy view's comparison. `None` for a geometric run, or when that
    /// calibration fails (the run itself then says why).
    fn geometric_reference(&self) -> Option<Box<Analysis>> {
        if self.settings.model.is_geometric() {
            return None;
        }
        let settings = CalibrationSettings {
            model: crate::kinematics::ErrorTerms::GEOMETRIC,
            ..self.settings.clone()
        };
        let result = Calibrator::new(&self.dataset, &self.nominal)
            .settings(settings)
            .run()
            .ok()?;
        self.analysis(&result.calibrated).ok().map(Box::new)
    }

    fn analysis(&self, model: &DualArmModel) -> Result<Analysis, AnalysisError> {
        Analysis::compute_excluding(
            &self.dataset,
            model,
            &self.body_from_left_base,
            &self.settings.exclude,
        )
    }

    fn outcome(&self, result: CalibrationResult) -> Outcome {
        if let Some(s) = result
            .stages
            .iter()
            .find(|s| s.termination == Termination::Cancelled)
        {
            return Outcome::Cancelled {
                stage: s.stage,
                iterations: s.iterations,
            };
        }
        let analysis = self.analysis(&result.calibrated);
        calibrated_outcome(
            &self.dataset,
            result,
            analysis,
            None,
            self.solver.as_secs_f64(),
        )
    }
}

/// A finished calibration with its figures and its screening.
fn calibrated_outcome(
    dataset: &Dataset,
    result: CalibrationResult,
    analysis: Result<Analysis, AnalysisError>,
    screening: Option<quality::Screening>,
    solver_secs: f64,
) -> Outcome {
    match analysis {
        Ok(analysis) => {
            let screening = screening.unwrap_or_else(|| {
                crate::exclusion::screen_result(dataset, &result, &ScreenSettings::default())
            });
            let uncertainty = crate::solver::uncertainty::for_result(dataset, &result);
            let params =
                crate::app::export::params_file(dataset, &result, &screening, &uncertainty);
            Outcome::Calibrated(Box::new(Calibrated {
                result,
                analysis,
                screening,
                uncertainty,
                params,
                solver_secs,
            }))
        }
        Err(e) => Outcome::Failed(format!("calibrated model: {e:#}")),
    }
}

impl Work for CalibrationWork {
    type Event = RunEvent;

    fn step(&mut self, task: &TaskContext<RunEvent>) -> Step {
        let Some(run) = &mut self.run else {
            #[cfg(test)]
            assert!(
                !self.panic_at_start,
                "fault injected into the calibration worker"
            );
            if self.nominal_excluded != self.settings.exclude {
                match self.analysis(&self.nominal) {
                    Ok(analysis) => task.report(RunEvent::Nominal(Box::new(analysis))),
                    Err(e) => {
                        task.report(RunEvent::Calibrated(Outcome::Failed(format!(
                            "nominal figures without the excluded configurations: {e:#}"
                        ))));
                        return Step::Done;
                    }
                }
                self.nominal_excluded = self.settings.exclude.clone();
            }
            let setup = Instant::now();
            task.report(RunEvent::Geometric(self.geometric_reference()));
            let started = Calibrator::new(&self.dataset, &self.nominal)
                .settings(self.settings.clone())
                .cancel(task.cancel_flag().clone())
                .start();
            self.solver += setup.elapsed();
            return match started {
                Ok(run) => {
                    self.run = Some(run);
                    Step::More
                }
                Err(e) => {
                    task.report(RunEvent::Calibrated(Outcome::Failed(e.to_string())));
                    Step::Done
                }
            };
        };
        if let Some(snapshot) = self.live.pending.take() {
            let started = Instant::now();
            // A model the figures cannot be computed of (e.g. a degenerate reflector triangle on the
            // way) is not shown; the view keeps the previous one.
            if let Ok(analysis) = Analysis::compute_excluding(
                &self.dataset,
                &snapshot.model,
                &self.body_from_left_base,
                &self.settings.exclude,
            ) {
                let cost = started.elapsed();
                task.report(RunEvent::Live(Box::new(LiveFigures {
                    stage: snapshot.stage,
                    iteration: snapshot.iteration,
                    stage_finished: snapshot.stage_finished,
                    analysis,
                    evaluation_secs: cost.as_secs_f64(),
                })));
            }
            self.live.last_cost = started.elapsed();
            self.live.last = Instant::now();
            return Step::Show;
        }
        let mut reporter = Reporter {
            task,
            live: Some(&mut self.live),
        };
        let stepping = Instant::now();
        let stepped = run.step(&mut [&mut reporter]);
        self.solver += stepping.elapsed();
        let outcome = match stepped {
            Ok(Progress::Running) => return Step::More,
            Ok(Progress::Finished(result)) => self.outcome(*result),
            Err(e) => Outcome::Failed(e.to_string()),
        };
        task.report(RunEvent::Calibrated(outcome));
        Step::Done
    }
}

/// The Auto-exclude rule ([`crate::exclusion::auto_exclude`], `dualcal calibrate --auto-exclude`): screen, leave
/// the suspects out, fit, screen again, … in one step (a few fits; no live view, not cancellable
/// midway). Reports the nominal figures without the configurations it removed, what it removed
/// ([`RunEvent::AutoExcluded`]) and the calibration it ended with.
pub struct AutoExcludeWork {
    dataset: Arc<Dataset>,
    nominal: DualArmModel,
    settings: CalibrationSettings,
    body_from_left_base: Isometry3<f64>,
}

impl AutoExcludeWork {
    /// `settings.exclude` (the user's own exclusions) is kept.
    pub fn new(session: &Session, settings: CalibrationSettings) -> Self {
        Self {
            dataset: session.dataset.clone(),
            nominal: session.nominal.model.clone(),
            settings: session.with_gravity(settings),
            body_from_left_base: session.body_from_left_base(),
        }
    }
}

impl Work for AutoExcludeWork {
    type Event = RunEvent;

    fn step(&mut self, task: &TaskContext<RunEvent>) -> Step {
        let started = Instant::now();
        let auto = match crate::exclusion::auto_exclude(
            &self.dataset,
            &self.nominal,
            None,
            &self.settings,
            &ScreenSettings::default(),
        ) {
            Ok(auto) => auto,
            Err(e) => {
                task.report(RunEvent::Calibrated(Outcome::Failed(e.to_string())));
                return Step::Done;
            }
        };
        let solver_secs = started.elapsed().as_secs_f64();
        let exclude = &auto.result.settings.exclude;
        let figures = |model: &DualArmModel| {
            Analysis::compute_excluding(&self.dataset, model, &self.body_from_left_base, exclude)
        };
        match figures(&self.nominal) {
            Ok(nominal) => task.report(RunEvent::Nominal(Box::new(nominal))),
            Err(e) => {
                task.report(RunEvent::Calibrated(Outcome::Failed(format!(
                    "nominal figures without the excluded configurations: {e:#}"
                ))));
                return Step::Done;
            }
        }
        task.report(RunEvent::AutoExcluded(AutoExcludeSummary {
            excluded: auto.excluded.clone(),
            rounds: auto.rounds,
            stopped: auto.stopped.clone(),
        }));
        let analysis = figures(&auto.result.calibrated);
        task.report(RunEvent::Calibrated(calibrated_outcome(
            &self.dataset,
            auto.result,
            analysis,
            Some(auto.screening),
            solver_secs,
        )));
        Step::Done
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
    fn on_progress(&mut self, cx: &mut JobContext<'_>, event: CalibrationEvent) {
        match event {
            CalibrationEvent::StageStarted { stage, .. } => {
                cx.status.running(Some(stage), 0);
                *cx.plot_stage = stage;
            }
            CalibrationEvent::Iteration(record) => {
                cx.status.running(Some(record.stage), record.iteration);
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

    fn on_event(
        &mut self,
        cx: &mut JobContext<'_>,
        task: &BackgroundTask,
        event: RunEvent,
    ) -> Flow {
        match event {
            RunEvent::Progress(progress) => self.on_progress(cx, progress),
            RunEvent::Live(live) => on_live(cx, *live),
            RunEvent::Nominal(analysis) => {
                if let Some(session) = cx.scene.edit() {
                    session.nominal = *analysis;
                }
            }
            RunEvent::Geometric(analysis) => {
                if let Some(session) = cx.scene.edit() {
                    session.geometric = analysis.map(|a| *a);
                }
            }
            RunEvent::AutoExcluded(summary) => {
                if let Some(session) = cx.scene.edit() {
                    session.auto_exclusion = Some(summary);
                }
            }
            RunEvent::Calibrated(outcome) => {
                on_calibration_end(cx, outcome, task, self.kind);
                return Flow::Ended;
            }
        }
        Flow::Running
    }

    fn on_failed(&mut self, cx: &mut JobContext<'_>, task: &BackgroundTask, message: String) {
        on_calibration_end(cx, Outcome::Failed(message), task, self.kind);
    }
}

/// Start a run of `kind`; a running one is replaced (its events are ignored from now on).
pub fn start_run(cx: &mut JobContext<'_>, kind: RunKind, work: impl Work<Event = RunEvent>) {
    // Dropping a running task cancels it.
    cx.jobs.stop(CalibrationJob::lane());
    discard_live(cx);
    // A calibration beyond geometry reports its geometric reference again; any other run has none.
    if cx.scene.get().is_some_and(|s| s.geometric.is_some())
        && let Some(session) = cx.scene.edit()
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
    match cx.start_job(name, job, work) {
        Ok(()) => cx.status.running(None, 0),
        Err(e) => cx
            .errors
            .push(format!("cannot start the calibration thread: {e}")),
    }
}

/// The model the running calibration has reached: shown instead of the last finished calibration
/// (the table, the Accuracy and Summary tabs, the viewport) until the run ends. The display scale
/// stays, so the error vectors visibly shrink; it follows the errors again at the end.
fn on_live(cx: &mut JobContext<'_>, live: LiveFigures) {
    if let Some(session) = cx.scene.edit() {
        session.live = Some(live);
    }
}

/// Drop the running calibration's live model (the last finished one is shown again).
fn discard_live(cx: &mut JobContext<'_>) {
    if cx.scene.get().is_some_and(|s| s.live.is_some())
        && let Some(session) = cx.scene.edit()
    {
        session.live = None;
    }
}

/// A run ended: record its timing, drop its live model, and take its result (or say why there is
/// none) — the status line tells which.
fn on_calibration_end(
    cx: &mut JobContext<'_>,
    outcome: Outcome,
    task: &BackgroundTask,
    kind: RunKind,
) {
    *cx.last_run = Some(RunTiming {
        wall_secs: task.elapsed_secs(),
        slices: task.slice_stats(),
    });
    discard_live(cx);
    let kept = kept_model(cx.scene.get());
    let status = match outcome {
        Outcome::Calibrated(calibrated) => {
            let status = done_status(&calibrated, task, kind);
            take_calibration(cx, *calibrated);
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
            cx.errors.push(format!("calibration: {message}"));
            format!("Calibration failed; {kept}.")
        }
    };
    cx.status.idle(status);
}

/// What is shown when a run ends without a result.
fn kept_model(session: Option<&Session>) -> &'static str {
    if session.is_some_and(|s| s.calibrated.is_some()) {
        "the previous calibration is shown again"
    } else {
        "the nominal model is shown again"
    }
}

/// A finished run becomes the session's calibration: its result with its whole history (the one
/// shown from now on, complete even if progress events were dropped), the exclusions it ran with
/// (Auto-exclude adds its own), its model.
fn take_calibration(cx: &mut JobContext<'_>, calibrated: Calibrated) {
    if let Some(session) = cx.scene.edit() {
        session.exclude = calibrated.result.settings.exclude.clone();
        session.calibrated = Some(calibrated);
    }
    if let Some(session) = cx.scene.get() {
        cx.viewport.auto_scale(session);
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
    let weak: Vec<String> = result
        .weak
        .iter()
        .flat_map(|(side, w)| w.iter().map(move |w| format!("{} ({side} arm)", w.name)))
        .collect();
    let weak = match (weak.is_empty(), result.settings.keep_weak) {
        (true, _) => String::new(),
        (false, false) => format!(
            " Weak, held at nominal: {} (the arm's panel says why).",
            weak.join(", ")
        ),
        (false, true) => format!(
            " Weak, kept free: {} (the arm's panel says why).",
            weak.join(", ")
        ),
    };
    let advice = excluded + &weak + &warnings;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::events::{AppEvent, EventChannel};
    use crate::app::job::load::LoadWork;
    use crate::app::task::{BackgroundTask, Execution, TaskReport};
    use crate::source::Files;
    use std::path::Path;
    use std::time::Duration;

    /// The work's events, stepped in frames to its end.
    fn run_in_frames<W: Work>(work: W, channel: &EventChannel) -> Vec<W::Event> {
        let mut task =
            BackgroundTask::start("work", work, channel.sender(), Execution::InFrames).unwrap();
        while task.needs_frames() {
            task.step_in_frame(Duration::from_millis(5));
        }
        channel
            .drain()
            .into_iter()
            .map(|event| match event {
                AppEvent::Task(_, TaskReport::Event(event)) => *event.downcast().unwrap(),
                AppEvent::Task(_, TaskReport::Failed(message)) => panic!("{message}"),
                _ => panic!("not a task's event"),
            })
            .collect()
    }

    /// Without threads: the example loads and calibrates when stepped from a frame loop.
    #[test]
    fn the_example_loads_and_calibrates_stepped_in_frames() {
        let channel = EventChannel::new(None);
        let load = LoadWork {
            dataset: Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example"),
            urdf: None,
            files: Files::default(),
        };
        let Some(Ok(loaded)) = run_in_frames(load, &channel).pop() else {
            panic!("the example did not load");
        };
        let calibration = CalibrationWork::new(
            &loaded.session,
            CalibrationSettings::default(),
            LiveRate::IN_FRAMES,
        );
        let events = run_in_frames(calibration, &channel);
        let iterations = events
            .iter()
            .filter(|e| matches!(e, RunEvent::Progress(CalibrationEvent::Iteration(_))))
            .count();
        // The live views: at least the end of both arms' stages (the last stage's result follows).
        let live: Vec<&LiveFigures> = events
            .iter()
            .filter_map(|e| match e {
                RunEvent::Live(live) => Some(&**live),
                _ => None,
            })
            .collect();
        let ends: Vec<Stage> = live
            .iter()
            .filter(|l| l.stage_finished)
            .map(|l| l.stage)
            .collect();
        assert_eq!(
            ends,
            [
                Stage::Arm(crate::side::Side::Left),
                Stage::Arm(crate::side::Side::Right)
            ]
        );
        let nominal_rms = |a: &Analysis| a.ver.report.unwrap().relative_left.unwrap().pos_rms_mm;
        let after_left = live.iter().find(|l| l.stage_finished).unwrap();
        assert!(nominal_rms(&after_left.analysis) < 0.1 * nominal_rms(&loaded.session.nominal));
        match events.last() {
            Some(RunEvent::Calibrated(Outcome::Calibrated(c))) => {
                assert!(c.result.is_converged());
                assert_eq!(iterations, c.result.history.len());
                // The left arm's stage ended with the model the run then kept.
                assert_eq!(
                    after_left.analysis.model.arms.left,
                    c.result.calibrated.arms.left
                );
            }
            _ => panic!("no calibrated result"),
        }
    }
}
