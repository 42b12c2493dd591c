//! The panels around the viewport: settings and view options ([`settings`], [`view_options`]), plots,
//! the configuration table and the status bar. They edit view state in place and push a [`Command`]
//! for everything else.

mod settings;
mod view_options;

pub(crate) use settings::{base_method_help, method_help};

use super::job::calibration::CalibrationJob;
use super::session::{self, After};
use super::{Command, ERROR_COLOR, Status, WorkbenchApp, plots, table};

/// Colour of warnings (the robot's).
const WARNING_COLOR: Color32 = Color32::from_rgb(235, 180, 90);
use crate::analysis::Indicator;
use crate::dataset::Split;
use crate::side::Side;
use crate::solver::Stage;
use eframe::egui::{self, Color32, RichText};

/// Tabs of the bottom area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlotTab {
    Convergence,
    Accuracy,
    Summary,
}

/// What the plot area shows.
pub struct PlotsView {
    tab: PlotTab,
    /// The stage whose convergence is plotted (follows a running calibration).
    pub stage: Stage,
    indicator: Indicator,
    split: Split,
    /// Where the plots were drawn last, for "Export plots as PNG".
    pub rect: Option<egui::Rect>,
}

impl Default for PlotsView {
    fn default() -> Self {
        Self {
            tab: PlotTab::Convergence,
            stage: Stage::Arm(Side::Left),
            indicator: Indicator::RelativePosition(Side::Left),
            split: Split::Ver,
            rect: None,
        }
    }
}

impl WorkbenchApp {
    /// Status bar; settings on the left at full height (a long form); the plots below the viewport
    /// and the table (the histograms and the summary table need the width); the table on the right.
    /// Default sizes follow the window (1280 × 800 up to 1920 × 1080 and beyond); every panel is
    /// resizable within limits that leave the viewport a usable size.
    pub(super) fn panels_ui(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let window = ui.available_size();
        egui::Panel::bottom("status bar").show(ui, |ui| self.status_bar_ui(ui, commands));
        egui::Panel::left("settings")
            .default_size((window.x * 0.19).clamp(230.0, 300.0))
            .size_range(200.0..=(window.x * 0.3).max(240.0))
            .resizable(true)
            .show(ui, |ui| {
                // A side panel is as wide as its contents: fill it, or it shrinks to them.
                ui.set_min_width(ui.available_width());
                self.settings_panel_ui(ui, commands)
            });
        if self.compare.open {
            // The comparison takes the rest of the window.
            return;
        }
        egui::Panel::bottom("plots")
            .default_size((window.y * 0.36).clamp(220.0, 420.0))
            .size_range(140.0..=(window.y * 0.6).max(200.0))
            .resizable(true)
            .show(ui, |ui| self.plots_panel_ui(ui));
        egui::Panel::right("table")
            .default_size((window.x * 0.36).clamp(320.0, 480.0))
            .size_range(220.0..=(window.x * 0.4).max(260.0))
            .resizable(true)
            .show(ui, |ui| {
                ui.set_min_width(ui.available_width());
                self.table_panel_ui(ui, commands)
            });
    }

    fn plots_panel_ui(&mut self, ui: &mut egui::Ui) {
        let view = &mut self.plots;
        ui.horizontal_wrapped(|ui| {
            ui.selectable_value(&mut view.tab, PlotTab::Convergence, "Convergence");
            ui.selectable_value(&mut view.tab, PlotTab::Accuracy, "Accuracy");
            ui.selectable_value(&mut view.tab, PlotTab::Summary, "Summary");
            ui.separator();
            if view.tab == PlotTab::Convergence {
                for stage in plots::STAGES {
                    ui.selectable_value(&mut view.stage, stage, stage.to_string());
                }
                return;
            }
            if view.tab == PlotTab::Accuracy {
                let label = ui.label("Figure:");
                egui::ComboBox::from_id_salt("figure")
                    .selected_text(view.indicator.label())
                    .width(230.0)
                    .show_ui(ui, |ui| {
                        for f in Indicator::ALL {
                            ui.selectable_value(&mut view.indicator, f, f.label());
                        }
                    })
                    .response
                    .labelled_by(label.id);
            }
            ui.selectable_value(&mut view.split, Split::Cal, "cal split");
            ui.selectable_value(&mut view.split, Split::Ver, "ver split");
        });
        view.rect = Some(ui.available_rect_before_wrap());
        match (view.tab, &self.session) {
            (PlotTab::Convergence, _) => plots::convergence_plot_ui(ui, &self.history, view.stage),
            (PlotTab::Accuracy, Some(s)) => plots::accuracy_ui(ui, s, view.indicator, view.split),
            (PlotTab::Summary, Some(s)) => plots::accuracy_summary_ui(ui, s, view.split),
            (PlotTab::Accuracy | PlotTab::Summary, None) => {
                ui.label("No dataset.");
            }
        }
    }

