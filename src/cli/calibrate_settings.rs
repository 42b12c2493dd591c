//! `dualcal calibrate`'s settings from its arguments (a reflector by the user's name), its progress
//! lines (one per outer iteration, each objective by the user's reflector name) and its lines on the
//! parameters' uncertainty.

use super::CalibrateArgs;
use crate::side::PerSide;
use crate::solver::{CalibrationEvent, CalibrationSettings, Reflector};
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

pub(super) fn settings_from(
    a: &CalibrateArgs,
    dataset: &crate::dataset::Dataset,
) -> Result<CalibrationSettings> {
    let reflector = a
        .reflector
        .as_deref()
        .map(|r| reflector_arg(r, &dataset.reflector_names))
        .transpose()?;
    Ok(CalibrationSettings {
        split: a.split,
        method: a
            .method
            .unwrap_or_else(|| crate::solver::default_method(dataset)),
        base_method: a.base_method,
        reflector,
        qp: a.qp,
        max_iterations: a.max_iterations,
        step_tolerance: a.tolerance,
        progress_tolerance: a.progress_tolerance,
        hold_kinematics: a.hold_kinematics,
        ..CalibrationSettings::default()
    })
}

/// A progress line per outer iteration; `reflectors` are the dataset's reflector names (`F_<name>`
/// per objective; a, b, c, … by position where the count differs).
pub fn print_event(event: &CalibrationEvent, reflectors: &[String]) {
    match event {
        CalibrationEvent::StageStarted {
            stage,
            n_configs,
            n_pairs,
        } => {
            eprintln!("{stage}: {n_configs} configurations, {n_pairs} pairs per reflector")
        }
        CalibrationEvent::Iteration(r) => {
            let lambda = match &r.lambda {
                Some(l) => format!(
                    "λ {}",
                    l.iter()
                        .map(|x| format!("{x:.2}"))
                        .collect::<Vec<_>>()
                        .join("/")
                ),
                None => format!("{:14}", "λ –"),
            };
            // One column per reflector, by the user's name.
            let defaults;
            let names: &[String] = if reflectors.len() == r.f_mm2.len() {
                reflectors
            } else {
                defaults = crate::kinematics::default_reflector_names(r.f_mm2.len());
                &defaults
            };
            let f = names
                .iter()
                .zip(&r.f_mm2)
                .map(|(n, v)| format!("F_{n} {v:>12.4}"))
                .collect::<Vec<_>>()
                .join("  ");
            eprintln!(
                "  {:>3}  ψ {:>14.6} mm²   {f}   {lambda}   step {:>9.2e}   KKT {:>9.2e}   {:>7.3} s",
                r.iteration, r.psi_mm2, r.step_norm, r.optimality_residual, r.elapsed_secs
            )
        }
        CalibrationEvent::StageFinished { stage, termination } => {
            eprintln!("{stage}: {termination}")
        }
    }
}

/// Each arm's parameter uncertainty in a few lines (the parameter file has every σ).
pub fn print_uncertainty(u: &PerSide<Option<crate::solver::uncertainty::ArmUncertainty>>) {
    for (side, u) in u.iter() {
        let Some(u) = u else { continue };
        let largest = |unit: &str| {
            u.largest(unit).map_or(String::new(), |p| {
                format!("{:.4} {unit} ({})", p.sigma, p.name)
            })
        };
        outln!(
            "{side} arm: 1σ of the identified parameters (from the residuals: point noise {:.4} mm per axis; {} configurations): largest {}, {}; condition number {:.1}",
            u.point_sigma_mm,
            u.configurations,
            largest("mm"),
            largest("mrad"),
            u.condition
        );
        // The errors beyond geometry, each unit once (`--model`).
        let mut units: Vec<&str> = Vec::new();
        for p in &u.parameters {
            if p.unit != "mm" && p.unit != "mrad" && !units.contains(&p.unit.as_str()) {
                units.push(&p.unit);
            }
        }
        if !units.is_empty() {
            let parts: Vec<String> = units.iter().map(|unit| largest(unit)).collect();
            outln!("  beyond geometry: largest {}", parts.join(", "));
        }
        if !u.correlations.is_empty() {
            let pairs: Vec<String> = u
                .correlations
                .iter()
                .take(5)
                .map(|c| format!("{}–{} {:+.2}", c.a, c.b, c.correlation))
                .collect();
            outln!(
                "  {} pair(s) correlated beyond ±{}: {}{}",
                u.correlations.len(),
                crate::solver::uncertainty::REPORTED_CORRELATION,
                pairs.join(", "),
                if u.correlations.len() > 5 {
                    ", …"
                } else {
                    ""
                }
            );
        }
    }
}

/// `JOINT=RATIO` of `--gear-ratio`.
pub(super) fn parse_gear_ratio(text: &str) -> Result<(String, f64), String> {
    let (joint, ratio) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: expected JOINT=RATIO, e.g. `joint_1=100`"))?;
    let ratio: f64 = ratio
        .trim()
        .parse()
        .map_err(|_| format!("`{ratio}`: expected a number (motor turns per joint turn)"))?;
    if !ratio.is_finite() || ratio == 0.0 {
        return Err(format!(
            "`{text}`: expected a finite, non-zero ratio (motor turns per joint turn)"
        ));
    }
    Ok((joint.trim().to_string(), ratio))
}

/// The gear ratios of a calibration: the URDF's transmissions, `--gear-ratio` over them; a joint
/// the arms' models do not have is refused (the built-in robot's joints are `j1` … `j7`, the names
/// of its error parameters).
pub(super) fn gear_ratios(
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
