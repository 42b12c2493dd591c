//! The `dualcal` command line: the commands ([`Command`]) and their dispatch ([`run`]); each
//! subcommand in its own room (`calibrate/`, `reproduce/` folders, the others a file each), what
//! several share in `common.rs`, the `outln!` macro in `outln.rs` (declared first: every room has it).

#[macro_use]
mod outln;

mod calibrate;
mod common;
mod controller;
mod dh;
mod evaluate;
mod import;
mod plan;
mod report;
mod reproduce;
mod simulate;

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};
use std::path::PathBuf;

pub use calibrate::{CalibrateArgs, NotConverged, comparison_table};
pub use common::describe_robot;
pub use controller::TargetsRefused;
pub use evaluate::EvaluateArgs;
pub use reproduce::{ReproduceArgs, Study};
pub use simulate::SimulateArgs;

/// Two-step minimax kinematic calibration of dual-arm robots from laser-tracker data.
#[derive(Parser, Debug)]
#[command(name = "dualcal", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the workbench (the default when no command is given).
    Gui {
        /// Dataset directory or its dataset.toml (default: the bundled example).
        dataset: Option<PathBuf>,
        /// Robot description (default: the dataset's, or the built-in IRB 14000).
        #[arg(long)]
        urdf: Option<PathBuf>,
    },
    /// Simulate a laser-tracker dataset of both arms (paper §4.1).
    Simulate(SimulateArgs),
    /// Accuracy of a parameter set on a dataset (paper eqs. 5–8).
    Evaluate(EvaluateArgs),
    /// Two-step minimax calibration (paper Algorithms I and II).
    Calibrate(CalibrateArgs),
    /// Reproduce the studies of the paper and of docs/solver.md on simulated data.
    Reproduce(ReproduceArgs),
    /// Make a dataset from tracker exports (SpatialAnalyzer, Leica Tracker Pilot, figaroh, any CSV
    /// with a column mapping) and the controller's joint logs (docs/formats.md).
    Import(Box<import::ImportArgs>),
    /// Write the calibration in a controller's terms: the arms' base frames as an ABB `MOC.cfg`
    /// fragment, the joint origins as a kinematics YAML for a xacro.
    Export(controller::ExportArgs),
    /// Move joint targets (or poses) so that the calibrated robot reaches what the controller's
    /// nominal model meant: what the controller cannot take, compensated.
    Compensate(controller::CompensateArgs),
    /// Plan the measurement: configurations that make every identifiable parameter well determined,
    /// collision-free and facing the tracker, in a short visiting order (a dataset to fill in; RAPID
    /// modules for the YuMi).
    Plan(plan::PlanArgs),
    /// Write the URDF a DH robot file (`dualcal-dh/1`, docs/formats.md) is read as.
    UrdfFromDh(dh::UrdfFromDhArgs),
    /// Write a calibration report: one self-contained HTML file with the dataset, the method, the
    /// identifiability, the parameters with their σ, the accuracy before and after, figures, the
    /// worst configurations, the screening and warnings.
    Report(report::ReportArgs),
}

/// What the commands take from the process's environment, read once where the program starts (`main`)
/// and handed down.
#[derive(Clone, Debug, Default)]
pub struct Environment {
    /// `DUALCAL_PDF_BROWSER` (unset or empty: `None`): the browser `dualcal report --pdf` prints
    /// with, instead of the first Chromium-based one on PATH.
    pub pdf_browser: Option<PathBuf>,
}

impl Environment {
    /// The process's environment variables.
    pub fn from_process() -> Self {
        Self {
            pdf_browser: std::env::var_os("DUALCAL_PDF_BROWSER")
                .filter(|v| !v.is_empty())
                .map(PathBuf::from),
        }
    }
}

/// Run a non-GUI command, on a thread of a work pool (rayon's): the engine's parallel loops then share
/// their work with the pool's other threads directly. Called from a thread outside a pool, every loop
/// hands its work over and sleeps until it is done — at the paper's size that costs more than the loops
/// save. `RAYON_NUM_THREADS` sets the pool's size as usual.
#[cfg(not(target_arch = "wasm32"))]
pub fn run(command: Command, env: &Environment) -> Result<()> {
    match rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("dualcal-work-{i}"))
        // The main thread's stack size: the readers recurse into nested files and markup.
        .stack_size(8 << 20)
        .build()
    {
        Ok(pool) => pool.install(|| run_command(command, env)),
        Err(_) => run_command(command, env),
    }
}

/// In a browser (no command line, one thread): the command on the page's thread.
#[cfg(target_arch = "wasm32")]
pub fn run(command: Command, env: &Environment) -> Result<()> {
    run_command(command, env)
}

fn run_command(command: Command, env: &Environment) -> Result<()> {
    match command {
        Command::Gui { .. } => {
            bail!("this build of dualcal has no workbench (built without the `gui` feature)")
        }
        Command::Simulate(a) => simulate::run(&a),
        Command::Evaluate(a) => evaluate::run(&a),
        Command::Calibrate(a) => calibrate::run(&a),
        Command::Reproduce(a) => reproduce::run(&a),
        Command::Import(a) => import::run(&a),
        Command::Export(a) => controller::run_export(&a),
        Command::Compensate(a) => controller::run_compensate(&a),
        Command::Plan(a) => plan::run(&a),
        Command::UrdfFromDh(a) => dh::run(&a),
        Command::Report(a) => report::run(&a, env.pdf_browser.as_deref()),
    }
}
