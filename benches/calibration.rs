//! Speed of the full two-step calibration (issue 3 sets the targets: paper size, 2 × 120 configurations,
//! in tens of milliseconds; 1000 configurations per arm in about a second).
//!
//! `cargo bench --bench calibration`
use criterion::{Criterion, criterion_group, criterion_main};
use dualcal::cli::{sim_options, simulate_with_robot, with_cal_subset};
use dualcal::robot::RobotDescription;
use dualcal::solver::{CalibrationSettings, calibrate};
use std::hint::black_box;
use std::sync::atomic::AtomicBool;

fn bench(c: &mut Criterion) {
    let robot = RobotDescription::builtin_irb14000();
    let mut group = c.benchmark_group("two_step_calibration");
    group.sample_size(10);
    for (configs, cal) in [(220usize, 120usize), (1100, 1000)] {
        let sim = simulate_with_robot(&sim_options(7, configs, cal), &robot).expect("simulation");
        let ds = with_cal_subset(&sim.dataset, cal);
        let settings = CalibrationSettings::default();
        group.bench_function(format!("{cal}_configs_per_arm"), |b| {
            b.iter(|| {
                let cancel = AtomicBool::new(false);
                let r = calibrate(
                    black_box(&ds),
                    &sim.nominal,
                    &settings,
                    &mut |_| {},
                    &cancel,
                )
                .expect("calibration");
                black_box(r.calibrated)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
