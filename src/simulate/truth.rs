//! Step 1 of the protocol: the true robot, the nominal one plus random geometric errors.

use super::{STREAM_GEOMETRY, STREAM_TARGET, SimOptions, gauss, gauss3, rng_for};
use crate::kinematics::{ArmModel, DualArmModel};
use crate::side::PerSide;
use nalgebra::DVector;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::Rng;

/// Reflector distances `|p_i,k − p_j,k|` of all pairs i < j of `configs`, flattened, mm.
pub(super) fn pair_distances_mm(arm: &ArmModel, configs: &[Vec<f64>]) -> Vec<[f64; 3]> {
    let points: Vec<_> = configs
        .iter()
        .map(|q| arm.reflector_fk(q).points_mm)
        .collect();
    let mut out = Vec::with_capacity(points.len() * points.len().saturating_sub(1) / 2);
    for (i, pi) in points.iter().enumerate() {
        for pj in &points[i + 1..] {
            out.push(std::array::from_fn(|k| (pi[k] - pj[k]).norm()));
        }
    }
    out
}

/// RMS relative positioning error (paper eq. 5, noise-free) of the nominal model against `truth` over all
/// pairs of `configs`, given the nominal pair distances: per reflector the RMS of
/// `|p_t,i − p_t,j| − |p_n,i − p_n,j|`, the largest of the three, mm.
pub(super) fn relative_rms_mm(
    truth: &ArmModel,
    nominal_distances: &[[f64; 3]],
    configs: &[Vec<f64>],
) -> f64 {
    if nominal_distances.is_empty() {
        return 0.0;
    }
    let mut sum_sq = [0.0; 3];
    for (t, n) in pair_distances_mm(truth, configs)
        .iter()
        .zip(nominal_distances)
    {
        for k in 0..3 {
            sum_sq[k] += (t[k] - n[k]).powi(2);
        }
    }
    sum_sq
        .iter()
        .map(|s| (s / nominal_distances.len() as f64).sqrt())
        .fold(0.0, f64::max)
}

/// One arm's true model: nominal plus the drawn error `delta`, scaled (when a target is given and the
/// error is not zero) so that the nominal relative RMS on `configs` equals `target_mm`.
fn true_arm(
    nominal: &ArmModel,
    delta: &DVector<f64>,
    target_mm: Option<f64>,
    configs: &[Vec<f64>],
) -> ArmModel {
    let v0 = nominal.to_vector();
    let at = |scale: f64| nominal.with_vector(&(&v0 + scale * delta));
    let Some(target_mm) = target_mm else {
        return at(1.0);
    };
    let nominal_distances = pair_distances_mm(nominal, configs);
    // The error is nearly linear in the scale: a few fixed-point steps converge to ~1e-4.
    let mut scale = 1.0;
    for _ in 0..8 {
        let rms = relative_rms_mm(&at(scale), &nominal_distances, configs);
        if !(rms > 1e-12 && rms.is_finite()) {
            break;
        }
        let ratio = target_mm / rms;
        scale *= ratio;
        if (ratio - 1.0).abs() < 1e-4 {
            break;
        }
    }
    at(scale)
}

/// Nominal model plus the random geometric errors of [`SimOptions`] (module documentation, step 1).
pub(super) fn perturb_model(
    opts: &SimOptions,
    nominal: &DualArmModel,
    configs: &PerSide<Vec<Vec<f64>>>,
) -> DualArmModel {
    let mut rng = rng_for(opts.seed, STREAM_GEOMETRY);
    let mut draw = |arm: &ArmModel| {
        let mut d = DVector::zeros(arm.param_count());
        for k in 0..arm.reflector_offset() {
            let sigma = if arm.param_is_angle(k) {
                opts.dh_error.angle_rad
            } else {
                opts.dh_error.length_mm
            };
            d[k] = sigma * gauss(&mut rng);
        }
        for k in arm.reflector_offset()..d.len() {
            d[k] = opts.reflector_error_mm * gauss(&mut rng);
        }
        // A chain's first joint-origin correction moves the whole arm rigidly: the same as the
        // right arm's base error, or the tracker frame for the left arm. The base error models the
        // mounting; the drawn values stay unused (so that the other draws do not change).
        if arm.chain().is_some() {
            for v in d.iter_mut().take(crate::kinematics::PARAMS_PER_JOINT) {
                *v = 0.0;
            }
        }
        d
    };
    let delta = PerSide::from_fn(|side| draw(nominal.arm(side)));
    let dt = opts.base_error_mm * gauss3(&mut rng);
    let dr = opts.base_error_rad * gauss3(&mut rng);
    let error = Isometry3::from_parts(Translation3::from(dt), UnitQuaternion::from_scaled_axis(dr));
    let mut target_rng = rng_for(opts.seed, STREAM_TARGET);
    let targets = opts.nominal_rms_target_mm.map(|(lo, hi)| {
        let mut pick = || {
            if lo < hi {
                target_rng.random_range(lo..hi)
            } else {
                lo
            }
        };
        PerSide::from_fn(|_| pick())
    });
    let mut arms = PerSide::from_fn(|side| {
        true_arm(
            nominal.arm(side),
            &delta[side],
            targets.map(|t| t[side]),
            &configs[side],
        )
    });
    // Joints on both chains (a torso) are one joint: the right arm's copy takes the left's errors, and
    // the arms hang from one body, so there is no mounting error between their base links (each arm's
    // own mounting is the correction of its first joint past the torso).
    let shared = nominal.shared_joints();
    let base_error = if shared.is_empty() {
        error
    } else {
        arms.right = shared.copy_to_right(&arms.left, &arms.right);
        Isometry3::identity()
    };
    DualArmModel {
        arms,
        left_base_from_right_base: nominal.left_base_from_right_base * base_error,
    }
}
