//! Unit tests of the metrics.

use super::*;
use crate::dataset::{Measurement, TrackerSpec};
use crate::kinematics::rotation_angle_rad;
use crate::kinematics::{DhRow, N_JOINTS, N_PARAMS, joint_limits_rad, param_is_angle};
use crate::side::PerSide;
use nalgebra::{Matrix3, Rotation3, Translation3, UnitQuaternion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;

fn nominal_reflectors() -> [Vector3<f64>; 3] {
    [
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ]
}

fn random_unit(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.norm() > 0.1 && v.norm() < 1.0 {
            return v.normalize();
        }
    }
}

fn random_isometry(rng: &mut ChaCha8Rng, scale_mm: f64) -> Isometry3<f64> {
    let axis = random_unit(rng);
    let angle = rng.random_range(-3.0..3.0);
    let t = random_unit(rng) * scale_mm;
    Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_scaled_axis(axis * angle),
    )
}

fn perturbed_arm(rng: &mut ChaCha8Rng, size: f64) -> ArmModel {
    let nominal = ArmModel::nominal_irb14000(nominal_reflectors());
    let mut v = nominal.to_vector();
    for k in 0..N_PARAMS {
        v[k] += size
            * if param_is_angle(k) {
                rng.random_range(-0.003..0.003)
            } else {
                rng.random_range(-0.5..0.5)
            };
    }
    nominal.with_vector(&v)
}

fn random_q(rng: &mut ChaCha8Rng) -> [f64; N_JOINTS] {
    let lim = joint_limits_rad();
    std::array::from_fn(|i| rng.random_range(lim[i].0..lim[i].1))
}

/// A dataset measured on `truth` by a tracker at `tracker_from_left_base`, with Gaussian-free uniform
/// noise of ±`noise_mm` per axis; every third configuration is `ver`.
fn simulate(
    truth: &DualArmModel,
    tracker_from_left_base: &Isometry3<f64>,
    n: [usize; 2],
    noise_mm: f64,
    seed: u64,
) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut arm = |side: Side, count: usize| {
        let tracker_from_base = tracker_from_left_base * truth.left_base_from(side);
        let measurements = (0..count)
            .map(|i| {
                let q_rad = random_q(&mut rng);
                let fk = truth.arm(side).reflector_fk(&q_rad);
                let tracker_points_mm = fk
                    .points_mm
                    .iter()
                    .map(|p| {
                        let noise = Vector3::from_fn(|_, _| rng.random_range(-1.0..=1.0));
                        tracker_from_base.transform_point(&(*p).into()).coords + noise * noise_mm
                    })
                    .collect();
                Measurement {
                    id: format!("{}{i:03}", side.name()),
                    q_rad: q_rad.to_vec(),
                    tracker_points_mm,
                    split: if i % 3 == 2 { Split::Ver } else { Split::Cal },
                    line: i + 2,
                }
            })
            .collect();
        ArmData {
            side,
            file: PathBuf::from(format!("{}.csv", side.name())),
            links: None,
            station: None,
            linear_joints: Vec::new(),
            nominal_reflectors_mm: None,
            measurements,
        }
    };
    let left = arm(Side::Left, n[0]);
    let right = arm(Side::Right, n[1]);
    Dataset {
        dir: PathBuf::from("mem"),
        robot: None,
        tracker: TrackerSpec::default(),
        nominal_reflectors_mm: nominal_reflectors().to_vec(),
        reflector_names: crate::kinematics::default_reflector_names(3),
        arms: PerSide::new(left, right),
        measured_together: false,
    }
}

fn nominal_base() -> Isometry3<f64> {
    #[rustfmt::skip]
    let r = Matrix3::new(
        0.2352, -0.8755, 0.4220,
        0.8746, 0.0012, -0.4849,
        0.4241, 0.4831, 0.7660,
    );
    Isometry3::from_parts(
        Translation3::new(61.61, -70.77, -34.14),
        UnitQuaternion::from_matrix(&r),
    )
}

fn true_model(rng: &mut ChaCha8Rng) -> DualArmModel {
    DualArmModel {
        arms: PerSide::new(perturbed_arm(rng, 1.0), perturbed_arm(rng, 1.0)),
        left_base_from_right_base: nominal_base(),
    }
}

