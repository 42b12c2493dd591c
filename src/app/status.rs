//! What the workbench is doing: the status line ([`Status`], written only through its owner
//! [`StatusLine`]), the error messages shown ([`Errors`], their one writer), the last run's timing ([`RunTiming`]),
//! and the state as JSON ([`StatusReport`]) for a page that embeds the workbench and for the browser
//! test (published to `#dualcal-status` by [`super::platform::publish_status`] whenever it changes):
//! what it is doing, the status line and errors, the renderer, the last run's timing and, after a
//! calibration, its parameters (`dualcal-params/1`, the same numbers "Parameters (JSON)…" exports)
//! and accuracy.

use super::session::Session;
use super::task::SliceStats;
use crate::solver::Stage;
use serde_json::{Value, json};

/// What the status bar says.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Idle(String),
    Running {
        stage: Option<Stage>,
        iteration: usize,
    },
}

/// The status line's owner, its one writer: whatever says what the workbench is doing calls it.
#[derive(Clone, Debug, PartialEq)]
pub struct StatusLine(Status);

impl StatusLine {
    pub fn new(text: impl Into<String>) -> Self {
        Self(Status::Idle(text.into()))
    }

    /// What it says.
    pub fn get(&self) -> &Status {
        &self.0
    }

    /// Idle, saying `text`.
    pub fn idle(&mut self, text: impl Into<String>) {
        self.0 = Status::Idle(text.into());
    }

    /// A calibration runs, at `iteration` of `stage` (`None`: setting up).
    pub fn running(&mut self, stage: Option<Stage>, iteration: usize) {
        self.0 = Status::Running { stage, iteration };
    }
}

/// The error messages shown (oldest first), their one writer: whatever reports an error pushes it
/// here; the user dismisses them one by one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Errors(Vec<String>);

impl Errors {
    pub fn push(&mut self, message: impl Into<String>) {
        self.0.push(message.into());
    }

    /// Remove the message at `k` (nothing if there is none).
    pub fn dismiss(&mut self, k: usize) {
        if k < self.0.len() {
            self.0.remove(k);
        }
    }

    pub fn list(&self) -> &[String] {
        &self.0
    }
}

/// How the last calibration went in time: the wall time, and (stepped in frames) the frames' work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunTiming {
    pub wall_secs: f64,
    pub slices: SliceStats,
}

/// What the JSON status is made of, borrowed from the app.
pub struct StatusReport<'a> {
    pub loading: bool,
    pub calibrating: bool,
    pub status: &'a Status,
    pub errors: &'a [String],
    /// The GPU adapter (name and backend).
    pub renderer: &'a str,
    /// Iterations of the convergence history shown (the running calibration's, else the last one's).
    pub iterations: usize,
    pub session: Option<&'a Session>,
    pub last_run: Option<RunTiming>,
}

impl StatusReport<'_> {
    /// The state as JSON (see the module documentation).
    pub fn json(&self) -> Value {
        let phase = if self.loading {
            "loading"
        } else if self.calibrating {
            "calibrating"
        } else {
            "idle"
        };
        let status = match self.status {
            Status::Idle(text) => text.clone(),
            Status::Running { stage, iteration } => match stage {
                Some(stage) => format!("Calibrating: {stage}, iteration {iteration}"),
                None => "Calibrating…".into(),
            },
        };
        let session = self.session.map(|s| {
            let d = &s.dataset;
            json!({
                "dataset": d.dir.display().to_string(),
                "robot": s.robot.name(),
                "robot_source": s.robot_source.as_ref().map(|p| p.display().to_string()),
                "robot_warnings": s.robot.warnings,
                "configurations": [d.arms.left.measurements.len(), d.arms.right.measurements.len()],
                "nominal": {
                    "cal": s.nominal.cal.report,
                    "ver": s.nominal.ver.report,
                },
                "live": s.live.as_ref().map(|l| l.label()),
            })
        });
        let calibrated = self
            .session
            .and_then(|s| Some((s, s.calibrated.as_ref()?)))
            .map(|(_, c)| {
                // The calibration's own file, made once (not per frame); the date differs from run
                // to run.
                let mut params = c.params.clone();
                params.provenance = None;
                json!({
                    "params": params,
                    "cal": c.analysis.cal.report,
                    "ver": c.analysis.ver.report,
                    "converged": c.result.is_converged(),
                    "solver_elapsed_s": c.result.elapsed_secs,
                    "solver_compute_s": c.solver_secs,
                })
            });
        let last_run = self.last_run.map(|t| {
            json!({
                "wall_s": t.wall_secs,
                "frames": t.slices.slices,
                "compute_s": t.slices.busy_secs,
                "longest_slice_ms": t.slices.longest_slice_secs * 1e3,
            })
        });
        json!({
            "phase": phase,
            "status": status,
            "errors": self.errors,
            "renderer": self.renderer,
            "iterations": self.iterations,
            "session": session,
            "calibrated": calibrated,
            "last_run": last_run,
        })
    }
}
