//! How stages end on data the model cannot explain (unmodelled joint compliance and gear errors):
//! SQP near a kink of the max where one active F_i has a vanishing multiplier, and the paper's inexact
//! subgradient QP. A stage may only report convergence at the optimum.

mod common;

use dualcal::robot::RobotDescription;
use dualcal::side::Side;
use dualcal::simulate::{
    JointErrorModel, SimOptions, SimOutput, paper_options, simulate_with_robot,
    unmodelled_joint_errors,
};
use dualcal::solver::{
    CalibrationResult, CalibrationSettings, QpMethod, Stage, StageSummary, Termination,
};

fn simulate(seed: u64, gear_mrad: f64, compliance_mrad_per_m: f64) -> SimOutput {
    let joint_error = JointErrorModel {
        periodic_amplitude_mrad: gear_mrad,
        compliance_mrad_per_m,
        ..unmodelled_joint_errors()
    };
    let opts = SimOptions {
        joint_error: Some(joint_error),
        ..paper_options(seed, 220, 120)
    };
    simulate_with_robot(&opts, &RobotDescription::builtin_irb14000()).expect("simulation")
}

fn run(sim: &SimOutput, settings: CalibrationSettings) -> CalibrationResult {
    common::calibrate(&sim.dataset, &sim.nominal, &settings)
}

fn stage(r: &CalibrationResult, side: Side) -> &StageSummary {
    r.stages
        .iter()
        .find(|s| s.stage == Stage::Arm(side))
        .expect("stage")
}

/// Seed 4 with joint compliance only: the left arm's optimum is a kink where F_c is active with a
/// multiplier of ~1e-4. SQP steps there shrink only slowly (the full step is rejected because the
/// Lagrangian does not see F_c's curvature); with the step-norm rule alone the default 100 iterations
/// ran out (`NotConverged` at ψ 239.59172, step norm 5.5e-6). The no-progress rule must end the stage
/// as converged, at the optimum that the step-norm rule reaches with a tenfold budget.
#[test]
fn a_kink_with_a_vanishing_multiplier_converges_within_the_default_budget() {
    let sim = simulate(4, 0.0, 0.5);
    let fast = run(&sim, CalibrationSettings::default());
    let slow = run(
        &sim,
        CalibrationSettings {
            progress_tolerance: 0.0,
            max_iterations: 1000,
            ..Default::default()
        },
    );
    let (f, s) = (stage(&fast, Side::Left), stage(&slow, Side::Left));
    assert!(f.termination.is_converged(), "{f:?}");
    assert!(f.iterations < 100, "{f:?}");
    assert!(s.iterations > f.iterations, "{s:?} vs {f:?}");
    assert!(
        f.psi_mm2 <= s.psi_mm2 * (1.0 + 1e-6),
        "no-progress stop at ψ {} vs {} after {} iterations",
        f.psi_mm2,
        s.psi_mm2,
        s.iterations
    );
}

