//! Text tables of accuracy reports (the CLI's output).

use super::{AccuracyReport, AccuracyStats};
use std::fmt::Write as _;

const COLUMN_TITLES: [&str; 3] = ["relative left", "relative right", "collaborative"];

/// The reflector names of a report without names at hand: a, b, c, … by position.
fn default_names(report: &AccuracyReport) -> Vec<String> {
    crate::kinematics::default_reflector_names(report.relative_left.pos_rms_per_reflector_mm.len())
        .to_vec()
}

/// Reads a row's value off the stats; `None` where the data cannot give it.
type RowValue = Box<dyn Fn(&AccuracyStats) -> Option<f64>>;

/// How a row's value is read off the stats and printed.
struct Row {
    label: String,
    /// `None`: not measurable from the data (the orientation with fewer than three reflectors).
    value: RowValue,
    kind: RowKind,
}

#[derive(Clone, Copy, PartialEq)]
enum RowKind {
    /// mm, printed with 3 decimals; lower is better.
    Mm,
    /// rad, printed in mrad with 3 decimals; lower is better.
    Mrad,
    /// fraction, printed in percent; higher is better.
    Percent,
    /// a count.
    Count,
}

/// What a figure the data cannot give shows.
pub const NOT_MEASURABLE: &str = "not measurable";

fn row(
    label: impl Into<String>,
    kind: RowKind,
    value: impl Fn(&AccuracyStats) -> Option<f64> + 'static,
) -> Row {
    Row {
        label: label.into(),
        value: Box::new(value),
        kind,
    }
}

/// The rows, one per reflector of `reflector_names` for the per-reflector RMS.
fn rows(reflector_names: &[String]) -> Vec<Row> {
    let mut out = vec![
        row("configurations", RowKind::Count, |s| {
            Some(s.n_configs as f64)
        }),
        row("pairs", RowKind::Count, |s| Some(s.n_pairs as f64)),
        row("positioning RMS (mm)", RowKind::Mm, |s| Some(s.pos_rms_mm)),
    ];
    for (k, name) in reflector_names.iter().enumerate() {
        out.push(row(
            format!("  reflector {name} RMS (mm)"),
            RowKind::Mm,
            move |s| s.pos_rms_per_reflector_mm.get(k).copied(),
        ));
    }
    out.extend([
        row("positioning max (mm)", RowKind::Mm, |s| Some(s.pos_max_mm)),
        row("|Δd| ≤ 0.3 mm", RowKind::Percent, |s| {
            Some(s.pos_within_0_3mm_frac)
        }),
        row("|Δd| ≤ 0.6 mm", RowKind::Percent, |s| {
            Some(s.pos_within_0_6mm_frac)
        }),
        row("orientation RMS (mrad)", RowKind::Mrad, |s| s.ori_rms_rad),
        row("orientation max (mrad)", RowKind::Mrad, |s| s.ori_max_rad),
        row("Δo ≤ 0.005 rad", RowKind::Percent, |s| {
            s.ori_within_0_005rad_frac
        }),
        row("Δo ≤ 0.01 rad", RowKind::Percent, |s| {
            s.ori_within_0_01rad_frac
        }),
    ]);
    out
}

fn format_value(kind: RowKind, v: Option<f64>) -> String {
    let Some(v) = v else {
        return NOT_MEASURABLE.into();
    };
    match kind {
        RowKind::Mm => format!("{v:.3}"),
        RowKind::Mrad => format!("{:.3}", v * 1e3),
        RowKind::Percent => format!("{:.2} %", v * 100.0),
        RowKind::Count => format!("{v:.0}"),
    }
}

/// The three columns; `None` for a kind of pairs the data cannot measure.
fn stats_of(report: &AccuracyReport) -> [Option<&AccuracyStats>; 3] {
    [
        Some(&report.relative_left),
        Some(&report.relative_right),
        report.collaborative.as_ref(),
    ]
}

const LABEL_WIDTH: usize = 24;

/// A table of one report: one column per set of pairs (reflectors named a, b, c, … by position).
pub fn format_table(report: &AccuracyReport) -> String {
    format_table_named(report, &default_names(report))
}

/// A table of one report, the per-reflector rows named `reflector_names`.
pub fn format_table_named(report: &AccuracyReport, reflector_names: &[String]) -> String {
    let stats = stats_of(report);
    let mut out = String::new();
    let _ = write!(out, "{:<LABEL_WIDTH$}", "");
    for t in COLUMN_TITLES {
        let _ = write!(out, "{t:>16}");
    }
    out.push('\n');
    for row in &rows(reflector_names) {
        let _ = write!(out, "{:<LABEL_WIDTH$}", row.label);
        for s in stats {
            let _ = write!(
                out,
                "{:>16}",
                format_value(row.kind, s.and_then(|s| (row.value)(s)))
            );
        }
        out.push('\n');
    }
    out
}

/// The change from `before` to `after`: relative reduction of an error, or percentage points of a
/// frequency.
fn format_change(kind: RowKind, before: Option<f64>, after: Option<f64>) -> String {
    let (Some(before), Some(after)) = (before, after) else {
        return "–".into();
    };
    match kind {
        RowKind::Count => String::new(),
        RowKind::Percent => format!("{:+.2} pp", (after - before) * 100.0),
        RowKind::Mm | RowKind::Mrad => {
            if before > 0.0 {
                format!("{:+.2} %", (after - before) / before * 100.0)
            } else {
                "–".into()
            }
        }
    }
}

/// Two reports side by side (typically nominal vs calibrated), one block per set of pairs, with the
/// change: relative change of errors (negative is better) and percentage points of frequencies.
pub fn format_comparison(
    before: &AccuracyReport,
    after: &AccuracyReport,
    labels: [&str; 2],
) -> String {
    format_comparison_named(before, after, labels, &default_names(before))
}

/// [`format_comparison`] with the per-reflector rows named `reflector_names`.
pub fn format_comparison_named(
    before: &AccuracyReport,
    after: &AccuracyReport,
    labels: [&str; 2],
    reflector_names: &[String],
) -> String {
    let rows = rows(reflector_names);
    let mut out = String::new();
    for ((title, b), a) in COLUMN_TITLES
        .iter()
        .zip(stats_of(before))
        .zip(stats_of(after))
    {
        if !out.is_empty() {
            out.push('\n');
        }
        let _ = writeln!(
            out,
            "{:<LABEL_WIDTH$}{:>14}{:>14}{:>14}",
            title, labels[0], labels[1], "change"
        );
        for row in &rows {
            let (vb, va) = (
                b.and_then(|b| (row.value)(b)),
                a.and_then(|a| (row.value)(a)),
            );
            let _ = writeln!(
                out,
                "{:<LABEL_WIDTH$}{:>14}{:>14}{:>14}",
                row.label,
                format_value(row.kind, vb),
                format_value(row.kind, va),
                format_change(row.kind, vb, va)
            );
        }
    }
    out
}
