//! Convergence curves and accuracy histograms (egui_plot).

use crate::analysis::{Analysis, Histogram, Indicator, SplitFigures};
use crate::app::session::{After, Session};
use crate::dataset::Split;
use crate::metrics::{AccuracyReport, ORI_THRESHOLDS_RAD, POS_THRESHOLDS_MM};
use crate::side::Side;
use crate::solver::{IterationRecord, Stage};
use eframe::egui::{self, Color32, RichText};
use egui_plot::{Bar, BarChart, Legend, Line, Plot, VLine};

pub use crate::solver::STAGES;

const F_COLORS: [Color32; 4] = [
    Color32::from_rgb(230, 120, 90),
    Color32::from_rgb(110, 190, 110),
    Color32::from_rgb(100, 160, 235),
    Color32::from_rgb(200, 130, 220),
];
const PSI_COLOR: Color32 = Color32::from_rgb(240, 220, 120);

fn log10(x: f64) -> Option<f64> {
    (x.is_finite() && x > 0.0).then(|| x.log10())
}

/// `10^k` axis labels for a log10 axis: `1e2` on a decade, else as many digits as the marks' spacing
/// tells apart (`2e1`, `5e1`; `2.2e1`, `2.4e1`).
fn log_axis_label(mark: egui_plot::GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let v = mark.value;
    if (v - v.round()).abs() < 1e-9 {
        return format!("1e{}", v.round() as i64);
    }
    // Neighbours differ by the factor 10^step: the digits that tell a relative 10^step − 1 apart
    // (none for the 2× and 5× marks).
    let apart = 10f64.powf(mark.step_size) - 1.0;
    let digits = (-apart.log10() - 0.05).ceil().clamp(0.0, 6.0) as usize;
    format!("{:.digits$e}", 10f64.powf(v))
}

/// The spacing, points, at which egui_plot shows a y tick label at full strength (it hides those
/// under 20 points apart and fades them in up to 30).
const Y_LABEL_SPACING_PT: f64 = 30.0;

/// Log10 axis: marks on whole decades, as many decades apart (1, 2, 5 × 10^k) as their labels need
/// to show however many decades the curves span; 2× and 5× marks between decades when each decade
/// has room; within one decade, marks within it, so a labelled mark is always inside the plot.
fn log_spacer(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = input.bounds;
    if !(input.base_step_size > 0.0 && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    // The smallest spacing, in decades, at which labels show.
    let label_spacing = points(&input, Y_LABEL_SPACING_PT);
    let step = nice_step(label_spacing.max(1.0));
    let mut marks: Vec<egui_plot::GridMark> = marks_apart((lo, hi), step);
    if step <= 1.0 {
        for k in lo.floor() as i64..hi.ceil() as i64 {
            for m in [2f64, 5.0] {
                marks.push(egui_plot::GridMark {
                    value: k as f64 + m.log10(),
                    step_size: 0.3,
                });
            }
        }
    }
    // No labelled mark clear of the ends (the curves within a decade): marks within it.
    let margin = points(&input, Y_LABEL_MARGIN_PT);
    let labelled_inside = marks
        .iter()
        .any(|m| m.step_size >= label_spacing && m.value >= lo + margin && m.value <= hi - margin);
    if !labelled_inside {
        marks = marks_apart((lo + margin, hi - margin), label_spacing);
    }
    marks
}

/// The finest grid spacing of every plot here, points (egui_plot's default, set explicitly:
/// [`labels_inside`] reads the scale from it).
pub const GRID_SPACING_MIN_PT: f32 = 8.0;
/// How far a y axis's marks stay from the plot's top and bottom, points: half a tick label's height.
pub const Y_LABEL_MARGIN_PT: f64 = 8.0;
/// How far an x axis's marks stay from the plot's left and right ends, points: half a short tick
/// label's width.
pub const X_LABEL_MARGIN_PT: f64 = 12.0;

/// `spacer`'s marks but those whose tick labels would reach out of the plot: a mark outside the
/// bounds, or closer than `margin_pt` to either end (egui_plot centres a label on its mark and does
/// not clip it to the plot, so a mark at the top edge puts half its label on what is above the
/// plot). When none left is labelled (egui_plot labels marks at least `label_pt` apart), one
/// labelled mark at a round value within: a plot always has a label on each axis. The plot's grid
/// spacing must start at [`GRID_SPACING_MIN_PT`] ([`framed`]).
pub fn labels_inside<'a>(
    spacer: impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a,
    margin_pt: f64,
    label_pt: f64,
) -> impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a {
    move |input| {
        let (lo, hi) = input.bounds;
        let margin = points(&input, margin_pt);
        let label_spacing = points(&input, label_pt);
        let mut marks: Vec<egui_plot::GridMark> = spacer(input)
            .into_iter()
            .filter(|m| m.value >= lo + margin && m.value <= hi - margin)
            .collect();
        let (inner_lo, inner_hi) = (lo + margin, hi - margin);
        if !marks.iter().any(|m| m.step_size >= label_spacing) && inner_hi > inner_lo {
            // The largest 1, 2, 5 × 10^k step, which has a multiple within.
            let width = inner_hi - inner_lo;
            let p = 10f64.powf(width.log10().floor());
            let step = [5.0, 2.0, 1.0]
                .into_iter()
                .map(|m| m * p)
                .find(|s| *s <= width)
                .unwrap_or(p);
            marks.push(egui_plot::GridMark {
                // `+ 0.0`: a mark at −0.0 would be labelled "-0.0".
                value: (inner_lo / step).ceil() * step + 0.0,
                step_size: step.max(label_spacing),
            });
        }
        marks
    }
}

