//! Loading and packing the session's robot meshes ([`MeshWork`]); placeholders are drawn until they
//! arrive. It goes on when a dataset with the same robot loads.

use super::super::WorkbenchApp;
use super::super::session::{RobotMeshes, Session};
use super::super::work::{self, MeshWork};
use super::{Flow, Job, Lane};
use crate::app::session::LoadedMeshes;
use crate::app::task::BackgroundTask;
use std::sync::Arc;

pub struct MeshJob;

impl MeshJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }
}

impl Job for MeshJob {
    type Event = Box<LoadedMeshes>;

    fn survives_load(&self) -> bool {
        // [`WorkbenchApp::start_mesh_loading`] decides.
        true
    }

    fn on_event(
        &mut self,
        app: &mut WorkbenchApp,
        _: &BackgroundTask,
        loaded: Box<LoadedMeshes>,
    ) -> Flow {
        set_meshes(app, RobotMeshes::Loaded(Arc::new(*loaded)));
        Flow::Ended
    }

    fn on_failed(&mut self, app: &mut WorkbenchApp, _: &BackgroundTask, message: String) {
        set_meshes(app, RobotMeshes::Failed(message));
    }
}

fn set_meshes(app: &mut WorkbenchApp, meshes: RobotMeshes) {
    if let Some(session) = app.scene_mut() {
        session.meshes = meshes;
    }
}

impl WorkbenchApp {
    /// Load the new session's robot meshes on a background task (placeholders are drawn until they
    /// arrive); the same robot as before keeps its meshes.
    pub(in crate::app) fn start_mesh_loading(&mut self, session: &mut Session, same_robot: bool) {
        if same_robot && let Some(old) = &self.session {
            session.meshes = old.meshes.clone();
            if self.jobs.is_running(MeshJob::lane()) {
                // Still loading for the previous session: the event updates the new one.
                return;
            }
            if !matches!(session.meshes, RobotMeshes::Failed(_)) {
                return;
            }
        }
        self.jobs.stop(MeshJob::lane());
        if !work::has_visual_meshes(&session.robot) {
            session.meshes = RobotMeshes::None;
            return;
        }
        let work = MeshWork {
            robot: session.robot.clone(),
        };
        match self.start_job("meshes", MeshJob, work) {
            Ok(()) => session.meshes = RobotMeshes::Loading,
            Err(e) => session.meshes = RobotMeshes::Failed(format!("cannot start loading: {e}")),
        }
    }
}
