//! Speed of the full two-step calibration (targets: paper size, 2 × 120 configurations, in tens of
//! milliseconds; 1000 configurations per arm in about a second): the built-in IRB 14000 (Table 3,
//! DH), and a robot description of the user's own (the YuMi-like test robot, URDF chains of 7 joints).
//!
//! `cargo bench --bench calibration`
#[path = "../tests/fixtures/robots.rs"]
mod robots;

use criterion::{Criterion, criterion_group, criterion_main};
use dualcal::robot::RobotDescription;
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{BaseMethod, CalibrationSettings, Calibrator, Method, Termination};
use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

fn bench(c: &mut Criterion) {
    let robot = RobotDescription::builtin_irb14000();
    let mut group = c.benchmark_group("two_step_calibration");
    group.sample_size(10);
    for (configs, cal) in [(220usize, 120usize), (1100, 1000)] {
        let sim = simulate_with_robot(&paper_options(7, configs, cal), &robot).expect("simulation");
        let ds = sim.dataset.with_cal_subset(cal);
        let settings = CalibrationSettings::default();
        group.bench_function(format!("{cal}_configs_per_arm"), |b| {
            b.iter(|| {
                let r = Calibrator::new(black_box(&ds), &sim.nominal)
                    .settings(settings.clone())
                    .run()
                    .expect("calibration");
                assert!(r.is_converged());
                black_box(r.calibrated)
            })
        });
    }
    // The same protocol on a URDF of the user's own: 7-joint chains, 51 parameters per arm (31 free).
    let dir = tempfile::tempdir().expect("temp dir");
    let yumi_like =
        RobotDescription::load(&robots::write_yumi_like(dir.path()), &Default::default())
            .expect("robot");
    let sim = simulate_with_robot(&paper_options(7, 220, 120), &yumi_like).expect("simulation");
    let ds = sim.dataset.with_cal_subset(120);
    group.bench_function("120_configs_per_arm_urdf_chains", |b| {
        b.iter(|| {
            let r = Calibrator::new(black_box(&ds), &sim.nominal)
                .run()
                .expect("calibration");
            assert!(r.is_converged());
            black_box(r.calibrated)
        })
    });
    group.finish();

    // The paper's comparison methods on the paper's protocol (2 × 120 calibration configurations):
    // each step-1 method with the paper's step 2, and each step-2 method with the paper's step 1.
    let sim = simulate_with_robot(&paper_options(7, 220, 120), &robot).expect("simulation");
    let ds = sim.dataset.with_cal_subset(120);
    let mut group = c.benchmark_group("methods_120_configs_per_arm");
    group.sample_size(10);
    let combinations = Method::ALL
        .iter()
        .copied()
        .map(|m| (m, BaseMethod::Minimax))
        .chain([
            (Method::Minimax, BaseMethod::Distance),
            (Method::Minimax, BaseMethod::Absolute),
        ]);
    for (method, base_method) in combinations {
        let settings = CalibrationSettings {
            method,
            base_method,
            ..CalibrationSettings::default()
        };
        group.bench_function(format!("{}+{}", method.name(), base_method.name()), |b| {
            b.iter(|| {
                let r = Calibrator::new(black_box(&ds), &sim.nominal)
                    .settings(settings.clone())
                    .run()
                    .expect("calibration");
                assert!(r.is_converged());
                black_box(r.calibrated)
            })
        });
    }
    group.finish();

    identifiability(c);

    // Cancel latency: a run inside a practically endless paper-QP solve is cancelled; the time from
    // setting the flag to the run returning is measured.
    let sim = simulate_with_robot(&paper_options(7, 220, 120), &robot).expect("simulation");
    let settings = CalibrationSettings {
        qp: dualcal::solver::QpMethod::Paper,
        max_qp_iterations: usize::MAX,
        ..CalibrationSettings::default()
    };
    c.bench_function("cancel_latency_inside_paper_qp", |b| {
        b.iter_custom(|iters| {
            let mut total = std::time::Duration::ZERO;
            for _ in 0..iters {
                let cancel = Arc::new(AtomicBool::new(false));
                let flag = cancel.clone();
                let (ds, nominal, settings) =
                    (sim.dataset.clone(), sim.nominal.clone(), settings.clone());
                let worker = std::thread::spawn(move || {
                    let r = Calibrator::new(&ds, &nominal)
                        .settings(settings)
                        .cancel(flag)
                        .run()
                        .expect("calibration");
                    let cancelled = r
                        .stages
                        .last()
                        .is_some_and(|s| s.termination == Termination::Cancelled);
                    (std::time::Instant::now(), cancelled)
                });
                std::thread::sleep(std::time::Duration::from_millis(20));
                let asked = std::time::Instant::now();
                cancel.store(true, std::sync::atomic::Ordering::Relaxed);
                let (returned, cancelled) = worker.join().expect("worker");
                assert!(cancelled);
                total += returned.saturating_duration_since(asked);
            }
            total
        })
    });
}

