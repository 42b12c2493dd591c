//! Export: parameter file, calibrated URDF, per-configuration CSV and plot PNG contents. Where the
//! bytes go is the file seam's business ([`super::files`]).

use super::session::{self, Session};
use crate::dataset::Split;
use crate::kinematics::Side;
use anyhow::Context as _;
use eframe::egui;

/// What to export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Export {
    Params,
    Urdf,
    Csv,
    PlotPng,
}

/// A screenshot region as PNG bytes.
pub fn encode_png(image: &egui::ColorImage) -> anyhow::Result<Vec<u8>> {
    let [w, h] = image.size;
    let mut rgba = Vec::with_capacity(w * h * 4);
    for c in &image.pixels {
        rgba.extend_from_slice(&c.to_array());
    }
    let buffer = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
        .context("screenshot has an inconsistent size")?;
    let mut bytes = Vec::new();
    buffer.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )?;
    Ok(bytes)
}

/// Per-configuration errors of the current model as CSV.
pub fn export_csv(session: &Session) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "id",
        "arm",
        "split",
        "worst_pos_mm",
        "worst_ori_rad",
        "rigidity_mm",
        "point_error_a_mm",
        "point_error_b_mm",
        "point_error_c_mm",
    ])?;
    for row in &session.current().configs {
        let e = row.point_errors_mm();
        w.write_record([
            row.id.clone(),
            row.side.name().to_string(),
            if row.split == Split::Cal {
                "cal"
            } else {
                "ver"
            }
            .to_string(),
            format!("{:.6}", row.worst_pos_mm),
            format!("{:.8}", row.worst_ori_rad),
            format!("{:.6}", row.rigidity_mm),
            format!("{:.6}", e[0]),
            format!("{:.6}", e[1]),
            format!("{:.6}", e[2]),
        ])?;
    }
    w.into_inner().context("CSV buffer")
}

/// The calibrated model as a `dualcal-params/1` file.
pub fn export_params(session: &Session, cal: &session::Calibrated) -> anyhow::Result<Vec<u8>> {
    let mut file = crate::params::ParamsFile::from_model(&cal.result.calibrated);
    file.method = Some(serde_json::to_value(&cal.result.settings)?);
    file.termination = Some(serde_json::json!({
        "stages": cal.result.stages.iter().map(|s| serde_json::json!({
            "stage": s.stage.to_string(),
            "termination": format!("{:?}", s.termination),
            "iterations": s.iterations,
            "psi_mm2": s.psi_mm2,
            "psi_start_mm2": s.psi_start_mm2,
        })).collect::<Vec<_>>(),
        "elapsed_secs": cal.result.elapsed_secs,
    }));
    let mut fixed = crate::params::FixedParameters {
        left: Vec::new(),
        right: Vec::new(),
    };
    for (side, report) in &cal.result.identifiability {
        let list = match side {
            Side::Left => &mut fixed.left,
            Side::Right => &mut fixed.right,
        };
        list.extend(report.fixed.iter().map(|f| crate::params::FixedParameter {
            name: f.name.clone(),
            reason: f.reason.clone(),
        }));
    }
    file.fixed_parameters = Some(fixed);
    file.provenance = Some(crate::params::Provenance::now(Some(&session.dataset.dir)));
    let mut text = serde_json::to_vec_pretty(&file)?;
    text.push(b'\n');
    Ok(text)
}

/// The calibrated robot description.
pub fn export_urdf(session: &Session, cal: &session::Calibrated) -> anyhow::Result<Vec<u8>> {
    let text = crate::urdf_export::calibrated_urdf(&session.robot, &cal.result.calibrated)?;
    Ok(text.into_bytes())
}
