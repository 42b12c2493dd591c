//! The paper study's tables: Tables 4–8 laid out as the paper does (mean ± standard deviation over the
//! seeds), Fig. 4's numbers, the raw per-run figures, and the Markdown report.

use super::paper_values::{self, NOMINAL};
use super::plan::{Plan, SeedRun};
use crate::comparison::{Comparison, MethodEntry, Observes};
use crate::dataset::Split;
use crate::metrics::{AccuracyReport, AccuracyStats};
use crate::side::Side;
use anyhow::Result;
use std::fmt::Write as _;

pub(crate) const TABLE4_CSV: &str = "table4_relative_frequency.csv";
pub(crate) const TABLE5_CSV: &str = "table5_relative_accuracy.csv";
pub(crate) const TABLE6_CSV: &str = "table6_base_methods.csv";
pub(crate) const TABLE7_CSV: &str = "table7_collaborative_frequency.csv";
pub(crate) const TABLE8_CSV: &str = "table8_collaborative_accuracy.csv";
pub(crate) const FIG4_CSV: &str = "fig4_configurations.csv";

/// The columns of every table CSV.
pub(crate) const TABLE_CSV_COLUMNS: [&str; 14] = [
    "table",
    "row",
    "section",
    "indicator",
    "unit",
    "column",
    "method",
    "paper_column",
    "mean",
    "sd",
    "min",
    "max",
    "n_seeds",
    "paper_value",
];

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unit {
    Mm,
    Rad,
    Percent,
}

impl Unit {
    fn name(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Rad => "rad",
            Unit::Percent => "%",
        }
    }

    fn digits(self) -> usize {
        match self {
            Unit::Mm => 4,
            Unit::Rad => 5,
            Unit::Percent => 2,
        }
    }
}

pub(super) type Pick = fn(&AccuracyStats) -> f64;

/// A row of the paper's tables: which pairs, which figure.
struct RowSpec {
    /// `right.pos_rms` etc.: the key of the paper's value.
    id: String,
    section: &'static str,
    label: &'static str,
    unit: Unit,
    pairs: Pairs,
    pick: Pick,
}

#[derive(Clone, Copy)]
pub(super) enum Pairs {
    Relative(Side),
    Collaborative,
}

impl Pairs {
    fn of(self, r: &AccuracyReport) -> AccuracyStats {
        match self {
            Pairs::Relative(s) => r.relative_or_nan(s),
            Pairs::Collaborative => r.collaborative_or_nan(),
        }
    }

    fn key(self) -> &'static str {
        match self {
            Pairs::Relative(Side::Left) => "left",
            Pairs::Relative(Side::Right) => "right",
            Pairs::Collaborative => "collab",
        }
    }

    fn section(self) -> &'static str {
        match self {
            Pairs::Relative(Side::Left) => "left arm",
            Pairs::Relative(Side::Right) => "right arm",
            Pairs::Collaborative => "collaborative",
        }
    }
}

/// The paper's RMS/max rows (Tables 5, 6, 8) for one set of pairs.
fn accuracy_rows(pairs: Pairs) -> Vec<RowSpec> {
    let rows: [(&str, &str, Unit, Pick); 4] = [
        ("pos_rms", "positioning RMS*", Unit::Mm, |s| s.pos_rms_mm),
        ("pos_max", "positioning max", Unit::Mm, |s| s.pos_max_mm),
        ("ori_rms", "orientation RMS", Unit::Rad, |s| {
            s.ori_rms_rad.unwrap_or(f64::NAN)
        }),
        ("ori_max", "orientation max", Unit::Rad, |s| {
            s.ori_max_rad.unwrap_or(f64::NAN)
        }),
    ];
    rows.into_iter()
        .map(|(id, label, unit, pick)| RowSpec {
            id: format!("{}.{id}", pairs.key()),
            section: pairs.section(),
            label,
            unit,
            pairs,
            pick,
        })
        .collect()
}

