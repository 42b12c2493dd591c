//! `dualcal plan`: the configurations to measure (the engine's `plan` module), written as a dataset
//! ready to be filled, and for the YuMi as RAPID modules.

use super::common::{describe_robot, parse_xyz};
use crate::dataset::TrackerSpec;
use crate::kinematics::ArmLinks;
use crate::output::{Overwrite, write_atomic};
use crate::plan::{
    ArmPlan, PlanOptions, PlanOutput, Region, bound_line, is_yumi, plan, plan_files, summary_line,
};
use crate::robot::{LoadOptions, RobotDescription};
use crate::side::{PerSide, Side};
use crate::simulate;
use anyhow::{Context, Result, bail};
use clap::Args;
use nalgebra::Vector3;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Robot description (URDF) [default: the built-in IRB 14000].
    #[arg(long)]
    pub robot: Option<PathBuf>,
    /// With --robot: the left arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "robot", value_parser = ArmLinks::parse)]
    pub left: Option<ArmLinks>,
    /// With --robot: the right arm's chain, BASE:TIP.
    #[arg(long, requires = "robot", value_parser = ArmLinks::parse)]
    pub right: Option<ArmLinks>,
    /// The tracker's position in the robot's root (body) frame, mm: X,Y,Z.
    #[arg(long, value_parser = parse_xyz)]
    pub tracker: Vector3<f64>,
    /// Configurations per arm.
    #[arg(long, default_value_t = 20)]
    pub n: usize,
    /// Output directory (created; must be empty or absent unless --force).
    #[arg(long)]
    pub out: PathBuf,
    /// Write into an existing non-empty --out.
    #[arg(long)]
    pub force: bool,
    /// Extend this dataset: its configurations (both splits) start the design and N new ones per arm
    /// are added (written alone, ids after the dataset's).
    #[arg(long)]
    pub extend: Option<PathBuf>,
    /// Candidate configurations drawn per arm (collision-free and facing the tracker).
    #[arg(long, default_value_t = 600)]
    pub candidates: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Largest angle between the reflectors' facing direction and the line to the tracker, deg.
    #[arg(long, default_value_t = 60.0)]
    pub max_incidence_deg: f64,
    /// Largest distance from the tracker, m.
    #[arg(long, default_value_t = 15.0)]
    pub max_range_m: f64,
    /// Fraction of each joint's range kept clear at both ends.
    #[arg(long, default_value_t = 0.05)]
    pub joint_margin: f64,
    /// Clearance to the body, the other arm and the keep-out boxes, mm.
    #[arg(long, default_value_t = 5.0)]
    pub clearance_mm: f64,
    /// A keep-out box of the cell (a fixture, the tracker's stand): X0,Y0,Z0,X1,Y1,Z1, mm in the
    /// robot's root frame; repeat for more.
    #[arg(long = "keep-out", value_parser = crate::collision::KeepOutBox::parse)]
    pub keep_out: Vec<crate::collision::KeepOutBox>,
    /// The tracker's maximum permissible error, constant part, µm (for the predicted σ).
    #[arg(long, default_value_t = TrackerSpec::default().mpe_um)]
    pub mpe_um: f64,
    /// The tracker's maximum permissible error, part per metre, µm/m.
    #[arg(long, default_value_t = TrackerSpec::default().mpe_um_per_m)]
    pub mpe_um_per_m: f64,
    /// Plan the smallest N per arm whose predicted verification accuracy over the region (the
    /// default method's mean, a multiple of the noise floor) reaches this (e.g. 1.1); prints the
    /// curve N → predicted accuracy. --n is then ignored.
    #[arg(long)]
    pub target: Option<f64>,
    /// The region where accuracy is needed, a box of the root frame: X0,Y0,Z0,X1,Y1,Z1 (mm; the
    /// flange's position) [default: the whole workspace].
    #[arg(long, value_parser = crate::collision::KeepOutBox::parse, conflicts_with = "region_configs")]
    pub region_box: Option<crate::collision::KeepOutBox>,
    /// The region where accuracy is needed: this dataset's configurations (both splits).
    #[arg(long)]
    pub region_configs: Option<PathBuf>,
    /// Configurations drawn for the region per arm.
    #[arg(long, default_value_t = PlanOptions::default().region_samples)]
    pub region_samples: usize,
}

/// The configurations of the dataset at `dir`, per arm.
fn dataset_configs(dir: &std::path::Path) -> Result<PerSide<Vec<Vec<f64>>>> {
    // Through the load pipeline: a prismatic joint's column read in its length unit.
    let ds = super::common::load_workspace(dir)?.dataset;
    Ok(PerSide::from_fn(|side| {
        ds.arm(side)
            .measurements
            .iter()
            .map(|m| m.q_rad.clone())
            .collect::<Vec<_>>()
    }))
}

