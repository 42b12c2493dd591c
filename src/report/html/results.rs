//! The sections on how well: accuracy, figures, worst configurations, screening, warnings.

use super::{escape, num, split_name, table, td};
use crate::analysis::Indicator;
use crate::metrics::comparison_blocks;
use crate::report::Report;
use crate::report::svg;
use crate::report::warnings::{NOISE_RATIO_THRESHOLD, WarningLevel};
use crate::side::{PerSide, Side};
use std::fmt::Write as _;

pub(super) fn accuracy(r: &Report) -> String {
    let mut out = String::from(
        "<p class=\"muted\">The paper's figures (eqs. 5–8), from <code>metrics::evaluate</code> as \
         <code>dualcal evaluate</code> prints them: relative — the distance errors Δd between the \
         configurations of one arm; collaborative — between the two arms' reflectors. Change: \
         relative change of an error (negative is better), percentage points of a frequency.</p>",
    );
    let excluded: usize = r.dataset.arms.values().map(|a| a.excluded).sum();
    if excluded > 0 {
        let _ = write!(
            out,
            "<p>Without the {excluded} configuration(s) left out of the calibration.</p>"
        );
    }
    let names: Vec<String> = r
        .dataset
        .reflectors
        .iter()
        .map(|(n, _)| n.clone())
        .collect();
    for a in &r.accuracy {
        let split = split_name(a.split);
        let _ = write!(
            out,
            "<h3>On the {split} configurations</h3><div class=\"figs\">"
        );
        for block in comparison_blocks(&a.before, &a.after, &names) {
            let cell = |text: &str, value: Option<f64>, model: &str, key: &str| match value {
                Some(v) => format!(
                    "<td class=\"n\" data-key=\"{}.{}.{}\" data-model=\"{model}\" \
                     data-value=\"{v:?}\">{}</td>",
                    a.split.name(),
                    block.key,
                    escape(key),
                    escape(text)
                ),
                None => num(text),
            };
            let rows: Vec<Vec<String>> = block
                .rows
                .iter()
                .map(|row| {
                    vec![
                        td(row.label.trim()),
                        cell(&row.before, row.before_value, "nominal", &row.key),
                        cell(&row.after, row.after_value, "calibrated", &row.key),
                        num(&row.change),
                    ]
                })
                .collect();
            out.push_str(&table(
                &format!("{} ({split})", block.title),
                &["figure", "nominal", "calibrated", "change"],
                &rows,
            ));
        }
        out.push_str("</div>");
    }
    if r.accuracy.is_empty() {
        out.push_str("<p class=\"bad\">Too few configurations for any accuracy figure.</p>");
    }
    out
}

fn indicator_title(i: Indicator) -> &'static str {
    match i {
        Indicator::RelativePosition(Side::Left) => "left arm (relative)",
        Indicator::RelativePosition(Side::Right) => "right arm (relative)",
        _ => "collaborative",
    }
}

/// An SVG figure with its caption, or the drawing error in its place.
fn figure(svg: Result<String, String>, caption: &str) -> String {
    match svg {
        Ok(svg) => format!(
            "<figure>{svg}<figcaption>{}</figcaption></figure>",
            escape(caption)
        ),
        Err(e) => format!("<p class=\"bad\">{}</p>", escape(&e)),
    }
}

