//! The executor: [`Calibrator`] sets a run up, [`CalibrationRun`] runs the stages in turn — step 1 for
//! the left arm, step 1 for the right arm, step 2 — one outer iteration per [`CalibrationRun::step`],
//! reporting to [`Observer`]s and polling the cancel flag. It names no method: each stage is set up by
//! the chosen method's entry of the table ([`super::methods`]).

use super::identifiability::{self, IdentifiabilityReport};
use super::methods::Method;
use super::methods::set_up::{ArmData, ArmSetUp, BaseSetUp, IDENTIFIABILITY_PAIRS, TreeSetUp};
use super::problem::StageParams;
use super::result::CalibrationResult;
use super::stage::StageSolver;
use super::{
    CalibrationError, CalibrationEvent, CalibrationSettings, IterationRecord, Reflector, Stage,
    StageSummary, Termination,
};
use crate::dataset::Dataset;
use crate::kinematics::{ArmModel, DualArmModel, SharedJoints};
use crate::side::{ConfigId, PerSide, Side};
use nalgebra::{Isometry3, Vector3};
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
// std's `Instant::now` panics in a browser (wasm32-unknown-unknown); web-time is std's on native targets.
use web_time::Instant;

/// Watches a run. Every method defaults to doing nothing; a closure over [`CalibrationEvent`] is an
/// observer too. The command line's progress lines, the workbench's live curves and the tests are
/// observers.
mod arms_at_once;

/// What a run reports as it goes. `Send`: [`Calibrator::run`] moves the run onto a thread of the work
/// pool.
pub trait Observer: Send {
    /// A stage begins: `n_configs` configurations (both arms' for step 2) and `n_pairs` pairs per
    /// reflector.
    fn stage_started(&mut self, _stage: Stage, _n_configs: usize, _n_pairs: usize) {}
    /// An outer iteration finished; `run` shows the model as it stands
    /// ([`CalibrationRun::current_model`]).
    fn iteration(&mut self, _record: &IterationRecord, _run: &CalibrationRun) {}
    /// A stage ended (converged or not); `run` holds the model with this stage's parameters.
    fn stage_finished(&mut self, _summary: &StageSummary, _run: &CalibrationRun) {}
}

impl<F: FnMut(&CalibrationEvent) + Send> Observer for F {
    fn stage_started(&mut self, stage: Stage, n_configs: usize, n_pairs: usize) {
        self(&CalibrationEvent::StageStarted {
            stage,
            n_configs,
            n_pairs,
        });
    }

    fn iteration(&mut self, record: &IterationRecord, _run: &CalibrationRun) {
        self(&CalibrationEvent::Iteration(record.clone()));
    }

    fn stage_finished(&mut self, summary: &StageSummary, _run: &CalibrationRun) {
        self(&CalibrationEvent::StageFinished {
            stage: summary.stage,
            termination: summary.termination,
        });
    }
}

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

/// Outcome of [`CalibrationRun::step`].
#[derive(Debug)]
pub enum Progress {
    Running,
    Finished(Box<CalibrationResult>),
}

/// The stage being solved.
struct ActiveStage {
    stage: Stage,
    solver: Box<dyn StageSolver>,
    iterations: usize,
    start_psi_mm2: f64,
    /// `StageStarted` is reported by the first step of the stage.
    announced: bool,
    /// The last iterate with finite, plausible parameters (kept when the stage ends `NonFinite` or
    /// `Diverged`); `None` until the first iteration.
    last_good: Option<StageParams>,
}

