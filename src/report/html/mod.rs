//! The report as one self-contained HTML5 file: inline CSS, inline SVG, no script. Every string that
//! comes from the user's files (paths, ids, names, reasons) goes through [`escape`]. `setup` writes
//! what was calibrated and how (dataset, robot, method, identifiability, parameters, base), `results`
//! how well (accuracy, figures, worst configurations, screening, warnings).

mod results;
mod setup;

use super::Report;
use super::WarningLevel;
use crate::dataset::Split;
use results::{accuracy, figures, screening, warnings, worst};
use setup::{converged, dataset, identifiability, method, parameters, robot};
use std::fmt::Write as _;

/// The sections, in order: `id` and heading.
pub const SECTIONS: [(&str, &str); 10] = [
    ("dataset", "Dataset"),
    ("robot", "Robot"),
    ("method", "Method"),
    ("identifiability", "Identifiability"),
    ("parameters", "Parameters"),
    ("accuracy", "Accuracy before and after"),
    ("figures", "Figures"),
    ("worst", "Worst configurations"),
    ("screening", "Screening"),
    ("warnings", "Warnings"),
];

const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:0 auto;\
max-width:1200px;padding:0 1.5em 3em;color:#222;line-height:1.4}\
h1{margin-bottom:.2em}h2{border-bottom:2px solid #1f77b4;padding-bottom:.2em;margin-top:1.8em}\
h3{margin-bottom:.3em}table{border-collapse:collapse;margin:.5em 0 1em;font-size:.92em}\
th,td{border:1px solid #ccc;padding:.2em .55em;text-align:left;vertical-align:top}\
th{background:#f0f3f7}td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}\
caption{text-align:left;font-weight:600;padding:.2em 0}code{background:#f4f4f4;padding:0 .2em}\
.muted{color:#666}.figs{display:flex;flex-wrap:wrap;gap:.5em}figure{margin:0}\
figcaption{font-size:.85em;color:#555;max-width:380px}svg{max-width:100%;height:auto}\
li.warning{color:#8a1c1c}li.note{color:#444}.bad{color:#8a1c1c;font-weight:600}\
.good{color:#1d6b2a;font-weight:600}nav a{margin-right:.8em}\
.summary{background:#f6f8fa;border:1px solid #dde;padding:.6em 1em}\
@media print{nav{display:none}section{break-inside:avoid-page}}";

/// `text` with `&`, `<`, `>`, `"` and `'` replaced by their character references: safe inside an
/// element and inside a quoted attribute.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A table: header cells (plain text) and rows of cells (HTML, escaped by the caller).
fn table(caption: &str, head: &[&str], rows: &[Vec<String>]) -> String {
    let mut out = String::from("<table>");
    if !caption.is_empty() {
        let _ = write!(out, "<caption>{}</caption>", escape(caption));
    }
    out.push_str("<thead><tr>");
    for h in head {
        let _ = write!(out, "<th>{}</th>", escape(h));
    }
    out.push_str("</tr></thead><tbody>");
    for row in rows {
        out.push_str("<tr>");
        for cell in row {
            out.push_str(cell);
        }
        out.push_str("</tr>");
    }
    out.push_str("</tbody></table>");
    out
}

/// A text cell.
fn td(text: &str) -> String {
    format!("<td>{}</td>", escape(text))
}

/// A number cell.
fn num(text: &str) -> String {
    format!("<td class=\"n\">{}</td>", escape(text))
}

/// Key–value rows.
fn facts(rows: &[(&str, String)]) -> String {
    let rows: Vec<Vec<String>> = rows
        .iter()
        .map(|(k, v)| vec![format!("<th>{}</th>", escape(k)), td(v)])
        .collect();
    table("", &["", ""], &rows).replacen("<thead><tr><th></th><th></th></tr></thead>", "", 1)
}

fn section(id: &str, body: &str) -> String {
    let title = SECTIONS
        .iter()
        .find(|(s, _)| *s == id)
        .map_or(id, |(_, t)| t);
    format!(
        "<section id=\"{id}\"><h2>{}</h2>{body}</section>\n",
        escape(title)
    )
}

fn split_name(split: Split) -> &'static str {
    match split {
        Split::Cal => "calibration",
        Split::Ver => "verification",
        Split::All => "all",
    }
}

/// The report as HTML.
pub fn render(r: &Report) -> String {
    let mut out =
        String::from("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    let _ = writeln!(
        out,
        "<title>Calibration report — {}</title>\n<style>{STYLE}</style>\n</head>\n<body>",
        escape(&r.dataset.dir.display().to_string())
    );
    out.push_str(&header(r));
    out.push_str("<main>\n");
    out.push_str(&section("dataset", &dataset(r)));
    out.push_str(&section("robot", &robot(r)));
    out.push_str(&section("method", &method(r)));
    out.push_str(&section("identifiability", &identifiability(r)));
    out.push_str(&section("parameters", &parameters(r)));
    out.push_str(&section("accuracy", &accuracy(r)));
    out.push_str(&section("figures", &figures(r)));
    out.push_str(&section("worst", &worst(r)));
    out.push_str(&section("screening", &screening(r)));
    out.push_str(&section("warnings", &warnings(r)));
    out.push_str("</main>\n</body>\n</html>\n");
    out
}

fn header(r: &Report) -> String {
    let mut out = String::from("<header><h1>Calibration report</h1>");
    let _ = write!(
        out,
        "<p>Parameters <code>{}</code> on the dataset <code>{}</code>. Made by dualcal {} on {}.",
        escape(&r.params_path.display().to_string()),
        escape(&r.dataset.dir.display().to_string()),
        escape(&r.tool_version),
        escape(&r.generated_utc)
    );
    if let Some(p) = &r.provenance {
        let _ = write!(
            out,
            " The parameters were written by {} {}{}{}.",
            escape(&p.tool),
            escape(&p.version),
            p.date_utc
                .as_ref()
                .map_or(String::new(), |d| format!(" on {}", escape(d))),
            p.dataset.as_ref().map_or(String::new(), |d| format!(
                " from <code>{}</code>",
                escape(d)
            ))
        );
    }
    out.push_str("</p>");
    out.push_str(&summary(r));
    out.push_str("<nav>");
    for (id, title) in SECTIONS {
        let _ = write!(out, "<a href=\"#{id}\">{}</a>", escape(title));
    }
    out.push_str("</nav></header>\n");
    out
}

/// The verdict in three lines: residual against the noise, convergence, warnings.
fn summary(r: &Report) -> String {
    let mut out = String::from("<div class=\"summary\"><p>");
    for (side, check) in r.noise.iter() {
        let Some(c) = check else { continue };
        let class = if c.exceeded() { "bad" } else { "good" };
        let _ = write!(
            out,
            "{side} arm: {} positioning RMS {:.4} mm = <span class=\"{class}\">{:.1}× the \
             tracker's MPE</span>.<br>",
            split_name(c.split),
            c.rms_mm,
            c.ratio
        );
    }
    let warnings = r
        .warnings
        .iter()
        .filter(|w| w.level == WarningLevel::Warning)
        .count();
    let notes = r.warnings.len() - warnings;
    let _ = write!(
        out,
        "</p><p>The calibration {}. <a href=\"#warnings\">{warnings} warning(s), {notes} note(s)</a>.</p></div>",
        match converged(r) {
            (_, "yes") => "converged",
            (_, "no") => "<span class=\"bad\">did not converge</span>",
            _ => "may or may not have converged (the parameter file records no termination)",
        }
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_replaces_markup() {
        assert_eq!(
            escape(r#"<a href="x">&'</a>"#),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;&lt;/a&gt;"
        );
        assert_eq!(escape("Δd ≤ 0.3 mm"), "Δd ≤ 0.3 mm");
        let hostile = "</td></table><script>alert(1)</script>";
        let cell = td(hostile);
        assert!(!cell.contains("<script>") && cell.matches("</td>").count() == 1);
    }
}