/// The paper's frequency rows (Tables 4 and 7) for one set of pairs.
fn frequency_rows(pairs: Pairs) -> Vec<RowSpec> {
    let rows: [(&str, &str, Pick); 4] = [
        ("pos_0.3", "positioning |Δd| ≤ 0.3 mm", |s| {
            100.0 * s.pos_within_0_3mm_frac
        }),
        ("pos_0.6", "positioning |Δd| ≤ 0.6 mm", |s| {
            100.0 * s.pos_within_0_6mm_frac
        }),
        ("ori_0.005", "orientation Δo ≤ 0.005 rad", |s| {
            100.0 * s.ori_within_0_005rad_frac.unwrap_or(f64::NAN)
        }),
        ("ori_0.01", "orientation Δo ≤ 0.01 rad", |s| {
            100.0 * s.ori_within_0_01rad_frac.unwrap_or(f64::NAN)
        }),
    ];
    rows.into_iter()
        .map(|(id, label, pick)| RowSpec {
            id: format!("{}.{id}", pairs.key()),
            section: pairs.section(),
            label,
            unit: Unit::Percent,
            pairs,
            pick,
        })
        .collect()
}

/// A column: the nominal model, a method, or the true parameters.
#[derive(Clone)]
pub(crate) struct Column {
    /// `nominal`, a method key, or `truth`.
    pub key: String,
    pub title: String,
    /// The paper's heading of the column, if the paper has it.
    pub paper: Option<&'static str>,
    which: Model,
}

#[derive(Clone, Copy)]
pub(super) enum Model {
    Nominal,
    Truth,
    Method(&'static str),
}

impl Model {
    fn report(self, c: &Comparison, split: Split) -> Option<&AccuracyReport> {
        match self {
            Model::Nominal => c.nominal.report(split),
            Model::Truth => c.truth.as_ref()?.report(split),
            Model::Method(key) => c.method(key)?.figures()?.report(split),
        }
    }
}

fn columns(methods: &[MethodEntry], with_truth: bool) -> Vec<Column> {
    let mut out = vec![Column {
        key: "nominal".into(),
        title: "nominal".into(),
        paper: Some(NOMINAL),
        which: Model::Nominal,
    }];
    out.extend(methods.iter().map(|m| Column {
        key: m.key.into(),
        title: m.title(),
        paper: m.paper,
        which: Model::Method(m.key),
    }));
    if with_truth {
        out.push(Column {
            key: "truth".into(),
            title: "true parameters".into(),
            paper: None,
            which: Model::Truth,
        });
    }
    out
}

/// One row's values: per column, one per seed (NaN where the method did not run).
pub(crate) struct Row {
    pub id: String,
    pub section: &'static str,
    pub label: &'static str,
    pub unit: Unit,
    pub values: Vec<Vec<f64>>,
    pub paper: Vec<Option<f64>>,
}

pub(crate) struct Table {
    pub id: &'static str,
    pub file: &'static str,
    pub title: &'static str,
    pub note: &'static str,
    pub columns: Vec<Column>,
    pub rows: Vec<Row>,
}

/// Mean, sample standard deviation, min and max of the finite values, and how many there are.
pub(crate) fn summary(values: &[f64]) -> (f64, f64, f64, f64, usize) {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, f64::NAN, f64::NAN, 0);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (mean, sd, min, max, n)
}

