//! Simulated laser-tracker measurements of both arms (the paper's §4.1 protocol made concrete).
//!
//! # Protocol
//! 1. **True robot.** Each arm's kinematic parameters get independent Gaussian errors
//!    (`dh_error.length_mm` on the lengths, `dh_error.angle_rad` on the angles: `a, d` and
//!    `theta, alpha` of the 28 DH values of the built-in robot; `tx, ty, tz` and `rx, ry, rz` of every
//!    joint-origin correction of a URDF chain but the first — a rigid motion of the whole arm, which
//!    the base error below models — including those distances cannot see), each reflector
//!    coordinate gets `reflector_error_mm`, and the true right-arm base is
//!    `left_base_from_right_base_nominal · E` with `E` a small random isometry (translation
//!    `N(0, base_error_mm)` per axis, rotation vector `N(0, base_error_rad)` per axis). The left-arm base
//!    is the reference frame and has no error. With `nominal_rms_target_mm` (the default) each arm's
//!    kinematic + reflector error is then scaled by one factor so that the nominal model's RMS relative
//!    positioning error on the simulated configurations is paper-like (paper Table 5: 2.45 mm left,
//!    5.56 mm right); the σ's then only shape the error.
//! 2. **Tracker.** Placed in the robot's body frame (x forward, z up as in ROS's REP 103;
//!    `body_from_left_base` links it to the left arm's model base) at a distance uniform in `tracker_distance_m` from the body origin, in a
//!    direction with azimuth uniform in `±tracker_azimuth_max_deg` about +x and elevation uniform in
//!    `tracker_elevation_deg`; its orientation is a uniformly random rotation.
//! 3. **Configurations** (drawn before the truth, see step 1). Commanded joint values uniform within
//!    the joint limits ([`crate::kinematics::ArmModel::joint_limits_rad`]) shrunk by
//!    `joint_limit_margin_fraction` of each joint's range at both ends. A configuration is accepted
//!    when the reflectors face the tracker — n · unit(tracker − tip origin) ≥ cos(`facing_max_angle_deg`)
//!    with n the normal of the reflector triangle pointing away from the tip origin (the flange z axis
//!    for the default reflectors) — and then
//!    `!collides(side, &q)` (so the closure is called only for facing configurations). Both checks use
//!    the *nominal* model (the planner does not know the truth), so the configurations depend only on the
//!    seed, the nominal model, the tracker pose and the closure; the error options never change them. After `max_attempts_per_config · n_configs`
//!    attempts per arm the simulation gives up with [`SimError::NotEnoughConfigurations`].
//! 4. **Measurements.** Recorded joint values are the commanded `q`. The true robot moves to
//!    `q + δq(q)` where `δq` is the optional unmodelled joint error ([`JointErrorModel`]). Measured point
//!    = `tracker_from_left_base · left_base_from_arm_base(true) · FK_true(q + δq) · t_k(true)` + Gaussian
//!    noise with σ = MPE/2 per axis, MPE = `mpe_um + mpe_um_per_m · distance_m` (converted to mm).
//!    Optional outliers ([`OutlierModel`]) then displace one reflector of some configurations, and
//!    optional gross errors ([`GrossErrorModel`]) misread a reflector, swap two labels or put a row of
//!    the other arm into some configurations.
//! 5. **Split.** The first `n_cal` accepted configurations of each arm are `cal`, the rest `ver`.
//!    Configurations are drawn independently, so this is a random split. Ids are `L001…`, `R001…`;
//!    `Measurement::line` is the CSV line the writer produces with the header on line 1 (`i + 2`).
//!
//! Every random quantity comes from its own ChaCha8 stream of the seed, so e.g. enabling outliers changes
//! only the outlier rows, and enabling joint errors does not change the configurations or the noise draws.

mod check;
mod gross;
mod joint_errors;
mod presets;
mod sampling;
#[cfg(test)]
mod tests;
mod truth;

