//! Step 1 (paper §2.6): the geometric parameters and reflector coordinates of one arm from the
//! distances between the same reflector in every pair of configurations.
//!
//! Δd_ij,k = |m_i,k − m_j,k| − |p_i,k(x) − p_j,k(x)| (measured minus model), F_k = Σ_{i<j} Δd²,
//! ∇F_k = −2 Σ_{i<j} Δd u_ijᵀ (J_i,k − J_j,k) with u_ij the unit model direction (eq. 34, exact distances).
//! The pair sum is regrouped per configuration, ∇F_k = −2 Σ_i J_i,kᵀ w_i,k with
//! w_i,k = Σ_{j≠i} Δd_ij,k u_ij,k, so the Jacobians are computed once per configuration and iterate and
//! no pair Jacobian is ever formed. The pair pass itself (distances, Σ Δd², the weights) is `pairs`:
//! the measured distances are kept up to `pairs::KEPT_DISTANCE_PAIRS` pairs per reflector, recomputed beyond.

use super::problem::{Eval, LeastSquaresSystem, MinimaxProblem, StageParams};
use crate::kinematics::{ArmJacobians, ArmModel, ReflectorFk, reflector_pairs};
use crate::par::prelude::*;
use nalgebra::{DMatrix, DVector, Vector3};
use pairs::{Plan, Points};

pub(super) mod pairs;

/// Side pairs of the reflector triangle, in the order of constraints (14): ab, bc, ca (three
/// reflectors; [`reflector_pairs`] for any number).
pub const SIDES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

/// Step-1 problem of one arm.
pub struct ArmProblem {
    qs: Vec<Vec<f64>>,
    /// Measured (tracker-frame) points per reflector, mm.
    measured: Vec<Points>,
    /// Their pairwise distances, kept up to [`pairs::KEPT_DISTANCE_PAIRS`] pairs per reflector;
    /// recomputed per pass beyond.
    kept_distances: Option<Vec<Vec<f64>>>,
    n_pairs: usize,
    /// How the pair passes are cut ([`pairs::Plan::for_pairs`]).
    plan: Plan,
    /// The start model (its form and chain; its parameters are `x0`).
    start: ArmModel,
    x0: DVector<f64>,
    /// Index of the first reflector coordinate in x.
    reflector_offset: usize,
    free: Vec<usize>,
    /// x = x0 + scatter(scale ∘ y).
    scale: DVector<f64>,
    /// The reflector pairs of the distance constraints ([`reflector_pairs`]: ab, bc, ca for three).
    sides: Vec<(usize, usize)>,
    /// Mean measured reflector-to-reflector distances of `sides`, mm.
    mean_side_mm: Vec<f64>,
    /// Allowed deviation δ of the model triangle's sides from the measured means, mm (ε = δ²).
    side_tolerance_mm: f64,
    /// The reflectors whose distance errors enter the normal equations ([`MinimaxProblem::least_squares`]):
    /// all, or one for the single-reflector method of ref. [26].
    reflectors: Vec<bool>,
}

impl ArmProblem {
    /// `measured` are tracker-frame reflector positions, one per reflector of `start` per
    /// configuration.
    pub fn new(
        qs: Vec<Vec<f64>>,
        measured: &[Vec<Vector3<f64>>],
        start: &ArmModel,
        free: Vec<usize>,
        scale: DVector<f64>,
        side_tolerance_mm: f64,
    ) -> Self {
        assert_eq!(qs.len(), measured.len());
        assert_eq!(free.len(), scale.len());
        let n = qs.len();
        let n_pairs = n * n.saturating_sub(1) / 2;
        let reflectors = start.reflector_count();
        let measured_points: Vec<Points> = (0..reflectors)
            .map(|k| Points::from_fn(n, |i| measured[i][k]))
            .collect();
        let sides = reflector_pairs(reflectors);
        let mean_side_mm = sides
            .iter()
            .map(|&(a, b)| {
                measured.iter().map(|m| (m[a] - m[b]).norm()).sum::<f64>() / n.max(1) as f64
            })
            .collect();
        Self {
            qs,
            kept_distances: pairs::kept_triangle_distances(&measured_points),
            measured: measured_points,
            n_pairs,
            plan: Plan::for_pairs(n_pairs),
            start: start.clone(),
            x0: start.to_vector(),
            reflector_offset: start.reflector_offset(),
            free,
            scale,
            sides,
            mean_side_mm,
            side_tolerance_mm,
            reflectors: vec![true; reflectors],
        }
    }

