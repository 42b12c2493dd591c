//! Step 1's two arms at once. The arms' stages are independent (each starts from the nominal model and
//! sees only its own arm's data), so [`Calibrator::run`](super::calibrator::Calibrator::run) solves
//! the right arm's as a job of the work pool (rayon's) while the left arm's runs on the caller's
//! thread. The right arm's events reach the
//! observers afterwards, in the order and with the models a one-stage-at-a-time run gives them: its
//! iterations follow the left arm's `stage_finished`, and `current_model` shows the left arm's result
//! with the right arm's iterate of the iteration reported. The history, the stages and the
//! diagnostics come out in the same order too; only the iterations' clock readings overlap.
//!
//! A run stepped by its caller ([`CalibrationRun::step`]: a UI frame loop, the browser) solves one
//! stage at a time as before.

use super::executor::{CalibrationRun, Observer, Progress};
use crate::side::Side;
use crate::solver::error::CalibrationError;
use crate::solver::problems::problem::StageParams;
use crate::solver::types::{IterationRecord, Stage, StageSummary, Termination};
use std::collections::VecDeque;

/// What the right arm's stage told its observer, kept for the replay.
enum Recorded {
    Started {
        n_configs: usize,
        n_pairs: usize,
    },
    Iteration {
        record: IterationRecord,
        params: Option<StageParams>,
    },
    Finished(StageSummary),
}

/// The observer of the right arm's stage: records, with the iterate of each iteration.
#[derive(Default)]
struct Recorder(Vec<Recorded>);

impl Observer for Recorder {
    fn stage_started(&mut self, _stage: Stage, n_configs: usize, n_pairs: usize) {
        self.0.push(Recorded::Started { n_configs, n_pairs });
    }

    fn iteration(&mut self, record: &IterationRecord, run: &CalibrationRun) {
        self.0.push(Recorded::Iteration {
            record: record.clone(),
            params: run.active.as_ref().map(|a| a.solver.current()),
        });
    }

    fn stage_finished(&mut self, summary: &StageSummary, _run: &CalibrationRun) {
        self.0.push(Recorded::Finished(summary.clone()));
    }
}

const RIGHT: Stage = Stage::Arm(Side::Right);

const LEFT: Stage = Stage::Arm(Side::Left);

impl CalibrationRun {
    /// Has the run not started, with the two arms' stages first in the plan, on a machine with a
    /// second core for the other one?
    fn arms_can_run_at_once(&self) -> bool {
        !cfg!(target_arch = "wasm32")
            && crate::par::current_num_threads() > 1
            && self.active.is_none()
            && self.stages.is_empty()
            && self.plan.iter().take(2).eq([LEFT, RIGHT].iter())
    }

    /// Set up and solve both arms' step-1 stages at once (see the module's documentation), reporting
    /// to `observers` as a one-stage-at-a-time run does, then set the plan's next stage up. `false`
    /// (nothing done) unless the run has not started, the arms come first in its plan and a second
    /// core is free.
    pub(super) fn arms_at_once(
        &mut self,
        observers: &mut [&mut dyn Observer],
    ) -> Result<bool, CalibrationError> {
        if !self.arms_can_run_at_once() {
            return Ok(false);
        }
        let mut right = self.fork();
        // The left arm's stage is the whole plan for now; the stages after the arms come back below.
        let rest: VecDeque<Stage> = std::mem::take(&mut self.plan).into_iter().skip(2).collect();
        let mut right_outcome = Ok(());
        let mut recorder = Recorder::default();
        // The right arm's stage is a job of the work pool (taken by an idle thread); the left arm's
        // runs on this thread. The scope ends when both have (a panic in the job is raised here).
        let left_outcome = crate::par::in_place_scope(|scope| {
            scope.spawn(|_| right_outcome = right.run_stage(RIGHT, &mut [&mut recorder]));
            self.run_stage(LEFT, observers)
        });
        // The left arm's set-up refused the data: so does a one-stage-at-a-time run, before any stage.
        left_outcome?;
        let left_cancelled = self
            .stages
            .last()
            .is_some_and(|s| s.termination == Termination::Cancelled);
        if left_cancelled {
            // A one-stage-at-a-time run would not have started the right arm.
            return Ok(true);
        }
        right_outcome?;
        let mut right_cancelled = false;
        for event in recorder.0 {
            match event {
                Recorded::Started { n_configs, n_pairs } => {
                    for o in observers.iter_mut() {
                        o.stage_started(RIGHT, n_configs, n_pairs);
                    }
                }
                Recorded::Iteration { record, params } => {
                    self.history.push(record.clone());
                    self.replaying = params.map(|p| (RIGHT, p));
                    for o in observers.iter_mut() {
                        o.iteration(&record, self);
                    }
                }
                Recorded::Finished(summary) => {
                    self.replaying = None;
                    right_cancelled = summary.termination == Termination::Cancelled;
                    self.adopt_arm(&mut right, Side::Right);
                    for o in observers.iter_mut() {
                        o.stage_finished(&summary, self);
                    }
                }
            }
        }
        self.replaying = None;
        if !right_cancelled {
            self.plan = rest;
            self.start_next()?;
        }
        Ok(true)
    }

    /// A run with this one's data, settings, start and cancel flag, and nothing done nor planned.
    fn fork(&self) -> CalibrationRun {
        CalibrationRun {
            settings: self.settings.clone(),
            nominal: self.nominal.clone(),
            committed: self.nominal.clone(),
            inputs: self.inputs.clone(),
            shared: self.shared.clone(),
            alone: self.alone,
            active: None,
            plan: VecDeque::new(),
            replaying: None,
            history: Vec::new(),
            stages: Vec::new(),
            identifiability: Default::default(),
            identifiability_at_solution: Default::default(),
            diagnostics: Vec::new(),
            weak: Default::default(),
            held: Default::default(),
            pair_sums: Default::default(),
            reflector_used: Default::default(),
            tracker_from_base: Default::default(),
            base_not_measurable: self.base_not_measurable.clone(),
            cancel: self.cancel.clone(),
            started: self.started,
        }
    }

    /// Set `stage` up and solve it (this run's plan being empty), reporting to `observers`.
    fn run_stage(
        &mut self,
        stage: Stage,
        observers: &mut [&mut dyn Observer],
    ) -> Result<(), CalibrationError> {
        self.active = Some(self.start_stage(stage)?);
        while let Progress::Running = self.step(observers)? {}
        Ok(())
    }

    /// Take `side`'s finished stage from `other`: the arm, the stage's summary, diagnostics,
    /// identifiability reports and weak parameters, the reflector used and the tracker frame.
    fn adopt_arm(&mut self, other: &mut CalibrationRun, side: Side) {
        *self.committed.arm_mut(side) = other.committed.arm(side).clone();
        self.stages.append(&mut other.stages);
        self.diagnostics.append(&mut other.diagnostics);
        self.identifiability[side] = other.identifiability[side].take();
        self.identifiability_at_solution[side] = other.identifiability_at_solution[side].take();
        self.weak[side] = std::mem::take(&mut other.weak[side]);
        self.held[side] = std::mem::take(&mut other.held[side]);
        self.pair_sums[side] = other.pair_sums[side].take();
        self.reflector_used[side] = other.reflector_used[side];
        if other.tracker_from_base[side].is_some() {
            self.tracker_from_base[side] = other.tracker_from_base[side];
        }
    }
}
