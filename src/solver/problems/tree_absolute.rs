//! Step 1's absolute method ([`super::absolute_problem`], ref. \[18\]'s positions) on a robot whose arms
//! share joints (a torso): one fit of both arms and of **one** tracker (camera) frame.
//!
//! Both chains start at one link (their shared joints sit above both arms), so one tracker-from-base
//! transform places both arms' model points: the tree's variables are its free parameters
//! ([`TreeLayout`]: the left arm's, then the right arm's own) followed by that transform's six. Each arm
//! keeps its own [`AbsoluteProblem`] on the variables it holds — a shared parameter and the transform
//! are the same variables in both, at the same scale and from the same start — and the tree stacks
//! their residuals and scatters their Jacobian columns. The objective is the plain sum of squares of
//! both arms' position errors (every measured point weighs alike).

use super::absolute_problem::AbsoluteProblem;
use super::problem::{LeastSquaresSystem, StageParams};
use super::tree_problem::TreeLayout;
use crate::kinematics::ArmModel;
use crate::side::{PerSide, Side};
use crate::solver::algorithms::least_squares::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector, Isometry3};

/// One arm's part of the tree's absolute problem.
struct Part {
    problem: AbsoluteProblem,
    /// For each of the arm problem's variables (its free parameters, then the transform's six), the
    /// tree's variable it is.
    gather: Vec<usize>,
}

impl Part {
    fn y(&self, y: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(self.gather.len(), self.gather.iter().map(|&c| y[c]))
    }
}

/// Both arms' absolute positions with one tracker frame.
pub struct TreeAbsoluteProblem {
    arms: PerSide<Part>,
    dim: usize,
    reflectors: usize,
}

impl TreeAbsoluteProblem {
    /// `probes`: each arm's absolute problem (every parameter free, unit scales) from one start of
    /// the transform; `free` the entries of the tree's vector identified, `scale` their scales followed
    /// by the transform's six.
    pub fn new(
        probes: PerSide<AbsoluteProblem>,
        layout: &TreeLayout,
        free: &[usize],
        scale: &DVector<f64>,
    ) -> Self {
        assert_eq!(free.len() + 6, scale.len());
        let nf = free.len();
        let arms = probes.map(|side, probe| {
            let (mut local, mut gather, mut s) = (Vec::new(), Vec::new(), Vec::new());
            for (c, &x) in free.iter().enumerate() {
                if let Some(k) = layout.index[side].iter().position(|&i| i == x) {
                    local.push(k);
                    gather.push(c);
                    s.push(scale[c]);
                }
            }
            gather.extend(nf..nf + 6);
            s.extend((nf..nf + 6).map(|c| scale[c]));
            Part {
                problem: probe.with_free(local, DVector::from_vec(s)),
                gather,
            }
        });
        let reflectors = arms.left.problem.reflector_count();
        Self {
            arms,
            dim: nf + 6,
            reflectors,
        }
    }

    /// Each arm's model at y.
    pub fn models_at(&self, y: &DVector<f64>) -> PerSide<ArmModel> {
        self.arms.as_ref().map(|_, a| a.problem.model_at(&a.y(y)))
    }

    /// The tracker-from-base transform at y (one for both arms).
    pub fn transform_at(&self, y: &DVector<f64>) -> Isometry3<f64> {
        let left = &self.arms.left;
        left.problem.transform_at(&left.y(y))
    }

    /// Stacked residuals (left arm's, then the right's) and their Jacobian in the tree's variables.
    pub fn jacobian(&self, y: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let parts = self.arms.as_ref().map(|_, a| a.problem.jacobian(&a.y(y)));
        let rows = parts.left.0.len() + parts.right.0.len();
        let mut r = DVector::zeros(rows);
        let mut j = DMatrix::zeros(rows, self.dim);
        let mut first = 0;
        for side in Side::BOTH {
            let (ri, ji) = &parts[side];
            r.rows_mut(first, ri.len()).copy_from(ri);
            for (c, &t) in self.arms[side].gather.iter().enumerate() {
                j.view_mut((first, t), (ri.len(), 1))
                    .copy_from(&ji.column(c));
            }
            first += ri.len();
        }
        (r, j)
    }
}

impl LeastSquaresProblem for TreeAbsoluteProblem {
    fn dim(&self) -> usize {
        self.dim
    }

    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        StageParams::Arms(Box::new(self.models_at(y)))
    }

    fn cost(&self, y: &DVector<f64>) -> f64 {
        self.arms
            .values()
            .map(|a| a.problem.residuals(&a.y(y)).norm_squared())
            .sum()
    }

    fn objectives_mm2(&self, y: &DVector<f64>) -> Vec<f64> {
        let mut f = vec![0.0; self.reflectors];
        for a in self.arms.values() {
            for (fk, v) in f.iter_mut().zip(a.problem.objectives_mm2(&a.y(y))) {
                *fk += v;
            }
        }
        f
    }

    fn normal_equations(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let (r, j) = self.jacobian(y);
        LeastSquaresSystem::of_residuals(&r, &j)
    }

    fn residuals_jacobian(&self, y: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
        Some(self.jacobian(y))
    }

    fn pair_count(&self) -> usize {
        self.arms.values().map(|a| a.problem.pair_count()).sum()
    }

    fn tracker_frames(&self, y: &DVector<f64>) -> PerSide<Option<Isometry3<f64>>> {
        let t = self.transform_at(y);
        PerSide::new(Some(t), Some(t))
    }
}
