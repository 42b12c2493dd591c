//! The paper study's figures as SVG (plotters' SVG backend): Fig. 4 (accuracy against the number of
//! calibration configurations) and Figs. 6–8 (histograms per model and box plots), with the numbers
//! behind the histograms and box plots as CSV.
//!
//! Histograms: per pair the worst reflector's signed `Δd` or `Δo` (as the paper's figures), binned per
//! seed over a range common to the seeds; bars are the mean fraction over the seeds and, with several
//! seeds, the error bars ± one standard deviation. The nominal model has a range of its own, the
//! calibrated models share one. Box plots pool the samples of all seeds (Tukey whiskers; dots at the
//! extremes).

use super::plan::{Plan, SeedRun};
use super::tables::summary;
use crate::analysis::{HISTOGRAM_BINS, Indicator};
use crate::comparison::{self, BoxStats, MethodEntry};
use crate::dataset::Split;
use crate::metrics::{ORI_THRESHOLDS_RAD, POS_THRESHOLDS_MM};
use crate::report::svg::{BoxLayout, BoxSeries, box_chart};
use crate::side::Side;
use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(crate) const FIG4_SVG: &str = "fig4_configurations.svg";
pub(crate) const FIG6_RIGHT_SVG: &str = "fig6_relative_right.svg";
pub(crate) const FIG6_LEFT_SVG: &str = "fig6_relative_left.svg";
pub(crate) const FIG7_SVG: &str = "fig7_base_methods.svg";
pub(crate) const FIG8_SVG: &str = "fig8_collaborative.svg";
pub(crate) const HISTOGRAMS_CSV: &str = "histograms.csv";
pub(crate) const BOXPLOTS_CSV: &str = "boxplots.csv";

pub(crate) const HISTOGRAM_CSV_COLUMNS: [&str; 9] = [
    "figure",
    "indicator",
    "model",
    "bin_lo",
    "bin_hi",
    "percent_mean",
    "percent_sd",
    "n_seeds",
    "samples_per_seed",
];

pub(crate) const BOXPLOT_CSV_COLUMNS: [&str; 12] = [
    "figure",
    "indicator",
    "model",
    "n",
    "min",
    "whisker_lo",
    "q1",
    "median",
    "q3",
    "whisker_hi",
    "max",
    "mean",
];

