//! `dualcal calibrate`'s arguments, and the parser of `--gear-ratio`.

use crate::cli::common::{choice, parse_xyz};
use crate::dataset::Split;
use crate::solver::{BaseMethod, Method, QpMethod};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    #[arg(long, value_parser = choice::<Split>(), default_value_t = Split::Cal)]
    pub split: Split,
    /// Step 1 (each arm): what is fitted, and how (the methods' table; see docs/solver.md)
    /// [default: minimax; position where the data call for it — one marker per hand, both measured
    /// together in one tracker frame — so that the camera frame is identified].
    #[arg(long, value_parser = choice::<Method>())]
    pub method: Option<Method>,
    /// Step 2 (the right-arm base in the left-arm base): what is fitted, and how.
    #[arg(long, value_parser = choice::<BaseMethod>(), default_value_t = BaseMethod::Minimax)]
    pub base_method: BaseMethod,
    /// With `--method distance-single`: the reflector whose distances are fitted, by its name in
    /// the dataset's `[reflectors]` (or `a`, `b`, `c` for the first three by position); default: the
    /// one with the largest nominal error, per arm (the summary and the parameter file say which).
    #[arg(long, value_name = "NAME")]
    pub reflector: Option<String>,
    #[arg(long, value_parser = choice::<QpMethod>(), default_value_t = QpMethod::Exact)]
    pub qp: QpMethod,
    /// The SQP's curvature: `auto` (Gauss–Newton on an arm whose data are ill-conditioned, else the
    /// paper's BFGS), `gauss-newton` (Σ λ_k 2 J_kᵀJ_k of the active sums, recomputed at each iterate:
    /// on ill-conditioned data with unmodelled errors about half BFGS's iterations) or `bfgs` (the
    /// paper's update); docs/solver.md, "Curvature".
    #[arg(long, value_parser = choice::<crate::solver::Hessian>(), default_value_t = crate::solver::Hessian::Auto)]
    pub hessian: crate::solver::Hessian,
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
    /// Keep the weak parameters free. A weak parameter is one these configurations barely
    /// constrain: its 1σ would move distances across the robot's workspace (random configurations
    /// within the joint limits) by more than 3× the tracker's noise — e.g. the reflector's offset
    /// along the flange's axis when the flange hardly turns. By default each is named with the reason
    /// and held at its nominal value (step 1 solved again without it); docs/reliability.md.
    #[arg(long)]
    pub keep_weak: bool,
    /// The model identified with the geometry: `geometric` (the paper's), `elastic-axis` (each joint
    /// giving about its axis under gravity, lumped masses), `elastic` (about its axis and across it),
    /// `harmonic` (first and second harmonics of each joint's angle), `full` (elastic and harmonic);
    /// see docs/solver.md. The calibrated URDF carries only the geometry.
    #[arg(long, value_parser = crate::kinematics::ErrorTerms::from_name, default_value = "geometric")]
    pub model: crate::kinematics::ErrorTerms,
    /// Gravity's direction in the robot's root link frame, for the elastic models (default 0,0,-1:
    /// the robot standing upright).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz)]
    pub gravity: Option<nalgebra::Vector3<f64>>,
    /// A joint's gear ratio (motor turns per joint turn), for the harmonic models: the motor's first
    /// and second harmonics (of ratio × joint angle) are identified too. Repeat or separate by commas;
    /// overrides the URDF's `<transmission>` reduction of that joint. A ratio of ±1 adds nothing.
    #[arg(long = "gear-ratio", value_name = "JOINT=RATIO", value_delimiter = ',', value_parser = parse_gear_ratio)]
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

/// `JOINT=RATIO` of `--gear-ratio`.
fn parse_gear_ratio(text: &str) -> Result<(String, f64), String> {
    let (joint, ratio) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: expected JOINT=RATIO, e.g. `joint_1=100`"))?;
    let ratio: f64 = ratio
        .trim()
        .parse()
        .map_err(|_| format!("`{ratio}`: expected a number (motor turns per joint turn)"))?;
    if !ratio.is_finite() || ratio == 0.0 {
        return Err(format!(
            "`{text}`: expected a finite, non-zero ratio (motor turns per joint turn)"
        ));
    }
    Ok((joint.trim().to_string(), ratio))
}
