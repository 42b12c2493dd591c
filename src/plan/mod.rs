//! Planning the measurement: which configurations to measure so that every identifiable parameter is
//! well determined, with every configuration collision-free and its reflectors facing the tracker.
//!
//! 1. **Candidates** ([`candidates`]): joint values drawn uniformly within the limits (less a margin),
//!    kept when the reflectors' triangle faces the tracker within the incidence limit, lies within its
//!    range, the arm is clear of the body, the other arm (resting at its home pose) and the cell's
//!    keep-out boxes by the clearance — the simulator's checks (parry3d), on the robot's own meshes —
//!    and no link of the robot lies on a reflector's line to the tracker.
//! 2. **Selection**: greedy, over the identifiable parameters (columns scaled to unit RMS over the
//!    candidates; the parameters distances between the candidates cannot identify — the calibration's
//!    own analysis, [`crate::solver::identifiability::identifiable_at`] — left out). The first two picks by
//!    D-optimality of the reflector positions' scatter ([`select`]: distances taken as isotropic, the
//!    information is that of the positions with the tracker's translation unknown); then
//!    ([`select_by_distances`]) each next configuration the one that lowers most `trace(M⁻¹ P)` — the
//!    predicted variance of a verification pair's distance error (I-optimality), with `M` the
//!    information of the distances between the chosen configurations and `P` the mean information of a
//!    pair of candidates — by the Woodbury identity. Then an exchange ([`exchange::exchange`], a
//!    modified Fedorov exchange) swaps chosen configurations for candidates while that lowers the
//!    same criterion.
//! 3. **Order** ([`order`]): a short visiting sequence — nearest neighbour from the first pick, then
//!    2-opt on the joint-space path length (rad; mm for a prismatic joint) — and each leg checked for
//!    collisions at 2° steps; a leg that collides is re-routed through a via point ([`reroute`]: the
//!    home pose or a collision-free candidate, the shortest detour whose two legs are clear).
//!
//! The predicted standard deviations of the parameters for the chosen set are those of
//! [`crate::solver::uncertainty`] with the tracker's noise (`plan` in `dualcal plan` prints them);
//! [`bound::relaxed_bound`] bounds the verification accuracy any design of as many of the candidates
//! could predict (a convex relaxation on the reflector positions' information).

use crate::collision::{CollisionWorld, KeepOutBox};
use crate::kinematics::ArmModel;
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};
use nalgebra::{DMatrix, Point3, Vector3};

pub mod bound;
pub mod exchange;
mod files;
pub mod region;
pub use bound::DesignBound;
pub use files::{PlanOutput, bound_line, id_prefix, is_yumi, plan_files, summary_line};
#[cfg(test)]
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
pub use region::{Region, RegionPrediction};

/// What the planner is told.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanOptions {
    /// Configurations to choose per arm.
    pub per_arm: usize,
    /// Candidates drawn per arm (accepted ones).
    pub candidates: usize,
    pub seed: u64,
    /// The tracker's position in the robot's body (root) frame, mm.
    pub tracker_in_body_mm: Vector3<f64>,
    /// Largest angle between the reflectors' facing direction and the line to the tracker, deg.
    pub max_incidence_deg: f64,
    /// Largest distance from the tracker to the flange, mm.
    pub max_range_mm: f64,
    /// Fraction of each joint's range kept clear at both ends.
    pub joint_limit_margin_fraction: f64,
    /// Clearance to the body and the other arm, mm.
    pub clearance_mm: f64,
    /// Random draws allowed per accepted candidate before giving up.
    pub max_attempts_per_candidate: usize,
    /// Keep-out boxes of the cell (body frame): no arm link within the clearance of one.
    pub keep_out: Vec<KeepOutBox>,
    /// Configurations already measured, per arm (extending a dataset): the design starts from them
    /// and adds `per_arm` new ones.
    pub existing: PerSide<Vec<Vec<f64>>>,
    /// Where the calibrated robot must be accurate: the criterion's verification pairs and the
    /// prediction's ([`region`]).
    pub region: Region,
    /// Configurations drawn for the region (per arm).
    pub region_samples: usize,
    /// Robots (the nominal one and perturbed ones) the region's information is averaged over.
    pub robust_draws: usize,
    /// Draws of the robot's errors and the tracker's noise behind the prediction.
    pub prediction_draws: usize,
    /// The tracker's MPE (the prediction's noise).
    pub tracker_mpe: crate::dataset::TrackerSpec,
    /// Plan the smallest number of configurations per arm whose predicted accuracy over the region
    /// (the default method's mean) reaches this multiple of the noise floor (`per_arm` ignored).
    pub target: Option<f64>,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            per_arm: 20,
            candidates: 600,
            seed: 1,
            tracker_in_body_mm: Vector3::new(2000.0, 0.0, 300.0),
            max_incidence_deg: 60.0,
            max_range_mm: 15_000.0,
            joint_limit_margin_fraction: 0.05,
            clearance_mm: 5.0,
            max_attempts_per_candidate: 200,
            keep_out: Vec::new(),
            existing: PerSide::new(Vec::new(), Vec::new()),
            region: Region::Workspace,
            region_samples: 100,
            robust_draws: 4,
            prediction_draws: 32,
            tracker_mpe: crate::dataset::TrackerSpec::default(),
            target: None,
        }
    }
}

