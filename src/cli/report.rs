//! `dualcal report`: the calibration report as one self-contained HTML file (the engine's `report`).

use super::common::load_workspace;
use crate::output;
use crate::params::ParamsFile;
use crate::report::{self, Report, ReportError};
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Dataset directory or its dataset.toml.
    pub dataset: PathBuf,
    /// Parameter file (dualcal-params/1), as `dualcal calibrate --out` writes it.
    #[arg(long)]
    pub params: PathBuf,
    /// The HTML file to write (replaced if it exists; never one of the inputs).
    #[arg(long)]
    pub out: PathBuf,
    /// Also print the report to this PDF file, with a Chromium-based browser found on PATH
    /// (`chromium`, `chromium-browser`, `google-chrome`, `google-chrome-stable`, `microsoft-edge`) or
    /// named by the environment variable DUALCAL_PDF_BROWSER. Without one the HTML is still written
    /// and the command fails saying so.
    #[arg(long)]
    pub pdf: Option<PathBuf>,
}

/// `dualcal report`; `pdf_browser` is `DUALCAL_PDF_BROWSER` (the browser `--pdf` prints with, else
/// one found on PATH).
pub fn run(a: &ReportArgs, pdf_browser: Option<&Path>) -> Result<()> {
    let ws = load_workspace(&a.dataset)?;
    let mut inputs: Vec<PathBuf> = ws.dataset.files().to_vec();
    inputs.extend(ws.dataset.robot.clone());
    inputs.push(a.params.clone());
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    output::refuse_overwrite_input(&a.out, &inputs)?;
    if let Some(pdf) = &a.pdf {
        output::refuse_overwrite_input(pdf, &inputs)?;
    }
    let params = ParamsFile::read(&a.params).map_err(ReportError::from)?;
    let report = Report::build(&ws, &params, &a.params)?;
    let html = report::render(&report);
    output::write_atomic(&a.out, html.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    let warnings = report
        .warnings
        .iter()
        .filter(|w| w.level == report::WarningLevel::Warning)
        .count();
    outln!(
        "report written to {} ({} warning(s), {} note(s))",
        a.out.display(),
        warnings,
        report.warnings.len() - warnings
    );
    for w in &report.warnings {
        if w.level == report::WarningLevel::Warning {
            eprintln!("warning: {}", w.text);
        }
    }
    if let Some(pdf) = &a.pdf {
        let browser = print_pdf(&a.out, pdf, pdf_browser)?;
        outln!(
            "PDF written to {} (printed by {})",
            pdf.display(),
            browser.display()
        );
    }
    Ok(())
}

/// The Chromium-based browsers `--pdf` looks for on PATH, in order.
const PDF_BROWSERS: [&str; 5] = [
    "chromium",
    "chromium-browser",
    "google-chrome",
    "google-chrome-stable",
    "microsoft-edge",
];

/// The browser that prints the PDF: `named` (DUALCAL_PDF_BROWSER), else the first of
/// [`PDF_BROWSERS`] on PATH.
fn pdf_browser(named: Option<&Path>) -> Option<PathBuf> {
    if let Some(named) = named {
        return Some(named.to_path_buf());
    }
    let path = std::env::var_os("PATH")?;
    PDF_BROWSERS.iter().find_map(|name| {
        std::env::split_paths(&path)
            .map(|dir| dir.join(name))
            .find(|candidate| candidate.is_file())
    })
}

/// Print the HTML report `html` to `pdf` with a headless browser: into a temporary file beside
/// `pdf`, checked to be a PDF, then renamed (an existing `pdf` stays as it was on failure). The
/// browser's name. `named`: the browser DUALCAL_PDF_BROWSER names.
fn print_pdf(html: &Path, pdf: &Path, named: Option<&Path>) -> Result<PathBuf> {
    let Some(browser) = pdf_browser(named) else {
        anyhow::bail!(
            "{}: no browser to print the PDF with: install Chromium or Google Chrome, or name one \
             with DUALCAL_PDF_BROWSER (looked on PATH for {}); the HTML report {} was written",
            pdf.display(),
            PDF_BROWSERS.join(", "),
            html.display()
        );
    };
    let html_abs = html
        .canonicalize()
        .with_context(|| format!("{}: cannot resolve its path", html.display()))?;
    let dir = match pdf.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // The browser writes into a temporary folder beside the PDF (its file gets the usual mode);
    // the rename is then atomic.
    let tmp_dir = tempfile::Builder::new()
        .prefix(".dualcal-report-")
        .tempdir_in(&dir)
        .with_context(|| format!("{}: cannot create a temporary folder", dir.display()))?;
    let tmp = tmp_dir.path().join("report.pdf");
    let profile = tempfile::tempdir().context("a temporary browser profile")?;
    let mut print_arg = std::ffi::OsString::from("--print-to-pdf=");
    print_arg.push(&tmp);
    let mut profile_arg = std::ffi::OsString::from("--user-data-dir=");
    profile_arg.push(profile.path());
    let out = std::process::Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-pdf-header-footer",
        ])
        .arg(profile_arg)
        .arg(print_arg)
        .arg(format!("file://{}", html_abs.display()))
        .output()
        .with_context(|| format!("{}: cannot run {}", pdf.display(), browser.display()))?;
    let bytes = std::fs::read(&tmp).unwrap_or_default();
    if !out.status.success() || !bytes.starts_with(b"%PDF") {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let last: Vec<&str> = stderr.lines().rev().take(5).collect();
        anyhow::bail!(
            "{}: {} did not print the report ({}; {}); the HTML report {} was written",
            pdf.display(),
            browser.display(),
            out.status,
            last.into_iter().rev().collect::<Vec<_>>().join(" / "),
            html.display()
        );
    }
    std::fs::rename(&tmp, pdf).with_context(|| format!("writing {}", pdf.display()))?;
    Ok(browser)
}