use crate::dataset::{ArmData, Dataset, Measurement, Split, TrackerSpec};
use crate::kinematics::DualArmModel;
use crate::side::{PerSide, Side};
pub use gross::{GrossError, GrossErrorModel, GrossErrorRecord};
use nalgebra::{Isometry3, Point3, Vector3};
pub use presets::{
    default_reflectors_for, paper_options, resting_poses, simulate_with_robot,
    unmodelled_joint_errors,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::path::PathBuf;

/// Standard deviation of the random kinematic errors of the true robot (DH values, or joint-origin
/// corrections of a chain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhErrorSize {
    /// σ of the lengths (`a`, `d`; `tx, ty, tz`), mm.
    pub length_mm: f64,
    /// σ of the angles (`theta`, `alpha`; `rx, ry, rz`), rad.
    pub angle_rad: f64,
}

/// Unmodelled joint errors of the true robot (not representable by the DH model).
///
/// The true joint angle of chain joint `i` is `q_i + δq_i` with
/// `δq_i = periodic_amplitude_mrad · 1e-3 · sin(periods_per_rev · q_i + φ_i)
///        + compliance_mrad_per_m · 1e-3 · τ_i`,
/// where the phases `φ_i` are uniform in [0, 2π) (per arm and joint, reported in
/// [`SimOutput::joint_error_phases_rad`]) and `τ_i` is a gravity-torque proxy in metres: one unit mass
/// at each frame origin `o_i … o_7` downstream of the joint,
/// `τ_i = z_{i−1} · Σ_{j≥i} (o_j − o_{i−1}) × ĝ / 1000`,
/// with `ĝ` the body's −z axis seen in the arm's base frame and the frames of the true model at `q`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointErrorModel {
    /// Amplitude of the periodic (gear) error of every joint, mrad.
    pub periodic_amplitude_mrad: f64,
    /// Periods of the periodic error per joint revolution.
    pub periods_per_rev: f64,
    /// Joint deflection per metre of gravity lever (see above), mrad/m.
    pub compliance_mrad_per_m: f64,
}

impl Default for JointErrorModel {
    /// A mild example: 0.3 mrad twice-per-revolution gear error and 0.2 mrad/m compliance.
    fn default() -> Self {
        Self {
            periodic_amplitude_mrad: 0.3,
            periods_per_rev: 2.0,
            compliance_mrad_per_m: 0.2,
        }
    }
}

/// Gross measurement errors: `round(fraction · n_configs)` configurations per arm (chosen at random) have
/// one reflector (chosen at random) displaced by exactly `magnitude_mm` in a uniformly random direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutlierModel {
    pub fraction: f64,
    pub magnitude_mm: f64,
}

/// Options of [`simulate`]. `SimOptions::default()` gives the paper-like setting.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    pub seed: u64,
    /// Configurations per arm (paper: 220).
    pub n_configs: usize,
    /// Of which calibration configurations (paper: 120); the rest are verification.
    pub n_cal: usize,
    pub dh_error: DhErrorSize,
    /// σ of each true reflector coordinate about its nominal value, mm.
    pub reflector_error_mm: f64,
    /// If set, each arm's drawn DH and reflector errors are scaled by one factor so that the nominal
    /// model's RMS relative positioning error on the simulated configurations (paper eq. 5, noise-free,
    /// without joint errors; largest reflector RMS over all pairs) equals a value drawn uniformly from
    /// this range (per arm), mm. The σ's then set only the shape of the error. Ignored for an arm whose
    /// drawn error is zero.
    pub nominal_rms_target_mm: Option<(f64, f64)>,
    /// σ per axis of the true right-arm base translation error, mm.
    pub base_error_mm: f64,
    /// σ per axis of the true right-arm base rotation-vector error, rad.
    pub base_error_rad: f64,
    pub tracker: TrackerSpec,
    /// Tracker distance from the body origin, m (min, max).
    pub tracker_distance_m: (f64, f64),
    /// Tracker direction: azimuth uniform in ±this about the body's +x axis, deg.
    pub tracker_azimuth_max_deg: f64,
    /// Tracker direction: elevation above the body's xy plane, uniform in (min, max), deg.
    pub tracker_elevation_deg: (f64, f64),
    /// The robot's body frame (x forward, z up) relative to the left arm's model base.
    pub body_from_left_base: Isometry3<f64>,
    pub joint_error: Option<JointErrorModel>,
    pub outliers: Option<OutlierModel>,
    /// Gross errors of real files (misread reflectors, swapped labels, rows of the other arm), applied
    /// after `outliers`.
    pub gross_errors: Option<GrossErrorModel>,
    /// Largest angle between the reflectors' facing direction (the flange z axis for the default
    /// reflectors) and the direction to the tracker, deg.
    pub facing_max_angle_deg: f64,
    /// Joint ranges are shrunk by this fraction of the range at both ends.
    pub joint_limit_margin_fraction: f64,
    /// Give up after `max_attempts_per_config · n_configs` random configurations per arm.
    pub max_attempts_per_config: usize,
}