/// A two-step calibration in progress: the executor of the stages. Advance it with
/// [`CalibrationRun::step`] until it reports [`Progress::Finished`].
pub struct CalibrationRun {
    settings: CalibrationSettings,
    nominal: DualArmModel,
    /// The model with the parameters of the finished stages.
    committed: DualArmModel,
    inputs: PerSide<ArmData>,
    /// The joints both arms' chains hold (a torso): step 1 is then one fit of both arms (empty when
    /// one arm was measured alone).
    shared: SharedJoints,
    /// The arm measured alone, if the dataset has one arm only: its stage is the only one.
    alone: Option<Side>,
    active: Option<ActiveStage>,
    /// The stages after the active one, in order.
    plan: VecDeque<Stage>,
    /// While [`CalibrationRun::arms_at_once`] replays the right arm's iterations: the stage and its
    /// parameters at the iteration replayed ([`CalibrationRun::current_model`] shows them).
    replaying: Option<(Stage, StageParams)>,
    history: Vec<IterationRecord>,
    stages: Vec<StageSummary>,
    identifiability: PerSide<Option<IdentifiabilityReport>>,
    /// The identifiability analysis repeated at each arm's solution.
    identifiability_at_solution: PerSide<Option<IdentifiabilityReport>>,
    /// What went wrong and where, for the warnings (divergence, non-finite values, new dependencies).
    diagnostics: Vec<String>,
    /// The reflector of each arm's single-reflector fit.
    reflector_used: PerSide<Option<Reflector>>,
    /// Each arm's base in the tracker frame, where the method identified it.
    tracker_from_base: PerSide<Option<Isometry3<f64>>>,
    /// Why step 2 is not in the plan (see [`CalibrationResult::base_not_measurable`]).
    base_not_measurable: Option<String>,
    cancel: Arc<AtomicBool>,
    started: Instant,
}

impl CalibrationRun {
    fn new(
        dataset: &Dataset,
        nominal: &DualArmModel,
        settings: CalibrationSettings,
        cancel: Arc<AtomicBool>,
    ) -> Result<Self, CalibrationError> {
        check_settings(&settings)?;
        // The model the settings ask for: the nominal geometry with their error terms at the start
        // values (its figures are the geometric model's exactly), or without any.
        let with_terms;
        let nominal = if nominal.error_terms() != settings.model {
            let gravity = settings
                .gravity_in_left_base
                .map_or(-nalgebra::Vector3::z(), nalgebra::Vector3::from);
            with_terms = DualArmModel {
                arms: nominal.arms.as_ref().map(|_, a| a.geometric()),
                left_base_from_right_base: nominal.left_base_from_right_base,
            }
            .with_error_terms(settings.model, gravity)
            .with_gear_ratios(&settings.gear_ratios)
            .with_held_masses(&settings.held_masses)
            .with_torso_instants(&dataset.instants());
            &with_terms
        } else if !settings.model.is_geometric() {
            // Already the model asked for: its torso hinges take this dataset's instants.
            with_terms = nominal.clone().with_torso_instants(&dataset.instants());
            &with_terms
        } else {
            nominal
        };
        let inputs = PerSide::try_from_fn(|side| {
            if dataset.arm(side).is_measured() {
                arm_input(dataset, nominal, side, &settings)
            } else {
                Ok(ArmData::none(side))
            }
        })?;
        let base_not_measurable = dataset.base_not_measurable().or_else(|| {
            settings.hold_kinematics.then(|| {
                "the kinematics are held: only the tracker frame and reflectors are fitted".into()
            })
        });
        // With one arm measured alone its chain is fitted whole, torso included (the other arm's
        // copy of the torso follows it when the stage ends).
        let shared = if dataset.both_measured() {
            nominal.shared_joints()
        } else {
            SharedJoints::default()
        };
        let alone = alone_arm(dataset);
        if !shared.is_empty() && settings.method.spec().tree_set_up.is_none() {
            return Err(unsupported(&shared, settings.method));
        }
        let mut plan = VecDeque::from(planned_stages(dataset, nominal));
        if settings.hold_kinematics {
            plan.retain(|s| *s != Stage::Base);
        }
        Ok(Self {
            settings,
            nominal: nominal.clone(),
            committed: nominal.clone(),
            inputs,
            shared,
            alone,
            active: None,
            plan,
            base_not_measurable,
            replaying: None,
            history: Vec::new(),
            stages: Vec::new(),
            identifiability: PerSide::default(),
            identifiability_at_solution: PerSide::default(),
            diagnostics: Vec::new(),
            reflector_used: PerSide::default(),
            tracker_from_base: PerSide::default(),
            cancel,
            started: Instant::now(),
        })
    }

    /// Set the plan's next stage up (the first, when the run has not started).
    fn start_next(&mut self) -> Result<(), CalibrationError> {
        if let Some(stage) = self.plan.pop_front() {
            self.active = Some(self.start_stage(stage)?);
        }
        Ok(())
    }

