//! The configurations panel (right): the selected configuration, the screening's summary with
//! Auto-exclude, and the per-configuration table.

use super::{ERROR_COLOR, WARNING_COLOR};
use crate::app::command::Command;
use crate::app::session::{self, After, Session};
use crate::app::{plots, table};
use crate::side::ConfigId;
use eframe::egui::{self, Color32, RichText};

/// The configurations panel and the state it shows: it scrolls and sorts its table in place and
/// pushes a [`Command`] for a selection or an exclusion.
pub struct TablePanel<'a> {
    pub session: Option<&'a Session>,
    pub selection: Option<ConfigId>,
    pub table: &'a mut table::TableState,
    /// Scroll the table to the selection (once: taken when the table is drawn).
    pub reveal_selection: &'a mut bool,
    pub loading: bool,
}

impl TablePanel<'_> {
    pub fn ui(self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
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
        let Some(session) = self.session else {
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
            let names = session.dataset.reflector_names.join("/");
            let errors = e
                .iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join(" / ");
            ui.horizontal_wrapped(|ui| {
                ui.label(format!(
                    "selected: {} ({} arm, {}), point errors {names} = {errors} mm",
                    row.id,
                    config.side,
                    row.split.name(),
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
            self.table,
            self.selection,
            std::mem::take(self.reveal_selection),
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
    fn quality_ui(&self, ui: &mut egui::Ui, session: &Session, commands: &mut Vec<Command>) {
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
                    !self.loading,
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
}
