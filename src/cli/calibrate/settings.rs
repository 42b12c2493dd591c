//! `dualcal calibrate`'s settings from its arguments: step 1's method (`--method`, else the engine's
//! default for the data, decided here once), a reflector by the user's name, the model beyond
//! geometry with its gear ratios, the configurations left out.

use super::args::CalibrateArgs;
use crate::dataset::Dataset;
use crate::solver::{CalibrationSettings, Method, Reflector};
use anyhow::Result;

/// `--reflector`: a reflector of the dataset by its name, or `a`/`b`/`c` by position where no
/// reflector has that name. The single-reflector method takes one of the first three.
fn reflector_arg(name: &str, names: &[String]) -> Result<Reflector> {
    let index = names
        .iter()
        .position(|n| n == name)
        .or(match name {
            "a" => Some(0),
            "b" => Some(1),
            "c" => Some(2),
            _ => None,
        })
        .filter(|&k| k < names.len())
        .ok_or_else(|| {
            anyhow::anyhow!(
                "--reflector {name}: the dataset's reflectors are {}",
                names.join(", ")
            )
        })?;
    Reflector::from_index(index).ok_or_else(|| {
        anyhow::anyhow!(
            "--reflector {name}: the single-reflector method takes one of the first three reflectors ({})",
            names.iter().take(3).cloned().collect::<Vec<_>>().join(", ")
        )
    })
}

/// Step 1's method: `--method`, else the engine's default for the data, with why where the data call
/// for other than the paper's minimax ([`crate::solver::default_method_reason`]).
fn step1_method(a: &CalibrateArgs, dataset: &Dataset) -> (Method, Option<&'static str>) {
    match a.method {
        Some(method) => (method, None),
        None => (
            crate::solver::default_method(dataset),
            crate::solver::default_method_reason(dataset),
        ),
    }
}

/// The settings of `--split`, `--method` (or the default for the data: why, where it is not
/// minimax, is the second value), `--base-method`, `--reflector`, `--qp` and the stopping rules.
pub(super) fn settings_from(
    a: &CalibrateArgs,
    dataset: &Dataset,
) -> Result<(CalibrationSettings, Option<&'static str>)> {
    let reflector = a
        .reflector
        .as_deref()
        .map(|r| reflector_arg(r, &dataset.reflector_names))
        .transpose()?;
    let (method, by_default) = step1_method(a, dataset);
    let settings = CalibrationSettings {
        split: a.split,
        method,
        base_method: a.base_method,
        reflector,
        qp: a.qp,
        hessian: a.hessian,
        max_iterations: a.max_iterations,
        step_tolerance: a.tolerance,
        progress_tolerance: a.progress_tolerance,
        hold_kinematics: a.hold_kinematics,
        keep_weak: a.keep_weak,
        ..CalibrationSettings::default()
    };
    Ok((settings, by_default))
}

/// `--exclude`: the configurations left out, by id (`left:ID` or `right:ID` where both arms have it).
pub(super) fn add_exclusions(
    a: &CalibrateArgs,
    dataset: &Dataset,
    settings: &mut CalibrationSettings,
) -> Result<()> {
    for spec in &a.exclude {
        let config = dataset
            .config_by_id(spec.trim())
            .map_err(|e| anyhow::anyhow!("--exclude: {e}"))?;
        if !settings.exclude.contains(&config) {
            settings.exclude.push(config);
        }
    }
    Ok(())
}

/// The gear ratios of a calibration: the URDF's transmissions, `--gear-ratio` over them; a joint
/// the arms' models do not have is refused (the built-in robot's joints are `j1` … `j7`, the names
/// of its error parameters).
fn gear_ratios(
    ws: &crate::workspace::Workspace,
    given: &[(String, f64)],
) -> Result<Vec<(String, f64)>> {
    let mut out = ws.robot.gear_ratios();
    let mut joints: Vec<String> = Vec::new();
    for side in crate::side::Side::BOTH {
        for name in joint_names(ws.nominal.arm(side)) {
            if !joints.contains(&name) {
                joints.push(name);
            }
        }
    }
    for (joint, ratio) in given {
        if !joints.contains(joint) {
            anyhow::bail!(
                "--gear-ratio {joint}={ratio}: `{joint}` is not a movable joint of either arm \
                 (they are {})",
                joints.join(", ")
            );
        }
        match out.iter_mut().find(|(j, _)| j == joint) {
            Some(entry) => entry.1 = *ratio,
            None => out.push((joint.clone(), *ratio)),
        }
    }
    Ok(out)
}

/// The names the error models give an arm's movable joints: its chain's, `j1` … `j7` for a DH arm.
fn joint_names(arm: &crate::kinematics::ArmModel) -> Vec<String> {
    match &arm.kinematics {
        crate::kinematics::ArmKinematics::Dh(_) => (1..=crate::kinematics::dh::N_JOINTS)
            .map(|j| format!("j{j}"))
            .collect(),
        crate::kinematics::ArmKinematics::Chain { chain, .. } => {
            chain.joints.iter().map(|j| j.name.clone()).collect()
        }
    }
}

/// The model beyond geometry and what it takes from the robot: gravity (−z of the root link unless
/// `--gravity`), the URDF's lumped masses, and for the harmonic models the gear ratios (the URDF's
/// transmissions, `--gear-ratio` over them; the motor terms printed).
pub(super) fn model_settings(
    a: &CalibrateArgs,
    ws: &crate::workspace::Workspace,
    settings: &mut CalibrationSettings,
) -> Result<()> {
    settings.model = a.model;
    settings.gravity_in_left_base = Some(ws.robot.gravity_in_left_base(a.gravity));
    if !settings.model.is_geometric() {
        settings.held_masses = crate::side::PerSide::from_fn(|s| ws.robot.lumped_masses(s));
    }
    if settings.model.harmonics > 0 {
        settings.gear_ratios = gear_ratios(ws, &a.gear_ratios)?;
        let motors: Vec<String> = settings
            .gear_ratios
            .iter()
            .filter(|(_, r)| (r.abs() - 1.0).abs() > 1e-9)
            .map(|(j, r)| format!("{j} {r}"))
            .collect();
        if !motors.is_empty() {
            outln!(
                "motor-side harmonics (gear ratio, motor turns per joint turn): {}",
                motors.join(", ")
            );
        }
    } else if !a.gear_ratios.is_empty() {
        anyhow::bail!(
            "--gear-ratio: the `{}` model has no harmonics; the motor's harmonics come with \
             `--model harmonic` or `--model full`",
            settings.model.name()
        );
    }
    Ok(())
}