fn all_stats(r: &AccuracyReport) -> [AccuracyStats; 3] {
    [
        r.relative_left.unwrap(),
        r.relative_right.unwrap(),
        r.collaborative.unwrap(),
    ]
}

fn assert_reports_close(a: &AccuracyReport, b: &AccuracyReport, tol: f64) {
    for (x, y) in all_stats(a).iter().zip(all_stats(b).iter()) {
        let vx = serde_json::to_value(x).unwrap();
        let vy = serde_json::to_value(y).unwrap();
        let (ox, oy) = (vx.as_object().unwrap(), vy.as_object().unwrap());
        for (k, v) in ox {
            let flat = |v: &serde_json::Value| -> Vec<f64> {
                match v {
                    serde_json::Value::Array(a) => a.iter().map(|e| e.as_f64().unwrap()).collect(),
                    e => vec![e.as_f64().unwrap()],
                }
            };
            for (p, q) in flat(v).iter().zip(flat(&oy[k])) {
                assert!((p - q).abs() <= tol, "{k}: {p} vs {q}");
            }
        }
    }
}

#[test]
fn perfect_model_on_noise_free_data_gives_zero() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let truth = true_model(&mut rng);
    let ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [15, 12], 0.0, 2);
    let r = evaluate(&ds, &truth, Split::All).unwrap();
    for s in all_stats(&r) {
        assert!(s.pos_max_mm < 1e-9, "{s:?}");
        assert!(s.ori_max_rad.unwrap() < 1e-7, "{s:?}");
        assert_eq!(s.pos_within_0_3mm_frac, 1.0);
        assert_eq!(s.ori_within_0_005rad_frac.unwrap(), 1.0);
    }
    assert_eq!(r.relative_left.unwrap().n_pairs, 15 * 14 / 2);
    assert_eq!(r.relative_right.unwrap().n_pairs, 12 * 11 / 2);
    assert_eq!(r.collaborative.unwrap().n_pairs, 15 * 12);
    assert_eq!(r.collaborative.unwrap().n_configs, 27);
    // The nominal model on the same data is clearly wrong (mm-level), so the check above can fail.
    let nominal = DualArmModel {
        arms: PerSide::new(
            ArmModel::nominal_irb14000(nominal_reflectors()),
            ArmModel::nominal_irb14000(nominal_reflectors()),
        ),
        left_base_from_right_base: nominal_base(),
    };
    let rn = evaluate(&ds, &nominal, Split::All).unwrap();
    for s in all_stats(&rn) {
        assert!(s.pos_rms_mm > 0.2, "{s:?}");
        assert!(s.ori_rms_rad.unwrap() > 1e-4, "{s:?}");
    }
}

#[test]
fn split_selects_configurations() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let truth = true_model(&mut rng);
    let ds = simulate(&truth, &Isometry3::identity(), [9, 7], 0.01, 4);
    let cal = evaluate(&ds, &truth, Split::Cal).unwrap();
    let ver = evaluate(&ds, &truth, Split::Ver).unwrap();
    assert_eq!(cal.relative_left.unwrap().n_configs, 6);
    assert_eq!(ver.relative_left.unwrap().n_configs, 3);
    assert_eq!(cal.relative_right.unwrap().n_configs, 5);
    assert_eq!(ver.relative_right.unwrap().n_configs, 2);
    assert_eq!(ver.collaborative.unwrap().n_pairs, 6);
    let p = relative_pairs(&ds, &truth, Side::Left, Split::Ver).unwrap();
    let ids: Vec<_> = p
        .iter()
        .map(|e| e.ids(&ds, PairKind::Relative(Side::Left)))
        .collect();
    assert_eq!(
        ids,
        vec![
            ("left002", "left005"),
            ("left002", "left008"),
            ("left005", "left008")
        ]
    );
}

