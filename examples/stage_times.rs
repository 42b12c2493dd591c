//! Where the engine's calibration spends its time, stage by stage: the paper's protocol (built-in
//! IRB 14000, 2 × 120 calibration configurations, the calibration bench's data), 60 runs, the median
//! and the minimum of each moment a stage starts or ends, from the start of the run. The two arms'
//! stages run at once (the right arm's events are replayed when both have ended), so "start Arm(Left)"
//! is the arms' set-up (identifiability QR, scales), "end Arm(Right)" the end of both, "start Base"
//! after step 2's set-up. The figures of docs/performance.md, "Fourth pass".
//!
//! `cargo run --release --example stage_times`

use dualcal::robot::RobotDescription;
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationEvent, Calibrator};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(7, 220, 120), &robot)?;
    let ds = sim.dataset.with_cal_subset(120);
    let mut runs: Vec<Vec<(String, f64)>> = Vec::new();
    for _ in 0..60 {
        let t0 = Instant::now();
        let ms = || t0.elapsed().as_secs_f64() * 1e3;
        let mut marks = Vec::new();
        let mut observer = |e: &CalibrationEvent| match e {
            CalibrationEvent::StageStarted { stage, .. } => {
                marks.push((format!("start {stage:?}"), ms()))
            }
            CalibrationEvent::StageFinished { stage, .. } => {
                marks.push((format!("end {stage:?}"), ms()))
            }
            CalibrationEvent::Iteration(_) => {}
        };
        let result = Calibrator::new(&ds, &sim.nominal)
            .observer(&mut observer)
            .run()?;
        marks.push(("total".into(), ms()));
        std::hint::black_box(result);
        runs.push(marks);
    }
    println!("moment (ms from the run's start)       median      min");
    for (i, (label, _)) in runs[0].iter().enumerate() {
        let mut v: Vec<f64> = runs.iter().map(|r| r[i].1).collect();
        v.sort_by(f64::total_cmp);
        println!("{label:36} {:9.2} {:8.2}", v[v.len() / 2], v[0]);
    }
    Ok(())
}
