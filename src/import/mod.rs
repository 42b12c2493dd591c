//! Importing tracker and controller files (`dualcal import`): point lists as tracker software writes
//! them (SpatialAnalyzer, Leica Tracker Pilot, figaroh, any CSV with a column mapping), joint logs
//! (CSV/TXT, spreadsheets, ROS 2 bags: the robot's still intervals, the clock offset estimated), the
//! matching of points to configurations (by target name, order or time stamp; repeated shots averaged)
//! and a report of what matched and what did not. The result is a [`Dataset`] that
//! [`write()`] saves as a `dualcal-dataset/1` directory. See docs/formats.md, "Importing tracker and
//! controller files".

pub mod bag;
#[cfg(not(target_arch = "wasm32"))]
mod cdr;
mod error;
pub mod joints;
mod matching;
pub mod points;
#[cfg(not(target_arch = "wasm32"))]
mod ros2;
pub mod sheet;
pub mod text;

pub use bag::BagOptions;
pub use error::ImportError;
pub use joints::{JointLog, JointLogOptions, JointRow, YUMI_ABB_ORDER, parse_joint_order};
pub use points::{ColumnMap, ConfigRow, Point, PointFile, PointTable, PointsFormat};
pub use text::PointUnit;

use crate::dataset::{
    self, AngleUnit, ArmData, ArmLinks, Dataset, LengthUnit, MANIFEST_FILE, Measurement, Split,
    TrackerSpec, Units,
};
use crate::kinematics::SharedJoints;
use crate::output::{FileError, OutputError, Overwrite, refuse_overwrite_input, write_atomic};
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};
use crate::source::FileSource;
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How points are matched to the joint log's configurations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MatchRule {
    /// By name where the target names carry the joint log's configuration ids, else by time where
    /// both files have time stamps, else by order where the counts agree (the report says which and
    /// why; counts that disagree are an error saying where the two sequences part).
    #[default]
    Auto,
    /// Target names `<id>_<reflector>` (`L012_a`) against the joint log's ids.
    Name,
    /// The points in file order, one group of every reflector (in the dataset's order) per
    /// configuration of the joint log; consecutive shots within 1 mm of each other are one shot
    /// repeated (averaged).
    Order,
    /// Each point to the configuration with the nearest time stamp within the tolerance; the reflector
    /// from a name's `_<reflector>` suffix, else by order within the configuration.
    Time,
}

impl crate::choice::Choice for MatchRule {
    const WHAT: &'static str = "matching rule";

    fn all() -> &'static [Self] {
        &[
            MatchRule::Auto,
            MatchRule::Name,
            MatchRule::Order,
            MatchRule::Time,
        ]
    }

    fn spelling(self) -> &'static str {
        match self {
            MatchRule::Auto => "auto",
            MatchRule::Name => "name",
            MatchRule::Order => "order",
            MatchRule::Time => "time",
        }
    }

    fn help(self) -> Option<&'static str> {
        Some(match self {
            MatchRule::Auto => {
                "By name where the target names carry the joint log's configuration ids, else by \
                 time where both files have time stamps, else by order where the counts agree (the \
                 report says which and why; counts that disagree are an error saying where the two \
                 sequences part)"
            }
            MatchRule::Name => {
                "Target names `<id>_<reflector>` (`L012_a`) against the joint log's ids"
            }
            MatchRule::Order => {
                "The points in file order, one group of every reflector (in the dataset's order) \
                 per configuration of the joint log; consecutive shots within 1 mm of each other \
                 are one shot repeated (averaged)"
            }
            MatchRule::Time => {
                "Each point to the configuration with the nearest time stamp within the tolerance; \
                 the reflector from a name's `_<reflector>` suffix, else by order within the \
                 configuration"
            }
        })
    }
}

crate::choice_strings!(MatchRule);

/// One arm's input files.
#[warn(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub struct ArmFiles {
    /// The point file (tracker export).
    pub points: PathBuf,
    /// `None`: the point file gives the joints (figaroh, or a mapping with joint columns).
    pub joints: Option<PathBuf>,
}

