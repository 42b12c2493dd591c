//! The pair sums behind every distance covariance, one pass per arm and set of free parameters, kept
//! per reflector and weighed afterwards.
//!
//! For reflector k and a pair i < j of the configurations used, the row `r = −(J_i − J_j)ᵀ û` (û the
//! model's unit direction from j to i, J the free columns of the reflector's Jacobian) and the
//! distance error `e = |m_i − m_j| − |p_i − p_j|`. Per reflector:
//!
//! - `JᵀJ = Σ r rᵀ` over the pairs,
//! - the sandwich's middle `Σ_i A_i A_iᵀ` with `A_i = Σ_{j≠i} r_ij d_ijᵀ`, d the unit direction from j to
//!   i — the measured one (the fit's sandwich) and the model's (the design's, [`Directions`]); as
//!   `r_ji = r_ij` and `d_ji = −d_ij`, each pair adds `r dᵀ` to `A_i` and subtracts it from `A_j`,
//! - `F_k = Σ e²` and its gradient `2 Σ e r`, and the row count.
//!
//! A weighting of the reflectors is then a weighted sum of these: `JᵀJ = Σ w_k JᵀJ_k`, the middle
//! `Σ w_k² B_k` (the uncertainty's `Weighting`: the minimax's multipliers need the unweighted F_k and
//! gradients first, and no second pass). A pair whose measured or model points coincide has no row.
//!
//! Work: regrouped by configuration (`one_reflector`), three matrix products of 3n × 3n by 3n × p per
//! reflector instead of a p × p update per pair (n ≤ [`MAX_CONFIGURATIONS`]); the reflectors
//! side by side. The matrices are made symmetric to the bit (upper triangle mirrored).

use crate::kinematics::{ArmJacobians, ArmModel};
use crate::par::prelude::*;
use nalgebra::{DMatrix, DVector, Vector3};

/// At most this many configurations per arm enter the sums (every k-th beyond; the pair sums grow as
/// n², and 80 keep both arms at ~3 ms).
pub const MAX_CONFIGURATIONS: usize = 80;

/// The configurations of `n_all` that enter the sums: all up to [`MAX_CONFIGURATIONS`], else every
/// k-th.
pub(super) fn used_configurations(n_all: usize) -> Vec<usize> {
    let stride = n_all.div_ceil(MAX_CONFIGURATIONS).max(1);
    (0..n_all).step_by(stride).collect()
}

/// Which unit directions the sandwich's middle uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Directions {
    /// The measured points' (the fit's covariance with its own data).
    Measured,
    /// The model's (the covariance a design predicts: the model's points stand for the measured ones).
    Model,
}

/// One reflector's sums (module documentation); matrices over the free parameters.
#[derive(Clone, Debug)]
struct ReflectorSums {
    jtj: DMatrix<f64>,
    middle_measured: DMatrix<f64>,
    middle_model: DMatrix<f64>,
    f: f64,
    g: DVector<f64>,
    rows: usize,
}

/// Weighted sums over the reflectors, as a covariance takes them.
pub(super) struct Sums {
    pub jtj: DMatrix<f64>,
    pub meat: DMatrix<f64>,
    /// Σ r² and the row count over the reflectors of non-zero weight.
    pub cost: f64,
    pub rows: usize,
    /// Per reflector (every one, whatever its weight): F_k = Σ r² and its gradient `2 Σ r ∂r/∂x`
    /// over the free parameters.
    pub f_k: Vec<f64>,
    pub g_k: Vec<DVector<f64>>,
}

/// One arm's pair sums at one parameter vector, for one set of free parameters and configurations
/// (module documentation): what the weak-parameter analysis and the method's uncertainty share.
#[derive(Clone, Debug)]
pub struct PairSums {
    reflectors: Vec<ReflectorSums>,
    /// What they were computed for: the arm's parameter vector, the free parameters and the number of
    /// configurations given (before the stride of [`MAX_CONFIGURATIONS`]).
    params: DVector<f64>,
    free: Vec<usize>,
    configurations: usize,
    /// A hash of the joint values and measured points of the configurations used.
    data: u64,
    /// Configurations in the sums.
    pub(super) used: usize,
}

