//! Step 2 (paper §2.7): the right-arm base in the left-arm base frame from the collaborative distances
//! between the same reflector on both arms, every left configuration with every right one (eqs. 17–21).
//!
//! `B(y) = (Exp(ω)·R₀, p₀ + δp)` with `y = (ω/s_rot, δp/s_trans)`; Δd_lr,k = |m_L,l,k − m_R,r,k| −
//! |p_L,l,k − (R p_R,r,k + p)|.

use super::problem::{Eval, LeastSquaresSystem, MinimaxProblem, StageParams};
use nalgebra::{
    DMatrix, DVector, Isometry3, Rotation3, SVector, Translation3, UnitQuaternion, Vector3,
};
use rayon::prelude::*;

pub struct BaseProblem {
    /// Model reflector points of the left arm in the left base frame.
    left_mm: Vec<[Vector3<f64>; 3]>,
    /// Model reflector points of the right arm in the right base frame.
    right_mm: Vec<[Vector3<f64>; 3]>,
    /// Measured collaborative distances, index `l * n_right + r`.
    measured_dist_mm: [Vec<f64>; 3],
    start: Isometry3<f64>,
    /// Scales of (ω, δp).
    scale: SVector<f64, 6>,
}

impl BaseProblem {
    pub fn new(
        left_mm: Vec<[Vector3<f64>; 3]>,
        right_mm: Vec<[Vector3<f64>; 3]>,
        measured_left: &[[Vector3<f64>; 3]],
        measured_right: &[[Vector3<f64>; 3]],
        start: Isometry3<f64>,
    ) -> Self {
        let measured_dist_mm = std::array::from_fn(|k| {
            let mut d = Vec::with_capacity(measured_left.len() * measured_right.len());
            for ml in measured_left {
                for mr in measured_right {
                    d.push((ml[k] - mr[k]).norm());
                }
            }
            d
        });
        let mut p = Self {
            left_mm,
            right_mm,
            measured_dist_mm,
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

    /// Gauss–Newton approximation of the Hessian of the mean of the three f_i (the initial BFGS
    /// matrix and the column scaling).
    pub fn gauss_newton(&self, y: &DVector<f64>) -> DMatrix<f64> {
        let mut h = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        for k in 0..3 {
            self.for_each_row(y, k, |_, row| h += row * row.transpose());
        }
        let h = h * (2.0 / (3.0 * self.n_pairs().max(1) as f64));
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
        let nr = self.right_mm.len();
        let mapped: Vec<Vector3<f64>> = self.right_mm.iter().map(|p| b.rotation * p[k]).collect();
        let t = b.translation.vector;
        for (l, pl) in self.left_mm.iter().enumerate() {
            for (r, rq) in mapped.iter().enumerate() {
                let v = pl[k] - rq - t;
                let dist = v.norm();
                let res = self.measured_dist_mm[k][l * nr + r] - dist;
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

    fn pair_count(&self) -> usize {
        self.n_pairs()
    }

    fn evaluate(&self, y: &DVector<f64>) -> Eval {
        let norm = 1.0 / self.n_pairs().max(1) as f64;
        let parts: Vec<(f64, DVector<f64>)> = (0..3)
            .into_par_iter()
            .map(|k| {
                let mut f = 0.0;
                let mut g = SVector::<f64, 6>::zeros();
                self.for_each_row(y, k, |r, row| {
                    f += r * r;
                    g += row * (2.0 * r);
                });
                (f * norm, DVector::from_column_slice((g * norm).as_slice()))
            })
            .collect();
        let mut it = parts.into_iter();
        let (f0, g0) = it.next().unwrap_or_default();
        let (f1, g1) = it.next().unwrap_or_default();
        let (f2, g2) = it.next().unwrap_or_default();
        Eval {
            f: [f0, f1, f2],
            grad: [g0, g1, g2],
            cons: Vec::new(),
            cons_grad: Vec::new(),
        }
    }

    fn values(&self, y: &DVector<f64>) -> ([f64; 3], Vec<f64>) {
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
        for k in 0..3 {
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
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut pts = |n: usize| -> Vec<[Vector3<f64>; 3]> {
            (0..n)
                .map(|_| {
                    std::array::from_fn(|_| {
                        Vector3::new(
                            rng.random_range(-400.0..400.0),
                            rng.random_range(-400.0..400.0),
                            rng.random_range(-400.0..400.0),
                        )
                    })
                })
                .collect()
        };
        let left = pts(6);
        let right = pts(5);
        let truth = Isometry3::new(
            Vector3::new(60.0, -70.0, -30.0),
            Vector3::new(0.3, -1.2, 0.4),
        );
        let ml = left.clone();
        let mr: Vec<_> = right
            .iter()
            .map(|p| {
                p.map(|v| truth * nalgebra::Point3::from(v))
                    .map(|p| p.coords)
            })
            .collect();
        let start = Isometry3::new(
            Vector3::new(62.0, -69.0, -33.0),
            Vector3::new(0.31, -1.19, 0.41),
        );
        let p = BaseProblem::new(left, right, &ml, &mr, start);
        let y = DVector::from_fn(6, |i, _| 0.1 * (i as f64 - 2.5));
        let e = p.evaluate(&y);
        let analytic = DMatrix::from_fn(3, 6, |k, c| e.grad[k][c]);
        let objectives = |y: &DVector<f64>| DVector::from_row_slice(&p.values(y).0);
        check_jacobian(objectives, &y, &analytic, |_| 1e-6, Tolerance::rel(1e-6))
            .unwrap_or_else(|m| panic!("objectives f0..f2: {m}"));
    }
}
