//! Export: parameter file, calibrated URDF, per-configuration CSV and plot PNG contents. Where the
//! bytes go is the file seam's business ([`super::files`]).

use super::files::SaveRequest;
use super::session::{self, Session};
use anyhow::Context as _;
use eframe::egui;

pub use super::command::Export;

impl Export {
    /// The file's contents from the session; `None` where there is nothing to export (a model
    /// before any calibration; the plots, which are a screenshot: see [`encode_png`]).
    pub fn contents(self, session: &Session) -> Option<anyhow::Result<Vec<u8>>> {
        match (self, &session.calibrated) {
            (Export::Params, Some(cal)) => Some(export_params(cal)),
            (Export::Report, Some(cal)) => Some(export_report(session, cal)),
            (Export::Urdf, Some(cal)) => Some(export_urdf(session, cal)),
            (Export::Csv, _) => Some(export_csv(session)),
            (Export::Params | Export::Urdf | Export::Report, None) | (Export::PlotPng, _) => None,
        }
    }

    /// The save dialog for `bytes` of this kind: title, suggested name, filter.
    pub fn save_request(self, bytes: Vec<u8>) -> SaveRequest {
        let (title, file_name, filter_name, extensions): (_, _, _, &'static [&'static str]) =
            match self {
                Export::Params => (
                    "Export parameters (dualcal-params/1)",
                    "params.json",
                    "JSON",
                    &["json"],
                ),
                Export::Urdf => (
                    "Export calibrated URDF",
                    "calibrated.urdf",
                    "URDF",
                    &["urdf"],
                ),
                Export::Csv => (
                    "Export per-configuration errors (CSV)",
                    "configurations.csv",
                    "CSV",
                    &["csv"],
                ),
                Export::Report => (
                    "Export calibration report (HTML)",
                    "report.html",
                    "HTML",
                    &["html"],
                ),
                Export::PlotPng => (
                    "Export plots as PNG",
                    "dualcal-plots.png",
                    "PNG image",
                    &["png"],
                ),
            };
        SaveRequest {
            title,
            file_name: file_name.into(),
            filter_name,
            extensions,
            bytes,
        }
    }
}

/// A screenshot region as PNG bytes.
pub fn encode_png(image: &egui::ColorImage) -> anyhow::Result<Vec<u8>> {
    let [w, h] = image.size;
    let mut rgba = Vec::with_capacity(w * h * 4);
    for c in &image.pixels {
        rgba.extend_from_slice(&c.to_array());
    }
    let (width, height) = (u32::try_from(w)?, u32::try_from(h)?);
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer
        .write_image_data(&rgba)
        .context("screenshot has an inconsistent size")?;
    writer.finish()?;
    Ok(bytes)
}

/// Per-configuration errors of the current model as CSV.
pub fn export_csv(session: &Session) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let names = &session.dataset.reflector_names;
    let mut header: Vec<String> = [
        "id",
        "arm",
        "split",
        "worst_pos_mm",
        "worst_ori_rad",
        "rigidity_mm",
    ]
    .map(String::from)
    .to_vec();
    header.extend(names.iter().map(|r| format!("point_error_{r}_mm")));
    header.extend(["excluded", "flag", "flag_size_mm", "flag_reason"].map(String::from));
    w.write_record(&header)?;
    let flags = session.current_screening().by_config();
    for row in &session.current().configs {
        let e = row.point_errors_mm();
        let flag = flags.get(&row.config).map(|f| f[0]);
        let mut record = vec![
            row.id.clone(),
            row.config.side.name().to_string(),
            row.split.name().to_string(),
            format!("{:.6}", row.worst_pos_mm),
            // Empty where the orientation is not measurable (fewer than three reflectors).
            row.worst_ori_rad
                .map_or_else(String::new, |v| format!("{v:.8}")),
            format!("{:.6}", row.rigidity_mm),
        ];
        record.extend(e.iter().map(|v| format!("{v:.6}")));
        record.extend([
            row.excluded.to_string(),
            flag.map_or("", |f| f.kind.label()).to_string(),
            flag.map_or_else(String::new, |f| format!("{:.6}", f.size_mm)),
            flag.map_or_else(String::new, |f| f.reason.clone()),
        ]);
        w.write_record(&record)?;
    }
    w.into_inner().context("CSV buffer")
}

/// The calibration's `dualcal-params/1` file (the same file `dualcal calibrate --out` writes: the
/// excluded configurations in `method.excluded`, the screening in `quality`, the parameters'
/// uncertainty in `uncertainty`).
pub fn params_file(
    dataset: &crate::dataset::Dataset,
    result: &crate::solver::CalibrationResult,
    screening: &crate::quality::Screening,
    uncertainty: &crate::side::PerSide<Option<crate::solver::uncertainty::ArmUncertainty>>,
) -> crate::params::ParamsFile {
    let mut file = crate::params::ParamsFile::from_calibration(result, dataset);
    file.quality = serde_json::to_value(crate::quality::QualityRecord::new(
        dataset,
        screening,
        &result.settings.exclude,
    ))
    .ok();
    file.record_uncertainty(uncertainty);
    file
}

/// The calibrated model's parameter file as bytes (made once per calibration, [`params_file`]).
pub fn export_params(cal: &session::Calibrated) -> anyhow::Result<Vec<u8>> {
    let mut text = serde_json::to_vec_pretty(&cal.params)?;
    text.push(b'\n');
    Ok(text)
}