/// A plot whose tick labels stay inside it: `spacers` (x, y) filtered by [`labels_inside`].
pub fn framed<'a>(
    plot: Plot<'a>,
    x_spacer: impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a,
    y_spacer: impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a,
) -> Plot<'a> {
    framed_with(plot, (x_spacer, X_LABEL_SPACING_PT), y_spacer)
}

/// [`framed`] with the x marks' labelled spacing `x_label_pt` (the spacing `x_spacer` keeps).
fn framed_with<'a>(
    plot: Plot<'a>,
    (x_spacer, x_label_pt): (
        impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a,
        f64,
    ),
    y_spacer: impl Fn(egui_plot::GridInput) -> Vec<egui_plot::GridMark> + 'a,
) -> Plot<'a> {
    plot.grid_spacing(egui::Rangef::new(GRID_SPACING_MIN_PT, 300.0))
        .x_grid_spacer(labels_inside(x_spacer, X_LABEL_MARGIN_PT, x_label_pt))
        .y_grid_spacer(labels_inside(
            y_spacer,
            Y_LABEL_MARGIN_PT,
            Y_LABEL_SPACING_PT,
        ))
}

/// The spacing, points, at which egui_plot shows an x tick label at full strength (it hides those
/// under 60 points apart and fades them in up to 80).
const X_LABEL_SPACING_PT: f64 = 80.0;

/// `pt` points in the axis's value.
fn points(input: &egui_plot::GridInput, pt: f64) -> f64 {
    pt * input.base_step_size / f64::from(GRID_SPACING_MIN_PT)
}

/// Iteration axis: integer marks about a third of the range apart (1, 2, 5 × 10^k), and far enough
/// apart for their labels to show.
fn iteration_spacer(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let raw = ((input.bounds.1 - input.bounds.0) / 3.0)
        .max(points(&input, X_LABEL_SPACING_PT))
        .max(1.0);
    marks_apart(input.bounds, raw)
}