    /// The flag that cancels this run (set it from anywhere; the next step ends the run).
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }

    /// Cancel the run: the next [`CalibrationRun::step`] ends it with the model reached.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// The stage that the next step advances (`None` when finished).
    pub fn stage(&self) -> Option<Stage> {
        self.active.as_ref().map(|a| a.stage)
    }

    /// The identifiability analysis of `side`'s step-1 stage at its start (`None` before it, or for a
    /// method without one).
    pub fn identifiability(&self, side: Side) -> Option<&IdentifiabilityReport> {
        self.identifiability[side].as_ref()
    }

    /// Outer iterations done in the current stage.
    pub fn stage_iterations(&self) -> usize {
        self.active.as_ref().map_or(0, |a| a.iterations)
    }

    /// The iterations so far, all stages.
    pub fn history(&self) -> &[IterationRecord] {
        &self.history
    }

    /// The model as it stands: the finished stages' parameters and the current stage's iterate.
    pub fn current_model(&self) -> DualArmModel {
        let mut model = self.committed.clone();
        if let Some((stage, params)) = &self.replaying {
            apply(&mut model, *stage, params.clone());
        } else if let Some(active) = &self.active {
            apply(&mut model, active.stage, active.solver.current());
        }
        model
    }

    /// Advance one outer iteration of the current stage, reporting to `observers`. When a stage ends
    /// the next one is set up; when the last ends — or the run is cancelled — the result is returned.
    pub fn step(
        &mut self,
        observers: &mut [&mut dyn Observer],
    ) -> Result<Progress, CalibrationError> {
        let Some(mut active) = self.active.take() else {
            return Ok(Progress::Finished(Box::new(self.result())));
        };
        if !active.announced {
            active.announced = true;
            let (n_configs, n_pairs) = self.stage_size(active.stage);
            for o in observers.iter_mut() {
                o.stage_started(active.stage, n_configs, n_pairs);
            }
        }
        let cancel = self.cancel.clone();
        let stop = move || cancel.load(Ordering::Relaxed);
        let state = if stop() {
            None
        } else {
            Some(active.solver.next_iter(&stop))
        };
        let termination = match state {
            None => Some(Termination::Cancelled),
            Some(state) if state.termination == Some(Termination::Cancelled) => {
                Some(Termination::Cancelled)
            }
            Some(state) => {
                active.iterations += 1;
                let psi_mm2 = max_of(&state.f_mm2);
                let params = active.solver.current();
                if !psi_mm2.is_finite() || !state.step_norm.is_finite() || !params_finite(&params) {
                    self.diagnostics.push(format!(
                        "{}: non-finite value at iteration {} (ψ = {psi_mm2}, step norm = {}); \
                         the parameters are those of the last finite iterate",
                        active.stage, active.iterations, state.step_norm
                    ));
                    return self.finish_stage(active, Termination::NonFinite, observers);
                }
                if let Some(why) = self.implausible(active.stage, &params) {
                    self.diagnostics.push(format!(
                        "{} diverged at iteration {}: {why}; the parameters are those of the last \
                         plausible iterate (are the measurements those of this robot? see \
                         `dualcal` quality flags)",
                        active.stage, active.iterations
                    ));
                    return self.finish_stage(active, Termination::Diverged, observers);
                }
                active.last_good = Some(params);
                let record = IterationRecord {
                    stage: active.stage,
                    iteration: active.iterations,
                    psi_mm2,
                    f_mm2: state.f_mm2,
                    step_norm: state.step_norm,
                    optimality_residual: state.residual,
                    lambda: state.lambda,
                    elapsed_secs: self.started.elapsed().as_secs_f64(),
                };
                self.history.push(record.clone());
                self.active = Some(active);
                for o in observers.iter_mut() {
                    o.iteration(&record, self);
                }
                active = self.active.take().expect("put back above");
                state
                    .termination
                    .or((active.iterations >= self.settings.max_iterations)
                        .then_some(Termination::MaxIterations))
            }
        };
        let Some(termination) = termination else {
            self.active = Some(active);
            return Ok(Progress::Running);
        };
        self.finish_stage(active, termination, observers)
    }

    /// Commit a finished stage, report it, and start the next one (none after a cancel).
    fn finish_stage(
        &mut self,
        mut active: ActiveStage,
        termination: Termination,
        observers: &mut [&mut dyn Observer],
    ) -> Result<Progress, CalibrationError> {
        let params = match termination {
            // The solver's iterate is broken or implausible: keep the last good one (or the start).
            Termination::NonFinite | Termination::Diverged => active.last_good.take(),
            _ => Some(active.solver.current()),
        };
        let f_mm2 = match termination {
            Termination::NonFinite | Termination::Diverged => {
                vec![f64::NAN; self.committed.arm(Side::Left).reflector_count()]
            }
            _ => active.solver.objectives_mm2(),
        };
        if let Some(params) = params {
            apply(&mut self.committed, active.stage, params);
            if let Some(side) = self.alone {
                self.committed = follow_torso(&self.committed, side);
            }
            if active.stage == Stage::Base && !self.shared.is_empty() {
                // Both arms start at one link: the base correction is how the right arm sits on the
                // shared joints.
                self.committed = self
                    .shared
                    .fold_base(&self.committed, &self.nominal.left_base_from_right_base);
            }
            let frames = active.solver.tracker_frames();
            for side in Side::BOTH {
                let identified = match active.stage {
                    Stage::Arm(s) => s == side,
                    Stage::Arms | Stage::Base => true,
                };
                if identified && frames[side].is_some() {
                    self.tracker_from_base[side] = frames[side];
                }
            }
        }
        let f_mm2 = if f_mm2.iter().all(|f| f.is_finite()) {
            f_mm2
        } else {
            self.stage_objectives(active.stage)
        };
        // The distance analysis at the solution, for the methods that fit distances.
        if let Stage::Arm(side) = active.stage
            && termination != Termination::Cancelled
            && !self.settings.method.is_absolute()
        {
            self.recheck_identifiability(side);
        }
        let summary = StageSummary {
            stage: active.stage,
            n_configs: self.stage_size(active.stage).0,
            iterations: active.iterations,
            termination,
            psi_mm2: max_of(&f_mm2),
            f_mm2,
            psi_start_mm2: active.start_psi_mm2,
        };
        self.stages.push(summary.clone());
        for o in observers.iter_mut() {
            o.stage_finished(&summary, self);
        }
        let next = if termination == Termination::Cancelled {
            None
        } else {
            self.plan.pop_front()
        };
        match next {
            Some(stage) => {
                self.active = Some(self.start_stage(stage)?);
                Ok(Progress::Running)
            }
            None => Ok(Progress::Finished(Box::new(self.result()))),
        }
    }

    /// (configurations, pairs per reflector) of a stage.
    fn stage_size(&self, stage: Stage) -> (usize, usize) {
        match stage {
            Stage::Arm(side) => {
                let n = self.inputs[side].qs.len();
                (n, n * n.saturating_sub(1) / 2)
            }
            Stage::Arms => {
                let (l, r) = (self.inputs.left.qs.len(), self.inputs.right.qs.len());
                (
                    l + r,
                    l * l.saturating_sub(1) / 2 + r * r.saturating_sub(1) / 2,
                )
            }
            Stage::Base => {
                let (l, r) = (self.inputs.left.qs.len(), self.inputs.right.qs.len());
                (l + r, l * r)
            }
        }
    }

    /// Set a stage up by the chosen method's entry of the table.
    fn start_stage(&mut self, stage: Stage) -> Result<ActiveStage, CalibrationError> {
        let solver = match stage {
            Stage::Arm(side) => {
                let set_up = ArmSetUp {
                    data: &self.inputs[side],
                    start: self.nominal.arm(side),
                    settings: &self.settings,
                };
                let arm = (self.settings.method.spec().set_up)(&set_up)?;
                self.identifiability[side] = Some(arm.identifiability);
                self.reflector_used[side] = arm.reflector;
                arm.solver
            }
            Stage::Arms => {
                let method = self.settings.method;
                let tree_set_up = method
                    .spec()
                    .tree_set_up
                    .ok_or_else(|| unsupported(&self.shared, method))?;
                let set_up = TreeSetUp {
                    data: &self.inputs,
                    start: &self.nominal,
                    shared: &self.shared,
                    settings: &self.settings,
                };
                let tree = tree_set_up(&set_up)?;
                for (side, report) in tree.identifiability.into_iter() {
                    self.identifiability[side] = Some(report);
                }
                tree.solver
            }
            Stage::Base => {
                let set_up = BaseSetUp {
                    data: &self.inputs,
                    model: &self.committed,
                    settings: &self.settings,
                };
                (self.settings.base_method.spec().set_up)(&set_up)?
            }
        };
        Ok(ActiveStage {
            stage,
            start_psi_mm2: max_of(&solver.objectives_mm2()),
            solver,
            iterations: 0,
            announced: false,
            last_good: None,
        })
    }

    /// Why step-1 parameters are implausible (moved too far from the nominal model), if they are.
    fn implausible(&self, stage: Stage, params: &StageParams) -> Option<String> {
        match (stage, params) {
            (Stage::Arm(side), StageParams::Arm(arm)) => self.implausible_arm(side, arm),
            (Stage::Arms, StageParams::Arms(arms)) => Side::BOTH
                .into_iter()
                .find_map(|side| self.implausible_arm(side, &arms[side])),
            _ => None,
        }
    }

    /// Why one arm's step-1 parameters are implausible, if they are.
    fn implausible_arm(&self, side: Side, arm: &ArmModel) -> Option<String> {
        let now = arm.to_vector();
        let nominal = self.nominal.arm(side).to_vector();
        // The geometry and reflectors (the error terms have no nominal value to stray from).
        (0..arm.error_offset().min(nominal.len())).find_map(|k| {
            let moved = (now[k] - nominal[k]).abs();
            let (limit, unit) = if arm.param_is_angle(k) {
                (super::DIVERGED_ANGLE_RAD, "rad")
            } else {
                (super::DIVERGED_LENGTH_MM, "mm")
            };
            (moved > limit).then(|| {
                format!(
                    "{} moved {moved:.3} {unit} from its nominal value (more than {limit} {unit})",
                    arm.param_name(k)
                )
            })
        })
    }

    /// F_a, F_b, F_c of the committed model on a stage's data, mm² (for a stage whose solver state is
    /// unusable).
    fn stage_objectives(&self, stage: Stage) -> Vec<f64> {
        match stage {
            Stage::Arm(side) => self.inputs[side]
                .distance_probe(self.committed.arm(side))
                .start_objectives_mm2(),
            Stage::Arms => {
                let mut f = vec![0.0; self.committed.arm(Side::Left).reflector_count()];
                for side in Side::BOTH {
                    let arm = self.inputs[side].distance_probe(self.committed.arm(side));
                    for (fk, v) in f.iter_mut().zip(arm.start_objectives_mm2()) {
                        *fk += v;
                    }
                }
                f
            }
            Stage::Base => vec![f64::NAN; self.committed.arm(Side::Left).reflector_count()],
        }
    }

    /// Repeat the identifiability analysis at `side`'s solution: a parameter that was identifiable at
    /// the start but is (nearly) dependent there is poorly determined by the data at the answer.
    fn recheck_identifiability(&mut self, side: Side) {
        let Some(start) = &self.identifiability[side] else {
            return;
        };
        let arm = self.committed.arm(side);
        let input = &self.inputs[side];
        // The start's sample of pairs at the solution; one Gram product (the verdicts are the QR's).
        let at_solution = identifiability::at_solution(
            arm,
            &input.qs,
            &start.free,
            IDENTIFIABILITY_PAIRS,
            identifiability::GramMethod::Product,
        );
        let allowed = |k: usize| start.free.contains(&k);
        let before = start.condition_after;
        for f in &at_solution.fixed {
            if allowed(f.index) {
                self.diagnostics.push(format!(
                    "step 1 ({side} arm): at the solution {} is no longer identifiable from these \
                     configurations ({}); its value is poorly determined",
                    f.name, f.reason
                ));
            }
        }
        let after = at_solution.condition_after;
        if after.is_finite() && before.is_finite() && after > CONDITION_GROWTH * before {
            self.diagnostics.push(format!(
                "step 1 ({side} arm): the scaled Jacobian's condition number grew from {before:.3e} at \
                 the start to {after:.3e} at the solution; the identified parameters are sensitive to \
                 measurement errors"
            ));
        }
        self.identifiability_at_solution[side] = Some(at_solution);
    }

    fn result(&self) -> CalibrationResult {
        CalibrationResult {
            nominal: self.nominal.clone(),
            calibrated: self.committed.clone(),
            settings: self.settings.clone(),
            history: self.history.clone(),
            stages: self.stages.clone(),
            identifiability: self.identifiability.clone(),
            identifiability_at_solution: self.identifiability_at_solution.clone(),
            diagnostics: self.diagnostics.clone(),
            side_tolerance_mm: self.inputs.as_ref().map(|_, i| i.side_tolerance_mm),
            reflector_used: self.reflector_used,
            tracker_from_base: self.tracker_from_base,
            base_not_measurable: self.base_not_measurable.clone(),
            alone: self.alone,
            elapsed_secs: self.started.elapsed().as_secs_f64(),
        }
    }
}

