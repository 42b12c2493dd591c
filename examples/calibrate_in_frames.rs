//! The workbench's calibration of the bundled example, stepped in frames as in a browser (no threads),
//! natively: the time its steps take (solver and figures), to compare with the browser's (see
//! docs/performance.md; `tools/web.sh measure` runs it):
//!
//! ```sh
//! cargo run --release --example calibrate_in_frames [-- RUNS]
//! ```
//!
//! Prints JSON: each run's compute time (s) and the median.
use dualcal::app::events::EventChannel;
use dualcal::app::session::Session;
use dualcal::app::task::{BackgroundTask, Execution};
use dualcal::app::work::{CalibrationWork, LiveRate};
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
            channel.drain();
        }
        secs.push(task.slice_stats().busy_secs);
    }
    let mut sorted = secs.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{}",
        serde_json::json!({ "compute_s": secs, "median_compute_s": median })
    );
    Ok(())
}