    /// The same problem whose normal equations ([`MinimaxProblem::least_squares`]) sum the distance
    /// errors of the reflectors in `reflectors` only (the minimax objectives stay those of all three).
    pub fn with_reflectors(mut self, reflectors: Vec<bool>) -> Self {
        debug_assert_eq!(reflectors.len(), self.measured.len());
        self.reflectors = reflectors;
        self
    }

    /// The same problem (data, start point, constraints) with another set of free parameters and their
    /// scales — no recomputation of the measured distances.
    pub fn with_free(mut self, free: Vec<usize>, scale: DVector<f64>) -> Self {
        assert_eq!(free.len(), scale.len());
        self.free = free;
        self.scale = scale;
        self
    }

    /// Number of reflectors (objectives).
    pub fn reflector_count(&self) -> usize {
        self.measured.len()
    }

    pub fn free(&self) -> &[usize] {
        &self.free
    }
    /// Number of parameters of the arm (free and fixed).
    pub fn param_count(&self) -> usize {
        self.x0.len()
    }

    /// Full parameter vector at scaled point y.
    pub fn x_of(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut x = self.x0.clone();
        for (c, &k) in self.free.iter().enumerate() {
            x[k] += self.scale[c] * y[c];
        }
        x
    }

    pub fn model_at(&self, y: &DVector<f64>) -> ArmModel {
        self.start.with_vector(&self.x_of(y))
    }

    fn fk_all(&self, model: &ArmModel) -> Vec<ReflectorFk> {
        self.qs.par_iter().map(|q| model.reflector_fk(q)).collect()
    }

    fn jac_all(&self, model: &ArmModel) -> Vec<ArmJacobians> {
        self.qs
            .par_iter()
            .map(|q| model.reflector_jacobians(q))
            .collect()
    }

    /// Pair passes in blocks and lanes whatever the size (tests of the blocked path on small data).
    #[cfg(test)]
    fn blocked(mut self) -> Self {
        self.plan = Plan::Blocked;
        self
    }

    fn constraints(&self, x: &DVector<f64>, with_grad: bool) -> (Vec<f64>, Vec<DVector<f64>>) {
        let off = self.reflector_offset;
        let t = |r: usize| x.fixed_rows::<3>(off + 3 * r).into_owned();
        let eps = self.side_tolerance_mm * self.side_tolerance_mm;
        let mut cons = Vec::with_capacity(self.sides.len());
        let mut grads = Vec::new();
        for (l, &(a, b)) in self.sides.iter().enumerate() {
            let v = t(a) - t(b);
            let len = v.norm();
            let dev = len - self.mean_side_mm[l];
            // c_l = (t_l² − ε)/ε ≤ 0: eq. (15), normalised so that its scale is one.
            cons.push((dev * dev - eps) / eps);
            if with_grad {
                let mut gx = DVector::zeros(x.len());
                if len > 0.0 {
                    let dl = v / len * (2.0 * dev / eps);
                    for c in 0..3 {
                        gx[off + 3 * a + c] += dl[c];
                        gx[off + 3 * b + c] -= dl[c];
                    }
                }
                grads.push(self.restrict(&gx));
            }
        }
        (cons, grads)
    }

    /// Gradient with respect to x → gradient with respect to y.
    fn restrict(&self, gx: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(
            self.free.len(),
            self.free
                .iter()
                .enumerate()
                .map(|(c, &k)| gx[k] * self.scale[c]),
        )
    }