/// Why a plan could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error(
        "{side} arm: only {found} of {wanted} candidate configurations face the tracker, are free \
         of collisions and seen after {attempts} draws ({facing} did not face it or were out of range, \
         {colliding} collided, {hidden} had a reflector hidden by the robot): move the tracker, or \
         allow a larger incidence angle"
    )]
    TooFewCandidates {
        side: Side,
        found: usize,
        wanted: usize,
        attempts: usize,
        facing: usize,
        colliding: usize,
        hidden: usize,
    },
    #[error("{0}")]
    Options(String),
}

/// One arm's plan.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmPlan {
    /// The chosen configurations in visiting order (rad; mm for a prismatic joint).
    pub configs: Vec<Vec<f64>>,
    /// Candidates accepted, and draws made.
    pub candidates: usize,
    pub attempts: usize,
    /// `log det` of the chosen set's (scaled) information, and that of the same number of candidates
    /// taken in the order they were drawn (a random set), for comparison.
    pub log_det: f64,
    pub log_det_random: f64,
    /// Joint-space length of the visiting path (through the via points).
    pub path_length: f64,
    /// Points the arm passes through, not measured, where the straight joint motion between two
    /// chosen configurations would collide ([`reroute`]).
    pub vias: Vec<Via>,
    /// Legs of the path (from configuration k to k + 1) on which a collision was found and no via
    /// point clears it.
    pub colliding_legs: Vec<usize>,
    /// Candidates the design did not choose (up to [`SAMPLE`], evenly spread over the pool): where
    /// the robot goes, for the predicted verification accuracy.
    pub sample: Vec<Vec<f64>>,
    /// The I-criterion `trace(M⁻¹ P)` of the greedy pass's design, and of the design after
    /// exchange ([`exchange::exchange`]) with the swaps it made.
    pub criterion_greedy: f64,
    pub criterion: f64,
    pub swaps: usize,
    /// What no design of as many of these candidates predicts better than, judged on
    /// [`Self::sample`] ([`bound::relaxed_bound`]; `None` where its information is singular).
    pub bound: Option<DesignBound>,
    /// Configurations of the region ([`region::samples`]) the criterion and the prediction used.
    pub region_count: usize,
    /// What the design predicts over the region ([`region::predict`]; `None` where singular).
    pub prediction: Option<RegionPrediction>,
    /// With a target ([`PlanOptions::target`]): the designs tried, N and their prediction, by N.
    pub curve: Vec<(usize, Option<RegionPrediction>)>,
}

/// How many unchosen candidates [`ArmPlan::sample`] keeps.
pub const SAMPLE: usize = 60;

/// A via point: where the arm goes between `configs[leg]` and `configs[leg + 1]` instead of the
/// straight joint motion, which collides.
#[derive(Clone, Debug, PartialEq)]
pub struct Via {
    pub leg: usize,
    pub q: Vec<f64>,
}

/// How many via candidates (the shortest detours first) are checked for a colliding leg.
const VIA_CANDIDATES: usize = 60;

/// Where each arm rests while the other one moves (its home pose), and the joints both arms share (a
/// torso: they follow the moving arm).
pub struct Resting {
    pub q: PerSide<Vec<f64>>,
    pub shared: crate::kinematics::SharedJoints,
}

impl Resting {
    fn of(robot: &RobotDescription) -> Self {
        Self {
            q: PerSide::from_fn(|side| robot.home_q_rad(side)),
            shared: robot.shared_joints(),
        }
    }

    /// Both arms' joint values with `side` at `q` and the other resting; shared joints take `q`'s.
    fn posed(&self, side: Side, q: &[f64]) -> (Vec<f64>, Vec<f64>) {
        match side {
            Side::Left => (
                q.to_vec(),
                self.shared.right_with_left_values(q, &self.q.right),
            ),
            Side::Right => (
                self.shared.left_with_right_values(&self.q.left, q),
                q.to_vec(),
            ),
        }
    }
}