#[test]
fn base_translation_error_gives_the_expected_collaborative_error() {
    // Hand-built: all DH parameters zero and q = 0, so the flange is the base; the tracker frame is
    // the left base and the right base sits 300 mm along x. Every measured left-right distance is
    // 300 mm for every reflector.
    let zero_arm = ArmModel {
        kinematics: crate::kinematics::ArmKinematics::Dh(
            [DhRow::new(0.0, 0.0, 0.0, 0.0); N_JOINTS],
        ),
        reflectors_mm: nominal_reflectors().to_vec(),
        reflector_names: crate::kinematics::default_reflector_names(3),
        errors: Default::default(),
    };
    let truth = DualArmModel {
        arms: PerSide::new(zero_arm.clone(), zero_arm.clone()),
        left_base_from_right_base: Isometry3::translation(300.0, 0.0, 0.0),
    };
    let mut ds = simulate(&truth, &Isometry3::identity(), [3, 4], 0.0, 5);
    for (arm, offset) in [(&mut ds.arms.left, 0.0), (&mut ds.arms.right, 300.0)] {
        for m in &mut arm.measurements {
            m.q_rad = vec![0.0; N_JOINTS];
            m.tracker_points_mm = nominal_reflectors()
                .map(|t| t + Vector3::x() * offset)
                .to_vec();
        }
    }
    let mut wrong = truth.clone();
    // 4 mm sideways: model distance sqrt(300² + 4²), so Δd = 300 − sqrt(90016) for every pair.
    wrong.left_base_from_right_base = Isometry3::translation(300.0, 4.0, 0.0);
    let expected = 300.0 - 90016.0f64.sqrt();
    let pairs = collaborative_pairs(&ds, &wrong, Split::All).unwrap();
    assert_eq!(pairs.len(), 12);
    for p in &pairs {
        for &d in p.pos_error_mm.iter() {
            assert!((d - expected).abs() < 1e-12, "{d} vs {expected}");
        }
        assert!((p.pos_worst_mm - expected).abs() < 1e-12);
        assert!(p.ori_error_rad.unwrap() < 1e-12);
    }
    // 2 mm further along x: Δd = 300 − 302 = −2 mm.
    wrong.left_base_from_right_base = Isometry3::translation(302.0, 0.0, 0.0);
    let r = evaluate(&ds, &wrong, Split::All).unwrap();
    assert!((r.collaborative.unwrap().pos_rms_mm - 2.0).abs() < 1e-12);
    assert!((r.collaborative.unwrap().pos_max_mm - 2.0).abs() < 1e-12);
    assert_eq!(r.collaborative.unwrap().pos_within_0_6mm_frac, 0.0);
    assert!(
        r.relative_left.unwrap().pos_max_mm < 1e-12 && r.relative_right.unwrap().pos_max_mm < 1e-12
    );
}

#[test]
fn base_translation_error_on_a_real_arm() {
    // A base translation error δ leaves the relative figures and all orientations alone and changes
    // each collaborative distance to |v − δ| where v = p_L − B·p_R on the true robot.
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let truth = true_model(&mut rng);
    let ds = simulate(&truth, &random_isometry(&mut rng, 2500.0), [5, 6], 0.0, 7);
    let delta = Vector3::new(1.5, -0.7, 2.0);
    let mut wrong = truth.clone();
    wrong.left_base_from_right_base =
        Isometry3::from_parts(Translation3::from(delta), Default::default())
            * truth.left_base_from_right_base;
    let pairs = collaborative_pairs(&ds, &wrong, Split::All).unwrap();
    let mut n = 0;
    for p in &pairs {
        let l = truth
            .arms
            .left
            .reflector_fk(&ds.arms.left.measurements[p.first].q_rad);
        let r = truth
            .arms
            .right
            .reflector_fk(&ds.arms.right.measurements[p.second].q_rad);
        for k in 0..3 {
            let v = l.points_mm[k]
                - truth
                    .left_base_from_right_base
                    .transform_point(&r.points_mm[k].into())
                    .coords;
            let expected = v.norm() - (v - delta).norm();
            assert!((p.pos_error_mm[k] - expected).abs() < 1e-9);
            assert!(expected.abs() > 1e-3);
            n += 1;
        }
        assert!(p.ori_error_rad.unwrap() < 1e-7);
    }
    assert_eq!(n, 5 * 6 * 3);
    let r = evaluate(&ds, &wrong, Split::All).unwrap();
    assert!(
        r.relative_left.unwrap().pos_max_mm < 1e-9
            && r.relative_right.unwrap().ori_max_rad.unwrap() < 1e-7
    );
}