    /// The pair Jacobian (all parameters, unscaled) on an evenly strided subset of at most
    /// `max_pairs` pairs per reflector, one column per pair and reflector ([`pair_jacobian_columns`]).
    pub fn sample_pair_jacobian(&self, y: &DVector<f64>, max_pairs: usize) -> DMatrix<f64> {
        let model = self.model_at(y);
        pair_jacobian_columns(&self.jac_all(&model), max_pairs, &self.reflectors)
    }

    /// [`pair_jacobian_gram`] of the sampled pair Jacobian at `y`.
    pub fn sample_pair_jacobian_gram(&self, y: &DVector<f64>, max_pairs: usize) -> DMatrix<f64> {
        let model = self.model_at(y);
        pair_jacobian_gram(&self.jac_all(&model), max_pairs, &self.reflectors)
    }

    /// F_k of the start model on this problem's data, mm² (sums of squared distance errors), one per
    /// reflector.
    pub fn start_objectives_mm2(&self) -> Vec<f64> {
        let model = self.model_at(&DVector::zeros(self.free.len()));
        let fk = self.fk_all(&model);
        let points = model_points(
            fk.iter().map(|f| &f.points_mm),
            fk.len(),
            self.measured.len(),
        );
        pairs::triangle(
            &points,
            &self.measured,
            self.kept_distances.as_deref(),
            false,
            self.plan,
        )
        .into_iter()
        .map(|(f, _)| f)
        .collect()
    }
}

/// Pairs per reflector whose rows make the Gauss–Newton curvature ([`MinimaxProblem::curvature`]):
/// evenly strided over all pairs, enough for the curvature's shape (it scales the steps; the gradient
/// and the objectives are summed over every pair).
pub const CURVATURE_PAIRS: usize = 1000;

/// Each reflector's model points of every configuration (`per_config` yields the `n`
/// configurations' points, `reflectors` each).
fn model_points<'a>(
    per_config: impl Iterator<Item = &'a Vec<Vector3<f64>>> + Clone,
    n: usize,
    reflectors: usize,
) -> Vec<Points> {
    let configs: Vec<&Vec<Vector3<f64>>> = per_config.collect();
    debug_assert_eq!(configs.len(), n);
    (0..reflectors)
        .map(|k| Points::from_fn(n, |i| configs[i][k]))
        .collect()
}

/// `out[c] = −((J_i − J_j)ᵀ u)[p]` for every parameter `p = params[c]`: one row of the distance
/// Jacobian (the derivative of the measured-minus-model distance), in the same floating-point order as
/// nalgebra's `(J_i − J_j).transpose() * u`.
fn pair_row(
    ji: &nalgebra::Matrix3xX<f64>,
    jj: &nalgebra::Matrix3xX<f64>,
    u: &Vector3<f64>,
    params: impl Iterator<Item = usize>,
    out: &mut [f64],
) {
    for (o, p) in out.iter_mut().zip(params) {
        let d0 = ji[(0, p)] - jj[(0, p)];
        let d1 = ji[(1, p)] - jj[(1, p)];
        let d2 = ji[(2, p)] - jj[(2, p)];
        *o = -(d0 * u.x + d1 * u.y + d2 * u.z);
    }
}

/// One row of the sampled pair Jacobian: configurations `i < j`, reflector `k`, and the unit vector
/// from j's model point to i's.
struct SampledRow {
    i: usize,
    j: usize,
    k: usize,
    u: Vector3<f64>,
}

impl SampledRow {
    /// The row's numbers, one per parameter ([`pair_row`]), into `out`.
    fn write(&self, jac: &[ArmJacobians], out: &mut [f64]) {
        let (ji, jj) = (
            &jac[self.i].jacobians[self.k],
            &jac[self.j].jacobians[self.k],
        );
        pair_row(ji, jj, &self.u, 0..out.len(), out);
    }
}

