//! Tests of the simulator.

use super::joint_errors::joint_error_rad;
use super::truth::{pair_distances_mm, relative_rms_mm};
use super::*;
use crate::kinematics::{ArmModel, N_DH, N_JOINTS, joint_limits_rad};
use nalgebra::{Matrix3, Rotation3, Translation3, UnitQuaternion};

/// The nominal IRB 14000 with the public body layout's right-arm base.
fn nominal() -> DualArmModel {
    #[rustfmt::skip]
    let r = Matrix3::new(
        0.2352, -0.8755, 0.4220,
        0.8746, 0.0012, -0.4849,
        0.4241, 0.4831, 0.7660,
    );
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
    let arm = ArmModel::nominal_irb14000(SimOptions::default_reflectors());
    DualArmModel {
        arms: PerSide::new(arm.clone(), arm),
        left_base_from_right_base: Isometry3::from_parts(
            Translation3::new(61.61, -70.77, -34.14),
            rotation,
        ),
    }
}

fn never(_: Side, _: &[f64]) -> bool {
    false
}

fn small(seed: u64) -> SimOptions {
    SimOptions {
        seed,
        n_configs: 60,
        n_cal: 30,
        ..SimOptions::default()
    }
}

fn run(opts: &SimOptions) -> SimOutput {
    simulate(opts, &nominal(), &never).expect("simulation succeeds")
}

/// Relative positioning RMS (paper eq. 5): for all pairs and each reflector, measured minus model
/// distance; RMS per reflector, the largest of the three. Also returns the largest |Δd|.
fn relative_pos_rms_mm(out: &SimOutput, model: &DualArmModel, side: Side) -> (f64, f64) {
    let arm = model.arm(side);
    let ms = &out.dataset.arm(side).measurements;
    let model_points: Vec<_> = ms
        .iter()
        .map(|m| arm.reflector_fk(&m.q_rad).points_mm)
        .collect();
    let mut sum_sq = [0.0; 3];
    let mut max_abs: f64 = 0.0;
    let mut n = 0usize;
    for i in 0..ms.len() {
        for j in i + 1..ms.len() {
            for k in 0..3 {
                let dm = (ms[i].tracker_points_mm[k] - ms[j].tracker_points_mm[k]).norm();
                let dmod = (model_points[i][k] - model_points[j][k]).norm();
                sum_sq[k] += (dm - dmod).powi(2);
                max_abs = max_abs.max((dm - dmod).abs());
            }
            n += 1;
        }
    }
    let rms = sum_sq
        .iter()
        .map(|s| (s / n as f64).sqrt())
        .fold(0.0, f64::max);
    (rms, max_abs)
}

