//! The "Compare methods" view ([`compare_ui`]): which methods to run, the summary table (nominal
//! first, the best figure of each column highlighted, an Adopt button per method), a histogram and a
//! box plot per method. Its state is [`CompareView`]; the comparison is run by its job.

use super::indicator_choice_ui;
use super::settings::{base_method_help, method_help};
use crate::analysis::Indicator;
use crate::app::command::Command;
use crate::app::compare::{CompareView, paper_set};
use crate::app::plots;
use crate::comparison::{self, BoxStats, Comparison, METHODS, MethodEntry, MethodOutcome};
use crate::dataset::Split;
use crate::metrics::AccuracyStats;
use crate::side::Side;
use crate::solver::CalibrationSettings;
use eframe::egui::{self, Color32, RichText};
use egui_plot::{Bar, BarChart, BoxElem, BoxPlot, BoxSpread, Plot, log_grid_spacer};

/// Colour of the best figure of a column.
const BEST_COLOR: Color32 = Color32::from_rgb(110, 210, 120);
/// Colour of a method that failed or did not converge.
const FAIL_COLOR: Color32 = Color32::from_rgb(255, 110, 100);

/// The termination of a method's row: converged (with the iterations), or each stage that did not.
fn termination_text(outcome: &MethodOutcome) -> (String, bool) {
    match &outcome.outcome {
        Err(e) => (format!("failed: {e}"), false),
        Ok(run) => {
            let r = &run.result;
            if r.is_converged() {
                let iterations: usize = r.stages.iter().map(|s| s.iterations).sum();
                (format!("converged ({iterations} it.)"), true)
            } else {
                let stages: Vec<String> = r
                    .stages
                    .iter()
                    .filter(|s| !s.termination.is_converged())
                    .map(|s| format!("{}: {}", s.stage, s.termination))
                    .collect();
                let text = if stages.is_empty() {
                    "not every stage ran".to_string()
                } else {
                    stages.join("; ")
                };
                (text, false)
            }
        }
    }
}

/// The twelve figures of a summary row: for the left arm's relative, the right arm's relative and
/// the collaborative errors, `Δd` RMS* and max (mm), `Δo` RMS and max (rad).
fn row_figures(report: Option<&crate::metrics::AccuracyReport>) -> Option<[f64; 12]> {
    let r = report?;
    // NaN where the data cannot measure a figure (printed "not measurable").
    let four = |s: &AccuracyStats| {
        [
            s.pos_rms_mm,
            s.pos_max_mm,
            s.ori_rms_rad.unwrap_or(f64::NAN),
            s.ori_max_rad.unwrap_or(f64::NAN),
        ]
    };
    let mut out = [0.0; 12];
    let stats = [
        r.relative_or_nan(Side::Left),
        r.relative_or_nan(Side::Right),
        r.collaborative_or_nan(),
    ];
    for (k, s) in stats.iter().enumerate() {
        out[4 * k..4 * k + 4].copy_from_slice(&four(s));
    }
    Some(out)
}

/// What the comparison view needs to know of the app besides its own state.
#[derive(Clone, Copy, Debug)]
pub struct CompareState {
    pub has_session: bool,
    pub comparing: bool,
    pub calibrating: bool,
}

