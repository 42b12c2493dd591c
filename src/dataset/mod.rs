//! The `dualcal-dataset/1` measurement format: a directory with `dataset.toml` and one CSV per arm.
//! See `docs/formats.md`. Everything is converted to mm and rad on load.

mod csv;
mod error;
mod manifest;
mod save;
mod units;
mod validate;

pub use crate::kinematics::ArmLinks;
pub use crate::output::Overwrite;
use crate::side::{ConfigId, PerSide, Side};
use crate::source::FileSource;
pub use error::DatasetError;
use error::read_text;
use nalgebra::Vector3;
pub use save::{dataset_files, save, save_with};
use std::path::{Path, PathBuf};
use std::sync::Arc;
pub use units::{AngleUnit, LengthUnit, Units};
pub use validate::{
    JOINT_LIMIT_TOLERANCE_RAD, MAX_COORDINATE_MM, MAX_JOINT_RAD, check_arm_rows,
    check_both as check_arms_differ, check_joint_limits, check_measured_together,
};

/// The format tag written in `dataset.toml`.
pub const DATASET_FORMAT: &str = "dualcal-dataset/1";
/// Minimum number of configurations per arm in a dataset, and for a calibration (paper Table 2: 4
/// configurations make the truss rigid).
pub const MIN_CONFIGS: usize = 4;

/// The calibration or verification configurations, or all of them: a measurement's `split` is
/// `Cal` or `Ver`; an operation selects `Cal`, `Ver` or `All`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Cal,
    Ver,
    #[default]
    All,
}

impl crate::choice::Choice for Split {
    const WHAT: &'static str = "split";

    fn all() -> &'static [Self] {
        &[Split::Cal, Split::Ver, Split::All]
    }

    fn spelling(self) -> &'static str {
        self.name()
    }
}

crate::choice_strings!(Split);

impl Split {
    /// Whether a measurement of split `row` belongs to this selection.
    pub fn contains(self, row: Split) -> bool {
        self == Split::All || self == row
    }

    /// The name used in files and on the command line (`cal`, `ver`, `all`).
    pub fn name(self) -> &'static str {
        match self {
            Split::Cal => "cal",
            Split::Ver => "ver",
            Split::All => "all",
        }
    }
}

/// One measured configuration of one arm.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    pub id: String,
    /// Joint values in chain order (the CSV's `q1 … qN`), rad.
    pub q_rad: Vec<f64>,
    /// Measured reflector positions in the tracker frame, mm: one per reflector of the dataset, in
    /// the order of [`Dataset::reflector_names`] (a, b, c in the paper's set-up).
    pub tracker_points_mm: Vec<Vector3<f64>>,
    /// `Cal` or `Ver` (never `All`); rows without a split column are `Cal`.
    pub split: Split,
    /// 1-based line number in the CSV (for messages).
    pub line: usize,
}

/// The tracker's maximum permissible error `mpe_um + mpe_um_per_m · distance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerSpec {
    pub mpe_um: f64,
    pub mpe_um_per_m: f64,
}

impl Default for TrackerSpec {
    /// FARO Vantage, as in the paper: 16 µm + 0.8 µm/m.
    fn default() -> Self {
        Self {
            mpe_um: 16.0,
            mpe_um_per_m: 0.8,
        }
    }
}

/// One arm's measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmData {
    pub side: Side,
    pub file: PathBuf,
    /// The arm's chain in the robot description (`base_link`, `tip_link` in the manifest); `None`:
    /// the description's default arms (the built-in robot, or the YuMi joint names).
    pub links: Option<ArmLinks>,
    /// The tracker station the arm was measured from (`[[arms]] station`): `None` on both arms means
    /// one station, as files without the key.
    pub station: Option<String>,
    /// Which joint columns are lengths — prismatic joints, in mm — rather than angles (rad); empty:
    /// all angles. Set from the robot ([`ArmData::set_linear_joints`]).
    pub linear_joints: Vec<bool>,
    /// The arm's own nominal reflector coordinates in its tip frame (`[[arms]] reflectors`, the
    /// dataset's reflectors in its order), mm; `None`: the dataset's `[reflectors]`
    /// ([`Dataset::nominal_reflectors`]).
    pub nominal_reflectors_mm: Option<Vec<Vector3<f64>>>,
    pub measurements: Vec<Measurement>,
}