/// `dualcal plan`.
pub fn run(a: &PlanArgs) -> Result<()> {
    if !(a.max_incidence_deg > 0.0 && a.max_incidence_deg <= 90.0) {
        bail!("--max-incidence-deg: expected an angle in (0, 90]");
    }
    let robot = match &a.robot {
        Some(path) => RobotDescription::load(
            path.as_path(),
            &LoadOptions {
                arms: PerSide::new(a.left.clone(), a.right.clone()),
                ..Default::default()
            },
        )?,
        None => RobotDescription::builtin_irb14000(),
    };
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    if a.out.exists() && !a.out.is_dir() {
        bail!(
            "{}: is a file: the output is a dataset directory",
            a.out.display()
        );
    }
    let non_empty = std::fs::read_dir(&a.out).is_ok_and(|mut d| d.next().is_some());
    if non_empty && overwrite == Overwrite::Refuse {
        return Err(crate::output::OutputError::Exists {
            path: a.out.clone(),
        }
        .into());
    }
    let reflectors = simulate::default_reflectors_for(&robot);
    let existing = match &a.extend {
        Some(dir) => dataset_configs(dir)?,
        None => PerSide::new(Vec::new(), Vec::new()),
    };
    let region = match (&a.region_box, &a.region_configs) {
        (Some(b), _) => Region::Box {
            min_mm: b.min_mm,
            max_mm: b.max_mm,
        },
        (None, Some(dir)) => Region::Configs(dataset_configs(dir)?),
        (None, None) => Region::Workspace,
    };
    let tracker = TrackerSpec {
        mpe_um: a.mpe_um,
        mpe_um_per_m: a.mpe_um_per_m,
    };
    let options = PlanOptions {
        per_arm: a.n,
        candidates: a.candidates,
        seed: a.seed,
        tracker_in_body_mm: a.tracker,
        max_incidence_deg: a.max_incidence_deg,
        max_range_mm: a.max_range_m * 1000.0,
        joint_limit_margin_fraction: a.joint_margin,
        clearance_mm: a.clearance_mm,
        keep_out: a.keep_out.clone(),
        existing,
        region,
        region_samples: a.region_samples,
        tracker_mpe: tracker,
        target: a.target,
        ..PlanOptions::default()
    };
    let plans = plan(&robot, &reflectors, &options)?;
    outln!("{}", describe_robot(&robot));
    let nominal = robot.nominal_model(reflectors.to_vec());
    for side in Side::BOTH {
        print_arm(
            &robot,
            nominal.arm(side),
            &tracker,
            &a.tracker,
            side,
            &plans[side],
        );
        print_region(&options, &plans[side]);
    }
    let output = PlanOutput {
        robot: &robot,
        robot_path: a.robot.as_deref(),
        reflectors_mm: &reflectors,
        tracker,
        extending: a.extend.is_some(),
    };
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    for (name, text) in plan_files(&output, &plans) {
        let path = a.out.join(name);
        write_atomic(&path, text.as_bytes())
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    outln!(
        "wrote {}: left.csv, right.csv (id,q1..qN in degrees, chain order — add the reflector columns \
         from the measurement), path_left.csv and path_right.csv (the visiting sequence with its via \
         points), dataset.toml{}",
        a.out.display(),
        if is_yumi(&robot) {
            ", plan_left.mod and plan_right.mod (RAPID MoveAbsJ targets)"
        } else {
            ""
        }
    );
    Ok(())
}

/// One arm's table, its lines of the summary with the predicted σ, and for the YuMi its RAPID module.
/// Print an arm's summary and its predicted σ.
fn print_arm(
    robot: &RobotDescription,
    arm: &crate::kinematics::ArmModel,
    tracker: &TrackerSpec,
    tracker_in_body_mm: &Vector3<f64>,
    side: Side,
    p: &ArmPlan,
) {
    outln!("{}", summary_line(side, p));
    if let Some(d) = crate::solver::uncertainty::predicted_for_tracker(
        robot,
        arm,
        side,
        &p.configs,
        &p.sample,
        tracker,
        tracker_in_body_mm,
    ) {
        let u = &d.uncertainty;
        let largest = |unit: &str| {
            u.largest(unit).map_or(String::new(), |s| {
                format!("{:.4} {unit} ({})", s.sigma, s.name)
            })
        };
        outln!(
            "  predicted 1σ with {:.4} mm of tracker noise: largest {}, {}; condition number {:.1}",
            d.point_sigma_mm,
            largest("mm"),
            largest("mrad"),
            u.condition
        );
        if let Some(ratio) = d.verification_ratio {
            outln!(
                "  predicted verification accuracy: {ratio:.3}× the noise floor (least squares, on \
                 {} unchosen candidates; the true parameters give 1.000×)",
                p.sample.len()
            );
        }
    }
    if let Some(line) = bound_line(p) {
        outln!("  {line}");
    }
}

/// An arm's prediction over the region and, with a target, the curve N → prediction.
fn print_region(options: &PlanOptions, p: &ArmPlan) {
    let region = options.region.describe(p.region_count);
    match &p.prediction {
        Some(pred) => outln!(
            "  predicted over the region ({region}; {} draws of the robot's errors and the noise, \
             10–90 %): {}",
            pred.draws,
            pred.summary()
        ),
        None => outln!("  predicted over the region ({region}): not predictable (singular fit)"),
    }
    let Some(target) = options.target else {
        return;
    };
    let n = p.configs.len();
    let reached = p
        .prediction
        .as_ref()
        .is_some_and(|q| q.default_method.mean <= target);
    if reached {
        outln!("  target {target:.3}×: {n} configurations reach it (the default method's mean)");
    } else {
        outln!("  target {target:.3}×: not reached with up to {n} configurations");
    }
    for (n, pred) in &p.curve {
        match pred {
            Some(pred) => outln!("    N = {n:3}: {}", pred.summary()),
            None => outln!("    N = {n:3}: not predictable"),
        }
    }
}
