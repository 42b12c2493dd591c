//! The error model's Jacobian columns against central differences (DH and chain forms, every term),
//! and its parameters through the parameter vector.

use super::*;
use crate::kinematics::chain::tests::{random_arm, random_q};
use crate::kinematics::tests::{check_arm_jacobian, stacked_jacobian};
use crate::kinematics::{ArmModel, SerialChain};
use crate::test_robots::{lift_mimic_urdf, yumi_like_urdf};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FULL: ErrorTerms = ErrorTerms {
    elastic: true,
    bending: true,
    harmonics: 2,
};

/// `model` with random error values of a realistic size: compliances 0.005–0.08 mrad/(N·m),
/// harmonics within ±1 mrad, and held masses of 0.5–4 kg with moments within ±400 kg·mm.
fn with_random_errors(model: ArmModel, rng: &mut ChaCha8Rng) -> ArmModel {
    let mut model = model.with_error_terms(FULL, Vector3::new(0.1, -0.2, -1.0));
    // Gear ratios on every other joint (motor-side harmonics), one of them 1 (no motor term).
    let names = model.errors.model.as_ref().unwrap().joint_names().to_vec();
    let ratios: Vec<(String, f64)> = names
        .iter()
        .step_by(2)
        .zip([100.0, -50.5, 1.0, 160.0, 80.0])
        .map(|(n, r)| (n.clone(), r))
        .collect();
    model = model.with_gear_ratios(&ratios);
    let off = model.error_offset();
    let m = model.errors.model.clone().unwrap();
    let masses = (0..m.link_masses().len())
        .map(|_| {
            (
                rng.random_range(0.5..4.0),
                Vector3::from_fn(|_, _| rng.random_range(-400.0..400.0)),
            )
        })
        .collect();
    model.errors.model = Some(Arc::new(m.with_masses(masses).unwrap()));
    let mut v = model.to_vector();
    for i in 0..m.param_count() {
        v[off + i] = if m.param_is_compliance(i) {
            rng.random_range(0.005..0.08)
        } else {
            rng.random_range(-1e-3..1e-3)
        };
    }
    model.with_vector(&v)
}

#[test]
fn dh_error_columns_match_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..5 {
        let model = with_random_errors(crate::kinematics::tests::perturbed(&mut rng), &mut rng);
        // 28 DH, 9 reflector, 4 harmonics and 2 compliances (axis, α) per joint, 4 motor harmonics
        // on each of j1, j3, j7 (j5's ratio is 1).
        assert_eq!(model.param_count(), 28 + 9 + 7 * 4 + 14 + 3 * 4);
        let names: Vec<String> = (0..model.param_count())
            .map(|k| model.param_name(k))
            .collect();
        assert!(names.contains(&"j7.m2_sin".to_string()), "{names:?}");
        assert!(!names.iter().any(|n| n.starts_with("j5.m")), "{names:?}");
        let q = crate::kinematics::tests::random_q(&mut rng);
        if let Err(e) = check_arm_jacobian(&model, &q, &stacked_jacobian(&model, &q)) {
            panic!("q {q:?}: {e}");
        }
    }
}

#[test]
fn chain_error_columns_match_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    for (text, base, tip) in [
        (yumi_like_urdf(), "yumi_body", "yumi_link_7_l"),
        (lift_mimic_urdf(), "torso", "left_flange"),
    ] {
        let robot = urdf_rs::read_from_string(&text).unwrap();
        let chain = Arc::new(SerialChain::from_urdf(&robot, base, tip).unwrap());
        for _ in 0..4 {
            let model = with_random_errors(random_arm(&chain, &mut rng, 1.0, 0.01), &mut rng);
            let q = random_q(&chain, &mut rng);
            if let Err(e) = check_arm_jacobian(&model, &q, &stacked_jacobian(&model, &q)) {
                panic!("{base} → {tip}, q {q:?}: {e}");
            }
        }
    }
}

#[test]
fn start_model_is_the_geometric_model() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let geometric = crate::kinematics::tests::perturbed(&mut rng);
    let start = geometric.clone().with_error_terms(FULL, -Vector3::z());
    for _ in 0..5 {
        let q = crate::kinematics::tests::random_q(&mut rng);
        assert_eq!(
            start.reflector_fk(&q).points_mm,
            geometric.reflector_fk(&q).points_mm
        );
    }
    // Names are unique and the vector round-trips.
    let names: std::collections::HashSet<String> = (0..start.param_count())
        .map(|k| start.param_name(k))
        .collect();
    assert_eq!(names.len(), start.param_count());
    let v = DVector::from_fn(start.param_count(), |k, _| k as f64 * 0.1);
    assert_eq!(start.with_vector(&v).to_vector(), v);
}