    fn table_panel_ui(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.horizontal(|ui| {
            ui.heading("Configurations");
            if ui
                .button("Select worst")
                .on_hover_text("Select the configuration with the largest |Δd|")
                .clicked()
            {
                commands.push(Command::SelectWorst);
            }
        });
        let Some(session) = &self.session else {
            ui.label("No dataset.");
            return;
        };
        match session.after() {
            Some(After::Live(live)) => ui.label(
                RichText::new(format!(
                    "errors of the current iterate ({}, live)",
                    live.label()
                ))
                .small()
                .color(plots::LIVE_COLOR),
            ),
            Some(After::Calibrated(_)) => ui.label(
                RichText::new("errors of the calibrated model")
                    .small()
                    .color(Color32::GRAY),
            ),
            None => ui.label(
                RichText::new("errors of the nominal model")
                    .small()
                    .color(Color32::GRAY),
            ),
        };
        if let Some(config) = self.selection
            && let Some(row) = session::config_row(session.current(), config)
        {
            let e = row.point_errors_mm();
            ui.horizontal_wrapped(|ui| {
                ui.label(format!(
                    "selected: {} ({} arm, {}), point errors a/b/c = {:.3} / {:.3} / {:.3} mm",
                    row.id,
                    config.side,
                    row.split.name(),
                    e[0],
                    e[1],
                    e[2]
                ));
                let text = if row.excluded {
                    "Include (X)"
                } else {
                    "Exclude (X)"
                };
                if ui
                    .small_button(text)
                    .on_hover_text("Leave the selected configuration out (or take it back in) and calibrate again at once; X does the same, in the table or the 3D view")
                    .clicked()
                {
                    commands.push(Command::ToggleExclude(config));
                }
            });
        }
        self.quality_ui(ui, session, commands);
        let flags = session.current_screening().by_config();
        let clicked = table::config_table_ui(
            ui,
            session.current(),
            &flags,
            &mut self.table,
            self.selection,
            std::mem::take(&mut self.scroll_table_to_selection),
        );
        match clicked {
            Some(table::TableAction::Select(config)) => commands.push(Command::Select {
                config: Some(config),
                reveal_in_table: false,
            }),
            Some(table::TableAction::ToggleExclude(config)) => {
                commands.push(Command::ToggleExclude(config));
            }
            None => {}
        }
    }

