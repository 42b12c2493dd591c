//! Steps 2 and 3 of the protocol: the tracker's place and the configurations that face it.

use super::{STREAM_TRACKER, SimError, SimOptions, gauss, rng_for, stream_configs};
use crate::kinematics::ArmModel;
use crate::side::Side;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;

/// The tracker pose relative to the left-arm base (see the module documentation).
/// Joint values drawn uniformly within `(lower, upper)` limits, rad (a joint fixed by equal limits
/// keeps its value).
pub(super) fn uniform_within(rng: &mut impl Rng, limits: &[(f64, f64)]) -> Vec<f64> {
    limits
        .iter()
        .map(|&(lo, hi)| {
            if lo < hi {
                rng.random_range(lo..hi)
            } else {
                lo
            }
        })
        .collect()
}

pub(super) fn place_tracker(opts: &SimOptions) -> Isometry3<f64> {
    let mut rng = rng_for(opts.seed, STREAM_TRACKER);
    let (lo, hi) = opts.tracker_distance_m;
    let dist_mm = 1000.0
        * if lo < hi {
            rng.random_range(lo..hi)
        } else {
            lo
        };
    let az = opts.tracker_azimuth_max_deg.to_radians();
    let az = if az > 0.0 {
        rng.random_range(-az..az)
    } else {
        0.0
    };
    let (elo, ehi) = opts.tracker_elevation_deg;
    let el = if elo < ehi {
        rng.random_range(elo..ehi)
    } else {
        elo
    }
    .to_radians();
    let dir = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
    let position_in_body = dir * dist_mm;
    // Uniform random rotation: a normalised 4-D Gaussian is uniform on the unit quaternions.
    let q = nalgebra::Quaternion::new(
        gauss(&mut rng),
        gauss(&mut rng),
        gauss(&mut rng),
        gauss(&mut rng),
    );
    let tracker_rotation = UnitQuaternion::from_quaternion(q);
    let tracker_from_body = Isometry3::from_parts(Translation3::identity(), tracker_rotation)
        * Translation3::from(-position_in_body);
    tracker_from_body * opts.body_from_left_base
}

/// The direction the reflectors of `arm` face, in its tip frame: the normal of their triangle,
/// pointing away from the tip origin (+z for a degenerate triangle).
pub(super) fn facing_axis(arm: &ArmModel) -> Vector3<f64> {
    let t = &arm.reflectors_mm;
    let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let norm = n.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return Vector3::z();
    }
    let n = n / norm;
    if n.dot(&(t[0] + t[1] + t[2])) < 0.0 {
        -n
    } else {
        n
    }
}

/// Do the reflectors of `arm` at `q` face a tracker at `tracker_in_base_mm`?
fn faces(
    arm: &ArmModel,
    axis: &Vector3<f64>,
    q: &[f64],
    tracker_in_base_mm: &Point3<f64>,
    cos_max: f64,
) -> bool {
    let flange = arm.base_from_flange(q);
    let z = flange.rotation * axis;
    let to_tracker = tracker_in_base_mm - Point3::from(flange.translation.vector);
    let n = to_tracker.norm();
    n > 0.0 && z.dot(&to_tracker) >= cos_max * n
}

pub(super) struct Accepted {
    pub configs: Vec<Vec<f64>>,
    pub attempts: usize,
    pub rejected_for_facing: usize,
    pub rejected_for_collision: usize,
}

pub(super) fn sample_configurations(
    opts: &SimOptions,
    side: Side,
    nominal_arm: &ArmModel,
    tracker_in_base_mm: &Point3<f64>,
    collides: &dyn Fn(Side, &[f64]) -> bool,
) -> Result<Accepted, SimError> {
    let mut rng = rng_for(opts.seed, stream_configs(side));
    let limits: Vec<(f64, f64)> = nominal_arm
        .joint_limits_rad()
        .into_iter()
        .map(|(lo, hi)| {
            let margin = opts.joint_limit_margin_fraction * (hi - lo);
            (lo + margin, hi - margin)
        })
        .collect();
    let axis = facing_axis(nominal_arm);
    let cos_max = opts.facing_max_angle_deg.to_radians().cos();
    let max_attempts = opts.max_attempts_per_config.saturating_mul(opts.n_configs);
    let mut out = Accepted {
        configs: Vec::with_capacity(opts.n_configs),
        attempts: 0,
        rejected_for_facing: 0,
        rejected_for_collision: 0,
    };
    while out.configs.len() < opts.n_configs {
        if out.attempts >= max_attempts {
            return Err(SimError::NotEnoughConfigurations {
                side,
                accepted: out.configs.len(),
                wanted: opts.n_configs,
                attempts: out.attempts,
                rejected_for_facing: out.rejected_for_facing,
                rejected_for_collision: out.rejected_for_collision,
            });
        }
        out.attempts += 1;
        let q = uniform_within(&mut rng, &limits);
        if !faces(nominal_arm, &axis, &q, tracker_in_base_mm, cos_max) {
            out.rejected_for_facing += 1;
        } else if collides(side, &q) {
            out.rejected_for_collision += 1;
        } else {
            out.configs.push(q);
        }
    }
    Ok(out)
}