/// The rows of the sampled pair Jacobian in their order: every `stride`-th pair `(i, j)`, `i < j`, of
/// the `n(n−1)/2`, so that at most `max_pairs` pairs per reflector are kept; per pair each reflector of
/// `reflectors` whose two model points differ.
fn sampled_rows(jac: &[ArmJacobians], max_pairs: usize, reflectors: &[bool]) -> Vec<SampledRow> {
    let n = jac.len();
    let n_pairs = n * n.saturating_sub(1) / 2;
    let stride = n_pairs.div_ceil(max_pairs.max(1)).max(1);
    let mut rows = Vec::with_capacity(reflectors.len() * n_pairs.div_ceil(stride));
    let mut idx = 0usize;
    for i in 0..n {
        for j in i + 1..n {
            if idx.is_multiple_of(stride) {
                for k in (0..reflectors.len()).filter(|&k| reflectors[k]) {
                    let v = jac[i].fk.points_mm[k] - jac[j].fk.points_mm[k];
                    let dist = v.norm();
                    if dist > 0.0 {
                        rows.push(SampledRow {
                            i,
                            j,
                            k,
                            u: v / dist,
                        });
                    }
                }
            }
            idx += 1;
        }
    }
    rows
}

/// Rows −u_ijᵀ(J_i,k − J_j,k) of the pair Jacobian (all parameters, unscaled) for an evenly strided
/// subset of at most `max_pairs` pairs per reflector (of the reflectors in `reflectors`), as the columns
/// of a matrix (parameters × rows), so that `M Mᵀ` is the Gram matrix.
pub fn pair_jacobian_columns(
    jac: &[ArmJacobians],
    max_pairs: usize,
    reflectors: &[bool],
) -> DMatrix<f64> {
    let rows = sampled_rows(jac, max_pairs, reflectors);
    let p = jac.first().map_or(0, |j| j.jacobians[0].ncols());
    let mut m = DMatrix::zeros(p, rows.len());
    for (r, mut column) in rows.iter().zip(m.column_iter_mut()) {
        r.write(jac, column.as_mut_slice());
    }
    m
}

/// The mean Gram matrix `MMᵀ / rows` of [`pair_jacobian_columns`]' `M`, summed over blocks of rows so
/// that `M` is never held whole (a few hundred kilobytes to a few megabytes of fresh memory per call
/// otherwise). Equal to `gram_by_product` of `M` up to the order of the sums' rounding.
///
/// The sums are written out (four rows at a time, in their order) rather than left to a matrix
/// product: a library product picks its kernel by the processor (natively with fused multiply-adds,
/// in the browser without) and its order of sums by its tiling, so the start of a calibration — its
/// column scales and start Hessian come from this matrix — would differ in the last bits between the
/// desktop and the browser, and the two would end their runs an iteration apart. These sums are the
/// same arithmetic everywhere.
pub fn pair_jacobian_gram(
    jac: &[ArmJacobians],
    max_pairs: usize,
    reflectors: &[bool],
) -> DMatrix<f64> {
    const BLOCK: usize = 1024;
    let rows = sampled_rows(jac, max_pairs, reflectors);
    let p = jac.first().map_or(0, |j| j.jacobians[0].ncols());
    // Column-major; the lower triangle (i ≥ j) is summed, then mirrored. Each block's rows are
    // summed on their own and the block's sum added to the total (two levels of sums: the rounding
    // of a few hundred terms, not of thousands, in each).
    let mut gram = vec![0.0; p * p];
    let mut local = vec![0.0; p * p];
    let mut block = vec![0.0; p * BLOCK];
    for chunk in rows.chunks(BLOCK) {
        local.fill(0.0);
        for (r, row) in chunk.iter().zip(block.chunks_exact_mut(p.max(1))) {
            r.write(jac, row);
        }
        let filled = &block[..chunk.len() * p];
        let mut quads = filled.chunks_exact((4 * p).max(1));
        for quad in &mut quads {
            let (a, rest) = quad.split_at(p);
            let (b, rest) = rest.split_at(p);
            let (c, d) = rest.split_at(p);
            for j in 0..p {
                let (aj, bj, cj, dj) = (a[j], b[j], c[j], d[j]);
                let column = &mut local[j * p + j..(j + 1) * p];
                for ((((g, ai), bi), ci), di) in column
                    .iter_mut()
                    .zip(&a[j..])
                    .zip(&b[j..])
                    .zip(&c[j..])
                    .zip(&d[j..])
                {
                    *g += ai * aj + bi * bj + ci * cj + di * dj;
                }
            }
        }
        for a in quads.remainder().chunks_exact(p.max(1)) {
            for j in 0..p {
                let aj = a[j];
                for (g, ai) in local[j * p + j..(j + 1) * p].iter_mut().zip(&a[j..]) {
                    *g += ai * aj;
                }
            }
        }
        for (g, l) in gram.iter_mut().zip(&local) {
            *g += l;
        }
    }
    let mut gram = DMatrix::from_vec(p, p, gram);
    for j in 0..p {
        for i in j + 1..p {
            gram[(j, i)] = gram[(i, j)];
        }
    }
    gram / rows.len().max(1) as f64
}