pub(super) fn figures(r: &Report) -> String {
    let f = &r.figures;
    let split = split_name(f.split);
    let mut out = format!(
        "<p class=\"muted\">On the {split} configurations. Histograms: every reflector's signed \
         distance error Δd of every pair, over ± the largest (grey lines at ±0.3 and ±0.6 mm). Box \
         plots: per pair the signed Δd of the reflector with the largest |Δd| (quartiles, Tukey \
         whiskers, dots at the extremes). The nominal model has scales of its own.</p>"
    );
    for (k, model, colour) in [
        (0, "nominal", svg::NOMINAL),
        (1, "calibrated", svg::CALIBRATED),
    ] {
        let _ = write!(
            out,
            "<h3>Histograms of Δd, {model} model</h3><div class=\"figs\">"
        );
        for (indicator, before, after) in &f.histograms {
            let title = indicator_title(*indicator);
            let h = if k == 0 { before } else { after };
            match h.as_ref().filter(|h| h.samples > 0) {
                Some(h) => out.push_str(&figure(
                    svg::histogram(&format!("{title}, {model}"), "Δd (mm)", h, colour),
                    &format!(
                        "{title}, {model}: {} samples, bins of {:.4} mm",
                        h.samples,
                        h.bin_width()
                    ),
                )),
                None => {
                    let _ = write!(
                        out,
                        "<p>{title}, {model}: not measurable from this data.</p>"
                    );
                }
            }
        }
        out.push_str("</div>");
    }
    out.push_str("<h3>Box plots per arm</h3><div class=\"figs\">");
    for (model, k, colour) in [
        ("nominal", 0, svg::NOMINAL),
        ("calibrated", 1, svg::CALIBRATED),
    ] {
        let boxes: Vec<(&str, _)> = f
            .boxes
            .iter()
            .map(|(i, b, a)| {
                let label = match i {
                    Indicator::RelativePosition(Side::Left) => "left",
                    Indicator::RelativePosition(Side::Right) => "right",
                    _ => "collaborative",
                };
                (label, if k == 0 { *b } else { *a })
            })
            .collect();
        let n: Vec<String> = boxes
            .iter()
            .map(|(l, b)| format!("{l} {}", b.map_or(0, |b| b.n)))
            .collect();
        out.push_str(&figure(
            svg::box_plot(
                &format!("{model} model"),
                "worst-reflector Δd (mm)",
                &boxes,
                colour,
            ),
            &format!("{model}: pairs {}", n.join(", ")),
        ));
    }
    out.push_str("</div>");
    out
}

pub(super) fn worst(r: &Report) -> String {
    let mut out = String::from(
        "<p class=\"muted\">The configurations with the largest |Δd| over every pair involving them \
         (relative and collaborative), under the calibrated model; the nominal model's figure beside \
         it. Rigidity: the largest deviation of the measured distances between its reflectors from \
         the model's.</p>",
    );
    for (side, rows) in r.worst.iter().filter(|(s, _)| r.dataset.measured[*s]) {
        let rows: Vec<Vec<String>> = rows
            .iter()
            .enumerate()
            .map(|(k, w)| {
                vec![
                    num(&(k + 1).to_string()),
                    td(&w.id),
                    td(split_name(w.split)),
                    num(&format!("{:.4}", w.worst_pos_mm)),
                    num(&w
                        .nominal_worst_pos_mm
                        .map_or("—".into(), |v| format!("{v:.4}"))),
                    num(&w
                        .worst_ori_rad
                        .map_or("—".into(), |v| format!("{:.3}", v * 1e3))),
                    num(&format!("{:.4}", w.rigidity_mm)),
                    td(w.flag.unwrap_or("")),
                    td(if w.excluded { "excluded" } else { "kept" }),
                ]
            })
            .collect();
        out.push_str(&table(
            &format!("{side} arm"),
            &[
                "#",
                "id",
                "split",
                "worst |Δd| (mm)",
                "nominal (mm)",
                "worst Δo (mrad)",
                "rigidity (mm)",
                "screening flag",
                "status",
            ],
            &rows,
        ));
    }
    out
}