/// Candidate configurations of `side` (module documentation, step 1): `(candidates, draws)`.
pub fn candidates(
    robot: &RobotDescription,
    arm: &ArmModel,
    side: Side,
    world: &CollisionWorld,
    options: &PlanOptions,
) -> Result<(Vec<Vec<f64>>, usize), PlanError> {
    let rest = Resting::of(robot);
    let body_from_base = robot.body_from_arm_base(side);
    let tracker = body_from_base.inverse_transform_point(&Point3::from(options.tracker_in_body_mm));
    let limits = region::limits_with_margin(arm, options.joint_limit_margin_fraction);
    let axis = facing_axis(arm);
    let cos_max = options.max_incidence_deg.to_radians().cos();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed ^ (0x9e37 + side as u64));
    let (mut out, mut attempts, mut facing, mut colliding, mut hidden) = (Vec::new(), 0, 0, 0, 0);
    let max_attempts = options.max_attempts_per_candidate * options.candidates;
    while out.len() < options.candidates {
        if attempts == max_attempts {
            return Err(PlanError::TooFewCandidates {
                side,
                found: out.len(),
                wanted: options.candidates,
                attempts,
                facing,
                colliding,
                hidden,
            });
        }
        attempts += 1;
        let q = region::draw_q(&mut rng, &limits);
        let flange = arm.base_from_flange(&q);
        let to_tracker = tracker - Point3::from(flange.translation.vector);
        let dist = to_tracker.norm();
        let normal = flange.rotation * axis;
        if !(dist > 0.0
            && dist <= options.max_range_mm
            && normal.dot(&to_tracker) >= cos_max * dist)
        {
            facing += 1;
            continue;
        }
        let (ql, qr) = rest.posed(side, &q);
        let (ql, qr) = (&ql, &qr);
        let clear = !world.in_collision(ql, qr, options.clearance_mm)
            && !world.in_keep_out(ql, qr, &options.keep_out, options.clearance_mm);
        if !clear {
            colliding += 1;
            continue;
        }
        // Every reflector seen: no link of the robot on its line to the tracker.
        let reflectors: Vec<Vector3<f64>> = arm
            .reflector_fk(&q)
            .points_mm
            .iter()
            .map(|p| body_from_base.transform_point(&Point3::from(*p)).coords)
            .collect();
        if world.line_of_sight_blocked(ql, qr, &reflectors, &options.tracker_in_body_mm, 5.0) {
            hidden += 1;
            continue;
        }
        out.push(q);
    }
    Ok((out, attempts))
}

/// The direction the reflectors face in the tip frame: their triangle's normal away from the tip
/// (the tip's z axis with fewer than three reflectors).
pub fn facing_axis(arm: &ArmModel) -> Vector3<f64> {
    let t = &arm.reflectors_mm;
    if t.len() < 3 {
        return Vector3::z();
    }
    let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let Some(n) = n.try_normalize(1e-12) else {
        return Vector3::z();
    };
    if n.dot(&(t[0] + t[1] + t[2])) < 0.0 {
        -n
    } else {
        n
    }
}

/// The columns the design works on and their scale: the parameters distances between the candidates
/// identify ([`crate::solver::identifiability::identifiable_at`], the calibration's analysis), each
/// scaled to unit RMS scatter over the candidates.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnScale {
    pub free: Vec<usize>,
    pub scale: Vec<f64>,
}

/// The reflector Jacobians of every candidate, the columns distances between the candidates identify
/// ([`crate::solver::identifiability::identifiable_at`], the calibration's analysis) scaled to unit
/// RMS scatter over the candidates: one `3·reflectors × p` matrix per candidate.
pub fn scaled_jacobians(arm: &ArmModel, configs: &[Vec<f64>]) -> Vec<DMatrix<f64>> {
    let scale = column_scale(arm, configs);
    jacobians_scaled(arm, configs, &scale)
}

/// [`ColumnScale`] over `configs`.
pub fn column_scale(arm: &ArmModel, configs: &[Vec<f64>]) -> ColumnScale {
    let free = crate::solver::identifiability::identifiable_at(arm, configs);
    let unit = ColumnScale {
        scale: vec![1.0; free.len()],
        free,
    };
    let jac = jacobians_scaled(arm, configs, &unit);
    let rows = 3 * arm.reflector_count();
    let n = jac.len().max(1) as f64;
    let mean = jac
        .iter()
        .fold(DMatrix::zeros(rows, unit.free.len()), |a, j| a + j)
        / n;
    let scale: Vec<f64> = (0..unit.free.len())
        .map(|c| {
            let ss: f64 = jac
                .iter()
                .map(|j| (j.column(c) - mean.column(c)).norm_squared())
                .sum();
            let rms = (ss / n).sqrt();
            if rms > 0.0 { 1.0 / rms } else { 0.0 }
        })
        .collect();
    ColumnScale {
        free: unit.free,
        scale,
    }
}