#[test]
fn an_axis_deflection_is_the_gravity_torque_times_the_compliance() {
    // One joint's arm: a 2 kg mass 500 mm out along x of the tip, the joint axis horizontal (y):
    // τ = 2 kg · 9.80665 m/s² · 0.5 m about the axis; with 0.1 mrad/(N·m) the joint gives 0.98 mrad.
    let urdf = r#"<robot name="one"><link name="base"/><link name="tip"/>
        <joint name="j" type="revolute"><parent link="base"/><child link="tip"/>
        <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
        </robot>"#;
    let robot = urdf_rs::read_from_string(urdf).unwrap();
    let chain = Arc::new(SerialChain::from_urdf(&robot, "base", "tip").unwrap());
    let terms = ErrorTerms::from_name("elastic-axis").unwrap();
    let model = ArmModel::nominal_chain(chain, [Vector3::new(500.0, 0.0, 0.0)])
        .with_error_terms(terms, -Vector3::z());
    let mut v = model.to_vector();
    let off = model.error_offset();
    let name = |k: usize| model.param_name(k);
    let find = |n: &str| (off..model.param_count()).find(|&k| name(k) == n).unwrap();
    v[find("j.k_axis")] = 0.1;
    let mut model = model.with_vector(&v);
    let m = model.errors.model.clone().unwrap();
    let masses = vec![(2.0, Vector3::new(2.0 * 500.0, 0.0, 0.0))];
    model.errors.model = Some(Arc::new(m.with_masses(masses).unwrap()));
    let inc = model.errors.increments(&[0.0]).unwrap();
    let expected = 0.1e-3 * 2.0 * STANDARD_GRAVITY_M_S2 * 0.5;
    assert_eq!(inc.slots.len(), 1);
    let (_, value, _) = &inc.slots[0];
    // The mass on +x under −z gravity turns the arm about +y positively (x → −z).
    assert!(
        (value.abs() - expected).abs() < 1e-12,
        "{value} vs {expected}"
    );
    let p = model.reflector_fk(&[0.0]).points_mm[0];
    assert!((p.z.abs() - 500.0 * expected.sin()).abs() < 1e-9, "{p:?}");
    assert!(p.z < 0.0, "the tip sags: {p:?}");
}

#[test]
fn model_names_parse() {
    for (name, terms, _) in ErrorTerms::NAMED {
        assert_eq!(ErrorTerms::from_name(name).unwrap(), terms);
        assert_eq!(terms.name(), name);
    }
    assert!(ErrorTerms::from_name("elastics").is_err());
}

/// A torso both arms share, measured together: the other arm's masses load the torso's hinges. The
/// left arm's points move when only the right arm moves, and the Jacobian stays exact.
#[test]
fn the_other_arm_loads_the_shared_torso() {
    use crate::kinematics::DualArmModel;
    use crate::side::PerSide;
    use crate::test_robots::{SHARED_TORSO_ARMS, shared_torso_urdf};
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let robot = urdf_rs::read_from_string(&shared_torso_urdf(true)).unwrap();
    let chains = PerSide::from_fn(|side| {
        let (base, tip) = SHARED_TORSO_ARMS[usize::from(side == crate::side::Side::Right)];
        Arc::new(SerialChain::from_urdf(&robot, base, tip).unwrap())
    });
    let geometric = DualArmModel {
        arms: chains
            .as_ref()
            .map(|_, c| random_arm(c, &mut rng, 0.5, 0.005)),
        left_base_from_right_base: Isometry3::identity(),
    };
    let shared = geometric.shared_joints();
    assert!(!shared.is_empty());
    let elastic = ErrorTerms::from_name("elastic").unwrap();
    let mut model = geometric.with_error_terms(elastic, -Vector3::z());
    for side in crate::side::Side::BOTH {
        let arm = model.arm(side);
        let mut v = arm.to_vector();
        for k in arm.error_offset()..arm.param_count() {
            if arm
                .errors
                .model
                .as_ref()
                .unwrap()
                .param_is_compliance(k - arm.error_offset())
            {
                v[k] = rng.random_range(0.01..0.1);
            }
        }
        *model.arm_mut(side) = arm.with_vector(&v);
    }
    // Two instants with the same left configuration (torso included) and different right arms.
    let q_left = random_q(&chains.left, &mut rng);
    let mut q_right = random_q(&chains.right, &mut rng);
    for &(l, r) in &shared.variables {
        q_right[r] = q_left[l];
    }
    let mut q_right_2 = random_q(&chains.right, &mut rng);
    for &(l, r) in &shared.variables {
        q_right_2[r] = q_left[l];
    }
    let a = model
        .clone()
        .with_torso_instants(&[(q_left.clone(), q_right.clone())]);
    let b = model
        .clone()
        .with_torso_instants(&[(q_left.clone(), q_right_2.clone())]);
    let (pa, pb, p0) = (
        a.arm(crate::side::Side::Left)
            .reflector_fk(&q_left)
            .points_mm[0],
        b.arm(crate::side::Side::Left)
            .reflector_fk(&q_left)
            .points_mm[0],
        model
            .arm(crate::side::Side::Left)
            .reflector_fk(&q_left)
            .points_mm[0],
    );
    assert!((pa - pb).norm() > 1e-3, "{pa:?} vs {pb:?}");
    assert!((pa - p0).norm() > 1e-3, "{pa:?} vs {p0:?}");
    // A configuration that is no instant of the data: the arm's own masses only.
    let other_q = random_q(&chains.left, &mut rng);
    assert_eq!(
        a.arm(crate::side::Side::Left)
            .reflector_fk(&other_q)
            .points_mm,
        model
            .arm(crate::side::Side::Left)
            .reflector_fk(&other_q)
            .points_mm
    );
    for (arm, q) in [
        (a.arm(crate::side::Side::Left), &q_left),
        (a.arm(crate::side::Side::Right), &q_right),
    ] {
        if let Err(e) = check_arm_jacobian(arm, q, &stacked_jacobian(arm, q)) {
            panic!("{e}");
        }
    }
}
