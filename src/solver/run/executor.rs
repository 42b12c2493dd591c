//! The executor: [`CalibrationRun`] runs the stages in turn — step 1 for the left arm, step 1 for the
//! right arm, step 2 — one outer iteration per [`CalibrationRun::step`], reporting to [`Observer`]s and
//! polling the cancel flag. It names no method: each stage is set up by the chosen method's entry of
//! the table ([`crate::solver::methods`]). Its input is checked before (`super::inputs`), and the
//! stages it plans are [`super::policy`]'s.

use super::inputs::{arm_input, check_settings, unsupported};
use super::policy::{alone_arm, planned_stages};
use crate::dataset::Dataset;
use crate::kinematics::{ArmModel, DualArmModel, SharedJoints};
use crate::side::{PerSide, Side};
use crate::solver::algorithms::stage::StageSolver;
use crate::solver::analysis::identifiability::{self, IdentifiabilityReport};
use crate::solver::analysis::uncertainty::PairSums;
use crate::solver::analysis::weak::{WeakParameter, weak_parameters_of};
use crate::solver::error::CalibrationError;
use crate::solver::methods::set_up::{ArmData, ArmSetUp, BaseSetUp, TreeSetUp};
use crate::solver::problems::problem::StageParams;
use crate::solver::result::CalibrationResult;
use crate::solver::settings::CalibrationSettings;
use crate::solver::types::{
    CalibrationEvent, DIVERGED_ANGLE_RAD, DIVERGED_LENGTH_MM, IterationRecord, Reflector, Stage,
    StageSummary, Termination,
};
use nalgebra::Isometry3;
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
// std's `Instant::now` panics in a browser (wasm32-unknown-unknown); web-time is std's on native targets.
use web_time::Instant;

/// Watches a run. Every method defaults to doing nothing; a closure over [`CalibrationEvent`] is an
/// observer too. The command line's progress lines, the workbench's live curves and the tests are
/// observers.
///
/// What a run reports as it goes. `Send`: [`Calibrator::run`](crate::solver::Calibrator::run) moves the run onto a thread of the work
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

/// Outcome of [`CalibrationRun::step`].
#[derive(Debug)]
pub enum Progress {
    Running,
    Finished(Box<CalibrationResult>),
}

/// The stage being solved.
pub(super) struct ActiveStage {
    pub(super) stage: Stage,
    pub(super) solver: Box<dyn StageSolver>,
    pub(super) iterations: usize,
    start_psi_mm2: f64,
    /// `StageStarted` is reported by the first step of the stage.
    pub(super) announced: bool,
    /// The last iterate with finite, plausible parameters (kept when the stage ends `NonFinite` or
    /// `Diverged`); `None` until the first iteration.
    pub(super) last_good: Option<StageParams>,
    /// The iterations before the weak parameters were held (the stage solved again from the start:
    /// [`CalibrationRun::hold_weak`]); the iteration limit counts those after.
    pub(super) before_hold: usize,
    /// The run's diagnostics when the stage started (a stage solved again drops its first solve's).
    pub(super) diagnostics_at_start: usize,
}

/// A two-step calibration in progress: the executor of the stages. Advance it with
/// [`CalibrationRun::step`] until it reports [`Progress::Finished`].
pub struct CalibrationRun {
    pub(super) settings: CalibrationSettings,
    pub(super) nominal: DualArmModel,
    /// The model with the parameters of the finished stages.
    pub(super) committed: DualArmModel,
    pub(super) inputs: PerSide<ArmData>,
    /// The joints both arms' chains hold (a torso): step 1 is then one fit of both arms (empty when
    /// one arm was measured alone).
    pub(super) shared: SharedJoints,
    /// The arm measured alone, if the dataset has one arm only: its stage is the only one.
    pub(super) alone: Option<Side>,
    pub(super) active: Option<ActiveStage>,
    /// The stages after the active one, in order.
    pub(super) plan: VecDeque<Stage>,
    /// While [`CalibrationRun::arms_at_once`] replays the right arm's iterations: the stage and its
    /// parameters at the iteration replayed ([`CalibrationRun::current_model`] shows them).
    pub(super) replaying: Option<(Stage, StageParams)>,
    pub(super) history: Vec<IterationRecord>,
    pub(super) stages: Vec<StageSummary>,
    pub(super) identifiability: PerSide<Option<IdentifiabilityReport>>,
    /// The identifiability analysis repeated at each arm's solution.
    pub(super) identifiability_at_solution: PerSide<Option<IdentifiabilityReport>>,
    /// What went wrong and where, for the warnings (divergence, non-finite values, new dependencies).
    pub(super) diagnostics: Vec<String>,
    /// Each arm's weak parameters ([`crate::solver::weak`]), found at its step-1 solution.
    pub(super) weak: PerSide<Vec<WeakParameter>>,
    /// Each arm's parameters held at their nominal values as weak (step 1 solved again without them).
    pub(super) held: PerSide<Vec<usize>>,
    /// Each arm's pair sums at its step-1 solution, from the weak-parameter analysis (`None` where it
    /// did not run, or held parameters and the arm was solved again).
    pub(super) pair_sums: PerSide<Option<Arc<PairSums>>>,
    /// The reflector of each arm's single-reflector fit.
    pub(super) reflector_used: PerSide<Option<Reflector>>,
    /// Each arm's base in the tracker frame, where the method identified it.
    pub(super) tracker_from_base: PerSide<Option<Isometry3<f64>>>,
    /// Why step 2 is not in the plan (see [`CalibrationResult::base_not_measurable`]).
    pub(super) base_not_measurable: Option<String>,
    pub(super) cancel: Arc<AtomicBool>,
    pub(super) started: Instant,
}