/// The paper's subgradient QP is inexact; a step-1 stage run with it may end above the optimum, but
/// then it must say so (`Stalled`), never `Converged`. Datasets where it stopped 0.01–2% above the
/// exact QP's optimum before the classification existed (one of them at 63%, reported as converged).
///
/// How each stage ends is pinned. Since the cold-start retries the paper QP ended within 3e-4 of the
/// exact QP's ψ on all of them, and two stages (about 1e-4 above, where the exact QP still found a
/// descent) ended `Stalled`; since the retries polish the last iterations (sixteenth session, until
/// the exact QP predicts less than `sqp::PAPER_RETRY_RTOL`) every stage here converges, the largest gap
/// 6.7e-5 (seed 6, gear 3, left). The `Stalled` path is held by `a_starved_paper_qp_stalls_and_says_so`.
/// A solver change that moves a case must update the table.
#[test]
fn the_paper_qp_reports_convergence_only_at_the_optimum() {
    // (seed, gear error mrad, compliance mrad/m): both arm stages converge, within 1e-4 of the exact
    // QP's ψ (the stopping classification's `STATIONARY_RTOL`; 1e-3 while two of them stalled).
    let cases = [(4, 0.0, 0.5), (6, 3.0, 0.0), (6, 0.0, 2.0), (6, 1.0, 0.5)];
    for (seed, gear, compliance) in cases {
        let sim = simulate(seed, gear, compliance);
        let exact = run(&sim, CalibrationSettings::default());
        let paper = run(
            &sim,
            CalibrationSettings {
                qp: QpMethod::Paper,
                ..Default::default()
            },
        );
        for side in Side::BOTH {
            let (e, p) = (stage(&exact, side), stage(&paper, side));
            let case = format!("seed {seed} gear {gear} compliance {compliance} {side}");
            assert!(e.termination.is_converged(), "{case}: exact QP {e:?}");
            assert!(
                p.termination.is_converged(),
                "{case}: expected the paper QP to converge, got {p:?}"
            );
            let gap = p.psi_mm2 / e.psi_mm2 - 1.0;
            assert!(
                gap < 1e-4,
                "{case}: paper QP says {} at ψ {} but the optimum is {}",
                p.termination,
                p.psi_mm2,
                e.psi_mm2
            );
        }
    }
}

/// A paper QP starved of iterations (one per outer iteration, at most 64 in its retries) cannot reach
/// the optimum: both arm stages end `Stalled`, above the exact QP's optimum, and the run is not
/// converged. This exercises the `Stalled` path deterministically.
#[test]
fn a_starved_paper_qp_stalls_and_says_so() {
    let sim = simulate(1, 1.0, 0.5);
    let exact = run(&sim, CalibrationSettings::default());
    let starved = run(
        &sim,
        CalibrationSettings {
            qp: QpMethod::Paper,
            max_qp_iterations: 1,
            ..Default::default()
        },
    );
    assert!(!starved.is_converged());
    for side in Side::BOTH {
        let (p, e) = (stage(&starved, side), stage(&exact, side));
        assert_eq!(p.termination, Termination::Stalled, "{side}: {p:?}");
        // Above the optimum by more than the classification's `STATIONARY_RTOL` (1e-4); it was
        // more than 1e-3 before the retries polished the last iterations (7e-4 and 8e-4 now).
        assert!(
            p.psi_mm2 > e.psi_mm2 * (1.0 + 1e-4),
            "{side}: {p:?} vs {e:?}"
        );
    }
}

/// The default curvature (`auto`) on the paper-size simulations, geometric errors and unmodelled
/// joint errors alike: the identified parameters' scaled Jacobian is well conditioned (~15), so every
/// stage runs the paper's BFGS — the same run as `--hessian bfgs`, to the bit. (On the ill-conditioned
/// one-reflector arm it picks Gauss–Newton: tests/ill_conditioned.rs.)
#[test]
fn the_default_curvature_is_the_papers_bfgs_on_well_conditioned_data() {
    use dualcal::solver::{AUTO_GAUSS_NEWTON_CONDITION, Hessian};
    for sim in [simulate(2, 0.0, 0.0), simulate(4, 0.3, 0.5)] {
        let auto = run(&sim, CalibrationSettings::default());
        let bfgs = run(
            &sim,
            CalibrationSettings {
                hessian: Hessian::Bfgs,
                ..Default::default()
            },
        );
        for side in Side::BOTH {
            let condition = auto.identifiability[side].as_ref().unwrap().condition_after;
            assert!(condition < AUTO_GAUSS_NEWTON_CONDITION / 3.0, "{condition}");
            assert_eq!(stage(&auto, side).curvature, Some(Hessian::Bfgs));
        }
        assert_eq!(auto.stages, bfgs.stages);
        assert_eq!(auto.calibrated, bfgs.calibrated);
    }
}