/// Everything an import is told besides the files.
#[warn(missing_docs)]
#[derive(Clone, Debug)]
pub struct ImportOptions {
    /// `None`: recognised from each file.
    pub points_format: Option<PointsFormat>,
    /// The generic format's column mapping.
    pub columns: Option<ColumnMap>,
    /// An arm's own mapping, in place of `columns` for that arm (`--left-columns`,
    /// `--right-columns`: both arms in one file, each with its columns or elements).
    pub arm_columns: PerSide<Option<ColumnMap>>,
    /// The unit of point files that do not state theirs (`None`: mm; m for figaroh).
    pub length_unit: Option<PointUnit>,
    /// The unit of joint logs (`None`: the header's `[deg]`/`[rad]`, else degrees) and of a mapping's
    /// joint columns (`None`: degrees).
    pub angle_unit: Option<AngleUnit>,
    /// Numbers with a decimal comma (`1234,56`; fields then separated by `;`, tabs or spaces).
    pub decimal_comma: bool,
    /// Chain joint k is the joint log's joint column `joint_order[k]` (1-based).
    pub joint_order: Option<Vec<usize>>,
    /// How points find their configuration.
    pub matching: MatchRule,
    /// `MatchRule::Time`: the largest time difference between a point and its configuration.
    pub time_tolerance_s: f64,
    /// The dataset's reflectors: names (target suffixes) and nominal positions in the tip frame, mm.
    pub reflector_names: Vec<String>,
    /// The reflectors' nominal positions in the tip frame, mm, in the order of `reflector_names`.
    pub nominal_reflectors_mm: Vec<Vector3<f64>>,
    /// An arm's own nominal reflector positions (markers that sit differently on each hand), in the
    /// order of `reflector_names`, mm: the dataset's `[[arms]] reflectors`.
    pub arm_reflectors_mm: PerSide<Option<Vec<Vector3<f64>>>>,
    /// The tracker's maximum permissible error (the dataset's `[tracker]`).
    pub tracker: TrackerSpec,
    /// Each arm's joints in chain order (from the robot description): counts checked, figaroh's
    /// columns and named log columns put in chain order.
    pub joint_names: PerSide<Option<Vec<String>>>,
    /// The dataset's robot description (`None`: the built-in IRB 14000) and arm chains.
    pub robot: Option<PathBuf>,
    /// The arms' chains the dataset names (with `robot`).
    pub links: PerSide<Option<ArmLinks>>,
    /// The tracker station each arm was measured from.
    pub stations: PerSide<Option<String>>,
    /// Which of each arm's joints (chain order) are prismatic (from the robot description; empty:
    /// all revolute): their values are lengths, read with `joint_length_unit`.
    pub linear_joints: PerSide<Vec<bool>>,
    /// The unit of prismatic joints' values in the joint logs and mapped joint columns (`None`: mm;
    /// m for figaroh, which writes the URDF's units).
    pub joint_length_unit: Option<LengthUnit>,
    /// Both hands were measured at one instant (the dataset's `measured_together`): a left and a
    /// right configuration with one id are one pose, so the joints both arms share have one value
    /// in them (checked as the loader does). Ids made up for files without ids are then the same
    /// on both arms (`C001`, …) rather than `L001`/`R001`.
    pub measured_together: bool,
    /// The joints both arms share (from the robot description; a torso): what `measured_together`
    /// checks.
    pub shared_joints: SharedJoints,
    /// The last N configurations of each arm, in file order, are verification (`ver`), the others
    /// calibration (`cal`), whatever the files say. `None`: the files' splits, else `cal`.
    pub verify_last: Option<usize>,
    /// The sheet of spreadsheet joint logs (`None`: the first).
    pub sheet: Option<String>,
    /// ROS 2 bags (`.mcap` joint logs): the topic, the still intervals' thresholds, the clock offset.
    pub bag: BagOptions,
}

impl ImportOptions {
    /// The defaults with these reflectors.
    pub fn new(reflector_names: Vec<String>, nominal_reflectors_mm: Vec<Vector3<f64>>) -> Self {
        Self {
            points_format: None,
            columns: None,
            length_unit: None,
            angle_unit: None,
            decimal_comma: false,
            joint_order: None,
            matching: MatchRule::Auto,
            time_tolerance_s: 0.5,
            reflector_names,
            nominal_reflectors_mm,
            tracker: TrackerSpec::default(),
            joint_names: PerSide::new(None, None),
            robot: None,
            links: PerSide::new(None, None),
            stations: PerSide::new(None, None),
            linear_joints: PerSide::new(Vec::new(), Vec::new()),
            joint_length_unit: None,
            arm_columns: PerSide::new(None, None),
            arm_reflectors_mm: PerSide::new(None, None),
            measured_together: false,
            shared_joints: SharedJoints::default(),
            verify_last: None,
            sheet: None,
            bag: BagOptions::default(),
        }
    }
}

