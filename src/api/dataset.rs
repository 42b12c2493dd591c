//! [`Dataset`]: measurements with the robot they were taken on, checked and ready to calibrate.

use super::error::{Error, Result};
use super::robot::{Origin, Robot};
use crate::dataset::{self, ArmData, Measurement, Split, TrackerSpec, Units};
use crate::kinematics::ArmLinks;
use crate::quality::ScreenSettings;
use crate::side::{PerSide, Side};
use crate::workspace::{Workspace, WorkspaceOptions};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// One arm's measurements as arrays: for configuration `i`, its joint values (chain order; rad, a
/// prismatic joint's in mm) and the tracker's point of each reflector (tracker frame, mm).
#[derive(Clone, Debug, Default)]
pub struct ArmArrays {
    /// `joints[i][j]`: configuration `i`, joint `j` (rad; mm for a prismatic joint).
    pub joints: Vec<Vec<f64>>,
    /// `points_mm[i][k]`: configuration `i`, reflector `k`, (x, y, z) in the tracker frame, mm.
    pub points_mm: Vec<Vec<[f64; 3]>>,
    /// Each configuration's split ([`Split::Cal`] or [`Split::Ver`]); empty: every one `Cal`.
    pub split: Vec<Split>,
    /// Each configuration's id (empty: `L001…`/`R001…` by position).
    pub ids: Vec<String>,
}

/// Measurements given as arrays ([`Dataset::from_arrays`]).
#[derive(Clone, Debug)]
pub struct Arrays {
    /// The reflectors' names, in the order of each configuration's points (`a`, `b`, `c`).
    pub reflector_names: Vec<String>,
    /// The reflectors' nominal coordinates in the arm's tip frame (the flange for the built-in
    /// robot), mm, in the order of `reflector_names`.
    pub nominal_reflectors_mm: Vec<[f64; 3]>,
    /// The left arm's measurements (`None`: not measured).
    pub left: Option<ArmArrays>,
    /// The right arm's measurements (`None`: not measured).
    pub right: Option<ArmArrays>,
    /// The tracker's maximum permissible error (default: the paper's, 16 µm + 0.8 µm/m).
    pub tracker: TrackerSpec,
    /// Both hands measured at one instant (rows of equal index are one pose of the robot).
    pub measured_together: bool,
}

/// A dataset with the robot it was measured on: loaded, checked against each other (joint counts,
/// limits), with the nominal model and the screening of every configuration.
///
/// ```
/// let ds = dualcal::Dataset::load(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example"))?;
/// assert_eq!(ds.configuration_count(dualcal::side::Side::Left), 220);
/// # Ok::<(), dualcal::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Dataset {
    pub(crate) workspace: Workspace,
}

impl Dataset {
    /// A dataset directory (or its `dataset.toml`) with the robot its manifest names, else the
    /// built-in IRB 14000 — exactly what `dualcal calibrate DIR` loads.
    pub fn load(path: impl AsRef<Path>) -> Result<Dataset> {
        let workspace = Workspace::load(path.as_ref(), &WorkspaceOptions::default())?;
        Ok(Dataset { workspace })
    }

    /// A dataset directory measured on `robot` (whatever robot its manifest names). The arms are
    /// `robot`'s where it names them ([`Robot::with_arms`]), else the manifest's links.
    pub fn load_with_robot(path: impl AsRef<Path>, robot: &Robot) -> Result<Dataset> {
        let workspace = match &robot.origin {
            Origin::File(file) => Workspace::load(
                path.as_ref(),
                &WorkspaceOptions {
                    robot: Some(file.clone()),
                    arms: robot.arms.clone(),
                    ..WorkspaceOptions::default()
                },
            )?,
            _ => {
                let (mut ds, units) = dataset::load_with_units(path.as_ref())?;
                // A robot of another origin than the manifest's file.
                ds.robot = None;
                let description = super::robot::load(&robot.origin, &arms_for(robot, &ds))?;
                Workspace::from_loaded(ds, units, description, &ScreenSettings::default())?
            }
        };
        Ok(Dataset { workspace })
    }

