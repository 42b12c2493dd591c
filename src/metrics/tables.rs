//! Text tables of accuracy reports (the CLI's output).

use super::{AccuracyReport, AccuracyStats};
use std::fmt::Write as _;

/// The sets of pairs, as titled in the tables and named in the report's JSON; the fourth only where a
/// report has it (both hands measured together).
const COLUMN_TITLES: [&str; 4] = [
    "relative left",
    "relative right",
    "collaborative",
    "same instant",
];
const COLUMN_KEYS: [&str; 4] = [
    "relative_left",
    "relative_right",
    "collaborative",
    "collaborative_same_instant",
];

/// The reflector names of a report without names at hand: a, b, c, … by position.
fn default_names(report: &AccuracyReport) -> Vec<String> {
    let n = stats_of(report)
        .into_iter()
        .flatten()
        .next()
        .map_or(0, |s| s.pos_rms_per_reflector_mm.len());
    crate::kinematics::default_reflector_names(n).to_vec()
}

/// Reads a row's value off the stats; `None` where the data cannot give it.
type RowValue = Box<dyn Fn(&AccuracyStats) -> Option<f64>>;

/// How a row's value is read off the stats and printed.
struct Row {
    label: String,
    /// The field of [`AccuracyStats`] it shows (as serialised; `pos_rms_per_reflector_mm.<k>` for a
    /// reflector's RMS).
    key: String,
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
    key: impl Into<String>,
    kind: RowKind,
    value: impl Fn(&AccuracyStats) -> Option<f64> + 'static,
) -> Row {
    Row {
        label: label.into(),
        key: key.into(),
        value: Box::new(value),
        kind,
    }
}

