//! The calibration methods as data: one [`MethodSpec`] per step-1 method and one [`BaseMethodSpec`]
//! per step-2 method, each a value in one table ([`Method::ALL`], [`BaseMethod::ALL`]). A method's
//! value holds everything the program knows of it — its name, labels, what it minimises and cannot
//! see, how many configurations it needs, whether it identifies the tracker frames, which kind of
//! solver it runs and the function that sets its stage up (identifiability analysis, scaling, the
//! [`crate::solver::StageSolver`]). The executor ([`crate::solver::CalibrationRun`]), the command
//! line, the parameter file, the workbench's settings and `comparison::METHODS` read the table and
//! name no method.
//!
//! A new step-1 method is one file in this folder that defines its `MethodSpec` (and its set-up
//! function, built from the helpers of [`set_up`]), plus its line in [`Method::ALL`] ([`table`]) and
//! the file's `mod` line below.

mod absolute;
mod base;
mod distance_single;
mod lsq;
mod minimax;
pub mod set_up;
pub mod spec;
pub mod table;

pub use set_up::{ArmData, ArmSetUp, ArmStage, BaseSetUp, TreeSetUp, TreeStage, worst_reflector};
pub use spec::{BaseMethodSpec, MethodSpec, Observes, SolverKind, TreeSetUpFn};
pub use table::{BaseMethod, Method};