/// The reflector Jacobians of `configs`, the columns of `scale` scaled by it.
pub fn jacobians_scaled(
    arm: &ArmModel,
    configs: &[Vec<f64>],
    scale: &ColumnScale,
) -> Vec<DMatrix<f64>> {
    let rows = 3 * arm.reflector_count();
    configs
        .iter()
        .map(|q| {
            let j = arm.reflector_jacobians(q);
            DMatrix::from_fn(rows, scale.free.len(), |r, c| {
                j.jacobians[r / 3][(r % 3, scale.free[c])] * scale.scale[c]
            })
        })
        .collect()
}

/// `log det` of the scatter of `chosen` (indices into `jac`), regularised by `1e-9 · p`.
pub fn log_det(jac: &[DMatrix<f64>], chosen: &[usize]) -> f64 {
    let Some(first) = jac.first() else {
        return f64::NEG_INFINITY;
    };
    let p = first.ncols();
    let n = chosen.len().max(1) as f64;
    let mean = chosen
        .iter()
        .fold(DMatrix::zeros(first.nrows(), p), |a, &i| a + &jac[i])
        / n;
    let mut m = DMatrix::<f64>::identity(p, p) * 1e-9;
    for &i in chosen {
        let d = &jac[i] - &mean;
        m += d.transpose() * d;
    }
    m.cholesky().map_or(f64::NEG_INFINITY, |c| {
        2.0 * c.l().diagonal().map(f64::ln).sum()
    })
}