impl ImportOptions {
    /// The defaults for a dataset of `robot` with these reflectors: each arm's joint names (counts
    /// checked, named columns put in chain order) and prismatic joints from the description; the
    /// dataset refers to `robot_path` and the arms' chains where the robot is a file (`None`: the
    /// built-in IRB 14000).
    pub fn for_robot(
        robot: &RobotDescription,
        robot_path: Option<&Path>,
        reflector_names: Vec<String>,
        nominal_reflectors_mm: Vec<Vector3<f64>>,
    ) -> Self {
        let mut options = Self::new(reflector_names, nominal_reflectors_mm);
        options.joint_names = PerSide::from_fn(|s| Some(robot.arm_joint_names(s)));
        if let Some(path) = robot_path {
            options.robot = Some(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()));
            options.links = PerSide::from_fn(|s| Some(robot.arm(s).links.clone()));
        }
        options.linear_joints = PerSide::from_fn(|s| robot.arm(s).linear_joints());
        options.shared_joints = robot.shared_joints();
        options
    }
}

/// A point or configuration that was not used, and why.
#[warn(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub struct Unmatched {
    /// The target name (or `#k`, the point's place in the file) or the configuration id.
    pub name: String,
    /// The file it is in.
    pub file: PathBuf,
    /// Its line (1-based).
    pub line: usize,
    /// Why it was not used.
    pub reason: String,
}

/// Several shots of one reflector in one configuration, averaged.
#[warn(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub struct RepeatedShots {
    /// The configuration's id.
    pub id: String,
    /// The reflector's name.
    pub reflector: String,
    /// How many shots were averaged.
    pub shots: usize,
    /// The largest distance of a shot from their mean, mm.
    pub spread_mm: f64,
    /// The lines of the shots in the point file.
    pub lines: Vec<usize>,
}

/// What one arm's import did.
#[warn(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub struct ArmReport {
    /// The arm.
    pub side: Side,
    /// Its point file.
    pub points_file: PathBuf,
    /// Its joint log (`None`: the point file gave the joints).
    pub joints_file: Option<PathBuf>,
    /// The point file's format (recognised or forced).
    pub format: PointsFormat,
    /// The point file's length unit.
    pub length_unit: PointUnit,
    /// The working frame named in the point file's header.
    pub frame: Option<String>,
    /// The joint log's unit and order, when there is a log.
    pub angle_unit: Option<AngleUnit>,
    /// The joint log's column order (`None`: chain order).
    pub joint_order: Option<String>,
    /// Points (or configuration rows) in the point file.
    pub points_read: usize,
    /// Configurations in the joint log (or rows of the point file without one).
    pub configurations_read: usize,
    /// Configurations of the dataset.
    pub matched: usize,
    /// Points that found no configuration, and why.
    pub unmatched_points: Vec<Unmatched>,
    /// Configurations of the joint log that got no points, and why.
    pub unmatched_configurations: Vec<Unmatched>,
    /// Reflectors shot more than once in a configuration (averaged).
    pub repeated: Vec<RepeatedShots>,
    /// What the import worked out and how (the matching rule chosen, units, …).
    pub notes: Vec<String>,
}

/// What an import did, per arm (`None`: the arm was not imported — a dataset of one arm).
#[warn(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    /// Each arm's report.
    pub arms: PerSide<Option<ArmReport>>,
}

impl ImportReport {
    /// The reports of the arms imported, left first.
    pub fn imported(&self) -> impl Iterator<Item = &ArmReport> {
        self.arms.values().filter_map(Option::as_ref)
    }
}

/// The result of an import: the dataset (its arms' `file` are the joint logs, or the point files, so
/// that messages about its rows name the input) and the report.
#[warn(missing_docs)]
#[derive(Clone, Debug)]
pub struct Imported {
    /// The imported measurements.
    pub dataset: Dataset,
    /// What matched and what did not.
    pub report: ImportReport,
}

/// Import both arms (files read through `files`).
pub fn import(
    files: &dyn FileSource,
    inputs: &PerSide<ArmFiles>,
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    import_arms(files, &both(inputs), options)
}

