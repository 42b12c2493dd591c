//! The files `dualcal calibrate` writes beside its parameter file: none over an input or over one
//! another; the calibrated URDF and the overlay, if asked for.

use super::args::CalibrateArgs;
use crate::dataset::Dataset;
use crate::robot::RobotDescription;
use crate::solver::CalibrationResult;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Refuse outputs that would write over an input (the dataset's files, its robot description) or
/// over one another.
pub(super) fn refuse_overwrites(a: &CalibrateArgs, ds: &Dataset) -> Result<()> {
    let mut inputs: Vec<PathBuf> = ds.files().to_vec();
    inputs.extend(ds.robot.clone());
    for out in [Some(&a.out), a.urdf.as_ref(), a.overlay.as_ref()]
        .into_iter()
        .flatten()
    {
        crate::output::refuse_overwrite_input(
            out,
            &inputs.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        )?;
    }
    if let Some(urdf) = &a.urdf {
        crate::output::refuse_overwrite_input(urdf, &[&a.out])
            .context("--urdf and --out name the same file")?;
    }
    if let Some(overlay) = &a.overlay {
        let others: Vec<&Path> = [Some(&a.out), a.urdf.as_ref()]
            .into_iter()
            .flatten()
            .map(PathBuf::as_path)
            .collect();
        crate::output::refuse_overwrite_input(overlay, &others)
            .context("--overlay names the same file as another output")?;
    }
    Ok(())
}

/// The calibrated URDF and the overlay, if asked for.
pub(super) fn write_robot_exports(
    a: &CalibrateArgs,
    robot: &RobotDescription,
    result: &CalibrationResult,
) -> Result<()> {
    if let Some(path) = &a.urdf {
        let text = crate::urdf_export::calibrated_urdf(robot, &result.calibrated)?;
        crate::output::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("calibrated URDF written to {}", path.display());
    }
    if let Some(path) = &a.overlay {
        let overlay = crate::urdf_export::calibrated_overlay(robot, &result.calibrated)?;
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let text = if json {
            overlay.to_json()
        } else {
            overlay.to_yaml()
        };
        crate::output::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("calibration overlay written to {}", path.display());
    }
    Ok(())
}
