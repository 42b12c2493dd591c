//! What the background tasks do: load a dataset into a [`Session`] (one step), load and pack its
//! robot's meshes ([`MeshWork`], one step), and calibrate one (a [`CalibrationRun`], one outer
//! iteration per step; now and then one more step evaluates the model the run has reached, for the
//! live view: [`LiveRate`]), or apply the Auto-exclude rule ([`AutoExcludeWork`], one step).
//!
//! A calibration leaves out the session's excluded configurations (`CalibrationSettings::exclude`);
//! when they differ from those of the nominal figures shown, its first step re-evaluates the nominal
//! model without them ([`RunEvent::Nominal`]), so "before" and "after" figures are of the same
//! configurations, as in `dualcal calibrate --exclude`.

use super::session::{AutoExcludeSummary, Calibrated, LiveFigures, LoadedMeshes, Session};
use super::task::{Execution, Step, TaskContext, Work};
use super::viewport::mesh_pack::{MeshKey, PackedMeshes};
use crate::analysis::{Analysis, AnalysisError};
use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::meshes::{GeometryKind, MeshWarning, lod};
use crate::quality::{self, ScreenSettings};
use crate::robot::{RobotDescription, ShapeKind};
use crate::side::{ConfigId, Side};
use crate::solver::{
    CalibrationEvent, CalibrationResult, CalibrationRun, CalibrationSettings, Calibrator,
    IterationRecord, Observer, Progress, Stage, StageSummary, Termination,
};
use crate::source::Files;
use anyhow::Context as _;
use nalgebra::Isometry3;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use web_time::Instant;

/// A dataset and robot loaded.
pub struct Loaded {
    pub session: Session,
    /// The robot description it was loaded with (`None`: the dataset's own or the built-in one).
    pub urdf: Option<PathBuf>,
    pub elapsed_secs: f64,
}

/// What a load reports: the loaded dataset, or why it could not load.
pub type LoadEvent = Result<Box<Loaded>, String>;

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

/// Load a dataset (directory or `dataset.toml`), with `urdf` overriding its robot.
pub struct LoadWork {
    pub dataset: PathBuf,
    pub urdf: Option<PathBuf>,
    /// Where the files are read from (the file system, or a browser's files in memory).
    pub files: Files,
}

impl Work for LoadWork {
    type Event = LoadEvent;

    fn step(&mut self, task: &TaskContext<LoadEvent>) -> Step {
        let started = Instant::now();
        let result = Session::load_from(&self.files, &self.dataset, self.urdf.as_deref())
            .with_context(|| match &self.urdf {
                Some(urdf) => format!(
                    "cannot use robot description {} for dataset {}",
                    urdf.display(),
                    self.dataset.display()
                ),
                None => format!("cannot open dataset {}", self.dataset.display()),
            })
            .map(|session| {
                Box::new(Loaded {
                    session,
                    urdf: self.urdf.take(),
                    elapsed_secs: started.elapsed().as_secs_f64(),
                })
            })
            .map_err(|e| format!("{e:#}"));
        task.report(result);
        Step::Done
    }
}

/// Load a robot's visual meshes and pack them for the GPU. Links whose visual mesh cannot be loaded
/// get their collision meshes loaded too (drawn as stand-ins).
pub struct MeshWork {
    pub robot: Arc<RobotDescription>,
}

impl Work for MeshWork {
    type Event = Box<LoadedMeshes>;

    fn step(&mut self, task: &TaskContext<Box<LoadedMeshes>>) -> Step {
        task.report(Box::new(load_meshes(&self.robot)));
        Step::Done
    }
}

/// Does the robot draw any mesh?
pub fn has_visual_meshes(robot: &RobotDescription) -> bool {
    robot.urdf.links.iter().any(|l| {
        l.visual
            .iter()
            .any(|v| matches!(v.geometry, urdf_rs::Geometry::Mesh { .. }))
    })
}

/// The robot's visual meshes packed, with the collision meshes of the links whose visual mesh is
/// missing; and a simplified copy of that pack for software renderers (not in the browser).
pub fn load_meshes(robot: &RobotDescription) -> LoadedMeshes {
    let started = Instant::now();
    let visual = robot.load_meshes(GeometryKind::Visual);
    let home = |side| robot.home_q_rad(side);
    let (ql, qr) = (home(Side::Left), home(Side::Right));
    let missing_links: Vec<String> = robot
        .shapes(&ql, &qr, GeometryKind::Visual)
        .into_iter()
        .filter(|s| match &s.kind {
            ShapeKind::Mesh {
                filename, scale, ..
            } => visual.get(filename, (*scale).into()).is_none(),
            _ => false,
        })
        .map(|s| s.link)
        .collect();
    let collision = if missing_links.is_empty() {
        Default::default()
    } else {
        robot.load_meshes(GeometryKind::Collision)
    };
    let stand_ins: Vec<(MeshKey, &crate::meshes::TriangleMesh)> = robot
        .shapes(&ql, &qr, GeometryKind::Collision)
        .into_iter()
        .filter(|s| missing_links.contains(&s.link))
        .filter_map(|s| match s.kind {
            ShapeKind::Mesh {
                filename, scale, ..
            } => {
                let scale: [f64; 3] = scale.into();
                let mesh = collision.get(&filename, scale)?;
                Some((
                    MeshKey::new(GeometryKind::Collision, &filename, scale),
                    &**mesh,
                ))
            }
            _ => None,
        })
        .collect();
    let visual_meshes = visual.meshes.iter().map(|((filename, bits), mesh)| {
        (
            MeshKey {
                kind: GeometryKind::Visual,
                filename: filename.clone(),
                scale_bits: *bits,
            },
            &**mesh,
        )
    });
    let (packed, simplified) =
        PackedMeshes::pack_with_lod(visual_meshes.chain(stand_ins), lod::ROBOT_TRIANGLES);
    // Files not found are named by the robot's own warnings already (per link).
    let warnings = visual
        .warnings
        .iter()
        .filter(|w| {
            !matches!(
                w,
                MeshWarning::NotFound { .. }
                    | MeshWarning::UnknownPackage { .. }
                    | MeshWarning::UnsupportedScheme { .. }
            )
        })
        .map(|w| format!("{w}; drawn as a placeholder"))
        .collect();
    LoadedMeshes {
        packed: Arc::new(packed),
        simplified: simplified.map(Arc::new),
        visual_files: visual.meshes.len(),
        visual_triangles: visual.triangle_count(),
        visual_missing: visual.warnings.len(),
        warnings,
        elapsed_secs: started.elapsed().as_secs_f64(),
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
struct Snapshot {
    stage: Stage,
    iteration: usize,
    stage_finished: bool,
    model: DualArmModel,
}

/// When the next live view is due, and the one waiting to be evaluated.
pub struct LiveSchedule {
    rate: LiveRate,
    /// When the last live view was sent (or the run started).
    last: Instant,
    /// How long its evaluation took.
    last_cost: Duration,
    pending: Option<Snapshot>,
}

impl LiveSchedule {
    fn new(rate: LiveRate) -> Self {
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
pub(super) fn calibrated_outcome(
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
            let params = super::export::params_file(dataset, &result, &screening, &uncertainty);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::events::{AppEvent, EventChannel};
    use crate::app::task::{BackgroundTask, Execution, TaskReport};
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