/// Both arms' files as [`import_arms`] takes them.
fn both(inputs: &PerSide<ArmFiles>) -> PerSide<Option<ArmFiles>> {
    PerSide::from_fn(|side| Some(inputs[side].clone()))
}

/// Import the arms whose files are given (`None`: the arm was not measured): both, or one alone —
/// the dataset's one-arm form (one `[[arms]]` entry).
pub fn import_arms(
    files: &dyn FileSource,
    inputs: &PerSide<Option<ArmFiles>>,
    options: &ImportOptions,
) -> Result<Imported, ImportError> {
    check_options(options)?;
    let given: Vec<Side> = Side::BOTH
        .into_iter()
        .filter(|&s| inputs[s].is_some())
        .collect();
    match given.as_slice() {
        [] => {
            return Err(ImportError::Options(
                "no point file: give one arm's point file (a dataset of that arm alone) or both \
                 arms'"
                    .to_string(),
            ));
        }
        [side] if options.measured_together => {
            return Err(ImportError::Options(format!(
                "both hands measured together, but only the {side} arm's files are given"
            )));
        }
        _ => {}
    }
    let arms = PerSide::try_from_fn(|side| {
        inputs[side]
            .as_ref()
            .map(|input| import_arm(files, side, input, options))
            .transpose()
    })?;
    let mut data = PerSide::from_fn(|side| {
        arms[side]
            .as_ref()
            .map_or_else(|| ArmData::not_measured(side), |a| a.0.clone())
    });
    let mut reports = PerSide::from_fn(|side| arms[side].as_ref().map(|a| a.1.clone()));
    if let Some(n) = options.verify_last {
        for side in Side::BOTH {
            if let Some(report) = &mut reports[side] {
                verify_last(&mut data[side], n, report)?;
            }
        }
    }
    let dataset = Dataset {
        dir: PathBuf::new(),
        robot: options.robot.clone(),
        tracker: options.tracker,
        nominal_reflectors_mm: options.nominal_reflectors_mm.clone(),
        reflector_names: options.reflector_names.clone().into(),
        arms: data,
        measured_together: options.measured_together,
    };
    if options.measured_together {
        // What the loader refuses, refused here with the input files' lines (values shown in the
        // files' units).
        let units = Units {
            length: options.joint_length_unit.unwrap_or(LengthUnit::Mm),
            angle: options.angle_unit.unwrap_or(AngleUnit::Deg),
        };
        dataset::check_measured_together(&dataset, &options.shared_joints, units)?;
    }
    Ok(Imported {
        dataset,
        report: ImportReport { arms: reports },
    })
}

/// `--verify-last n`: the arm's last `n` configurations (file order) `ver`, the others `cal`.
fn verify_last(arm: &mut ArmData, n: usize, report: &mut ArmReport) -> Result<(), ImportError> {
    let count = arm.measurements.len();
    if n >= count {
        return Err(ImportError::Content {
            path: arm.file.clone(),
            message: format!(
                "--verify-last {n}: the {} arm has {count} configurations, so none would be left \
                 to calibrate with; give a number below {count}",
                arm.side
            ),
        });
    }
    for (k, m) in arm.measurements.iter_mut().enumerate() {
        m.split = if k + n >= count {
            Split::Ver
        } else {
            Split::Cal
        };
    }
    report.notes.push(format!(
        "split: the last {n} of {count} configurations `ver` (--verify-last), the others `cal`"
    ));
    Ok(())
}

fn check_options(o: &ImportOptions) -> Result<(), ImportError> {
    let names = &o.reflector_names;
    if names.is_empty() || names.len() != o.nominal_reflectors_mm.len() {
        return Err(ImportError::Options(format!(
            "{} reflector names for {} nominal reflector positions",
            names.len(),
            o.nominal_reflectors_mm.len()
        )));
    }
    for (side, own) in o.arm_reflectors_mm.iter() {
        if let Some(own) = own
            && own.len() != names.len()
        {
            return Err(ImportError::Options(format!(
                "{} nominal reflector positions of the {side} arm for the dataset's {} reflectors \
                 ({})",
                own.len(),
                names.len(),
                names.join(", ")
            )));
        }
    }
    for (k, n) in names.iter().enumerate() {
        let ok = !n.is_empty()
            && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
            && !n.starts_with(|c: char| c.is_ascii_digit());
        if !ok {
            return Err(ImportError::Options(format!(
                "reflector name `{n}`: expected letters, digits or `-`, starting with a letter \
                 (the target suffix `_{n}` and the CSV columns `{n}x`, … use it)"
            )));
        }
        if names[..k].contains(n) {
            return Err(ImportError::Options(format!("reflector `{n}` named twice")));
        }
    }
    if !(o.time_tolerance_s >= 0.0 && o.time_tolerance_s.is_finite()) {
        return Err(ImportError::Options(format!(
            "time tolerance {} s: expected a finite number ≥ 0",
            o.time_tolerance_s
        )));
    }
    Ok(())
}