/// The comparison view (instead of the 3D view, the table and the plots): it picks methods and
/// chooses what is shown in `view`, and pushes a [`Command`] to run, cancel, adopt or close.
pub fn compare_ui(
    ui: &mut egui::Ui,
    view: &mut CompareView,
    state: CompareState,
    commands: &mut Vec<Command>,
) {
    let running = state.comparing;
    let busy = running || state.calibrating;
    let has_session = state.has_session;
    ui.horizontal_wrapped(|ui| {
        ui.heading("Compare methods");
        if ui
            .button("Back to the 3D view")
            .on_hover_text("Close the comparison (it is kept; Compare methods… opens it again)")
            .clicked()
        {
            commands.push(Command::ShowComparison(false));
        }
        ui.separator();
        let run = egui::Button::new(RichText::new("Run comparison").strong());
        let picked = view.picked.iter().any(|p| *p);
        if ui
            .add_enabled(!busy && has_session && picked, run)
            .on_hover_text(
                "Calibrate the loaded dataset with each picked method, one after another in the \
                     background, with the settings on the left (split, limits, tolerances) and the \
                     excluded configurations",
            )
            .on_disabled_hover_text(
                "Load a dataset, pick a method, and wait for a running calibration",
            )
            .clicked()
        {
            commands.push(Command::StartComparison);
        }
        if ui
            .add_enabled(running, egui::Button::new("Cancel comparison"))
            .on_hover_text("Stop the running method and skip the rest; finished rows stay")
            .clicked()
        {
            commands.push(Command::CancelComparison);
        }
        if let Some(progress) = &view.progress {
            ui.spinner();
            ui.label(progress.label());
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("Methods:");
        ui.add_enabled_ui(!running, |ui| {
            for (entry, picked) in METHODS.iter().zip(view.picked.iter_mut()) {
                ui.checkbox(picked, entry.title())
                    .on_hover_text(entry_help(entry));
            }
            if ui.small_button("paper's set").clicked() {
                view.picked = paper_set();
            }
            if ui.small_button("all").clicked() {
                view.picked = vec![true; METHODS.len()];
            }
        });
    });
    ui.horizontal_wrapped(|ui| {
        ui.selectable_value(&mut view.split, Split::Ver, "ver split");
        ui.selectable_value(&mut view.split, Split::Cal, "cal split");
        ui.separator();
        indicator_choice_ui(
            ui,
            "Histograms and box plots of:",
            "compare indicator",
            &mut view.indicator,
        );
    });
    ui.separator();
    let Some(comparison) = &view.comparison else {
        ui.label(if has_session {
            "Pick methods and press Run comparison."
        } else {
            "No dataset."
        });
        return;
    };
    let split = view.split;
    let adopt_enabled = !busy;
    let adopted = view.adopted;
    // A solid scroll bar: a floating one would cover the last row.
    ui.spacing_mut().scroll = egui::style::ScrollStyle::solid();
    egui::ScrollArea::horizontal()
        .id_salt("compare table")
        .auto_shrink([false, true])
        .show(ui, |ui| {
            summary_table_ui(ui, comparison, split, adopt_enabled, adopted, commands)
        });
    if comparison.cancelled {
        ui.label(
            RichText::new("Cancelled: the methods that had not run are not listed.")
                .color(FAIL_COLOR),
        );
    }
    ui.separator();
    distributions_ui(ui, comparison, split, view.indicator);
}

/// A method's hover text: what it is and what it cannot see.
fn entry_help(entry: &MethodEntry) -> String {
    let settings = entry.settings(&CalibrationSettings::default());
    let (_, step1) = method_help(settings.method);
    let (_, step2) = base_method_help(settings.base_method);
    format!(
        "{}: step 1 {}, step 2 {}.\nStep 1: {step1}\nStep 2: {step2}",
        entry.title(),
        settings.method.name(),
        settings.base_method.name()
    )
}

/// The summary table: a row per model (nominal first), the twelve figures of the split, the best of
/// each column among the methods highlighted, each method's termination and an Adopt button.
fn summary_table_ui(
    ui: &mut egui::Ui,
    comparison: &Comparison,
    split: Split,
    adopt_enabled: bool,
    adopted: Option<&'static str>,
    commands: &mut Vec<Command>,
) {
    let rows: Vec<Option<[f64; 12]>> = comparison
        .methods
        .iter()
        .map(|m| row_figures(m.figures().and_then(|f| f.report(split))))
        .collect();
    let mut best = [f64::INFINITY; 12];
    for figures in rows.iter().flatten() {
        for (b, v) in best.iter_mut().zip(figures) {
            *b = b.min(*v);
        }
    }
    let groups = ["relative, left arm", "relative, right arm", "collaborative"];
    let columns = ["Δd RMS* mm", "Δd max mm", "Δo RMS rad", "Δo max rad"];
    let value = |k: usize, v: f64| {
        if v.is_nan() {
            crate::metrics::NOT_MEASURABLE.to_string()
        } else if k % 4 < 2 {
            format!("{v:.3}")
        } else {
            format!("{v:.5}")
        }
    };
    egui::Grid::new(("compare summary", split))
        .striped(true)
        .num_columns(15)
        .spacing([8.0, 3.0])
        .show(ui, |ui| {
            ui.label("");
            ui.label("");
            for g in groups {
                ui.label(RichText::new(g).strong());
                for _ in 1..4 {
                    ui.label("");
                }
            }
            ui.label("");
            ui.end_row();
            ui.label(RichText::new("model").strong());
            ui.label("");
            for _ in groups {
                for c in columns {
                    ui.label(RichText::new(c).small());
                }
            }
            ui.label(RichText::new("termination").strong());
            ui.end_row();

            ui.label("nominal");
            ui.label("");
            match row_figures(comparison.nominal.report(split)) {
                Some(figures) => {
                    for (k, v) in figures.iter().enumerate() {
                        ui.label(RichText::new(value(k, *v)).color(Color32::GRAY));
                    }
                }
                None => {
                    for _ in 0..12 {
                        ui.label("—");
                    }
                }
            }
            ui.label(RichText::new("the robot description's model").color(Color32::GRAY));
            ui.end_row();

            for (method, figures) in comparison.methods.iter().zip(&rows) {
                let title = method.entry.title();
                let mut name = RichText::new(title.as_str());
                if adopted == Some(method.entry.key) {
                    name = name.strong();
                }
                ui.label(name).on_hover_text(entry_help(&method.entry));
                let adopt = ui
                    .add_enabled(
                        adopt_enabled && method.run().is_some(),
                        egui::Button::new(format!("Adopt {}", method.entry.key)).small(),
                    )
                    .on_hover_text(
                        "Make this method's result the current calibration: the 3D view, the table, \
                         the plots and the exports show it",
                    );
                if adopt.clicked() {
                    commands.push(Command::AdoptCompared(method.entry.key));
                }
                match figures {
                    Some(figures) => {
                        for (k, v) in figures.iter().enumerate() {
                            let text = RichText::new(value(k, *v));
                            if *v <= best[k] && rows.iter().flatten().count() > 1 {
                                ui.label(text.color(BEST_COLOR).strong())
                                    .on_hover_text("the best of this column");
                            } else {
                                ui.label(text);
                            }
                        }
                    }
                    None => {
                        for _ in 0..12 {
                            ui.label("—");
                        }
                    }
                }
                termination_cell_ui(ui, method);
                ui.end_row();
            }
        });
}

/// A method's termination (and, for distance-single, the reflector each arm used), red unless it
/// converged.
fn termination_cell_ui(ui: &mut egui::Ui, method: &MethodOutcome) {
    let (mut termination, converged) = termination_text(method);
    if let Some(run) = method.run() {
        let used: Vec<String> = Side::BOTH
            .iter()
            .filter_map(|&s| run.result.reflector_used[s].map(|r| format!("{s} {r}")))
            .collect();
        if !used.is_empty() {
            termination = format!("{termination}; reflector {}", used.join(", "));
        }
    }
    let shown = crate::textfile::excerpt_n(&termination, 70);
    let color = if converged { Color32::GRAY } else { FAIL_COLOR };
    ui.label(RichText::new(shown).color(color))
        .on_hover_text(termination);
}

/// Per method a histogram of the indicator's samples on the split, on one shared range, and a box
/// plot per method beside them.
fn distributions_ui(
    ui: &mut egui::Ui,
    comparison: &Comparison,
    split: Split,
    indicator: Indicator,
) {
    let samples: Vec<(String, &[f32])> = comparison
        .methods
        .iter()
        .filter_map(|m| {
            let s = m.figures()?.samples(split, indicator)?;
            Some((m.entry.key.to_string(), s))
        })
        .collect();
    if samples.is_empty() {
        ui.label("No method has figures on this split yet.");
        return;
    }
    let extent = samples
        .iter()
        .map(|(_, s)| comparison::extent(s))
        .fold(0.0, f64::max);
    let unit = if indicator.is_position() { "mm" } else { "rad" };
    ui.label(
        RichText::new(format!(
            "{} — {} split (Δd: per pair the worst of the three reflectors); box plots: quartiles, \
             whiskers at 1.5 IQR",
            indicator.label(),
            split.name()
        ))
        .small(),
    );
    let height = (ui.available_height() - 8.0).max(120.0);
    let n = samples.len();
    let cols = n.clamp(1, 4);
    let rows = n.div_ceil(cols);
    ui.columns(2, |columns| {
        let ui = &mut columns[0];
        let cell_w = ui.available_width() / cols as f32 - 6.0;
        let cell_h = (height / rows as f32 - 6.0).max(60.0);
        for (r, chunk) in samples.chunks(cols).enumerate() {
            ui.horizontal(|ui| {
                for (c, (key, s)) in chunk.iter().enumerate() {
                    let k = r * cols + c;
                    let h = comparison::histogram(
                        indicator,
                        s,
                        extent,
                        crate::analysis::HISTOGRAM_BINS,
                    );
                    let width = h.bin_width();
                    let bars: Vec<Bar> = h
                        .bars()
                        .map(|(x, f)| Bar::new(x, 100.0 * f).width(width))
                        .collect();
                    let plot = Plot::new(("compare histogram", key.as_str(), split))
                        .width(cell_w)
                        .height(cell_h)
                        .allow_scroll(false)
                        .allow_drag(false)
                        .allow_zoom(false)
                        .show_axes([true, false])
                        .x_axis_label(format!("{key} ({unit})"));
                    plots::framed(plot, log_grid_spacer(10), log_grid_spacer(10)).show(
                        ui,
                        |plot| {
                            plot.bar_chart(BarChart::new(key.as_str(), bars).color(color(k)));
                        },
                    );
                }
            });
        }
        let ui = &mut columns[1];
        let boxes: Vec<(usize, &String, BoxStats)> = samples
            .iter()
            .enumerate()
            .filter_map(|(k, (key, s))| Some((k, key, BoxStats::of(s)?)))
            .collect();
        let names: Vec<String> = samples.iter().map(|(k, _)| k.clone()).collect();
        let plot = Plot::new(("compare box plots", split))
            .height(height)
            .allow_scroll(false)
            .allow_drag(false)
            .allow_zoom(false)
            .y_axis_label(unit)
            .x_axis_formatter(move |mark, _| {
                let k = mark.value.round();
                if (mark.value - k).abs() < 1e-6 && k >= 0.0 {
                    names.get(k as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            });
        plots::framed(plot, log_grid_spacer(10), log_grid_spacer(10)).show(ui, |plot| {
            for (k, key, b) in boxes {
                let elem = BoxElem::new(
                    k as f64,
                    BoxSpread::new(b.whisker_lo, b.q1, b.median, b.q3, b.whisker_hi),
                )
                .name(key)
                .box_width(0.5)
                .whisker_width(0.3)
                .fill(color(k).gamma_multiply(0.3))
                .stroke(egui::Stroke::new(1.5, color(k)));
                plot.box_plot(BoxPlot::new(key.as_str(), vec![elem]));
            }
        });
    });
}

/// A method's colour in the plots.
fn color(k: usize) -> Color32 {
    const COLORS: [Color32; 8] = [
        Color32::from_rgb(90, 160, 255),
        Color32::from_rgb(255, 160, 60),
        Color32::from_rgb(120, 200, 110),
        Color32::from_rgb(230, 90, 90),
        Color32::from_rgb(180, 130, 230),
        Color32::from_rgb(200, 170, 90),
        Color32::from_rgb(90, 200, 200),
        Color32::from_rgb(230, 120, 190),
    ];
    COLORS[k % COLORS.len()]
}