/// The histograms' x marks are closer than [`X_LABEL_SPACING_PT`]: their labels are short ("-0.05",
/// "10"), so their axis fades labels in from 35 to this many points apart instead of egui_plot's
/// 60–80, and a histogram ~190 points wide (the three of the Accuracy tab at 1280 × 800) keeps
/// −0.05, 0, 0.05 or −10, 0, 10 instead of a lone 0.
const HISTOGRAM_LABEL_SPACING_PT: f64 = 50.0;

/// Histogram axis: marks about a quarter of the range apart (1, 2, 5 × 10^k), so a narrow histogram
/// still has labels (egui_plot's own marks are powers of ten, whose labels a narrow plot hides), and
/// far enough apart for their labels to show.
fn histogram_spacer(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let raw =
        ((input.bounds.1 - input.bounds.0) / 4.0).max(points(&input, HISTOGRAM_LABEL_SPACING_PT));
    marks_apart(input.bounds, raw)
}

/// Percentage axis: marks as close as their labels show (1, 2, 5 × 10^k apart), so a low histogram
/// keeps labels.
fn percent_spacer(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    marks_apart(input.bounds, points(&input, Y_LABEL_SPACING_PT))
}

/// The smallest 1, 2, 5 × 10^k of at least `raw` (> 0).
fn nice_step(raw: f64) -> f64 {
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

/// Marks at multiples of the smallest 1, 2, 5 × 10^k step of at least `raw` within `(lo, hi)`.
fn marks_apart((lo, hi): (f64, f64), raw: f64) -> Vec<egui_plot::GridMark> {
    if !(raw.is_finite() && raw > 0.0) {
        return Vec::new();
    }
    let step = nice_step(raw);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| egui_plot::GridMark {
            value: k as f64 * step,
            step_size: step,
        })
        .collect()
}

/// ψ and F_a, F_b, F_c (log scale) over the iterations of `stage`, and below them the step norm and
/// KKT residual.
pub fn convergence_plot_ui(ui: &mut egui::Ui, history: &[IterationRecord], stage: Stage) {
    let records: Vec<&IterationRecord> = history.iter().filter(|r| r.stage == stage).collect();
    if records.is_empty() {
        ui.label(
            RichText::new(format!("{stage}: no iterations yet — press Calibrate."))
                .color(Color32::GRAY),
        );
    } else if let Some(last) = records.last() {
        let list = |v: &[f64], digits: usize| {
            v.iter()
                .map(|x| format!("{x:.digits$}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        ui.label(format!(
            "{stage}: iteration {}, ψ = {:.6} mm², F = [{}] mm², {}step {:.2e}, KKT {:.2e}",
            last.iteration,
            last.psi_mm2,
            list(&last.f_mm2, 4),
            last.lambda
                .as_ref()
                .map_or(String::new(), |l| format!("weights λ = [{}], ", list(l, 2))),
            last.step_norm,
            last.optimality_residual
        ));
    }
    let series = |f: &dyn Fn(&IterationRecord) -> f64| -> Vec<[f64; 2]> {
        records
            .iter()
            .filter_map(|r| log10(f(r)).map(|y| [r.iteration as f64, y]))
            .collect()
    };
    let psi = series(&|r| r.psi_mm2);
    // One objective per reflector (F_a, F_b, F_c for three), named a, b, c, … by position.
    let n_reflectors = records.first().map_or(0, |r| r.f_mm2.len());
    let f: Vec<(String, Vec<[f64; 2]>)> = crate::kinematics::default_reflector_names(n_reflectors)
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let points = series(&|r| r.f_mm2.get(k).copied().unwrap_or(f64::NAN));
            (format!("F_{name}"), points)
        })
        .collect();
    let step = series(&|r| r.step_norm);
    let kkt = series(&|r| r.optimality_residual);
    ui.columns(2, |cols| {
        iteration_plot(("objective", stage), "mm² (log10)").show(&mut cols[0], |plot| {
            plot.line(Line::new("ψ = max F", psi).color(PSI_COLOR).width(2.5));
            for (k, (name, points)) in f.into_iter().enumerate() {
                plot.line(Line::new(name, points).color(F_COLORS[k % F_COLORS.len()]));
            }
        });
        iteration_plot(("step", stage), "log10").show(&mut cols[1], |plot| {
            plot.line(
                Line::new("step norm (scaled)", step).color(Color32::from_rgb(200, 150, 240)),
            );
            plot.line(Line::new("KKT residual", kkt).color(Color32::from_rgb(150, 210, 210)));
        });
    });
}

