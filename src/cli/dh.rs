//! `dualcal urdf-from-dh`: the URDF a DH robot file (`dualcal-dh/1`) is read as.

use super::common::describe_robot;
use crate::robot::{LoadOptions, RobotDescription};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct UrdfFromDhArgs {
    /// The DH robot file (`dualcal-dh/1`).
    pub dh: PathBuf,
    /// The URDF to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// `dualcal urdf-from-dh`: the URDF is loaded back (its arms' forward kinematics are the table's)
/// before it is written.
pub fn run(a: &UrdfFromDhArgs) -> Result<()> {
    crate::output::refuse_overwrite_input(&a.out, &[a.dh.as_path()])?;
    let text = std::fs::read_to_string(&a.dh)
        .with_context(|| format!("{}: cannot read", a.dh.display()))?;
    let urdf = crate::robot::dh_file::to_urdf(&text).map_err(|message| {
        crate::robot::RobotError::DhFile {
            path: a.dh.clone(),
            message,
        }
    })?;
    let robot = RobotDescription::load(a.dh.as_path(), &LoadOptions::default())?;
    crate::output::write_atomic(&a.out, urdf.as_bytes())
        .with_context(|| format!("{}: cannot write", a.out.display()))?;
    outln!("{}", describe_robot(&robot));
    outln!("wrote {}", a.out.display());
    Ok(())
}
