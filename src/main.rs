//! `dualcal`: the workbench (no arguments, or `gui`) and the command line; in a browser (wasm32), the
//! workbench alone.
#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    use clap::Parser;
    use dualcal::cli::{Cli, Command};
    let cli = Cli::parse();
    let result = match cli.command {
        None => run_gui(None, None),
        Some(Command::Gui { dataset, urdf }) => run_gui(dataset, urdf),
        Some(command) => dualcal::cli::run(command, &dualcal::cli::Environment::from_process()),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            if err.is::<dualcal::cli::NotConverged>() {
                std::process::ExitCode::from(dualcal::cli::NotConverged::EXIT_CODE)
            } else if err.is::<dualcal::cli::TargetsRefused>() {
                std::process::ExitCode::from(dualcal::cli::TargetsRefused::EXIT_CODE)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}

#[cfg(all(feature = "gui", not(target_arch = "wasm32")))]
fn run_gui(
    dataset: Option<std::path::PathBuf>,
    urdf: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    // The environment's knobs, read here once (docs/environment.md); the app gets plain values.
    let options = dualcal::app::LaunchOptions::from_vars(|name| std::env::var_os(name));
    dualcal::app::run_native(dualcal::app::AppLaunch { dataset, urdf }, options)
}

#[cfg(all(not(feature = "gui"), not(target_arch = "wasm32")))]
fn run_gui(
    _dataset: Option<std::path::PathBuf>,
    _urdf: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    anyhow::bail!(
        "this build of dualcal has no workbench (built without the `gui` feature); see `dualcal --help`"
    )
}

/// In a browser (`tools/web.sh build`): the workbench on the page's canvas; wasm-bindgen runs this on
/// load.
#[cfg(target_arch = "wasm32")]
fn main() {
    #[cfg(feature = "gui")]
    dualcal::app::web::start();
}
