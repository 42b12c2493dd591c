//! The status bar: the errors (each dismissable), what the workbench is doing, the registration RMS.

use super::ERROR_COLOR;
use crate::app::command::Command;
use crate::app::plots;
use crate::app::session::Session;
use crate::app::status::Status;
use crate::app::task::BackgroundTask;
use eframe::egui::{self, Color32, RichText};

/// The status bar and the state it shows.
pub struct StatusBar<'a> {
    pub errors: &'a [String],
    pub status: &'a Status,
    pub loading: bool,
    /// The running calibration's task (its time, whether it is being cancelled).
    pub calibration: Option<&'a BackgroundTask>,
    pub session: Option<&'a Session>,
}

impl StatusBar<'_> {
    pub fn ui(self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        for (k, e) in self.errors.iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.small_button("×").on_hover_text("Dismiss").clicked() {
                    commands.push(Command::DismissError(k));
                }
                ui.add(egui::Label::new(RichText::new(e).color(ERROR_COLOR)).wrap());
            });
        }
        // One line whatever it says: the registration RMS at the right, then what the workbench is
        // doing in the width left, elided (the whole on hover); nothing moves when a message
        // grows, nor when a run ends.
        ui.horizontal(|ui| {
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                if let Some(session) = self.session {
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
                }
                ui.with_layout(egui::Layout::left_to_right(egui::Align::Center), |ui| {
                    self.status_ui(ui);
                });
            });
        });
    }

    /// What the workbench is doing, in one line.
    fn status_ui(&self, ui: &mut egui::Ui) {
        let elided = |ui: &mut egui::Ui, text: RichText| {
            ui.add(egui::Label::new(text).truncate());
        };
        match self.status {
            Status::Idle(text) => {
                if self.loading {
                    ui.spinner();
                }
                elided(ui, RichText::new(text));
            }
            Status::Running { stage, iteration } => {
                ui.spinner();
                let task = self.calibration;
                let elapsed = task.map_or(0.0, |t| t.elapsed_secs());
                let cancelling = task.is_some_and(|t| t.is_cancelling());
                elided(
                    ui,
                    RichText::new(match stage {
                        Some(stage) => format!(
                            "Calibrating: {stage}, iteration {iteration} ({elapsed:.1} s){}",
                            if cancelling { " — cancelling…" } else { "" }
                        ),
                        None => "Calibrating: starting…".into(),
                    }),
                );
                if let Some(live) = self.session.and_then(|s| s.live.as_ref()) {
                    elided(
                        ui,
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
    }
}
