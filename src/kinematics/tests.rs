//! Tests of the DH kinematics and the arm model.

use super::*;
use crate::finite_difference::{Tolerance, check_jacobian};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn nominal() -> ArmModel {
    ArmModel::nominal_irb14000([
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ])
}

pub(crate) fn random_q(rng: &mut ChaCha8Rng) -> [f64; N_JOINTS] {
    let lim = joint_limits_rad();
    std::array::from_fn(|i| rng.random_range(lim[i].0..lim[i].1))
}

pub(crate) fn perturbed(rng: &mut ChaCha8Rng) -> ArmModel {
    let m = nominal();
    let mut v = m.to_vector();
    for k in 0..N_PARAMS {
        v[k] += if param_is_angle(k) {
            rng.random_range(-0.01..0.01)
        } else {
            rng.random_range(-1.0..1.0)
        };
    }
    m.with_vector(&v)
}

#[test]
fn vector_roundtrip() {
    let m = nominal();
    assert_eq!(m.with_vector(&m.to_vector()), m);
    assert_eq!(m.to_vector().len(), N_PARAMS);
    assert_eq!(m.param_count(), N_PARAMS);
}

#[test]
fn dh_transform_matches_composition() {
    let row = DhRow::new(12.0, -7.0, 0.3, -1.1);
    let q = 0.77;
    let composed = Isometry3::rotation(Vector3::z() * (q + row.theta_rad))
        * Isometry3::translation(0.0, 0.0, row.d_mm)
        * Isometry3::translation(row.a_mm, 0.0, 0.0)
        * Isometry3::rotation(Vector3::x() * row.alpha_rad);
    let t = row.transform(q);
    assert!((t.to_homogeneous() - composed.to_homogeneous()).abs().max() < 1e-12);
}

#[test]
fn zero_pose_matches_hand_computation() {
    // At q = 0 the flange z axis and position follow from Table 3 by hand:
    // frame 1: x=(1,0,0), z=(0,1,0) after alpha=-pi/2 ... checked through an independent product.
    let m = nominal();
    let q = [0.0; N_JOINTS];
    let mut t = nalgebra::Matrix4::<f64>::identity();
    for row in m.dh().unwrap() {
        let (st, ct) = row.theta_rad.sin_cos();
        let (sa, ca) = row.alpha_rad.sin_cos();
        #[rustfmt::skip]
        let a = nalgebra::Matrix4::new(
            ct, -st * ca, st * sa, row.a_mm * ct,
            st, ct * ca, -ct * sa, row.a_mm * st,
            0.0, sa, ca, row.d_mm,
            0.0, 0.0, 0.0, 1.0,
        );
        t *= a;
    }
    let f = m.base_from_flange(&q).to_homogeneous();
    assert!((f - t).abs().max() < 1e-9, "{f}\n{t}");
}

/// The three reflector Jacobians stacked (rows: t_a x, y, z, t_b …, t_c …).
pub(crate) fn stacked_jacobian(model: &ArmModel, q: &[f64]) -> DMatrix<f64> {
    let jac = model.reflector_jacobians(q).jacobians;
    DMatrix::from_fn(9, model.param_count(), |r, c| jac[r / 3][(r % 3, c)])
}

/// Check `jac` (stacked as [`stacked_jacobian`]) against central differences of the reflector
/// points of `model` (either form) at `q`; the message names reflector rows and parameters.
pub(crate) fn check_arm_jacobian(
    model: &ArmModel,
    q: &[f64],
    jac: &DMatrix<f64>,
) -> Result<(), String> {
    let points = |v: &DVector<f64>| {
        let fk = model.with_vector(v).reflector_fk(q);
        DVector::from_iterator(9, fk.points_mm.iter().flat_map(|p| p.iter().copied()))
    };
    let step = |k: usize| if model.param_is_angle(k) { 1e-6 } else { 1e-4 };
    check_jacobian(points, &model.to_vector(), jac, step, Tolerance::rel(1e-6)).map_err(|e| {
        e.describe(
            |r| format!("t_{}.{}", REFLECTOR_NAMES[r / 3], ["x", "y", "z"][r % 3]),
            |k| model.param_name(k),
        )
    })
}

#[test]
fn analytic_jacobian_matches_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..20 {
        let model = perturbed(&mut rng);
        let q = random_q(&mut rng);
        if let Err(e) = check_arm_jacobian(&model, &q, &stacked_jacobian(&model, &q)) {
            panic!("q {q:?}: {e}");
        }
    }
}

#[test]
fn jacobian_check_detects_a_wrong_column() {
    // The check above must be able to fail: given a Jacobian whose α4 column is θ5's (a plausible
    // indexing slip), it names α4 and nothing else.
    let model = nominal();
    let q = [0.3, -0.5, 0.2, -0.4, 0.6, 0.5, -0.2];
    let alpha4 = 3 * 4 + 3;
    let mut jac = stacked_jacobian(&model, &q);
    check_arm_jacobian(&model, &q, &jac).expect("the true Jacobian passes");
    let theta5 = jac.column(alpha4 + 1).into_owned();
    jac.set_column(alpha4, &theta5);
    let err = check_arm_jacobian(&model, &q, &jac).unwrap_err();
    assert!(err.contains("alpha4") && !err.contains("theta5"), "{err}");
}

#[test]
fn rotation_angle_is_robust() {
    for &a in &[0.0, 1e-9, 0.3, 1.0, 3.0, std::f64::consts::PI - 1e-7] {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), a);
        assert!((rotation_angle_rad(&r) - a).abs() < 1e-9, "{a}");
    }
}

#[test]
fn param_names() {
    assert_eq!(param_name(0), "a1");
    assert_eq!(param_name(2), "theta1");
    assert_eq!(param_name(27), "alpha7");
    assert_eq!(param_name(28), "t_a.x");
    assert_eq!(param_name(36), "t_c.z");
}

#[test]
fn dh_path_matches_the_static_jacobian_bit_for_bit() {
    // The dynamic Jacobian of the DH form is a copy of the static 3 × 37 one.
    let model = nominal();
    let q = [0.3, -0.5, 0.2, -0.4, 0.6, 0.5, -0.2];
    let ArmKinematics::Dh(dh) = &model.kinematics else {
        panic!("DH")
    };
    let stat = dh::reflector_jacobians(dh, &model.reflectors_mm, &q).jacobians;
    let dynamic = model.reflector_jacobians(&q).jacobians;
    for k in 0..3 {
        assert_eq!(stat[k].as_slice(), dynamic[k].as_slice());
    }
    // Joint frames: frame i's z axis is joint i+1's axis, then the flange.
    let frames = model.joint_frames(&q);
    assert_eq!(frames.len(), N_JOINTS + 1);
    assert_eq!(frames[N_JOINTS], model.base_from_flange(&q));
}