/// A plot over the iterations with a log10 y axis.
fn iteration_plot<'a>(id: (&str, Stage), y_label: &str) -> Plot<'a> {
    let plot = Plot::new((id.0, format!("{:?}", id.1)))
        .legend(Legend::default())
        .x_axis_label("iteration")
        .include_x(0.0)
        .x_axis_formatter(|m, _| format!("{:.0}", m.value))
        .set_margin_fraction(egui::vec2(0.05, 0.12))
        .y_axis_label(y_label)
        .y_axis_formatter(log_axis_label);
    framed(plot, iteration_spacer, log_spacer)
}

/// Width of the numbers beside the histograms.
const NUMBERS_WIDTH: f32 = 290.0;
/// Narrowest histogram worth drawing.
const MIN_HISTOGRAM_WIDTH: f32 = 210.0;
/// Lowest histogram worth drawing.
const MIN_HISTOGRAM_HEIGHT: f32 = 110.0;

/// Colour of the marker of live figures (a running calibration's current iterate).
pub const LIVE_COLOR: Color32 = Color32::from_rgb(250, 200, 90);

/// "live: iteration k of step s", shown above figures of a running calibration's current iterate.
pub fn live_marker_ui(ui: &mut egui::Ui, after: Option<After<'_>>) {
    if let Some(After::Live(live)) = after {
        ui.label(RichText::new(format!("live: {}", live.label())).color(LIVE_COLOR))
            .on_hover_text(
                "The model the running calibration has reached, re-evaluated on the whole dataset \
                 a few times a second; the finished run replaces it, Cancel discards it",
            );
    }
}

