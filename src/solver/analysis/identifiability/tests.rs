//! Tests of the identifiability analysis on the built-in DH arm and on URDF chains.

use super::*;
use crate::kinematics::{ArmModel, CORRECTION_NAMES, SerialChain, minimal_parameter_count};
use crate::solver::problems::arm_problem::pair_jacobian_columns;
use crate::test_robots::{dual_ur_like_urdf, yumi_like_urdf};
use nalgebra::{DMatrix, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

fn reflectors() -> [Vector3<f64>; 3] {
    [
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ]
}

fn chain(text: &str, base: &str, tip: &str) -> Arc<SerialChain> {
    let urdf = urdf_rs::read_from_string(text).unwrap();
    Arc::new(SerialChain::from_urdf(&urdf, base, tip).unwrap())
}

/// The reflector Jacobians of `n` random configurations of `arm`.
fn random_jacobians(
    arm: &ArmModel,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<crate::kinematics::ArmJacobians> {
    let limits = arm.joint_limits_rad();
    (0..n)
        .map(|_| {
            let q: Vec<f64> = limits
                .iter()
                .map(|&(lo, hi)| rng.random_range(lo..hi))
                .collect();
            arm.reflector_jacobians(&q)
        })
        .collect()
}

/// The pair-Jacobian columns of `n` random configurations of `arm`.
fn columns(arm: &ArmModel, n: usize, rng: &mut ChaCha8Rng) -> DMatrix<f64> {
    pair_jacobian_columns(&random_jacobians(arm, n, rng), 3000, &[true; 3])
}

fn report(arm: &ArmModel, gram: &DMatrix<f64>) -> IdentifiabilityReport {
    let order = arm.identifiability_order();
    analyse(
        gram,
        &ParameterInfo {
            order: &order,
            allowed: &vec![true; arm.param_count()],
            name: &|k| arm.param_name(k),
            reason: &|k| arm.unidentifiable_reason(k),
            data: ParameterInfo::DISTANCES,
            not_allowed: ParameterInfo::FIXED_BY_USER,
        },
    )
}

#[test]
fn the_dh_arm_fixes_exactly_the_six_parameters_physics_predicts() {
    let arm = ArmModel::nominal_irb14000(reflectors());
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let rep = report(&arm, &gram_by_qr(&columns(&arm, 120, &mut rng)));
    let fixed: Vec<&str> = rep.fixed.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(fixed, ["d1", "theta1", "a7", "d7", "theta7", "alpha7"]);
    assert!(
        rep.fixed
            .iter()
            .all(|f| f.reason.starts_with("unidentifiable"))
    );
    assert!(rep.condition_before.is_infinite());
    assert!(rep.condition_after < 30.0, "{}", rep.condition_after);
}

/// The URDF chains of these tests — a YuMi-like arm, a UR-like arm (parallel axes), the built-in URDF
/// read as a chain — as (text, base link, tip link, joints).
fn test_chains() -> Vec<(String, &'static str, &'static str, usize)> {
    vec![
        (yumi_like_urdf(), "yumi_body", "yumi_link_7_l", 7),
        (dual_ur_like_urdf(), "left_base_link", "left_ee_link", 6),
        (
            crate::robot::BUILTIN_IRB14000_URDF.to_string(),
            "yumi_body",
            "yumi_flange_l",
            7,
        ),
    ]
}

#[test]
fn chains_keep_the_minimal_count_base_first() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (text, base, tip, n) in test_chains() {
        let chain = chain(&text, base, tip);
        let arm = ArmModel::nominal_chain(chain.clone(), reflectors());
        let rep = report(&arm, &gram_by_product(&columns(&arm, 60, &mut rng)));
        assert_eq!(rep.free.len(), minimal_parameter_count(n), "{tip}");
        assert!(rep.condition_before.is_infinite());
        assert!(rep.condition_after < 30.0, "{tip}: {}", rep.condition_after);
        let kept = |k: usize| -> Vec<&str> {
            (0..6)
                .filter(|c| rep.free.contains(&(6 * k + c)))
                .map(|c| CORRECTION_NAMES[c])
                .collect()
        };
        // Joint 1's correction is a rigid motion of the arm; the reflectors are all kept.
        assert!(kept(0).is_empty());
        assert!((chain.reflector_offset()..chain.param_count(3)).all(|k| rep.free.contains(&k)));
        for k in 1..n {
            let name = &chain.joints[k].name;
            let kept = kept(k);
            if k == n - 1 {
                // The last joint's offset and shift pass to the reflectors.
                assert_eq!(kept.len(), 2, "{name}");
                assert!(!kept.contains(&"tz") && !kept.contains(&"rz"), "{name}");
            } else {
                // Every other joint keeps its offset and three more: the shift tz, or for an axis
                // parallel to the previous one the tilt about the common normal (Hayati's β).
                assert_eq!(kept.len(), 4, "{name}: {kept:?}");
                assert!(kept.contains(&"rz"), "{name}");
                assert_eq!(
                    kept.contains(&"tz"),
                    !chain.parallel_to_previous(k),
                    "{name}: {kept:?}"
                );
            }
        }
        // Every fixed parameter has a physical reason.
        for f in &rep.fixed {
            assert!(f.reason.contains('`'), "{}: {}", f.name, f.reason);
        }
    }
}

#[test]
fn gram_by_qr_and_by_product_keep_the_same_parameters() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let yumi = chain(&yumi_like_urdf(), "yumi_body", "yumi_link_7_l");
    let ur = chain(&dual_ur_like_urdf(), "left_base_link", "left_ee_link");
    for arm in [
        ArmModel::nominal_irb14000(reflectors()),
        ArmModel::nominal_chain(yumi, reflectors()),
        ArmModel::nominal_chain(ur, reflectors()),
    ] {
        let m = columns(&arm, 120, &mut rng);
        let (a, b) = (gram_by_qr(&m), gram_by_product(&m));
        assert!((&a - &b).amax() < 1e-9 * b.amax());
        let (ra, rb) = (report(&arm, &a), report(&arm, &b));
        assert_eq!(ra.free, rb.free);
        assert!((ra.condition_after / rb.condition_after - 1.0).abs() < 1e-6);
        for (fa, fb) in ra.fixed.iter().zip(&rb.fixed) {
            assert_eq!(fa.index, fb.index);
            assert!((fa.residual - fb.residual).abs() < 1e-6, "{}", fa.name);
        }
    }
}

