//! `dualcal evaluate`: the accuracy figures (paper eqs. 5–8) of a parameter file or the nominal model on
//! a dataset, as a table or JSON, and — where the parameter file has the tracker frame — the absolute
//! position errors (a summary, every marker's error as CSV).

use super::common::{describe_robot, load_workspace};
use crate::dataset::Split;
use crate::metrics;
use crate::params::ParamsFile;
use crate::side::PerSide;
use crate::workspace::Workspace;
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct EvaluateArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    /// Parameter file (dualcal-params/1).
    #[arg(long, conflicts_with = "nominal", required_unless_present = "nominal")]
    pub params: Option<PathBuf>,
    /// Use the nominal model: the dataset's robot description (Table 3 for the built-in IRB 14000, else
    /// the URDF's own arm chains), the dataset's nominal reflectors and the URDF's base transform.
    #[arg(long)]
    pub nominal: bool,
    #[arg(long, value_parser = crate::cli::common::choice::<Split>(), default_value_t = Split::All)]
    pub split: Split,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write every measured point's absolute position error (`arm,id,reflector,error_mm`) to this
    /// CSV file, where the parameter file has the tracker frame.
    #[arg(long)]
    pub absolute_csv: Option<PathBuf>,
}

/// `dualcal evaluate`: the paper's figures of a parameter file (or the nominal model) on a dataset's
/// split, and where the file has the tracker frame the absolute position errors.
pub(super) fn run(a: &EvaluateArgs) -> Result<()> {
    let Workspace {
        dataset: ds,
        robot,
        nominal,
        ..
    } = load_workspace(&a.dataset)?;
    let (model, frames) = match &a.params {
        Some(p) => {
            let file = ParamsFile::read(p)?;
            let model = file
                .to_model_for(&robot)
                .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?
                .with_torso_instants(&ds.instants());
            let frames = file
                .tracker_from_base()
                .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
            (model, frames)
        }
        None => (nominal, PerSide::default()),
    };
    let report = metrics::evaluate(&ds, &model, a.split)?;
    // Where a method identified the tracker (camera) frame: the absolute position errors too.
    let absolute = metrics::absolute_stats(&ds, &model, &frames, a.split)?;
    if let Some(path) = &a.absolute_csv {
        if absolute.is_none() {
            anyhow::bail!(
                "--absolute-csv {}: the parameter file has no tracker frame (an absolute method \
                 identifies it: --method position or pose)",
                path.display()
            );
        }
        let mut text = String::from("arm,id,reflector,error_mm\n");
        for e in metrics::absolute_errors(&ds, &model, &frames, a.split)? {
            let id = if e.id.contains([',', '"']) {
                format!("\"{}\"", e.id.replace('"', "\"\""))
            } else {
                e.id
            };
            text.push_str(&format!(
                "{},{id},{},{}\n",
                e.side, ds.reflector_names[e.reflector], e.error_mm
            ));
        }
        let inputs: Vec<PathBuf> = std::iter::once(ds.dir.join(crate::dataset::MANIFEST_FILE))
            .chain(ds.arms.values().map(|arm| arm.file.clone()))
            .chain(a.params.clone())
            .collect();
        let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        crate::output::refuse_overwrite_input(path, &inputs)?;
        crate::output::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if a.json {
        let mut value = serde_json::to_value(report)?;
        if let (Some(abs), Some(obj)) = (absolute, value.as_object_mut()) {
            obj.insert("absolute".into(), serde_json::to_value(abs)?);
        }
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        let what = match &a.params {
            Some(p) => format!("parameters {}", p.display()),
            None => "nominal model".to_string(),
        };
        outln!(
            "Accuracy of the {what} on {} (split: {:?})",
            ds.dir.display(),
            a.split
        );
        outln!("{}", describe_robot(&robot));
        outln!(
            "{}",
            metrics::format_table_named(&report, &ds.reflector_names)
        );
        if let Some(abs) = absolute {
            outln!(
                "absolute position error (the parameter file's tracker frame): mean {:.3} mm, RMS \
                 {:.3} mm, max {:.3} mm over {} measured points",
                abs.mean_mm,
                abs.rms_mm,
                abs.max_mm,
                abs.n_points
            );
        }
    }
    Ok(())
}