/// Histograms of one indicator before (nominal) and after (the live iterate during a run, else the
/// last calibration) on one split, with the Tables 4–8 style numbers beside them. The histograms
/// stand side by side when the width allows, else one above the other beside the numbers, else
/// below the numbers.
pub fn accuracy_ui(ui: &mut egui::Ui, session: &Session, indicator: Indicator, split: Split) {
    let after = session.after();
    // Beside a calibration with errors beyond geometry, the geometric calibration of the same data
    // between the two ("geometric" against "calibrated"/"iteration k": the full model).
    let geometric = session.geometric.as_ref().filter(|_| after.is_some());
    let mut analyses = vec![Some(&session.nominal)];
    let mut names = vec!["nominal".to_string()];
    let mut colors = vec![NOMINAL_COLOR];
    if let Some(g) = geometric {
        analyses.push(Some(g));
        names.push("geometric".into());
        colors.push(GEOMETRIC_COLOR);
    }
    analyses.push(after.map(|a| a.analysis()));
    // Beside the geometric fit, the finished calibration is named by its model ("full model").
    names.push(match (geometric, after) {
        (Some(_), Some(After::Calibrated(c))) => {
            format!("{} model", c.result.settings.model.name())
        }
        _ => after.map_or_else(|| "calibrated".into(), After::short_name),
    });
    colors.push(if matches!(after, Some(After::Live(_))) {
        LIVE_COLOR
    } else {
        CALIBRATED_COLOR
    });
    let figures: Vec<Option<&SplitFigures>> = analyses
        .iter()
        .map(|a| a.and_then(|a| a.figures(split)))
        .collect();
    let histograms: Vec<(&str, &Histogram, Color32)> = (0..figures.len())
        .filter_map(|k| {
            let h = figures[k].and_then(|f| f.histogram(indicator))?;
            Some((names[k].as_str(), h, colors[k]))
        })
        .collect();

    let spacing = ui.spacing().item_spacing.x;
    let width = ui.available_width();
    let height = ui.available_height();
    let numbers = |ui: &mut egui::Ui| {
        ui.vertical(|ui| {
            ui.set_width(NUMBERS_WIDTH);
            accuracy_numbers_ui(ui, indicator, split, &figures, &names, after);
        });
    };
    let n = histograms.len().max(1) as f32;
    if width >= NUMBERS_WIDTH + n * (MIN_HISTOGRAM_WIDTH + spacing) {
        // Numbers | histograms side by side.
        ui.horizontal_top(|ui| {
            numbers(ui);
            let w = (ui.available_width() - (n - 1.0) * spacing) / n;
            for (name, h, color) in &histograms {
                histogram_plot_ui(ui, indicator, split, name, h, *color, egui::vec2(w, height));
            }
        });
    } else if width >= NUMBERS_WIDTH + MIN_HISTOGRAM_WIDTH + spacing
        && height >= n * MIN_HISTOGRAM_HEIGHT
    {
        // Numbers | histograms stacked.
        ui.horizontal_top(|ui| {
            numbers(ui);
            ui.vertical(|ui| {
                let w = ui.available_width();
                let h = (height - (n - 1.0) * ui.spacing().item_spacing.y) / n;
                for (name, hist, color) in &histograms {
                    histogram_plot_ui(ui, indicator, split, name, hist, *color, egui::vec2(w, h));
                }
            });
        });
    } else {
        // Narrow: numbers, then the histograms side by side below them, all scrolling.
        egui::ScrollArea::vertical().show(ui, |ui| {
            numbers(ui);
            ui.horizontal(|ui| {
                let w = ((ui.available_width() - (n - 1.0) * spacing) / n).max(120.0);
                for (name, h, color) in &histograms {
                    histogram_plot_ui(
                        ui,
                        indicator,
                        split,
                        name,
                        h,
                        *color,
                        egui::vec2(w, MIN_HISTOGRAM_HEIGHT * 1.5),
                    );
                }
            });
        });
    }
}

/// The Tables 4–8 style numbers of one indicator, nominal and after.
fn accuracy_numbers_ui(
    ui: &mut egui::Ui,
    indicator: Indicator,
    split: Split,
    figures: &[Option<&SplitFigures>],
    names: &[String],
    after: Option<After<'_>>,
) {
    let unit = if indicator.is_position() { "mm" } else { "rad" };
    let split_name = match split {
        Split::Cal => "calibration",
        Split::Ver => "verification",
        Split::All => "every",
    };
    ui.label(RichText::new(format!("{} — {split_name} split", indicator.label())).strong());
    live_marker_ui(ui, after);
    let thresholds: [String; 2] = if indicator.is_position() {
        POS_THRESHOLDS_MM.map(|t| format!("|Δd| ≤ {t} mm"))
    } else {
        ORI_THRESHOLDS_RAD.map(|t| format!("Δo ≤ {t} rad"))
    };
    egui::Grid::new(("accuracy numbers", indicator.label(), split))
        .striped(true)
        .num_columns(1 + names.len())
        .show(ui, |ui| {
            ui.label("");
            for name in names {
                ui.label(name);
            }
            ui.end_row();
            let reports: Vec<_> = figures
                .iter()
                .map(|f| f.and_then(|f| f.report.as_ref()))
                .collect();
            // `None` without a report; `Some(None)`: the data cannot measure it.
            let summaries: Vec<_> = reports
                .iter()
                .map(|r| r.map(|r| indicator.summary(r)))
                .collect();
            let cell = |ui: &mut egui::Ui, v: Option<Option<String>>| {
                ui.label(match v {
                    None => "—".into(),
                    Some(None) => crate::metrics::NOT_MEASURABLE.into(),
                    Some(Some(v)) => v,
                });
            };
            let digits = if indicator.is_position() { 3 } else { 5 };
            ui.label(format!("RMS ({unit})"));
            for &s in &summaries {
                cell(ui, s.map(|s| s.map(|s| format!("{:.digits$}", s.0))));
            }
            ui.end_row();
            ui.label(format!("max ({unit})"));
            for &s in &summaries {
                cell(ui, s.map(|s| s.map(|s| format!("{:.digits$}", s.1))));
            }
            ui.end_row();
            for (t, label) in thresholds.iter().enumerate() {
                ui.label(label);
                for &s in &summaries {
                    cell(ui, s.map(|s| s.map(|s| format!("{:.1} %", 100.0 * s.2[t]))));
                }
                ui.end_row();
            }
            ui.label("pairs");
            for &r in &reports {
                let stats = r.and_then(|r| r.stats(indicator.pair_kind()));
                cell(ui, stats.map(|s| Some(s.n_pairs.to_string())));
            }
            ui.end_row();
        });
    if after.is_none() {
        ui.label(RichText::new("Calibrate to see the calibrated figures.").color(Color32::GRAY));
    }
}

