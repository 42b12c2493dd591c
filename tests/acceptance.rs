//! The solver's acceptance on the paper-size simulation (§4.1: 120 calibration + 100 verification
//! configurations per arm, geometric errors only): the calibrated model's verification accuracy is within
//! 10% of what the true parameters give (the measurement-noise floor), for the default QP; and the paper's
//! subgradient QP reaches the same optimum: each arm stage's ψ within 1e-6 (measured ≤ 4.2e-8), the
//! base stage's within 1% (measured 0.5% and 0.003%: step 2 is solved over each run's own step-1 arms,
//! and step 1's minimax optimum is flat in some directions — docs/solver.md).

mod common;

use dualcal::dataset::Split;
use dualcal::metrics::{AccuracyReport, AccuracyStats, evaluate};
use dualcal::robot::RobotDescription;
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationResult, CalibrationSettings, QpMethod, STAGES};

fn run(
    ds: &dualcal::dataset::Dataset,
    nominal: &dualcal::kinematics::DualArmModel,
    qp: QpMethod,
) -> CalibrationResult {
    let settings = CalibrationSettings {
        qp,
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    common::calibrate(ds, nominal, &settings)
}

fn stats(r: &AccuracyReport) -> [(&'static str, &AccuracyStats); 3] {
    [
        ("relative left", r.relative_left.as_ref().unwrap()),
        ("relative right", r.relative_right.as_ref().unwrap()),
        ("collaborative", r.collaborative.as_ref().unwrap()),
    ]
}

#[test]
fn paper_size_simulation_reaches_the_noise_floor() {
    let robot = RobotDescription::builtin_irb14000();
    for seed in [1u64, 2] {
        let sim = simulate_with_robot(&paper_options(seed, 220, 120), &robot).expect("simulation");
        let truth = evaluate(&sim.dataset, &sim.truth, Split::Ver).unwrap();
        let nominal = evaluate(&sim.dataset, &sim.nominal, Split::Ver).unwrap();
        let exact = run(&sim.dataset, &sim.nominal, QpMethod::Exact);
        let cal = evaluate(&sim.dataset, &exact.calibrated, Split::Ver).unwrap();
        for ((name, t), ((_, c), (_, n))) in stats(&truth)
            .into_iter()
            .zip(stats(&cal).into_iter().zip(stats(&nominal)))
        {
            // The test must start far from the floor for this to mean anything.
            assert!(
                n.pos_rms_mm > 20.0 * t.pos_rms_mm,
                "seed {seed} {name}: nominal {} vs truth {}",
                n.pos_rms_mm,
                t.pos_rms_mm
            );
            assert!(
                c.pos_rms_mm <= 1.1 * t.pos_rms_mm,
                "seed {seed} {name}: position RMS {} vs truth {}",
                c.pos_rms_mm,
                t.pos_rms_mm
            );
            assert!(
                c.ori_rms_rad.unwrap() <= 1.1 * t.ori_rms_rad.unwrap(),
                "seed {seed} {name}: orientation RMS {} vs truth {}",
                c.ori_rms_rad.unwrap(),
                t.ori_rms_rad.unwrap()
            );
        }

        let paper = run(&sim.dataset, &sim.nominal, QpMethod::Paper);
        for (e, p) in exact.stages.iter().zip(&paper.stages) {
            assert_eq!(e.stage, p.stage);
            let rel = (p.psi_mm2 - e.psi_mm2) / e.psi_mm2;
            let tolerance = if e.stage == STAGES[2] { 0.01 } else { 1e-6 };
            assert!(
                rel.abs() <= tolerance,
                "seed {seed} {:?}: ψ paper {} vs exact {} ({:+.3}%)",
                e.stage,
                p.psi_mm2,
                e.psi_mm2,
                rel * 100.0
            );
        }
    }
}
