//! [`Import`]: a [`Dataset`] from tracker exports and the controller's joint logs (`dualcal import`).

use super::dataset::Dataset;
use super::error::Result;
use super::robot::Robot;
use crate::dataset::{AngleUnit, LengthUnit, TrackerSpec};
use crate::import::{ArmFiles, ImportOptions, ImportReport, MatchRule, PointUnit, PointsFormat};
use crate::output::Overwrite;
use crate::quality::ScreenSettings;
use crate::side::{PerSide, Side};
use crate::workspace::Workspace;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// Tracker files to import: per arm a point file (SpatialAnalyzer, Leica Tracker Pilot, figaroh, or
/// any CSV with a column mapping) and the controller's joint log, matched to each other by target
/// name, order or time stamp — what `dualcal import` reads (docs/formats.md, "Importing tracker and
/// controller files"). Options not set are the command line's defaults; [`Import::options`] reaches
/// the rest of them.
///
/// ```
/// # use dualcal::{Import, Robot, Side};
/// # let dir = std::env::temp_dir().join(format!("dualcal-doc-import-{}", std::process::id()));
/// # std::fs::create_dir_all(&dir).unwrap();
/// # let ds = dualcal::Dataset::load(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example"))?;
/// # for side in Side::BOTH {
/// #     let (mut points, mut joints) = (String::new(), String::from("id,q1,q2,q3,q4,q5,q6,q7,split\n"));
/// #     for m in &ds.data().arm(side).measurements {
/// #         for (name, p) in ds.reflector_names().iter().zip(&m.tracker_points_mm) {
/// #             points += &format!("{}_{name} {} {} {}\n", m.id, p.x, p.y, p.z);
/// #         }
/// #         let q: Vec<String> = m.q_rad.iter().map(|q| q.to_degrees().to_string()).collect();
/// #         joints += &format!("{},{},{}\n", m.id, q.join(","), m.split.name());
/// #     }
/// #     std::fs::write(dir.join(format!("{side}.txt")), points).unwrap();
/// #     std::fs::write(dir.join(format!("{side}-joints.csv")), joints).unwrap();
/// # }
/// // SpatialAnalyzer exports (`L001_a x y z`) and joint logs (`id,q1..q7,split`, degrees).
/// let imported = Import::new(&Robot::builtin_irb14000())
///     .arm(Side::Left, dir.join("left.txt"), Some(dir.join("left-joints.csv")))
///     .arm(Side::Right, dir.join("right.txt"), Some(dir.join("right-joints.csv")))
///     .matching(dualcal::import::MatchRule::Name)
///     .run()?;
/// println!("{}", imported.report_text()); // what matched, what did not, and why
/// assert_eq!(imported.dataset().configuration_count(Side::Left), 220);
/// let result = dualcal::Calibration::new(imported.dataset()).max_iterations(5).run()?;
/// # let _ = result;
/// # std::fs::remove_dir_all(&dir).ok();
/// # Ok::<(), dualcal::Error>(())
/// ```
pub struct Import {
    robot: Robot,
    files: PerSide<Option<ArmFiles>>,
    reflectors: Option<(Vec<String>, Vec<Vector3<f64>>)>,
    options: ImportOptions,
}

impl Import {
    /// An import of data measured on `robot` (its joint names, counts, limits and prismatic joints
    /// are checked; a robot from a file is the one the saved dataset refers to). No arm yet.
    pub fn new(robot: &Robot) -> Self {
        Self {
            robot: robot.clone(),
            files: PerSide::new(None, None),
            reflectors: None,
            options: ImportOptions::new(Vec::new(), Vec::new()),
        }
    }

    /// An arm's files: its point file and its joint log (`None`: the point file holds the joints —
    /// figaroh, or a mapping with joint columns). Only one arm given: a dataset of that arm alone.
    pub fn arm(mut self, side: Side, points: impl AsRef<Path>, joints: Option<PathBuf>) -> Self {
        self.files[side] = Some(ArmFiles {
            points: points.as_ref().to_path_buf(),
            joints,
        });
        self
    }

    /// The reflectors: names (the targets' `_<name>` suffixes) and nominal positions in the tip
    /// (flange) frame, mm, in order. Default: `a`, `b`, `c` at the paper's positions (turned to the
    /// robot's tool axis), as `dualcal import` without `--reflector`.
    pub fn reflectors<S: Into<String>>(
        mut self,
        reflectors: impl IntoIterator<Item = (S, [f64; 3])>,
    ) -> Self {
        let (names, positions) = reflectors
            .into_iter()
            .map(|(n, p)| (n.into(), Vector3::from(p)))
            .unzip();
        self.reflectors = Some((names, positions));
        self
    }

    /// How points find their configuration ([`MatchRule::Auto`] by default: by name where the target
    /// names carry the joint log's ids, else by time, else by order where the counts agree).
    pub fn matching(mut self, rule: MatchRule) -> Self {
        self.options.matching = rule;
        self
    }

    /// With [`MatchRule::Time`]: the largest time difference between a point and its configuration,
    /// s (default 0.5).
    pub fn time_tolerance_s(mut self, seconds: f64) -> Self {
        self.options.time_tolerance_s = seconds;
        self
    }