impl SimOptions {
    /// Nominal reflector coordinates in the flange frame, mm: a = (45, 0, 40), b = (−25, 40, 40),
    /// c = (−25, −40, 40).
    pub fn default_reflectors() -> [Vector3<f64>; 3] {
        [
            Vector3::new(45.0, 0.0, 40.0),
            Vector3::new(-25.0, 40.0, 40.0),
            Vector3::new(-25.0, -40.0, 40.0),
        ]
    }
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            n_configs: 220,
            n_cal: 120,
            // Angle-dominated, as the paper's orientation/position ratio suggests (Table 5).
            dh_error: DhErrorSize {
                length_mm: 0.3,
                angle_rad: 0.004,
            },
            reflector_error_mm: 0.5,
            nominal_rms_target_mm: Some((2.5, 5.5)),
            base_error_mm: 1.0,
            base_error_rad: 0.005,
            tracker: TrackerSpec::default(),
            tracker_distance_m: (1.5, 3.0),
            tracker_azimuth_max_deg: 45.0,
            tracker_elevation_deg: (-10.0, 30.0),
            body_from_left_base: Isometry3::identity(),
            joint_error: None,
            outliers: None,
            gross_errors: None,
            facing_max_angle_deg: 70.0,
            joint_limit_margin_fraction: 0.05,
            max_attempts_per_config: 500,
        }
    }
}

/// One injected outlier.
#[derive(Clone, Debug, PartialEq)]
pub struct OutlierRecord {
    pub side: Side,
    /// Index into the arm's measurements.
    pub index: usize,
    pub id: String,
    /// Reflector index (0 = a, 1 = b, 2 = c).
    pub reflector: usize,
    /// Displacement added to the measured point, tracker frame, mm.
    pub displacement_mm: Vector3<f64>,
}

/// Everything [`simulate`] produces, in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOutput {
    /// The measurements; `dir` is empty, `robot` is `None`, reflectors are the nominal ones.
    pub dataset: Dataset,
    /// True DH tables, true reflectors and true `left_base_from_right_base`.
    pub truth: DualArmModel,
    /// The model the user starts from (the one passed in).
    pub nominal: DualArmModel,
    pub tracker_from_left_base: Isometry3<f64>,
    /// Configurations that faced the tracker but collided, both arms.
    pub rejected_for_collision: usize,
    /// Configurations whose reflectors did not face the tracker, both arms.
    pub rejected_for_facing: usize,
    /// Random configurations tried per arm.
    pub attempts: PerSide<usize>,
    /// Injected outliers (empty without [`SimOptions::outliers`]).
    pub outliers: Vec<OutlierRecord>,
    /// Injected gross errors (empty without [`SimOptions::gross_errors`]).
    pub gross_errors: Vec<GrossErrorRecord>,
    /// Phases φ_i of the periodic joint error per arm and joint (zeros without joint errors).
    pub joint_error_phases_rad: PerSide<Vec<f64>>,
}

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("invalid simulation option `{field}`: {message}")]
    InvalidOption {
        field: &'static str,
        message: String,
    },
    #[error("{side} arm: no resting pose free of collisions found ({attempts} tried)")]
    NoRestingPose { side: Side, attempts: usize },
    #[error(
        "{side} arm: only {accepted} of {wanted} configurations found in {attempts} attempts \
         ({rejected_for_facing} not facing the tracker, {rejected_for_collision} in collision)"
    )]
    NotEnoughConfigurations {
        side: Side,
        accepted: usize,
        wanted: usize,
        attempts: usize,
        rejected_for_facing: usize,
        rejected_for_collision: usize,
    },
}

