//! Step 2 (paper §2.7): the right-arm base in the left-arm base frame from the collaborative distances
//! between the same reflector on both arms, every left configuration with every right one (eqs. 17–21).
//!
//! `B(y) = (Exp(ω)·R₀, p₀ + δp)` with `y = (ω/s_rot, δp/s_trans)`; Δd_lr,k = |m_L,l,k − m_R,r,k| −
//! |p_L,l,k − (R p_R,r,k + p)|.
//!
//! The values and gradients are regrouped per right configuration like step 1's,
//! ∇ = 2 Σ_r (−S_ω J_lᵀ (a_r × R q_r), S_p a_r) with a_r = Σ_l Δd_lr u_lr, and the Gauss–Newton
//! matrix per right configuration from M_r = Σ_l u_lr u_lrᵀ: the pair loop does a distance and a few
//! multiply-adds per pair, in the blocks and lanes of `pairs` (run in parallel, reduced in order: the
//! same numbers on any number of threads), and nothing is stored per pair. At every size: at the
//! paper's 14 400 pairs per reflector a sequential sum of stored pair rows (earlier releases' order)
//! took twice as long and gave the same base to ~1e-14 mm (docs/performance.md, "Fourteenth pass").
//! A pair's row one by one (`BaseProblem::for_each_row`) is the least-squares method's (ref. 26) and the
//! tests' reference.

use super::arm_problem::pairs::{self, Points};
use super::problem::{Eval, LeastSquaresSystem, MinimaxProblem, StageParams};
use crate::par::prelude::*;
use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Rotation3, SMatrix, SVector, Translation3,
    UnitQuaternion, Vector3,
};

pub struct BaseProblem {
    /// Model reflector points of the left arm in the left base frame.
    left_mm: Vec<Vec<Vector3<f64>>>,
    /// Model reflector points of the right arm in the right base frame.
    right_mm: Vec<Vec<Vector3<f64>>>,
    /// Number of reflectors (on each arm: the same reflectors of both arms are paired).
    reflectors: usize,
    /// The left arm's model points again, per reflector, struct-of-arrays.
    left_points: Vec<Points>,
    /// Measured points of each arm per reflector (tracker frame), mm: the collaborative distances are
    /// recomputed per pass.
    measured_left: Vec<Points>,
    measured_right: Vec<Points>,
    /// Their pairwise (left × right) distances, kept up to [`pairs::KEPT_DISTANCE_PAIRS`] pairs per
    /// reflector; recomputed per pass beyond.
    kept_distances: Option<Vec<Vec<f64>>>,
    start: Isometry3<f64>,
    /// Scales of (ω, δp).
    scale: SVector<f64, 6>,
}

impl BaseProblem {
    /// `left_mm`, `right_mm`, `measured_left`, `measured_right`: per configuration the points of the
    /// same `reflectors` reflectors.
    pub fn new(
        left_mm: Vec<Vec<Vector3<f64>>>,
        right_mm: Vec<Vec<Vector3<f64>>>,
        measured_left: &[Vec<Vector3<f64>>],
        measured_right: &[Vec<Vector3<f64>>],
        reflectors: usize,
        start: Isometry3<f64>,
    ) -> Self {
        let soa = |points: &[Vec<Vector3<f64>>]| -> Vec<Points> {
            (0..reflectors)
                .map(|k| Points::from_fn(points.len(), |i| points[i][k]))
                .collect()
        };
        let (measured_left, measured_right) = (soa(measured_left), soa(measured_right));
        let kept_distances = pairs::kept_rectangle_distances(&measured_left, &measured_right);
        let mut p = Self {
            left_points: soa(&left_mm),
            measured_left,
            measured_right,
            kept_distances,
            left_mm,
            right_mm,
            reflectors,
            start,
            scale: SVector::from_element(1.0),
        };
        // Column scaling from the Gauss–Newton diagonal at the start.
        let h = p.gauss_newton(&DVector::zeros(6));
        p.scale = SVector::from_fn(|i, _| {
            let d = (h[(i, i)] * 0.5).sqrt();
            if d > 1e-12 { 1.0 / d } else { 1.0 }
        });
        p
    }

