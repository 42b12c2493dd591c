//! What a job may change ([`JobContext`]): handed to it with each of its work's events, and to the
//! functions that start jobs. The app lends it for the event and takes it back; a job never sees the
//! whole app.

use super::Jobs;
use crate::app::compare::CompareView;
use crate::app::events::EventSender;
use crate::app::plan_view::PlanView;
use crate::app::scene::Scene;
use crate::app::session::Session;
use crate::app::status::{Errors, RunTiming, StatusLine};
use crate::app::task::{Execution, Work};
use crate::app::viewport::ViewportState;
use crate::side::ConfigId;
use crate::solver::{CalibrationSettings, Stage};
use std::path::PathBuf;

/// The workbench's state a job reads and changes: the status line and the errors (each through its
/// one writer), the session (through its one mutator, [`Scene`]), what it needs of the settings and
/// of the views, and the jobs themselves (to start one, or drop a dataset's).
pub struct JobContext<'a> {
    pub status: &'a mut StatusLine,
    pub errors: &'a mut Errors,
    pub scene: &'a mut Scene,
    /// The calibration settings: a new dataset sets its default step-1 method until the user picks one.
    pub settings: &'a mut CalibrationSettings,
    /// Has the user picked the step-1 method?
    pub method_picked: bool,
    pub viewport: &'a mut ViewportState,
    /// The stage the convergence plots show.
    pub plot_stage: &'a mut Stage,
    pub compare: &'a mut CompareView,
    pub plan_view: &'a mut PlanView,
    pub selection: &'a mut Option<ConfigId>,
    /// The robot description used instead of the dataset's.
    pub urdf_override: &'a mut Option<PathBuf>,
    /// How the last calibration went in time.
    pub last_run: &'a mut Option<RunTiming>,
    pub jobs: &'a mut Jobs,
    pub events: &'a EventSender,
    pub execution: Execution,
}

impl JobContext<'_> {
    /// Start `work` on a background task, its events handled by `job`; the job running in the same
    /// lane is replaced.
    pub fn start_job<J: super::Job, W: Work<Event = J::Event>>(
        &mut self,
        name: &str,
        job: J,
        work: W,
    ) -> std::io::Result<()> {
        self.jobs
            .start(name, job, work, self.events, self.execution)
    }

    /// A new session replaces the current one. Until the user picks a step-1 method, it follows the
    /// data as the command line's default does (`solver::default_method`: the absolute positions for
    /// one marker per hand measured together in one frame, else minimax).
    pub fn set_session(&mut self, session: Session) {
        if !self.method_picked {
            self.settings.method = crate::solver::default_method(&session.dataset);
        }
        self.scene.replace(session);
    }
}
