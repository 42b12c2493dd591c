//! Speed of the screening, before and after the fit (`quality::screen` with the nominal model,
//! `quality::screen_model` with the fitted one — here the simulation's true model, which a
//! calibration reaches to the noise), and of the load pipeline as a whole (`Workspace::new`: checks,
//! nominal model, nominal screening). Its pair loops grow as n² per arm; the target is to cost less
//! than the solver at every size (docs/performance.md).
//!
//! `cargo bench --no-default-features --bench screening` (the engine alone)
use criterion::{Criterion, criterion_group, criterion_main};
use dualcal::quality::{self, ScreenSettings};
use dualcal::robot::RobotDescription;
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::workspace::Workspace;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let robot = RobotDescription::builtin_irb14000();
    let settings = ScreenSettings::default();
    let mut group = c.benchmark_group("screening");
    group.sample_size(10);
    // The paper's size (220 per arm, 120 for calibration) and 1000 calibration configurations per
    // arm (+ 100 for verification).
    for (configs, cal) in [(220usize, 120usize), (1100, 1000)] {
        let sim = simulate_with_robot(&paper_options(7, configs, cal), &robot).expect("simulation");
        let (dataset, nominal, truth) = (&sim.dataset, &sim.nominal, &sim.truth);
        group.bench_function(format!("before_fit_{configs}_configs_per_arm"), |b| {
            b.iter(|| quality::screen(black_box(dataset), black_box(nominal), &settings))
        });
        group.bench_function(format!("after_fit_{configs}_configs_per_arm"), |b| {
            b.iter(|| {
                quality::screen_model(black_box(dataset), nominal, black_box(truth), &settings)
            })
        });
        group.bench_function(format!("load_pipeline_{configs}_configs_per_arm"), |b| {
            b.iter(|| {
                Workspace::new(black_box(dataset.clone()), robot.clone(), &settings)
                    .expect("workspace")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