/// What physics names as unidentifiable on a URDF chain (`unidentifiable_reason`: the first joint's six,
/// the last joint's offset and shift, each joint's axis-line pair the previous joint's offset and shift
/// move — for a parallel axis its shift and one shift across) is exactly what the analysis fixes, so
/// the count physics gives is the calibration's (31 of 51 on a YuMi-like arm; it said 19).
#[test]
fn the_chains_physical_reasons_name_what_the_analysis_fixes() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut chains = test_chains();
    chains.push((yumi_like_urdf(), "yumi_body", "yumi_link_7_r", 7));
    for (text, base, tip, n) in chains {
        let chain = chain(&text, base, tip);
        let arm = ArmModel::nominal_chain(chain.clone(), reflectors());
        let rep = report(&arm, &gram_by_product(&columns(&arm, 60, &mut rng)));
        let fixed: Vec<usize> = rep.fixed.iter().map(|f| f.index).collect();
        let named: Vec<usize> = (0..arm.param_count())
            .filter(|&k| arm.unidentifiable_reason(k).is_some())
            .collect();
        for k in &named {
            assert!(
                fixed.contains(k),
                "{tip}: {} named, not fixed",
                arm.param_name(*k)
            );
        }
        assert_eq!(named, fixed, "{tip}");
        assert_eq!(
            crate::solver::types::identifiable_params(&arm),
            rep.free.len(),
            "{tip}"
        );
        assert_eq!(rep.free.len(), minimal_parameter_count(n), "{tip}");
    }
}