    /// Gauss–Newton approximation of the Hessian of the mean of the f_i (the initial BFGS matrix and
    /// the column scaling).
    pub fn gauss_newton(&self, y: &DVector<f64>) -> DMatrix<f64> {
        let h = self.gauss_newton_regrouped(y)
            * (2.0 / (self.reflectors as f64 * self.n_pairs().max(1) as f64));
        DMatrix::from_column_slice(6, 6, h.as_slice())
    }

    /// The transform at scaled point y.
    pub fn transform_at(&self, y: &DVector<f64>) -> Isometry3<f64> {
        let w = Vector3::new(y[0], y[1], y[2]).component_mul(&self.scale.fixed_rows::<3>(0));
        let dp = Vector3::new(y[3], y[4], y[5]).component_mul(&self.scale.fixed_rows::<3>(3));
        let r = Rotation3::new(w) * self.start.rotation.to_rotation_matrix();
        Isometry3::from_parts(
            Translation3::from(self.start.translation.vector + dp),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    }

    fn n_pairs(&self) -> usize {
        self.left_mm.len() * self.right_mm.len()
    }

    /// J_l(ω) and the right arm's points rotated into the left base (R q_r), per reflector.
    fn rotated_right(&self, y: &DVector<f64>) -> (Isometry3<f64>, Matrix3<f64>, Vec<Points>) {
        let b = self.transform_at(y);
        let w = Vector3::new(y[0], y[1], y[2]).component_mul(&self.scale.fixed_rows::<3>(0));
        let right = (0..self.reflectors)
            .map(|k| Points::from_fn(self.right_mm.len(), |r| b.rotation * self.right_mm[r][k]))
            .collect();
        (b, left_jacobian_so3(&w), right)
    }

    /// Values and gradients regrouped per right configuration (module docs), unnormalised:
    /// (F_k, ∇F_k in y).
    fn sums_regrouped(&self, y: &DVector<f64>) -> Vec<(f64, SVector<f64, 6>)> {
        let (b, jl, right) = self.rotated_right(y);
        let t = b.translation.vector;
        let sums = pairs::rectangle(
            &self.left_points,
            &right,
            &t,
            &self.measured_left,
            &self.measured_right,
            self.kept_distances.as_deref(),
        );
        (0..self.reflectors)
            .map(|k| {
                let (f, a) = &sums[k];
                let (mut c, mut sp) = (Vector3::zeros(), Vector3::zeros());
                for r in 0..a.len() {
                    let ar = a.get(r);
                    c += ar.cross(&right[k].get(r));
                    sp += ar;
                }
                let dw = jl.transpose() * c;
                let s = &self.scale;
                let g = SVector::<f64, 6>::new(
                    -dw.x * s[0],
                    -dw.y * s[1],
                    -dw.z * s[2],
                    sp.x * s[3],
                    sp.y * s[4],
                    sp.z * s[5],
                ) * 2.0;
                (*f, g)
            })
            .collect()
    }

    /// Σ rows rowsᵀ regrouped: row = C_r u with C_r = [S_ω J_lᵀ [R q_r]×; S_p], so the sum over l is
    /// C_r M_r C_rᵀ with M_r = Σ_l u uᵀ.
    fn gauss_newton_regrouped(&self, y: &DVector<f64>) -> SMatrix<f64, 6, 6> {
        self.gauss_newton_per_reflector(y).into_iter().sum()
    }

    /// [`Self::gauss_newton_regrouped`]'s terms, one per reflector (Σ over its rows of row rowᵀ).
    fn gauss_newton_per_reflector(&self, y: &DVector<f64>) -> Vec<SMatrix<f64, 6, 6>> {
        let (b, jl, right) = self.rotated_right(y);
        let t = b.translation.vector;
        let s = &self.scale;
        let sw = Matrix3::from_diagonal(&Vector3::new(s[0], s[1], s[2]));
        let sp = Matrix3::from_diagonal(&Vector3::new(s[3], s[4], s[5]));
        (0..self.reflectors)
            .into_par_iter()
            .map(|k| {
                let m = pairs::rectangle_directions(&self.left_points[k], &right[k], &t);
                let mut h = SMatrix::<f64, 6, 6>::zeros();
                #[allow(clippy::needless_range_loop)] // r indexes several arrays of the same length
                for r in 0..right[k].len() {
                    let mr = Matrix3::new(
                        m[0][r], m[1][r], m[2][r], m[1][r], m[3][r], m[4][r], m[2][r], m[4][r],
                        m[5][r],
                    );
                    let mut c = SMatrix::<f64, 6, 3>::zeros();
                    c.fixed_view_mut::<3, 3>(0, 0)
                        .copy_from(&(sw * jl.transpose() * right[k].get(r).cross_matrix()));
                    c.fixed_view_mut::<3, 3>(3, 0).copy_from(&sp);
                    h += c * mr * c.transpose();
                }
                h
            })
            .collect()
    }

    /// Calls `visit(k, residual, ∂Δd/∂y)` for every pair and reflector.
    fn for_each_row(
        &self,
        y: &DVector<f64>,
        k: usize,
        mut visit: impl FnMut(f64, &SVector<f64, 6>),
    ) {
        let b = self.transform_at(y);
        let w = Vector3::new(y[0], y[1], y[2]).component_mul(&self.scale.fixed_rows::<3>(0));
        let jl = left_jacobian_so3(&w);
        let mapped: Vec<Vector3<f64>> = self.right_mm.iter().map(|p| b.rotation * p[k]).collect();
        let t = b.translation.vector;
        for (l, pl) in self.left_mm.iter().enumerate() {
            for (r, rq) in mapped.iter().enumerate() {
                let v = pl[k] - rq - t;
                let dist = v.norm();
                let measured =
                    pairs::distance_between(&self.measured_left[k], l, &self.measured_right[k], r);
                let res = measured - dist;
                if dist <= 0.0 {
                    continue;
                }
                let u = v / dist;
                // ∂dist/∂ω = (u × Rq)ᵀ J_l(ω), ∂dist/∂p = −uᵀ; Δd = d_m − dist.
                let dw = jl.transpose() * u.cross(rq);
                let row = SVector::<f64, 6>::new(
                    -dw.x * self.scale[0],
                    -dw.y * self.scale[1],
                    -dw.z * self.scale[2],
                    u.x * self.scale[3],
                    u.y * self.scale[4],
                    u.z * self.scale[5],
                );
                visit(res, &row);
            }
        }
    }
}

/// Left Jacobian of SO(3): `d Exp(ω) = [J_l(ω) dω]× Exp(ω)`.
pub(super) fn left_jacobian_so3(w: &Vector3<f64>) -> nalgebra::Matrix3<f64> {
    let theta = w.norm();
    let k = w.cross_matrix();
    if theta < 1e-6 {
        return nalgebra::Matrix3::identity() + k * 0.5 + k * k / 6.0;
    }
    let t2 = theta * theta;
    nalgebra::Matrix3::identity()
        + k * ((1.0 - theta.cos()) / t2)
        + k * k * ((theta - theta.sin()) / (t2 * theta))
}

impl MinimaxProblem for BaseProblem {
    fn dim(&self) -> usize {
        6
    }

