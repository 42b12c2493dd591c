//! The one load pipeline: a dataset and its robot description read, checked against each other, the
//! nominal model built and the measurements screened with it — what `dualcal calibrate`, `dualcal
//! evaluate`, the workbench (and importers and planners) start from.
//!
//! ```text
//! dataset.toml + CSVs ─► dataset::load_from ─┐
//!                                            ├─► joint columns vs the arms' chains (RobotDescription::check_dataset)
//! URDF (or built-in) ─► RobotDescription ────┘   joint values vs the joint limits (dataset::check_joint_limits)
//!                                                 nominal model (RobotDescription::nominal_model)
//!                                                 nominal screening (quality::screen)  ─► Workspace
//! ```
//!
//! Every step's failure is a typed [`LoadError`] naming the file, line and field. The screening's
//! whole-file findings are not errors of the load: a [`Workspace`] with [`Workspace::refusals`] is
//! still shown by the workbench (with the refusals), and refused by the command line.

use crate::dataset::{self, Dataset, DatasetError, Units};
use crate::kinematics::DualArmModel;
use crate::meshes::PackageMap;
use crate::quality::{self, Finding, ScreenSettings, Screening, Severity};
use crate::robot::{
    ArmLinks, LoadOptions as RobotOptions, RobotDescription, RobotError, RobotSource,
};
use crate::side::{PerSide, Side};
use crate::source::Files;
use std::path::{Path, PathBuf};

/// How to load a [`Workspace`].
#[derive(Clone, Debug, Default)]
pub struct WorkspaceOptions {
    /// The robot description to use instead of the dataset's `robot` entry (`None`: the dataset's, or
    /// the built-in IRB 14000).
    pub robot: Option<PathBuf>,
    /// Each arm's chain, where the dataset gives none (`None`: the dataset's, or the YuMi names).
    pub arms: PerSide<Option<ArmLinks>>,
    /// Where `package://` meshes are (tried first).
    pub packages: PackageMap,
    /// Where the files are read from (default: the file system).
    pub files: Files,
    /// Thresholds of the nominal screening.
    pub screen: ScreenSettings,
}

/// Why a dataset and its robot could not be loaded together.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The dataset's manifest or CSVs (file, line, field).
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The robot description (file, line, joint), or its arms against the dataset's joint columns.
    #[error("loading the robot of {}", .dataset_dir.display())]
    Robot {
        dataset_dir: PathBuf,
        #[source]
        source: RobotError,
    },
    /// A joint value outside the robot's limits (file, line, column).
    #[error(transparent)]
    JointLimits(DatasetError),
}

/// A dataset with its robot description, checked against each other, the nominal model and the
/// nominal screening.
#[derive(Clone, Debug)]
pub struct Workspace {
    pub dataset: Dataset,
    pub robot: RobotDescription,
    /// The description's own model: Table 3 for the built-in robot, the URDF's chains otherwise, with
    /// the dataset's nominal reflectors.
    pub nominal: DualArmModel,
    /// The configurations screened with the nominal model ([`quality::screen`]).
    pub screening: Screening,
}

impl Workspace {
    /// Load the dataset at `dataset_path` (its directory or its `dataset.toml`) and its robot.
    pub fn load(dataset_path: &Path, options: &WorkspaceOptions) -> Result<Self, LoadError> {
        // The built-in robot's description (parsed once per process) parsed while the measurements
        // are read, when the dataset names no robot of its own.
        let (dataset, units, ()) =
            dataset::load_from_with(&*options.files, dataset_path, |robot| {
                if options.robot.is_none() && robot.is_none() {
                    RobotDescription::builtin_parsed();
                }
            })?;
        let robot = RobotDescription::load(
            RobotSource::Dataset {
                dataset: &dataset,
                robot: options.robot.as_deref(),
            },
            &RobotOptions {
                arms: options.arms.clone(),
                packages: options.packages.clone(),
                files: options.files.clone(),
            },
        )
        .map_err(|source| LoadError::Robot {
            dataset_dir: dataset.dir.clone(),
            source,
        })?;
        Self::from_loaded(dataset, units, robot, &options.screen)
    }

    /// A dataset read in `units` (its joint columns as read: angles) and the robot description
    /// compiled for it: the prismatic joints' columns made lengths, then checked against each other,
    /// the nominal model, screened.
    pub fn from_loaded(
        mut dataset: Dataset,
        units: Units,
        robot: RobotDescription,
        screen: &ScreenSettings,
    ) -> Result<Self, LoadError> {
        // A prismatic joint's column holds a length (the file's length unit), known now.
        for side in Side::BOTH {
            let linear = robot.arm(side).linear_joints();
            dataset.arms[side].set_linear_joints(&linear, units)?;
        }
        Self::checked(dataset, robot, screen, units)
    }

    /// A dataset and a robot description already in hand (simulated, imported, compiled in): checked
    /// against each other, the nominal model, screened.
    pub fn new(
        dataset: Dataset,
        robot: RobotDescription,
        screen: &ScreenSettings,
    ) -> Result<Self, LoadError> {
        Self::checked(dataset, robot, screen, Units::MM_RAD)
    }