impl ArmData {
    /// An arm the dataset has no measurements of (a dataset of the other arm alone).
    pub fn not_measured(side: Side) -> Self {
        Self {
            side,
            file: PathBuf::new(),
            links: None,
            station: None,
            linear_joints: Vec::new(),
            nominal_reflectors_mm: None,
            measurements: Vec::new(),
        }
    }

    /// Was this arm measured? An arm of the dataset has at least four configurations (the loader
    /// checks), so an arm without any is one the dataset does not have ([`ArmData::not_measured`]).
    pub fn is_measured(&self) -> bool {
        !self.measurements.is_empty()
    }

    /// Is joint column `i` (0-based) a prismatic joint's length (mm)?
    pub fn is_linear_joint(&self, i: usize) -> bool {
        self.linear_joints.get(i).copied().unwrap_or(false)
    }

    /// Read the joint columns flagged in `linear` as lengths (prismatic joints, mm) and the others as
    /// angles (rad). The reader converts every joint column with the angle unit, knowing nothing of
    /// the robot; a column whose reading changes is converted back to the file's number with the
    /// unit it was read with and again with the other, `units` being the file's. Checks every value's
    /// magnitude for its kind (file, line and column on failure). Idempotent.
    pub fn set_linear_joints(&mut self, linear: &[bool], units: Units) -> Result<(), DatasetError> {
        let now = |i: usize| linear.get(i).copied().unwrap_or(false);
        let changed: Vec<usize> = (0..self.joint_count())
            .filter(|&i| now(i) != self.is_linear_joint(i))
            .collect();
        if changed.is_empty() {
            return Ok(());
        }
        for m in &mut self.measurements {
            for &i in &changed {
                let Some(v) = m.q_rad.get_mut(i) else {
                    continue;
                };
                let raw = if now(i) {
                    units.angle.from_rad(*v)
                } else {
                    units.length.from_mm(*v)
                };
                *v = if now(i) {
                    units.length.to_mm(raw)
                } else {
                    units.angle.to_rad(raw)
                };
                validate::joint_value_magnitude(*v, now(i)).map_err(|message| {
                    DatasetError::Field {
                        path: self.file.clone(),
                        line: m.line,
                        field: format!("q{}", i + 1),
                        message,
                    }
                })?;
            }
        }
        self.linear_joints = if linear.iter().any(|&b| b) {
            linear.to_vec()
        } else {
            Vec::new()
        };
        Ok(())
    }

    /// Number of joint values per configuration (the CSV's joint columns; every row has as many).
    pub fn joint_count(&self) -> usize {
        self.measurements.first().map_or(0, |m| m.q_rad.len())
    }

    pub fn select(&self, split: Split) -> Vec<&Measurement> {
        self.measurements
            .iter()
            .filter(|m| split.contains(m.split))
            .collect()
    }
}

/// A loaded dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Directory the dataset was loaded from.
    pub dir: PathBuf,
    /// Robot description (resolved path), or `None` for the built-in IRB 14000.
    pub robot: Option<PathBuf>,
    pub tracker: TrackerSpec,
    /// Nominal reflector coordinates in the tip link's frame (the flange for the built-in robot), mm:
    /// one or more, in the order of `reflector_names`.
    pub nominal_reflectors_mm: Vec<Vector3<f64>>,
    /// The reflectors' names (the manifest's `[reflectors]` keys, in its order): `a`, `b`, `c` in the
    /// paper's set-up.
    pub reflector_names: Arc<[String]>,
    pub arms: PerSide<ArmData>,
    /// Both hands were measured at one instant (the manifest's `measured_together = true`): a row of
    /// the left file and a row of the right file with the same id are one pose of the robot, so the
    /// joints both arms share (a torso) have one value in them ([`check_measured_together`]).
    pub measured_together: bool,
}

