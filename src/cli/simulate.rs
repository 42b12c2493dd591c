//! `dualcal simulate`: a laser-tracker dataset of both arms (paper §4.1), written with its true
//! parameters.

use super::common::describe_robot;
use crate::dataset;
use crate::output::Overwrite;
use crate::params::{ParamsFile, Provenance};
use crate::robot::{ArmLinks, LoadOptions, RobotDescription};
use crate::side::PerSide;
use crate::simulate;
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Output directory (created; must not already hold a dataset unless --force).
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Configurations per arm.
    #[arg(long, default_value_t = 220)]
    pub configs: usize,
    /// Of which calibration configurations (the rest are verification).
    #[arg(long, default_value_t = 120)]
    pub cal: usize,
    /// Amplitude of unmodelled periodic (gear) joint errors, mrad (0 = none).
    #[arg(long, default_value_t = 0.0)]
    pub joint_error_mrad: f64,
    /// Unmodelled joint compliance: deflection per metre of gravity lever, mrad/m (0 = none).
    #[arg(long, default_value_t = 0.0)]
    pub compliance_mrad_per_m: f64,
    /// Fraction of configurations with an outlier reflector measurement.
    #[arg(long, default_value_t = 0.0)]
    pub outlier_fraction: f64,
    /// Size of an outlier displacement, mm.
    #[arg(long, default_value_t = 1.0)]
    pub outlier_mm: f64,
    /// Fraction of configurations with a reflector misread by 0.5–5 mm (gross errors, docs/reliability.md).
    #[arg(long, default_value_t = 0.0)]
    pub misread_fraction: f64,
    /// Fraction of configurations with two reflector labels swapped.
    #[arg(long, default_value_t = 0.0)]
    pub swapped_labels_fraction: f64,
    /// Fraction of configurations replaced by a configuration of the other arm.
    #[arg(long, default_value_t = 0.0)]
    pub other_arm_fraction: f64,
    /// Overwrite an existing simulated dataset in --out.
    #[arg(long)]
    pub force: bool,
    /// Simulate this robot description (URDF) instead of the built-in IRB 14000; the dataset refers to
    /// it. Its collision geometry keeps the configurations collision-free.
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// With --urdf: the left arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "urdf", value_parser = ArmLinks::parse)]
    pub left: Option<ArmLinks>,
    /// With --urdf: the right arm's chain, BASE:TIP (default: the YuMi joint names).
    #[arg(long, requires = "urdf", value_parser = ArmLinks::parse)]
    pub right: Option<ArmLinks>,
}

/// `dualcal simulate`.
pub(super) fn run(a: &SimulateArgs) -> Result<()> {
    if a.cal > a.configs {
        bail!("--cal ({}) cannot exceed --configs ({})", a.cal, a.configs);
    }
    if a.out.join(dataset::MANIFEST_FILE).exists() && !a.force {
        bail!(
            "{} already holds a dataset ({}); pass --force to replace it",
            a.out.display(),
            dataset::MANIFEST_FILE
        );
    }
    let mut opts = simulate::paper_options(a.seed, a.configs, a.cal);
    if a.joint_error_mrad > 0.0 || a.compliance_mrad_per_m > 0.0 {
        opts.joint_error = Some(simulate::JointErrorModel {
            periodic_amplitude_mrad: a.joint_error_mrad,
            compliance_mrad_per_m: a.compliance_mrad_per_m,
            ..simulate::JointErrorModel::default()
        });
    }
    if a.outlier_fraction > 0.0 {
        opts.outliers = Some(simulate::OutlierModel {
            fraction: a.outlier_fraction,
            magnitude_mm: a.outlier_mm,
        });
    }
    if a.misread_fraction > 0.0 || a.swapped_labels_fraction > 0.0 || a.other_arm_fraction > 0.0 {
        opts.gross_errors = Some(simulate::GrossErrorModel {
            misread_fraction: a.misread_fraction,
            swapped_labels_fraction: a.swapped_labels_fraction,
            other_arm_fraction: a.other_arm_fraction,
            ..simulate::GrossErrorModel::study()
        });
    }
    let robot = match &a.urdf {
        Some(path) => RobotDescription::load(
            path,
            &LoadOptions {
                arms: PerSide::new(a.left.clone(), a.right.clone()),
                ..Default::default()
            },
        )?,
        None => RobotDescription::builtin_irb14000(),
    };
    for w in &robot.warnings {
        eprintln!("warning: {w}");
    }
    let mut out = simulate::simulate_with_robot(&opts, &robot)?;
    if let Some(path) = &a.urdf {
        out.dataset.robot = Some(path.canonicalize().unwrap_or_else(|_| path.clone()));
        for (side, arm) in out.dataset.arms.iter_mut() {
            arm.links = Some(robot.arm(side).links.clone());
        }
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    crate::output::refuse_existing(&[&a.out.join("truth.json")], overwrite)?;
    dataset::save_with(&out.dataset, &a.out, dataset::Units::MM_DEG, overwrite)?;
    let mut truth = ParamsFile::from_model(&out.truth);
    truth.method = Some(serde_json::json!("simulation truth"));
    truth.provenance = Some(Provenance::now(Some(&a.out)));
    truth.write(&a.out.join("truth.json"))?;
    outln!("{}", describe_robot(&robot));
    outln!(
        "simulated {} configurations per arm ({} cal, {} ver), seed {}, into {}",
        a.configs,
        a.cal,
        a.configs - a.cal,
        a.seed,
        a.out.display()
    );
    outln!(
        "rejected samples: {} in collision, {} not facing the tracker",
        out.rejected_for_collision,
        out.rejected_for_facing
    );
    outln!("true parameters: {}", a.out.join("truth.json").display());
    for r in &out.gross_errors {
        outln!(
            "gross error: {} arm `{}`: {:?}",
            r.config.side,
            r.id,
            r.error
        );
    }
    Ok(())
}
