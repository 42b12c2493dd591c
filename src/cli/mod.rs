//! The `dualcal` command line: simulate, evaluate, calibrate, reproduce (and `gui` in the binary).

use crate::dataset::{self, Dataset, Split};
use crate::output::Overwrite;
use crate::params::{ParamsFile, Provenance, StatisticsRecord};
use crate::quality;
use crate::robot::{ArmLinks, LoadOptions, RobotDescription};
use crate::side::{ConfigId, PerSide, Side};
use crate::simulate;
use crate::solver::{BaseMethod, CalibrationResult, Method, QpMethod};
use crate::workspace::{Workspace, WorkspaceOptions};
use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

/// `println!` for command output that a closed pipe (`dualcal … | head`) ends quietly, as Unix tools
/// do, instead of panicking: the process exits with 141 (128 + SIGPIPE). Any other write error (a full
/// disk behind a redirection) is reported and exits with 1.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(err) = writeln!(std::io::stdout(), $($arg)*) {
            if err.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(141);
            }
            eprintln!("error: writing to standard output: {err}");
            std::process::exit(1);
        }
    }};
}

mod calibrate_settings;
mod controller;
mod dh;
mod evaluate;
mod fit;
mod import;
mod outlier_study;
mod paper_study;
mod plan;
mod report;
mod reproduce;
mod timings;

