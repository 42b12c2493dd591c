//! What each stage minimises: the [`problem::MinimaxProblem`] interface and its problems — step 1's
//! distances of one arm ([`arm_problem`]) or of both arms sharing joints ([`tree_problem`]), the
//! absolute positions or poses of one arm ([`absolute_problem`]) or of both ([`tree_absolute`]), and
//! step 2's collaborative distances ([`base_problem`]).

pub mod absolute_problem;
pub mod arm_problem;
pub mod base_problem;
pub mod problem;
pub mod tree_absolute;
pub mod tree_problem;
