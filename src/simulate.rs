//! Simulated laser-tracker measurements of both arms (the paper's §4.1 protocol made concrete).
//!
//! # Protocol
//! 1. **True robot.** Each arm's 28 DH values get independent Gaussian errors
//!    (`dh_error.length_mm` on `a`, `d`; `dh_error.angle_rad` on `theta`, `alpha`), each reflector
//!    coordinate gets `reflector_error_mm`, and the true right-arm base is
//!    `left_base_from_right_base_nominal · E` with `E` a small random isometry (translation
//!    `N(0, base_error_mm)` per axis, rotation vector `N(0, base_error_rad)` per axis). The left-arm base
//!    is the reference frame and has no error. With `nominal_rms_target_mm` (the default) each arm's
//!    DH + reflector error is then scaled by one factor so that the nominal model's RMS relative
//!    positioning error on the simulated configurations is paper-like (paper Table 5: 2.45 mm left,
//!    5.56 mm right); the σ's then only shape the error.
//! 2. **Tracker.** Placed in the robot's body frame (x forward, z up; `body_from_left_base` links it
//!    to the left DH base) at a distance uniform in `tracker_distance_m` from the body origin, in a
//!    direction with azimuth uniform in `±tracker_azimuth_max_deg` about +x and elevation uniform in
//!    `tracker_elevation_deg`; its orientation is a uniformly random rotation.
//! 3. **Configurations** (drawn before the truth, see step 1). Commanded joint values uniform within
//!    the joint limits shrunk by `joint_limit_margin_fraction` of each joint's range at both ends. A
//!    configuration is accepted when the reflectors face the tracker —
//!    flange z · unit(tracker − flange origin) ≥ cos(`facing_max_angle_deg`) — and then
//!    `!collides(side, &q)` (so the closure is called only for facing configurations). Both checks use
//!    the *nominal* model (the planner does not know the truth), so the configurations depend only on the
//!    seed, the nominal model, the tracker pose and the closure; the error options never change them. After `max_attempts_per_config · n_configs`
//!    attempts per arm the simulation gives up with [`SimError::NotEnoughConfigurations`].
//! 4. **Measurements.** Recorded joint values are the commanded `q`. The true robot moves to
//!    `q + δq(q)` where `δq` is the optional unmodelled joint error ([`JointErrorModel`]). Measured point
//!    = `tracker_from_left_base · left_base_from_arm_base(true) · FK_true(q + δq) · t_k(true)` + Gaussian
//!    noise with σ = MPE/2 per axis, MPE = `mpe_um + mpe_um_per_m · distance_m` (converted to mm).
//!    Optional outliers ([`OutlierModel`]) then displace one reflector of some configurations.
//! 5. **Split.** The first `n_cal` accepted configurations of each arm are `cal`, the rest `ver`.
//!    Configurations are drawn independently, so this is a random split. Ids are `L001…`, `R001…`;
//!    `Measurement::line` is the CSV line the writer produces with the header on line 1 (`i + 2`).
//!
//! Every random quantity comes from its own ChaCha8 stream of the seed, so e.g. enabling outliers changes
//! only the outlier rows, and enabling joint errors does not change the configurations or the noise draws.

use crate::dataset::{ArmData, Dataset, MIN_CONFIGS, Measurement, Split, TrackerSpec};
use crate::kinematics::{
    ArmModel, DualArmModel, N_DH, N_JOINTS, ParamVector, Side, joint_limits_rad,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::path::PathBuf;

/// Standard deviation of the random DH errors of the true robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhErrorSize {
    /// σ of `a` and `d`, mm.
    pub length_mm: f64,
    /// σ of `theta` and `alpha`, rad.
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
    /// The robot's body frame (x forward, z up) relative to the left-arm DH base.
    pub body_from_left_base: Isometry3<f64>,
    pub joint_error: Option<JointErrorModel>,
    pub outliers: Option<OutlierModel>,
    /// Largest angle between the flange z axis and the direction to the tracker, deg.
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
    /// Random configurations tried, `[left, right]`.
    pub attempts: [usize; 2],
    /// Injected outliers (empty without [`SimOptions::outliers`]).
    pub outliers: Vec<OutlierRecord>,
    /// Phases φ_i of the periodic joint error, `[left, right]` (zeros without joint errors).
    pub joint_error_phases_rad: [[f64; N_JOINTS]; 2],
}

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("invalid simulation option `{field}`: {message}")]
    InvalidOption {
        field: &'static str,
        message: String,
    },
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

fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

fn check_options(opts: &SimOptions, nominal: &DualArmModel) -> Result<(), SimError> {
    let bad =
        |field: &'static str, message: String| Err(SimError::InvalidOption { field, message });
    let nonneg = |field: &'static str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            bad(field, format!("expected a finite value ≥ 0, got {v}"))
        }
    };
    if opts.n_configs < MIN_CONFIGS {
        return bad(
            "n_configs",
            format!("expected at least {MIN_CONFIGS}, got {}", opts.n_configs),
        );
    }
    if opts.n_cal > opts.n_configs {
        return bad(
            "n_cal",
            format!("{} exceeds n_configs = {}", opts.n_cal, opts.n_configs),
        );
    }
    nonneg("dh_error.length_mm", opts.dh_error.length_mm)?;
    nonneg("dh_error.angle_rad", opts.dh_error.angle_rad)?;
    nonneg("reflector_error_mm", opts.reflector_error_mm)?;
    if let Some((lo, hi)) = opts.nominal_rms_target_mm
        && !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi)
    {
        return bad(
            "nominal_rms_target_mm",
            format!("expected 0 < min ≤ max, got ({lo}, {hi})"),
        );
    }
    nonneg("base_error_mm", opts.base_error_mm)?;
    nonneg("base_error_rad", opts.base_error_rad)?;
    nonneg("tracker.mpe_um", opts.tracker.mpe_um)?;
    nonneg("tracker.mpe_um_per_m", opts.tracker.mpe_um_per_m)?;
    let (lo, hi) = opts.tracker_distance_m;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
        return bad(
            "tracker_distance_m",
            format!("expected 0 < min ≤ max, got ({lo}, {hi})"),
        );
    }
    nonneg("tracker_azimuth_max_deg", opts.tracker_azimuth_max_deg)?;
    let (elo, ehi) = opts.tracker_elevation_deg;
    if !(elo.is_finite() && ehi.is_finite() && elo <= ehi && elo >= -90.0 && ehi <= 90.0) {
        return bad(
            "tracker_elevation_deg",
            format!("expected −90 ≤ min ≤ max ≤ 90, got ({elo}, {ehi})"),
        );
    }
    let f = opts.facing_max_angle_deg;
    if !(f.is_finite() && f > 0.0 && f <= 180.0) {
        return bad(
            "facing_max_angle_deg",
            format!("expected 0 < angle ≤ 180, got {f}"),
        );
    }
    let m = opts.joint_limit_margin_fraction;
    if !(m.is_finite() && (0.0..0.5).contains(&m)) {
        return bad(
            "joint_limit_margin_fraction",
            format!("expected 0 ≤ fraction < 0.5, got {m}"),
        );
    }
    if opts.max_attempts_per_config == 0 {
        return bad("max_attempts_per_config", "expected at least 1".into());
    }
    if let Some(j) = &opts.joint_error {
        nonneg(
            "joint_error.periodic_amplitude_mrad",
            j.periodic_amplitude_mrad,
        )?;
        if !j.periods_per_rev.is_finite() {
            return bad(
                "joint_error.periods_per_rev",
                format!("expected a finite value, got {}", j.periods_per_rev),
            );
        }
        if !j.compliance_mrad_per_m.is_finite() {
            return bad(
                "joint_error.compliance_mrad_per_m",
                format!("expected a finite value, got {}", j.compliance_mrad_per_m),
            );
        }
    }
    if let Some(o) = &opts.outliers {
        if !(o.fraction.is_finite() && (0.0..=1.0).contains(&o.fraction)) {
            return bad(
                "outliers.fraction",
                format!("expected 0 ≤ fraction ≤ 1, got {}", o.fraction),
            );
        }
        nonneg("outliers.magnitude_mm", o.magnitude_mm)?;
    }
    if nominal.left.reflectors_mm != nominal.right.reflectors_mm {
        return bad(
            "nominal",
            "the dataset has one set of nominal reflectors; both arms must share it".into(),
        );
    }
    Ok(())
}