const NOMINAL_COLOR: Color32 = Color32::from_rgb(230, 120, 90);
const CALIBRATED_COLOR: Color32 = Color32::from_rgb(100, 190, 235);
/// The geometric calibration beside one with errors beyond geometry.
const GEOMETRIC_COLOR: Color32 = Color32::from_rgb(170, 150, 220);

/// One histogram of `size`: symmetric range for signed Δd, from zero for Δo; the paper's thresholds
/// as lines when they fall in range.
fn histogram_plot_ui(
    ui: &mut egui::Ui,
    indicator: Indicator,
    split: Split,
    name: &str,
    histogram: &Histogram,
    color: Color32,
    size: egui::Vec2,
) {
    let width = histogram.bin_width();
    let bars: Vec<Bar> = histogram
        .bars()
        .map(|(x, y)| Bar::new(x, 100.0 * y).width(width * 0.95))
        .collect();
    let extent = histogram.hi;
    // The id does not depend on the name ("iteration k" changes during a run): the plot keeps its
    // state while the live figures update.
    let slot = match name {
        "nominal" => "nominal",
        "geometric" => "geometric",
        _ => "after",
    };
    let plot = Plot::new(("histogram", indicator.label(), split, slot))
        .width(size.x.max(MIN_HISTOGRAM_WIDTH * 0.5))
        .height(size.y.max(MIN_HISTOGRAM_HEIGHT * 0.5))
        .legend(Legend::default())
        .custom_x_axes(vec![
            egui_plot::AxisHints::new_x()
                .label(if indicator.is_position() {
                    "Δd (mm)"
                } else {
                    "Δo (rad)"
                })
                .label_spacing(35.0..=HISTOGRAM_LABEL_SPACING_PT as f32),
        ])
        .y_axis_label("% of samples")
        .allow_scroll(false);
    framed_with(
        plot,
        (histogram_spacer, HISTOGRAM_LABEL_SPACING_PT),
        percent_spacer,
    )
    .show(ui, |plot| {
        plot.bar_chart(BarChart::new(name, bars).color(color));
        let t = if indicator.is_position() {
            POS_THRESHOLDS_MM.to_vec()
        } else {
            ORI_THRESHOLDS_RAD.to_vec()
        };
        for (i, x) in t.into_iter().enumerate().filter(|(_, x)| *x <= extent) {
            let c = Color32::from_gray(if i == 0 { 150 } else { 100 });
            plot.vline(VLine::new(format!("±{x}"), x).color(c));
            if indicator.is_position() {
                plot.vline(VLine::new(format!("±{x}"), -x).color(c));
            }
        }
    });
}