use calibrate_settings::{print_uncertainty, settings_from};
pub use controller::TargetsRefused;
pub use evaluate::EvaluateArgs;
pub use evaluate::comparison_table;
use fit::fit_and_screen;

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

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Output directory (created; must not already hold a dataset unless --force).
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Configurations per arm.
    #[arg(long, default_value_t = 220)]
    pub configs: usize,
    /// Of which calibration configurations (the rest are verification).
    #[arg(long, default_value_t = 120)]
    pub cal: usize,
    /// Amplitude of unmodelled periodic (gear) joint errors, mrad (0 = none).
    #[arg(long, default_value_t = 0.0)]
    pub joint_error_mrad: f64,
    /// Unmodelled joint compliance: deflection per metre of gravity lever, mrad/m (0 = none).
    #[arg(long, default_value_t = 0.0)]
    pub compliance_mrad_per_m: f64,
    /// Fraction of configurations with an outlier reflector measurement.
    #[arg(long, default_value_t = 0.0)]
    pub outlier_fraction: f64,
    /// Size of an outlier displacement, mm.
    #[arg(long, default_value_t = 1.0)]
    pub outlier_mm: f64,
    /// Fraction of configurations with a reflector misread by 0.5–5 mm (gross errors, docs/reliability.md).
    #[arg(long, default_value_t = 0.0)]
    pub misread_fraction: f64,
    /// Fraction of configurations with two reflector labels swapped.
    #[arg(long, default_value_t = 0.0)]
    pub swapped_labels_fraction: f64,
    /// Fraction of configurations replaced by a configuration of the other arm.
    #[arg(long, default_value_t = 0.0)]
    pub other_arm_fraction: f64,
    /// Overwrite an existing simulated dataset in --out.
    #[arg(long)]
    pub force: bool,
    /// Simulate this robot description (URDF) instead of the built-in IRB 14000; the dataset refers to
    /// it. Its collision geometry keeps the configurations collision-free.
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// With --urdf: the left arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "urdf", value_parser = ArmLinks::parse)]
    pub left: Option<ArmLinks>,
    /// With --urdf: the right arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "urdf", value_parser = ArmLinks::parse)]
    pub right: Option<ArmLinks>,
}

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    #[arg(long, value_enum, default_value_t = Split::Cal)]
    pub split: Split,
    /// Step 1 (each arm): what is fitted, and how (the methods' table; see docs/solver.md)
    /// [default: minimax; position where the data call for it — one marker per hand, both measured
    /// together in one tracker frame — so that the camera frame is identified].
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Step 2 (the right-arm base in the left-arm base): what is fitted, and how.
    #[arg(long, value_enum, default_value_t = BaseMethod::Minimax)]
    pub base_method: BaseMethod,
    /// With `--method distance-single`: the reflector whose distances are fitted, by its name in
    /// the dataset's `[reflectors]` (or `a`, `b`, `c` for the first three by position); default: the
    /// one with the largest nominal error, per arm (the summary and the parameter file say which).
    #[arg(long, value_name = "NAME")]
    pub reflector: Option<String>,
    #[arg(long, value_enum, default_value_t = QpMethod::Exact)]
    pub qp: QpMethod,
    /// Where to write the parameters (dualcal-params/1 JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write a calibrated copy of the robot's URDF (the user's own file with only the arm joints'
    /// origins changed, and the reflectors added as links).
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// Also write the calibration as an overlay robot software can apply to its description: the
    /// calibrated origin of every changed joint and the reflector links (YAML, or JSON for `.json`).
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// Outer iterations per stage.
    #[arg(long, default_value_t = crate::solver::CalibrationSettings::default().max_iterations)]
    pub max_iterations: usize,
    /// Stop when the scaled parameter step is below this.
    #[arg(long, default_value_t = 1e-8)]
    pub tolerance: f64,
    /// Also stop when ψ fell by less than this (relative) over the last five iterations; 0 disables.
    #[arg(long, default_value_t = crate::solver::sqp::PROGRESS_RTOL)]
    pub progress_tolerance: f64,
    /// Fit only the tracker (camera) frame and the reflector coordinates, the arms' kinematic
    /// parameters held nominal (an absolute method: `--method position` or `pose`): what the nominal
    /// robot reaches once its frame and markers are known. No step 2.
    #[arg(long)]
    pub hold_kinematics: bool,
    /// The model identified with the geometry: `geometric` (the paper's), `elastic-axis` (each joint
    /// giving about its axis under gravity, lumped masses), `elastic` (about its axis and across it),
    /// `harmonic` (first and second harmonics of each joint's angle), `full` (elastic and harmonic);
    /// see docs/solver.md. The calibrated URDF carries only the geometry.
    #[arg(long, value_parser = crate::kinematics::ErrorTerms::from_name, default_value = "geometric")]
    pub model: crate::kinematics::ErrorTerms,
    /// Gravity's direction in the robot's root link frame, for the elastic models (default 0,0,-1:
    /// the robot standing upright).
    #[arg(long, value_name = "X,Y,Z", value_parser = plan::parse_xyz)]
    pub gravity: Option<nalgebra::Vector3<f64>>,
    /// A joint's gear ratio (motor turns per joint turn), for the harmonic models: the motor's first
    /// and second harmonics (of ratio × joint angle) are identified too. Repeat or separate by commas;
    /// overrides the URDF's `<transmission>` reduction of that joint. A ratio of ±1 adds nothing.
    #[arg(long = "gear-ratio", value_name = "JOINT=RATIO", value_delimiter = ',', value_parser = calibrate_settings::parse_gear_ratio)]
    pub gear_ratios: Vec<(String, f64)>,
    /// Only the summary, no per-iteration lines.
    #[arg(long, short)]
    pub quiet: bool,
    /// Leave these configurations out (ids, comma separated; `left:ID` or `right:ID` where both arms
    /// have the id). Also left out of the accuracy tables.
    #[arg(long, value_delimiter = ',')]
    pub exclude: Vec<String>,
    /// Leave out the configurations the screening flags, by the documented rule (docs/reliability.md):
    /// flags before fitting, then after each fit, at most 10% of an arm.
    #[arg(long)]
    pub auto_exclude: bool,
    /// Print where the time went (load and screening, calibration, screening of the result, tables,
    /// writing) to standard error at the end (docs/performance.md).
    #[arg(long)]
    pub timings: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum Study {
    /// Paper Fig. 4: accuracy against the number of calibration configurations.
    Fig4,
    /// The paper's subgradient QP against the exact QP (docs/solver.md).
    Qp,
    /// Minimax against least squares with unmodelled joint errors and outliers (docs/solver.md).
    Robustness,
    /// Gross errors (misread reflectors, swapped labels, rows of the other arm): detection, false
    /// alarms, accuracy with and without exclusion (docs/reliability.md).
    Outliers,
    /// The paper's comparison of methods: Tables 4–8 and Figs. 4, 6–8 as CSV, SVG and a Markdown
    /// report in --out (docs/reproduction.md).
    Paper,
}

