//! `dualcal calibrate`, one room: its arguments ([`args`]), the command's course ([`run`]), the
//! settings from the arguments ([`settings`]), the fit with what runs beside it ([`fit`]), the
//! progress lines (an observer of the solver, [`progress`]), what it prints of the result
//! ([`summary`]), the files it writes beside the parameters ([`outputs`]) and `--timings`.

mod args;
mod fit;
mod outputs;
mod progress;
mod run;
mod settings;
mod summary;
mod timings;

pub use args::CalibrateArgs;
pub use run::NotConverged;
pub(super) use run::run;
pub use summary::comparison_table;