/// The name the workbench's report gives the parameters it shows: they are the session's last
/// calibration (the file "Parameters (JSON)…" exports), not a file on disk.
pub const REPORT_PARAMS_NAME: &str = "the workbench's calibration (Export → Parameters)";

/// The calibration report of the last calibration, as `dualcal report` writes it for the exported
/// parameter file (the same engine function, [`crate::report::Report::build_from`]).
pub fn export_report(session: &Session, cal: &session::Calibrated) -> anyhow::Result<Vec<u8>> {
    let input = crate::report::ReportInput {
        dataset: &session.dataset,
        robot: &session.robot,
        nominal: &session.nominal.model,
    };
    let report = crate::report::Report::build_from(
        input,
        &cal.params,
        std::path::Path::new(REPORT_PARAMS_NAME),
    )?;
    Ok(crate::report::render(&report).into_bytes())
}

/// The calibrated robot description.
pub fn export_urdf(session: &Session, cal: &session::Calibrated) -> anyhow::Result<Vec<u8>> {
    let text = crate::urdf_export::calibrated_urdf(&session.robot, &cal.result.calibrated)?;
    Ok(text.into_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::Analysis;
    use crate::app::session::Calibrated;
    use crate::side::Side;
    use crate::solver::Calibrator;
    use std::path::Path;

    fn calibrated_example() -> (Session, Calibrated) {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
        let session = Session::load(&dir, None).unwrap();
        let result = Calibrator::new(&session.dataset, &session.nominal.model)
            .run()
            .unwrap();
        assert!(result.is_converged());
        let analysis = Analysis::compute(
            &session.dataset,
            &result.calibrated,
            &session.body_from_left_base(),
        )
        .unwrap();
        let screening =
            crate::exclusion::screen_result(&session.dataset, &result, &Default::default());
        let uncertainty = crate::solver::uncertainty::for_result(&session.dataset, &result);
        let params = params_file(&session.dataset, &result, &screening, &uncertainty);
        (
            session,
            Calibrated {
                uncertainty,
                params,
                result,
                analysis,
                screening,
                solver_secs: 0.0,
            },
        )
    }

    fn max_dh_difference(
        a: &crate::kinematics::DualArmModel,
        b: &crate::kinematics::DualArmModel,
    ) -> f64 {
        Side::BOTH
            .iter()
            .flat_map(|&s| {
                let (a, b) = (a.arm(s).dh().unwrap(), b.arm(s).dh().unwrap());
                a.iter().zip(b).flat_map(|(x, y)| {
                    [
                        (x.a_mm - y.a_mm).abs(),
                        (x.d_mm - y.d_mm).abs(),
                        (x.theta_rad - y.theta_rad).abs(),
                        (x.alpha_rad - y.alpha_rad).abs(),
                    ]
                })
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn exports_read_back_as_the_calibrated_model() {
        let (session, cal) = calibrated_example();

        let json = export_params(&cal).unwrap();
        let file = crate::params::ParamsFile::parse(Path::new("params.json"), &json).unwrap();
        let model = file.to_model().unwrap();
        assert!(max_dh_difference(&model, &cal.result.calibrated) < 1e-9);
        assert!(file.termination.is_some() && file.method.is_some());

        let urdf = String::from_utf8(export_urdf(&session, &cal).unwrap()).unwrap();
        let robot = crate::robot::RobotDescription::load(
            crate::robot::RobotSource::Text {
                text: &urdf,
                path: None,
            },
            &Default::default(),
        )
        .unwrap();
        let back = robot
            .dh_model(session.dataset.nominal_reflectors_mm.clone())
            .unwrap();
        assert!(max_dh_difference(&back, &cal.result.calibrated) < 1e-6);

        let csv = String::from_utf8(export_csv(&session).unwrap()).unwrap();
        let n = session.dataset.arms.left.measurements.len()
            + session.dataset.arms.right.measurements.len();
        assert_eq!(csv.lines().count(), n + 1);
        assert!(csv.starts_with("id,arm,split,worst_pos_mm"));

        // The report of the workbench's calibration is the one `dualcal report` writes for the
        // exported parameter file (but for the time it was made and the parameters' name).
        let html = String::from_utf8(export_report(&session, &cal).unwrap()).unwrap();
        let ws = crate::workspace::Workspace::load(
            &session.dataset.dir,
            &crate::workspace::WorkspaceOptions::default(),
        )
        .unwrap();
        let mut cli =
            crate::report::Report::build(&ws, &file, Path::new(REPORT_PARAMS_NAME)).unwrap();
        let ours = crate::report::Report::build_from(
            crate::report::ReportInput {
                dataset: &session.dataset,
                robot: &session.robot,
                nominal: &session.nominal.model,
            },
            &cal.params,
            Path::new(REPORT_PARAMS_NAME),
        )
        .unwrap();
        cli.generated_utc.clone_from(&ours.generated_utc);
        let (a, b) = (crate::report::render(&cli), crate::report::render(&ours));
        let at = a.bytes().zip(b.bytes()).position(|(x, y)| x != y);
        assert!(
            at.is_none() && a.len() == b.len(),
            "the reports differ at byte {at:?}: `{}` against `{}`",
            at.map_or("", |k| &a[k.saturating_sub(80)..(k + 80).min(a.len())]),
            at.map_or("", |k| &b[k.saturating_sub(80)..(k + 80).min(b.len())]),
        );
        assert!(
            html.contains("<section id=\"warnings\">"),
            "{}",
            &html[..200]
        );
    }
}
