//! The workbench's state as JSON, for a page that embeds it and for the browser test (published to
//! `#dualcal-status` by [`super::platform::publish_status`] whenever it changes): what it is doing,
//! the status line and errors, the renderer, the last run's timing and, after a calibration, its
//! parameters (`dualcal-params/1`, the same numbers "Parameters (JSON)…" exports) and accuracy.

use super::{Status, WorkbenchApp};
use serde_json::{Value, json};

impl WorkbenchApp {
    /// The state as JSON (see the module documentation).
    pub fn status_json(&self) -> Value {
        let phase = if self.is_loading() {
            "loading"
        } else if self.is_calibrating() {
            "calibrating"
        } else {
            "idle"
        };
        let status = match &self.status {
            Status::Idle(text) => text.clone(),
            Status::Running { stage, iteration } => match stage {
                Some(stage) => format!("Calibrating: {stage}, iteration {iteration}"),
                None => "Calibrating…".into(),
            },
        };
        let session = self.session.as_ref().map(|s| {
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
            .as_ref()
            .and_then(|s| Some((s, s.calibrated.as_ref()?)))
            .map(|(s, c)| {
                let mut params = crate::params::ParamsFile::from_calibration(&c.result, &s.dataset);
                // The date differs from run to run.
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
            "iterations": self.history.len(),
            "session": session,
            "calibrated": calibrated,
            "last_run": last_run,
        })
    }

    /// Publish the state when it changed.
    pub(super) fn publish_status(&mut self) {
        let text = self.status_json().to_string();
        if text != self.published_status {
            super::platform::publish_status(&text);
            self.published_status = text;
        }
    }
}