    /// `Σ_k w_k ∇²f_k ≈ Σ_k w_k 2 Σ_rows row rowᵀ / pairs` (every pair: the regrouped sums cost one
    /// 3 × 3 outer-product sum per right configuration).
    fn curvature(&self, y: &DVector<f64>, weights: &[f64]) -> Option<DMatrix<f64>> {
        if weights.len() != self.reflectors {
            return None;
        }
        let per_reflector = self.gauss_newton_per_reflector(y);
        let mut h = SMatrix::<f64, 6, 6>::zeros();
        for (w, hk) in weights.iter().zip(&per_reflector) {
            h += hk * *w;
        }
        let h = h * (2.0 / self.n_pairs().max(1) as f64);
        Some(DMatrix::from_column_slice(6, 6, h.as_slice()))
    }

    fn pair_count(&self) -> usize {
        self.n_pairs()
    }

    fn evaluate(&self, y: &DVector<f64>) -> Eval {
        let norm = 1.0 / self.n_pairs().max(1) as f64;
        let (f, grad) = self
            .sums_regrouped(y)
            .into_iter()
            .map(|(f, g)| (f * norm, DVector::from_column_slice((g * norm).as_slice())))
            .unzip();
        Eval {
            f,
            grad,
            cons: Vec::new(),
            cons_grad: Vec::new(),
        }
    }