/// The refusal of a method without a fit of both arms on a robot whose arms share `shared`.
fn unsupported(shared: &SharedJoints, method: Method) -> CalibrationError {
    CalibrationError::SharedJointsUnsupported {
        joints: shared
            .names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", "),
        method,
    }
}

/// Settings that cannot work together are refused before any work.
fn check_settings(settings: &CalibrationSettings) -> Result<(), CalibrationError> {
    if settings.hold_kinematics && !settings.method.is_absolute() {
        return Err(CalibrationError::InvalidSettings(format!(
            "holding the kinematics (fitting only the tracker frame and the reflectors) needs a \
             method that identifies the tracker frame (`position` or `pose`), not `{}`",
            settings.method.name()
        )));
    }
    if let Some(r) = settings.reflector
        && !settings.method.spec().takes_reflector
    {
        let takers = Method::ALL
            .iter()
            .filter(|m| m.spec().takes_reflector)
            .map(|m| format!("`{}`", m.name()))
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(CalibrationError::InvalidSettings(format!(
            "a reflector ({r}) can only be chosen for method {takers}; `{}` uses all three",
            settings.method.name()
        )));
    }
    Ok(())
}

/// The selected split of one arm, checked.
fn arm_input(
    dataset: &Dataset,
    nominal: &DualArmModel,
    side: Side,
    settings: &CalibrationSettings,
) -> Result<ArmData, CalibrationError> {
    let ms: Vec<&crate::dataset::Measurement> = dataset
        .arm(side)
        .measurements
        .iter()
        .enumerate()
        .filter(|(i, m)| {
            settings.split.contains(m.split) && !settings.exclude.contains(&ConfigId::new(side, *i))
        })
        .map(|(_, m)| m)
        .collect();
    let params = super::identifiable_params(nominal.arm(side));
    let needed = settings.method.min_configurations(nominal.arm(side));
    if ms.len() < needed {
        return Err(CalibrationError::TooFewConfigurations {
            side,
            found: ms.len(),
            needed,
            params,
            method: settings.method,
        });
    }
    let expected = nominal.arm(side).joint_count();
    if let Some(m) = ms.iter().find(|m| m.q_rad.len() != expected) {
        return Err(CalibrationError::JointCount {
            side,
            id: m.id.clone(),
            found: m.q_rad.len(),
            expected,
        });
    }
    let qs: Vec<Vec<f64>> = ms.iter().map(|m| m.q_rad.clone()).collect();
    let reflectors = nominal.arm(side).reflector_count();
    if let Some(m) = ms.iter().find(|m| m.tracker_points_mm.len() != reflectors) {
        return Err(CalibrationError::InvalidSettings(format!(
            "{side} arm: configuration `{}` has {} reflector positions, the model has {reflectors} \
             reflectors",
            m.id,
            m.tracker_points_mm.len()
        )));
    }
    let measured: Vec<Vec<Vector3<f64>>> = ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
    if qs
        .iter()
        .flatten()
        .chain(measured.iter().flatten().flat_map(|v| v.iter()))
        .any(|v| !v.is_finite())
    {
        return Err(CalibrationError::NonFinite {
            stage: Stage::Arm(side),
            detail: "measurement data".into(),
        });
    }
    // ε of constraint (14): the tracker's MPE at the mean measuring distance, squared.
    let mean_dist_m = measured.iter().flatten().map(|p| p.norm()).sum::<f64>()
        / (reflectors as f64 * measured.len() as f64)
        / 1000.0;
    let side_tolerance_mm =
        (dataset.tracker.mpe_um + dataset.tracker.mpe_um_per_m * mean_dist_m) / 1000.0;
    Ok(ArmData {
        side,
        ids: ms.iter().map(|m| m.id.clone()).collect(),
        qs,
        measured,
        side_tolerance_mm,
    })
}

