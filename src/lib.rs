//! dualcal: two-step minimax kinematic calibration of dual-arm robots from laser-tracker data.
//!
//! The engine modules (`kinematics`, `robot`, `dataset`, `params`, `simulate`, `metrics`, `solver`,
//! `export`) never depend on egui or wgpu; the workbench lives in `app` behind the `gui` feature.
#![forbid(unsafe_code)]

pub mod dataset;
pub mod kinematics;
pub mod params;
pub mod simulate;
