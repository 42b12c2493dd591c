//! `dualcal import`: a dataset from tracker exports and the controller's joint logs (the readers are
//! the engine's `import` module; docs/formats.md).

use super::common::describe_robot;
use crate::dataset;
use crate::output::Overwrite;
use crate::robot::{ArmLinks, LoadOptions, RobotDescription};
use crate::side::PerSide;
use crate::simulate;
use anyhow::Result;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ImportArgs {
    /// Robot description (URDF) the joint counts and names are checked against, and that the dataset
    /// refers to [default: the built-in IRB 14000].
    #[arg(long)]
    pub robot: Option<PathBuf>,
    /// With --robot: the left arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "robot", value_parser = ArmLinks::parse)]
    pub left_links: Option<ArmLinks>,
    /// With --robot: the right arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "robot", value_parser = ArmLinks::parse)]
    pub right_links: Option<ArmLinks>,
    /// The left arm's point file (tracker export); with only one arm's files, a dataset of that
    /// arm alone.
    #[arg(long)]
    pub left_points: Option<PathBuf>,
    /// The left arm's joint log (`id,q1..qN`, CSV/TXT, or a spreadsheet: .xlsx, .xls, .ods, or a
    /// ROS 2 bag: .mcap); not needed when the point file has the joints (figaroh).
    #[arg(long)]
    pub left_joints: Option<PathBuf>,
    /// The right arm's point file (tracker export).
    #[arg(long)]
    pub right_points: Option<PathBuf>,
    /// The right arm's joint log (as --left-joints); not needed when the point file has the joints.
    #[arg(long)]
    pub right_joints: Option<PathBuf>,
    /// Output dataset directory (created; must be empty or absent unless --force).
    #[arg(long)]
    pub out: PathBuf,
    /// Write into an existing non-empty --out, replacing its dataset.
    #[arg(long)]
    pub force: bool,
    /// The point files' format [default: recognised from each file].
    #[arg(long, value_parser = crate::cli::common::choice::<crate::import::PointsFormat>())]
    pub points_format: Option<crate::import::PointsFormat>,
    /// Column mapping of a generic CSV/TXT (implies --points-format generic): `target=1,x=2,y=3,z=4`
    /// (a point per row) or `id=1,a.x=2,a.y=3,a.z=4,…,q=11-17,split=18` (a configuration per row);
    /// columns by 1-based number or header name. Vector and matrix cells as numpy prints them:
    /// `COL[i]`, `COL[i][j]` (0-based), `q=COL[i-j]` (elements i…j as the next joints); a joint
    /// computed from others: `q4=-joints[1]-joints[2]`, `0.5*COL[1]+$3+0.1` (`$N`: column N). Each
    /// `q=` appends joints after those mapped so far. docs/formats.md, "Generic CSV/TXT".
    #[arg(long, value_parser = crate::import::ColumnMap::parse)]
    pub columns: Option<crate::import::ColumnMap>,
    /// The left arm's own column mapping (as --columns, which it replaces for the left arm): both arms
    /// in one file, e.g. `id=1,q=joints[0-2],q=-joints[1]-joints[2],q=joints[10-16],m.x=markers[1][0],
    /// m.y=markers[1][1],m.z=markers[1][2]`.
    #[arg(long, value_parser = crate::import::ColumnMap::parse, value_name = "SPEC")]
    pub left_columns: Option<crate::import::ColumnMap>,
    /// The right arm's own column mapping (as --columns, which it replaces for the right arm).
    #[arg(long, value_parser = crate::import::ColumnMap::parse, value_name = "SPEC")]
    pub right_columns: Option<crate::import::ColumnMap>,
    /// Both hands were measured at one instant (a motion-capture system seeing both markers): a left
    /// and a right configuration with the same id are one pose; the joints both arms share (a torso)
    /// must then have one value per id. Writes `measured_together = true`.
    #[arg(long)]
    pub measured_together: bool,
    /// The last N configurations of each arm (file order) are verification (`ver`), the others
    /// calibration (`cal`), whatever the files say [default: the files' split, else `cal`].
    #[arg(long, value_name = "N")]
    pub verify_last: Option<usize>,
    /// Length unit of point files that do not state theirs [default: mm; m for figaroh].
    #[arg(long, value_parser = crate::cli::common::choice::<crate::import::PointUnit>())]
    pub length_unit: Option<crate::import::PointUnit>,
    /// Angle unit of the joint logs [default: the header's `[deg]`/`[rad]`, else deg].
    #[arg(long, value_enum)]
    pub angle_unit: Option<AngleArg>,
    /// Length unit of prismatic joints' values (a lift, a linear axis) in the joint logs and mapped
    /// joint columns [default: mm; m for figaroh].
    #[arg(long, value_enum)]
    pub joint_length_unit: Option<LengthArg>,
    /// Numbers with a decimal comma (`1234,56`; fields then separated by `;`, tabs or spaces).
    #[arg(long)]
    pub decimal_comma: bool,
    /// The joint logs' column order: chain joint k is the log's joint column given k-th (1-based),
    /// e.g. `1,2,7,3,4,5,6` (or `yumi-abb`) for the YuMi's ABB axes 1…7.
    #[arg(long, value_parser = crate::import::parse_joint_order)]
    pub joint_order: Option<JointOrder>,
    /// How points find their configuration: target names `<id>_<reflector>`, file order, or time
    /// stamps [default: auto — by name where the names carry configuration ids, else by time where
    /// both files have time stamps, else by order where the counts agree].
    #[arg(long = "match", value_parser = crate::cli::common::choice::<crate::import::MatchRule>(), default_value_t = crate::import::MatchRule::Auto)]
    pub matching: crate::import::MatchRule,
    /// The sheet of spreadsheet joint logs (.xlsx, .xls, .ods) [default: the first].
    #[arg(long, value_name = "NAME")]
    pub sheet: Option<String>,
    /// ROS 2 bags (.mcap joint logs): the topic of the `sensor_msgs/msg/JointState` messages.
    #[arg(long, value_name = "TOPIC", default_value = crate::import::bag::DEFAULT_TOPIC)]
    pub joint_topic: String,
    /// ROS 2 bags: a joint is still below this velocity, rad/s (m/s for a prismatic joint).
    #[arg(long, value_name = "RAD_PER_S", default_value_t = crate::import::bag::DEFAULT_STILL_VELOCITY)]
    pub still_velocity: f64,
    /// ROS 2 bags: the shortest still interval (every joint still), s; each becomes a configuration.
    #[arg(long, value_name = "S", default_value_t = crate::import::bag::DEFAULT_STILL_SECS)]
    pub still_secs: f64,
    /// ROS 2 bags: the robot's clock minus the tracker PC's, s [default: estimated from the shots'
    /// time stamps — the offset that puts the most shots into still intervals — and reported].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub clock_offset: Option<f64>,
    /// With --match time: the largest time difference between a point and its configuration (a
    /// bag's still interval), s.
    #[arg(long, default_value_t = 0.5)]
    pub time_tolerance_s: f64,
    /// A reflector and its nominal position in the tip (flange) frame, mm: NAME=X,Y,Z; repeat for each,
    /// in order [default: a, b, c at the paper's positions].
    #[arg(long = "reflector", value_parser = parse_reflector)]
    pub reflectors: Vec<(String, nalgebra::Vector3<f64>)>,
    /// The left arm's own nominal reflector position (markers that sit differently on each hand):
    /// NAME=X,Y,Z, mm, tip frame; one for each reflector of --reflector (same names) [default: those
    /// of --reflector].
    #[arg(long = "left-reflector", value_parser = parse_reflector, value_name = "NAME=X,Y,Z")]
    pub left_reflectors: Vec<(String, nalgebra::Vector3<f64>)>,
    /// The right arm's own nominal reflector position, as --left-reflector.
    #[arg(long = "right-reflector", value_parser = parse_reflector, value_name = "NAME=X,Y,Z")]
    pub right_reflectors: Vec<(String, nalgebra::Vector3<f64>)>,
    /// The tracker's maximum permissible error, constant part, µm.
    #[arg(long, default_value_t = dataset::TrackerSpec::default().mpe_um)]
    pub mpe_um: f64,
    /// The tracker's maximum permissible error, part per metre of distance, µm/m.
    #[arg(long, default_value_t = dataset::TrackerSpec::default().mpe_um_per_m)]
    pub mpe_um_per_m: f64,
    /// The tracker station the left arm was measured from (when the arms were measured from two).
    #[arg(long)]
    pub left_station: Option<String>,
    /// The tracker station the right arm was measured from.
    #[arg(long)]
    pub right_station: Option<String>,
}

