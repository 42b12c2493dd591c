//! dualcal: two-step minimax kinematic calibration of dual-arm robots from laser-tracker data — the
//! method of *Robust Kinematic Calibration for Improving Collaboration Accuracy of Dual-arm
//! Manipulators* (Algorithms I and II), for the built-in ABB IRB 14000 (YuMi) and any dual-arm robot
//! described by a URDF or a DH table.
//!
//! # The front door
//!
//! Five types cover calibrating: [`Dataset`] (measurements with the robot they were taken
//! on: a dataset directory, or arrays), [`Robot`] (the built-in IRB 14000, a URDF, a DH table),
//! [`Calibration`] (what to run: method, error model, split, exclusions — the command line's
//! defaults otherwise), [`Calibrated`] (parameters with their σ, accuracy before and after on both
//! splits, per-configuration errors, the exports) and [`Error`] (the engine's messages, naming file,
//! line and field).
//!
//! ```
//! let ds = dualcal::Dataset::load(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example"))?;
//! let result = dualcal::Calibration::new(&ds).run()?;
//! let ver = result.accuracy()?.verification.expect("the example has a verification split");
//! let collaborative = |r: &dualcal::metrics::AccuracyReport| r.collaborative.unwrap().pos_rms_mm;
//! println!("collaborative RMS {:.3} → {:.3} mm", collaborative(&ver.nominal), collaborative(&ver.calibrated));
//! assert!(collaborative(&ver.calibrated) < 0.05);
//! let urdf = result.urdf()?; // the calibrated description, only the arm joints' origins changed
//! # let _ = urdf;
//! # Ok::<(), dualcal::Error>(())
//! ```
//!
//! The other tasks: [`Import`] reads tracker exports and joint logs into a [`Dataset`] (with the
//! report of what matched), [`Plan`] says which configurations to measure for a tracker at a given
//! place (with the predicted accuracy), [`evaluate`] gives a parameter file's accuracy on a dataset,
//! and [`Calibrated`] exports the parameter file, the calibrated URDF and overlay, the ABB base frames
//! and compensated joint targets. One runnable example per task in `examples/`: `calibrate`,
//! `from_arrays`, `import`, `plan`, `export` (`cargo run --release --example import`).
//!
//! Everything else — the kinematics, the solver's stages, the metrics, the import readers and the
//! planner — is the engine's own modules below, which the command line (`dualcal`) and the workbench (feature `gui`)
//! are built on. The engine never depends on egui or wgpu.
#![forbid(unsafe_code)]

#[warn(missing_docs)]
mod api;
pub use api::{
    Accuracy, ArmArrays, Arrays, Calibrated, Calibration, Dataset, Error, Import, ImportedDataset,
    Parameter, PerSplit, Plan, Planned, Result, Robot, SplitAccuracy, evaluate,
};
pub use dataset::Split;
pub use kinematics::ErrorTerms;
pub use side::Side;
pub use solver::{BaseMethod, Method};

pub mod analysis;
#[cfg(feature = "gui")]
pub mod app;
pub mod choice;
// The `dualcal` command line's internals (its subcommands): not an interface to build on — the
// front door above is.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod cli;
pub mod collision;
pub mod comparison;
pub mod controller;
pub mod dataset;
pub mod exclusion;
pub mod finite_difference;
pub mod import;
pub mod kinematics;
pub mod meshes;
pub mod metrics;
pub mod output;
pub mod par;
pub mod params;
pub mod plan;
pub mod quality;
pub mod report;
pub mod robot;
pub mod side;
pub mod simulate;
pub mod solver;
pub mod sort;
pub mod source;
pub mod stats;
pub mod textfile;
pub mod urdf_export;
pub mod workspace;

/// Robot descriptions and mesh files the tests write (shared with the integration tests).
#[cfg(test)]
#[path = "../tests/fixtures/robots.rs"]
pub(crate) mod test_robots;