/// Greedy D-optimal choice of `n` of the candidates (module documentation, step 2): their indices in
/// the order chosen.
pub fn select(jac: &[DMatrix<f64>], n: usize) -> Vec<usize> {
    let Some(first) = jac.first() else {
        return Vec::new();
    };
    let (rows, p) = first.shape();
    let count = jac.len() as f64;
    let pool_mean = jac.iter().fold(DMatrix::zeros(rows, p), |a, j| a + j) / count;
    let start = (0..jac.len())
        .max_by(|&a, &b| {
            (&jac[a] - &pool_mean)
                .norm_squared()
                .total_cmp(&(&jac[b] - &pool_mean).norm_squared())
        })
        .unwrap_or(0);
    let mut chosen = vec![start];
    let mut taken = vec![false; jac.len()];
    taken[start] = true;
    let mut mean = jac[start].clone();
    let mut info = DMatrix::<f64>::identity(p, p) * 1e-9;
    while chosen.len() < n.min(jac.len()) {
        let Some(chol) = info.clone().cholesky() else {
            break;
        };
        let inverse = chol.inverse();
        let k = chosen.len() as f64;
        // Adding c: scatter += k/(k+1) · (J_c − J̄)ᵀ (J_c − J̄); the gain is log det(I + α D M⁻¹ Dᵀ).
        let alpha = k / (k + 1.0);
        let gain = |c: usize| -> f64 {
            let d = &jac[c] - &mean;
            let mut w = &d * &inverse * d.transpose() * alpha;
            for r in 0..rows {
                w[(r, r)] += 1.0;
            }
            w.cholesky().map_or(f64::NEG_INFINITY, |c| {
                2.0 * c.l().diagonal().map(f64::ln).sum()
            })
        };
        let best = (0..jac.len())
            .filter(|&c| !taken[c])
            .map(|c| (c, gain(c)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((c, _)) = best else { break };
        let d = &jac[c] - &mean;
        info += d.transpose() * &d * alpha;
        mean = (&mean * k + &jac[c]) / (k + 1.0);
        taken[c] = true;
        chosen.push(c);
    }
    chosen
}

/// The rows `u_cj,kᵀ (J_c,k − J_j,k)` of the distances between candidate `c` and each of `others`,
/// one per reflector k (`others` in order, reflectors within): what measuring `c` beside `others`
/// adds to the distance information. A zero row where two reflector positions coincide.
pub fn pair_rows(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    c: usize,
    others: &[usize],
) -> DMatrix<f64> {
    let p = jac[c].ncols();
    let reflectors = jac[c].nrows() / 3;
    let mut g = DMatrix::<f64>::zeros(others.len() * reflectors, p);
    for (r, (j, k)) in others
        .iter()
        .flat_map(|&j| (0..reflectors).map(move |k| (j, k)))
        .enumerate()
    {
        let v = points[c][k] - points[j][k];
        let Some(u) = v.try_normalize(1e-12) else {
            continue;
        };
        for col in 0..p {
            let mut acc = 0.0;
            for t in 0..3 {
                acc += u[t] * (jac[c][(3 * k + t, col)] - jac[j][(3 * k + t, col)]);
            }
            g[(r, col)] = acc;
        }
    }
    g
}

/// `P`, the information of the pairs a verification would measure: the mean of `GᵀG` over pairs of
/// candidates (every k-th pair, at most ~4000), `G` their [`pair_rows`].
pub fn pair_information(points: &[Vec<Vector3<f64>>], jac: &[DMatrix<f64>]) -> DMatrix<f64> {
    let p = jac.first().map_or(0, |j| j.ncols());
    let count = jac.len();
    let total = count * count.saturating_sub(1) / 2;
    let stride = total.div_ceil(4000).max(1);
    let mut info = DMatrix::<f64>::zeros(p, p);
    let mut sampled = 0usize;
    let mut pair = 0usize;
    for i in 0..count {
        for j in i + 1..count {
            if pair.is_multiple_of(stride) {
                let g = pair_rows(points, jac, i, &[j]);
                info += g.transpose() * &g;
                sampled += 1;
            }
            pair += 1;
        }
    }
    info / sampled.max(1) as f64
}

/// The I-criterion of the design `chosen`: `trace(M⁻¹ P)` with `M` the information of the distances
/// between its configurations (plus `1e-9 I`) and `P` = `pool_info` ([`pair_information`]); infinite
/// where `M` is singular. What [`select_by_distances`] and [`exchange::exchange`] lower.
pub fn i_criterion(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    pool_info: &DMatrix<f64>,
    chosen: &[usize],
) -> f64 {
    let p = pool_info.nrows();
    let mut info = DMatrix::<f64>::identity(p, p) * 1e-9;
    for (k, &c) in chosen.iter().enumerate() {
        let g = pair_rows(points, jac, c, &chosen[..k]);
        info += g.transpose() * &g;
    }
    info.cholesky()
        .map_or(f64::INFINITY, |c| (c.inverse() * pool_info).trace())
}

/// Greedy I-optimal choice on the exact distance information (module documentation, step 2): the
/// rows `u_ij,kᵀ (J_i,k − J_j,k)` ([`pair_rows`]) a candidate adds with every configuration chosen
/// so far lower `trace(M⁻¹ P)` by `trace((I + G M⁻¹ Gᵀ)⁻¹ G M⁻¹ P M⁻¹ Gᵀ)`. `points[c]` are
/// candidate c's model reflector positions, `jac[c]` its scaled Jacobian rows (3 per reflector),
/// `pool_info` is `P` ([`pair_information`]). Starts from `start` (the isotropic design's first
/// picks, or the configurations already measured).
pub fn select_by_distances(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    pool_info: &DMatrix<f64>,
    n: usize,
    start: &[usize],
) -> Vec<usize> {
    let Some(first) = jac.first() else {
        return Vec::new();
    };
    let p = first.ncols();
    let rows_with = |c: usize, chosen: &[usize]| pair_rows(points, jac, c, chosen);
    let mut chosen: Vec<usize> = start.iter().copied().take(n).collect();
    let mut taken = vec![false; jac.len()];
    let mut info = DMatrix::<f64>::identity(p, p) * 1e-9;
    for (k, &c) in chosen.iter().enumerate() {
        taken[c] = true;
        let g = rows_with(c, &chosen[..k]);
        info += g.transpose() * &g;
    }
    while chosen.len() < n.min(jac.len()) {
        let Some(chol) = info.clone().cholesky() else {
            break;
        };
        let inverse = chol.inverse();
        // I-optimality: the candidate that lowers trace(M⁻¹ P) most — the predicted variance of a
        // verification pair's distance error — by the Woodbury identity:
        // Δ = trace((I + G M⁻¹ Gᵀ)⁻¹ G M⁻¹ P M⁻¹ Gᵀ).
        let b = &inverse * pool_info * &inverse;
        let best = (0..jac.len())
            .filter(|&c| !taken[c])
            .map(|c| {
                let g = rows_with(c, &chosen);
                let mut w = &g * &inverse * g.transpose();
                for r in 0..w.nrows() {
                    w[(r, r)] += 1.0;
                }
                let gbg = &g * &b * g.transpose();
                let gain = w
                    .cholesky()
                    .map_or(f64::NEG_INFINITY, |c| c.solve(&gbg).trace());
                (c, gain)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((c, _)) = best else { break };
        let g = rows_with(c, &chosen);
        info += g.transpose() * &g;
        taken[c] = true;
        chosen.push(c);
    }
    chosen
}

/// Joint-space distance (rad; mm for a prismatic joint).
fn leg(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// A short visiting order of `configs` (module documentation, step 3): nearest neighbour from the
/// first, then 2-opt moves while they shorten the path.
pub fn order(configs: &[Vec<f64>]) -> Vec<usize> {
    let n = configs.len();
    if n < 3 {
        return (0..n).collect();
    }
    let mut path = vec![0];
    let mut left: Vec<usize> = (1..n).collect();
    while !left.is_empty() {
        let last = &configs[*path.last().unwrap_or(&0)];
        let (k, _) = left
            .iter()
            .enumerate()
            .map(|(k, &c)| (k, leg(last, &configs[c])))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        path.push(left.swap_remove(k));
    }
    let d = |path: &[usize], a: usize, b: usize| leg(&configs[path[a]], &configs[path[b]]);
    let mut improved = true;
    let mut rounds = 0;
    while improved && rounds < 100 {
        improved = false;
        rounds += 1;
        for i in 0..n - 2 {
            for j in i + 2..n - 1 {
                let now = d(&path, i, i + 1) + d(&path, j, j + 1);
                let swapped = d(&path, i, j) + d(&path, i + 1, j + 1);
                if swapped + 1e-12 < now {
                    path[i + 1..=j].reverse();
                    improved = true;
                }
            }
        }
    }
    path
}

/// Whether the straight joint-space motion of `side` from `a` to `b` collides (checked every 2°, or
/// 5 mm for a prismatic joint; the other arm resting).
fn leg_collides(
    side: Side,
    a: &[f64],
    b: &[f64],
    rest: &Resting,
    world: &CollisionWorld,
    options: &PlanOptions,
) -> bool {
    let clearance_mm = options.clearance_mm;
    let largest = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let steps = (largest / 2f64.to_radians()).ceil().max(1.0) as usize;
    (1..steps).any(|s| {
        let t = s as f64 / steps as f64;
        let q: Vec<f64> = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
        let (ql, qr) = rest.posed(side, &q);
        let (ql, qr) = (&ql, &qr);
        world.in_collision(ql, qr, clearance_mm)
            || world.in_keep_out(ql, qr, &options.keep_out, clearance_mm)
    })
}

/// The path's length and the legs on which the straight joint-space motion collides.
fn check_path(
    side: Side,
    configs: &[Vec<f64>],
    rest: &Resting,
    world: &CollisionWorld,
    options: &PlanOptions,
) -> (f64, Vec<usize>) {
    let mut length = 0.0;
    let mut colliding = Vec::new();
    for (k, pair) in configs.windows(2).enumerate() {
        length += leg(&pair[0], &pair[1]);
        if leg_collides(side, &pair[0], &pair[1], rest, world, options) {
            colliding.push(k);
        }
    }
    (length, colliding)
}

/// Re-route each colliding leg through a via point: of the arm's home pose and the candidates
/// (all collision-free), the `VIA_CANDIDATES` shortest detours `a → v → b` are tried in order and
/// the first whose two straight motions are both clear is taken. The via points, the legs no via
/// point clears, and the path's new length.
#[allow(clippy::too_many_arguments)]
pub fn reroute(
    side: Side,
    configs: &[Vec<f64>],
    colliding: &[usize],
    pool: &[Vec<f64>],
    rest: &Resting,
    world: &CollisionWorld,
    options: &PlanOptions,
    path_length: f64,
) -> (Vec<Via>, Vec<usize>, f64) {
    let (mut vias, mut left, mut length) = (Vec::new(), Vec::new(), path_length);
    for &k in colliding {
        let (a, b) = (&configs[k], &configs[k + 1]);
        let mut tries: Vec<(f64, &Vec<f64>)> = std::iter::once(&rest.q[side])
            .chain(pool)
            .map(|v| (leg(a, v) + leg(v, b), v))
            .collect();
        crate::sort::sort_by(&mut tries, |x, y| x.0.total_cmp(&y.0));
        let found = tries.iter().take(VIA_CANDIDATES).find(|(_, v)| {
            !leg_collides(side, a, v, rest, world, options)
                && !leg_collides(side, v, b, rest, world, options)
        });
        match found {
            Some((detour, v)) => {
                length += detour - leg(a, b);
                vias.push(Via {
                    leg: k,
                    q: (*v).clone(),
                });
            }
            None => left.push(k),
        }
    }
    (vias, left, length)
}

/// Plan both arms of `robot` with the reflectors `reflectors_mm` (tip frame).
pub fn plan(
    robot: &RobotDescription,
    reflectors_mm: &[Vector3<f64>],
    options: &PlanOptions,
) -> Result<PerSide<ArmPlan>, PlanError> {
    check_options(options)?;
    let nominal = robot.nominal_model(reflectors_mm.to_vec());
    let world = CollisionWorld::new(robot);
    PerSide::try_from_fn(|side| plan_arm_with(robot, nominal.arm(side), &world, side, options))
}

/// Plan one arm (the other resting at its home pose): what [`plan`] does for each.
pub fn plan_arm(
    robot: &RobotDescription,
    reflectors_mm: &[Vector3<f64>],
    options: &PlanOptions,
    side: Side,
) -> Result<ArmPlan, PlanError> {
    check_options(options)?;
    let nominal = robot.nominal_model(reflectors_mm.to_vec());
    let world = CollisionWorld::new(robot);
    plan_arm_with(robot, nominal.arm(side), &world, side, options)
}

fn check_options(options: &PlanOptions) -> Result<(), PlanError> {
    if let Some(t) = options.target
        && !(t.is_finite() && t > 1.0)
    {
        return Err(PlanError::Options(format!(
            "target {t}: expected a multiple of the noise floor above 1"
        )));
    }
    if options.target.is_none() && (options.per_arm < 2 || options.candidates < options.per_arm) {
        return Err(PlanError::Options(format!(
            "{} configurations per arm from {} candidates: expected at least 2, and at least as many \
             candidates",
            options.per_arm, options.candidates
        )));
    }
    Ok(())
}

/// What the designs of one arm share: the pool (candidates, then the configurations already
/// measured), its scaled Jacobians and points, the region's information, the design's start.
struct Pool<'a> {
    points: &'a [Vec<Vector3<f64>>],
    jac: &'a [DMatrix<f64>],
    info: &'a DMatrix<f64>,
    start: &'a [usize],
    fixed: usize,
    drawn: usize,
    existing: usize,
}

impl Pool<'_> {
    /// Greedy, then exchange, for `n` new configurations.
    fn design(&self, n: usize) -> exchange::Exchange {
        let greedy = select_by_distances(
            self.points,
            self.jac,
            self.info,
            self.existing + n,
            self.start,
        );
        exchange::exchange(
            self.points,
            self.jac,
            self.info,
            &greedy,
            self.fixed,
            self.drawn,
        )
    }
}

/// The numbers of configurations [`target_search`] tries first.
const TARGET_LADDER: [usize; 13] = [6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 80, 100];

type Predicted = Option<RegionPrediction>;

/// The smallest N (up to the candidates' number) whose design's predicted default-method mean is at
/// most `target`: up [`TARGET_LADDER`], then by bisection below the first N that reaches it. Returns
/// that N (the largest tried where none does), its design and prediction, and every N tried.
fn target_search(
    pool: &Pool,
    target: f64,
    predict: &dyn Fn(&[usize]) -> Predicted,
) -> (
    usize,
    exchange::Exchange,
    Predicted,
    Vec<(usize, Predicted)>,
) {
    let reaches = |p: &Predicted| p.as_ref().is_some_and(|p| p.default_method.mean <= target);
    let mut curve = Vec::new();
    let tried = |n: usize, curve: &mut Vec<(usize, Predicted)>| {
        let ex = pool.design(n);
        let p = predict(&ex.chosen);
        curve.push((n, p.clone()));
        (ex, p)
    };
    let ladder: Vec<usize> = TARGET_LADDER
        .iter()
        .copied()
        .filter(|&n| n <= pool.drawn)
        .chain((!TARGET_LADDER.contains(&pool.drawn)).then_some(pool.drawn))
        .filter(|&n| n >= 2)
        .collect();
    let mut lo = 1usize;
    let mut best = None;
    for &n in &ladder {
        let (ex, p) = tried(n, &mut curve);
        let ok = reaches(&p);
        best = Some((n, ex, p));
        if ok {
            break;
        }
        lo = n;
    }
    let (mut hi, mut ex, mut p) = best.unwrap_or_else(|| {
        let ex = pool.design(2);
        (2, ex, None)
    });
    if reaches(&p) {
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            let (e, q) = tried(mid, &mut curve);
            if reaches(&q) {
                (hi, ex, p) = (mid, e, q);
            } else {
                lo = mid;
            }
        }
    }
    crate::sort::sort_by(&mut curve, |a, b| a.0.cmp(&b.0));
    (hi, ex, p, curve)
}

fn plan_arm_with(
    robot: &RobotDescription,
    arm: &ArmModel,
    world: &CollisionWorld,
    side: Side,
    options: &PlanOptions,
) -> Result<ArmPlan, PlanError> {
    let rest = Resting::of(robot);
    let (mut pool, attempts) = candidates(robot, arm, side, world, options)?;
    let drawn = pool.len();
    // Configurations already measured join the pool and start the design.
    let existing = &options.existing[side];
    if let Some(q) = existing.iter().find(|q| q.len() != arm.joint_count()) {
        return Err(PlanError::Options(format!(
            "{side} arm: an existing configuration has {} joint values, the arm {}",
            q.len(),
            arm.joint_count()
        )));
    }
    pool.extend(existing.iter().cloned());
    let scale = column_scale(arm, &pool);
    let jac = jacobians_scaled(arm, &pool, &scale);
    let points: Vec<Vec<Vector3<f64>>> =
        pool.iter().map(|q| arm.reflector_fk(q).points_mm).collect();
    // The isotropic design's first two picks start the exact one (a single configuration has no
    // distance yet), or the existing configurations.
    let start: Vec<usize> = if existing.is_empty() {
        select(&jac, 2)
    } else {
        (drawn..pool.len()).collect()
    };
    // The verification pairs the criterion weighs: the region's, over robots with errors.
    let region_qs = region::samples(robot, arm, side, world, options)?;
    let pool_info =
        region::robust_information(arm, &region_qs, &scale, options.robust_draws, options.seed);
    // The configurations already measured stay (they lead the design); the others are exchanged.
    let fixed = if existing.is_empty() { 0 } else { start.len() };
    let shared = Pool {
        points: &points,
        jac: &jac,
        info: &pool_info,
        start: &start,
        fixed,
        drawn,
        existing: existing.len(),
    };
    let sigma_mm = region::point_sigma_mm(robot, side, options);
    let predict = |design: &[usize]| {
        let qs: Vec<Vec<f64>> = design.iter().map(|&i| pool[i].clone()).collect();
        region::predict(
            arm,
            &qs,
            &region_qs,
            sigma_mm,
            options.prediction_draws,
            options.seed,
        )
    };
    let (per_arm, exchanged, prediction, curve) = match options.target {
        None => {
            let ex = shared.design(options.per_arm);
            let p = predict(&ex.chosen);
            (options.per_arm, ex, p, Vec::new())
        }
        Some(target) => target_search(&shared, target, &predict),
    };
    let design = exchanged.chosen.clone();
    let chosen: Vec<usize> = design.iter().copied().filter(|&i| i < drawn).collect();
    let random: Vec<usize> = (0..per_arm.min(drawn)).collect();
    let configs: Vec<Vec<f64>> = chosen.iter().map(|&i| pool[i].clone()).collect();
    let path = order(&configs);
    let configs: Vec<Vec<f64>> = path.iter().map(|&k| configs[k].clone()).collect();
    let (straight_length, colliding) = check_path(side, &configs, &rest, world, options);
    let (vias, colliding_legs, path_length) = reroute(
        side,
        &configs,
        &colliding,
        &pool[..drawn],
        &rest,
        world,
        options,
        straight_length,
    );
    let unchosen: Vec<usize> = (0..drawn).filter(|i| !chosen.contains(i)).collect();
    let stride = unchosen.len().div_ceil(SAMPLE).max(1);
    let sample_indices: Vec<usize> = unchosen.iter().copied().step_by(stride).collect();
    let sample = sample_indices.iter().map(|&i| pool[i].clone()).collect();
    let bound = bound::relaxed_bound(
        &points,
        &jac,
        drawn,
        &start[..fixed],
        per_arm,
        &design,
        &sample_indices,
    );
    Ok(ArmPlan {
        sample,
        criterion_greedy: exchanged.before,
        criterion: exchanged.after,
        swaps: exchanged.swaps,
        bound,
        configs,
        candidates: drawn,
        attempts,
        log_det: log_det(&jac, &chosen),
        log_det_random: log_det(&jac, &random),
        path_length,
        vias,
        colliding_legs,
        region_count: region_qs.len(),
        prediction,
        curve,
    })
}

/// A made-up pool for the selection's tests: `count` candidates of `reflectors` positions (mm,
/// within a 1 m cube) and `params` columns of Jacobian rows drawn at random.
#[cfg(test)]
pub(crate) fn synthetic_pool(
    count: usize,
    reflectors: usize,
    params: usize,
    seed: u64,
) -> (Vec<Vec<Vector3<f64>>>, Vec<DMatrix<f64>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let points = (0..count)
        .map(|_| {
            (0..reflectors)
                .map(|_| Vector3::from_fn(|_, _| rng.random_range(-500.0..500.0)))
                .collect()
        })
        .collect();
    let jac = (0..count)
        .map(|_| DMatrix::from_fn(3 * reflectors, params, |_, _| rng.random_range(-1.0..1.0)))
        .collect();
    (points, jac)
}