/// The step-1 method a calibration of `dataset` uses unless told otherwise: the paper's minimax on
/// distances, or the absolute positions ([`Method::Position`]) where the data call for it
/// ([`default_method_reason`]).
pub fn default_method(dataset: &Dataset) -> Method {
    if default_method_reason(dataset).is_some() {
        Method::Position
    } else {
        Method::Minimax
    }
}

/// Why [`default_method`] is the absolute positions for `dataset`, if it is: one marker per hand and
/// both hands measured together in one tracker frame (a motion-capture camera, as DLR's data) —
/// distances of one marker see a third of what three do and nothing of the camera frame, which the
/// absolute positions identify with the arms.
pub fn default_method_reason(dataset: &Dataset) -> Option<&'static str> {
    (dataset.reflector_count() == 1 && dataset.measured_together && dataset.one_tracker_frame())
        .then_some(
            "one marker per hand, both measured together in one tracker frame: the absolute \
             positions, the camera frame identified with the arms",
        )
}

/// The arm measured alone, when `dataset` has one arm only.
fn alone_arm(dataset: &Dataset) -> Option<Side> {
    match dataset.measured_sides().as_slice() {
        [side] => Some(*side),
        _ => None,
    }
}

/// The stages a calibration of `dataset` from `nominal` runs, in order: each arm's step 1 (one stage
/// of both where their chains share joints; the one arm's where one arm was measured alone), then
/// step 2 unless the data cannot measure the base ([`Dataset::base_not_measurable`]).
pub fn planned_stages(dataset: &Dataset, nominal: &DualArmModel) -> Vec<Stage> {
    let mut plan = match alone_arm(dataset) {
        Some(side) => vec![Stage::Arm(side)],
        None if nominal.shared_joints().is_empty() => {
            vec![Stage::Arm(Side::Left), Stage::Arm(Side::Right)]
        }
        None => vec![Stage::Arms],
    };
    if dataset.base_not_measurable().is_none() {
        plan.push(Stage::Base);
    }
    plan
}