type ArmOut = (ArmData, ArmReport);

fn import_arm(
    files: &dyn FileSource,
    side: Side,
    input: &ArmFiles,
    o: &ImportOptions,
) -> Result<ArmOut, ImportError> {
    let joint_names = o.joint_names[side].as_deref();
    let (text, encoding) = text::read_noted(files, &input.points)?;
    let read_options = points::ReadOptions {
        format: o.points_format,
        unit: o.length_unit,
        decimal_comma: o.decimal_comma,
        columns: o.arm_columns[side].as_ref().or(o.columns.as_ref()),
        reflector_names: &o.reflector_names,
        joint_names,
        angle_unit: o.angle_unit.unwrap_or(AngleUnit::Deg),
    };
    let pf = points::read(&input.points, &text, &read_options)?;
    let prefix = id_prefix(side, o.measured_together);
    let log = match &input.joints {
        Some(path) => Some(read_log(files, path, o, joint_names, prefix, &pf.table)?),
        None => None,
    };
    let mut report = ArmReport {
        side,
        points_file: input.points.clone(),
        joints_file: input.joints.clone(),
        format: pf.format,
        length_unit: pf.unit,
        frame: pf.frame.clone(),
        angle_unit: log.as_ref().map(|l| l.angle_unit),
        joint_order: log.as_ref().map(|l| l.order.clone()),
        points_read: 0,
        configurations_read: 0,
        matched: 0,
        unmatched_points: Vec::new(),
        unmatched_configurations: Vec::new(),
        repeated: Vec::new(),
        notes: encoding
            .into_iter()
            .chain(pf.notes.iter().cloned())
            .collect(),
    };
    if let Some(log) = &log {
        report.notes.extend(log.notes.iter().cloned());
        report.configurations_read = log.rows.len();
    }
    let measurements = match (&pf.table, &log) {
        (PointTable::Points(pts), Some(log)) => {
            report.points_read = pts.len();
            matching::match_points(
                &input.points,
                input.joints.as_deref(),
                pts,
                log,
                o,
                &mut report,
            )?
        }
        (PointTable::Points(_), None) => {
            return Err(ImportError::Options(format!(
                "{}: a list of points without joint values: give the {side} arm's joint log \
                 (--{side}-joints)",
                input.points.display()
            )));
        }
        (PointTable::Rows(rows), log) => {
            report.points_read = rows.len();
            if log.is_none() {
                report.configurations_read = rows.len();
            }
            matching::match_rows(
                &input.points,
                rows,
                log.as_ref(),
                o,
                prefix,
                joint_names,
                &mut report,
            )?
        }
    };
    report.matched = measurements.len();
    let file = input.joints.clone().unwrap_or_else(|| input.points.clone());
    let mut arm = ArmData {
        side,
        file,
        links: o.links[side].clone(),
        station: o.stations[side].clone(),
        linear_joints: Vec::new(),
        nominal_reflectors_mm: o.arm_reflectors_mm[side].clone(),
        measurements,
    };
    // The readers convert every joint value with the angle unit; a prismatic joint's value is a
    // length, converted again here with the units the joint values were written in.
    let mut units = joint_value_units(pf.format, log.as_ref(), o);
    if input.joints.as_deref().is_some_and(bag::is_bag) {
        // ROS's units: a bag's prismatic joints are in metres.
        units.length = LengthUnit::M;
    }
    arm.set_linear_joints(&o.linear_joints[side], units)?;
    Ok((arm, report))
}