#[derive(Args, Debug)]
pub struct ReproduceArgs {
    #[arg(value_enum)]
    pub study: Study,
    /// Simulation seed(s), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// Calibration set sizes for fig4 and paper [default: 10,20,…,120; paper --quick: 20,60,120].
    #[arg(long, value_delimiter = ',')]
    pub sizes: Option<Vec<usize>>,
    /// Use this dataset instead of simulating (fig4 and paper).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Paper study: the output directory (created) for the CSVs, the SVG figures and report.md.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Paper study: replace outputs that already exist in --out.
    #[arg(long)]
    pub force: bool,
    /// Paper study: the quick version the tests run (one seed unless --seeds; Fig. 4 at 20, 60 and 120
    /// calibration configurations instead of twelve sizes).
    #[arg(long)]
    pub quick: bool,
    /// Paper study: only these methods (keys of `comparison::METHODS`, comma separated) [default: all].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Simulate with unmodelled joint errors (1 mrad gear error, 0.5 mrad/m compliance) — a paper-like
    /// residual of ~0.4 mm after calibration (fig4 and qp).
    #[arg(long)]
    pub unmodelled: bool,
    /// With --unmodelled (implied; all studies): amplitude of the periodic (gear) joint error, mrad,
    /// instead of 1.
    #[arg(long)]
    pub joint_error_mrad: Option<f64>,
    /// With --unmodelled (implied; all studies): joint compliance, mrad/m, instead of 0.5.
    #[arg(long)]
    pub compliance_mrad_per_m: Option<f64>,
    /// Outliers study: fraction of each arm's configurations with a misread reflector (default 0.03).
    #[arg(long)]
    pub misread_fraction: Option<f64>,
    /// Outliers study: fraction with two reflector labels swapped (default 0.01).
    #[arg(long)]
    pub swapped_labels_fraction: Option<f64>,
    /// Outliers study: fraction replaced by a row of the other arm (default 0.01).
    #[arg(long)]
    pub other_arm_fraction: Option<f64>,
}

impl ReproduceArgs {
    /// The unmodelled joint errors of the study, if any.
    pub(crate) fn joint_errors(&self) -> Option<simulate::JointErrorModel> {
        let custom = self.joint_error_mrad.is_some() || self.compliance_mrad_per_m.is_some();
        (self.unmodelled || custom).then(|| {
            let default = simulate::unmodelled_joint_errors();
            simulate::JointErrorModel {
                periodic_amplitude_mrad: self
                    .joint_error_mrad
                    .unwrap_or(default.periodic_amplitude_mrad),
                compliance_mrad_per_m: self
                    .compliance_mrad_per_m
                    .unwrap_or(default.compliance_mrad_per_m),
                ..default
            }
        })
    }
}

/// Run a non-GUI command, on a thread of a work pool (rayon's): the engine's parallel loops then share
/// their work with the pool's other threads directly. Called from a thread outside a pool, every loop
/// hands its work over and sleeps until it is done — at the paper's size that costs more than the loops
/// save. `RAYON_NUM_THREADS` sets the pool's size as usual.
#[cfg(not(target_arch = "wasm32"))]
pub fn run(command: Command) -> Result<()> {
    match rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("dualcal-work-{i}"))
        // The main thread's stack size: the readers recurse into nested files and markup.
        .stack_size(8 << 20)
        .build()
    {
        Ok(pool) => pool.install(|| run_command(command)),
        Err(_) => run_command(command),
    }
}

/// In a browser (no command line, one thread): the command on the page's thread.
#[cfg(target_arch = "wasm32")]
pub fn run(command: Command) -> Result<()> {
    run_command(command)
}