/// Collaborative positioning RMS (largest reflector RMS) of `model` over all left × right pairs.
fn collaborative_pos_rms_mm(out: &SimOutput, model: &DualArmModel) -> f64 {
    let l = &out.dataset.arms.left.measurements;
    let r = &out.dataset.arms.right.measurements;
    let pl: Vec<_> = l
        .iter()
        .map(|m| model.arms.left.reflector_fk(&m.q_rad).points_mm)
        .collect();
    let pr: Vec<_> = r
        .iter()
        .map(|m| {
            model
                .arms
                .right
                .reflector_fk(&m.q_rad)
                .points_mm
                .iter()
                .map(|p| {
                    model
                        .left_base_from_right_base
                        .transform_point(&(*p).into())
                        .coords
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let mut sum_sq = [0.0; 3];
    for (ml, pl) in l.iter().zip(&pl) {
        for (mr, pr) in r.iter().zip(&pr) {
            for k in 0..3 {
                let dm = (ml.tracker_points_mm[k] - mr.tracker_points_mm[k]).norm();
                let dmod = (pl[k] - pr[k]).norm();
                sum_sq[k] += (dm - dmod).powi(2);
            }
        }
    }
    let n = (l.len() * r.len()) as f64;
    sum_sq.iter().map(|s| (s / n).sqrt()).fold(0.0, f64::max)
}

/// Noise-free relative orientation RMS of `model` against `truth` (flange rotations, all pairs), rad.
fn relative_ori_rms_rad(out: &SimOutput, model: &DualArmModel, side: Side) -> f64 {
    let ms = &out.dataset.arm(side).measurements;
    let rt: Vec<_> = ms
        .iter()
        .map(|m| out.truth.arm(side).base_from_flange(&m.q_rad).rotation)
        .collect();
    let rm: Vec<_> = ms
        .iter()
        .map(|m| model.arm(side).base_from_flange(&m.q_rad).rotation)
        .collect();
    let mut sum_sq = 0.0;
    let mut n = 0;
    for i in 0..ms.len() {
        for j in i + 1..ms.len() {
            let a = (rt[i].inverse() * rt[j]).inverse() * (rm[i].inverse() * rm[j]);
            sum_sq += a.angle().powi(2);
            n += 1;
        }
    }
    (sum_sq / n as f64).sqrt()
}

/// Noise-free collaborative orientation RMS of `model` against the truth (all left × right pairs), rad.
fn collaborative_ori_rms_rad(out: &SimOutput, model: &DualArmModel) -> f64 {
    let rots = |m: &DualArmModel, side: Side| -> Vec<UnitQuaternion<f64>> {
        out.dataset
            .arm(side)
            .measurements
            .iter()
            .map(|ms| (m.left_base_from(side) * m.arm(side).base_from_flange(&ms.q_rad)).rotation)
            .collect()
    };
    let (tl, ol) = (rots(&out.truth, Side::Left), rots(model, Side::Left));
    let (tr, or) = (rots(&out.truth, Side::Right), rots(model, Side::Right));
    let mut sum_sq = 0.0;
    for (tl, ol) in tl.iter().zip(&ol) {
        for (tr, or) in tr.iter().zip(&or) {
            sum_sq += ((tl.inverse() * tr).inverse() * (ol.inverse() * or))
                .angle()
                .powi(2);
        }
    }
    (sum_sq / (tl.len() * tr.len()) as f64).sqrt()
}

/// Residuals of the measurements against `model` placed by `tracker_from_left_base`, divided by the
/// documented σ (MPE/2 per axis): should be standard normal when the model is the truth.
fn normalised_residuals(out: &SimOutput, model: &DualArmModel) -> Vec<f64> {
    let mut z = Vec::new();
    for side in Side::BOTH {
        let tracker_from_base = out.tracker_from_left_base * model.left_base_from(side);
        for m in &out.dataset.arm(side).measurements {
            let fk = model.arm(side).reflector_fk(&m.q_rad);
            for k in 0..3 {
                let p = tracker_from_base
                    .transform_point(&fk.points_mm[k].into())
                    .coords;
                let mpe_um = out.dataset.tracker.mpe_um
                    + out.dataset.tracker.mpe_um_per_m * p.norm() / 1000.0;
                let sigma_mm = mpe_um / 2000.0;
                let r = m.tracker_points_mm[k] - p;
                z.extend(r.iter().map(|x| x / sigma_mm));
            }
        }
    }
    z
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn same_seed_is_deterministic() {
    let opts = SimOptions {
        joint_error: Some(JointErrorModel::default()),
        outliers: Some(OutlierModel {
            fraction: 0.05,
            magnitude_mm: 3.0,
        }),
        ..small(5)
    };
    assert_eq!(run(&opts), run(&opts));
}

#[test]
fn different_seeds_differ() {
    let a = run(&small(1));
    let b = run(&small(2));
    assert_ne!(a.truth, b.truth);
    assert_ne!(a.tracker_from_left_base, b.tracker_from_left_base);
    assert_ne!(
        a.dataset.arms.left.measurements[0].q_rad,
        b.dataset.arms.left.measurements[0].q_rad
    );
    assert_ne!(
        a.dataset.arms.right.measurements[0].q_rad,
        b.dataset.arms.right.measurements[0].q_rad
    );
}

#[test]
fn layout_ids_and_split() {
    let out = run(&small(3));
    assert_eq!(out.nominal, nominal());
    assert_eq!(
        out.dataset.nominal_reflectors_mm,
        SimOptions::default_reflectors()
    );
    assert_eq!(out.dataset.dir, PathBuf::new());
    assert!(out.dataset.robot.is_none());
    for (side, prefix) in [(Side::Left, "L"), (Side::Right, "R")] {
        let arm = out.dataset.arm(side);
        assert_eq!(arm.side, side);
        assert_eq!(arm.measurements.len(), 60);
        for (i, m) in arm.measurements.iter().enumerate() {
            assert_eq!(m.id, format!("{prefix}{:03}", i + 1));
            assert_eq!(m.split, if i < 30 { Split::Cal } else { Split::Ver });
            assert_eq!(m.line, i + 2);
        }
    }
}

#[test]
fn truth_differs_from_nominal_by_the_requested_amounts() {
    let opts = SimOptions {
        nominal_rms_target_mm: None,
        ..SimOptions::default()
    };
    let out = run(&opts);
    assert_ne!(out.truth.arms.left, out.nominal.arms.left);
    assert_ne!(out.truth.arms.right, out.nominal.arms.right);
    assert_ne!(out.truth.arms.left, out.truth.arms.right);
    for side in Side::BOTH {
        let d = out.truth.arm(side).to_vector() - out.nominal.arm(side).to_vector();
        let lengths: Vec<f64> = (0..N_DH).filter(|k| k % 4 < 2).map(|k| d[k]).collect();
        let angles: Vec<f64> = (0..N_DH).filter(|k| k % 4 >= 2).map(|k| d[k]).collect();
        let refl: Vec<f64> = (N_DH..d.len()).map(|k| d[k]).collect();
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        // 14 (or 9) samples of N(0, σ): the sample RMS lies within a factor 2 of σ.
        for (v, sigma) in [
            (&lengths, opts.dh_error.length_mm),
            (&angles, opts.dh_error.angle_rad),
            (&refl, opts.reflector_error_mm),
        ] {
            let r = rms(v);
            assert!(
                r > 0.5 * sigma && r < 2.0 * sigma,
                "{side}: rms {r} vs σ {sigma}"
            );
        }
    }
    let base_err =
        out.nominal.left_base_from_right_base.inverse() * out.truth.left_base_from_right_base;
    let t = base_err.translation.vector.norm();
    let a = base_err.rotation.angle();
    // |N(0, σ I3)| is around 1.6 σ; accept a wide band that still rules out "no error" and "wrong unit".
    assert!(
        t > 0.1 * opts.base_error_mm && t < 5.0 * opts.base_error_mm,
        "{t}"
    );
    assert!(
        a > 0.1 * opts.base_error_rad && a < 5.0 * opts.base_error_rad,
        "{a}"
    );
}

#[test]
fn nominal_relative_error_is_paper_like() {
    // Paper Table 5: nominal RMS relative positioning error 2.45 mm (left) and 5.56 mm (right),
    // relative orientation RMS 0.019 / 0.023 rad; Table 6: collaborative 3.4 mm.
    for seed in [1, 2, 3] {
        let out = run(&SimOptions {
            seed,
            ..SimOptions::default()
        });
        for side in Side::BOTH {
            let (rms, max) = relative_pos_rms_mm(&out, &out.nominal, side);
            let ori = relative_ori_rms_rad(&out, &out.nominal, side);
            eprintln!(
                "seed {seed} {side}: nominal pos rms {rms:.3} mm, max {max:.3} mm, ori rms {ori:.4} rad"
            );
            assert!((2.0..=6.0).contains(&rms), "seed {seed} {side}: rms {rms}");
            assert!(
                max > rms && max < 8.0 * rms,
                "seed {seed} {side}: max {max}"
            );
            assert!(
                (0.005..=0.06).contains(&ori),
                "seed {seed} {side}: ori {ori}"
            );
            // The truth explains the data to noise level.
            let (rms_true, _) = relative_pos_rms_mm(&out, &out.truth, side);
            assert!(rms_true < 0.05, "seed {seed} {side}: truth rms {rms_true}");
        }
        let collab = collaborative_pos_rms_mm(&out, &out.nominal);
        let collab_ori = collaborative_ori_rms_rad(&out, &out.nominal);
        let collab_true = collaborative_pos_rms_mm(&out, &out.truth);
        eprintln!(
            "seed {seed}: collaborative nominal pos rms {collab:.3} mm, ori rms {collab_ori:.4} rad; \
             truth pos rms {collab_true:.4} mm"
        );
        assert!(
            (1.0..=15.0).contains(&collab),
            "seed {seed}: collaborative {collab}"
        );
        assert!(
            (0.005..=0.1).contains(&collab_ori),
            "seed {seed}: collaborative ori {collab_ori}"
        );
        assert!(
            collab_true < 0.05,
            "seed {seed}: collaborative truth rms {collab_true}"
        );
    }
}

#[test]
fn target_scaling_keeps_the_error_direction() {
    let raw = run(&SimOptions {
        nominal_rms_target_mm: None,
        ..small(9)
    });
    let (lo, hi) = (3.0, 3.5);
    let scaled = run(&SimOptions {
        nominal_rms_target_mm: Some((lo, hi)),
        ..small(9)
    });
    assert_eq!(
        raw.dataset.arms.left.measurements.len(),
        scaled.dataset.arms.left.measurements.len()
    );
    assert_eq!(
        raw.truth.left_base_from_right_base,
        scaled.truth.left_base_from_right_base
    );
    for side in Side::BOTH {
        let nominal = raw.nominal.arm(side).to_vector();
        let d_raw = raw.truth.arm(side).to_vector() - &nominal;
        let d_scaled = scaled.truth.arm(side).to_vector() - &nominal;
        let s = d_scaled.dot(&d_raw) / d_raw.norm_squared();
        assert!(
            (d_scaled - s * &d_raw).norm() < 1e-9 * d_raw.norm() * s.max(1.0),
            "{side}"
        );
        // Noise-free target hit; the data adds only ~10 µm of tracker noise.
        let configs: Vec<_> = scaled
            .dataset
            .arm(side)
            .measurements
            .iter()
            .map(|m| m.q_rad.clone())
            .collect();
        let nominal_distances = pair_distances_mm(scaled.nominal.arm(side), &configs);
        let exact = relative_rms_mm(scaled.truth.arm(side), &nominal_distances, &configs);
        assert!((lo - 1e-3..=hi + 1e-3).contains(&exact), "{side}: {exact}");
        let (measured, _) = relative_pos_rms_mm(&scaled, &scaled.nominal, side);
        assert!(
            (measured - exact).abs() < 0.05,
            "{side}: {measured} vs {exact}"
        );
        let (raw_rms, _) = relative_pos_rms_mm(&raw, &raw.nominal, side);
        assert!(
            (raw_rms - exact).abs() > 0.01,
            "{side}: scaling did nothing"
        );
    }
}

#[test]
fn residuals_against_truth_are_tracker_noise() {
    let out = run(&SimOptions::default());
    let z = normalised_residuals(&out, &out.truth);
    let (mean, std) = mean_std(&z);
    assert_eq!(z.len(), 2 * 220 * 9);
    assert!(mean.abs() < 0.1, "mean {mean}");
    assert!((std - 1.0).abs() < 0.06, "std {std}");
    // … while the nominal model is far off.
    let (_, std_nominal) = mean_std(&normalised_residuals(&out, &out.nominal));
    assert!(std_nominal > 10.0, "nominal {std_nominal}");
}

#[test]
fn distance_noise_matches_sigma_without_geometric_errors() {
    let opts = SimOptions {
        dh_error: DhErrorSize {
            length_mm: 0.0,
            angle_rad: 0.0,
        },
        reflector_error_mm: 0.0,
        base_error_mm: 0.0,
        base_error_rad: 0.0,
        tracker: TrackerSpec {
            mpe_um: 100.0,
            mpe_um_per_m: 10.0,
        },
        n_configs: 120,
        ..SimOptions::default()
    };
    let out = run(&opts);
    assert_eq!(out.truth, out.nominal);
    // Δd of a pair is the difference of two independent σ-noises projected on the pair's direction:
    // std = √2 σ, σ = MPE/2 at the tracker distance.
    for side in Side::BOTH {
        let ms = &out.dataset.arm(side).measurements;
        let model: Vec<_> = ms
            .iter()
            .map(|m| out.truth.arm(side).reflector_fk(&m.q_rad).points_mm)
            .collect();
        let mut dd = Vec::new();
        let mut sigma_sum = 0.0;
        for m in ms {
            let dist_m = m.tracker_points_mm[0].norm() / 1000.0;
            sigma_sum += (opts.tracker.mpe_um + opts.tracker.mpe_um_per_m * dist_m) / 2000.0;
        }
        let sigma = sigma_sum / ms.len() as f64;
        for i in 0..ms.len() {
            for j in i + 1..ms.len() {
                let (pi, pj) = (&ms[i].tracker_points_mm, &ms[j].tracker_points_mm);
                dd.extend(
                    (0..3).map(|k| (pi[k] - pj[k]).norm() - (model[i][k] - model[j][k]).norm()),
                );
            }
        }
        let (mean, std) = mean_std(&dd);
        let expected = 2f64.sqrt() * sigma;
        assert!(mean.abs() < 0.1 * expected, "{side}: mean {mean}");
        assert!(
            (std / expected - 1.0).abs() < 0.15,
            "{side}: std {std} vs {expected}"
        );
    }
}

#[test]
fn tracker_is_placed_as_documented_and_reflectors_face_it() {
    for seed in 1..=5 {
        let body_from_left_base = Isometry3::from_parts(
            Translation3::new(50.0, 100.0, 400.0),
            UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0),
        );
        let opts = SimOptions {
            body_from_left_base,
            ..small(seed)
        };
        let out = run(&opts);
        let tracker_in_body = body_from_left_base
            * out
                .tracker_from_left_base
                .inverse_transform_point(&Point3::origin());
        let d_m = tracker_in_body.coords.norm() / 1000.0;
        assert!((1.5..=3.0).contains(&d_m), "distance {d_m}");
        let az = tracker_in_body.y.atan2(tracker_in_body.x).to_degrees();
        let el = (tracker_in_body.z / tracker_in_body.coords.norm())
            .asin()
            .to_degrees();
        assert!(az.abs() <= 45.0 + 1e-9, "azimuth {az}");
        assert!((-10.0 - 1e-9..=30.0 + 1e-9).contains(&el), "elevation {el}");
        let nom = &out.nominal;
        let cos_max = 70f64.to_radians().cos();
        for side in Side::BOTH {
            let tracker_in_base = (out.tracker_from_left_base * nom.left_base_from(side))
                .inverse_transform_point(&Point3::origin());
            for m in &out.dataset.arm(side).measurements {
                let f = nom.arm(side).base_from_flange(&m.q_rad);
                let dir = (tracker_in_base.coords - f.translation.vector).normalize();
                let cos = (f.rotation * Vector3::z()).dot(&dir);
                assert!(cos >= cos_max - 1e-12, "{side} {}: cos {cos}", m.id);
            }
        }
        assert!(out.rejected_for_facing > 0);
        assert_eq!(out.rejected_for_collision, 0);
        assert_eq!(
            out.attempts.left + out.attempts.right,
            120 + out.rejected_for_facing
        );
    }
}

#[test]
fn configurations_respect_shrunk_joint_limits() {
    let out = run(&SimOptions::default());
    let lim = joint_limits_rad();
    for side in Side::BOTH {
        for m in &out.dataset.arm(side).measurements {
            for (j, q) in m.q_rad.iter().enumerate() {
                let margin = 0.05 * (lim[j].1 - lim[j].0);
                assert!(
                    *q >= lim[j].0 + margin && *q <= lim[j].1 - margin,
                    "{side} {} q{j}",
                    m.id
                );
            }
        }
    }
}

#[test]
fn collision_closure_is_honoured() {
    let opts = small(4);
    let free = run(&opts);
    // Reject the half of the space with q1 > 0 on the left arm only.
    let calls = std::cell::Cell::new(0usize);
    let half = |side: Side, q: &[f64]| {
        calls.set(calls.get() + 1);
        side == Side::Left && q[0] > 0.0
    };
    let out = simulate(&opts, &nominal(), &half).unwrap();
    assert!(
        out.dataset
            .arms
            .left
            .measurements
            .iter()
            .all(|m| m.q_rad[0] <= 0.0)
    );
    assert!(
        free.dataset
            .arms
            .left
            .measurements
            .iter()
            .any(|m| m.q_rad[0] > 0.0)
    );
    assert_eq!(calls.get(), 120 + out.rejected_for_collision);
    let frac = out.rejected_for_collision as f64 / (60 + out.rejected_for_collision) as f64;
    assert!(frac > 0.3 && frac < 0.7, "rejected fraction {frac}");
    assert!(out.attempts.left > free.attempts.left);
    // The right arm saw no rejections and is unchanged.
    assert_eq!(out.dataset.arms.right, free.dataset.arms.right);

    // Rejecting everything ends with an error after the attempt cap, not a hang.
    let opts = SimOptions {
        max_attempts_per_config: 20,
        ..opts
    };
    let all = |_: Side, _: &[f64]| true;
    let err = simulate(&opts, &nominal(), &all).unwrap_err();
    match err {
        SimError::NotEnoughConfigurations {
            side,
            accepted,
            wanted,
            attempts,
            rejected_for_facing,
            rejected_for_collision,
        } => {
            assert_eq!(side, Side::Left);
            assert_eq!(accepted, 0);
            assert_eq!(wanted, 60);
            assert_eq!(attempts, 60 * opts.max_attempts_per_config);
            assert_eq!(rejected_for_facing + rejected_for_collision, attempts);
        }
        e => panic!("unexpected {e}"),
    }
}

#[test]
fn outliers_displace_exactly_the_recorded_points() {
    let clean = run(&small(6));
    let magnitude_mm = 2.5;
    let out = run(&SimOptions {
        outliers: Some(OutlierModel {
            fraction: 0.1,
            magnitude_mm,
        }),
        ..small(6)
    });
    assert_eq!(out.outliers.len(), 2 * 6);
    assert_eq!(out.truth, clean.truth);
    for side in Side::BOTH {
        let a = &clean.dataset.arm(side).measurements;
        let b = &out.dataset.arm(side).measurements;
        for (i, (ma, mb)) in a.iter().zip(b).enumerate() {
            assert_eq!(ma.q_rad, mb.q_rad);
            let rec = out.outliers.iter().find(|o| o.side == side && o.index == i);
            for k in 0..3 {
                let d = mb.tracker_points_mm[k] - ma.tracker_points_mm[k];
                match rec {
                    Some(o) if o.reflector == k => {
                        assert_eq!(o.id, mb.id);
                        assert!((d - o.displacement_mm).norm() < 1e-9);
                        assert!((d.norm() - magnitude_mm).abs() < 1e-9);
                    }
                    _ => assert_eq!(d, Vector3::zeros(), "{side} {} reflector {k}", mb.id),
                }
            }
        }
    }
}

#[test]
fn periodic_joint_error_follows_the_documented_formula() {
    let model = JointErrorModel {
        periodic_amplitude_mrad: 2.0,
        periods_per_rev: 3.0,
        compliance_mrad_per_m: 0.0,
    };
    let clean = run(&small(7));
    let out = run(&SimOptions {
        joint_error: Some(model),
        ..small(7)
    });
    assert_eq!(out.truth, clean.truth);
    assert_eq!(out.tracker_from_left_base, clean.tracker_from_left_base);
    let mut largest_shift: f64 = 0.0;
    for side in Side::BOTH {
        let phases = &out.joint_error_phases_rad[side];
        assert!(
            phases
                .iter()
                .all(|p| (0.0..std::f64::consts::TAU).contains(p))
        );
        assert!(phases.iter().any(|p| *p != 0.0));
        let tracker_from_base = out.tracker_from_left_base * out.truth.left_base_from(side);
        let pairs = clean
            .dataset
            .arm(side)
            .measurements
            .iter()
            .zip(&out.dataset.arm(side).measurements);
        for (mc, m) in pairs {
            assert_eq!(
                mc.q_rad, m.q_rad,
                "joint errors must not change the commanded q"
            );
            let q_true: [f64; N_JOINTS] =
                std::array::from_fn(|i| m.q_rad[i] + 2e-3 * (3.0 * m.q_rad[i] + phases[i]).sin());
            let fk = out.truth.arm(side).reflector_fk(&q_true);
            for k in 0..3 {
                let p = tracker_from_base
                    .transform_point(&fk.points_mm[k].into())
                    .coords;
                // Same noise draws in both runs: the residual is noise-scale only.
                assert!((m.tracker_points_mm[k] - p).norm() < 0.1, "{side} {}", m.id);
                largest_shift =
                    largest_shift.max((m.tracker_points_mm[k] - mc.tracker_points_mm[k]).norm());
            }
        }
    }
    // 2 mrad on several joints with levers of a few hundred mm: millimetre-level shifts.
    assert!(largest_shift > 0.5, "largest shift {largest_shift}");
}

#[test]
fn compliance_shift_scales_with_the_compliance() {
    let shift = |c: f64| {
        let clean = run(&small(8));
        let out = run(&SimOptions {
            joint_error: Some(JointErrorModel {
                periodic_amplitude_mrad: 0.0,
                periods_per_rev: 1.0,
                compliance_mrad_per_m: c,
            }),
            ..small(8)
        });
        let a = &clean.dataset.arms.left.measurements;
        let b = &out.dataset.arms.left.measurements;
        a.iter()
            .zip(b)
            .map(|(ma, mb)| (ma.tracker_points_mm[0] - mb.tracker_points_mm[0]).norm())
            .sum::<f64>()
    };
    let s1 = shift(1.0);
    let s2 = shift(2.0);
    assert!(s1 > 1.0, "total shift {s1}");
    assert!((s2 / s1 - 2.0).abs() < 0.05, "{s1} {s2}");
}

#[test]
fn compliance_follows_the_gravity_torque() {
    // With gravity along joint 1's axis, joint 1 carries no torque whatever the pose.
    let arm = ArmModel::nominal_irb14000(SimOptions::default_reflectors());
    let model = JointErrorModel {
        periodic_amplitude_mrad: 0.0,
        periods_per_rev: 1.0,
        compliance_mrad_per_m: 1.0,
    };
    let q = [0.4, -0.7, 0.3, -0.5, 1.1, 0.6, -0.9];
    let dq = joint_error_rad(&model, &[0.0; N_JOINTS], &arm, &q, &Vector3::z());
    assert!(dq[0].abs() < 1e-15, "{dq:?}");
    // Flipping gravity flips every deflection; some joint is loaded.
    let up = joint_error_rad(&model, &[0.0; N_JOINTS], &arm, &q, &Vector3::x());
    let down = joint_error_rad(&model, &[0.0; N_JOINTS], &arm, &q, &-Vector3::x());
    assert!(up.iter().zip(&down).all(|(a, b)| (a + b).abs() < 1e-15));
    assert!(up.iter().any(|a| a.abs() > 1e-4), "{up:?}");
}

#[test]
fn invalid_options_are_refused() {
    let cases = [
        SimOptions {
            n_configs: 3,
            n_cal: 2,
            ..SimOptions::default()
        },
        SimOptions {
            n_cal: 300,
            ..SimOptions::default()
        },
        SimOptions {
            tracker_distance_m: (3.0, 1.5),
            ..SimOptions::default()
        },
        SimOptions {
            reflector_error_mm: f64::NAN,
            ..SimOptions::default()
        },
        SimOptions {
            facing_max_angle_deg: 0.0,
            ..SimOptions::default()
        },
        SimOptions {
            outliers: Some(OutlierModel {
                fraction: 1.5,
                magnitude_mm: 1.0,
            }),
            ..SimOptions::default()
        },
    ];
    for opts in &cases {
        assert!(
            matches!(
                simulate(opts, &nominal(), &never),
                Err(SimError::InvalidOption { .. })
            ),
            "{opts:?}"
        );
    }
}
