//! `dualcal report` (issue 22): the HTML report of a calibration on simulated data — every section,
//! the accuracy tables equal to `dualcal evaluate --json`'s figures, the σ equal to the parameter
//! file's, tags balanced and user strings escaped, the residual-against-noise warning on data with
//! unmodelled joint errors and not on clean data, σ and screening computed when the file has no
//! record of them, and bad input refused naming the file.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

const SECTIONS: [&str; 10] = [
    "dataset",
    "robot",
    "method",
    "identifiability",
    "parameters",
    "accuracy",
    "figures",
    "worst",
    "screening",
    "warnings",
];

/// The warning's words (the apostrophe is escaped in the HTML).
const NOISE_WARNING: &str = "× the tracker&#39;s noise (MPE): the geometric model does not explain";

fn dualcal(args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Simulate a small dataset into `dir/name` (extra `simulate` arguments), calibrate it into
/// `dir/name.json`, report into `dir/name.html`; the paths of dataset, parameters and report.
fn calibrated(dir: &Path, name: &str, extra: &[&str]) -> (PathBuf, PathBuf, PathBuf) {
    let data = dir.join(name);
    let params = dir.join(format!("{name}.json"));
    let html = dir.join(format!("{name}.html"));
    let mut args = vec![
        "simulate",
        "--out",
        s(&data),
        "--seed",
        "3",
        "--configs",
        "50",
        "--cal",
        "34",
    ];
    args.extend_from_slice(extra);
    ok(&dualcal(&args));
    ok(&dualcal(&[
        "calibrate",
        s(&data),
        "--out",
        s(&params),
        "--quiet",
    ]));
    ok(&dualcal(&[
        "report",
        s(&data),
        "--params",
        s(&params),
        "--out",
        s(&html),
    ]));
    (data, params, html)
}

/// The value of attribute `name` in the tag text `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let k = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    let end = tag[k..].find('"')?;
    Some(&tag[k..k + end])
}

/// Every opening tag `<td …>` of the HTML that has attribute `name`.
fn cells_with<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    html.split("<td")
        .skip(1)
        .filter_map(|rest| rest.split('>').next())
        .filter(|tag| tag.contains(&format!(" {name}=\"")))
        .collect()
}

fn count(html: &str, needle: &str) -> usize {
    html.matches(needle).count()
}

fn assert_well_formed(html: &str) {
    assert!(html.starts_with("<!DOCTYPE html>"), "{}", &html[..40]);
    for (open, close) in [
        ("<section", "</section>"),
        ("<table>", "</table>"),
        ("<tr>", "</tr>"),
        ("<td", "</td>"),
        ("<th>", "</th>"),
        ("<svg", "</svg>"),
        ("<ul>", "</ul>"),
        ("<figure>", "</figure>"),
        ("<h2>", "</h2>"),
        ("<h3>", "</h3>"),
    ] {
        assert_eq!(count(html, open), count(html, close), "{open} vs {close}");
    }
    // `<p` alone would count the SVG's `<path` and `<polyline`.
    assert_eq!(
        count(html, "<p>") + count(html, "<p class="),
        count(html, "</p>")
    );
    assert_eq!(count(html, "<html"), 1);
    assert!(html.trim_end().ends_with("</html>"));
    // Self-contained: no script, nothing fetched.
    for banned in [
        "<script",
        "<link",
        "<img",
        "src=\"http",
        "href=\"http",
        "@import",
    ] {
        assert!(!html.contains(banned), "{banned}");
    }
}

