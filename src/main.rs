//! `dualcal`: the workbench (no arguments, or `gui`) and the command line.
use clap::Parser;
use dualcal::cli::{Cli, Command};

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => run_gui(None, None),
        Some(Command::Gui { dataset, urdf }) => run_gui(dataset, urdf),
        Some(command) => dualcal::cli::run(command),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            match err.downcast_ref::<dualcal::cli::NotConverged>() {
                Some(_) => std::process::ExitCode::from(dualcal::cli::NotConverged::EXIT_CODE),
                None => std::process::ExitCode::FAILURE,
            }
        }
    }
}

#[cfg(feature = "gui")]
fn run_gui(
    dataset: Option<std::path::PathBuf>,
    urdf: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    dualcal::app::run_native(dualcal::app::AppLaunch { dataset, urdf })
}

#[cfg(not(feature = "gui"))]
fn run_gui(
    _dataset: Option<std::path::PathBuf>,
    _urdf: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    anyhow::bail!(
        "this build of dualcal has no workbench (built without the `gui` feature); see `dualcal --help`"
    )
}