/// The units an arm's joint values were written in: angles in the joint log's unit, else radians in
/// a FIGAROH file, else the options' (degrees unless given); lengths as the options say, else metres
/// in a FIGAROH file and millimetres otherwise.
fn joint_value_units(format: PointsFormat, log: Option<&JointLog>, o: &ImportOptions) -> Units {
    let figaroh = format == PointsFormat::Figaroh;
    Units {
        length: o.joint_length_unit.unwrap_or(if figaroh {
            LengthUnit::M
        } else {
            LengthUnit::Mm
        }),
        angle: match log {
            Some(log) => log.angle_unit,
            None if figaroh => AngleUnit::Rad,
            None => o.angle_unit.unwrap_or(AngleUnit::Deg),
        },
    }
}

/// A joint log: a ROS 2 bag or a spreadsheet (by its extension; a bag's still intervals matched in
/// time to `table`'s shots), or CSV/TXT.
fn read_log(
    files: &dyn FileSource,
    path: &Path,
    o: &ImportOptions,
    joint_names: Option<&[String]>,
    prefix: &str,
    table: &PointTable,
) -> Result<JointLog, ImportError> {
    let log_options = JointLogOptions {
        angle_unit: o.angle_unit,
        joint_order: o.joint_order.as_deref(),
        joint_names,
        decimal_comma: o.decimal_comma,
        id_prefix: prefix,
    };
    if bag::is_bag(path) {
        read_bag(files, path, o, &log_options, table)
    } else if sheet::is_sheet(path) {
        sheet::read(files, path, o.sheet.as_deref(), &log_options)
    } else {
        // The encoding, when guessed (not UTF-8: Windows-1252), noted as for point files.
        let (text, encoding) = text::read_noted(files, path)?;
        let mut log = joints::read(path, &text, &log_options)?;
        log.notes.splice(0..0, encoding);
        Ok(log)
    }
}

/// Read a bag's still intervals as a joint log, matched in time to the point file's shots
/// (`table`).
#[cfg(not(target_arch = "wasm32"))]
fn read_bag(
    files: &dyn FileSource,
    path: &Path,
    o: &ImportOptions,
    log_options: &JointLogOptions,
    table: &PointTable,
) -> Result<JointLog, ImportError> {
    ros2::read(files, path, o, log_options, table)
}

/// In a browser: no bag reader in the module (its size budget).
#[cfg(target_arch = "wasm32")]
fn read_bag(
    _files: &dyn FileSource,
    path: &Path,
    _o: &ImportOptions,
    _log_options: &JointLogOptions,
    _table: &PointTable,
) -> Result<JointLog, ImportError> {
    Err(ImportError::Format {
        path: path.to_path_buf(),
        message: "ROS 2 bags are read by the desktop workbench and `dualcal import`, not in the \
                  browser: import there, or export the configurations as CSV (`id,q1,…`)"
            .into(),
    })
}

/// The prefix of ids made up for rows without one (`L001`, `R001`): the same on both arms (`C001`)
/// when the rows are poses of both.
fn id_prefix(side: Side, measured_together: bool) -> &'static str {
    match side {
        _ if measured_together => "C",
        Side::Left => "L",
        Side::Right => "R",
    }
}

/// What the dataset reader would refuse on loading the import's result, refused before it is
/// written (by [`write()`] and [`files_of`]): too few configurations matched, reflector distances
/// that do not fit the nominal ones (the unit), degenerate reflector triangles, a row twice — named
/// by the arm's file (its joint log, else its point file) and line. The import itself succeeds, so
/// that its report says what did not match.
pub fn check(imported: &Imported) -> Result<(), ImportError> {
    let ds = &imported.dataset;
    for side in Side::BOTH {
        if imported.report.arms[side].is_some() {
            dataset::check_arm_rows(
                &ds.arms[side],
                ds.nominal_reflectors(side),
                &ds.reflector_names,
            )?;
        }
    }
    if imported.report.arms.values().all(Option::is_some) {
        dataset::check_arms_differ(&ds.arms)?;
    }
    Ok(())
}

/// The files [`write()`] writes into `out` — the dataset's (mm and rad, full precision) and the
/// report — with their contents, written nowhere (a browser keeps them in memory).
pub fn files_of(imported: &Imported, out: &Path) -> Result<Vec<(PathBuf, Vec<u8>)>, ImportError> {
    check(imported)?;
    let mut ds = imported.dataset.clone();
    ds.dir = out.to_path_buf();
    let mut files = dataset::dataset_files(&ds, out, Units::MM_RAD)?;
    files.push((
        out.join(REPORT_FILE),
        imported.report.to_string().into_bytes(),
    ));
    Ok(files)
}