pub(super) fn screening(r: &Report) -> String {
    let s = &r.screening;
    let mut out = format!(
        "<p>{} ({} flag(s) on {} configuration(s); {} kept in the calibration). See \
         docs/reliability.md for the rules.</p>",
        if s.recorded {
            "The parameter file's screening of the calibrated model"
        } else {
            "The screening of the calibrated model, computed by this report (the parameter file \
             records none)"
        },
        s.record.flags.len(),
        {
            let mut c: Vec<_> = s.record.flags.iter().map(|f| f.config).collect();
            crate::sort::sort(&mut c);
            c.dedup();
            c.len()
        },
        s.kept_suspects.len()
    );
    let excluded = |f: &crate::quality::Flag| !s.kept_suspects.iter().any(|k| k.config == f.config);
    let rows: Vec<Vec<String>> = s
        .record
        .flags
        .iter()
        .map(|f| {
            vec![
                td(f.config.side.name()),
                td(&f.id),
                num(&f.line.to_string()),
                td(split_name(f.split)),
                td(f.kind.label()),
                num(&format!("{:.3}", f.size_mm)),
                num(&format!("{:.3}", f.threshold_mm)),
                td(if excluded(f) { "excluded" } else { "kept" }),
                td(&f.reason),
            ]
        })
        .collect();
    if !rows.is_empty() {
        out.push_str(&table(
            "Suspect configurations",
            &[
                "arm",
                "id",
                "line",
                "split",
                "kind",
                "size (mm)",
                "threshold (mm)",
                "status",
                "reason",
            ],
            &rows,
        ));
    }
    let rows: Vec<Vec<String>> = s
        .record
        .excluded
        .iter()
        .map(|e| vec![td(e.arm.name()), td(&e.id), td(&e.reason)])
        .collect();
    if rows.is_empty() {
        out.push_str("<p>No configuration was left out.</p>");
    } else {
        out.push_str(&table(
            "Left out of the calibration",
            &["arm", "id", "why"],
            &rows,
        ));
    }
    if !s.record.findings.is_empty() {
        out.push_str("<p>Whole-file findings:</p><ul>");
        for f in &s.record.findings {
            let _ = write!(out, "<li>{}</li>", escape(&f.message));
        }
        out.push_str("</ul>");
    }
    out
}

pub(super) fn warnings(r: &Report) -> String {
    let mut out = format!(
        "<p class=\"muted\">The tracker's noise is its MPE at the arm's mean measuring distance, \
         <code>mpe_um + mpe_um_per_m · L</code> from the dataset's <code>[tracker]</code> ({} µm + \
         {} µm/m). With a point error of σ = MPE/2 per axis a distance between two points errs by \
         MPE/√2 ≈ 0.71 MPE (RMS), so a model that explains the data leaves a residual near 1× the \
         MPE; above {NOISE_RATIO_THRESHOLD}× the geometric model does not explain the data.</p>",
        r.dataset.tracker.mpe_um, r.dataset.tracker.mpe_um_per_m
    );
    out.push_str(&noise_table(&r.noise));
    if r.warnings.is_empty() {
        out.push_str("<p class=\"good\">No warning.</p>");
    } else {
        out.push_str("<ul>");
        for w in &r.warnings {
            let (class, label) = match w.level {
                WarningLevel::Warning => ("warning", "Warning"),
                WarningLevel::Note => ("note", "Note"),
            };
            let _ = write!(
                out,
                "<li class=\"{class}\"><strong>{label}:</strong> {}</li>",
                escape(&w.text)
            );
        }
        out.push_str("</ul>");
    }
    out
}

fn noise_table(noise: &PerSide<Option<crate::report::NoiseCheck>>) -> String {
    let rows: Vec<Vec<String>> = noise
        .iter()
        .filter_map(|(side, c)| {
            let c = c.as_ref()?;
            Some(vec![
                td(side.name()),
                td(split_name(c.split)),
                num(&format!("{:.4}", c.rms_mm)),
                num(&format!("{:.4}", c.mpe_mm)),
                format!(
                    "<td class=\"n {}\" data-noise-ratio=\"{}\">{:.2}×</td>",
                    if c.exceeded() { "bad" } else { "good" },
                    side.name(),
                    c.ratio
                ),
            ])
        })
        .collect();
    table(
        "Calibrated residual against the tracker's noise",
        &[
            "arm",
            "split",
            "positioning RMS (mm)",
            "MPE (mm)",
            "RMS / MPE",
        ],
        &rows,
    )
}