/// All figures of one split at a glance, nominal against the live iterate or the last calibration
/// (the paper's Tables 4–8). Scrolls both ways, with solid scroll bars, when the panel is smaller.
pub fn accuracy_summary_ui(ui: &mut egui::Ui, session: &Session, split: Split) {
    fn report(a: &Analysis, split: Split) -> Option<&AccuracyReport> {
        a.figures(split).and_then(|f| f.report.as_ref())
    }
    let after = session.after();
    live_marker_ui(ui, after);
    let reports = [
        ("nominal".to_string(), report(&session.nominal, split)),
        (
            after.map_or_else(|| "calibrated".into(), After::short_name),
            after.and_then(|a| report(a.analysis(), split)),
        ),
    ];
    let titles = [
        "",
        "model",
        "Δd RMS (mm)",
        "Δd max (mm)",
        "|Δd| ≤ 0.3 mm",
        "|Δd| ≤ 0.6 mm",
        "Δo RMS (rad)",
        "Δo max (rad)",
        "Δo ≤ 0.005 rad",
        "Δo ≤ 0.01 rad",
    ];
    ui.spacing_mut().scroll = egui::style::ScrollStyle::solid();
    egui::ScrollArea::both()
        .auto_shrink([false, false])
        .show(ui, |ui| {
            egui::Grid::new(("accuracy summary", split))
                .striped(true)
                .num_columns(titles.len())
                .spacing([14.0, 4.0])
                .show(ui, |ui| {
                    for t in titles {
                        ui.label(RichText::new(t).strong());
                    }
                    ui.end_row();
                    let kinds = [
                        (
                            "relative, left arm",
                            Indicator::RelativePosition(Side::Left),
                            Indicator::RelativeOrientation(Side::Left),
                        ),
                        (
                            "relative, right arm",
                            Indicator::RelativePosition(Side::Right),
                            Indicator::RelativeOrientation(Side::Right),
                        ),
                        (
                            "collaborative",
                            Indicator::CollaborativePosition,
                            Indicator::CollaborativeOrientation,
                        ),
                    ];
                    for (name, pos, ori) in kinds {
                        for (row, (model, report)) in reports.iter().enumerate() {
                            ui.label(if row == 0 { name } else { "" });
                            ui.label(model);
                            match report {
                                Some(r) => {
                                    let four = |s: Option<(f64, f64, [f64; 2])>, digits: usize| {
                                        s.map_or_else(
                                            || {
                                                std::array::from_fn(|_| {
                                                    crate::metrics::NOT_MEASURABLE.to_string()
                                                })
                                            },
                                            |(rms, max, freq)| {
                                                [
                                                    format!("{rms:.digits$}"),
                                                    format!("{max:.digits$}"),
                                                    format!("{:.1} %", 100.0 * freq[0]),
                                                    format!("{:.1} %", 100.0 * freq[1]),
                                                ]
                                            },
                                        )
                                    };
                                    for text in four(pos.summary(r), 3)
                                        .into_iter()
                                        .chain(four(ori.summary(r), 5))
                                    {
                                        ui.label(text);
                                    }
                                }
                                None => {
                                    for _ in 0..8 {
                                        ui.label("—");
                                    }
                                }
                            }
                            ui.end_row();
                        }
                    }
                });
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid input of an axis showing `bounds` on `length_pt` points.
    fn input(bounds: (f64, f64), length_pt: f64) -> egui_plot::GridInput {
        egui_plot::GridInput {
            bounds,
            base_step_size: (bounds.1 - bounds.0) / length_pt * f64::from(GRID_SPACING_MIN_PT),
        }
    }

    #[test]
    fn iteration_marks_are_whole_and_spaced_about_a_third_of_the_range() {
        for (lo, hi) in [(0.0, 7.0), (-0.5, 100.5), (0.0, 2.0), (3.0, 1234.0)] {
            let marks = iteration_spacer(input((lo, hi), 600.0));
            assert!(!marks.is_empty(), "{lo}..{hi}");
            for m in &marks {
                assert!(m.value >= lo && m.value <= hi);
                assert_eq!(m.value, m.value.round());
                assert!(m.step_size >= (hi - lo) / 3.0 - 1e-9 || m.step_size == 1.0);
                assert!(m.step_size <= (hi - lo) / 1.0 + 1.0);
            }
        }
    }

    /// However many decades the curves span, on however tall a plot, labelled marks (as far apart
    /// as egui_plot shows their labels) stand inside it, clear of its ends.
    #[test]
    fn log_marks_keep_labels_inside_the_plot_over_any_span() {
        for decades in [0.05, 0.4, 1.0, 3.0, 8.0, 17.0, 40.0, 300.0] {
            for height_pt in [70.0, 140.0, 400.0] {
                for lo in [-12.3, -1.0, 0.4, 2.0] {
                    let bounds = (lo, lo + decades);
                    let input = input(bounds, height_pt);
                    let per_pt = (bounds.1 - bounds.0) / height_pt;
                    let labelled: Vec<_> =
                        labels_inside(log_spacer, Y_LABEL_MARGIN_PT, Y_LABEL_SPACING_PT)(input)
                            .into_iter()
                            .filter(|m| m.step_size / per_pt >= Y_LABEL_SPACING_PT - 1e-6)
                            .collect();
                    assert!(
                        !labelled.is_empty(),
                        "{decades} decades from {lo} on {height_pt} pt: no labelled mark"
                    );
                    for m in &labelled {
                        assert!(m.value - bounds.0 >= Y_LABEL_MARGIN_PT * per_pt - 1e-9);
                        assert!(bounds.1 - m.value >= Y_LABEL_MARGIN_PT * per_pt - 1e-9);
                    }
                    let texts: Vec<String> = labelled
                        .iter()
                        .map(|m| log_axis_label(*m, &(bounds.0..=bounds.1)))
                        .collect();
                    let mut unique = texts.clone();
                    unique.dedup();
                    assert_eq!(unique, texts, "labels told apart");
                }
            }
        }
    }

    /// A histogram's axes keep labelled marks however narrow or low it is drawn.
    #[test]
    fn histogram_marks_are_far_enough_apart_to_be_labelled() {
        for (bounds, length_pt) in [
            ((-0.2, 0.2), 120.0),
            ((-30.0, 30.0), 600.0),
            ((0.0, 0.02), 180.0),
        ] {
            let per_pt = (bounds.1 - bounds.0) / length_pt;
            let x = histogram_spacer(input(bounds, length_pt));
            assert!(!x.is_empty());
            assert!(
                x.iter()
                    .all(|m| m.step_size / per_pt >= HISTOGRAM_LABEL_SPACING_PT - 1e-6)
            );
        }
        // The Accuracy tab's histograms at 1280 × 800 (~190 points for ±0.065 mm): three labelled
        // marks, not a lone 0.
        let x = labels_inside(
            histogram_spacer,
            X_LABEL_MARGIN_PT,
            HISTOGRAM_LABEL_SPACING_PT,
        )(input((-0.065, 0.065), 190.0));
        let values: Vec<f64> = x.iter().map(|m| m.value).collect();
        assert_eq!(values.len(), 3, "{values:?}");
        for height_pt in [50.0, 90.0, 300.0] {
            let bounds = (-1.0, 11.0);
            let per_pt = 12.0 / height_pt;
            let y = labels_inside(percent_spacer, Y_LABEL_MARGIN_PT, Y_LABEL_SPACING_PT)(input(
                bounds, height_pt,
            ));
            assert!(!y.is_empty(), "{height_pt} pt");
            assert!(
                y.iter()
                    .all(|m| m.step_size / per_pt >= Y_LABEL_SPACING_PT - 1e-6)
            );
        }
    }
}