pub(super) fn fmt_num(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

impl Table {
    fn new(
        id: &'static str,
        file: &'static str,
        title: &'static str,
        note: &'static str,
        columns: Vec<Column>,
        specs: Vec<RowSpec>,
        runs: &[SeedRun],
    ) -> Self {
        let rows = specs
            .into_iter()
            .map(|spec| Row {
                values: columns
                    .iter()
                    .map(|c| {
                        runs.iter()
                            .map(|r| {
                                c.which
                                    .report(&r.comparison, Split::Ver)
                                    .map_or(f64::NAN, |rep| (spec.pick)(&spec.pairs.of(rep)))
                            })
                            .collect()
                    })
                    .collect(),
                paper: columns
                    .iter()
                    .map(|c| c.paper.and_then(|p| paper_values::value(id, &spec.id, p)))
                    .collect(),
                id: spec.id,
                section: spec.section,
                label: spec.label,
                unit: spec.unit,
            })
            .collect();
        Self {
            id,
            file,
            title,
            note,
            columns,
            rows,
        }
    }

    /// The table as CSV ([`TABLE_CSV_COLUMNS`]), one line per row and column.
    pub fn to_csv(&self) -> Result<String> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(TABLE_CSV_COLUMNS)?;
        for row in &self.rows {
            for (c, col) in self.columns.iter().enumerate() {
                let (mean, sd, min, max, n) = summary(&row.values[c]);
                let num = |x: f64| {
                    if x.is_finite() {
                        format!("{x}")
                    } else {
                        String::new()
                    }
                };
                w.write_record([
                    self.id.to_owned(),
                    row.id.clone(),
                    row.section.to_owned(),
                    row.label.to_owned(),
                    row.unit.name().to_owned(),
                    col.key.clone(),
                    col.title.clone(),
                    col.paper.unwrap_or("").to_owned(),
                    num(mean),
                    num(sd),
                    num(min),
                    num(max),
                    n.to_string(),
                    row.paper[c].map_or(String::new(), |p| format!("{p}")),
                ])?;
            }
        }
        Ok(String::from_utf8(w.into_inner()?)?)
    }

    /// The table in Markdown: per row a line of our figures (mean ± sd over the seeds) and, where the
    /// paper has the row, a line of its figures.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("#### {}\n\n{}\n\n", self.title, self.note);
        let _ = write!(out, "| indicator | |");
        for c in &self.columns {
            let _ = write!(out, " {} |", c.title);
        }
        out.push_str("\n|---|---|");
        out.push_str(&"---:|".repeat(self.columns.len()));
        out.push('\n');
        let mut section = "";
        for row in &self.rows {
            // A `|` in a label would end the Markdown cell.
            let label = row.label.replace('|', "\\|");
            let head = if row.section == section {
                format!("{label} ({})", row.unit.name())
            } else {
                section = row.section;
                format!("**{}** {label} ({})", row.section, row.unit.name())
            };
            let _ = write!(out, "| {head} | simulation |");
            for v in &row.values {
                let (mean, sd, _, _, n) = summary(v);
                let d = row.unit.digits();
                if n > 1 {
                    let _ = write!(out, " {} ± {} |", fmt_num(mean, d), fmt_num(sd, d));
                } else {
                    let _ = write!(out, " {} |", fmt_num(mean, d));
                }
            }
            out.push('\n');
            if row.paper.iter().any(Option::is_some) {
                let _ = write!(out, "| | paper |");
                for p in &row.paper {
                    let _ = write!(
                        out,
                        " {} |",
                        p.map_or_else(|| "–".to_owned(), |p| format!("{p}"))
                    );
                }
                out.push('\n');
            }
        }
        out
    }
}

pub(crate) struct Tables {
    pub tables: Vec<Table>,
    pub fig4_csv: String,
    pub fig4_markdown: String,
}

