//! The solvers that minimise a stage's problem, one outer iteration per
//! [`stage::StageSolver::next_iter`]: the paper's SQP ([`sqp`]) with its QP subproblem ([`qp`]), and
//! Gauss–Newton / Levenberg–Marquardt ([`least_squares`]).

pub mod least_squares;
pub mod qp;
pub mod sqp;
pub mod stage;