impl CalibrationRun {
    pub(super) fn new(
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
            weak: PerSide::default(),
            held: PerSide::default(),
            pair_sums: PerSide::default(),
            reflector_used: PerSide::default(),
            tracker_from_base: PerSide::default(),
            cancel,
            started: Instant::now(),
        })
    }

    /// Set the plan's next stage up (the first, when the run has not started).
    pub(super) fn start_next(&mut self) -> Result<(), CalibrationError> {
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

    /// The pair sums of `side`'s step-1 fit at its solution (its free parameters, the configurations it
    /// fitted), as the identifiability re-check and the weak-parameter analysis took them: a method's
    /// uncertainty of that arm starts from them ([`crate::solver::uncertainty::PairSums::matches`] says
    /// whether they are the arm's). `None` before the arm's stage ends, for the methods that do not
    /// fit distances, and while the arm is solved again with held parameters.
    pub fn pair_sums(&self, side: Side) -> Option<Arc<PairSums>> {
        self.pair_sums[side].clone()
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
                state.termination.or((active.iterations - active.before_hold
                    >= self.settings.max_iterations)
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
        // The distance analyses at the solution, for the methods that fit distances: one pass of pair
        // sums for the identifiability re-check, the weak parameters and the uncertainty.
        let sums = match active.stage {
            Stage::Arm(side)
                if termination != Termination::Cancelled && !self.settings.method.is_absolute() =>
            {
                self.solution_sums(side)
            }
            _ => None,
        };
        if let (Stage::Arm(side), Some(sums)) = (active.stage, &sums) {
            self.recheck_identifiability(side, sums);
        }
        if let (Stage::Arm(side), Some(sums)) = (active.stage, sums)
            && self.hold_weak(side, sums)
        {
            // Solved again from the nominal model with the weak parameters held; one stage to the
            // observers, its iterations counted on.
            let mut again = self.start_stage(active.stage)?;
            again.announced = true;
            again.iterations = active.iterations;
            again.before_hold = active.iterations;
            again.start_psi_mm2 = active.start_psi_mm2;
            again.diagnostics_at_start = active.diagnostics_at_start;
            self.diagnostics.truncate(active.diagnostics_at_start);
            self.active = Some(again);
            return Ok(Progress::Running);
        }
        let summary = StageSummary {
            stage: active.stage,
            n_configs: self.stage_size(active.stage).0,
            iterations: active.iterations,
            termination,
            psi_mm2: max_of(&f_mm2),
            f_mm2,
            psi_start_mm2: active.start_psi_mm2,
            curvature: active.solver.curvature(),
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
    pub(super) fn start_stage(&mut self, stage: Stage) -> Result<ActiveStage, CalibrationError> {
        let solver = match stage {
            Stage::Arm(side) => {
                let set_up = ArmSetUp {
                    data: &self.inputs[side],
                    start: self.nominal.arm(side),
                    options: self.settings.stage_options(),
                    held: &self.held[side],
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
                    options: self.settings.stage_options(),
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
                    options: self.settings.stage_options(),
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
            before_hold: 0,
            diagnostics_at_start: self.diagnostics.len(),
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
                (DIVERGED_ANGLE_RAD, "rad")
            } else {
                (DIVERGED_LENGTH_MM, "mm")
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

    /// `side`'s pair sums at its solution over the parameters its start left free (`None` without a
    /// start analysis).
    fn solution_sums(&self, side: Side) -> Option<PairSums> {
        let start = self.identifiability[side].as_ref()?;
        let input = &self.inputs[side];
        let arm = self.committed.arm(side);
        Some(PairSums::new(arm, &input.qs, &input.measured, &start.free))
    }

    /// Repeat the identifiability analysis at `side`'s solution, from its pair sums there: a parameter
    /// that was identifiable at the start but is (nearly) dependent there is poorly determined by the
    /// data at the answer.
    fn recheck_identifiability(&mut self, side: Side, sums: &PairSums) {
        let Some(start) = &self.identifiability[side] else {
            return;
        };
        let Some(at_solution) =
            identifiability::at_solution_of_sums(self.committed.arm(side), sums)
        else {
            return;
        };
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

    /// Find `side`'s weak parameters at its step-1 solution from its pair sums there (the distance
    /// methods of all the reflectors); unless the settings keep them, hold them at their nominal values:
    /// `true` when the stage is to be solved again (the arm is back at its nominal model). Once per arm.
    /// The sums are kept for the arm's uncertainty unless the stage is solved again.
    fn hold_weak(&mut self, side: Side, sums: PairSums) -> bool {
        if self.reflector_used[side].is_some() || !self.held[side].is_empty() {
            self.pair_sums[side] = Some(Arc::new(sums));
            return false;
        }
        let input = &self.inputs[side];
        let arm = self.committed.arm(side);
        let mut weak = weak_parameters_of(arm, &input.qs, &sums);
        let hold = !weak.is_empty() && !self.settings.keep_weak;
        self.pair_sums[side] = (!hold).then(|| Arc::new(sums));
        if hold {
            for w in &mut weak {
                w.held = true;
            }
            self.held[side] = weak.iter().map(|w| w.index).collect();
            *self.committed.arm_mut(side) = self.nominal.arm(side).clone();
        }
        self.weak[side] = weak;
        hold
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
            weak: self.weak.clone(),
            pair_sums: self.pair_sums.clone(),
            elapsed_secs: self.started.elapsed().as_secs_f64(),
        }
    }
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