/// A joint-order mapping (a type of its own: clap takes a `Vec` argument for a list of values).
pub type JointOrder = Vec<usize>;

/// Length unit of prismatic joints on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum LengthArg {
    Mm,
    M,
}

/// Angle unit on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum AngleArg {
    Deg,
    Rad,
}

fn parse_reflector(s: &str) -> std::result::Result<(String, nalgebra::Vector3<f64>), String> {
    let (name, xyz) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected NAME=X,Y,Z (mm, tip frame)"))?;
    let v: Vec<f64> = xyz
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("`{s}`: expected NAME=X,Y,Z with three numbers (mm)"))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => {
            Ok((name.trim().to_string(), nalgebra::Vector3::new(*x, *y, *z)))
        }
        _ => Err(format!(
            "`{s}`: expected NAME=X,Y,Z with three numbers (mm)"
        )),
    }
}

/// An arm's own reflector positions (`--left-reflector`), in the order of the dataset's `names`:
/// every name once, no other.
fn arm_reflectors(
    side: crate::side::Side,
    given: &[(String, nalgebra::Vector3<f64>)],
    names: &[String],
) -> Result<Option<Vec<nalgebra::Vector3<f64>>>> {
    if given.is_empty() {
        return Ok(None);
    }
    for (k, (name, _)) in given.iter().enumerate() {
        if !names.contains(name) || given[..k].iter().any(|(n, _)| n == name) {
            anyhow::bail!(
                "--{side}-reflector {name}=…: give each of the dataset's reflectors ({}) once",
                names.join(", ")
            );
        }
    }
    names
        .iter()
        .map(|n| {
            given
                .iter()
                .find(|(g, _)| g == n)
                .map(|(_, p)| *p)
                .ok_or_else(|| {
                    anyhow::anyhow!("--{side}-reflector: no position for reflector `{n}`")
                })
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// `dualcal import`: read the files, print the robot and the report, check the joint limits, write.
pub fn run(a: &ImportArgs) -> Result<()> {
    use crate::import::{self, ArmFiles, ImportOptions};
    let robot = match &a.robot {
        Some(path) => RobotDescription::load(
            path.as_path(),
            &LoadOptions {
                arms: PerSide::new(a.left_links.clone(), a.right_links.clone()),
                ..Default::default()
            },
        )?,
        None => RobotDescription::builtin_irb14000(),
    };
    for w in &robot.warnings {
        eprintln!("warning: {w}");
    }
    let (names, positions): (Vec<String>, Vec<nalgebra::Vector3<f64>>) = if a.reflectors.is_empty()
    {
        let defaults = simulate::default_reflectors_for(&robot);
        eprintln!(
            "note: no --reflector given: reflectors a, b, c at the paper's nominal positions (mm, tip \
             frame) {}",
            defaults
                .iter()
                .map(|p| format!("({}, {}, {})", p.x, p.y, p.z))
                .collect::<Vec<_>>()
                .join(", ")
        );
        (
            crate::kinematics::default_reflector_names(3).to_vec(),
            defaults.to_vec(),
        )
    } else {
        a.reflectors.iter().cloned().unzip()
    };
    let own = PerSide::new(&a.left_reflectors, &a.right_reflectors);
    let arm_reflectors_mm = PerSide::try_from_fn(|side| arm_reflectors(side, own[side], &names))?;
    let mut options = ImportOptions::for_robot(&robot, a.robot.as_deref(), names, positions);
    options.arm_reflectors_mm = arm_reflectors_mm;
    options.points_format = a.points_format;
    options.columns = a.columns.clone();
    options.arm_columns = PerSide::new(a.left_columns.clone(), a.right_columns.clone());
    options.measured_together = a.measured_together;
    options.verify_last = a.verify_last;
    options.length_unit = a.length_unit;
    options.angle_unit = a.angle_unit.map(|u| match u {
        AngleArg::Deg => dataset::AngleUnit::Deg,
        AngleArg::Rad => dataset::AngleUnit::Rad,
    });
    options.decimal_comma = a.decimal_comma;
    options.joint_order = a.joint_order.clone();
    options.matching = a.matching;
    options.time_tolerance_s = a.time_tolerance_s;
    options.sheet = a.sheet.clone();
    options.bag = import::BagOptions {
        topic: a.joint_topic.clone(),
        still_velocity: a.still_velocity,
        still_secs: a.still_secs,
        clock_offset_s: a.clock_offset,
    };
    options.tracker = dataset::TrackerSpec {
        mpe_um: a.mpe_um,
        mpe_um_per_m: a.mpe_um_per_m,
    };
    options.stations = PerSide::new(a.left_station.clone(), a.right_station.clone());
    options.joint_length_unit = a.joint_length_unit.map(|u| match u {
        LengthArg::Mm => dataset::LengthUnit::Mm,
        LengthArg::M => dataset::LengthUnit::M,
    });
    let points = PerSide::new(&a.left_points, &a.right_points);
    let joints = PerSide::new(&a.left_joints, &a.right_joints);
    for side in crate::side::Side::BOTH {
        if points[side].is_none() && joints[side].is_some() {
            anyhow::bail!(
                "--{side}-joints without --{side}-points: give the {side} arm's point file"
            );
        }
    }
    let inputs = PerSide::from_fn(|side| {
        points[side].clone().map(|points| ArmFiles {
            points,
            joints: joints[side].clone(),
        })
    });
    let imported = import::import_arms(&crate::source::OsFiles, &inputs, &options)?;
    outln!("{}", describe_robot(&robot));
    outln!("{}", imported.report);
    // Joint values outside the robot's limits are refused before anything is written.
    let limits = PerSide::from_fn(|s| robot.joint_limits_checked_rad(s));
    dataset::check_joint_limits(&imported.dataset, &limits)?;
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    import::write_arms(&imported, &inputs, &a.out, overwrite)?;
    let counts = match imported.dataset.measured_sides().as_slice() {
        [side] => format!(
            "{} configurations of the {side} arm alone",
            imported.dataset.arms[*side].measurements.len()
        ),
        _ => format!(
            "{} + {} configurations",
            imported.dataset.arms.left.measurements.len(),
            imported.dataset.arms.right.measurements.len()
        ),
    };
    outln!(
        "wrote the dataset {} ({counts}; the report in {})",
        a.out.display(),
        a.out.join(import::REPORT_FILE).display()
    );
    Ok(())
}