/// Colours of the models, in the order nominal, methods…, true parameters (Tableau 10).
const PALETTE: [RGBColor; 10] = [
    RGBColor(127, 127, 127),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn colour(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

const FONT: &str = "sans-serif";

/// The SVG files and CSVs of the figures.
pub(crate) struct Figures {
    pub files: Vec<(&'static str, Vec<u8>)>,
}

/// A model in a figure: its name, colour and its samples per seed.
struct Series {
    name: String,
    colour: RGBColor,
    per_seed: Vec<Vec<f32>>,
}

/// One of Figs. 6–8: a row of panels per indicator.
struct HistFigure {
    file: &'static str,
    title: String,
    indicators: [Indicator; 2],
    methods: Vec<MethodEntry>,
}

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("drawing: {e}")
}

pub(crate) fn draw(plan: &Plan, runs: &[SeedRun]) -> Result<Figures> {
    let arms = plan.arm_methods();
    let figures = [
        HistFigure {
            file: FIG6_RIGHT_SVG,
            title: "Fig. 6 analogue: relative accuracy of the right arm by step-1 method (verification)"
                .into(),
            indicators: [
                Indicator::RelativePosition(Side::Right),
                Indicator::RelativeOrientation(Side::Right),
            ],
            methods: arms.clone(),
        },
        HistFigure {
            file: FIG6_LEFT_SVG,
            title: "Fig. 6 analogue, left arm: relative accuracy by step-1 method (verification)"
                .into(),
            indicators: [
                Indicator::RelativePosition(Side::Left),
                Indicator::RelativeOrientation(Side::Left),
            ],
            methods: arms.clone(),
        },
        HistFigure {
            file: FIG7_SVG,
            title: "Fig. 7 analogue: collaborative accuracy by step-2 method, arms by minimax (verification)"
                .into(),
            indicators: [
                Indicator::CollaborativePosition,
                Indicator::CollaborativeOrientation,
            ],
            methods: plan.base_methods(),
        },
        HistFigure {
            file: FIG8_SVG,
            title: "Fig. 8 analogue: collaborative accuracy by step-1 method (verification)".into(),
            indicators: [
                Indicator::CollaborativePosition,
                Indicator::CollaborativeOrientation,
            ],
            methods: arms,
        },
    ];
    let mut hist_csv = csv::Writer::from_writer(Vec::new());
    hist_csv.write_record(HISTOGRAM_CSV_COLUMNS)?;
    let mut box_csv = csv::Writer::from_writer(Vec::new());
    box_csv.write_record(BOXPLOT_CSV_COLUMNS)?;
    let mut files = vec![(FIG4_SVG, fig4_svg(plan, runs)?.into_bytes())];
    for f in &figures {
        let svg = hist_figure(f, runs, &mut hist_csv, &mut box_csv)?;
        files.push((f.file, svg.into_bytes()));
    }
    files.push((HISTOGRAMS_CSV, hist_csv.into_inner().map_err(err)?));
    files.push((BOXPLOTS_CSV, box_csv.into_inner().map_err(err)?));
    Ok(Figures { files })
}

fn indicator_key(i: Indicator) -> String {
    match i {
        Indicator::RelativePosition(s) => format!("relative_position_{s}"),
        Indicator::RelativeOrientation(s) => format!("relative_orientation_{s}"),
        Indicator::CollaborativePosition => "collaborative_position".into(),
        Indicator::CollaborativeOrientation => "collaborative_orientation".into(),
    }
}

fn unit(i: Indicator) -> &'static str {
    if i.is_position() {
        "Δd (mm)"
    } else {
        "Δo (rad)"
    }
}

/// The models of a figure for one indicator: nominal, the methods, and the true parameters if known.
fn series(f: &HistFigure, indicator: Indicator, runs: &[SeedRun]) -> Vec<Series> {
    let per_seed = |get: &dyn Fn(&SeedRun) -> Option<Vec<f32>>| -> Vec<Vec<f32>> {
        runs.iter().filter_map(get).collect()
    };
    let mut out = vec![Series {
        name: "nominal".into(),
        colour: colour(0),
        per_seed: per_seed(&|r| {
            r.comparison
                .nominal
                .samples(Split::Ver, indicator)
                .map(<[f32]>::to_vec)
        }),
    }];
    for (k, m) in f.methods.iter().enumerate() {
        let key = m.key;
        out.push(Series {
            name: m.title(),
            colour: colour(k + 1),
            per_seed: per_seed(&|r| {
                r.comparison
                    .method(key)?
                    .figures()?
                    .samples(Split::Ver, indicator)
                    .map(<[f32]>::to_vec)
            }),
        });
    }
    if runs.iter().any(|r| r.comparison.truth.is_some()) {
        out.push(Series {
            name: "true parameters".into(),
            colour: colour(f.methods.len() + 1),
            per_seed: per_seed(&|r| {
                r.comparison
                    .truth
                    .as_ref()?
                    .samples(Split::Ver, indicator)
                    .map(<[f32]>::to_vec)
            }),
        });
    }
    out
}

/// Mean and sd (percent) per bin over the seeds, over `[lo, hi]` as the engine bins it.
fn binned(s: &Series, indicator: Indicator, extent: f64) -> (f64, f64, Vec<(f64, f64)>) {
    let hists: Vec<_> = s
        .per_seed
        .iter()
        .map(|v| comparison::histogram(indicator, v, extent, HISTOGRAM_BINS))
        .collect();
    let (lo, hi) = hists.first().map_or((0.0, 1.0), |h| (h.lo, h.hi));
    let bars = (0..HISTOGRAM_BINS)
        .map(|b| {
            let v: Vec<f64> = hists.iter().map(|h| 100.0 * h.fractions[b]).collect();
            let (mean, sd, ..) = summary(&v);
            (mean, sd)
        })
        .collect();
    (lo, hi, bars)
}

fn hist_figure(
    f: &HistFigure,
    runs: &[SeedRun],
    hist_csv: &mut csv::Writer<Vec<u8>>,
    box_csv: &mut csv::Writer<Vec<u8>>,
) -> Result<String> {
    let n_seeds = runs.len();
    let rows: Vec<(Indicator, Vec<Series>)> = f
        .indicators
        .iter()
        .map(|&i| (i, series(f, i, runs)))
        .collect();
    // Panels per row: every model's histogram (the true parameters' only in the box plot) and a box plot.
    let n_hist = 1 + f.methods.len();
    let cols = n_hist + 1;
    let (panel_w, panel_h) = (300u32, 240u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (panel_w * cols as u32, panel_h * 2 + 40))
            .into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(&f.title, (FONT, 18)).map_err(err)?;
        let areas = root.split_evenly((2, cols));
        for (r, (indicator, models)) in rows.iter().enumerate() {
            let ind_key = indicator_key(*indicator);
            let flat = |s: &Series| -> Vec<f32> { s.per_seed.iter().flatten().copied().collect() };
            let nominal_extent = comparison::extent(&flat(&models[0]));
            let method_extent = models[1..n_hist.min(models.len())]
                .iter()
                .map(|s| comparison::extent(&flat(s)))
                .fold(0.0, f64::max);
            for (k, s) in models.iter().enumerate() {
                let extent = if k == 0 {
                    nominal_extent
                } else {
                    method_extent
                };
                let (lo, hi, bars) = binned(s, *indicator, extent);
                let width = (hi - lo) / HISTOGRAM_BINS as f64;
                let samples = s.per_seed.first().map_or(0, Vec::len);
                for (b, (mean, sd)) in bars.iter().enumerate() {
                    let x0 = lo + b as f64 * width;
                    hist_csv.write_record([
                        f.file.trim_end_matches(".svg").to_owned(),
                        ind_key.clone(),
                        s.name.clone(),
                        format!("{x0}"),
                        format!("{}", x0 + width),
                        format!("{mean}"),
                        format!("{sd}"),
                        s.per_seed.len().to_string(),
                        samples.to_string(),
                    ])?;
                }
                if k < n_hist {
                    hist_panel(&areas[r * cols + k], s, *indicator, lo, hi, &bars, n_seeds)?;
                }
            }
            let boxes: Vec<(String, RGBColor, Option<BoxStats>)> = models
                .iter()
                .map(|s| (s.name.clone(), s.colour, BoxStats::of(&flat(s))))
                .collect();
            for (name, _, b) in &boxes {
                if let Some(b) = b {
                    box_csv.write_record(
                        [
                            f.file.trim_end_matches(".svg").to_owned(),
                            ind_key.clone(),
                            name.clone(),
                            b.n.to_string(),
                        ]
                        .into_iter()
                        .chain(
                            [
                                b.min,
                                b.whisker_lo,
                                b.q1,
                                b.median,
                                b.q3,
                                b.whisker_hi,
                                b.max,
                                b.mean,
                            ]
                            .map(|x| format!("{x}")),
                        ),
                    )?;
                }
            }
            // The box plot leaves the nominal model out: its spread would flatten the others.
            box_panel(&areas[r * cols + n_hist], *indicator, &boxes[1..])?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn hist_panel(
    area: &DrawingArea<SVGBackend, Shift>,
    s: &Series,
    indicator: Indicator,
    lo: f64,
    hi: f64,
    bars: &[(f64, f64)],
    n_seeds: usize,
) -> Result<()> {
    let width = (hi - lo) / bars.len().max(1) as f64;
    let top = bars.iter().map(|(m, sd)| m + sd).fold(1.0, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption(&s.name, (FONT, 13))
        .margin(6)
        .x_label_area_size(40)
        .y_label_area_size(40)
        .build_cartesian_2d(lo..hi, 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(5)
        .y_labels(5)
        .x_desc(unit(indicator))
        .y_desc("% of pairs")
        .label_style((FONT, 10))
        .axis_desc_style((FONT, 11))
        .draw()
        .map_err(err)?;
    // The paper's intervals (Tables 4 and 7).
    let marks: Vec<f64> = if indicator.is_position() {
        POS_THRESHOLDS_MM.iter().flat_map(|&t| [-t, t]).collect()
    } else {
        ORI_THRESHOLDS_RAD.to_vec()
    };
    for m in marks.into_iter().filter(|m| (lo..=hi).contains(m)) {
        chart
            .draw_series(LineSeries::new(
                [(m, 0.0), (m, top)],
                RGBColor(200, 200, 200).stroke_width(1),
            ))
            .map_err(err)?;
    }
    chart
        .draw_series(bars.iter().enumerate().map(|(b, &(mean, _))| {
            let x0 = lo + b as f64 * width;
            Rectangle::new([(x0, 0.0), (x0 + width, mean)], s.colour.mix(0.8).filled())
        }))
        .map_err(err)?;
    if n_seeds > 1 {
        chart
            .draw_series(bars.iter().enumerate().map(|(b, &(mean, sd))| {
                let x = lo + (b as f64 + 0.5) * width;
                ErrorBar::new_vertical(
                    x,
                    (mean - sd).max(0.0),
                    mean,
                    mean + sd,
                    BLACK.stroke_width(1),
                    3,
                )
            }))
            .map_err(err)?;
    }
    Ok(())
}

fn box_panel(
    area: &DrawingArea<SVGBackend, Shift>,
    indicator: Indicator,
    boxes: &[(String, RGBColor, Option<BoxStats>)],
) -> Result<()> {
    let series: Vec<BoxSeries> = boxes
        .iter()
        .enumerate()
        .map(|(k, (name, c, b))| BoxSeries {
            name: (k + 1).to_string(),
            colour: *c,
            stats: b.as_ref(),
            legend: Some(format!("{} {name}", k + 1)),
        })
        .collect();
    let layout = BoxLayout {
        caption: "box plots (1 … n: legend)",
        y_desc: unit(indicator),
        x_label_area: 40,
        y_label_area: 56,
        empty_range: (0.0, 1.0),
    };
    let mut chart = box_chart(area, &layout, &series).map_err(anyhow::Error::msg)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 9))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Fig. 4: per arm, positioning RMS* and orientation RMS against the number of calibration
/// configurations, verification (solid) and calibration (dashed), one colour per step-1 method.
fn fig4_svg(plan: &Plan, runs: &[SeedRun]) -> Result<String> {
    let methods = plan.arm_methods();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 760)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root
            .titled(
                "Fig. 4 analogue: accuracy against the number of calibration configurations \
                 (solid: verification, dashed: calibration)",
                (FONT, 16),
            )
            .map_err(err)?;
        let areas = root.split_evenly((2, 2));
        type Pick = fn(&crate::metrics::AccuracyStats) -> f64;
        let rows: [(&str, Pick); 2] = [
            ("positioning RMS* (mm)", |s| s.pos_rms_mm),
            ("orientation RMS (rad)", |s| {
                s.ori_rms_rad.unwrap_or(f64::NAN)
            }),
        ];
        for (r, (label, pick)) in rows.iter().enumerate() {
            for (c, side) in Side::BOTH.into_iter().enumerate() {
                // (method, split) → points (n, mean, sd)
                let mut lines = Vec::new();
                for (k, m) in methods.iter().enumerate() {
                    for split in [Split::Ver, Split::Cal] {
                        let points: Vec<(f64, f64, f64)> = plan
                            .sizes
                            .iter()
                            .filter_map(|&n| {
                                let v: Vec<f64> = runs
                                    .iter()
                                    .flat_map(|run| run.fig4.iter())
                                    .filter(|p| p.n == n && p.key == m.key)
                                    .map(|p| {
                                        let rep = if split == Split::Cal { p.cal } else { p.ver };
                                        rep.map_or(f64::NAN, |rep| pick(&rep.relative_or_nan(side)))
                                    })
                                    .collect();
                                let (mean, sd, _, _, count) = summary(&v);
                                (count > 0).then_some((n as f64, mean, sd))
                            })
                            .collect();
                        lines.push((k, m.title(), split, points));
                    }
                }
                let top = lines
                    .iter()
                    .flat_map(|l| l.3.iter().map(|p| p.1 + p.2))
                    .fold(0.0, f64::max)
                    .max(1e-9)
                    * 1.1;
                let x_hi = plan.sizes.iter().copied().max().unwrap_or(1) as f64 + 5.0;
                let mut chart = ChartBuilder::on(&areas[r * 2 + c])
                    .caption(format!("{side} arm: {label}"), (FONT, 14))
                    .margin(8)
                    .x_label_area_size(44)
                    .y_label_area_size(56)
                    .build_cartesian_2d(0.0..x_hi, 0.0..top)
                    .map_err(err)?;
                chart
                    .configure_mesh()
                    .x_desc("calibration configurations")
                    .y_desc(*label)
                    .label_style((FONT, 10))
                    .axis_desc_style((FONT, 11))
                    .bold_line_style(RGBColor(215, 215, 215))
                    .light_line_style(RGBColor(240, 240, 240))
                    .draw()
                    .map_err(err)?;
                for (k, title, split, points) in &lines {
                    let col = colour(k + 1);
                    let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
                    if *split == Split::Ver {
                        chart
                            .draw_series(LineSeries::new(xy.clone(), col.stroke_width(2)))
                            .map_err(err)?
                            .label(title.clone())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 14, y)], col.stroke_width(2))
                            });
                    } else {
                        chart
                            .draw_series(DashedLineSeries::new(
                                xy.clone(),
                                6,
                                4,
                                col.stroke_width(1),
                            ))
                            .map_err(err)?;
                    }
                    chart
                        .draw_series(xy.iter().map(|&p| Circle::new(p, 3, col.filled())))
                        .map_err(err)?;
                    if runs.len() > 1 {
                        chart
                            .draw_series(points.iter().map(|&(x, m, sd)| {
                                ErrorBar::new_vertical(x, m - sd, m, m + sd, col.stroke_width(1), 4)
                            }))
                            .map_err(err)?;
                    }
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .label_font((FONT, 10))
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK.mix(0.3))
                    .draw()
                    .map_err(err)?;
            }
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}
