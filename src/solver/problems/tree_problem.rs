//! Step 1 of a robot whose arms share joints (a torso on both chains): one fit of both arms.
//!
//! **Parameters.** The tree's vector `X` is the left arm's parameter vector followed by the right
//! arm's parameters that are not shared ([`TreeLayout`]); a shared joint's corrections appear once and
//! set both arms' copies. The identifiability analysis runs on `X` (both arms' sampled pair
//! Jacobians, one Gram matrix), so a torso correction that only the two arms' data together fix is
//! identified, and one that neither moves is reported unidentifiable like any other.
//!
//! **Objective.** Reflector `k`'s objective is the summed squared distance errors of reflector `k` of
//! *both* arms, normalised by both arms' pairs: `f_k = (F_k,left + F_k,right) / (pairs_left +
//! pairs_right)`. The minimax is over the reflectors, as in one arm (Algorithm I); the reflector
//! triangle constraints (14) of both arms are kept. Distances are still only between configurations
//! of one arm (each arm's files may come from their own moments). Without a shared joint this is
//! not used: each arm is fitted on its own, as the paper does.
//!
//! Each arm keeps its own [`ArmProblem`] on the parameters of `X` that it holds (a shared one is free
//! in both at the same scale), so the pair passes are those of one arm; the tree gathers each arm's
//! variables from its own and adds their gradients, constraint gradients and normal equations back.

use super::arm_problem::ArmProblem;
use super::problem::{Eval, LeastSquaresSystem, MinimaxProblem, StageParams};
use crate::kinematics::{ArmModel, SharedJoints};
use crate::side::{PerSide, Side};
use crate::solver::analysis::identifiability::analyse::{FixedParameter, IdentifiabilityReport};
use nalgebra::{DMatrix, DVector};

/// Where each arm's parameters sit in the tree's vector `X`.
#[derive(Clone, Debug)]
pub struct TreeLayout {
    /// For each side, the index in `X` of each of its parameters.
    pub index: PerSide<Vec<usize>>,
    /// Length of `X`.
    pub len: usize,
}