impl PairSums {
    /// The sums of `arm` at the configurations `qs` (every k-th beyond [`MAX_CONFIGURATIONS`])
    /// against `measured` (one point per reflector each), over the parameters `free`.
    pub fn new(
        arm: &ArmModel,
        qs: &[Vec<f64>],
        measured: &[Vec<Vector3<f64>>],
        free: &[usize],
    ) -> Self {
        let n_all = qs.len().min(measured.len());
        let used = used_configurations(n_all);
        let jac: Vec<ArmJacobians> = used
            .par_iter()
            .map(|&i| arm.reflector_jacobians(&qs[i]))
            .collect();
        let points: Vec<&Vec<Vector3<f64>>> = used.iter().map(|&i| &measured[i]).collect();
        let mut sums = Self::from_jacobians(arm, &jac, &points, free, n_all);
        sums.data = data_hash(qs, measured);
        sums
    }

    /// [`PairSums::new`] of Jacobians already computed at the configurations used (`n_all`: how many
    /// the stride chose them from).
    pub(super) fn from_jacobians(
        arm: &ArmModel,
        jac: &[ArmJacobians],
        measured: &[&Vec<Vector3<f64>>],
        free: &[usize],
        n_all: usize,
    ) -> Self {
        Self {
            reflectors: reflector_sums(jac, measured, free, arm.reflector_count()),
            params: arm.to_vector(),
            free: free.to_vec(),
            configurations: n_all,
            used: jac.len().min(measured.len()),
            data: 0,
        }
    }

    /// Whether these are the sums [`PairSums::new`] would compute for `arm`, `qs`, `measured` and
    /// `free` (the same parameters, free set and data, to the bit).
    pub fn matches(
        &self,
        arm: &ArmModel,
        qs: &[Vec<f64>],
        measured: &[Vec<Vector3<f64>>],
        free: &[usize],
    ) -> bool {
        self.free == free
            && self.configurations == qs.len().min(measured.len())
            && self.params == arm.to_vector()
            && self.data == data_hash(qs, measured)
    }

    /// The free parameters (indices into the arm's parameter vector).
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// The mean Gram matrix of the pair Jacobian's rows over every reflector, `Σ_k JᵀJ_k / rows`, over
    /// the free parameters (in [`PairSums::free`]'s order); `None` without rows.
    pub fn mean_gram(&self) -> Option<DMatrix<f64>> {
        let p = self.free.len();
        let rows: usize = self.reflectors.iter().map(|r| r.rows).sum();
        if rows == 0 {
            return None;
        }
        let mut gram = DMatrix::zeros(p, p);
        for r in &self.reflectors {
            gram += &r.jtj;
        }
        Some(gram / rows as f64)
    }

    /// The point noise per axis the residuals show, mm: `Σ e² / (2 (rows − p))` over every reflector's
    /// pairs (as the least-squares uncertainty estimates it); `None` without residual degrees of
    /// freedom or with a zero or broken noise.
    pub fn point_sigma_mm(&self) -> Option<f64> {
        let (cost, rows) = self
            .reflectors
            .iter()
            .fold((0.0, 0usize), |(c, n), r| (c + r.f, n + r.rows));
        let dof = rows.checked_sub(self.free.len()).filter(|&d| d > 0)?;
        let noise = (cost / (2.0 * dof as f64)).sqrt();
        (noise.is_finite() && noise > 0.0).then_some(noise)
    }

    /// Configurations given, and how many entered the sums.
    pub(super) fn configurations(&self) -> (usize, usize) {
        (self.configurations, self.used)
    }

    /// The reflectors' sums weighed by `weights` (one per reflector; `JᵀJ` by w, the middle by w²).
    pub(super) fn weighed(&self, weights: &[f64], directions: Directions) -> Sums {
        let p = self.free.len();
        let mut sums = Sums {
            jtj: DMatrix::zeros(p, p),
            meat: DMatrix::zeros(p, p),
            cost: 0.0,
            rows: 0,
            f_k: self.reflectors.iter().map(|r| r.f).collect(),
            g_k: self.reflectors.iter().map(|r| r.g.clone()).collect(),
        };
        for (r, &w) in self.reflectors.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            let middle = match directions {
                Directions::Measured => &r.middle_measured,
                Directions::Model => &r.middle_model,
            };
            sums.jtj += &r.jtj * w;
            sums.meat += middle * (w * w);
            sums.cost += r.f;
            sums.rows += r.rows;
        }
        sums
    }
}