impl Dataset {
    /// Number of reflectors per arm.
    pub fn reflector_count(&self) -> usize {
        self.nominal_reflectors_mm.len()
    }

    /// Were both arms measured in one tracker frame (one station, or the same station named on both
    /// arms)? Only then do distances between the two arms' reflectors mean anything: step 2 and the
    /// collaborative figures need it.
    pub fn one_tracker_frame(&self) -> bool {
        self.both_measured() && self.arms.left.station == self.arms.right.station
    }

    /// Were both arms measured? A dataset may hold one arm alone (one `[[arms]]` entry).
    pub fn both_measured(&self) -> bool {
        self.arms.values().all(ArmData::is_measured)
    }

    /// Measured together: each instant's (left, right) joint values, the rows of one id in both arms'
    /// files (every split); none otherwise. What the error models of a shared torso take
    /// ([`crate::kinematics::DualArmModel::with_torso_instants`]).
    pub fn instants(&self) -> Vec<(Vec<f64>, Vec<f64>)> {
        if !self.measured_together {
            return Vec::new();
        }
        let right: std::collections::HashMap<&str, &Measurement> = self
            .arms
            .right
            .measurements
            .iter()
            .map(|m| (m.id.as_str(), m))
            .collect();
        self.arms
            .left
            .measurements
            .iter()
            .filter_map(|l| {
                right
                    .get(l.id.as_str())
                    .map(|r| (l.q_rad.clone(), r.q_rad.clone()))
            })
            .collect()
    }

    /// The arms the dataset has measurements of, left first: both, or one alone.
    pub fn measured_sides(&self) -> Vec<Side> {
        Side::BOTH
            .into_iter()
            .filter(|&s| self.arms[s].is_measured())
            .collect()
    }

    /// Why step 2 (the right-arm base) and the collaborative figures cannot be computed from this
    /// data, if they cannot: one arm measured alone, or the arms measured from different tracker
    /// stations (their coordinates unrelated).
    pub fn base_not_measurable(&self) -> Option<String> {
        if let [side] = self.measured_sides().as_slice() {
            return Some(format!("only the {side} arm was measured"));
        }
        (!self.one_tracker_frame()).then(|| {
            format!(
                "the arms were measured from different tracker stations (left `{}`, right `{}`)",
                self.arms.left.station.as_deref().unwrap_or(""),
                self.arms.right.station.as_deref().unwrap_or("")
            )
        })
    }

    /// `side`'s nominal reflector coordinates: its own (`[[arms]] reflectors`), else the dataset's, mm.
    pub fn nominal_reflectors(&self, side: Side) -> &[Vector3<f64>] {
        self.arms[side]
            .nominal_reflectors_mm
            .as_deref()
            .unwrap_or(&self.nominal_reflectors_mm)
    }

    pub fn arm(&self, side: Side) -> &ArmData {
        &self.arms[side]
    }

