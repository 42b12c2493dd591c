//! Loading a dataset with its robot ([`LoadWork`]): on success the new session replaces the current
//! one (and the jobs of the old one are dropped); on failure the current one stays.

use super::super::WorkbenchApp;
use super::super::status::Status;
use super::super::work::{LoadEvent, LoadWork, Loaded};
use super::{Flow, Job, Lane};
use crate::app::task::BackgroundTask;
use std::path::PathBuf;

pub struct LoadJob;

impl LoadJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }
}

impl Job for LoadJob {
    type Event = LoadEvent;

    fn survives_load(&self) -> bool {
        // The load that ended is out of the collection; a newer one goes on.
        true
    }

    fn on_event(&mut self, app: &mut WorkbenchApp, _: &BackgroundTask, event: LoadEvent) -> Flow {
        match event {
            Ok(loaded) => app.on_loaded(*loaded),
            Err(message) => load_failed(app, message),
        }
        Flow::Ended
    }

    fn on_failed(&mut self, app: &mut WorkbenchApp, _: &BackgroundTask, message: String) {
        load_failed(app, message);
    }
}

fn load_failed(app: &mut WorkbenchApp, message: String) {
    app.status = Status::Idle("Loading failed; the previous dataset stays, with its robot.".into());
    app.errors.push(message);
}

impl WorkbenchApp {
    /// Load on a background task; on failure the error is shown and the current session stays.
    pub(in crate::app) fn start_load(&mut self, dataset: PathBuf, urdf: Option<PathBuf>) {
        let status = format!("Loading {}…", dataset.display());
        let work = LoadWork {
            dataset,
            urdf,
            files: self.input_files.clone(),
        };
        match self.start_job("load", LoadJob, work) {
            Ok(()) => self.status = Status::Idle(status),
            Err(e) => self.errors.push(format!("cannot start loading: {e}")),
        }
    }

    fn on_loaded(&mut self, loaded: Loaded) {
        let Loaded {
            mut session,
            urdf,
            elapsed_secs,
        } = loaded;
        // A calibration and a comparison are of the dataset they ran on.
        self.jobs.dataset_replaced();
        self.compare.comparison = None;
        self.compare.progress = None;
        self.compare.adopted = None;
        self.plan_view.dataset_replaced();
        self.selection = None;
        self.urdf_override = urdf;
        self.viewport.reset_poses();
        self.viewport.auto_scale(&session);
        let same_robot = self.session.as_ref().is_some_and(|old| {
            old.robot_source == session.robot_source && old.robot.text == session.robot.text
        });
        if !same_robot {
            self.viewport.frame(&session);
        }
        self.start_mesh_loading(&mut session, same_robot);
        let d = &session.dataset;
        let warnings = match session.robot.warnings.len() {
            0 => String::new(),
            1 => " The robot has a warning (see Robot).".into(),
            n => format!(" The robot has {n} warnings (see Robot)."),
        };
        self.status = Status::Idle(format!(
            "Loaded {} ({} left + {} right configurations) in {elapsed_secs:.2} s.{warnings}",
            d.dir.display(),
            d.arms.left.measurements.len(),
            d.arms.right.measurements.len(),
        ));
        self.set_session(session);
    }
}