#[test]
fn rotating_one_measured_triangle_gives_that_orientation_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let truth = true_model(&mut rng);
    let mut ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [6, 5], 0.0, 9);
    let alpha = 0.004;
    let axis = nalgebra::Unit::new_normalize(random_unit(&mut rng));
    let rot = Rotation3::from_axis_angle(&axis, alpha);
    let pts = &mut ds.arms.left.measurements[2].tracker_points_mm;
    let c = (pts[0] + pts[1] + pts[2]) / 3.0;
    for p in pts.iter_mut() {
        *p = c + rot * (*p - c);
    }
    for p in relative_pairs(&ds, &truth, Side::Left, Split::All).unwrap() {
        let expected = if p.first == 2 || p.second == 2 {
            alpha
        } else {
            0.0
        };
        assert!((p.ori_error_rad.unwrap() - expected).abs() < 1e-9, "{p:?}");
    }
    for p in collaborative_pairs(&ds, &truth, Split::All).unwrap() {
        let expected = if p.first == 2 { alpha } else { 0.0 };
        assert!((p.ori_error_rad.unwrap() - expected).abs() < 1e-9, "{p:?}");
    }
    let r = evaluate(&ds, &truth, Split::All).unwrap();
    assert!((r.relative_left.unwrap().ori_max_rad.unwrap() - alpha).abs() < 1e-9);
    assert!(r.relative_right.unwrap().ori_max_rad.unwrap() < 1e-7);
    // 5 of 15 left pairs involve configuration 2.
    let expected_rms = (5.0 / 15.0f64).sqrt() * alpha;
    assert!((r.relative_left.unwrap().ori_rms_rad.unwrap() - expected_rms).abs() < 1e-9);
    assert!((r.relative_left.unwrap().ori_within_0_005rad_frac.unwrap() - 1.0).abs() < 1e-12);
    let per = per_config(&ds, &truth, Split::All).unwrap();
    assert_eq!(per.len(), 11);
    assert!((per[2].relative_ori_max_rad.unwrap() - alpha).abs() < 1e-9);
    assert!((per[2].collaborative_ori_max_rad.unwrap() - alpha).abs() < 1e-9);
    assert!(
        per[3].relative_ori_max_rad.unwrap() > alpha - 1e-9
            && per[3].collaborative_ori_max_rad.unwrap() < 1e-7
    );
    // A rotation about the centroid keeps the triangle rigid and the fit exact.
    assert!(
        per.iter()
            .all(|c| c.rigidity_mm < 1e-9 && c.fit_rms_mm.unwrap() < 1e-9)
    );
}

#[test]
fn tracker_frame_does_not_matter() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let truth = true_model(&mut rng);
    let ds = simulate(
        &truth,
        &random_isometry(&mut rng, 2000.0),
        [10, 9],
        0.05,
        11,
    );
    let nominal = DualArmModel {
        arms: PerSide::new(
            ArmModel::nominal_irb14000(nominal_reflectors()),
            ArmModel::nominal_irb14000(nominal_reflectors()),
        ),
        left_base_from_right_base: nominal_base(),
    };
    let before = evaluate(&ds, &nominal, Split::All).unwrap();
    let moved = random_isometry(&mut rng, 3000.0);
    let mut ds2 = ds.clone();
    for arm in [&mut ds2.arms.left, &mut ds2.arms.right] {
        for m in &mut arm.measurements {
            for p in &mut m.tracker_points_mm {
                *p = moved.transform_point(&(*p).into()).coords;
            }
        }
    }
    let after = evaluate(&ds2, &nominal, Split::All).unwrap();
    assert_reports_close(&before, &after, 1e-9);
    assert!(before.collaborative.unwrap().pos_rms_mm > 0.1);
}

