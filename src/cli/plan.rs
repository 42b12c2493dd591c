//! `dualcal plan`: the configurations to measure (the engine's `plan` module), written as a dataset
//! ready to be filled, and for the YuMi as RAPID modules.

use super::describe_robot;
use crate::dataset::TrackerSpec;
use crate::kinematics::ArmLinks;
use crate::output::{Overwrite, write_atomic};
use crate::plan::{ArmPlan, PlanOptions, plan};
use crate::robot::{LoadOptions, RobotDescription, arm_joint_name};
use crate::side::{PerSide, Side};
use crate::simulate;
use anyhow::{Context, Result, bail};
use clap::Args;
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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
}

fn parse_xyz(s: &str) -> std::result::Result<Vector3<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("`{s}`: expected X,Y,Z (mm)"))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(format!("`{s}`: expected X,Y,Z, three numbers (mm)")),
    }
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
        Some(dir) => {
            // Through the load pipeline: a prismatic joint's column read in its length unit.
            let ds = super::load_workspace(dir)?.dataset;
            PerSide::from_fn(|side| {
                ds.arm(side)
                    .measurements
                    .iter()
                    .map(|m| m.q_rad.clone())
                    .collect::<Vec<_>>()
            })
        }
        None => PerSide::new(Vec::new(), Vec::new()),
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
        ..PlanOptions::default()
    };
    let plans = plan(&robot, &reflectors, &options)?;
    outln!("{}", describe_robot(&robot));
    let nominal = robot.nominal_model(reflectors.to_vec());
    let tracker = TrackerSpec {
        mpe_um: a.mpe_um,
        mpe_um_per_m: a.mpe_um_per_m,
    };
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    for side in Side::BOTH {
        write_arm(a, &robot, nominal.arm(side), &tracker, side, &plans[side])?;
    }
    write_atomic(
        &a.out.join(crate::dataset::MANIFEST_FILE),
        manifest(&robot, a.robot.as_deref(), &reflectors, &tracker).as_bytes(),
    )
    .with_context(|| format!("{}: cannot write", a.out.display()))?;
    outln!(
        "wrote {}: left.csv, right.csv (id,q1..qN in degrees, chain order — add the reflector columns \
         from the measurement), dataset.toml{}",
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
fn write_arm(
    a: &PlanArgs,
    robot: &RobotDescription,
    arm: &crate::kinematics::ArmModel,
    tracker: &TrackerSpec,
    side: Side,
    p: &ArmPlan,
) -> Result<()> {
    let linear = arm.linear_joints();
    let prefix = match (side, a.extend.is_some()) {
        (Side::Left, false) => "L",
        (Side::Right, false) => "R",
        // New ids beside the extended dataset's own.
        (Side::Left, true) => "LP",
        (Side::Right, true) => "RP",
    };
    write_atomic(
        &a.out.join(format!("{}.csv", side.name())),
        arm_csv(side, prefix, p, &linear).as_bytes(),
    )
    .with_context(|| format!("{}: cannot write", a.out.display()))?;
    outln!(
        "{side} arm: {} configurations chosen from {} candidates ({} draws); log det of the \
         design {:.1} (the first {} candidates drawn: {:.1}); path {:.2} (joint space){}",
        p.configs.len(),
        p.candidates,
        p.attempts,
        p.log_det,
        p.configs.len(),
        p.log_det_random,
        p.path_length,
        if p.colliding_legs.is_empty() {
            String::new()
        } else {
            format!(
                "; WARNING: the straight joint motion of legs {:?} collides — add a via point",
                p.colliding_legs.iter().map(|k| k + 1).collect::<Vec<_>>()
            )
        }
    );
    let free: Vec<usize> = (0..arm.param_count())
        .filter(|&k| arm.unidentifiable_reason(k).is_none())
        .collect();
    // The noise at the tracker's distance to the arm's base (half the MPE, per axis).
    let base = robot.body_from_arm_base(side).translation.vector;
    let sigma_mm =
        0.5e-3 * (tracker.mpe_um + tracker.mpe_um_per_m * (a.tracker - base).norm() / 1e3);
    if let Some(u) = crate::solver::uncertainty::predicted(arm, &p.configs, &free, sigma_mm) {
        let largest = |unit: &str| {
            u.largest(unit).map_or(String::new(), |s| {
                format!("{:.4} {unit} ({})", s.sigma, s.name)
            })
        };
        outln!(
            "  predicted 1σ with {sigma_mm:.4} mm of tracker noise: largest {}, {}; condition \
             number {:.1}",
            largest("mm"),
            largest("mrad"),
            u.condition
        );
    }
    if is_yumi(robot) {
        let path = a.out.join(format!("plan_{}.mod", side.name()));
        write_atomic(&path, rapid_module(side, p).as_bytes())
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}

fn is_yumi(robot: &RobotDescription) -> bool {
    robot.is_builtin()
        || robot
            .urdf
            .joints
            .iter()
            .any(|j| j.name == arm_joint_name(Side::Left, 0))
}

/// `id,q1..qN,split`: degrees (mm for a prismatic joint), every configuration a calibration one.
fn arm_csv(side: Side, prefix: &str, p: &ArmPlan, linear: &[bool]) -> String {
    let n = p.configs.first().map_or(0, Vec::len);
    let mut s = format!(
        "# dualcal plan: {side} arm, {} configurations in visiting order; q in degrees (mm for a \
         prismatic joint), chain order. Add the reflector columns <name>x,<name>y,<name>z (mm) from the \
         measurement.\nid",
        p.configs.len()
    );
    for k in 1..=n {
        let _ = write!(s, ",q{k}");
    }
    s.push_str(",split\n");
    for (i, q) in p.configs.iter().enumerate() {
        let _ = write!(s, "{prefix}{:03}", i + 1);
        for (k, v) in q.iter().enumerate() {
            let v = if linear.get(k).copied().unwrap_or(false) {
                *v
            } else {
                v.to_degrees()
            };
            let _ = write!(s, ",{v:.6}");
        }
        s.push_str(",cal\n");
    }
    s
}

/// A RAPID module of `MoveAbsJ` targets for one YuMi arm: robot axes 1–6 (ABB order) and axis 7 as
/// the external axis `eax_a`, in degrees; chain order is ABB axes 1, 2, 7, 3, 4, 5, 6.
fn rapid_module(side: Side, p: &ArmPlan) -> String {
    let name = format!("dualcal_plan_{}", side.name());
    let mut s = format!(
        "MODULE {name}\n    ! dualcal plan, {side} arm: {} configurations in visiting order.\n    ! Move \
         to each, stop, measure the reflectors, go on.\n",
        p.configs.len()
    );
    for (i, q) in p.configs.iter().enumerate() {
        let d: Vec<f64> = q.iter().map(|v| v.to_degrees()).collect();
        let _ = writeln!(
            s,
            "    CONST jointtarget p{:03} := [[{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}],[{:.4},9E9,9E9,9E9,9E9,9E9]];",
            i + 1,
            d[0],
            d[1],
            d[3],
            d[4],
            d[5],
            d[6],
            d[2]
        );
    }
    s.push_str("\n    PROC measure_all()\n");
    for i in 0..p.configs.len() {
        let _ = writeln!(
            s,
            "        MoveAbsJ p{:03}, v100, fine, tool0;\n        WaitTime 2; ! measure p{:03}",
            i + 1,
            i + 1
        );
    }
    s.push_str("    ENDPROC\nENDMODULE\n");
    s
}

/// The dataset manifest for the planned files.
fn manifest(
    robot: &RobotDescription,
    robot_path: Option<&Path>,
    reflectors: &[Vector3<f64>],
    tracker: &TrackerSpec,
) -> String {
    let mut s = String::from("format = \"dualcal-dataset/1\"\n");
    if let Some(path) = robot_path {
        let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        let _ = writeln!(s, "robot = {:?}", path.display().to_string());
    }
    let _ = write!(
        s,
        "description = \"planned by dualcal plan: fill in the reflector columns\"\n\n[units]\nlength = \
         \"mm\"\nangle = \"deg\"\n\n[tracker]\nmpe_um = {:?}\nmpe_um_per_m = {:?}\n\n[reflectors]\n",
        tracker.mpe_um, tracker.mpe_um_per_m
    );
    for (name, r) in crate::kinematics::default_reflector_names(reflectors.len())
        .iter()
        .zip(reflectors)
    {
        let _ = writeln!(s, "{name} = [{:?}, {:?}, {:?}]", r.x, r.y, r.z);
    }
    for side in Side::BOTH {
        let _ = write!(
            s,
            "\n[[arms]]\nname = \"{}\"\nfile = \"{}.csv\"\n",
            side.name(),
            side.name()
        );
        if robot_path.is_some() {
            let links = &robot.arm(side).links;
            let _ = write!(
                s,
                "base_link = {:?}\ntip_link = {:?}\n",
                links.base_link, links.tip_link
            );
        }
    }
    s
}
