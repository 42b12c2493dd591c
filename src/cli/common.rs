//! What several subcommands share: the dataset loaded with its robot (the description's warnings
//! printed), the robot described in one line, a vector argument parsed.

use crate::choice::Choice;
use crate::robot::RobotDescription;
use crate::workspace::{Workspace, WorkspaceOptions};
use anyhow::Result;
use nalgebra::Vector3;
use std::path::Path;

/// The dataset at `path` with its robot, checked, its nominal model and screening
/// ([`Workspace::load`]); the robot description's warnings printed.
pub(crate) fn load_workspace(path: &Path) -> Result<Workspace> {
    let ws = Workspace::load(path, &WorkspaceOptions::default())?;
    for w in &ws.robot.warnings {
        eprintln!("warning: {w}");
    }
    Ok(ws)
}

/// `robot: FILE; left arm BASE → TIP (N joints: …), right arm …; nominal model …`.
pub fn describe_robot(robot: &RobotDescription) -> String {
    if robot.is_one_arm() {
        let arm = robot.arm(crate::side::Side::Left);
        return format!(
            "robot: {}; one arm {} ({} joints); nominal model: the URDF's joint origins",
            robot.name(),
            arm.links,
            arm.chain.dof()
        );
    }
    let arms: Vec<String> = robot
        .arms()
        .iter()
        .map(|(side, a)| format!("{side} arm {} ({} joints)", a.links, a.chain.dof()))
        .collect();
    let left = robot.arm(crate::side::Side::Left).chain.joint_names();
    let shared: Vec<&str> = robot
        .arm(crate::side::Side::Right)
        .chain
        .joint_names()
        .into_iter()
        .filter(|n| left.contains(n))
        .collect();
    let shared = if shared.is_empty() {
        String::new()
    } else {
        format!(
            "; shared by both arms: {} (identified once, from both arms' data)",
            shared.join(", ")
        )
    };
    format!(
        "robot: {}; {}{shared}; nominal model: {}",
        robot.name(),
        arms.join(", "),
        if robot.is_builtin() {
            "Table 3 (DH)"
        } else {
            "the URDF's joint origins"
        }
    )
}

/// `X,Y,Z`: three finite numbers (`--gravity`, `plan --tracker`).
pub(super) fn parse_xyz(s: &str) -> std::result::Result<Vector3<f64>, String> {
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

/// The argument parser of one of the engine's [`Choice`]s: its spellings (and their aliases), each
/// with its line of help, as `--help` lists them.
pub(crate) fn choice<T: Choice + Clone + Send + Sync>()
-> impl clap::builder::TypedValueParser<Value = T> {
    let values = T::all().iter().map(|&v| {
        let value =
            clap::builder::PossibleValue::new(v.spelling()).aliases(v.aliases().iter().copied());
        match v.help() {
            Some(help) => value.help(help),
            None => value,
        }
    });
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(values).try_map(|text: String| T::parse_choice(&text))
}