impl TreeLayout {
    pub fn new(left: &ArmModel, right: &ArmModel, shared: &SharedJoints) -> Self {
        let n_left = left.param_count();
        let mut next = n_left;
        let right_index = (0..right.param_count())
            .map(|b| {
                shared.left_param_of(b).unwrap_or_else(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        Self {
            index: PerSide::new((0..n_left).collect(), right_index),
            len: next,
        }
    }

    /// The side and parameter an entry of `X` is first found at (the left arm's, for a shared one).
    pub fn owner(&self, x: usize) -> (Side, usize) {
        for side in Side::BOTH {
            if let Some(k) = self.index[side].iter().position(|&i| i == x) {
                return (side, k);
            }
        }
        unreachable!("every entry of X belongs to an arm")
    }

    /// The entries of `X` in the identifiability analysis' preference order: each arm's own order
    /// interleaved (both arms' reflectors first, then the joints from the base), a shared one once,
    /// where the left arm's order puts it.
    pub fn interleaved_order(&self, arms: &PerSide<ArmModel>) -> Vec<usize> {
        let orders = arms.as_ref().map(|_, a| a.identifiability_order());
        let mut order: Vec<usize> = Vec::with_capacity(self.len);
        for i in 0..orders.left.len().max(orders.right.len()) {
            for side in Side::BOTH {
                if let Some(&k) = orders[side].get(i) {
                    let x = self.index[side][k];
                    if !order.contains(&x) {
                        order.push(x);
                    }
                }
            }
        }
        order
    }

    /// How the analysis names entry `x`: `left a3`, or `d1 (shared)` for one both arms hold.
    pub fn param_name(&self, x: usize, arms: &PerSide<ArmModel>) -> String {
        let (side, k) = self.owner(x);
        if self.is_shared(x) {
            format!("{} (shared)", arms[side].param_name(k))
        } else {
            format!("{side} {}", arms[side].param_name(k))
        }
    }

    /// Is entry `x` of `X` held by both arms?
    pub fn is_shared(&self, x: usize) -> bool {
        Side::BOTH
            .into_iter()
            .all(|side| self.index[side].contains(&x))
    }

    /// The tree's report split into each arm's (in each arm's own parameter indices and names); a
    /// shared parameter is in both.
    pub fn split_report(
        &self,
        report: &IdentifiabilityReport,
        arms: &PerSide<ArmModel>,
    ) -> PerSide<IdentifiabilityReport> {
        PerSide::from_fn(|side| {
            let index = &self.index[side];
            let local = |x: usize| index.iter().position(|&i| i == x);
            let free = report.free.iter().filter_map(|&x| local(x)).collect();
            let fixed = report
                .fixed
                .iter()
                .filter_map(|f| {
                    local(f.index).map(|k| FixedParameter {
                        index: k,
                        name: arms[side].param_name(k),
                        residual: f.residual,
                        reason: f.reason.clone(),
                    })
                })
                .collect();
            IdentifiabilityReport {
                free,
                fixed,
                condition_before: report.condition_before,
                condition_after: report.condition_after,
            }
        })
    }
}

/// One arm's part of the tree problem.
struct TreeArm {
    problem: ArmProblem,
    /// For each of the arm problem's variables, the tree's variable it is.
    gather: Vec<usize>,
}

impl TreeArm {
    fn y(&self, y: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(self.gather.len(), self.gather.iter().map(|&c| y[c]))
    }

    fn scatter(&self, g: &DVector<f64>, dim: usize) -> DVector<f64> {
        let mut out = DVector::zeros(dim);
        for (i, &c) in self.gather.iter().enumerate() {
            out[c] += g[i];
        }
        out
    }
}

/// The step-1 problem of both arms of a robot with shared joints.
pub struct TreeProblem {
    arms: PerSide<TreeArm>,
    dim: usize,
    reflectors: usize,
}

impl TreeProblem {
    /// `probes` are each arm's distance problem (every parameter free at unit scale); `free` the
    /// entries of `X` the tree identifies and `scale` their scales.
    pub fn new(
        probes: PerSide<ArmProblem>,
        layout: &TreeLayout,
        free: &[usize],
        scale: &DVector<f64>,
    ) -> Self {
        let reflectors = probes.left.reflector_count();
        let arms = probes.map(|side, probe| {
            let mut local = Vec::new();
            let mut gather = Vec::new();
            let mut s = Vec::new();
            for (c, &x) in free.iter().enumerate() {
                if let Some(k) = layout.index[side].iter().position(|&i| i == x) {
                    local.push(k);
                    gather.push(c);
                    s.push(scale[c]);
                }
            }
            TreeArm {
                problem: probe.with_free(local, DVector::from_vec(s)),
                gather,
            }
        });
        Self {
            arms,
            dim: free.len(),
            reflectors,
        }
    }

    /// Each arm's share of the normalisation: its pairs over both arms'.
    fn weights(&self) -> PerSide<f64> {
        let total = self.pair_count().max(1) as f64;
        self.arms
            .as_ref()
            .map(|_, a| a.problem.pair_count() as f64 / total)
    }

    /// F_k of each arm's start model, summed over the arms, mm² (one per reflector).
    pub fn start_objectives_mm2(&self) -> Vec<f64> {
        let mut f = vec![0.0; self.reflectors];
        for (_, arm) in self.arms.iter() {
            for (fk, v) in f.iter_mut().zip(arm.problem.start_objectives_mm2()) {
                *fk += v;
            }
        }
        f
    }

    /// Each arm's model at y.
    pub fn models_at(&self, y: &DVector<f64>) -> PerSide<ArmModel> {
        self.arms.as_ref().map(|_, a| a.problem.model_at(&a.y(y)))
    }
}

impl MinimaxProblem for TreeProblem {
    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        StageParams::Arms(Box::new(self.models_at(y)))
    }

    fn dim(&self) -> usize {
        self.dim
    }

    fn pair_count(&self) -> usize {
        self.arms.left.problem.pair_count() + self.arms.right.problem.pair_count()
    }

    fn evaluate(&self, y: &DVector<f64>) -> Eval {
        let w = self.weights();
        let evals = self.arms.as_ref().map(|_, a| a.problem.evaluate(&a.y(y)));
        let mut f = vec![0.0; self.reflectors];
        let mut grad = vec![DVector::zeros(self.dim); self.reflectors];
        let (mut cons, mut cons_grad) = (Vec::new(), Vec::new());
        for side in Side::BOTH {
            let (arm, e) = (&self.arms[side], &evals[side]);
            for k in 0..self.reflectors {
                f[k] += w[side] * e.f[k];
                grad[k] += arm.scatter(&e.grad[k], self.dim) * w[side];
            }
            cons.extend_from_slice(&e.cons);
            cons_grad.extend(e.cons_grad.iter().map(|g| arm.scatter(g, self.dim)));
        }
        Eval {
            f,
            grad,
            cons,
            cons_grad,
        }
    }

    fn values(&self, y: &DVector<f64>) -> (Vec<f64>, Vec<f64>) {
        let w = self.weights();
        let mut f = vec![0.0; self.reflectors];
        let mut cons = Vec::new();
        for side in Side::BOTH {
            let arm = &self.arms[side];
            let (fs, cs) = arm.problem.values(&arm.y(y));
            for (fk, v) in f.iter_mut().zip(fs) {
                *fk += w[side] * v;
            }
            cons.extend(cs);
        }
        (f, cons)
    }

    fn least_squares(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let mut out = LeastSquaresSystem {
            cost: 0.0,
            jtj: DMatrix::zeros(self.dim, self.dim),
            jtr: DVector::zeros(self.dim),
        };
        for (_, arm) in self.arms.iter() {
            let s = arm.problem.least_squares(&arm.y(y));
            out.cost += s.cost;
            for (i, &ci) in arm.gather.iter().enumerate() {
                out.jtr[ci] += s.jtr[i];
                for (j, &cj) in arm.gather.iter().enumerate() {
                    out.jtj[(ci, cj)] += s.jtj[(i, j)];
                }
            }
        }
        out
    }
}