/// `dualcal evaluate --json` of `params` (or the nominal model) on `split`.
fn evaluate(data: &Path, params: Option<&Path>, split: &str) -> Value {
    let mut args = vec!["evaluate", s(data), "--split", split, "--json"];
    match params {
        Some(p) => args.extend(["--params", s(p)]),
        None => args.push("--nominal"),
    }
    serde_json::from_str(&ok(&dualcal(&args))).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

#[test]
fn the_report_shows_every_section_with_the_evaluated_figures_and_the_recorded_sigmas() {
    let dir = tempfile::tempdir().unwrap();
    let (data, params, html_path) = calibrated(dir.path(), "clean", &[]);
    let html = std::fs::read_to_string(&html_path).unwrap();
    assert_well_formed(&html);
    for id in SECTIONS {
        assert_eq!(count(&html, &format!("<section id=\"{id}\">")), 1, "{id}");
    }
    assert!(count(&html, "<svg") >= 8, "histograms and box plots");

    // The accuracy tables: every figure equal to `dualcal evaluate --json`'s.
    let mut evaluated = std::collections::HashMap::new();
    for split in ["cal", "ver"] {
        evaluated.insert((split, "nominal"), evaluate(&data, None, split));
        evaluated.insert((split, "calibrated"), evaluate(&data, Some(&params), split));
    }
    let cells = cells_with(&html, "data-key");
    assert!(cells.len() >= 2 * 2 * 3 * 12, "{}", cells.len());
    for tag in &cells {
        let key = attr(tag, "data-key").unwrap();
        let model = attr(tag, "data-model").unwrap();
        let value: f64 = attr(tag, "data-value").unwrap().parse().unwrap();
        let mut parts = key.splitn(2, '.');
        let split = parts.next().unwrap();
        let pointer = format!("/{}", parts.next().unwrap().replace('.', "/"));
        let want = evaluated[&(split, model)]
            .pointer(&pointer)
            .and_then(Value::as_f64)
            .unwrap_or_else(|| panic!("{key}: not in the evaluation"));
        assert!(close(value, want), "{key} {model}: {value} vs {want}");
    }

    // The σ: those of the parameter file's `uncertainty` record, every identified parameter.
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&params).unwrap()).unwrap();
    let mut checked = 0;
    for side in ["left", "right"] {
        for p in file["uncertainty"][side]["parameters"].as_array().unwrap() {
            let name = p["name"].as_str().unwrap();
            let tag = cells_with(&html, "data-param")
                .into_iter()
                .find(|t| attr(t, "data-param") == Some(&format!("{side}.{name}")))
                .unwrap_or_else(|| panic!("{side}.{name} not in the report"));
            let sigma: f64 = attr(tag, "data-sigma").unwrap().parse().unwrap();
            assert_eq!(sigma, p["sigma"].as_f64().unwrap(), "{side}.{name}");
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked}");
    assert!(html.contains("σ from the parameter file&#39;s `uncertainty` record"));

    // Clean data: the residual is at the tracker's noise, no warning of it.
    assert!(!html.contains(NOISE_WARNING));
    let ratios = noise_ratios(&html);
    assert_eq!(ratios.len(), 2);
    assert!(ratios.iter().all(|&r| r < 2.0), "{ratios:?}");
}

/// The RMS / MPE ratios of the noise table (`1.23×`).
fn noise_ratios(html: &str) -> Vec<f64> {
    html.split("data-noise-ratio=\"")
        .skip(1)
        .map(|rest| {
            let text = &rest[rest.find('>').unwrap() + 1..];
            text[..text.find('×').unwrap()].parse().unwrap()
        })
        .collect()
}

#[test]
fn unmodelled_joint_errors_are_reported_as_a_residual_far_above_the_tracker_noise() {
    let dir = tempfile::tempdir().unwrap();
    let (_, _, html_path) = calibrated(dir.path(), "joints", &["--joint-error-mrad", "0.5"]);
    let html = std::fs::read_to_string(&html_path).unwrap();
    assert_well_formed(&html);
    assert!(html.contains(NOISE_WARNING), "no noise warning");
    assert!(html.contains("verification residual (RMS) is"));
    let ratios = noise_ratios(&html);
    assert!(ratios.iter().all(|&r| r > 3.0), "{ratios:?}");
    // The warning's N is the table's ratio.
    let n = format!("{:.1}× the tracker&#39;s noise", ratios[0]);
    assert!(html.contains(&n), "{n}");
}

#[test]
fn without_uncertainty_and_quality_records_the_report_computes_them_as_calibrate_does() {
    let dir = tempfile::tempdir().unwrap();
    let (data, params, _) = calibrated(dir.path(), "data", &[]);
    let mut file: Value = serde_json::from_str(&std::fs::read_to_string(&params).unwrap()).unwrap();
    let recorded = file["uncertainty"].clone();
    let obj = file.as_object_mut().unwrap();
    obj.remove("uncertainty");
    obj.remove("quality");
    let bare = dir.path().join("bare.json");
    std::fs::write(&bare, serde_json::to_string(&file).unwrap()).unwrap();
    let out = dir.path().join("bare.html");
    ok(&dualcal(&[
        "report",
        s(&data),
        "--params",
        s(&bare),
        "--out",
        s(&out),
    ]));
    let html = std::fs::read_to_string(&out).unwrap();
    assert_well_formed(&html);
    assert!(html.contains("σ computed by this report from the data"));
    assert!(html.contains("The screening of the calibrated model, computed by this report"));
    let cells = cells_with(&html, "data-sigma");
    for side in ["left", "right"] {
        for p in recorded[side]["parameters"].as_array().unwrap() {
            let key = format!("{side}.{}", p["name"].as_str().unwrap());
            let tag = cells
                .iter()
                .find(|t| attr(t, "data-param") == Some(key.as_str()))
                .unwrap_or_else(|| panic!("{key}"));
            let sigma: f64 = attr(tag, "data-sigma").unwrap().parse().unwrap();
            let want = p["sigma"].as_f64().unwrap();
            assert!(
                (sigma - want).abs() <= 1e-9 * want,
                "{key}: {sigma} vs {want}"
            );
        }
    }
}

