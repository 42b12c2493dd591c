//! `dualcal reproduce`: the studies of the paper and of docs/solver.md on simulated data. Its
//! arguments ([`args`]), the short studies and the dispatch ([`run`]), the outliers study and the
//! paper's comparison of methods in their own rooms.

mod args;
mod outlier_study;
mod paper_study;
mod run;

pub use args::{ReproduceArgs, Study};
pub(super) use run::run;