/// `model` with the other arm's copy of the joints both chains hold (a torso) corrected as `side`'s
/// (the arm measured alone), so that the robot has one torso. Unchanged without shared joints.
fn follow_torso(model: &DualArmModel, side: Side) -> DualArmModel {
    let shared = model.shared_joints();
    if shared.is_empty() {
        return model.clone();
    }
    let mut out = model.clone();
    if model.is_one_arm() {
        // A single-arm robot: the other "arm" is the same chain; it is the arm calibrated.
        *out.arm_mut(side.other()) = model.arm(side).clone();
        return out;
    }
    let x = model.arm(side).to_vector();
    let mut other = model.arm(side.other()).to_vector();
    for &(a, b) in &shared.params {
        let (from, to) = match side {
            Side::Left => (a, b),
            Side::Right => (b, a),
        };
        other[to] = x[from];
    }
    *out.arm_mut(side.other()) = model.arm(side.other()).with_vector(&other);
    out
}

/// Put a stage's parameters into `model`.
fn apply(model: &mut DualArmModel, stage: Stage, params: StageParams) {
    match (stage, params) {
        (Stage::Arm(side), StageParams::Arm(arm)) => *model.arm_mut(side) = *arm,
        (Stage::Arms, StageParams::Arms(arms)) => model.arms = *arms,
        (_, StageParams::Base(base)) => model.left_base_from_right_base = base,
        (stage, _) => debug_assert!(false, "{stage} does not identify these parameters"),
    }
}

/// Are all of a stage's parameters finite?
fn params_finite(params: &StageParams) -> bool {
    match params {
        StageParams::Arm(arm) => arm.to_vector().iter().all(|v| v.is_finite()),
        StageParams::Arms(arms) => arms
            .iter()
            .all(|(_, arm)| arm.to_vector().iter().all(|v| v.is_finite())),
        StageParams::Base(b) => {
            b.translation.vector.iter().all(|v| v.is_finite())
                && b.rotation.coords.iter().all(|v| v.is_finite())
        }
    }
}

/// A condition number at the solution this many times the start's is reported.
pub const CONDITION_GROWTH: f64 = 10.0;

fn max_of(f: &[f64]) -> f64 {
    f.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}