    /// The point files' format (default: recognised from each file).
    pub fn points_format(mut self, format: PointsFormat) -> Self {
        self.options.points_format = Some(format);
        self
    }

    /// The length unit of point files that do not state theirs (default: mm; m for figaroh).
    pub fn length_unit(mut self, unit: PointUnit) -> Self {
        self.options.length_unit = Some(unit);
        self
    }

    /// The joint logs' angle unit (default: the header's `[deg]`/`[rad]`, else degrees).
    pub fn angle_unit(mut self, unit: AngleUnit) -> Self {
        self.options.angle_unit = Some(unit);
        self
    }

    /// The unit of prismatic joints' values in the joint logs (default: mm; m for figaroh).
    pub fn joint_length_unit(mut self, unit: LengthUnit) -> Self {
        self.options.joint_length_unit = Some(unit);
        self
    }

    /// The last `n` configurations of each arm (file order) are verification, the others
    /// calibration, whatever the files say.
    pub fn verify_last(mut self, n: usize) -> Self {
        self.options.verify_last = Some(n);
        self
    }

    /// The tracker's maximum permissible error (default: the paper's).
    pub fn tracker(mut self, tracker: TrackerSpec) -> Self {
        self.options.tracker = tracker;
        self
    }

    /// Every other option (column mappings, decimal comma, joint order, stations, a sheet of a
    /// spreadsheet, measured together, …): the engine's [`ImportOptions`], changed in place. The
    /// reflectors and the robot's joints are set by [`Import::run`].
    pub fn options(mut self, change: impl FnOnce(&mut ImportOptions)) -> Self {
        change(&mut self.options);
        self
    }

    /// Read and match the files; then the checks the dataset reader makes (at least 4 configurations
    /// per arm, reflector distances that fit the nominal ones, joint limits), the nominal model and
    /// the screening. Errors name the file, line and field.
    pub fn run(self) -> Result<ImportedDataset> {
        let description = self.robot.description();
        let (names, positions) = self.reflectors.clone().unwrap_or_else(|| {
            (
                crate::kinematics::default_reflector_names(3).to_vec(),
                crate::simulate::default_reflectors_for(description).to_vec(),
            )
        });
        let mut options =
            ImportOptions::for_robot(description, self.robot.file(), names, positions);
        let own = self.options;
        options.points_format = own.points_format;
        options.columns = own.columns;
        options.arm_columns = own.arm_columns;
        options.length_unit = own.length_unit;
        options.angle_unit = own.angle_unit;
        options.decimal_comma = own.decimal_comma;
        options.joint_order = own.joint_order;
        options.matching = own.matching;
        options.time_tolerance_s = own.time_tolerance_s;
        options.arm_reflectors_mm = own.arm_reflectors_mm;
        options.tracker = own.tracker;
        options.stations = own.stations;
        options.joint_length_unit = own.joint_length_unit;
        options.measured_together = own.measured_together;
        options.verify_last = own.verify_last;
        options.sheet = own.sheet;
        if self.files.values().all(Option::is_none) {
            return Err(super::Error::Invalid(
                "no files: give the left arm's, the right arm's or both (Import::arm)".into(),
            ));
        }
        let imported = crate::import::import_arms(&crate::source::OsFiles, &self.files, &options)?;
        crate::import::check(&imported)?;
        let workspace = Workspace::new(
            imported.dataset.clone(),
            description.clone(),
            &ScreenSettings::default(),
        )?;
        Ok(ImportedDataset {
            dataset: Dataset { workspace },
            imported,
            files: self.files,
        })
    }
}

/// An import's result: the [`Dataset`], ready to calibrate, and the report of what matched.
#[derive(Clone, Debug)]
pub struct ImportedDataset {
    dataset: Dataset,
    imported: crate::import::Imported,
    files: PerSide<Option<ArmFiles>>,
}

impl ImportedDataset {
    /// The imported measurements with their robot, checked and screened.
    pub fn dataset(&self) -> &Dataset {
        &self.dataset
    }

    /// What each arm's import did: formats and units recognised, points and configurations read and
    /// matched, repeated shots averaged, what did not match and why (file and line).
    pub fn report(&self) -> &ImportReport {
        &self.imported.report
    }

    /// [`ImportedDataset::report`] as `dualcal import` prints it and writes it beside the dataset.
    pub fn report_text(&self) -> String {
        self.imported.report.to_string()
    }

    /// Write the dataset directory `out` (`dataset.toml`, the arms' CSVs in mm and rad, the report
    /// as `import-report.txt`), each file atomically, as `dualcal import --out` does. An existing
    /// non-empty `out` is refused unless `overwrite`; an input file is never replaced.
    pub fn save(&self, out: impl AsRef<Path>, overwrite: bool) -> Result<()> {
        let overwrite = if overwrite {
            Overwrite::Allow
        } else {
            Overwrite::Refuse
        };
        crate::import::write_arms(&self.imported, &self.files, out.as_ref(), overwrite)?;
        Ok(())
    }
}