    /// [`Workspace::new`], messages about joint values in `units` (the files', when loaded).
    fn checked(
        dataset: Dataset,
        robot: RobotDescription,
        screen: &ScreenSettings,
        units: Units,
    ) -> Result<Self, LoadError> {
        robot
            .check_dataset(&dataset)
            .map_err(|source| LoadError::Robot {
                dataset_dir: dataset.dir.clone(),
                source,
            })?;
        let limits = PerSide::from_fn(|side| robot.joint_limits_checked_rad(side));
        dataset::check_joint_limits(&dataset, &limits).map_err(LoadError::JointLimits)?;
        let nominal = robot.nominal_model_for(&dataset);
        // Shared joints that disagree between rows measured together.
        dataset::check_measured_together(&dataset, &nominal.shared_joints(), units)?;
        let screening = quality::screen(&dataset, &nominal, screen);
        Ok(Self {
            dataset,
            robot,
            nominal,
            screening,
        })
    }

    /// Problems that did not stop the load, in the order the command line prints them: the robot
    /// description's (missing meshes, unusual joints), then the screening's whole-file warnings.
    pub fn warnings(&self) -> Vec<String> {
        let findings = self
            .screening
            .findings
            .iter()
            .filter(|f| f.severity == Severity::Warning)
            .map(ToString::to_string);
        self.robot
            .warnings
            .iter()
            .cloned()
            .chain(findings)
            .collect()
    }

    /// The screening's whole-file findings of [`Severity::Error`]: data that cannot give a meaningful
    /// calibration as they are (a robot description that does not fit them); the command line refuses
    /// to go on.
    pub fn refusals(&self) -> Vec<&Finding> {
        self.screening.errors().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::MemoryFiles;

    fn example() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example")
    }

    #[test]
    fn the_example_loads_with_its_nominal_model_and_screening() {
        let ws = Workspace::load(&example(), &WorkspaceOptions::default()).unwrap();
        assert!(ws.robot.is_builtin());
        assert_eq!(ws.dataset.arms.left.measurements.len(), 220);
        assert_eq!(
            ws.nominal.arm(crate::side::Side::Left).param_count(),
            ws.robot
                .nominal_model_for(&ws.dataset)
                .arm(crate::side::Side::Left)
                .param_count()
        );
        assert_eq!(
            ws.screening,
            quality::screen(&ws.dataset, &ws.nominal, &ScreenSettings::default())
        );
        assert!(ws.refusals().is_empty());
        assert!(ws.warnings().is_empty(), "{:?}", ws.warnings());
    }

    #[test]
    fn each_step_fails_with_its_own_typed_error() {
        // No dataset.
        let err = Workspace::load(Path::new("/nonexistent/ds"), &WorkspaceOptions::default())
            .unwrap_err();
        assert!(matches!(err, LoadError::Dataset(_)), "{err}");
        // Named, and the operating system's reason said once, as the command line prints it.
        let printed = format!("{:#}", anyhow::Error::new(err));
        assert!(printed.contains("/nonexistent/ds"), "{printed}");
        assert_eq!(printed.matches("(os error").count(), 1, "{printed}");

        // A robot file that is not there: named, and the dataset it was loaded for.
        let options = WorkspaceOptions {
            robot: Some(PathBuf::from("/nonexistent/robot.urdf")),
            ..Default::default()
        };
        let err = Workspace::load(&example(), &options).unwrap_err();
        assert!(matches!(err, LoadError::Robot { .. }), "{err}");
        let printed = format!("{:#}", anyhow::Error::new(err));
        assert!(
            printed.starts_with("loading the robot of ") && printed.contains("robot.urdf"),
            "{printed}"
        );
        assert_eq!(printed.matches("(os error").count(), 1, "{printed}");

        // A joint value beyond its limit: the CSV's line and column.
        let mut ds = dataset::load(&example()).unwrap();
        ds.arms.right.measurements[3].q_rad[0] = 10.0;
        let line = ds.arms.right.measurements[3].line;
        let err = Workspace::new(
            ds,
            RobotDescription::builtin_irb14000(),
            &ScreenSettings::default(),
        )
        .unwrap_err();
        assert!(matches!(err, LoadError::JointLimits(_)), "{err}");
        let msg = err.to_string();
        assert!(
            msg.contains(&format!("right.csv:{line}: field `q1`")),
            "{msg}"
        );
    }

    #[test]
    fn files_in_memory_load_as_on_disk() {
        let memory = MemoryFiles::new();
        for name in ["dataset.toml", "left.csv", "right.csv"] {
            memory.insert(
                Path::new("/uploads/1").join(name),
                std::fs::read(example().join(name)).unwrap(),
            );
        }
        let options = WorkspaceOptions {
            files: Files(std::sync::Arc::new(memory)),
            ..Default::default()
        };
        let ws = Workspace::load(Path::new("/uploads/1/dataset.toml"), &options).unwrap();
        let on_disk = Workspace::load(&example(), &WorkspaceOptions::default()).unwrap();
        assert_eq!(ws.screening, on_disk.screening);
        assert_eq!(
            ws.dataset.arms.left.measurements,
            on_disk.dataset.arms.left.measurements
        );
    }
}