/// The rows, one per reflector of `reflector_names` for the per-reflector RMS.
fn rows(reflector_names: &[String]) -> Vec<Row> {
    let mut out = vec![
        row("configurations", "n_configs", RowKind::Count, |s| {
            Some(s.n_configs as f64)
        }),
        row("pairs", "n_pairs", RowKind::Count, |s| {
            Some(s.n_pairs as f64)
        }),
        row("positioning RMS (mm)", "pos_rms_mm", RowKind::Mm, |s| {
            Some(s.pos_rms_mm)
        }),
    ];
    for (k, name) in reflector_names.iter().enumerate() {
        out.push(row(
            format!("  reflector {name} RMS (mm)"),
            format!("pos_rms_per_reflector_mm.{k}"),
            RowKind::Mm,
            move |s| s.pos_rms_per_reflector_mm.get(k).copied(),
        ));
    }
    out.extend([
        row("positioning max (mm)", "pos_max_mm", RowKind::Mm, |s| {
            Some(s.pos_max_mm)
        }),
        row(
            "|Δd| ≤ 0.3 mm",
            "pos_within_0_3mm_frac",
            RowKind::Percent,
            |s| Some(s.pos_within_0_3mm_frac),
        ),
        row(
            "|Δd| ≤ 0.6 mm",
            "pos_within_0_6mm_frac",
            RowKind::Percent,
            |s| Some(s.pos_within_0_6mm_frac),
        ),
        row(
            "orientation RMS (mrad)",
            "ori_rms_rad",
            RowKind::Mrad,
            |s| s.ori_rms_rad,
        ),
        row(
            "orientation max (mrad)",
            "ori_max_rad",
            RowKind::Mrad,
            |s| s.ori_max_rad,
        ),
        row(
            "Δo ≤ 0.005 rad",
            "ori_within_0_005rad_frac",
            RowKind::Percent,
            |s| s.ori_within_0_005rad_frac,
        ),
        row(
            "Δo ≤ 0.01 rad",
            "ori_within_0_01rad_frac",
            RowKind::Percent,
            |s| s.ori_within_0_01rad_frac,
        ),
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

/// The columns; `None` for a kind of pairs the data cannot measure (an arm not measured, the
/// collaborative pairs of arms in different tracker frames or of one arm alone, the same-instant pairs
/// of arms not measured together).
fn stats_of(report: &AccuracyReport) -> [Option<&AccuracyStats>; 4] {
    [
        report.relative_left.as_ref(),
        report.relative_right.as_ref(),
        report.collaborative.as_ref(),
        report.collaborative_same_instant.as_ref(),
    ]
}

/// How many of [`COLUMN_TITLES`] the reports show: the same-instant pairs only where one has them.
fn shown_columns(reports: &[&AccuracyReport]) -> usize {
    if reports
        .iter()
        .any(|r| r.collaborative_same_instant.is_some())
    {
        4
    } else {
        3
    }
}

const LABEL_WIDTH: usize = 24;

/// A table of one report: one column per set of pairs (reflectors named a, b, c, … by position).
pub fn format_table(report: &AccuracyReport) -> String {
    format_table_named(report, &default_names(report))
}

/// A table of one report, the per-reflector rows named `reflector_names`.
pub fn format_table_named(report: &AccuracyReport, reflector_names: &[String]) -> String {
    let n = shown_columns(&[report]);
    let stats = stats_of(report);
    let mut out = String::new();
    let _ = write!(out, "{:<LABEL_WIDTH$}", "");
    for t in &COLUMN_TITLES[..n] {
        let _ = write!(out, "{t:>16}");
    }
    out.push('\n');
    for row in &rows(reflector_names) {
        let _ = write!(out, "{:<LABEL_WIDTH$}", row.label);
        for s in &stats[..n] {
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
    let mut out = String::new();
    for block in comparison_blocks(before, after, reflector_names) {
        if !out.is_empty() {
            out.push('\n');
        }
        // Pairs the data do not have (an arm not measured; the collaborative pairs of arms in
        // different tracker frames or of one arm alone): one line, not a column of blanks.
        if block
            .rows
            .iter()
            .all(|r| r.before_value.is_none() && r.after_value.is_none())
        {
            let _ = writeln!(out, "{}: {NOT_MEASURABLE} from this data", block.title);
            continue;
        }
        let _ = writeln!(
            out,
            "{:<LABEL_WIDTH$}{:>14}{:>14}{:>14}",
            block.title, labels[0], labels[1], "change"
        );
        for row in &block.rows {
            let _ = writeln!(
                out,
                "{:<LABEL_WIDTH$}{}{}{:>14}",
                row.label,
                cell(&row.before),
                cell(&row.after),
                row.change
            );
        }
    }
    out
}

/// A value right-aligned in a column of 14, with a space before one that fills it ("not
/// measurable"), so that two never run together.
fn cell(text: &str) -> String {
    if text.chars().count() >= 14 {
        format!(" {text}")
    } else {
        format!("{text:>14}")
    }
}

/// One set of pairs of a comparison ([`comparison_blocks`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonBlock {
    /// `relative left`, `relative right`, `collaborative`.
    pub title: &'static str,
    /// The report's field: `relative_left`, `relative_right`, `collaborative`.
    pub key: &'static str,
    pub rows: Vec<ComparisonRow>,
}

/// One figure of a comparison: as the text table prints it, and the values behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonRow {
    /// The text table's label (`positioning RMS (mm)`, `  reflector a RMS (mm)`, …).
    pub label: String,
    /// The [`AccuracyStats`] field it shows, as serialised (`pos_rms_mm`,
    /// `pos_rms_per_reflector_mm.0`, …).
    pub key: String,
    /// The printed values: before, after (mm with 3 decimals, mrad, percent, counts, or
    /// [`NOT_MEASURABLE`]) and the change (relative change of an error, percentage points of a
    /// frequency).
    pub before: String,
    pub after: String,
    pub change: String,
    /// The values in the stats' own units (mm, rad, fraction, count); `None`: not measurable.
    pub before_value: Option<f64>,
    pub after_value: Option<f64>,
}

/// The rows of [`format_comparison_named`], one block per set of pairs: what the text table prints
/// and an HTML report shows.
pub fn comparison_blocks(
    before: &AccuracyReport,
    after: &AccuracyReport,
    reflector_names: &[String],
) -> Vec<ComparisonBlock> {
    let rows = rows(reflector_names);
    let n = shown_columns(&[before, after]);
    COLUMN_TITLES
        .iter()
        .zip(COLUMN_KEYS)
        .zip(stats_of(before).into_iter().zip(stats_of(after)))
        .take(n)
        .map(|((&title, key), (b, a))| ComparisonBlock {
            title,
            key,
            rows: rows
                .iter()
                .map(|row| {
                    let (vb, va) = (
                        b.and_then(|b| (row.value)(b)),
                        a.and_then(|a| (row.value)(a)),
                    );
                    ComparisonRow {
                        label: row.label.clone(),
                        key: row.key.clone(),
                        before: format_value(row.kind, vb),
                        after: format_value(row.kind, va),
                        change: format_change(row.kind, vb, va),
                        before_value: vb,
                        after_value: va,
                    }
                })
                .collect(),
        })
        .collect()
}