    /// Measurements in memory on `robot`: the same checks as a dataset read from files (joint counts
    /// against the arms' chains, joint limits, finite values), then the nominal model and the
    /// screening.
    pub fn from_arrays(robot: &Robot, arrays: Arrays) -> Result<Dataset> {
        let reflectors = arrays.nominal_reflectors_mm.len();
        if reflectors == 0 || arrays.reflector_names.len() != reflectors {
            return Err(Error::Invalid(format!(
                "{} reflector name(s) for {reflectors} nominal reflector coordinate(s): give one name \
                 and one nominal (x, y, z) per reflector",
                arrays.reflector_names.len()
            )));
        }
        let arms = PerSide::new(arrays.left, arrays.right);
        if arms.left.is_none() && arms.right.is_none() {
            return Err(Error::Invalid(
                "no measurements: give the left arm's, the right arm's or both".into(),
            ));
        }
        let mut data = PerSide::from_fn(ArmData::not_measured);
        for side in Side::BOTH {
            if let Some(arm) = &arms[side] {
                data[side] = arm_data(side, arm, reflectors, &robot.linear_joints(side))?;
            }
        }
        let nominal: Vec<Vector3<f64>> = arrays
            .nominal_reflectors_mm
            .iter()
            .map(|p| Vector3::from(*p))
            .collect();
        let ds = crate::dataset::Dataset {
            dir: PathBuf::from("<arrays>"),
            robot: None,
            tracker: arrays.tracker,
            nominal_reflectors_mm: nominal,
            reflector_names: arrays.reflector_names.into(),
            arms: data,
            measured_together: arrays.measured_together,
        };
        let description = super::robot::load(&robot.origin, &robot.arms)?;
        let workspace =
            Workspace::from_loaded(ds, Units::MM_RAD, description, &ScreenSettings::default())?;
        Ok(Dataset { workspace })
    }

    /// How many configurations of `side` the dataset holds (both splits).
    pub fn configuration_count(&self, side: Side) -> usize {
        self.workspace.dataset.arm(side).measurements.len()
    }

    /// The reflectors' names.
    pub fn reflector_names(&self) -> &[String] {
        &self.workspace.dataset.reflector_names
    }

    /// Warnings of the load: the robot description's and the screening's whole-file ones.
    pub fn warnings(&self) -> Vec<String> {
        self.workspace.warnings()
    }

    /// The measured data (the engine's type).
    pub fn data(&self) -> &crate::dataset::Dataset {
        &self.workspace.dataset
    }

    /// The robot description the data were checked against.
    pub fn robot(&self) -> &crate::robot::RobotDescription {
        &self.workspace.robot
    }

    /// The dataset with its robot, nominal model and screening (the engine's type).
    pub fn workspace(&self) -> &Workspace {
        &self.workspace
    }
}

/// The arms a robot is compiled with for a dataset: the robot's own where given, else the dataset's.
fn arms_for(robot: &Robot, ds: &crate::dataset::Dataset) -> PerSide<Option<ArmLinks>> {
    PerSide::from_fn(|side| {
        robot.arms[side]
            .clone()
            .or_else(|| ds.arm(side).links.clone())
    })
}

/// One arm's arrays as the dataset's measurements, shapes checked.
fn arm_data(side: Side, arm: &ArmArrays, reflectors: usize, linear: &[bool]) -> Result<ArmData> {
    let n = arm.joints.len();
    let shape = |what: &str, got: usize| {
        Error::Invalid(format!(
            "{side} arm: {got} {what} for {n} configurations (one per configuration)"
        ))
    };
    if arm.points_mm.len() != n {
        return Err(shape("rows of points", arm.points_mm.len()));
    }
    if !arm.split.is_empty() && arm.split.len() != n {
        return Err(shape("splits", arm.split.len()));
    }
    if !arm.ids.is_empty() && arm.ids.len() != n {
        return Err(shape("ids", arm.ids.len()));
    }
    let joints = arm.joints.first().map_or(0, Vec::len);
    let prefix = match side {
        Side::Left => "L",
        Side::Right => "R",
    };
    let mut measurements = Vec::with_capacity(n);
    for i in 0..n {
        let field = |what: String| Error::Invalid(format!("{side} arm, configuration {i}: {what}"));
        if arm.joints[i].len() != joints {
            return Err(field(format!(
                "{} joint values, the first configuration has {joints}",
                arm.joints[i].len()
            )));
        }
        if arm.points_mm[i].len() != reflectors {
            return Err(field(format!(
                "{} points, the dataset has {reflectors} reflector(s)",
                arm.points_mm[i].len()
            )));
        }
        let values = arm.joints[i]
            .iter()
            .chain(arm.points_mm[i].iter().flatten());
        if values.clone().any(|v| !v.is_finite()) {
            return Err(field("a joint value or point is not finite".into()));
        }
        let split = arm.split.get(i).copied().unwrap_or(Split::Cal);
        if split == Split::All {
            return Err(field("its split is `all`; give `cal` or `ver`".into()));
        }
        measurements.push(Measurement {
            id: arm
                .ids
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("{prefix}{:03}", i + 1)),
            q_rad: arm.joints[i].clone(),
            tracker_points_mm: arm.points_mm[i].iter().map(|p| Vector3::from(*p)).collect(),
            split,
            line: i + 1,
        });
    }
    let mut data = ArmData {
        side,
        file: PathBuf::from(format!("<{} arm arrays>", side.name())),
        links: None,
        station: None,
        linear_joints: Vec::new(),
        nominal_reflectors_mm: None,
        measurements,
    };
    data.set_linear_joints(linear, Units::MM_RAD)?;
    Ok(data)
}