/// The Gram matrix summed over blocks of rows (the start's analysis and the re-check) is the one
/// product's up to rounding — on the DH arm and a URDF chain, with fewer sampled rows than parameters,
/// and with several blocks.
#[test]
fn the_blocked_sample_gives_the_full_samples_gram() {
    use crate::solver::problems::arm_problem::pair_jacobian_gram;
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let yumi = chain(&yumi_like_urdf(), "yumi_body", "yumi_link_7_l");
    for arm in [
        ArmModel::nominal_irb14000(reflectors()),
        ArmModel::nominal_chain(yumi, reflectors()),
    ] {
        for (n, max_pairs, reflectors) in [
            (120, 3000, [true; 3]),
            (40, 3000, [true, false, true]),
            (5, 3000, [true; 3]),
            (3, 1, [false, true, false]),
        ] {
            let jacs = random_jacobians(&arm, n, &mut rng);
            let m = pair_jacobian_columns(&jacs, max_pairs, &reflectors);
            let (blocked, product) = (
                pair_jacobian_gram(&jacs, max_pairs, &reflectors),
                gram_by_product(&m),
            );
            assert!(
                (&blocked - &product).amax() <= 1e-12 * product.amax(),
                "n {n}: {:e}",
                (&blocked - &product).amax() / product.amax()
            );
            if m.ncols() > 0 {
                assert!(product.amax() > 0.0);
            }
        }
    }
}

#[test]
fn negligible_columns_are_unidentifiable_outright() {
    // Three parameters: two independent, and one whose sensitivity is 1e-9 of the others' — as a
    // `1.570796325` in a URDF leaves a rigid motion. Scaled to unit norm it would look independent.
    let m = DMatrix::from_fn(3, 200, |r, c| {
        let t = c as f64;
        match r {
            0 => t.sin(),
            1 => (0.7 * t).cos(),
            _ => 1e-9 * (1.3 * t).sin(),
        }
    });
    let gram = gram_by_product(&m);
    let rep = analyse(
        &gram,
        &ParameterInfo {
            order: &[0, 1, 2],
            allowed: &[true; 3],
            name: &|k| format!("p{k}"),
            reason: &|_| None,
            data: ParameterInfo::DISTANCES,
            not_allowed: ParameterInfo::FIXED_BY_USER,
        },
    );
    assert_eq!(rep.free, [0, 1]);
    assert_eq!(rep.fixed[0].index, 2);
    assert!(
        rep.fixed[0].reason.contains("do not depend"),
        "{}",
        rep.fixed[0].reason
    );
    assert!(rep.condition_before.is_infinite());
}

#[test]
fn user_fixed_and_near_dependent_parameters_are_reported() {
    let m = DMatrix::from_fn(3, 100, |r, c| {
        let t = c as f64;
        match r {
            0 => t.sin(),
            1 => (0.7 * t).cos(),
            // Nearly the first column.
            _ => t.sin() + 1e-4 * (0.7 * t).cos() + 1e-4 * (2.1 * t).sin(),
        }
    });
    let rep = analyse(
        &gram_by_product(&m),
        &ParameterInfo {
            order: &[0, 1, 2],
            allowed: &[true, false, true],
            name: &|k| format!("p{k}"),
            reason: &|_| None,
            data: ParameterInfo::DISTANCES,
            not_allowed: ParameterInfo::FIXED_BY_USER,
        },
    );
    assert_eq!(rep.free, [0]);
    assert_eq!(rep.fixed[0].reason, "fixed by the user");
    assert!(rep.fixed[1].reason.contains("near-dependent") && rep.fixed[1].reason.contains("p0"));
}