    /// The same dataset with only the first `n` calibration configurations of each arm (all
    /// verification configurations are kept).
    pub fn with_cal_subset(&self, n: usize) -> Dataset {
        let mut out = self.clone();
        for (_, arm) in out.arms.iter_mut() {
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

    /// The same dataset without the configurations `exclude` (indices into this dataset's arms; the
    /// result's indices are renumbered). For accuracy figures without suspect measurements; a
    /// calibration leaves configurations out with `CalibrationSettings::exclude` instead, which keeps
    /// the indices.
    pub fn excluding(&self, exclude: &[ConfigId]) -> Dataset {
        let mut out = self.clone();
        for (side, arm) in out.arms.iter_mut() {
            let mut index = 0;
            arm.measurements.retain(|_| {
                let keep = !exclude.contains(&ConfigId::new(side, index));
                index += 1;
                keep
            });
        }
        out
    }

    /// The configuration with id `spec` (unique across both arms), or `left:ID` / `right:ID`.
    pub fn config_by_id(&self, spec: &str) -> Result<ConfigId, String> {
        let (sides, id): (Vec<Side>, &str) = match spec.split_once(':') {
            Some(("left", id)) => (vec![Side::Left], id),
            Some(("right", id)) => (vec![Side::Right], id),
            _ => (Side::BOTH.to_vec(), spec),
        };
        let found: Vec<ConfigId> = sides
            .iter()
            .filter_map(|&side| {
                let index = self
                    .arm(side)
                    .measurements
                    .iter()
                    .position(|m| m.id == id)?;
                Some(ConfigId::new(side, index))
            })
            .collect();
        match found.as_slice() {
            [one] => Ok(*one),
            [] => Err(format!(
                "no configuration with id `{}`",
                crate::textfile::excerpt(id)
            )),
            _ => Err(format!(
                "both arms have a configuration `{}`: write left:{0} or right:{0}",
                crate::textfile::excerpt(id)
            )),
        }
    }

    /// The files the dataset was read from: the manifest and both CSVs.
    pub fn files(&self) -> [PathBuf; 3] {
        [
            self.dir.join(MANIFEST_FILE),
            self.arms.left.file.clone(),
            self.arms.right.file.clone(),
        ]
    }
}

/// The CSV columns of an arm with `joints` joints and the reflectors `reflectors`, in order (`split`,
/// optional, comes last): `id, q1 … qN, ax, ay, az, bx, by, bz, cx, cy, cz` for a, b, c.
pub fn csv_columns(joints: usize, reflectors: &[String]) -> Vec<String> {
    csv::columns(joints, reflectors)
}
/// The optional last CSV column.
pub const SPLIT_COLUMN: &str = "split";

/// Resolve a dataset path (its directory or its manifest) into (directory, manifest path).
fn resolve(files: &dyn FileSource, path: &Path) -> (PathBuf, PathBuf) {
    if files.is_dir(path) {
        (path.to_path_buf(), path.join(MANIFEST_FILE))
    } else {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        (dir, path.to_path_buf())
    }
}

/// The manifest's file name inside a dataset directory.
pub const MANIFEST_FILE: &str = "dataset.toml";

/// Load a dataset from its directory or from the path of its `dataset.toml`.
pub fn load(path: &Path) -> Result<Dataset, DatasetError> {
    load_with_units(path).map(|(d, _)| d)
}

/// Like [`load`], also returning the units the files were written in (to save back in the same units).
pub fn load_with_units(path: &Path) -> Result<(Dataset, Units), DatasetError> {
    load_from(&crate::source::OsFiles, path)
}

/// Like [`load_with_units`], reading the files through `files` (the file system, or files in memory:
/// a browser's uploads).
pub fn load_from(files: &dyn FileSource, path: &Path) -> Result<(Dataset, Units), DatasetError> {
    load_from_with(files, path, |_| ()).map(|(dataset, units, ())| (dataset, units))
}

/// [`load_from`], running `beside` on the work pool while the arms' files are read, given the
/// manifest's `robot` entry (the loader of a workspace parses the robot description meanwhile).
pub fn load_from_with<R: Send>(
    files: &dyn FileSource,
    path: &Path,
    beside: impl FnOnce(Option<&Path>) -> R + Send,
) -> Result<(Dataset, Units, R), DatasetError> {
    let (dir, manifest_path) = resolve(files, path);
    let text = read_text(files, &manifest_path)?;
    let mut m = manifest::parse(files, &manifest_path, &dir, &text)?;
    let arms = std::mem::replace(&mut m.arms, PerSide::new(None, None));
    // The two arms' files side by side (each a few milliseconds at the paper's size).
    let (arms, beside) = crate::par::join(
        || {
            arms.par_try_map(|side, arm| {
                let Some(arm) = arm else {
                    return Ok(ArmData::not_measured(side));
                };
                let measurements = csv::read_arm(
                    files,
                    &arm.file,
                    side,
                    m.units,
                    arm.reflectors_mm.as_ref().unwrap_or(&m.reflectors_mm),
                    &m.reflector_names,
                )?;
                Ok::<_, DatasetError>(ArmData {
                    side,
                    file: arm.file,
                    links: arm.links,
                    station: arm.station,
                    linear_joints: Vec::new(),
                    nominal_reflectors_mm: arm.reflectors_mm,
                    measurements,
                })
            })
        },
        || beside(m.robot.as_deref()),
    );
    let arms = arms?;
    validate::check_both(&arms)?;
    Ok((
        Dataset {
            dir,
            robot: m.robot,
            tracker: m.tracker,
            nominal_reflectors_mm: m.reflectors_mm,
            reflector_names: m.reflector_names.into(),
            arms,
            measured_together: m.measured_together,
        },
        m.units,
        beside,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::OutputError;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_arm(rng: &mut ChaCha8Rng, side: Side, n: usize, n_joints: usize) -> ArmData {
        let measurements = (0..n)
            .map(|i| Measurement {
                // Ids that need CSV quoting must survive too.
                id: match i {
                    0 => "pose, \"first\"".to_string(),
                    1 => "ü-2".to_string(),
                    _ => format!("{side}{i}"),
                },
                q_rad: (0..n_joints).map(|_| rng.random_range(-3.0..3.0)).collect(),
                // The nominal triangle turned and placed at random.
                tracker_points_mm: {
                    let turn =
                        nalgebra::UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| {
                            rng.random_range(-3.0..3.0)
                        }));
                    let centre = Vector3::from_fn(|_, _| rng.random_range(-3000.0..3000.0));
                    crate::simulate::SimOptions::default_reflectors()
                        .map(|p| turn * p + centre)
                        .to_vec()
                },
                split: if rng.random_bool(0.3) {
                    Split::Ver
                } else {
                    Split::Cal
                },
                line: 0,
            })
            .collect();
        ArmData {
            side,
            file: PathBuf::new(),
            links: None,
            station: None,
            linear_joints: Vec::new(),
            nominal_reflectors_mm: None,
            measurements,
        }
    }

    fn random_dataset(seed: u64) -> Dataset {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Dataset {
            dir: PathBuf::new(),
            robot: None,
            tracker: TrackerSpec {
                mpe_um: 10.0,
                mpe_um_per_m: 1.25,
            },
            nominal_reflectors_mm: crate::simulate::SimOptions::default_reflectors()
                .map(|p| p + Vector3::from_fn(|_, _| rng.random_range(-5.0..5.0)))
                .to_vec(),
            reflector_names: crate::kinematics::default_reflector_names(3),
            arms: PerSide::new(
                random_arm(&mut rng, Side::Left, 9, 7),
                random_arm(&mut rng, Side::Right, 7, 7),
            ),
            measured_together: false,
        }
    }

    /// Compare everything but paths and line numbers.
    fn assert_close(a: &Dataset, b: &Dataset, tol_mm: f64, tol_rad: f64) {
        assert_eq!(a.tracker, b.tracker);
        for k in 0..3 {
            assert!((a.nominal_reflectors_mm[k] - b.nominal_reflectors_mm[k]).amax() <= tol_mm);
        }
        for side in Side::BOTH {
            let (x, y) = (a.arm(side), b.arm(side));
            assert_eq!(y.side, side);
            assert_eq!(x.links, y.links);
            assert_eq!(x.measurements.len(), y.measurements.len());
            for (m, n) in x.measurements.iter().zip(&y.measurements) {
                assert_eq!(m.id, n.id);
                assert_eq!(m.split, n.split);
                assert_eq!(m.q_rad.len(), n.q_rad.len());
                for (q, r) in m.q_rad.iter().zip(&n.q_rad) {
                    assert!((q - r).abs() <= tol_rad);
                }
                for k in 0..3 {
                    assert!((m.tracker_points_mm[k] - n.tracker_points_mm[k]).amax() <= tol_mm);
                }
            }
        }
    }

    #[test]
    fn round_trip_in_every_unit() {
        let original = random_dataset(7);
        for length in [LengthUnit::Mm, LengthUnit::M] {
            for angle in [AngleUnit::Rad, AngleUnit::Deg] {
                let units = Units { length, angle };
                let dir = tempfile::tempdir().unwrap();
                let out = dir.path().join("ds");
                save(&original, &out, units).unwrap();
                let (back, read_units) = load_with_units(&out).unwrap();
                assert_eq!(read_units, units);
                assert_eq!(back.dir, out);
                assert_eq!(back.arms.left.file, out.join("left.csv"));
                if units == Units::MM_RAD {
                    // No conversion: bit-exact.
                    assert_close(&original, &back, 0.0, 0.0);
                } else {
                    assert_close(&original, &back, 1e-9, 1e-12);
                }
                // Line numbers point at the rows: comment line 1, header line 2.
                assert_eq!(back.arms.right.measurements[3].line, 6);
            }
        }
    }

    #[test]
    fn arms_of_other_joint_counts_and_their_links_round_trip() {
        let mut d = random_dataset(11);
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        d.arms.left = random_arm(&mut rng, Side::Left, 6, 6);
        d.arms.right = random_arm(&mut rng, Side::Right, 5, 9);
        d.arms.left.links = Some(ArmLinks::new("table", "left_ee_link"));
        d.arms.right.links = Some(ArmLinks::new("right_base_link", "right tool \"x\""));
        let dir = tempfile::tempdir().unwrap();
        save(&d, dir.path(), Units::MM_RAD).unwrap();
        let header = std::fs::read_to_string(dir.path().join("right.csv")).unwrap();
        assert!(
            header.contains("id,q1,q2,q3,q4,q5,q6,q7,q8,q9,ax,"),
            "{header}"
        );
        let back = load(dir.path()).unwrap();
        assert_close(&d, &back, 0.0, 0.0);
        assert_eq!(back.arms.left.joint_count(), 6);
        // Rows of different lengths are refused on save.
        d.arms.left.measurements[1].q_rad.push(0.5);
        assert!(matches!(
            save_with(&d, dir.path(), Units::MM_RAD, Overwrite::Allow),
            Err(DatasetError::Content { .. })
        ));
    }

    #[test]
    fn save_refuses_to_replace_a_dataset_without_the_flag() {
        let d = random_dataset(3);
        let dir = tempfile::tempdir().unwrap();
        save(&d, dir.path(), Units::MM_DEG).unwrap();
        let before = std::fs::read(dir.path().join("left.csv")).unwrap();
        let other = random_dataset(4);
        let err = save(&other, dir.path(), Units::MM_DEG).unwrap_err();
        assert!(matches!(
            err,
            DatasetError::Output(OutputError::Exists { .. })
        ));
        assert_eq!(std::fs::read(dir.path().join("left.csv")).unwrap(), before);
        save_with(&other, dir.path(), Units::MM_DEG, Overwrite::Allow).unwrap();
        let back = load(dir.path()).unwrap();
        assert_close(&other, &back, 1e-9, 1e-12);
    }

    #[test]
    fn save_refuses_unsavable_data_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let mut d = random_dataset(5);
        d.arms.left.measurements[2].q_rad[4] = f64::NAN;
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.arms.right.measurements[1].id = "#hidden".into();
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.arms.right.measurements[1].id = d.arms.right.measurements[2].id.clone();
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.arms.left.measurements.truncate(MIN_CONFIGS - 1);
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::TooFewConfigurations { .. })
        ));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn robot_path_survives_a_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("robot.urdf");
        std::fs::write(&urdf, "<robot/>").unwrap();
        let mut d = random_dataset(9);
        // Outside the output directory: written as an absolute path.
        d.robot = Some(urdf.clone());
        let out = dir.path().join("a");
        save(&d, &out, Units::MM_DEG).unwrap();
        let back = load(&out).unwrap();
        assert_eq!(
            back.robot.unwrap().canonicalize().unwrap(),
            urdf.canonicalize().unwrap()
        );
        // Inside: written relative, so the directory can move.
        d.robot = Some(dir.path().join("robot.urdf"));
        save_with(&d, dir.path(), Units::MM_DEG, Overwrite::Allow).unwrap();
        let text = std::fs::read_to_string(dir.path().join(MANIFEST_FILE)).unwrap();
        assert!(text.contains("robot = \"robot.urdf\""), "{text}");
        assert_eq!(load(dir.path()).unwrap().robot, Some(urdf));
    }
}