    fn values(&self, y: &DVector<f64>) -> (Vec<f64>, Vec<f64>) {
        let e = self.evaluate(y);
        (e.f, e.cons)
    }

    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        StageParams::Base(self.transform_at(y))
    }

    fn least_squares(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let mut jtj = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        let mut jtr = SVector::<f64, 6>::zeros();
        let mut cost = 0.0;
        for k in 0..self.reflectors {
            self.for_each_row(y, k, |r, row| {
                jtj += row * row.transpose();
                jtr += row * r;
                cost += r * r;
            });
        }
        LeastSquaresSystem {
            cost,
            jtj: DMatrix::from_column_slice(6, 6, jtj.as_slice()),
            jtr: DVector::from_column_slice(jtr.as_slice()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finite_difference::{Tolerance, check_jacobian};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn gradient_matches_finite_differences() {
        let p = problem(6, 5);
        let y = DVector::from_fn(6, |i, _| 0.1 * (i as f64 - 2.5));
        let e = p.evaluate(&y);
        let analytic = DMatrix::from_fn(3, 6, |k, c| e.grad[k][c]);
        let objectives = |y: &DVector<f64>| DVector::from_row_slice(&p.values(y).0);
        check_jacobian(objectives, &y, &analytic, |_| 1e-6, Tolerance::rel(1e-6))
            .unwrap_or_else(|m| panic!("objectives f0..f2: {m}"));
    }

    /// The regrouped passes (values, gradients, Gauss–Newton matrix per reflector) are the sums of
    /// the pair rows taken one by one, up to rounding — at the start, where the set-up's column scales
    /// and H₀ come from, and away from it.
    #[test]
    fn the_regrouped_passes_sum_the_pair_rows() {
        let p = problem(23, 19);
        let norm = 1.0 / (23.0 * 19.0);
        for y in [
            DVector::zeros(6),
            DVector::from_fn(6, |i, _| 0.03 * (i as f64 - 2.5)),
        ] {
            let e = p.evaluate(&y);
            let per_reflector = p.gauss_newton_per_reflector(&y);
            for (k, hk) in per_reflector.iter().enumerate() {
                let (mut f, mut g, mut h) = (0.0, SVector::<f64, 6>::zeros(), SMatrix::zeros());
                p.for_each_row(&y, k, |r, row| {
                    f += r * r;
                    g += row * (2.0 * r);
                    h += row * row.transpose();
                });
                let (f, g) = (f * norm, g * norm);
                assert!((e.f[k] - f).abs() <= 1e-12 * f, "{} {f}", e.f[k]);
                let diff = (&e.grad[k] - DVector::from_column_slice(g.as_slice())).amax();
                assert!(diff <= 1e-10 * g.amax(), "{diff}");
                assert!((hk - h).amax() <= 1e-11 * h.amax(), "{hk} {h}");
            }
        }
    }

    /// Left and right model points, measurements of a true base, a start near it.
    fn problem(n_left: usize, n_right: usize) -> BaseProblem {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut pts = |n: usize| -> Vec<Vec<Vector3<f64>>> {
            (0..n)
                .map(|_| {
                    (0..3)
                        .map(|_| {
                            Vector3::new(
                                rng.random_range(-400.0..400.0),
                                rng.random_range(-400.0..400.0),
                                rng.random_range(-400.0..400.0),
                            )
                        })
                        .collect()
                })
                .collect()
        };
        let left = pts(n_left);
        let right = pts(n_right);
        let truth = Isometry3::new(
            Vector3::new(60.0, -70.0, -30.0),
            Vector3::new(0.3, -1.2, 0.4),
        );
        let ml = left.clone();
        let mr: Vec<_> = right
            .iter()
            .map(|p: &Vec<Vector3<f64>>| {
                p.iter()
                    .map(|v| (truth * nalgebra::Point3::from(*v)).coords)
                    .collect::<Vec<_>>()
            })
            .collect();
        let start = Isometry3::new(
            Vector3::new(62.0, -69.0, -33.0),
            Vector3::new(0.31, -1.19, 0.41),
        );
        BaseProblem::new(left, right, &ml, &mr, 3, start)
    }
}
