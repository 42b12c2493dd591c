//! The `dualcal` command line: simulate, evaluate, calibrate, reproduce (and `gui` in the binary).

use crate::atomic::Overwrite;
use crate::collision::CollisionWorld;
use crate::dataset::{self, Dataset, Split, SplitSelect};
use crate::kinematics::{DualArmModel, Side};
use crate::metrics;
use crate::params::{ParamsFile, Provenance};
use crate::robot::RobotDescription;
use crate::simulate::{self, SimOptions, SimOutput};
use crate::solver::{
    self, CalibrationEvent, CalibrationResult, CalibrationSettings, Method, QpMethod,
};
use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

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
    /// Overwrite an existing simulated dataset in --out.
    #[arg(long)]
    pub force: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum SplitArg {
    Cal,
    Ver,
    All,
}

impl From<SplitArg> for SplitSelect {
    fn from(s: SplitArg) -> Self {
        match s {
            SplitArg::Cal => SplitSelect::Cal,
            SplitArg::Ver => SplitSelect::Ver,
            SplitArg::All => SplitSelect::All,
        }
    }
}

#[derive(Args, Debug)]
pub struct EvaluateArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    /// Parameter file (dualcal-params/1).
    #[arg(long, conflicts_with = "nominal", required_unless_present = "nominal")]
    pub params: Option<PathBuf>,
    /// Use the nominal model: Table 3, the dataset's nominal reflectors and the URDF's base transform.
    #[arg(long)]
    pub nominal: bool,
    #[arg(long, value_enum, default_value_t = SplitArg::All)]
    pub split: SplitArg,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum MethodArg {
    Minimax,
    /// Ordinary least squares (Levenberg–Marquardt), for comparison.
    Lsq,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum QpArg {
    Paper,
    Exact,
}

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    #[arg(long, value_enum, default_value_t = SplitArg::Cal)]
    pub split: SplitArg,
    #[arg(long, value_enum, default_value_t = MethodArg::Minimax)]
    pub method: MethodArg,
    #[arg(long, value_enum, default_value_t = QpArg::Exact)]
    pub qp: QpArg,
    /// Where to write the parameters (dualcal-params/1 JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write a calibrated copy of the robot's URDF.
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// Outer iterations per stage.
    #[arg(long, default_value_t = 200)]
    pub max_iterations: usize,
    /// Stop when the scaled parameter step is below this.
    #[arg(long, default_value_t = 1e-8)]
    pub tolerance: f64,
    /// Also stop when ψ fell by less than this (relative) over the last five iterations; 0 disables.
    #[arg(long, default_value_t = crate::solver::sqp::PROGRESS_RTOL)]
    pub progress_tolerance: f64,
    /// Only the summary, no per-iteration lines.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum Study {
    /// Paper Fig. 4: accuracy against the number of calibration configurations.
    Fig4,
    /// The paper's subgradient QP against the exact QP (docs/solver.md).
    Qp,
    /// Minimax against least squares with unmodelled joint errors and outliers (docs/solver.md).
    Robustness,
}

#[derive(Args, Debug)]
pub struct ReproduceArgs {
    #[arg(value_enum)]
    pub study: Study,
    /// Simulation seed(s), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// Calibration set sizes for fig4.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "10,20,30,40,50,60,70,80,90,100,110,120"
    )]
    pub sizes: Vec<usize>,
    /// Use this dataset instead of simulating (fig4 only).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
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
}