/// Reflector distances `|p_i,k − p_j,k|` of all pairs i < j of `configs`, flattened, mm.
fn pair_distances_mm(arm: &ArmModel, configs: &[[f64; N_JOINTS]]) -> Vec<[f64; 3]> {
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
fn relative_rms_mm(
    truth: &ArmModel,
    nominal_distances: &[[f64; 3]],
    configs: &[[f64; N_JOINTS]],
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
    delta: &ParamVector,
    target_mm: Option<f64>,
    configs: &[[f64; N_JOINTS]],
) -> ArmModel {
    let v0 = nominal.to_vector();
    let at = |scale: f64| ArmModel::from_vector(&(v0 + scale * delta));
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
fn perturb_model(
    opts: &SimOptions,
    nominal: &DualArmModel,
    configs: &[Vec<[f64; N_JOINTS]>; 2],
) -> DualArmModel {
    let mut rng = rng_for(opts.seed, STREAM_GEOMETRY);
    let mut draw = || {
        let mut d = ParamVector::zeros();
        for k in 0..N_DH {
            let sigma = if k % 4 < 2 {
                opts.dh_error.length_mm
            } else {
                opts.dh_error.angle_rad
            };
            d[k] = sigma * gauss(&mut rng);
        }
        for k in N_DH..d.len() {
            d[k] = opts.reflector_error_mm * gauss(&mut rng);
        }
        d
    };
    let delta_left = draw();
    let delta_right = draw();
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
        [pick(), pick()]
    });
    DualArmModel {
        left: true_arm(
            &nominal.left,
            &delta_left,
            targets.map(|t| t[0]),
            &configs[0],
        ),
        right: true_arm(
            &nominal.right,
            &delta_right,
            targets.map(|t| t[1]),
            &configs[1],
        ),
        left_base_from_right_base: nominal.left_base_from_right_base * error,
    }
}

/// The tracker pose relative to the left-arm base (see the module documentation).
fn place_tracker(opts: &SimOptions) -> Isometry3<f64> {
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

/// Do the reflectors of `arm` at `q` face a tracker at `tracker_in_base_mm`?
fn faces(
    arm: &ArmModel,
    q: &[f64; N_JOINTS],
    tracker_in_base_mm: &Point3<f64>,
    cos_max: f64,
) -> bool {
    let flange = arm.base_from_flange(q);
    let z = flange.rotation * Vector3::z();
    let to_tracker = tracker_in_base_mm - Point3::from(flange.translation.vector);
    let n = to_tracker.norm();
    n > 0.0 && z.dot(&to_tracker) >= cos_max * n
}

struct Accepted {
    configs: Vec<[f64; N_JOINTS]>,
    attempts: usize,
    rejected_for_facing: usize,
    rejected_for_collision: usize,
}

fn sample_configurations(
    opts: &SimOptions,
    side: Side,
    nominal_arm: &ArmModel,
    tracker_in_base_mm: &Point3<f64>,
    collides: &dyn Fn(Side, &[f64; N_JOINTS]) -> bool,
) -> Result<Accepted, SimError> {
    let mut rng = rng_for(opts.seed, stream_configs(side));
    let limits = joint_limits_rad().map(|(lo, hi)| {
        let margin = opts.joint_limit_margin_fraction * (hi - lo);
        (lo + margin, hi - margin)
    });
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
        let q: [f64; N_JOINTS] = std::array::from_fn(|i| {
            let (lo, hi) = limits[i];
            if lo < hi {
                rng.random_range(lo..hi)
            } else {
                lo
            }
        });
        if !faces(nominal_arm, &q, tracker_in_base_mm, cos_max) {
            out.rejected_for_facing += 1;
        } else if collides(side, &q) {
            out.rejected_for_collision += 1;
        } else {
            out.configs.push(q);
        }
    }
    Ok(out)
}

/// Unmodelled joint error `δq(q)` of [`JointErrorModel`] for the true `arm`.
fn joint_error_rad(
    model: &JointErrorModel,
    phases_rad: &[f64; N_JOINTS],
    arm: &ArmModel,
    q: &[f64; N_JOINTS],
    gravity_in_base: &Vector3<f64>,
) -> [f64; N_JOINTS] {
    let frames = arm.frames(q);
    std::array::from_fn(|i| {
        let periodic = model.periodic_amplitude_mrad
            * 1e-3
            * (model.periods_per_rev * q[i] + phases_rad[i]).sin();
        let axis = frames[i].rotation * Vector3::z();
        let o = frames[i].translation.vector;
        let lever_mm: Vector3<f64> = frames[i + 1..]
            .iter()
            .map(|f| f.translation.vector - o)
            .sum();
        let torque_m = axis.dot(&lever_mm.cross(gravity_in_base)) / 1000.0;
        periodic + model.compliance_mrad_per_m * 1e-3 * torque_m
    })
}

