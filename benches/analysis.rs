//! Speed of re-evaluating a model for the workbench: everything it shows of one model (the accuracy
//! figures and histograms of both splits, the per-configuration rows, the registration for drawing),
//! which the workbench recomputes for the live view while a calibration runs. Targets: under 20 ms for
//! 2 × 220 configurations, under 200 ms for 2 × 1000 (docs/performance.md).
//!
//! `cargo bench --no-default-features --bench analysis` (the engine alone; no GUI to build)
use criterion::{Criterion, criterion_group, criterion_main};
use dualcal::analysis::Analysis;
use dualcal::dataset::Split;
use dualcal::robot::RobotDescription;
use dualcal::side::Side;
use dualcal::simulate::{paper_options, simulate_with_robot};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let robot = RobotDescription::builtin_irb14000();
    let body_from_left_base = robot.body_from_dh_base(Side::Left);
    let mut group = c.benchmark_group("analysis");
    group.sample_size(10);
    // The bundled example's size (220 per arm, 120 for calibration) and 1000 calibration
    // configurations per arm (+ 100 for verification).
    for (configs, cal) in [(220usize, 120usize), (1100, 1000)] {
        let sim = simulate_with_robot(&paper_options(7, configs, cal), &robot).expect("simulation");
        let (dataset, model) = (&sim.dataset, &sim.nominal);
        group.bench_function(format!("whole_analysis_{configs}_configs_per_arm"), |b| {
            b.iter(|| {
                Analysis::compute(black_box(dataset), black_box(model), &body_from_left_base)
                    .expect("analysis")
            })
        });
        // The pass over the pairs alone (figures, rows, histogram samples; no binning, no
        // registration).
        group.bench_function(format!("pair_sweep_{configs}_configs_per_arm"), |b| {
            b.iter(|| dualcal::metrics::sweep(black_box(dataset), black_box(model)).expect("sweep"))
        });
        // The paper's figures of the calibration split alone (what the CLI prints), for comparison.
        group.bench_function(format!("cal_split_report_{configs}_configs_per_arm"), |b| {
            b.iter(|| {
                dualcal::metrics::evaluate(black_box(dataset), black_box(model), Split::Cal)
                    .expect("report")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