impl ReproduceArgs {
    /// The unmodelled joint errors of the study, if any.
    fn joint_errors(&self) -> Option<simulate::JointErrorModel> {
        let custom = self.joint_error_mrad.is_some() || self.compliance_mrad_per_m.is_some();
        (self.unmodelled || custom).then(|| {
            let default = unmodelled_joint_errors();
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

/// Run a non-GUI command.
pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Gui { .. } => {
            bail!("this build of dualcal has no workbench (built without the `gui` feature)")
        }
        Command::Simulate(a) => simulate_cmd(&a),
        Command::Evaluate(a) => evaluate_cmd(&a),
        Command::Calibrate(a) => calibrate_cmd(&a),
        Command::Reproduce(a) => reproduce_cmd(&a),
    }
}

/// The robot a dataset refers to (its `robot` entry or the built-in IRB 14000).
pub fn robot_for(dataset: &Dataset) -> Result<RobotDescription> {
    match &dataset.robot {
        Some(path) => RobotDescription::load(path)
            .with_context(|| format!("loading the robot of {}", dataset.dir.display())),
        None => Ok(RobotDescription::builtin_irb14000()),
    }
}

/// The nominal model of a dataset: Table 3, its nominal reflectors, the URDF's base transform.
pub fn nominal_for(dataset: &Dataset, robot: &RobotDescription) -> DualArmModel {
    robot.nominal_model(dataset.nominal_reflectors_mm)
}

/// Simulation options of the CLI's defaults.
pub fn sim_options(seed: u64, configs: usize, cal: usize) -> SimOptions {
    SimOptions {
        seed,
        n_configs: configs,
        n_cal: cal,
        ..SimOptions::default()
    }
}

/// Simulate with the built-in robot's collision model.
pub fn simulate_with_robot(opts: &SimOptions, robot: &RobotDescription) -> Result<SimOutput> {
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let world = CollisionWorld::new(robot);
    // While one arm is measured the other rests in the home pose.
    let parked = Side::BOTH.map(crate::robot::home_q_rad);
    let collides = |side: Side, q: &[f64; 7]| match side {
        Side::Left => world.in_collision(q, &parked[1], 5.0),
        Side::Right => world.in_collision(&parked[0], q, 5.0),
    };
    let mut opts = opts.clone();
    opts.body_from_left_base = robot.body_from_dh_base(Side::Left);
    Ok(simulate::simulate(&opts, &nominal, &collides)?)
}

fn simulate_cmd(a: &SimulateArgs) -> Result<()> {
    if a.cal > a.configs {
        bail!("--cal ({}) cannot exceed --configs ({})", a.cal, a.configs);
    }
    if a.out.join("dataset.toml").exists() && !a.force {
        bail!(
            "{} already holds a dataset (dataset.toml); pass --force to replace it",
            a.out.display()
        );
    }
    let mut opts = sim_options(a.seed, a.configs, a.cal);
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
    let robot = RobotDescription::builtin_irb14000();
    let out = simulate_with_robot(&opts, &robot)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    crate::atomic::refuse_existing(&[&a.out.join("truth.json")], overwrite)?;
    dataset::save_with(&out.dataset, &a.out, dataset::Units::MM_DEG, overwrite)?;
    let mut truth = ParamsFile::from_model(&out.truth);
    truth.method = Some(serde_json::json!("simulation truth"));
    truth.provenance = Some(Provenance::now(Some(&a.out)));
    truth.write(&a.out.join("truth.json"))?;
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
    Ok(())
}

fn load_dataset(path: &Path) -> Result<Dataset> {
    Ok(dataset::load(path)?)
}

fn evaluate_cmd(a: &EvaluateArgs) -> Result<()> {
    let ds = load_dataset(&a.dataset)?;
    let model = match &a.params {
        Some(p) => ParamsFile::read(p)?.to_model()?,
        None => nominal_for(&ds, &robot_for(&ds)?),
    };
    let report = metrics::evaluate(&ds, &model, a.split.into())?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        let what = match &a.params {
            Some(p) => format!("parameters {}", p.display()),
            None => "nominal model".to_string(),
        };
        outln!(
            "Accuracy of the {what} on {} (split: {:?})",
            ds.dir.display(),
            a.split
        );
        outln!("{}", metrics::format_table(&report));
    }
    Ok(())
}

fn settings_from(a: &CalibrateArgs) -> CalibrationSettings {
    CalibrationSettings {
        split: a.split.into(),
        method: match a.method {
            MethodArg::Minimax => Method::Minimax,
            MethodArg::Lsq => Method::LeastSquares,
        },
        qp: match a.qp {
            QpArg::Paper => QpMethod::Paper,
            QpArg::Exact => QpMethod::Exact,
        },
        max_iterations: a.max_iterations,
        step_tolerance: a.tolerance,
        progress_tolerance: a.progress_tolerance,
        ..CalibrationSettings::default()
    }
}

/// A progress line per outer iteration.
pub fn print_event(event: &CalibrationEvent) {
    match event {
        CalibrationEvent::StageStarted {
            stage,
            n_configs,
            n_pairs,
        } => {
            eprintln!("{stage}: {n_configs} configurations, {n_pairs} pairs per reflector")
        }
        CalibrationEvent::Iteration(r) => eprintln!(
            "  {:>3}  ψ {:>14.6} mm²   F_a {:>12.4}  F_b {:>12.4}  F_c {:>12.4}   λ {:.2}/{:.2}/{:.2}   step {:>9.2e}   KKT {:>9.2e}   {:>7.3} s",
            r.iteration,
            r.psi_mm2,
            r.f_mm2[0],
            r.f_mm2[1],
            r.f_mm2[2],
            r.lambda[0],
            r.lambda[1],
            r.lambda[2],
            r.step_norm,
            r.kkt_residual,
            r.elapsed_secs
        ),
        CalibrationEvent::StageFinished { stage, termination } => {
            eprintln!("{stage}: {termination}")
        }
    }
}

fn calibrate_cmd(a: &CalibrateArgs) -> Result<()> {
    let ds = load_dataset(&a.dataset)?;
    let dataset_files: Vec<PathBuf> = [
        ds.dir.join("dataset.toml"),
        ds.left.file.clone(),
        ds.right.file.clone(),
    ]
    .into();
    for out in [Some(&a.out), a.urdf.as_ref()].into_iter().flatten() {
        crate::atomic::refuse_overwrite_input(
            out,
            &dataset_files
                .iter()
                .map(PathBuf::as_path)
                .collect::<Vec<_>>(),
        )?;
    }
    let robot = robot_for(&ds)?;
    let nominal = nominal_for(&ds, &robot);
    let settings = settings_from(a);
    let cancel = AtomicBool::new(false);
    let mut observer = |e: &CalibrationEvent| {
        if !a.quiet {
            print_event(e)
        }
    };
    let result = solver::calibrate(&ds, &nominal, &settings, &mut observer, &cancel)?;
    print_identifiability(&result);
    outln!("\n{}", comparison_table(&ds, &result)?);
    let file = result.params_file(&ds);
    file.write(&a.out)?;
    outln!("parameters written to {}", a.out.display());
    if let Some(path) = &a.urdf {
        let text = crate::urdf_export::calibrated_urdf(&robot, &result.calibrated)?;
        crate::atomic::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("calibrated URDF written to {}", path.display());
    }
    Ok(())
}

fn print_identifiability(result: &CalibrationResult) {
    for (side, rep) in &result.identifiability {
        outln!(
            "\n{side} arm: {} of 37 parameters identified; condition number {:.3e} → {:.3e}",
            rep.free.len(),
            rep.condition_before,
            rep.condition_after
        );
        for f in &rep.fixed {
            outln!("  fixed {:<8} {}", f.name, f.reason);
        }
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
    for warning in result.stall_warnings() {
        eprintln!("warning: {warning}");
    }
    outln!("total time {:.3} s", result.elapsed_secs);
}

/// Nominal vs calibrated, on the calibration and verification splits.
pub fn comparison_table(ds: &Dataset, result: &CalibrationResult) -> Result<String> {
    let mut out = String::new();
    let has = |split: Split| {
        Side::BOTH.iter().all(|s| {
            ds.arm(*s)
                .measurements
                .iter()
                .filter(|m| m.split == split)
                .count()
                >= 2
        })
    };
    for (split, name) in [
        (SplitSelect::Cal, "calibration"),
        (SplitSelect::Ver, "verification"),
    ] {
        let s = match split {
            SplitSelect::Cal => Split::Cal,
            _ => Split::Ver,
        };
        if !has(s) {
            continue;
        }
        let before = metrics::evaluate(ds, &result.nominal, split)?;
        let after = metrics::evaluate(ds, &result.calibrated, split)?;
        out.push_str(&format!(
            "Accuracy on the {name} configurations (nominal → calibrated)\n"
        ));
        out.push_str(&metrics::format_comparison(
            &before,
            &after,
            ["nominal", "calibrated"],
        ));
        out.push('\n');
    }
    Ok(out)
}

/// The unmodelled joint errors of the robustness study: 1 mrad twice-per-revolution gear error and
/// 0.5 mrad/m compliance.
pub fn unmodelled_joint_errors() -> simulate::JointErrorModel {
    simulate::JointErrorModel {
        periodic_amplitude_mrad: 1.0,
        periods_per_rev: 2.0,
        compliance_mrad_per_m: 0.5,
    }
}

/// Keep the first `n` calibration configurations of each arm and all verification ones.
pub fn with_cal_subset(ds: &Dataset, n: usize) -> Dataset {
    let mut out = ds.clone();
    for arm in [&mut out.left, &mut out.right] {
        let mut kept = 0;
        arm.measurements.retain(|m| {
            if m.split == Split::Cal {
                kept += 1;
                kept <= n
            } else {
                true
            }
        });
    }
    out
}

fn quiet_calibrate(
    ds: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
) -> Result<CalibrationResult> {
    let cancel = AtomicBool::new(false);
    Ok(solver::calibrate(
        ds,
        nominal,
        settings,
        &mut |_| {},
        &cancel,
    )?)
}

/// The simulation of a study: the paper's protocol, with unmodelled joint errors if asked.
fn study_options(a: &ReproduceArgs, seed: u64) -> SimOptions {
    SimOptions {
        joint_error: a.joint_errors(),
        ..sim_options(seed, 220, 120)
    }
}

fn reproduce_cmd(a: &ReproduceArgs) -> Result<()> {
    let robot = RobotDescription::builtin_irb14000();
    match a.study {
        Study::Fig4 => {
            let ds = match &a.dataset {
                Some(p) => load_dataset(p)?,
                None => simulate_with_robot(&study_options(a, a.seeds[0]), &robot)?.dataset,
            };
            let nominal = robot.nominal_model(ds.nominal_reflectors_mm);
            outln!(
                "Paper Fig. 4: relative accuracy against the number of calibration configurations (per arm)"
            );
            outln!(
                "| configs | left pos RMS cal / ver (mm) | right pos RMS cal / ver (mm) | left ori RMS cal / ver (rad) | right ori RMS cal / ver (rad) |"
            );
            outln!("|---:|---:|---:|---:|---:|");
            for &n in &a.sizes {
                let sub = with_cal_subset(&ds, n);
                let res = quiet_calibrate(&sub, &nominal, &CalibrationSettings::default())
                    .with_context(|| format!("calibrating with {n} configurations"))?;
                let cal = metrics::evaluate(&sub, &res.calibrated, SplitSelect::Cal)?;
                let ver = metrics::evaluate(&sub, &res.calibrated, SplitSelect::Ver)?;
                outln!(
                    "| {n} | {:.4} / {:.4} | {:.4} / {:.4} | {:.5} / {:.5} | {:.5} / {:.5} |",
                    cal.relative_left.pos_rms_mm,
                    ver.relative_left.pos_rms_mm,
                    cal.relative_right.pos_rms_mm,
                    ver.relative_right.pos_rms_mm,
                    cal.relative_left.ori_rms_rad,
                    ver.relative_left.ori_rms_rad,
                    cal.relative_right.ori_rms_rad,
                    ver.relative_right.ori_rms_rad
                );
            }
        }
        Study::Qp => {
            outln!(
                "Exact QP against the paper's subgradient QP (120 cal + 100 ver configurations per arm)"
            );
            outln!(
                "| seed | QP | iterations (L/R/base) | stop (L/R/base) | time (s) | ψ left (mm²) | ψ right (mm²) | ψ base (mm²) | ver pos RMS L/R/collab (mm) | ver ori RMS L/R/collab (rad) |"
            );
            outln!("|---:|---|---|---|---:|---:|---:|---:|---|---|");
            for &seed in &a.seeds {
                let sim = simulate_with_robot(&study_options(a, seed), &robot)?;
                let truth_ver = metrics::evaluate(&sim.dataset, &sim.truth, SplitSelect::Ver)?;
                outln!(
                    "| {seed} | truth | – | – | – | – | – | – | {:.4} / {:.4} / {:.4} | {:.5} / {:.5} / {:.5} |",
                    truth_ver.relative_left.pos_rms_mm,
                    truth_ver.relative_right.pos_rms_mm,
                    truth_ver.collaborative.pos_rms_mm,
                    truth_ver.relative_left.ori_rms_rad,
                    truth_ver.relative_right.ori_rms_rad,
                    truth_ver.collaborative.ori_rms_rad
                );
                for qp in [QpMethod::Exact, QpMethod::Paper] {
                    let settings = CalibrationSettings {
                        qp,
                        max_iterations: 400,
                        ..CalibrationSettings::default()
                    };
                    let res = quiet_calibrate(&sim.dataset, &sim.nominal, &settings)?;
                    let ver = metrics::evaluate(&sim.dataset, &res.calibrated, SplitSelect::Ver)?;
                    let it: Vec<String> = res
                        .stages
                        .iter()
                        .map(|s| s.iterations.to_string())
                        .collect();
                    let psi: Vec<f64> = res.stages.iter().map(|s| s.psi_mm2).collect();
                    let stops: Vec<String> = res
                        .stages
                        .iter()
                        .map(|s| format!("{:?}", s.termination))
                        .collect();
                    outln!(
                        "| {seed} | {qp:?} | {} | {} | {:.3} | {:.6} | {:.6} | {:.6} | {:.4} / {:.4} / {:.4} | {:.5} / {:.5} / {:.5} |",
                        it.join(" / "),
                        stops.join(" / "),
                        res.elapsed_secs,
                        psi[0],
                        psi[1],
                        psi[2],
                        ver.relative_left.pos_rms_mm,
                        ver.relative_right.pos_rms_mm,
                        ver.collaborative.pos_rms_mm,
                        ver.relative_left.ori_rms_rad,
                        ver.relative_right.ori_rms_rad,
                        ver.collaborative.ori_rms_rad
                    );
                }
            }
        }
        Study::Robustness => robustness_study(a, &robot)?,
    }
    Ok(())
}

/// Minimax against least squares on data the model cannot explain: per seed, once with unmodelled joint
/// errors and once more with 5% outliers; prints a table per run and a summary of ratios.
fn robustness_study(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    let joint_errors = a.joint_errors().unwrap_or_else(unmodelled_joint_errors);
    outln!(
        "Minimax (paper) against least squares (LM) on data with unmodelled errors \
         (gear {} mrad, {} per revolution; compliance {} mrad/m); verification split unless marked cal",
        joint_errors.periodic_amplitude_mrad,
        joint_errors.periods_per_rev,
        joint_errors.compliance_mrad_per_m
    );
    outln!(
        "| seed | data | method | pos max L/R/collab (mm) | pos RMS L/R/collab (mm) | ori max L/R/collab (rad) | ori RMS L/R/collab (rad) | final λ_a/λ_b/λ_c left; right |"
    );
    outln!("|---:|---|---|---|---|---|---|---|");
    let case_names = ["joint errors", "joint errors + 5% outliers of 1 mm"];
    // The indicators compared, each for left / right / collaborative.
    type Pick = fn(&metrics::AccuracyStats) -> f64;
    let worst_reflector: Pick = |s| {
        s.pos_rms_per_reflector_mm
            .iter()
            .copied()
            .fold(0.0, f64::max)
    };
    let indicators: [(&str, bool, Pick); 5] = [
        ("position max", false, |s| s.pos_max_mm),
        ("orientation max", false, |s| s.ori_max_rad),
        ("orientation RMS", false, |s| s.ori_rms_rad),
        ("worst reflector's position RMS", false, worst_reflector),
        (
            "worst reflector's position RMS (cal)",
            true,
            worst_reflector,
        ),
    ];
    // ratios[case][run][indicator][L/R/collab] = minimax / LM
    let mut ratios: [Vec<Vec<[f64; 3]>>; 2] = [Vec::new(), Vec::new()];
    for &seed in &a.seeds {
        for (c, name) in case_names.iter().enumerate() {
            let opts = SimOptions {
                joint_error: Some(joint_errors),
                outliers: (c == 1).then_some(simulate::OutlierModel {
                    fraction: 0.05,
                    magnitude_mm: 1.0,
                }),
                ..sim_options(seed, 220, 120)
            };
            let sim = simulate_with_robot(&opts, robot)?;
            let mut values = Vec::new();
            for method in [Method::Minimax, Method::LeastSquares] {
                let settings = CalibrationSettings {
                    method,
                    ..CalibrationSettings::default()
                };
                let res = quiet_calibrate(&sim.dataset, &sim.nominal, &settings)?;
                let ver = metrics::evaluate(&sim.dataset, &res.calibrated, SplitSelect::Ver)?;
                let cal = metrics::evaluate(&sim.dataset, &res.calibrated, SplitSelect::Cal)?;
                let three = |r: &metrics::AccuracyReport, pick: Pick| {
                    [r.relative_left, r.relative_right, r.collaborative].map(|s| pick(&s))
                };
                let f = |v: [f64; 3], digits: usize| v.map(|x| format!("{x:.digits$}")).join(" / ");
                let final_lambda = |side: Side| {
                    res.history
                        .iter()
                        .rfind(|r| r.stage == solver::Stage::Arm(side))
                        .map_or_else(|| "–".to_owned(), |r| f(r.lambda, 2).replace(" / ", "/"))
                };
                outln!(
                    "| {seed} | {name} | {method:?} | {} | {} | {} | {} | {}; {} |",
                    f(three(&ver, |s| s.pos_max_mm), 4),
                    f(three(&ver, |s| s.pos_rms_mm), 4),
                    f(three(&ver, |s| s.ori_max_rad), 5),
                    f(three(&ver, |s| s.ori_rms_rad), 5),
                    final_lambda(Side::Left),
                    final_lambda(Side::Right),
                );
                values.push(
                    indicators
                        .iter()
                        .map(|&(_, on_cal, pick)| three(if on_cal { &cal } else { &ver }, pick))
                        .collect::<Vec<_>>(),
                );
            }
            ratios[c].push(
                (0..indicators.len())
                    .map(|i| std::array::from_fn(|k| values[0][i][k] / values[1][i][k]))
                    .collect(),
            );
        }
    }
    outln!("");
    outln!(
        "Summary over {} seed(s): minimax relative to least squares (below 1: minimax smaller)",
        a.seeds.len()
    );
    outln!(
        "| data | indicator | mean ratio minimax/LM (L / R / collab) | minimax smaller or equal in |"
    );
    outln!("|---|---|---|---:|");
    for (c, name) in case_names.iter().enumerate() {
        for (i, (label, _, _)) in indicators.iter().enumerate() {
            let runs = &ratios[c];
            let n = runs.len().max(1) as f64;
            let mean: Vec<String> = (0..3)
                .map(|k| format!("{:.3}", runs.iter().map(|r| r[i][k]).sum::<f64>() / n))
                .collect();
            let wins = runs
                .iter()
                .flat_map(|r| r[i].iter())
                .filter(|&&x| x <= 1.0)
                .count();
            outln!(
                "| {name} | {label} | {} | {wins} of {} |",
                mean.join(" / "),
                3 * runs.len()
            );
        }
    }
    Ok(())
}
