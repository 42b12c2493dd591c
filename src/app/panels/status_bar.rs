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
                ui.label(RichText::new(e).color(ERROR_COLOR));
            });
        }
        ui.horizontal(|ui| {
            match self.status {
                Status::Idle(text) => {
                    if self.loading {
                        ui.spinner();
                    }
                    ui.label(text);
                }
                Status::Running { stage, iteration } => {
                    ui.spinner();
                    let task = self.calibration;
                    let elapsed = task.map_or(0.0, |t| t.elapsed_secs());
                    let cancelling = task.is_some_and(|t| t.is_cancelling());
                    ui.label(match stage {
                        Some(stage) => format!(
                            "Calibrating: {stage}, iteration {iteration} ({elapsed:.1} s){}",
                            if cancelling { " — cancelling…" } else { "" }
                        ),
                        None => "Calibrating: starting…".into(),
                    });
                    if let Some(live) = self.session.and_then(|s| s.live.as_ref()) {
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
            if let Some(session) = self.session {
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