/// Every table of the study.
pub(crate) fn build(plan: &Plan, runs: &[SeedRun]) -> Tables {
    let truth = runs.iter().any(|r| r.comparison.truth.is_some());
    let arms = columns(&plan.arm_methods(), truth);
    let base = columns(&plan.base_methods(), truth);
    let mut table4 = frequency_rows(Pairs::Relative(Side::Right));
    table4.extend(frequency_rows(Pairs::Relative(Side::Left)));
    let mut table5 = accuracy_rows(Pairs::Relative(Side::Right));
    table5.extend(accuracy_rows(Pairs::Relative(Side::Left)));
    let mut table6 = accuracy_rows(Pairs::Collaborative);
    table6.extend(frequency_rows(Pairs::Collaborative));
    let tables = vec![
        Table::new(
            "table4",
            TABLE4_CSV,
            "Table 4 analogue: frequency of relative errors within the intervals (verification)",
            "Percent of the verification pairs of each arm whose worst reflector's |Δd| (positioning) or \
             whose Δo (orientation) is within the interval. The paper does not say which arm its Table 4 \
             is of; it says the statistics come from its Fig. 6, which is the right arm's: its values \
             stand in the right-arm rows.",
            arms.clone(),
            table4,
            runs,
        ),
        Table::new(
            "table5",
            TABLE5_CSV,
            "Table 5 analogue: relative accuracy by step-1 method (verification)",
            "RMS* is the largest of the three reflectors' RMS of Δd (eq. 5); max the largest |Δd|; \
             orientation Δo of eq. (6).",
            arms.clone(),
            table5,
            runs,
        ),
        Table::new(
            "table6",
            TABLE6_CSV,
            "Table 6 analogue: collaborative accuracy by step-2 method, arms by minimax (verification)",
            "Collaborative Δd and Δo of eqs. (7) and (8) over every pair of a left and a right \
             verification configuration. The paper quotes the frequencies in §5.1, for its method and \
             [28] only.",
            base,
            table6,
            runs,
        ),
        Table::new(
            "table7",
            TABLE7_CSV,
            "Table 7 analogue: frequency of collaborative errors within the intervals, by step-1 method (verification)",
            "Step 2 by the paper's minimax for every step-1 method.",
            arms.clone(),
            frequency_rows(Pairs::Collaborative),
            runs,
        ),
        Table::new(
            "table8",
            TABLE8_CSV,
            "Table 8 analogue: collaborative accuracy by step-1 method (verification)",
            "Step 2 by the paper's minimax for every step-1 method.",
            arms,
            accuracy_rows(Pairs::Collaborative),
            runs,
        ),
    ];
    let (fig4_csv, fig4_markdown) = fig4(plan, runs);
    Tables {
        tables,
        fig4_csv,
        fig4_markdown,
    }
}

/// The columns of the Fig. 4 CSV.
pub(crate) const FIG4_CSV_COLUMNS: [&str; 9] = [
    "n_configs",
    "method",
    "arm",
    "split",
    "pos_rms_mm_mean",
    "pos_rms_mm_sd",
    "ori_rms_rad_mean",
    "ori_rms_rad_sd",
    "n_seeds",
];

/// Fig. 4's points (mean ± sd over the seeds): CSV and a Markdown table.
fn fig4(plan: &Plan, runs: &[SeedRun]) -> (String, String) {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(FIG4_CSV_COLUMNS);
    let mut md = String::from(
        "| configs | method | left pos RMS* cal / ver (mm) | right pos RMS* cal / ver (mm) | left ori RMS cal / ver (rad) | right ori RMS cal / ver (rad) |\n|---:|---|---|---|---|---|\n",
    );
    for &n in &plan.sizes {
        for m in plan.arm_methods() {
            let points: Vec<_> = runs
                .iter()
                .flat_map(|r| r.fig4.iter().filter(|p| p.n == n && p.key == m.key))
                .collect();
            if points.is_empty() {
                continue;
            }
            let mut cells = Vec::new();
            for (unit, pick) in [
                (Unit::Mm, (|s| s.pos_rms_mm) as Pick),
                (Unit::Rad, |s| s.ori_rms_rad.unwrap_or(f64::NAN)),
            ] {
                for side in Side::BOTH {
                    let mut pair = Vec::new();
                    for split in [Split::Cal, Split::Ver] {
                        let values: Vec<f64> = points
                            .iter()
                            .map(|p| {
                                let r = if split == Split::Cal { p.cal } else { p.ver };
                                r.map_or(f64::NAN, |r| pick(&r.relative_or_nan(side)))
                            })
                            .collect();
                        let (mean, sd, _, _, k) = summary(&values);
                        pair.push(if k > 1 {
                            format!(
                                "{} ± {}",
                                fmt_num(mean, unit.digits()),
                                fmt_num(sd, unit.digits())
                            )
                        } else {
                            fmt_num(mean, unit.digits())
                        });
                        if unit == Unit::Mm {
                            // One CSV line per (arm, split), with both figures.
                            let ori: Vec<f64> = points
                                .iter()
                                .map(|p| {
                                    let r = if split == Split::Cal { p.cal } else { p.ver };
                                    r.map_or(f64::NAN, |r| {
                                        r.relative_or_nan(side).ori_rms_rad.unwrap_or(f64::NAN)
                                    })
                                })
                                .collect();
                            let (om, osd, _, _, _) = summary(&ori);
                            let num = |x: f64| {
                                if x.is_finite() {
                                    format!("{x}")
                                } else {
                                    String::new()
                                }
                            };
                            let _ = w.write_record([
                                n.to_string(),
                                m.key.to_owned(),
                                side.name().to_owned(),
                                split.name().to_owned(),
                                num(mean),
                                num(sd),
                                num(om),
                                num(osd),
                                k.to_string(),
                            ]);
                        }
                    }
                    cells.push(pair.join(" / "));
                }
            }
            let _ = writeln!(md, "| {n} | {} | {} |", m.title(), cells.join(" | "));
        }
    }
    let csv = w
        .into_inner()
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .unwrap_or_default();
    (csv, md)
}

