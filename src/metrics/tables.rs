//! Text tables of accuracy reports (the CLI's output).

use super::{AccuracyReport, AccuracyStats};
use std::fmt::Write as _;

const COLUMN_TITLES: [&str; 3] = ["relative left", "relative right", "collaborative"];

/// How a row's value is read off the stats and printed.
struct Row {
    label: &'static str,
    value: fn(&AccuracyStats) -> f64,
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

const ROWS: [Row; 13] = [
    Row {
        label: "configurations",
        value: |s| s.n_configs as f64,
        kind: RowKind::Count,
    },
    Row {
        label: "pairs",
        value: |s| s.n_pairs as f64,
        kind: RowKind::Count,
    },
    Row {
        label: "positioning RMS (mm)",
        value: |s| s.pos_rms_mm,
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector a RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[0],
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector b RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[1],
        kind: RowKind::Mm,
    },
    Row {
        label: "  reflector c RMS (mm)",
        value: |s| s.pos_rms_per_reflector_mm[2],
        kind: RowKind::Mm,
    },
    Row {
        label: "positioning max (mm)",
        value: |s| s.pos_max_mm,
        kind: RowKind::Mm,
    },
    Row {
        label: "|Δd| ≤ 0.3 mm",
        value: |s| s.pos_within_0_3mm_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "|Δd| ≤ 0.6 mm",
        value: |s| s.pos_within_0_6mm_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "orientation RMS (mrad)",
        value: |s| s.ori_rms_rad,
        kind: RowKind::Mrad,
    },
    Row {
        label: "orientation max (mrad)",
        value: |s| s.ori_max_rad,
        kind: RowKind::Mrad,
    },
    Row {
        label: "Δo ≤ 0.005 rad",
        value: |s| s.ori_within_0_005rad_frac,
        kind: RowKind::Percent,
    },
    Row {
        label: "Δo ≤ 0.01 rad",
        value: |s| s.ori_within_0_01rad_frac,
        kind: RowKind::Percent,
    },
];

fn format_value(kind: RowKind, v: f64) -> String {
    match kind {
        RowKind::Mm => format!("{v:.3}"),
        RowKind::Mrad => format!("{:.3}", v * 1e3),
        RowKind::Percent => format!("{:.2} %", v * 100.0),
        RowKind::Count => format!("{v:.0}"),
    }
}

fn stats_of(report: &AccuracyReport) -> [&AccuracyStats; 3] {
    [
        &report.relative_left,
        &report.relative_right,
        &report.collaborative,
    ]
}

const LABEL_WIDTH: usize = 24;

/// A table of one report: one column per set of pairs.
pub fn format_table(report: &AccuracyReport) -> String {
    let stats = stats_of(report);
    let mut out = String::new();
    let _ = write!(out, "{:<LABEL_WIDTH$}", "");
    for t in COLUMN_TITLES {
        let _ = write!(out, "{t:>16}");
    }
    out.push('\n');
    for row in &ROWS {
        let _ = write!(out, "{:<LABEL_WIDTH$}", row.label);
        for s in stats {
            let _ = write!(out, "{:>16}", format_value(row.kind, (row.value)(s)));
        }
        out.push('\n');
    }
    out
}

/// The change from `before` to `after`: relative reduction of an error, or percentage points of a
/// frequency.
fn format_change(kind: RowKind, before: f64, after: f64) -> String {
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
        for row in &ROWS {
            let (vb, va) = ((row.value)(b), (row.value)(a));
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