#[test]
fn stats_agree_with_the_pair_lists() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let truth = true_model(&mut rng);
    let ds = simulate(
        &truth,
        &random_isometry(&mut rng, 2000.0),
        [12, 10],
        0.3,
        13,
    );
    let mut model = truth.clone();
    model.arms.left = perturbed_arm(&mut rng, 0.2);
    let r = evaluate(&ds, &model, Split::Cal).unwrap();
    let check = |s: &AccuracyStats, p: &[PairResiduals]| {
        assert_eq!(s.n_pairs, p.len());
        let n = p.len() as f64;
        for k in 0..3 {
            let rms = (p.iter().map(|e| e.pos_error_mm[k].powi(2)).sum::<f64>() / n).sqrt();
            assert!((rms - s.pos_rms_per_reflector_mm[k]).abs() < 1e-9);
        }
        let max = p.iter().map(|e| e.pos_worst_mm.abs()).fold(0.0, f64::max);
        assert!((max - s.pos_max_mm).abs() < 1e-12);
        let frac =
            |f: &dyn Fn(&PairResiduals) -> bool| p.iter().filter(|e| f(e)).count() as f64 / n;
        assert_eq!(
            frac(&|e| e.pos_worst_mm.abs() <= 0.3),
            s.pos_within_0_3mm_frac
        );
        assert_eq!(
            frac(&|e| e.pos_worst_mm.abs() <= 0.6),
            s.pos_within_0_6mm_frac
        );
        assert_eq!(
            frac(&|e| e.ori_error_rad.unwrap() <= 0.005),
            s.ori_within_0_005rad_frac.unwrap()
        );
        assert_eq!(
            frac(&|e| e.ori_error_rad.unwrap() <= 0.01),
            s.ori_within_0_01rad_frac.unwrap()
        );
        let ori = (p
            .iter()
            .map(|e| e.ori_error_rad.unwrap().powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        assert!((ori - s.ori_rms_rad.unwrap()).abs() < 1e-12);
    };
    check(
        &r.relative_left.unwrap(),
        &relative_pairs(&ds, &model, Side::Left, Split::Cal).unwrap(),
    );
    check(
        &r.relative_right.unwrap(),
        &relative_pairs(&ds, &model, Side::Right, Split::Cal).unwrap(),
    );
    check(
        &r.collaborative.unwrap(),
        &collaborative_pairs(&ds, &model, Split::Cal).unwrap(),
    );
    // Not all trivially 0 or 1, so the frequency checks mean something.
    assert!(r.relative_left.unwrap().pos_within_0_3mm_frac < 1.0);
    assert!(r.relative_right.unwrap().pos_within_0_6mm_frac > 0.0);
    let alone = relative_stats(&ds, &model.arms.left, Side::Left, Split::Cal).unwrap();
    assert_reports_close(
        &AccuracyReport {
            relative_left: Some(alone),
            ..r
        },
        &r,
        1e-9,
    );
    let col = collaborative_stats(&ds, &model, Split::Cal).unwrap();
    assert_eq!(col, r.collaborative);
}

#[test]
fn triangle_rigidity_sees_a_displaced_reflector() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let truth = true_model(&mut rng);
    let mut ds = simulate(&truth, &random_isometry(&mut rng, 2000.0), [4, 4], 0.0, 15);
    // Move reflector a 0.25 mm away from b: |ab| grows by 0.25 mm, |ca| by less.
    let m = &mut ds.arms.right.measurements[1];
    let dir = (m.tracker_points_mm[0] - m.tracker_points_mm[1]).normalize();
    m.tracker_points_mm[0] += dir * 0.25;
    let per = per_config(&ds, &truth, Split::All).unwrap();
    let c = per.iter().find(|c| c.id == "right001").unwrap();
    assert!((c.triangle_side_errors_mm[0] - 0.25).abs() < 1e-9, "{c:?}");
    assert!(c.triangle_side_errors_mm[1].abs() < 1e-9);
    assert!((c.rigidity_mm - 0.25).abs() < 1e-9);
    assert!(c.fit_rms_mm.unwrap() > 0.01);
    assert!(
        per.iter()
            .filter(|c| c.id != "right001")
            .all(|c| c.rigidity_mm < 1e-9)
    );
}

