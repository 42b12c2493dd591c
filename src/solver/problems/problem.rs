//! The interface between the minimax problems of the two steps and the SQP machinery.

use crate::kinematics::ArmModel;
use crate::side::PerSide;
use nalgebra::{DMatrix, DVector, Isometry3};

/// Values and first derivatives of a minimax problem at one (scaled) point.
///
/// `f[i]` are the normalised objectives (the paper's `F_i` divided by the number of pairs, i.e. the
/// mean squared distance error of reflector i, mm²); `cons` are the inequality constraints
/// `c_l(y) ≤ 0` (normalised to order one).
#[derive(Clone, Debug)]
pub struct Eval {
    /// One objective per reflector.
    pub f: Vec<f64>,
    pub grad: Vec<DVector<f64>>,
    pub cons: Vec<f64>,
    pub cons_grad: Vec<DVector<f64>>,
}

impl Eval {
    /// ψ = max_i f_i.
    pub fn psi(&self) -> f64 {
        self.f.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Σ_l max(0, c_l).
    pub fn violation(&self) -> f64 {
        self.cons.iter().map(|c| c.max(0.0)).sum()
    }

    pub fn is_finite(&self) -> bool {
        self.f.iter().all(|v| v.is_finite())
            && self.grad.iter().all(|g| g.iter().all(|v| v.is_finite()))
            && self.cons.iter().all(|v| v.is_finite())
            && self
                .cons_grad
                .iter()
                .all(|g| g.iter().all(|v| v.is_finite()))
    }
}

/// Normal equations of the least-squares fit of all distance errors (for the LM baseline).
#[derive(Clone, Debug)]
pub struct LeastSquaresSystem {
    /// Σ r², mm².
    pub cost: f64,
    pub jtj: DMatrix<f64>,
    pub jtr: DVector<f64>,
}

impl LeastSquaresSystem {
    /// The normal equations of residuals `r` and their Jacobian `j` (∂r/∂y).
    pub fn of_residuals(r: &DVector<f64>, j: &DMatrix<f64>) -> Self {
        Self {
            cost: r.norm_squared(),
            jtj: j.tr_mul(j),
            jtr: j.tr_mul(r),
        }
    }
}

/// What a stage identifies: one arm's model (step 1) or the right-arm base in the left-arm base
/// (step 2).
#[derive(Clone, Debug, PartialEq)]
pub enum StageParams {
    Arm(Box<ArmModel>),
    /// Both arms (step 1 of arms that share joints).
    Arms(Box<PerSide<ArmModel>>),
    Base(Isometry3<f64>),
}

/// A minimax identification problem in scaled variables `y` (y = 0 is the start point).
pub trait MinimaxProblem: Send + Sync {
    /// The stage's parameters at scaled point y.
    fn params_at(&self, y: &DVector<f64>) -> StageParams;
    /// Number of free (scaled) variables.
    fn dim(&self) -> usize;
    /// Number of configuration pairs per reflector (F_i = f_i · pairs).
    fn pair_count(&self) -> usize;
    /// Values and gradients.
    fn evaluate(&self, y: &DVector<f64>) -> Eval;
    /// Values only (line search).
    fn values(&self, y: &DVector<f64>) -> (Vec<f64>, Vec<f64>);
    /// Normal equations of Σ_i F_i (least-squares baseline); `cost` is Σ r².
    fn least_squares(&self, y: &DVector<f64>) -> LeastSquaresSystem;
    /// The Gauss–Newton curvature `Σ_i weights[i] ∇²f_i ≈ Σ_i weights[i] 2 J_iᵀJ_i / pairs` of the
    /// objectives at `y` (scaled variables, the [`Eval::f`] normalisation), or `None` where the
    /// problem has none (its SQP then updates BFGS).
    fn curvature(&self, y: &DVector<f64>, weights: &[f64]) -> Option<DMatrix<f64>> {
        let _ = (y, weights);
        None
    }
}