#[test]
fn user_strings_are_escaped() {
    let dir = tempfile::tempdir().unwrap();
    // A dataset directory whose name is markup.
    let hostile = "<b>&\"x'</td></table>";
    let (_, _, html_path) = calibrated(dir.path(), hostile, &[]);
    let html = std::fs::read_to_string(&html_path).unwrap();
    assert_well_formed(&html);
    assert!(!html.contains(hostile));
    assert!(html.contains("&lt;b&gt;&amp;&quot;x&#39;&lt;/td&gt;&lt;/table&gt;"));
}

#[test]
fn bad_input_is_refused_naming_the_file_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let (data, params, _) = calibrated(dir.path(), "data", &[]);
    let out = dir.path().join("out.html");
    let refused = |params: &Path, out: &Path, says: &str| {
        let o = dualcal(&["report", s(&data), "--params", s(params), "--out", s(out)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "accepted");
        assert!(err.contains(says), "{err}");
    };
    // Not JSON: file, line and column.
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{\n  \"format\": ").unwrap();
    refused(&broken, &out, &format!("{}:2:", broken.display()));
    // Missing.
    let missing = dir.path().join("missing.json");
    refused(
        &missing,
        &out,
        &format!("{}: cannot read", missing.display()),
    );
    // A chain file for the built-in robot: the field named, with the file.
    let mut file: Value = serde_json::from_str(&std::fs::read_to_string(&params).unwrap()).unwrap();
    file["arms"]["left"].as_object_mut().unwrap().remove("dh");
    file["arms"]["left"]["chain"] = serde_json::json!({
        "base_link": "a", "tip_link": "b",
        "joints": [{"name": "j", "tx": 0.0, "ty": 0.0, "tz": 0.0, "rx": 0.0, "ry": 0.0, "rz": 0.0}]
    });
    let chain = dir.path().join("chain.json");
    std::fs::write(&chain, serde_json::to_string(&file).unwrap()).unwrap();
    refused(&chain, &out, &chain.display().to_string());
    assert!(!out.exists());
    // The output may not be an input: the parameter file, or the dataset's CSV.
    let before = std::fs::read(&params).unwrap();
    refused(&params, &params, "refusing to overwrite the input file");
    assert_eq!(std::fs::read(&params).unwrap(), before);
    refused(
        &params,
        &data.join("left.csv"),
        "refusing to overwrite the input file",
    );
}

/// A browser on PATH that `--pdf` would find (CI installs Debian's Chromium for the browser test).
fn browser_on_path() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    [
        "chromium",
        "chromium-browser",
        "google-chrome",
        "google-chrome-stable",
    ]
    .iter()
    .find_map(|name| {
        std::env::split_paths(&path)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
    })
}

#[test]
fn the_report_prints_to_pdf_with_a_browser_and_says_so_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let (data, params, _) = calibrated(dir.path(), "data", &[]);
    let html = dir.path().join("r.html");
    let pdf = dir.path().join("r.pdf");
    let args = [
        "report",
        s(&data),
        "--params",
        s(&params),
        "--out",
        s(&html),
        "--pdf",
        s(&pdf),
    ];
    // No browser: the HTML is written, the command fails naming the PDF and what to install.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .env("DUALCAL_PDF_BROWSER", dir.path().join("no-such-browser"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains(&pdf.display().to_string()), "{err}");
    assert!(html.is_file() && !pdf.exists());
    // With the browser on PATH: a PDF of several pages.
    let Some(browser) = browser_on_path() else {
        eprintln!(
            "no Chromium on PATH: the PDF itself is not checked here (tools/test installs it)"
        );
        return;
    };
    std::fs::remove_file(&html).unwrap();
    let out = ok(&dualcal(&args));
    assert!(
        out.contains("PDF written to"),
        "{out} ({})",
        browser.display()
    );
    let bytes = std::fs::read(&pdf).unwrap();
    assert!(bytes.starts_with(b"%PDF"));
    // Page objects (`/Type /Page`, not the `/Type /Pages` tree).
    let pages = [&b"/Type /Page"[..], &b"/Type/Page"[..]]
        .iter()
        .map(|tag| {
            bytes
                .windows(tag.len() + 1)
                .filter(|w| w.starts_with(tag) && w[tag.len()] != b's')
                .count()
        })
        .sum::<usize>();
    assert!(pages >= 2, "{pages} page(s)");
    // No temporary file left beside it.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with(".dualcal-report-")),
        "{names:?}"
    );
}