// Independent random streams of one seed.
const STREAM_GEOMETRY: u64 = 1;

const STREAM_TRACKER: u64 = 2;

const STREAM_JOINT_ERROR: u64 = 3;

const STREAM_OUTLIERS: u64 = 4;

const STREAM_TARGET: u64 = 5;

const STREAM_RESTING: u64 = 6;

const STREAM_GROSS: u64 = 7;

const fn stream_configs(side: Side) -> u64 {
    match side {
        Side::Left => 10,
        Side::Right => 11,
    }
}

const fn stream_noise(side: Side) -> u64 {
    match side {
        Side::Left => 20,
        Side::Right => 21,
    }
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

fn gauss3(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    Vector3::new(gauss(rng), gauss(rng), gauss(rng))
}

/// Simulate a laser-tracker dataset of both arms. `collides(side, q)` tells whether the commanded
/// configuration `q` of `side` is in collision (with the body or the other arm).
pub fn simulate(
    opts: &SimOptions,
    nominal: &DualArmModel,
    collides: &dyn Fn(Side, &[f64]) -> bool,
) -> Result<SimOutput, SimError> {
    check::check_options(opts, nominal)?;
    let tracker_from_left_base = sampling::place_tracker(opts);
    let tracker_in_left_base = tracker_from_left_base.inverse_transform_point(&Point3::origin());

    // Configurations first: they depend on the nominal model and the tracker only.
    let accepted = PerSide::try_from_fn(|side| {
        let tracker_in_base = nominal
            .left_base_from(side)
            .inverse_transform_point(&tracker_in_left_base);
        sampling::sample_configurations(opts, side, nominal.arm(side), &tracker_in_base, collides)
    })?;
    let configs = accepted.as_ref().map(|_, a| a.configs.clone());
    let truth = truth::perturb_model(opts, nominal, &configs);

    let mut phases = PerSide::from_fn(|side| vec![0.0; nominal.arm(side).joint_count()]);
    if opts.joint_error.is_some() {
        let mut rng = rng_for(opts.seed, STREAM_JOINT_ERROR);
        for p in phases.left.iter_mut().chain(phases.right.iter_mut()) {
            *p = rng.random_range(0.0..std::f64::consts::TAU);
        }
    }
    let mut arms = PerSide::from_fn(|side| ArmData {
        side,
        file: PathBuf::from(format!("{}.csv", side.name())),
        links: None,
        station: None,
        linear_joints: {
            let linear = nominal.arm(side).linear_joints();
            if linear.contains(&true) {
                linear
            } else {
                Vec::new()
            }
        },
        nominal_reflectors_mm: None,
        measurements: measure_arm(
            opts,
            side,
            &truth,
            &tracker_from_left_base,
            &configs[side],
            &phases[side],
        ),
    });
    let outliers = match &opts.outliers {
        Some(model) => inject_outliers(opts, model, &mut arms),
        None => Vec::new(),
    };
    let gross_errors = match &opts.gross_errors {
        Some(model) => gross::inject(opts, model, &mut arms),
        None => Vec::new(),
    };
    Ok(SimOutput {
        dataset: Dataset {
            dir: PathBuf::new(),
            robot: None,
            tracker: opts.tracker,
            nominal_reflectors_mm: nominal.arm(Side::Left).reflectors_mm.clone(),
            reflector_names: nominal.arm(Side::Left).reflector_names.clone(),
            arms,
            measured_together: false,
        },
        truth,
        nominal: nominal.clone(),
        tracker_from_left_base,
        rejected_for_collision: accepted.values().map(|a| a.rejected_for_collision).sum(),
        rejected_for_facing: accepted.values().map(|a| a.rejected_for_facing).sum(),
        attempts: accepted.map(|_, a| a.attempts),
        outliers,
        gross_errors,
        joint_error_phases_rad: phases,
    })
}

/// Step 4 of the protocol for one arm: the true robot at `q + δq(q)`, seen by the tracker with noise.
fn measure_arm(
    opts: &SimOptions,
    side: Side,
    truth: &DualArmModel,
    tracker_from_left_base: &Isometry3<f64>,
    configs: &[Vec<f64>],
    phases: &[f64],
) -> Vec<Measurement> {
    let true_arm = truth.arm(side);
    let tracker_from_base = tracker_from_left_base * truth.left_base_from(side);
    let body_from_base = opts.body_from_left_base * truth.left_base_from(side);
    let gravity_in_base = body_from_base.inverse_transform_vector(&(-Vector3::z()));
    let mut noise_rng = rng_for(opts.seed, stream_noise(side));
    let prefix = match side {
        Side::Left => 'L',
        Side::Right => 'R',
    };
    configs
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let q_true = match &opts.joint_error {
                Some(model) => {
                    let dq =
                        joint_errors::joint_error_rad(model, phases, true_arm, q, &gravity_in_base);
                    q.iter().zip(&dq).map(|(q, dq)| q + dq).collect()
                }
                None => q.clone(),
            };
            let fk = true_arm.reflector_fk(&q_true);
            let tracker_points_mm = fk
                .points_mm
                .iter()
                .map(|p| {
                    let p = tracker_from_base.transform_point(&Point3::from(*p)).coords;
                    let mpe_um =
                        opts.tracker.mpe_um + opts.tracker.mpe_um_per_m * p.norm() / 1000.0;
                    let sigma_mm = 0.5 * mpe_um / 1000.0;
                    p + sigma_mm * gauss3(&mut noise_rng)
                })
                .collect();
            Measurement {
                id: format!("{prefix}{:03}", i + 1),
                q_rad: q.clone(),
                tracker_points_mm,
                split: if i < opts.n_cal {
                    Split::Cal
                } else {
                    Split::Ver
                },
                line: i + 2,
            }
        })
        .collect()
}

/// Displace one reflector of a fraction of each arm's configurations (left arm first).
fn inject_outliers(
    opts: &SimOptions,
    model: &OutlierModel,
    arms: &mut PerSide<ArmData>,
) -> Vec<OutlierRecord> {
    let mut outliers = Vec::new();
    let mut rng = rng_for(opts.seed, STREAM_OUTLIERS);
    let count = ((model.fraction * opts.n_configs as f64).round() as usize).min(opts.n_configs);
    for (_, arm) in arms.iter_mut() {
        let mut picked = rand::seq::index::sample(&mut rng, opts.n_configs, count).into_vec();
        picked.sort_unstable();
        for index in picked {
            let reflector = rng.random_range(0..3);
            let dir = loop {
                let v = gauss3(&mut rng);
                if v.norm() > 1e-6 {
                    break v.normalize();
                }
            };
            let displacement_mm = model.magnitude_mm * dir;
            let m = &mut arm.measurements[index];
            m.tracker_points_mm[reflector] += displacement_mm;
            outliers.push(OutlierRecord {
                side: arm.side,
                index,
                id: m.id.clone(),
                reflector,
                displacement_mm,
            });
        }
    }
    outliers
}
