//! [`Robot`]: the robot description a calibration starts from.

use super::error::Result;
use crate::kinematics::ArmLinks;
use crate::robot::{LoadOptions, RobotDescription, RobotSource};
use crate::side::{PerSide, Side};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a [`Robot`] came from: kept so that a dataset naming its arms' links can compile the same
/// description with them.
#[derive(Clone, Debug)]
pub(crate) enum Origin {
    Builtin,
    File(PathBuf),
    Text {
        text: Arc<str>,
        path: Option<PathBuf>,
    },
}

/// A robot description: the built-in ABB IRB 14000, a URDF (file or text, with its meshes), or a
/// `dualcal-dh/1` DH table — with the two chains that are its arms.
///
/// ```
/// let robot = dualcal::Robot::builtin_irb14000();
/// assert_eq!(robot.joint_names(dualcal::side::Side::Left).len(), 7);
/// ```
#[derive(Clone, Debug)]
pub struct Robot {
    pub(crate) origin: Origin,
    /// The arms given by the user (`None`: the dataset's, else the description's defaults).
    pub(crate) arms: PerSide<Option<ArmLinks>>,
    pub(crate) description: RobotDescription,
}

impl Robot {
    /// The built-in ABB IRB 14000 (YuMi): its URDF, nominal model the paper's Table 3 (DH).
    pub fn builtin_irb14000() -> Robot {
        Robot {
            origin: Origin::Builtin,
            arms: PerSide::default(),
            description: RobotDescription::builtin_irb14000(),
        }
    }

    /// A URDF file (`package://` and relative meshes resolved beside it and through
    /// `ROS_PACKAGE_PATH`; ROS is never run) or a `dualcal-dh/1` DH table (`.toml`). The arms are
    /// the description's default chains (YuMi's joint names, or the dataset's links when it is
    /// combined with one); [`Robot::with_arms`] names them.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Robot> {
        let path = path.as_ref().to_path_buf();
        Self::compile(Origin::File(path), PerSide::default())
    }

    /// URDF text; `path` (the file it came from, if any) names it in errors and anchors relative mesh
    /// paths.
    pub fn from_urdf_str(text: &str, path: Option<&Path>) -> Result<Robot> {
        Self::compile(
            Origin::Text {
                text: Arc::from(text),
                path: path.map(Path::to_path_buf),
            },
            PerSide::default(),
        )
    }

    /// The same description with its arms named: each arm the chain from `base_link` to `tip_link`
    /// (a dual-arm robot's two chains; a single arm as both).
    pub fn with_arms(&self, left: ArmLinks, right: ArmLinks) -> Result<Robot> {
        Self::compile(self.origin.clone(), PerSide::new(Some(left), Some(right)))
    }

    fn compile(origin: Origin, arms: PerSide<Option<ArmLinks>>) -> Result<Robot> {
        let description = load(&origin, &arms)?;
        Ok(Robot {
            origin,
            arms,
            description,
        })
    }

    /// The description's name (its file, or "built-in IRB 14000").
    pub fn name(&self) -> String {
        self.description.name()
    }

    /// The joints of an arm's chain, in chain order (the columns of its measurements).
    pub fn joint_names(&self, side: Side) -> Vec<String> {
        self.description.arm(side).joint_names()
    }

    /// Whether the joint columns of an arm are lengths (prismatic joints, mm) rather than angles
    /// (rad), in chain order.
    pub fn linear_joints(&self, side: Side) -> Vec<bool> {
        self.description.arm(side).linear_joints()
    }

    /// Warnings of the description's load (missing meshes, unusual joints).
    pub fn warnings(&self) -> &[String] {
        &self.description.warnings
    }

    /// The file the description was read from (`None`: the built-in robot, or text without a path).
    pub(crate) fn file(&self) -> Option<&Path> {
        match &self.origin {
            Origin::Builtin => None,
            Origin::File(path) => Some(path),
            Origin::Text { path, .. } => path.as_deref(),
        }
    }

    /// The compiled description (the engine's type, for what the front door does not cover).
    pub fn description(&self) -> &RobotDescription {
        &self.description
    }
}

/// Compile the description of `origin` with `arms` (each `None`: the description's default).
pub(crate) fn load(
    origin: &Origin,
    arms: &PerSide<Option<ArmLinks>>,
) -> Result<RobotDescription, crate::robot::RobotError> {
    let options = LoadOptions {
        arms: arms.clone(),
        ..LoadOptions::default()
    };
    let source = match origin {
        Origin::Builtin => RobotSource::Builtin,
        Origin::File(path) => RobotSource::File(path),
        Origin::Text { text, path } => RobotSource::Text {
            text,
            path: path.as_deref(),
        },
    };
    RobotDescription::load(source, &options)
}