/// The columns of `runs.csv`.
pub(crate) const RUNS_CSV_COLUMNS: [&str; 24] = [
    "seed",
    "model",
    "split",
    "pairs",
    "converged",
    "terminations",
    "iterations",
    "calibration_s",
    "n_configs",
    "n_pairs",
    "pos_rms_mm",
    "pos_rms_a_mm",
    "pos_rms_b_mm",
    "pos_rms_c_mm",
    "pos_max_mm",
    "ori_rms_rad",
    "ori_max_rad",
    "pos_within_0_3mm_frac",
    "pos_within_0_6mm_frac",
    "ori_within_0_005rad_frac",
    "ori_within_0_01rad_frac",
    "observes",
    "reflector_used",
    "error",
];

/// Every model's figures of every run: per seed, model, split and set of pairs.
pub(crate) fn runs_csv(runs: &[SeedRun]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(RUNS_CSV_COLUMNS)?;
    for r in runs {
        let seed = r
            .seed
            .map_or_else(|| "dataset".to_owned(), |s| s.to_string());
        let c = &r.comparison;
        let mut models: Vec<(String, Option<&crate::analysis::Analysis>, Vec<String>)> =
            vec![("nominal".into(), Some(&c.nominal), vec![String::new(); 4])];
        if let Some(t) = &c.truth {
            models.push(("truth".into(), Some(t), vec![String::new(); 4]));
        }
        for m in &c.methods {
            let run_info = match &m.outcome {
                Ok(run) => vec![
                    run.result.is_converged().to_string(),
                    run.result
                        .stages
                        .iter()
                        .map(|s| format!("{:?}", s.termination))
                        .collect::<Vec<_>>()
                        .join("/"),
                    run.result
                        .stages
                        .iter()
                        .map(|s| s.iterations.to_string())
                        .collect::<Vec<_>>()
                        .join("/"),
                    format!("{:.4}", run.result.elapsed_secs),
                ],
                Err(_) => vec!["false".into(), String::new(), String::new(), String::new()],
            };
            models.push((m.entry.key.to_owned(), m.figures(), run_info));
        }
        for (name, figures, info) in models {
            let entry = c.method(&name).map(|m| m.entry);
            let observes = match entry.map(|e| e.observes) {
                Some(Observes::ThreeReflectors) => "three reflectors",
                Some(Observes::OneReflector) => "one reflector",
                None => "",
            };
            let error = c
                .method(&name)
                .and_then(|m| m.outcome.as_ref().err().map(ToString::to_string))
                .unwrap_or_default();
            for split in [Split::Cal, Split::Ver] {
                let Some(rep) = figures.and_then(|f| f.report(split)) else {
                    if !error.is_empty() && split == Split::Cal {
                        let mut rec =
                            vec![seed.clone(), name.clone(), String::new(), String::new()];
                        rec.extend(info.iter().cloned());
                        rec.extend(std::iter::repeat_n(String::new(), 13));
                        rec.push(observes.to_owned());
                        rec.push(String::new());
                        rec.push(error.clone());
                        w.write_record(&rec)?;
                    }
                    continue;
                };
                for (pairs, s) in [
                    ("relative_left", &rep.relative_or_nan(Side::Left)),
                    ("relative_right", &rep.relative_or_nan(Side::Right)),
                    ("collaborative", &rep.collaborative_or_nan()),
                ] {
                    let mut rec = vec![
                        seed.clone(),
                        name.clone(),
                        split.name().to_owned(),
                        pairs.to_owned(),
                    ];
                    rec.extend(info.iter().cloned());
                    rec.extend(
                        [
                            s.n_configs as f64,
                            s.n_pairs as f64,
                            s.pos_rms_mm,
                            s.pos_rms_per_reflector_mm[0],
                            s.pos_rms_per_reflector_mm[1],
                            s.pos_rms_per_reflector_mm[2],
                            s.pos_max_mm,
                            s.ori_rms_rad.unwrap_or(f64::NAN),
                            s.ori_max_rad.unwrap_or(f64::NAN),
                            s.pos_within_0_3mm_frac,
                            s.pos_within_0_6mm_frac,
                            s.ori_within_0_005rad_frac.unwrap_or(f64::NAN),
                            s.ori_within_0_01rad_frac.unwrap_or(f64::NAN),
                        ]
                        .map(|x| format!("{x}")),
                    );
                    rec.push(observes.to_owned());
                    let used = |side: Side| {
                        c.method(&name)
                            .and_then(|m| m.run())
                            .and_then(|run| run.result.reflector_used[side])
                            .map_or("", |r| r.name())
                    };
                    rec.push(match pairs {
                        "relative_left" => used(Side::Left).to_owned(),
                        "relative_right" => used(Side::Right).to_owned(),
                        _ if used(Side::Left).is_empty() => String::new(),
                        _ => format!("{}/{}", used(Side::Left), used(Side::Right)),
                    });
                    rec.push(error.clone());
                    w.write_record(&rec)?;
                }
            }
        }
    }
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// The ratios `num / den` of the runs: `(mean, how many ≤ 1, how many)`.
pub(super) fn ratio_summary(
    runs: &[SeedRun],
    num: impl Fn(&SeedRun) -> Option<f64>,
    den: impl Fn(&SeedRun) -> Option<f64>,
) -> Option<(f64, usize, usize)> {
    let ratios: Vec<f64> = runs
        .iter()
        .filter_map(|r| Some(num(r)? / den(r)?))
        .filter(|x| x.is_finite())
        .collect();
    if ratios.is_empty() {
        return None;
    }
    let at_most_one = ratios.iter().filter(|&&x| x <= 1.0).count();
    Some((
        ratios.iter().sum::<f64>() / ratios.len() as f64,
        at_most_one,
        ratios.len(),
    ))
}

pub(super) const THREE: [(Pairs, &str); 3] = [
    (Pairs::Relative(Side::Left), "L"),
    (Pairs::Relative(Side::Right), "R"),
    (Pairs::Collaborative, "collab"),
];

/// The verification RMS of `side`'s relative `Δd` of the reflector the method `key` used on that arm,
/// under `model`.
pub(super) fn own_reflector_rms(r: &SeedRun, key: &str, side: Side, model: Model) -> Option<f64> {
    let k = r.comparison.method(key)?.run()?.result.reflector_used[side]?.index();
    model
        .report(&r.comparison, Split::Ver)
        .map(|rep| rep.relative_or_nan(side).pos_rms_per_reflector_mm[k])
}

pub(super) fn ver_stat(r: &SeedRun, model: Model, pairs: Pairs, pick: Pick) -> Option<f64> {
    model
        .report(&r.comparison, Split::Ver)
        .map(|rep| pick(&pairs.of(rep)))
}