#[test]
fn kabsch_recovers_a_random_rotation() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    for _ in 0..200 {
        let model: [Vector3<f64>; 3] =
            std::array::from_fn(|_| random_unit(&mut rng) * rng.random_range(10.0..100.0));
        let truth = random_isometry(&mut rng, 1000.0);
        let measured = model.map(|p| truth.transform_point(&p.into()).coords);
        let fit = kabsch_fit(&model, &measured).unwrap();
        let err =
            rotation_angle_rad(&(fit.rotation.transpose() * truth.rotation.to_rotation_matrix()));
        assert!(err < 1e-9, "{err}");
        assert!((fit.rotation.matrix().determinant() - 1.0).abs() < 1e-12);
        assert!((fit.translation_mm - truth.translation.vector).norm() < 1e-8);
        assert!(fit.rms_mm < 1e-9);
        assert!(
            (fit.isometry().to_homogeneous() - truth.to_homogeneous())
                .abs()
                .max()
                < 1e-8
        );
        let r = kabsch_rotation(&model, &measured);
        assert_eq!(r, fit.rotation);
    }
}

#[test]
fn kabsch_returns_a_proper_rotation_for_mirrored_points() {
    // Mirror images cannot be matched by a rotation; the fit must still be a rotation (det +1).
    let model = nominal_reflectors();
    let measured = model.map(|p| Vector3::new(p.x, p.y, -p.z) + Vector3::new(5.0, 0.0, 0.0));
    let fit = kabsch_fit(&model, &measured).unwrap();
    assert!((fit.rotation.matrix().determinant() - 1.0).abs() < 1e-12);
    // Three points are always coplanar: a proper rotation matches them exactly.
    assert!(fit.rms_mm < 1e-9, "{}", fit.rms_mm);
    let nan = [
        Vector3::new(f64::NAN, 0.0, 0.0),
        Vector3::zeros(),
        Vector3::x(),
    ];
    assert!(kabsch_fit(&model, &nan).is_none());
    assert_eq!(kabsch_rotation(&model, &nan), Rotation3::identity());
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let truth = true_model(&mut rng);
    let ds = simulate(&truth, &Isometry3::identity(), [6, 3], 0.0, 18);
    // Right arm has only one `ver` configuration.
    match evaluate(&ds, &truth, Split::Ver) {
        Err(MetricsError::TooFewConfigurations {
            side: Side::Right,
            found: 1,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let e = evaluate(&ds, &truth, Split::Ver).unwrap_err().to_string();
    assert!(
        e.contains("right") && e.contains("`ver`") && e.contains('2'),
        "{e}"
    );

    let mut bad = ds.clone();
    bad.arms.left.measurements[1].tracker_points_mm[2].y = f64::NAN;
    let e = evaluate(&bad, &truth, Split::All).unwrap_err();
    assert!(
        matches!(e, MetricsError::NonFiniteMeasurement { ref field, .. } if field == "cy"),
        "{e}"
    );
    assert!(e.to_string().contains("left001"));

    let mut bad = ds.clone();
    bad.arms.right.measurements[0].q_rad[4] = f64::INFINITY;
    assert!(matches!(
        evaluate(&bad, &truth, Split::All),
        Err(MetricsError::NonFiniteMeasurement { ref field, .. }) if field == "q5"
    ));

    let mut m = truth.clone();
    m.arms.right.dh_mut().unwrap()[3].alpha_rad = f64::NAN;
    let e = evaluate(&ds, &m, Split::All).unwrap_err();
    assert!(e.to_string().contains("alpha4"), "{e}");
    // A model of another joint count is refused, naming the configuration.
    let mut short = ds.clone();
    short.arms.left.measurements[1].q_rad.pop();
    let e = evaluate(&short, &truth, Split::All).unwrap_err();
    assert!(
        matches!(
            e,
            MetricsError::JointCount {
                found: 6,
                expected: 7,
                ..
            }
        ),
        "{e}"
    );

    let mut m = truth.clone();
    m.left_base_from_right_base.translation.vector.x = f64::NAN;
    assert!(matches!(
        evaluate(&ds, &m, Split::All),
        Err(MetricsError::NonFiniteModel { .. })
    ));

    let mut m = truth.clone();
    m.arms.left.reflectors_mm[2] =
        m.arms.left.reflectors_mm[0] * 2.0 - m.arms.left.reflectors_mm[1];
    assert!(matches!(
        evaluate(&ds, &m, Split::All),
        Err(MetricsError::DegenerateReflectors { side: Side::Left })
    ));

    let mut m = truth.clone();
    m.arms.left.dh_mut().unwrap()[0].d_mm = 1e308;
    m.arms.left.dh_mut().unwrap()[2].d_mm = 1e308;
    assert!(evaluate(&ds, &m, Split::All).is_err());
}

#[test]
fn report_json_has_the_issue_shape() {
    let mut rng = ChaCha8Rng::seed_from_u64(19);
    let truth = true_model(&mut rng);
    let ds = simulate(&truth, &Isometry3::identity(), [4, 4], 0.02, 20);
    let r = evaluate(&ds, &truth, Split::All).unwrap();
    let v = serde_json::to_value(r).unwrap();
    let o = v.as_object().unwrap();
    assert_eq!(o.len(), 3);
    for key in ["relative_left", "relative_right", "collaborative"] {
        let s = o[key].as_object().unwrap();
        for f in [
            "pos_rms_mm",
            "pos_max_mm",
            "ori_rms_rad",
            "ori_max_rad",
            "pos_within_0_3mm_frac",
            "pos_within_0_6mm_frac",
            "ori_within_0_005rad_frac",
            "ori_within_0_01rad_frac",
        ] {
            assert!(s[f].is_f64(), "{key}.{f}");
        }
    }
    let back: AccuracyReport = serde_json::from_value(v).unwrap();
    assert_eq!(back, r);
}

#[test]
fn tables_show_the_figures() {
    let stats = |x: f64| AccuracyStats {
        pos_rms_mm: 3.25 * x,
        pos_rms_per_reflector_mm: crate::kinematics::PerReflector::from_slice(&[
            3.25 * x,
            2.5 * x,
            1.0 * x,
        ]),
        pos_max_mm: 9.5 * x,
        ori_rms_rad: Some(0.0042 * x),
        ori_max_rad: Some(0.0123 * x),
        pos_within_0_3mm_frac: 0.0081 / x,
        pos_within_0_6mm_frac: 0.0311 / x,
        ori_within_0_005rad_frac: Some(0.023 / x),
        ori_within_0_01rad_frac: Some(0.1248 / x),
        n_configs: 100,
        n_pairs: 4950,
    };
    let before = AccuracyReport {
        relative_left: Some(stats(1.0)),
        relative_right: Some(stats(1.0)),
        collaborative: Some(stats(1.0)),
        collaborative_same_instant: None,
    };
    let t = format_table(&before);
    assert!(
        !t.contains("same instant"),
        "no column without same-instant pairs:\n{t}"
    );
    for s in [
        "relative left",
        "collaborative",
        "3.250",
        "9.500",
        "4.200",
        "12.300",
        "0.81 %",
        "12.48 %",
        "4950",
    ] {
        assert!(t.contains(s), "{s} missing in\n{t}");
    }
    // Rows are aligned: every line has the same width in characters.
    let widths: Vec<usize> = t.lines().map(|l| l.chars().count()).collect();
    assert!(widths.windows(2).all(|w| w[0] == w[1]), "{t}");
    let after = AccuracyReport {
        relative_left: Some(stats(0.1)),
        ..before
    };
    let c = format_comparison(&before, &after, ["nominal", "calibrated"]);
    // Both hands measured together: a fourth set of pairs, in the table and the comparison.
    let together = AccuracyReport {
        collaborative_same_instant: Some(stats(2.0)),
        ..before
    };
    let t4 = format_table(&together);
    assert!(t4.lines().next().unwrap().contains("same instant"), "{t4}");
    let widths: Vec<usize> = t4.lines().map(|l| l.chars().count()).collect();
    assert!(widths.windows(2).all(|w| w[0] == w[1]), "{t4}");
    let c4 = format_comparison(&before, &together, ["nominal", "calibrated"]);
    assert!(c4.contains("same instant"), "{c4}");
    for s in [
        "nominal",
        "calibrated",
        "0.325",
        "-90.00 %",
        "+7.29 pp",
        "+0.00 %",
    ] {
        assert!(c.contains(s), "{s} missing in\n{c}");
    }
}

/// One pass over every pair gives what `evaluate` of each split, `per_config` over all configurations and
/// the pair lists give (the verification configurations are interleaved with the calibration ones).
#[test]
fn sweep_agrees_with_evaluate_per_config_and_the_pair_lists() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let truth = true_model(&mut rng);
    let ds = simulate(
        &truth,
        &random_isometry(&mut rng, 2000.0),
        [14, 11],
        0.3,
        22,
    );
    let mut model = truth.clone();
    model.arms.right = perturbed_arm(&mut rng, 0.3);
    let s = sweep(&ds, &model).unwrap();
    for split in [Split::Cal, Split::Ver] {
        let expected = evaluate(&ds, &model, split).unwrap();
        let got = s.split(split).expect("both splits have pairs");
        assert_reports_close(&got.report, &expected, 1e-12);
        for kind in [
            PairKind::Relative(Side::Left),
            PairKind::Relative(Side::Right),
            PairKind::Collaborative,
        ] {
            let pairs = pairs(&ds, &model, split, kind).unwrap();
            let sorted = |mut v: Vec<f32>| {
                v.sort_by(f32::total_cmp);
                v
            };
            let samples = got.samples(kind);
            assert_eq!(
                sorted(samples.pos_mm.clone()),
                sorted(
                    pairs
                        .iter()
                        .flat_map(|p| p.pos_error_mm.iter().map(|&d| d as f32).collect::<Vec<_>>())
                        .collect()
                ),
                "{split:?} {kind:?} Δd"
            );
            let ori: Vec<f32> = pairs
                .iter()
                .map(|p| p.ori_error_rad.unwrap() as f32)
                .collect();
            let (a, b) = (sorted(samples.ori_rad.clone()), sorted(ori));
            assert_eq!(a.len(), b.len());
            for (x, y) in a.iter().zip(&b) {
                // Δo of (i, j) and (j, i) agree to rounding.
                assert!((x - y).abs() <= 1e-6 * y.abs().max(1e-3), "{x} vs {y}");
            }
        }
    }
    assert!(s.split(Split::All).is_none());
    let rows = per_config(&ds, &model, Split::All).unwrap();
    assert_eq!(rows.len(), s.per_config.len());
    for (a, b) in rows.iter().zip(&s.per_config) {
        assert_eq!((a.config, &a.id), (b.config, &b.id));
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(1e-9);
        for (x, y) in [
            (a.relative_pos_max_mm, b.relative_pos_max_mm),
            (
                a.relative_ori_rms_rad.unwrap(),
                b.relative_ori_rms_rad.unwrap(),
            ),
            (
                a.relative_ori_max_rad.unwrap(),
                b.relative_ori_max_rad.unwrap(),
            ),
            (
                a.collaborative_pos_max_mm.unwrap(),
                b.collaborative_pos_max_mm.unwrap(),
            ),
            (
                a.collaborative_ori_rms_rad.unwrap(),
                b.collaborative_ori_rms_rad.unwrap(),
            ),
            (
                a.collaborative_ori_max_rad.unwrap(),
                b.collaborative_ori_max_rad.unwrap(),
            ),
            (a.rigidity_mm, b.rigidity_mm),
            (a.fit_rms_mm.unwrap(), b.fit_rms_mm.unwrap()),
        ] {
            assert!(close(x, y), "{}: {x} vs {y}", a.id);
        }
    }
}

/// A split with fewer than two configurations on an arm has no figures; the other split still has.
#[test]
fn sweep_without_verification_configurations() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let truth = true_model(&mut rng);
    let mut ds = simulate(&truth, &Isometry3::identity(), [6, 7], 0.0, 6);
    for (_, arm) in ds.arms.iter_mut() {
        for m in &mut arm.measurements {
            m.split = Split::Cal;
        }
    }
    let s = sweep(&ds, &truth).unwrap();
    assert!(s.ver.is_none());
    let cal = s.cal.as_ref().unwrap();
    assert_eq!(cal.report.collaborative.unwrap().n_pairs, 42);
    assert_eq!(cal.samples(PairKind::Collaborative).ori_rad.len(), 42);
    assert_eq!(
        cal.samples(PairKind::Relative(Side::Right)).pos_mm.len(),
        3 * 21
    );
}