/// Simulate a laser-tracker dataset of both arms. `collides(side, q)` tells whether the commanded
/// configuration `q` of `side` is in collision (with the body or the other arm).
pub fn simulate(
    opts: &SimOptions,
    nominal: &DualArmModel,
    collides: &dyn Fn(Side, &[f64; N_JOINTS]) -> bool,
) -> Result<SimOutput, SimError> {
    check_options(opts, nominal)?;
    let tracker_from_left_base = place_tracker(opts);
    let tracker_in_left_base = tracker_from_left_base.inverse_transform_point(&Point3::origin());

    // Configurations first: they depend on the nominal model and the tracker only.
    let mut rejected_for_collision = 0;
    let mut rejected_for_facing = 0;
    let mut attempts = [0; 2];
    let mut configs: [Vec<[f64; N_JOINTS]>; 2] = [Vec::new(), Vec::new()];
    for side in Side::BOTH {
        let s = side_index(side);
        let tracker_in_base = nominal
            .left_base_from(side)
            .inverse_transform_point(&tracker_in_left_base);
        let accepted =
            sample_configurations(opts, side, nominal.arm(side), &tracker_in_base, collides)?;
        rejected_for_collision += accepted.rejected_for_collision;
        rejected_for_facing += accepted.rejected_for_facing;
        attempts[s] = accepted.attempts;
        configs[s] = accepted.configs;
    }

    let truth = perturb_model(opts, nominal, &configs);

    let mut phases = [[0.0; N_JOINTS]; 2];
    if opts.joint_error.is_some() {
        let mut rng = rng_for(opts.seed, STREAM_JOINT_ERROR);
        for p in phases.iter_mut().flatten() {
            *p = rng.random_range(0.0..std::f64::consts::TAU);
        }
    }

    let mut arms = Vec::with_capacity(2);
    for side in Side::BOTH {
        let s = side_index(side);
        let true_arm = truth.arm(side);
        let tracker_from_base = tracker_from_left_base * truth.left_base_from(side);
        let body_from_base = opts.body_from_left_base * truth.left_base_from(side);
        let gravity_in_base = body_from_base.inverse_transform_vector(&(-Vector3::z()));
        let mut noise_rng = rng_for(opts.seed, stream_noise(side));
        let prefix = match side {
            Side::Left => 'L',
            Side::Right => 'R',
        };
        let measurements = configs[s]
            .iter()
            .enumerate()
            .map(|(i, q)| {
                let q_true = match &opts.joint_error {
                    Some(model) => {
                        let dq = joint_error_rad(model, &phases[s], true_arm, q, &gravity_in_base);
                        std::array::from_fn(|j| q[j] + dq[j])
                    }
                    None => *q,
                };
                let fk = true_arm.reflector_fk(&q_true);
                let tracker_points_mm = fk.points_mm.map(|p| {
                    let p = tracker_from_base.transform_point(&Point3::from(p)).coords;
                    let mpe_um =
                        opts.tracker.mpe_um + opts.tracker.mpe_um_per_m * p.norm() / 1000.0;
                    let sigma_mm = 0.5 * mpe_um / 1000.0;
                    p + sigma_mm * gauss3(&mut noise_rng)
                });
                Measurement {
                    id: format!("{prefix}{:03}", i + 1),
                    q_rad: *q,
                    tracker_points_mm,
                    split: if i < opts.n_cal {
                        Split::Cal
                    } else {
                        Split::Ver
                    },
                    line: i + 2,
                }
            })
            .collect::<Vec<_>>();
        arms.push(ArmData {
            side,
            file: PathBuf::from(format!("{}.csv", side.name())),
            measurements,
        });
    }

    let mut outliers = Vec::new();
    if let Some(model) = &opts.outliers {
        let mut rng = rng_for(opts.seed, STREAM_OUTLIERS);
        let count = ((model.fraction * opts.n_configs as f64).round() as usize).min(opts.n_configs);
        for arm in arms.iter_mut() {
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
    }

    let right = arms.pop().expect("two arms");
    let left = arms.pop().expect("two arms");
    Ok(SimOutput {
        dataset: Dataset {
            dir: PathBuf::new(),
            robot: None,
            tracker: opts.tracker,
            nominal_reflectors_mm: nominal.left.reflectors_mm,
            left,
            right,
        },
        truth,
        nominal: nominal.clone(),
        tracker_from_left_base,
        rejected_for_collision,
        rejected_for_facing,
        attempts,
        outliers,
        joint_error_phases_rad: phases,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3};

    /// The nominal IRB 14000 with the public body layout's right-arm base (issue 2).
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
            left: arm.clone(),
            right: arm,
            left_base_from_right_base: Isometry3::from_parts(
                Translation3::new(61.61, -70.77, -34.14),
                rotation,
            ),
        }
    }

    fn never(_: Side, _: &[f64; N_JOINTS]) -> bool {
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
        let l = &out.dataset.left.measurements;
        let r = &out.dataset.right.measurements;
        let pl: Vec<_> = l
            .iter()
            .map(|m| model.left.reflector_fk(&m.q_rad).points_mm)
            .collect();
        let pr: Vec<_> = r
            .iter()
            .map(|m| {
                model.right.reflector_fk(&m.q_rad).points_mm.map(|p| {
                    model
                        .left_base_from_right_base
                        .transform_point(&p.into())
                        .coords
                })
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
                .map(|ms| {
                    (m.left_base_from(side) * m.arm(side).base_from_flange(&ms.q_rad)).rotation
                })
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
            a.dataset.left.measurements[0].q_rad,
            b.dataset.left.measurements[0].q_rad
        );
        assert_ne!(
            a.dataset.right.measurements[0].q_rad,
            b.dataset.right.measurements[0].q_rad
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
        assert_ne!(out.truth.left, out.nominal.left);
        assert_ne!(out.truth.right, out.nominal.right);
        assert_ne!(out.truth.left, out.truth.right);
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
            raw.dataset.left.measurements.len(),
            scaled.dataset.left.measurements.len()
        );
        assert_eq!(
            raw.truth.left_base_from_right_base,
            scaled.truth.left_base_from_right_base
        );
        for side in Side::BOTH {
            let nominal = raw.nominal.arm(side).to_vector();
            let d_raw = raw.truth.arm(side).to_vector() - nominal;
            let d_scaled = scaled.truth.arm(side).to_vector() - nominal;
            let s = d_scaled.dot(&d_raw) / d_raw.norm_squared();
            assert!(
                (d_scaled - s * d_raw).norm() < 1e-9 * d_raw.norm() * s.max(1.0),
                "{side}"
            );
            // Noise-free target hit; the data adds only ~10 µm of tracker noise.
            let configs: Vec<_> = scaled
                .dataset
                .arm(side)
                .measurements
                .iter()
                .map(|m| m.q_rad)
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
                out.attempts[0] + out.attempts[1],
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
        let half = |side: Side, q: &[f64; N_JOINTS]| {
            calls.set(calls.get() + 1);
            side == Side::Left && q[0] > 0.0
        };
        let out = simulate(&opts, &nominal(), &half).unwrap();
        assert!(
            out.dataset
                .left
                .measurements
                .iter()
                .all(|m| m.q_rad[0] <= 0.0)
        );
        assert!(
            free.dataset
                .left
                .measurements
                .iter()
                .any(|m| m.q_rad[0] > 0.0)
        );
        assert_eq!(calls.get(), 120 + out.rejected_for_collision);
        let frac = out.rejected_for_collision as f64 / (60 + out.rejected_for_collision) as f64;
        assert!(frac > 0.3 && frac < 0.7, "rejected fraction {frac}");
        assert!(out.attempts[0] > free.attempts[0]);
        // The right arm saw no rejections and is unchanged.
        assert_eq!(out.dataset.right, free.dataset.right);

        // Rejecting everything ends with an error after the attempt cap, not a hang.
        let opts = SimOptions {
            max_attempts_per_config: 20,
            ..opts
        };
        let all = |_: Side, _: &[f64; N_JOINTS]| true;
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
            let phases = out.joint_error_phases_rad[side_index(side)];
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
                let q_true: [f64; N_JOINTS] = std::array::from_fn(|i| {
                    m.q_rad[i] + 2e-3 * (3.0 * m.q_rad[i] + phases[i]).sin()
                });
                let fk = out.truth.arm(side).reflector_fk(&q_true);
                for k in 0..3 {
                    let p = tracker_from_base
                        .transform_point(&fk.points_mm[k].into())
                        .coords;
                    // Same noise draws in both runs: the residual is noise-scale only.
                    assert!((m.tracker_points_mm[k] - p).norm() < 0.1, "{side} {}", m.id);
                    largest_shift = largest_shift
                        .max((m.tracker_points_mm[k] - mc.tracker_points_mm[k]).norm());
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
            let a = &clean.dataset.left.measurements;
            let b = &out.dataset.left.measurements;
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
}
