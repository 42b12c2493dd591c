//! The workbench's calibration of the bundled example, stepped in frames as in a browser (no threads),
//! natively: the time its steps take (solver and figures), to compare with the browser's (see
//! docs/performance.md; `tools/web.sh measure` runs it):
//!
//! ```sh
//! cargo run --release --example calibrate_in_frames [-- RUNS]
//! ```
//!
//! Prints JSON: each run's compute time (s: the task's steps, solver and figures) and solver time (s:
//! the solver's steps alone), and their medians.
use dualcal::app::events::{AppEvent, EventChannel};
use dualcal::app::session::Session;
use dualcal::app::task::{BackgroundTask, Execution, TaskEvent};
use dualcal::app::work::{CalibrationWork, LiveRate, Outcome};
use dualcal::solver::CalibrationSettings;
use std::path::Path;
use std::time::Duration;

fn main() -> anyhow::Result<()> {
    let runs: usize = match std::env::args().nth(1) {
        Some(n) => n.parse()?,
        None => 5,
    };
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let session = Session::load(&example, None)?;
    let mut secs = Vec::new();
    let mut solver_secs = Vec::new();
    for _ in 0..runs {
        let channel = EventChannel::new(None);
        let work = CalibrationWork::new(
            &session,
            CalibrationSettings::default(),
            LiveRate::IN_FRAMES,
        );
        let mut task =
            BackgroundTask::start("calibration", work, channel.sender(), Execution::InFrames)?;
        // An unlimited budget: the browser test's one-frame run (`?budget_ms=60000`).
        while task.needs_frames() {
            task.step_in_frame(Duration::from_secs(60));
            for event in channel.drain() {
                if let AppEvent::Task(_, TaskEvent::Calibrated(outcome)) = event {
                    match outcome {
                        Outcome::Calibrated(c) => solver_secs.push(c.solver_secs),
                        _ => anyhow::bail!("the example did not calibrate"),
                    }
                }
            }
        }
        secs.push(task.slice_stats().busy_secs);
    }
    let median = |xs: &[f64]| {
        let mut sorted = xs.to_vec();
        sorted.sort_by(f64::total_cmp);
        sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "{}",
        serde_json::json!({
            "compute_s": secs,
            "median_compute_s": median(&secs),
            "solver_s": solver_secs,
            "median_solver_s": median(&solver_secs),
        })
    );
    Ok(())
}