/// The identifiability analysis of one arm (the built-in robot's left arm, the calibration split):
/// the start's Gram matrix from the Jacobians by the product summed over blocks of rows (what the
/// start does) and by nalgebra's QR of the sample (what the built-in robot's start did until the
/// sixteenth session), and the whole re-check at a solution by each.
fn identifiability(c: &mut Criterion) {
    use dualcal::solver::arm_problem::{pair_jacobian_columns, pair_jacobian_gram};
    use dualcal::solver::identifiability::{GramMethod, at_solution, gram_by_qr};
    let robot = RobotDescription::builtin_irb14000();
    let mut group = c.benchmark_group("identifiability");
    group.sample_size(20);
    for (configs, cal) in [(220usize, 120usize), (1100, 1000)] {
        let sim = simulate_with_robot(&paper_options(7, configs, cal), &robot).expect("simulation");
        let arm = sim.nominal.arm(dualcal::side::Side::Left);
        // The calibration split's joint values and measured points.
        let (qs, measured): (Vec<Vec<f64>>, Vec<_>) = sim
            .dataset
            .arms
            .left
            .measurements
            .iter()
            .filter(|m| m.split == dualcal::dataset::Split::Cal)
            .map(|m| (m.q_rad.clone(), m.tracker_points_mm.clone()))
            .unzip();
        let jac: Vec<_> = qs.iter().map(|q| arm.reflector_jacobians(q)).collect();
        group.bench_function(format!("start_sample_and_gram_{cal}"), |b| {
            b.iter(|| black_box(pair_jacobian_gram(black_box(&jac), 3000, &[true; 3])))
        });
        group.bench_function(format!("start_sample_and_qr_{cal}"), |b| {
            b.iter(|| {
                let m = pair_jacobian_columns(black_box(&jac), 3000, &[true; 3]);
                black_box(gram_by_qr(&m))
            })
        });
        let free: Vec<usize> = (0..arm.param_count()).collect();
        // What the data cannot tell (issue 47), on every calibration: the unit-noise covariance of
        // the fit, then the weak-parameter rule (that covariance, the workspace's 2000 pairs per
        // reflector, the residuals' noise).
        let identified = at_solution(arm, &qs, &free, 3000, GramMethod::Product).free;
        group.bench_function(format!("predicted_covariance_{cal}"), |b| {
            b.iter(|| {
                black_box(dualcal::solver::uncertainty::predicted_covariance(
                    arm,
                    black_box(&qs),
                    &identified,
                    1.0,
                ))
            })
        });
        group.bench_function(format!("weak_parameters_{cal}"), |b| {
            b.iter(|| {
                black_box(dualcal::solver::weak::weak_parameters(
                    arm,
                    black_box(&qs),
                    &measured,
                    &identified,
                ))
            })
        });
        for (name, how) in [("product", GramMethod::Product), ("qr", GramMethod::Qr)] {
            group.bench_function(format!("recheck_by_{name}_{cal}"), |b| {
                b.iter(|| black_box(at_solution(arm, black_box(&qs), &free, 3000, how)))
            });
        }
    }
    group.finish();
}

/// Issue 21's models on the paper's protocol with the robustness study's joint errors (2 × 120
/// calibration configurations, the built-in IRB 14000, minimax): the full model's calibration against
/// the geometric one's (target: within 3×).
fn models(c: &mut Criterion) {
    let robot = RobotDescription::builtin_irb14000();
    let opts = dualcal::simulate::SimOptions {
        joint_error: Some(dualcal::simulate::unmodelled_joint_errors()),
        ..paper_options(7, 220, 120)
    };
    let sim = simulate_with_robot(&opts, &robot).expect("simulation");
    let ds = sim.dataset.with_cal_subset(120);
    let mut group = c.benchmark_group("models_120_configs_per_arm");
    group.sample_size(10);
    for (name, terms, _) in dualcal::kinematics::ErrorTerms::NAMED {
        let settings = CalibrationSettings {
            model: terms,
            gravity_in_left_base: Some(robot.gravity_in_left_base(None)),
            ..Default::default()
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                let r = Calibrator::new(black_box(&ds), &sim.nominal)
                    .settings(settings.clone())
                    .run()
                    .expect("calibration");
                black_box(r.calibrated)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench, models);
criterion_main!(benches);