/// The file the report is written to inside the dataset directory.
pub const REPORT_FILE: &str = "import-report.txt";

/// Write an import as a `dualcal-dataset/1` directory `out` (mm and rad, full precision) with the
/// report as [`REPORT_FILE`]. Refuses an existing non-empty `out` unless `overwrite` allows it, and
/// never replaces one of the input files. Each file is written atomically.
pub fn write(
    imported: &Imported,
    inputs: &PerSide<ArmFiles>,
    out: &Path,
    overwrite: Overwrite,
) -> Result<(), ImportError> {
    write_arms(imported, &both(inputs), out, overwrite)
}

/// [`write()`] for an import of the arms whose files are given (one arm alone: a dataset of that arm,
/// one `[[arms]]` entry).
pub fn write_arms(
    imported: &Imported,
    inputs: &PerSide<Option<ArmFiles>>,
    out: &Path,
    overwrite: Overwrite,
) -> Result<(), ImportError> {
    if out.exists() && !out.is_dir() {
        return Err(ImportError::Content {
            path: out.to_path_buf(),
            message: "is a file: the output is a dataset directory".to_string(),
        });
    }
    let non_empty = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
    if non_empty && overwrite == Overwrite::Refuse {
        return Err(OutputError::Exists {
            path: out.to_path_buf(),
        }
        .into());
    }
    let input_paths: Vec<&Path> = inputs
        .values()
        .flatten()
        .flat_map(|f| std::iter::once(f.points.as_path()).chain(f.joints.as_deref()))
        .collect();
    for name in [MANIFEST_FILE, "left.csv", "right.csv", REPORT_FILE] {
        refuse_overwrite_input(&out.join(name), &input_paths)?;
    }
    check(imported)?;
    let mut ds = imported.dataset.clone();
    ds.dir = out.to_path_buf();
    dataset::save_with(&ds, out, Units::MM_RAD, Overwrite::Allow)?;
    let path = out.join(REPORT_FILE);
    write_atomic(&path, imported.report.to_string().as_bytes())
        .map_err(|error| FileError::write(&path, error))?;
    Ok(())
}

impl std::fmt::Display for ImportReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for arm in self.imported() {
            write!(f, "{arm}")?;
        }
        if let [side] = Side::BOTH
            .into_iter()
            .filter(|&s| self.arms[s].is_none())
            .collect::<Vec<_>>()
            .as_slice()
        {
            writeln!(
                f,
                "{side} arm: not imported (a dataset of the {} arm alone)",
                side.other()
            )?;
        }
        Ok(())
    }
}

impl std::fmt::Display for ArmReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} arm: {} ({}, {}{})",
            self.side,
            self.points_file.display(),
            self.format.name(),
            self.length_unit.name(),
            self.frame
                .as_ref()
                .map(|fr| format!(", working frame {fr}"))
                .unwrap_or_default()
        );
        if let Some(j) = &self.joints_file {
            let _ = writeln!(
                s,
                "  joints: {} ({}, {})",
                j.display(),
                self.angle_unit.map_or("rad", AngleUnit::name),
                self.joint_order.as_deref().unwrap_or("chain order")
            );
        }
        let _ = writeln!(
            s,
            "  {} points read, {} configurations read, {} configurations matched",
            self.points_read, self.configurations_read, self.matched
        );
        for n in &self.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        for r in &self.repeated {
            let lines: Vec<String> = r.lines.iter().map(usize::to_string).collect();
            let _ = writeln!(
                s,
                "  repeated: `{}` reflector {}: {} shots averaged, spread {:.4} mm (lines {})",
                r.id,
                r.reflector,
                r.shots,
                r.spread_mm,
                lines.join(", ")
            );
        }
        for u in &self.unmatched_configurations {
            let _ = writeln!(
                s,
                "  unmatched configuration `{}` ({}:{}): {}",
                u.name,
                u.file.display(),
                u.line,
                u.reason
            );
        }
        for u in &self.unmatched_points {
            let _ = writeln!(
                s,
                "  unmatched point `{}` ({}:{}): {}",
                u.name,
                u.file.display(),
                u.line,
                u.reason
            );
        }
        f.write_str(&s)
    }
}
