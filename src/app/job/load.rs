//! Loading a dataset with its robot ([`LoadWork`]): on success the new session replaces the current
//! one (and the jobs of the old one are dropped); on failure the current one stays.

use super::{Flow, Job, JobContext, Lane, meshes};
use crate::app::session::Session;
use crate::app::task::{BackgroundTask, Step, TaskContext, Work};
use crate::source::Files;
use anyhow::Context as _;
use std::path::PathBuf;
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

    fn on_event(&mut self, cx: &mut JobContext<'_>, _: &BackgroundTask, event: LoadEvent) -> Flow {
        match event {
            Ok(loaded) => on_loaded(cx, *loaded),
            Err(message) => load_failed(cx, message),
        }
        Flow::Ended
    }

    fn on_failed(&mut self, cx: &mut JobContext<'_>, _: &BackgroundTask, message: String) {
        load_failed(cx, message);
    }
}

fn load_failed(cx: &mut JobContext<'_>, message: String) {
    cx.status
        .idle("Loading failed; the previous dataset stays, with its robot.");
    cx.errors.push(message);
}

/// Load on a background task, from `files`; on failure the error is shown and the current session
/// stays.
pub fn start(cx: &mut JobContext<'_>, dataset: PathBuf, urdf: Option<PathBuf>, files: Files) {
    let status = format!("Loading {}…", dataset.display());
    let work = LoadWork {
        dataset,
        urdf,
        files,
    };
    match cx.start_job("load", LoadJob, work) {
        Ok(()) => cx.status.idle(status),
        Err(e) => cx.errors.push(format!("cannot start loading: {e}")),
    }
}

fn on_loaded(cx: &mut JobContext<'_>, loaded: Loaded) {
    let Loaded {
        mut session,
        urdf,
        elapsed_secs,
    } = loaded;
    // A calibration and a comparison are of the dataset they ran on.
    cx.jobs.dataset_replaced();
    cx.compare.comparison = None;
    cx.compare.progress = None;
    cx.compare.adopted = None;
    cx.plan_view.dataset_replaced();
    *cx.selection = None;
    *cx.urdf_override = urdf;
    cx.viewport.reset_poses();
    cx.viewport.auto_scale(&session);
    let same_robot = cx.scene.get().is_some_and(|old| {
        old.robot_source == session.robot_source && old.robot.text == session.robot.text
    });
    if !same_robot {
        cx.viewport.frame(&session);
    }
    meshes::start(cx, &mut session, same_robot);
    let d = &session.dataset;
    let warnings = match session.robot.warnings.len() {
        0 => String::new(),
        1 => " The robot has a warning (see Robot).".into(),
        n => format!(" The robot has {n} warnings (see Robot)."),
    };
    cx.status.idle(format!(
        "Loaded {} ({} left + {} right configurations) in {elapsed_secs:.2} s.{warnings}",
        d.dir.display(),
        d.arms.left.measurements.len(),
        d.arms.right.measurements.len(),
    ));
    cx.set_session(session);
}