    /// The screening's summary above the table: how many configurations are flagged and excluded,
    /// Auto-exclude and what it removed, the whole-file findings.
    fn quality_ui(
        &self,
        ui: &mut egui::Ui,
        session: &session::Session,
        commands: &mut Vec<Command>,
    ) {
        let screening = session.current_screening();
        let suspects = screening.suspects();
        let flagged_used = suspects
            .iter()
            .filter(|c| !session.exclude.contains(c))
            .count();
        ui.horizontal_wrapped(|ui| {
            let which = if session.calibrated.is_some() {
                "calibrated"
            } else {
                "nominal"
            };
            ui.label(
                RichText::new(format!(
                    "{} flagged ({which} model), {} excluded",
                    suspects.len(),
                    session.exclude.len()
                ))
                .color(if flagged_used > 0 {
                    crate::app::colormap::flag_color32(1.0)
                } else {
                    Color32::GRAY
                }),
            )
            .on_hover_text(
                "The screening of dualcal calibrate: each configuration's reflector triangle against \
                 the arm's rigid triangle, and its distances to the others under the model \
                 (docs/reliability.md). Untick a row's box, or select it and press X, to leave it out.",
            );
            if ui
                .add_enabled(
                    !self.is_loading(),
                    egui::Button::new("Auto-exclude"),
                )
                .on_hover_text(
                    "dualcal calibrate --auto-exclude: screen, leave the flagged configurations out, \
                     fit, screen again (at most 3 fits, at most 10% of an arm); lists what it removed",
                )
                .clicked()
            {
                commands.push(Command::AutoExclude);
            }
            if !session.exclude.is_empty()
                && ui
                    .button("Use all")
                    .on_hover_text("Take every excluded configuration back in and calibrate again")
                    .clicked()
            {
                commands.push(Command::ClearExclusions);
            }
        });
        if let Some(auto) = &session.auto_exclusion {
            let title = format!(
                "Auto-exclude removed {} configuration{} ({} fit{})",
                auto.excluded.len(),
                if auto.excluded.len() == 1 { "" } else { "s" },
                auto.rounds,
                if auto.rounds == 1 { "" } else { "s" }
            );
            egui::CollapsingHeader::new(title)
                .id_salt("auto-exclude")
                .default_open(true)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical()
                        .id_salt("auto-exclude list")
                        .max_height(90.0)
                        .show(ui, |ui| {
                            for f in &auto.excluded {
                                ui.label(
                                    RichText::new(format!(
                                        "{} {}: {} {:.2} mm — {}",
                                        f.config.side.name(),
                                        f.id,
                                        f.kind.label(),
                                        f.size_mm,
                                        f.reason
                                    ))
                                    .small(),
                                );
                            }
                            if let Some(why) = &auto.stopped {
                                ui.label(RichText::new(why).small().color(WARNING_COLOR));
                            }
                        });
                });
        }
        for f in &screening.findings {
            let color = match f.severity {
                crate::quality::Severity::Error => ERROR_COLOR,
                crate::quality::Severity::Warning => WARNING_COLOR,
            };
            ui.label(RichText::new(f.message.as_str()).small().color(color));
        }
    }

    fn status_bar_ui(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        for (k, e) in self.errors.iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.small_button("×").on_hover_text("Dismiss").clicked() {
                    commands.push(Command::DismissError(k));
                }
                ui.label(RichText::new(e).color(ERROR_COLOR));
            });
        }
        ui.horizontal(|ui| {
            match &self.status {
                Status::Idle(text) => {
                    if self.is_loading() {
                        ui.spinner();
                    }
                    ui.label(text);
                }
                Status::Running { stage, iteration } => {
                    ui.spinner();
                    let task = self.jobs.task(CalibrationJob::lane());
                    let elapsed = task.map_or(0.0, |t| t.elapsed_secs());
                    let cancelling = task.is_some_and(|t| t.is_cancelling());
                    ui.label(match stage {
                        Some(stage) => format!(
                            "Calibrating: {stage}, iteration {iteration} ({elapsed:.1} s){}",
                            if cancelling { " — cancelling…" } else { "" }
                        ),
                        None => "Calibrating: starting…".into(),
                    });
                    if let Some(live) = self.session.as_ref().and_then(|s| s.live.as_ref()) {
                        ui.label(
                            RichText::new(format!(
                                "· figures of {} (evaluated in {:.0} ms)",
                                live.label(),
                                live.evaluation_secs * 1e3
                            ))
                            .color(plots::LIVE_COLOR),
                        );
                    }
                }
            }
            if let Some(session) = &self.session {
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                    ui.label(
                        RichText::new(format!(
                            "registration RMS {:.3} mm",
                            session.current().registration_rms_mm
                        ))
                        .color(Color32::GRAY),
                    )
                    .on_hover_text(
                        "RMS residual of the best-fit tracker-to-robot transform used to draw the measured points",
                    );
                });
            }
        });
    }
}

/// One row of a two-column grid: a label (with a tooltip) and the widget `add` puts beside it,
/// labelled by it for screen readers and tests.
fn grid_row_ui(
    ui: &mut egui::Ui,
    label: &str,
    hover: &str,
    add: impl FnOnce(&mut egui::Ui) -> egui::Response,
) {
    let label = ui.label(label).on_hover_text(hover);
    add(ui).labelled_by(label.id);
    ui.end_row();
}

/// A combo box choosing `value` among `choices` (value, name).
fn choice_ui<T: PartialEq + Copy>(
    ui: &mut egui::Ui,
    id: &str,
    value: &mut T,
    choices: &[(T, &str)],
) -> egui::Response {
    let selected = choices
        .iter()
        .find(|(v, _)| v == value)
        .map_or("", |(_, name)| name);
    egui::ComboBox::from_id_salt(id)
        .selected_text(selected)
        .show_ui(ui, |ui| {
            for &(v, name) in choices {
                ui.selectable_value(value, v, name);
            }
        })
        .response
}