/// A hash of the bits of the joint values and measured points of the configurations [`PairSums::new`]
/// uses of `qs` and `measured`.
fn data_hash(qs: &[Vec<f64>], measured: &[Vec<Vector3<f64>>]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for i in used_configurations(qs.len().min(measured.len())) {
        qs[i].iter().for_each(|v| v.to_bits().hash(&mut h));
        measured[i]
            .iter()
            .flat_map(|p| p.iter())
            .for_each(|v| v.to_bits().hash(&mut h));
    }
    h.finish()
}

/// Every reflector's sums over the pairs of `jac` (module documentation), the reflectors side by
/// side.
fn reflector_sums(
    jac: &[ArmJacobians],
    measured: &[&Vec<Vector3<f64>>],
    free: &[usize],
    reflectors: usize,
) -> Vec<ReflectorSums> {
    let n = jac.len().min(measured.len());
    (0..reflectors)
        .into_par_iter()
        .map(|k| one_reflector(&jac[..n], &measured[..n], free, k))
        .collect()
}

/// Reflector `k`'s sums, regrouped by configuration (module documentation): with `J` the 3n × p
/// stack of the configurations' free Jacobian rows, `JᵀJ = Jᵀ L J` for the block Laplacian `L`
/// (block (i, j) `−û ûᵀ`, block (i, i) the sum of its row's `û ûᵀ`), the `A_i` of the model's
/// directions are the blocks of `−(L J)ᵀ`, and those of the measured directions the blocks of
/// `Jᵀ M` (block (i, j) `û dᵀ`, block (i, i) minus its row's sum); the gradient is
/// `−2 Σ_i J_iᵀ Σ_j e_ij û_ij`. Three matrix products instead of a p × p update per pair.
fn one_reflector(
    jac: &[ArmJacobians],
    measured: &[&Vec<Vector3<f64>>],
    free: &[usize],
    k: usize,
) -> ReflectorSums {
    let (n, p) = (jac.len(), free.len());
    let mut laplacian = DMatrix::<f64>::zeros(3 * n, 3 * n);
    let mut across = DMatrix::<f64>::zeros(3 * n, 3 * n);
    // Σ_j e_ij û_ij per configuration.
    let mut pull = vec![Vector3::<f64>::zeros(); n];
    let (mut f, mut rows) = (0.0, 0usize);
    for i in 0..n {
        for j in i + 1..n {
            let v = jac[i].fk.points_mm[k] - jac[j].fk.points_mm[k];
            let m = measured[i][k] - measured[j][k];
            let (dist, measured_dist) = (v.norm(), m.norm());
            if !(dist > 0.0 && measured_dist > 0.0) {
                continue;
            }
            let u = v / dist;
            let d = m / measured_dist;
            let e = measured_dist - dist;
            f += e * e;
            rows += 1;
            pull[i] += u * e;
            pull[j] -= u * e;
            for a in 0..3 {
                for b in 0..3 {
                    let (uu, ud) = (u[a] * u[b], u[a] * d[b]);
                    laplacian[(3 * i + a, 3 * j + b)] = -uu;
                    laplacian[(3 * j + a, 3 * i + b)] = -uu;
                    laplacian[(3 * i + a, 3 * i + b)] += uu;
                    laplacian[(3 * j + a, 3 * j + b)] += uu;
                    across[(3 * i + a, 3 * j + b)] = ud;
                    across[(3 * j + a, 3 * i + b)] = ud;
                    across[(3 * i + a, 3 * i + b)] -= ud;
                    across[(3 * j + a, 3 * j + b)] -= ud;
                }
            }
        }
    }
    // Jᵀ (p × 3n): column 3i + a is row a of configuration i's free Jacobian.
    let jt = DMatrix::<f64>::from_fn(p, 3 * n, |c, col| {
        jac[col / 3].jacobians[k][(col % 3, free[c])]
    });
    let lj = &laplacian * jt.transpose();
    let a_measured = &jt * &across;
    let symmetric = |mut m: DMatrix<f64>| {
        m.fill_lower_triangle_with_upper_triangle();
        m
    };
    let mut g = DVector::<f64>::zeros(p);
    for (i, t) in pull.iter().enumerate() {
        g.gemv(-2.0, &jt.columns(3 * i, 3), t, 1.0);
    }
    ReflectorSums {
        jtj: symmetric(&jt * &lj),
        middle_measured: symmetric(&a_measured * a_measured.transpose()),
        middle_model: symmetric(lj.transpose() * &lj),
        f,
        g,
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The regrouped sums equal the rows' definition, summed pair by pair (both directions of every
    /// pair in the middle), on a three-reflector arm at random configurations.
    #[test]
    fn the_sums_are_the_rows_definition() {
        use rand::{Rng, SeedableRng};
        let arm = ArmModel::nominal_irb14000(vec![
            Vector3::new(40.0, 0.0, 60.0),
            Vector3::new(-20.0, 35.0, 60.0),
            Vector3::new(-20.0, -35.0, 60.0),
        ]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let limits = arm.joint_limits_rad();
        let qs: Vec<Vec<f64>> = (0..23)
            .map(|_| {
                limits
                    .iter()
                    .map(|&(lo, hi)| rng.random_range(lo..hi))
                    .collect()
            })
            .collect();
        let measured: Vec<Vec<Vector3<f64>>> = qs
            .iter()
            .map(|q| {
                arm.reflector_fk(q)
                    .points_mm
                    .iter()
                    .map(|p| p + Vector3::new(rng.random(), rng.random(), rng.random()) * 0.05)
                    .collect()
            })
            .collect();
        let free: Vec<usize> = (0..arm.param_count()).step_by(2).collect();
        let sums = PairSums::new(&arm, &qs, &measured, &free);
        let jac: Vec<ArmJacobians> = qs.iter().map(|q| arm.reflector_jacobians(q)).collect();
        let p = free.len();
        for k in 0..3 {
            let (mut jtj, mut mid_m, mut mid_p) = (
                DMatrix::<f64>::zeros(p, p),
                DMatrix::<f64>::zeros(p, p),
                DMatrix::<f64>::zeros(p, p),
            );
            let (mut f, mut g) = (0.0, DVector::<f64>::zeros(p));
            for i in 0..qs.len() {
                let (mut a_m, mut a_p) = (DMatrix::<f64>::zeros(p, 3), DMatrix::<f64>::zeros(p, 3));
                for j in 0..qs.len() {
                    if j == i {
                        continue;
                    }
                    let v = jac[i].fk.points_mm[k] - jac[j].fk.points_mm[k];
                    let m = measured[i][k] - measured[j][k];
                    let u = v / v.norm();
                    let r = DVector::from_fn(p, |c, _| {
                        -(jac[i].jacobians[k].column(free[c]) - jac[j].jacobians[k].column(free[c]))
                            .dot(&u)
                    });
                    a_m += &r * (m / m.norm()).transpose();
                    a_p += &r * u.transpose();
                    if j > i {
                        jtj += &r * r.transpose();
                        let e = m.norm() - v.norm();
                        f += e * e;
                        g += &r * (2.0 * e);
                    }
                }
                mid_m += &a_m * a_m.transpose();
                mid_p += &a_p * a_p.transpose();
            }
            let mut w = vec![0.0; 3];
            w[k] = 1.0;
            let measured_sums = sums.weighed(&w, Directions::Measured);
            let model_sums = sums.weighed(&w, Directions::Model);
            let close = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b).amax() <= 1e-9 * b.amax();
            assert!(close(&measured_sums.jtj, &jtj), "JᵀJ of reflector {k}");
            assert!(close(&measured_sums.meat, &mid_m), "measured middle of {k}");
            assert!(close(&model_sums.meat, &mid_p), "model middle of {k}");
            assert!((measured_sums.f_k[k] - f).abs() <= 1e-9 * f);
            assert!((&measured_sums.g_k[k] - &g).amax() <= 1e-9 * g.amax());
            assert_eq!(measured_sums.rows, qs.len() * (qs.len() - 1) / 2);
            assert_eq!(measured_sums.jtj, measured_sums.jtj.transpose());
            assert_eq!(model_sums.meat, model_sums.meat.transpose());
        }
    }
}