/// The run's re-check at the solution takes its Gram matrix from the pair sums (every pair of the
/// configurations they use, over the free parameters); the planner's forms it on the start's sample of
/// pairs by one product (until the sixteenth session by a QR). Their verdicts — which parameters stay
/// free, which are fixed, whether the condition number grew beyond `CONDITION_GROWTH` — agree at the
/// solutions of every distance method on every test robot, and their condition numbers within a few
/// per cent (two samples of the same configurations).
#[test]
fn the_recheck_by_product_gives_the_qr_verdicts() {
    use crate::dataset::Split;
    use crate::robot::{ArmLinks, LoadOptions, RobotDescription, RobotSource};
    use crate::side::{PerSide, Side};
    use crate::simulate::{paper_options, simulate_with_robot};
    use crate::solver::methods::set_up::IDENTIFIABILITY_PAIRS;
    use crate::solver::methods::table::Method;
    use crate::solver::run::calibrator::Calibrator;
    use crate::solver::run::executor::CONDITION_GROWTH;
    use crate::solver::settings::CalibrationSettings;
    let urdf = |text: String, arms: [(&str, &str); 2]| {
        let options = LoadOptions {
            arms: PerSide::new(
                Some(ArmLinks::new(arms[0].0, arms[0].1)),
                Some(ArmLinks::new(arms[1].0, arms[1].1)),
            ),
            ..LoadOptions::default()
        };
        RobotDescription::load(
            RobotSource::Text {
                text: &text,
                path: None,
            },
            &options,
        )
        .expect("test robot")
    };
    let robots = [
        RobotDescription::builtin_irb14000(),
        urdf(yumi_like_urdf(), crate::test_robots::YUMI_LIKE_ARMS),
        urdf(dual_ur_like_urdf(), crate::test_robots::DUAL_UR_ARMS),
    ];
    let mut checked = 0;
    for (r, robot) in robots.iter().enumerate() {
        let sim = simulate_with_robot(&paper_options(20 + r as u64, 70, 50), robot).unwrap();
        for method in [
            Method::Minimax,
            Method::LeastSquares,
            Method::DistanceSingle,
        ] {
            let settings = CalibrationSettings {
                method,
                ..CalibrationSettings::default()
            };
            let result = Calibrator::new(&sim.dataset, &sim.nominal)
                .settings(settings.clone())
                .run()
                .unwrap();
            for side in Side::BOTH {
                let start = result.identifiability[side].as_ref().unwrap();
                let fast = result.identifiability_at_solution[side].as_ref().unwrap();
                let qs: Vec<Vec<f64>> = sim
                    .dataset
                    .arm(side)
                    .measurements
                    .iter()
                    .filter(|m| m.split == Split::Cal)
                    .map(|m| m.q_rad.clone())
                    .collect();
                let arm = result.calibrated.arm(side);
                let at = |how| at_solution(arm, &qs, &start.free, IDENTIFIABILITY_PAIRS, how);
                let (product, qr) = (at(GramMethod::Product), at(GramMethod::Qr));
                let case = format!("robot {r}, {}, {side} arm", method.name());
                let fixed = |rep: &IdentifiabilityReport| -> Vec<(usize, String)> {
                    rep.fixed
                        .iter()
                        .map(|f| (f.index, f.reason.clone()))
                        .collect()
                };
                // (Residuals of parameters fixed by the user are NaN: no `==` on whole reports.)
                let indices = |rep: &IdentifiabilityReport| -> Vec<usize> {
                    rep.fixed.iter().map(|f| f.index).collect()
                };
                assert_eq!(
                    fast.free, product.free,
                    "{case}: the run's re-check keeps the sample's parameters"
                );
                assert_eq!(indices(fast), indices(&product), "{case}");
                // At most 80 configurations, the sums' pairs are the sample's.
                let apart = fast.condition_after / product.condition_after - 1.0;
                assert!(
                    apart.abs() < 1e-9,
                    "{case}: the sums' condition number {:e}, the sample's {:e}",
                    fast.condition_after,
                    product.condition_after
                );
                assert_eq!(product.free, qr.free, "{case}");
                assert_eq!(fixed(&product), fixed(&qr), "{case}");
                let grew = |rep: &IdentifiabilityReport| {
                    rep.condition_after > CONDITION_GROWTH * start.condition_after
                };
                assert_eq!(grew(&product), grew(&qr), "{case}");
                assert_eq!(grew(fast), grew(&product), "{case}");
                let rel = product.condition_after / qr.condition_after - 1.0;
                assert!(
                    rel.abs() < 1e-8,
                    "{case}: condition numbers differ by {rel:e}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 18);
}

/// The built-in robot's paper-like simulation (`configs` per arm, `cal` of them to calibrate) and its
/// default calibration.
fn calibrated_builtin(
    seed: u64,
    configs: usize,
    cal: usize,
) -> (
    crate::simulate::SimOutput,
    crate::solver::result::CalibrationResult,
) {
    use crate::robot::RobotDescription;
    use crate::simulate::{paper_options, simulate_with_robot};
    use crate::solver::run::calibrator::Calibrator;
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(seed, configs, cal), &robot).unwrap();
    let result = Calibrator::new(&sim.dataset, &sim.nominal).run().unwrap();
    (sim, result)
}

/// The joint values and measured points of `side`'s calibration split.
fn calibration_split(
    dataset: &crate::dataset::Dataset,
    side: crate::side::Side,
) -> (Vec<Vec<f64>>, Vec<Vec<Vector3<f64>>>) {
    dataset
        .arm(side)
        .select(crate::dataset::Split::Cal)
        .iter()
        .map(|m| (m.q_rad.clone(), m.tracker_points_mm.clone()))
        .unzip()
}

/// The re-check from the pair sums is the sampled re-check when the sample is every pair of the
/// configurations the sums use: the same Gram matrix over the free parameters up to rounding, so the
/// same verdicts and condition number.
#[test]
fn the_recheck_of_the_sums_is_the_recheck_of_every_pair() {
    use crate::side::Side;
    use crate::solver::analysis::uncertainty::{MAX_CONFIGURATIONS, PairSums};
    let (sim, result) = calibrated_builtin(31, 60, 40);
    for side in Side::BOTH {
        let start = result.identifiability[side].as_ref().unwrap();
        let (qs, measured) = calibration_split(&sim.dataset, side);
        assert!(qs.len() <= MAX_CONFIGURATIONS);
        let arm = result.calibrated.arm(side);
        let sums = PairSums::new(arm, &qs, &measured, &start.free);
        let of_sums = at_solution_of_sums(arm, &sums).unwrap();
        let every_pair = at_solution(arm, &qs, &start.free, usize::MAX, GramMethod::Product);
        assert_eq!(of_sums.free, every_pair.free, "{side}");
        assert_eq!(of_sums.free, start.free, "{side}");
        let rel = of_sums.condition_after / every_pair.condition_after - 1.0;
        assert!(rel.abs() < 1e-9, "{side}: {rel:e}");
        // The allowed parameters' condition number: all of them kept, so the same.
        let rel = of_sums.condition_before / of_sums.condition_after - 1.0;
        assert!(rel.abs() < 1e-12, "{side}: {rel:e}");
        // What the run kept is this analysis.
        let run = result.identifiability_at_solution[side].as_ref().unwrap();
        assert_eq!(run.free, of_sums.free);
        assert_eq!(run.condition_after, of_sums.condition_after);
    }
}

/// Beyond `uncertainty::MAX_CONFIGURATIONS` the sums take every k-th configuration's pairs and the
/// sampled re-check every k-th pair of all the configurations: two samples of the same data, whose
/// verdicts agree and whose condition numbers differ by a few per cent (here −2.7 % and −3.9 %; the
/// warning is for a growth of 10×).
#[test]
fn the_recheck_of_the_sums_beyond_their_configurations_keeps_the_verdicts() {
    use crate::side::Side;
    use crate::solver::analysis::uncertainty::MAX_CONFIGURATIONS;
    use crate::solver::methods::set_up::IDENTIFIABILITY_PAIRS;
    let (sim, result) = calibrated_builtin(37, 200, 180);
    for side in Side::BOTH {
        let start = result.identifiability[side].as_ref().unwrap();
        let (qs, _) = calibration_split(&sim.dataset, side);
        assert!(qs.len() > 2 * MAX_CONFIGURATIONS);
        let arm = result.calibrated.arm(side);
        let run = result.identifiability_at_solution[side].as_ref().unwrap();
        let sampled = at_solution(
            arm,
            &qs,
            &start.free,
            IDENTIFIABILITY_PAIRS,
            GramMethod::Product,
        );
        assert_eq!(run.free, sampled.free, "{side}");
        let apart = run.condition_after / sampled.condition_after - 1.0;
        assert!(apart.abs() < 0.1, "{side}: {apart:e}");
    }
}
