//! Planning the measurement ([`PlanWork`]): one arm per step ([`crate::plan::plan_arm`], then its
//! predicted σ), so that in a browser the page draws between the arms. Each arm's plan goes into the
//! planning view as it arrives; an error ends the plan with its reason.

use super::{Flow, Job, JobContext, Lane};
use crate::app::plan_view::{ArmOutcome, PlanTarget};
use crate::app::task::{BackgroundTask, Step, TaskContext, Work};
use crate::plan::{PlanOptions, plan_arm};
use crate::side::Side;

/// One arm's plan, or why there is none.
pub type PlanEvent = (Side, Result<Box<ArmOutcome>, String>);

pub struct PlanWork {
    pub target: PlanTarget,
    pub options: PlanOptions,
    /// The arms still to plan.
    pub todo: Vec<Side>,
}

impl Work for PlanWork {
    type Event = PlanEvent;

    fn step(&mut self, task: &TaskContext<PlanEvent>) -> Step {
        let Some(side) = self.todo.pop() else {
            return Step::Done;
        };
        let t = &self.target;
        let outcome = plan_arm(&t.robot, &t.reflectors_mm, &self.options, side)
            .map(|plan| {
                let arm = t.robot.nominal_model(t.reflectors_mm.clone());
                let sigma = crate::solver::uncertainty::predicted_for_tracker(
                    &t.robot,
                    arm.arm(side),
                    side,
                    &plan.configs,
                    &plan.sample,
                    &t.tracker,
                    &self.options.tracker_in_body_mm,
                );
                Box::new(ArmOutcome { plan, sigma })
            })
            .map_err(|e| e.to_string());
        let failed = outcome.is_err();
        task.report((side, outcome));
        if failed || self.todo.is_empty() {
            Step::Done
        } else {
            Step::Show
        }
    }
}

pub struct PlanJob;

impl PlanJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }
}

impl Job for PlanJob {
    type Event = PlanEvent;

    fn on_event(&mut self, cx: &mut JobContext<'_>, _: &BackgroundTask, event: PlanEvent) -> Flow {
        let (side, outcome) = event;
        let view = &mut *cx.plan_view;
        match outcome {
            Ok(arm) => {
                if let Some(result) = &mut view.result {
                    result.arms[side] = Some(*arm);
                }
                let done = view
                    .result
                    .as_ref()
                    .is_some_and(|r| r.arms.left.is_some() && r.arms.right.is_some());
                cx.status.idle(if done {
                    "Plan made.".into()
                } else {
                    format!("Planning: the {side} arm is planned…")
                });
                if done { Flow::Ended } else { Flow::Running }
            }
            Err(e) => {
                view.error = Some(e);
                cx.status.idle("Planning failed (see the planning view).");
                Flow::Ended
            }
        }
    }

    fn on_failed(&mut self, cx: &mut JobContext<'_>, _: &BackgroundTask, message: String) {
        cx.plan_view.error = Some(message);
        cx.status.idle("Planning failed (see the planning view).");
    }
}

/// Plan both arms on a background task with the planning view's inputs, for the workbench's robot
/// and reflectors.
pub fn start(cx: &mut JobContext<'_>, target: PlanTarget) {
    let options = match cx.plan_view.options(&target) {
        Ok(o) => o,
        Err(e) => {
            cx.plan_view.error = Some(e);
            return;
        }
    };
    cx.plan_view.started(target.clone(), options.clone());
    let work = PlanWork {
        target,
        options,
        // Popped from the end: the left arm first.
        todo: vec![Side::Right, Side::Left],
    };
    match cx.start_job("plan", PlanJob, work) {
        Ok(()) => cx.status.idle("Planning the left arm…"),
        Err(e) => cx.plan_view.error = Some(format!("cannot start planning: {e}")),
    }
}
