//! dualcal: two-step minimax kinematic calibration of dual-arm robots from laser-tracker data.
//!
//! The engine modules (`kinematics`, `robot`, `meshes`, `collision`, `dataset`, `params`, `textfile`,
//! `simulate`, `metrics`, `quality`, `solver`, `urdf_export`, `cli`) never depend on egui or wgpu; the
//! workbench lives in `app` behind the `gui` feature.
#![forbid(unsafe_code)]

pub mod analysis;
#[cfg(feature = "gui")]
pub mod app;
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