fn run_command(command: Command) -> Result<()> {
    match command {
        Command::Gui { .. } => {
            bail!("this build of dualcal has no workbench (built without the `gui` feature)")
        }
        Command::Simulate(a) => simulate_cmd(&a),
        Command::Evaluate(a) => evaluate::run(&a),
        Command::Calibrate(a) => calibrate_cmd(&a),
        Command::Reproduce(a) => reproduce::run(&a),
        Command::Import(a) => import::run(&a),
        Command::Export(a) => controller::run_export(&a),
        Command::Compensate(a) => controller::run_compensate(&a),
        Command::Plan(a) => plan::run(&a),
        Command::UrdfFromDh(a) => dh::run(&a),
        Command::Report(a) => report::run(&a),
    }
}

fn simulate_cmd(a: &SimulateArgs) -> Result<()> {
    if a.cal > a.configs {
        bail!("--cal ({}) cannot exceed --configs ({})", a.cal, a.configs);
    }
    if a.out.join(dataset::MANIFEST_FILE).exists() && !a.force {
        bail!(
            "{} already holds a dataset ({}); pass --force to replace it",
            a.out.display(),
            dataset::MANIFEST_FILE
        );
    }
    let mut opts = simulate::paper_options(a.seed, a.configs, a.cal);
    if a.joint_error_mrad > 0.0 || a.compliance_mrad_per_m > 0.0 {
        opts.joint_error = Some(simulate::JointErrorModel {
            periodic_amplitude_mrad: a.joint_error_mrad,
            compliance_mrad_per_m: a.compliance_mrad_per_m,
            ..simulate::JointErrorModel::default()
        });
    }
    if a.outlier_fraction > 0.0 {
        opts.outliers = Some(simulate::OutlierModel {
            fraction: a.outlier_fraction,
            magnitude_mm: a.outlier_mm,
        });
    }
    if a.misread_fraction > 0.0 || a.swapped_labels_fraction > 0.0 || a.other_arm_fraction > 0.0 {
        opts.gross_errors = Some(simulate::GrossErrorModel {
            misread_fraction: a.misread_fraction,
            swapped_labels_fraction: a.swapped_labels_fraction,
            other_arm_fraction: a.other_arm_fraction,
            ..simulate::GrossErrorModel::study()
        });
    }
    let robot = match &a.urdf {
        Some(path) => RobotDescription::load(
            path,
            &LoadOptions {
                arms: PerSide::new(a.left.clone(), a.right.clone()),
                ..Default::default()
            },
        )?,
        None => RobotDescription::builtin_irb14000(),
    };
    for w in &robot.warnings {
        eprintln!("warning: {w}");
    }
    let mut out = simulate::simulate_with_robot(&opts, &robot)?;
    if let Some(path) = &a.urdf {
        out.dataset.robot = Some(path.canonicalize().unwrap_or_else(|_| path.clone()));
        for (side, arm) in out.dataset.arms.iter_mut() {
            arm.links = Some(robot.arm(side).links.clone());
        }
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    crate::output::refuse_existing(&[&a.out.join("truth.json")], overwrite)?;
    dataset::save_with(&out.dataset, &a.out, dataset::Units::MM_DEG, overwrite)?;
    let mut truth = ParamsFile::from_model(&out.truth);
    truth.method = Some(serde_json::json!("simulation truth"));
    truth.provenance = Some(Provenance::now(Some(&a.out)));
    truth.write(&a.out.join("truth.json"))?;
    outln!("{}", describe_robot(&robot));
    outln!(
        "simulated {} configurations per arm ({} cal, {} ver), seed {}, into {}",
        a.configs,
        a.cal,
        a.configs - a.cal,
        a.seed,
        a.out.display()
    );
    outln!(
        "rejected samples: {} in collision, {} not facing the tracker",
        out.rejected_for_collision,
        out.rejected_for_facing
    );
    outln!("true parameters: {}", a.out.join("truth.json").display());
    for r in &out.gross_errors {
        outln!(
            "gross error: {} arm `{}`: {:?}",
            r.config.side,
            r.id,
            r.error
        );
    }
    Ok(())
}

/// The dataset at `path` with its robot, checked, its nominal model and screening
/// ([`Workspace::load`]); the robot description's warnings printed.
pub(crate) fn load_workspace(path: &Path) -> Result<Workspace> {
    let ws = Workspace::load(path, &WorkspaceOptions::default())?;
    for w in &ws.robot.warnings {
        eprintln!("warning: {w}");
    }
    Ok(ws)
}

/// Print the nominal screening's whole-file findings as warnings; `Err` with the refusals among them.
fn report_findings(ws: &Workspace) -> Result<()> {
    for f in &ws.screening.findings {
        if f.severity == quality::Severity::Warning {
            eprintln!("warning: {f}");
        }
    }
    let errors: Vec<&str> = ws.refusals().iter().map(|f| f.message.as_str()).collect();
    if errors.is_empty() {
        Ok(())
    } else {
        bail!("{}", errors.join("\nerror: "))
    }
}

/// The suspect configurations, one line each (most severe flag first).
fn print_flags(title: &str, screening: &quality::Screening, excluded: &[ConfigId]) {
    let worst = screening.worst_per_config();
    if worst.is_empty() {
        return;
    }
    outln!("\n{title} ({}):", worst.len());
    for f in &worst {
        let mark = if excluded.contains(&f.config) {
            "excluded"
        } else {
            "kept"
        };
        outln!(
            "  {:<5} {:<10} line {:<5} {:<3} {:<14} {:>9.3} mm  {:<8}  {}",
            f.config.side.name(),
            crate::textfile::excerpt(&f.id),
            f.line,
            f.split.name(),
            f.kind.label(),
            f.size_mm,
            mark,
            f.reason
        );
    }
}

/// `robot: FILE; left arm BASE → TIP (N joints: …), right arm …; nominal model …`.
pub fn describe_robot(robot: &RobotDescription) -> String {
    if robot.is_one_arm() {
        let arm = robot.arm(crate::side::Side::Left);
        return format!(
            "robot: {}; one arm {} ({} joints); nominal model: the URDF's joint origins",
            robot.name(),
            arm.links,
            arm.chain.dof()
        );
    }
    let arms: Vec<String> = robot
        .arms()
        .iter()
        .map(|(side, a)| format!("{side} arm {} ({} joints)", a.links, a.chain.dof()))
        .collect();
    let left = robot.arm(crate::side::Side::Left).chain.joint_names();
    let shared: Vec<&str> = robot
        .arm(crate::side::Side::Right)
        .chain
        .joint_names()
        .into_iter()
        .filter(|n| left.contains(n))
        .collect();
    let shared = if shared.is_empty() {
        String::new()
    } else {
        format!(
            "; shared by both arms: {} (identified once, from both arms' data)",
            shared.join(", ")
        )
    };
    format!(
        "robot: {}; {}{shared}; nominal model: {}",
        robot.name(),
        arms.join(", "),
        if robot.is_builtin() {
            "Table 3 (DH)"
        } else {
            "the URDF's joint origins"
        }
    )
}

/// A calibration that ran but did not converge (a stage hit the iteration limit, stalled or was
/// cancelled). The command exits with [`NotConverged::EXIT_CODE`] after printing its summary and
/// writing the requested files, marked `"converged": false`.
#[derive(Debug, thiserror::Error)]
#[error("the calibration did not converge ({0}); the parameters written are those reached")]
pub struct NotConverged(pub String);

impl NotConverged {
    /// Exit status of a run that did not converge (1 is for errors).
    pub const EXIT_CODE: u8 = 2;
}

/// Refuse outputs that would write over an input (the dataset's files, its robot description) or
/// over one another.
fn refuse_overwrites(a: &CalibrateArgs, ds: &Dataset) -> Result<()> {
    let mut inputs: Vec<PathBuf> = ds.files().to_vec();
    inputs.extend(ds.robot.clone());
    for out in [Some(&a.out), a.urdf.as_ref(), a.overlay.as_ref()]
        .into_iter()
        .flatten()
    {
        crate::output::refuse_overwrite_input(
            out,
            &inputs.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        )?;
    }
    if let Some(urdf) = &a.urdf {
        crate::output::refuse_overwrite_input(urdf, &[&a.out])
            .context("--urdf and --out name the same file")?;
    }
    if let Some(overlay) = &a.overlay {
        let others: Vec<&Path> = [Some(&a.out), a.urdf.as_ref()]
            .into_iter()
            .flatten()
            .map(PathBuf::as_path)
            .collect();
        crate::output::refuse_overwrite_input(overlay, &others)
            .context("--overlay names the same file as another output")?;
    }
    Ok(())
}

/// Warn about suspect configurations the calibration kept, and about whole-file findings.
fn warn_suspects_kept(after: &quality::Screening, excluded: &[ConfigId]) {
    let suspects_kept: Vec<String> = after
        .worst_per_config()
        .iter()
        .filter(|f| !excluded.contains(&f.config))
        .map(|f| f.id.clone())
        .collect();
    if !suspects_kept.is_empty() {
        let shown = suspects_kept.len().min(10);
        eprintln!(
            "warning: {} suspect configuration(s) were used for the calibration; the minimax fit is \
             steered by its worst point: look at them, then --exclude {}{} or --auto-exclude",
            suspects_kept.len(),
            suspects_kept[..shown].join(","),
            if shown < suspects_kept.len() {
                ",…"
            } else {
                ""
            }
        );
    }
    for f in &after.findings {
        eprintln!("warning: {f}");
    }
}

/// The calibrated URDF and the overlay, if asked for.
fn write_robot_exports(
    a: &CalibrateArgs,
    robot: &RobotDescription,
    result: &CalibrationResult,
) -> Result<()> {
    if let Some(path) = &a.urdf {
        let text = crate::urdf_export::calibrated_urdf(robot, &result.calibrated)?;
        crate::output::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("calibrated URDF written to {}", path.display());
    }
    if let Some(path) = &a.overlay {
        let overlay = crate::urdf_export::calibrated_overlay(robot, &result.calibrated)?;
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let text = if json {
            overlay.to_json()
        } else {
            overlay.to_yaml()
        };
        crate::output::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("calibration overlay written to {}", path.display());
    }
    Ok(())
}

fn calibrate_cmd(a: &CalibrateArgs) -> Result<()> {
    let mut phases = timings::Phases::new();
    let ws = load_workspace(&a.dataset)?;
    phases.end("load, checks, nominal model, screening");
    refuse_overwrites(a, &ws.dataset)?;
    if !a.quiet {
        eprintln!("{}", describe_robot(&ws.robot));
    }
    let mut settings = settings_from(a, &ws.dataset)?;
    calibrate_settings::model_settings(a, &ws, &mut settings)?;
    if a.method.is_none()
        && let Some(why) = crate::solver::default_method_reason(&ws.dataset)
    {
        outln!(
            "method: step 1 `{}` by default for this data ({why}); --method minimax fits the \
             distances alone",
            settings.method.name()
        );
    }
    for spec in &a.exclude {
        let config = ws
            .dataset
            .config_by_id(spec.trim())
            .map_err(|e| anyhow::anyhow!("--exclude: {e}"))?;
        if !settings.exclude.contains(&config) {
            settings.exclude.push(config);
        }
    }
    report_findings(&ws)?;
    let Workspace {
        dataset: ds,
        robot,
        nominal,
        screening: before,
    } = ws;
    // The parameter file's figures and the accuracy tables (the calibrated model's figures are the
    // ones the file records: computed once), beside the screening of the result.
    let tables = |result: &CalibrationResult| {
        let file = ParamsFile::from_calibration(result, &ds);
        let recorded: Option<StatisticsRecord> = file
            .statistics
            .clone()
            .and_then(|v| serde_json::from_value(v).ok());
        let table = comparison_table(
            &ds.excluding(&result.settings.exclude),
            result,
            recorded.as_ref(),
        );
        (file, table)
    };
    let (result, after, uncertainty, (mut file, table)) =
        fit_and_screen(a, &ds, &nominal, settings, &before, tables)?;
    phases.end("calibration, the screening of its result, its uncertainty, the accuracy tables");
    phases.done.push((
        "  of which the calibration (two steps, re-checks)",
        std::time::Duration::from_secs_f64(result.elapsed_secs),
    ));
    print_identifiability(&result);
    print_uncertainty(&uncertainty);
    let excluded = &result.settings.exclude;
    file.record_uncertainty(&uncertainty);
    outln!("\n{}", table?);
    print_flags(
        "Suspect configurations with the calibrated model",
        &after,
        excluded,
    );
    warn_suspects_kept(&after, excluded);
    file.quality = serde_json::to_value(quality::QualityRecord::new(&ds, &after, excluded)).ok();
    phases.end("the parameter file's quality record");
    file.write(&a.out)?;
    outln!("parameters written to {}", a.out.display());
    write_robot_exports(a, &robot, &result)?;
    phases.end("writing");
    if a.timings {
        phases.print();
    }
    if !result.is_converged() {
        let how: Vec<String> = result
            .stages
            .iter()
            .filter(|s| !s.termination.is_converged())
            .map(|s| format!("{}: {}", s.stage, s.termination))
            .collect();
        return Err(NotConverged(how.join("; ")).into());
    }
    Ok(())
}

fn print_identifiability(result: &CalibrationResult) {
    let settings = &result.settings;
    outln!(
        "\nmethod: step 1 `{}`, step 2 `{}`",
        settings.method.name(),
        settings.base_method.name()
    );
    for (side, rep) in result.identifiability.iter() {
        let Some(rep) = rep else { continue };
        let extra = if settings.method.is_absolute() {
            format!(" and the 6 of tracker_from_{}_base", side.name())
        } else {
            String::new()
        };
        outln!(
            "\n{side} arm: {} of {} parameters identified{extra}; condition number {:.3e} → {:.3e}",
            rep.free.len(),
            result.nominal.arm(side).param_count(),
            rep.condition_before,
            rep.condition_after
        );
        if let Some(r) = result.reflector_used[side] {
            let arm = result.nominal.arm(side);
            let name = arm
                .reflector_names
                .get(r.index())
                .map_or("?", String::as_str);
            outln!(
                "  reflector {name} used ({}); the other reflectors' coordinates are nominal: the \
                 flange's orientation is not identified",
                settings.method.name()
            );
        }
        for f in &rep.fixed {
            outln!("  fixed {:<8} {}", f.name, f.reason);
        }
    }
    for (side, t) in result.tracker_from_base.iter() {
        let Some(t) = t else { continue };
        let v = t.translation.vector;
        let w = t.rotation.scaled_axis();
        outln!(
            "tracker_from_{}_base: translation ({:.3}, {:.3}, {:.3}) mm, rotation vector ({:.6}, \
             {:.6}, {:.6}) rad",
            side.name(),
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    for s in &result.stages {
        outln!(
            "{}: {} after {} iterations, ψ {:.6} → {:.6} mm²",
            s.stage,
            s.termination,
            s.iterations,
            s.psi_start_mm2,
            s.psi_mm2
        );
    }
    let reflectors = result.nominal.arm(Side::Left).reflector_count();
    if reflectors == 1 {
        outln!(
            "one reflector per arm: ψ is that reflector's summed squared distance errors (the minimax \
             of step 1 is a least-squares fit); the flange's orientation is not measurable"
        );
    } else if reflectors == 2 {
        outln!(
            "two reflectors per arm: ψ is the larger of their summed squared distance errors; the \
             flange's orientation is not measurable"
        );
    }
    if let Some(why) = &result.base_not_measurable {
        outln!(
            "{}: not measurable from this data ({why}); the base is nominal",
            crate::solver::Stage::Base
        );
    }
    for warning in result.warnings() {
        eprintln!("warning: {warning}");
    }
    outln!("total time {:.3} s", result.elapsed_secs);
}