impl MinimaxProblem for ArmProblem {
    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        StageParams::Arm(Box::new(self.model_at(y)))
    }

    fn dim(&self) -> usize {
        self.free.len()
    }

    fn pair_count(&self) -> usize {
        self.n_pairs
    }

    fn evaluate(&self, y: &DVector<f64>) -> Eval {
        let x = self.x_of(y);
        let model = self.start.with_vector(&x);
        let jac = self.jac_all(&model);
        let points = model_points(
            jac.iter().map(|j| &j.fk.points_mm),
            jac.len(),
            self.measured.len(),
        );
        let norm = 1.0 / self.n_pairs.max(1) as f64;
        let sums = pairs::triangle(
            &points,
            &self.measured,
            self.kept_distances.as_deref(),
            true,
            self.plan,
        );
        let per_reflector: Vec<(f64, DVector<f64>)> = sums
            .par_iter()
            .enumerate()
            .map(|(k, (sum, w))| {
                // ∇F_k = −2 Σ_i J_i,kᵀ w_i,k, on the free parameters only (the others are dropped by
                // the restriction to y anyway).
                let mut g = vec![0.0; self.free.len()];
                for (i, jk) in jac.iter().enumerate() {
                    let j = &jk.jacobians[k];
                    let (wx, wy, wz) = (w.x[i], w.y[i], w.z[i]);
                    for (gc, &p) in g.iter_mut().zip(&self.free) {
                        *gc -= (j[(0, p)] * wx + j[(1, p)] * wy + j[(2, p)] * wz) * 2.0;
                    }
                }
                let grad = DVector::from_iterator(
                    self.free.len(),
                    g.iter().zip(self.scale.iter()).map(|(gc, s)| gc * norm * s),
                );
                (sum * norm, grad)
            })
            .collect();
        let (cons, cons_grad) = self.constraints(&x, true);
        let (f, grad) = per_reflector.into_iter().unzip();
        Eval {
            f,
            grad,
            cons,
            cons_grad,
        }
    }

    fn values(&self, y: &DVector<f64>) -> (Vec<f64>, Vec<f64>) {
        let x = self.x_of(y);
        let model = self.start.with_vector(&x);
        let fk = self.fk_all(&model);
        let points = model_points(
            fk.iter().map(|f| &f.points_mm),
            fk.len(),
            self.measured.len(),
        );
        let norm = 1.0 / self.n_pairs.max(1) as f64;
        let f = pairs::triangle(
            &points,
            &self.measured,
            self.kept_distances.as_deref(),
            false,
            self.plan,
        )
        .into_iter()
        .map(|(f, _)| f * norm)
        .collect();
        let (cons, _) = self.constraints(&x, false);
        (f, cons)
    }
    /// `Σ_k w_k 2 G_k` with `G_k` the mean Gram matrix of reflector k's pair rows, sampled on
    /// [`CURVATURE_PAIRS`] pairs ([`pair_jacobian_gram`]; the curvature only shapes the step, the
    /// gradient and values stay exact), restricted to the free parameters and scaled.
    fn curvature(&self, y: &DVector<f64>, weights: &[f64]) -> Option<DMatrix<f64>> {
        if weights.len() != self.measured.len() {
            return None;
        }
        let model = self.model_at(y);
        let jac = self.jac_all(&model);
        let grams: Vec<(f64, DMatrix<f64>)> = (0..weights.len())
            .into_par_iter()
            .map(|k| {
                let only_k: Vec<bool> = (0..weights.len()).map(|r| r == k).collect();
                (
                    weights[k],
                    pair_jacobian_gram(&jac, CURVATURE_PAIRS, &only_k),
                )
            })
            .collect();
        let m = self.free.len();
        Some(DMatrix::from_fn(m, m, |i, j| {
            let (fi, fj) = (self.free[i], self.free[j]);
            let sum: f64 = grams.iter().map(|(w, g)| w * g[(fi, fj)]).sum();
            2.0 * sum * self.scale[i] * self.scale[j]
        }))
    }

    fn least_squares(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let model = self.model_at(y);
        let jac = self.jac_all(&model);
        let m = self.free.len();
        let n = jac.len();
        // Blocks of first indices with nearly equal pair counts, fixed by n alone, summed in
        // parallel and added in block order: the system (and so the iterations) do not depend on
        // how the threads were scheduled (a parallel `reduce` adds in whatever order the work was
        // stolen, and least squares' stopping test then fired an iteration or three apart from run
        // to run on the same data).
        let blocks = pairs::triangle_blocks(n, Plan::Blocked);
        let parts: Vec<(f64, DMatrix<f64>, DVector<f64>)> = blocks
            .into_par_iter()
            .map(|rows| {
                let mut jtj = DMatrix::<f64>::zeros(m, m);
                let mut jtr = DVector::<f64>::zeros(m);
                let mut cost = 0.0;
                let mut row = DVector::<f64>::zeros(m);
                for i in rows {
                    for j in i + 1..n {
                        for k in (0..self.reflectors.len()).filter(|&k| self.reflectors[k]) {
                            let v = jac[i].fk.points_mm[k] - jac[j].fk.points_mm[k];
                            let dist = v.norm();
                            if dist <= 0.0 {
                                continue;
                            }
                            let r = self.measured[k].distance(i, j) - dist;
                            let u = v / dist;
                            pair_row(
                                &jac[i].jacobians[k],
                                &jac[j].jacobians[k],
                                &u,
                                self.free.iter().copied(),
                                row.as_mut_slice(),
                            );
                            for (c, r) in row.iter_mut().enumerate() {
                                *r *= self.scale[c];
                            }
                            jtj.ger(1.0, &row, &row, 1.0);
                            jtr.axpy(r, &row, 1.0);
                            cost += r * r;
                        }
                    }
                }
                (cost, jtj, jtr)
            })
            .collect();
        let (mut cost, mut jtj, mut jtr) = (0.0, DMatrix::zeros(m, m), DVector::zeros(m));
        for (c, a, b) in parts {
            cost += c;
            jtj += a;
            jtr += b;
        }
        LeastSquaresSystem { cost, jtj, jtr }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finite_difference::{Tolerance, check_jacobian};
    use crate::kinematics::{SerialChain, joint_limits_rad};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::sync::Arc;

    fn reflectors() -> [Vector3<f64>; 3] {
        [
            Vector3::new(45.0, 0.0, 40.0),
            Vector3::new(-25.0, 40.0, 40.0),
            Vector3::new(-25.0, -40.0, 40.0),
        ]
    }

    /// The built-in DH arm and a YuMi-like chain.
    fn nominals() -> [ArmModel; 2] {
        let urdf = urdf_rs::read_from_string(&crate::test_robots::yumi_like_urdf()).unwrap();
        let chain = SerialChain::from_urdf(&urdf, "yumi_body", "yumi_link_7_l").unwrap();
        [
            ArmModel::nominal_irb14000(reflectors()),
            ArmModel::nominal_chain(Arc::new(chain), reflectors()),
        ]
    }

    fn setup(nominal: &ArmModel, n: usize) -> ArmProblem {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut xt = nominal.to_vector();
        for k in 0..xt.len() {
            xt[k] +=
                rng.random_range(-0.5..0.5) * if nominal.param_is_angle(k) { 0.01 } else { 1.0 };
        }
        let truth = nominal.with_vector(&xt);
        let lim = joint_limits_rad();
        let qs: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                (0..7)
                    .map(|i| rng.random_range(lim[i].0..lim[i].1))
                    .collect()
            })
            .collect();
        let measured: Vec<_> = qs.iter().map(|q| truth.reflector_fk(q).points_mm).collect();
        let free: Vec<usize> = (0..xt.len()).collect();
        let scale = DVector::from_element(xt.len(), 0.7);
        ArmProblem::new(qs, &measured, nominal, free, scale, 0.02)
    }

    #[test]
    fn gradient_matches_finite_differences() {
        for nominal in nominals() {
            gradient_check(&setup(&nominal, 9));
            gradient_check(&setup(&nominal, 9).blocked());
        }
    }

    /// The blocked pair passes (beyond [`pairs::SEQUENTIAL_PAIRS`]) sum the same as the sequential one.
    #[test]
    fn blocked_and_sequential_passes_agree() {
        for nominal in nominals() {
            let (seq, blocked) = (setup(&nominal, 41), setup(&nominal, 41).blocked());
            let y = DVector::from_fn(seq.dim(), |i, _| 0.05 * (i as f64 % 7.0 - 3.0));
            let (a, b) = (seq.evaluate(&y), blocked.evaluate(&y));
            for k in 0..a.f.len() {
                assert!(
                    (a.f[k] - b.f[k]).abs() <= 1e-13 * a.f[k],
                    "{} {}",
                    a.f[k],
                    b.f[k]
                );
                let diff = (&a.grad[k] - &b.grad[k]).amax();
                assert!(diff <= 1e-11 * a.grad[k].amax(), "{diff}");
            }
            assert_eq!(blocked.values(&y).0, b.f);
        }
    }

    fn gradient_check(p: &ArmProblem) {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let y = DVector::from_fn(p.dim(), |_, _| rng.random_range(-0.3..0.3));
        let e = p.evaluate(&y);
        let rows = |g: &[DVector<f64>]| DMatrix::from_fn(g.len(), p.dim(), |r, c| g[r][c]);
        let objectives = |y: &DVector<f64>| DVector::from_row_slice(&p.values(y).0);
        check_jacobian(
            objectives,
            &y,
            &rows(&e.grad),
            |_| 1e-5,
            Tolerance::rel(1e-6),
        )
        .unwrap_or_else(|m| panic!("objectives f0..f2: {m}"));
        let constraints = |y: &DVector<f64>| DVector::from_vec(p.values(y).1);
        // The side-length constraints curve sharply: O(h²) truncation is ~3e-7 relative here.
        check_jacobian(
            constraints,
            &y,
            &rows(&e.cons_grad),
            |_| 1e-5,
            Tolerance::rel(1e-5),
        )
        .unwrap_or_else(|m| panic!("constraints c0..c2: {m}"));
    }

    #[test]
    fn least_squares_system_matches_pairwise_definition() {
        for nominal in nominals() {
            least_squares_check(&setup(&nominal, 7));
        }
    }

    fn least_squares_check(p: &ArmProblem) {
        let y = DVector::from_element(p.dim(), 0.1);
        let ls = p.least_squares(&y);
        let (f, _) = p.values(&y);
        let total: f64 = f.iter().sum::<f64>() * p.pair_count() as f64;
        assert!((ls.cost - total).abs() < 1e-9 * total.max(1.0));
        // Jᵀr is ½ ∇(Σ F_k) in y (rows are ∂r/∂y): compare with the minimax gradients.
        let e = p.evaluate(&y);
        let g = (&e.grad[0] + &e.grad[1] + &e.grad[2]) * p.pair_count() as f64;
        let diff = (&ls.jtr * 2.0 - g).amax();
        assert!(diff < 1e-6 * (1.0 + ls.jtr.amax()), "{diff}");
    }
}
