//! The panels around the viewport: the left panel (dataset, robot, settings, export and the view
//! options: [`settings`], [`view_options`]), the plots ([`PlotsView`]), the configurations
//! ([`configurations`]), the status bar ([`status_bar`]), the comparison view ([`compare`]) and the
//! import and planning windows ([`import`], [`plan`]).
//!
//! A panel is given the state it shows, borrowed: what it only reads by shared reference, what it
//! edits in place (view state: the calibration settings, the display options, plot tabs, the table's
//! sort) by `&mut`, and a `&mut Vec<Command>` for every other change, which
//! [`WorkbenchApp::apply`](super::WorkbenchApp::apply) carries out after the frame's UI is built. No
//! panel sees the app itself; [`super::WorkbenchApp`]'s `ui` lays them out, handing each its state.

mod compare;
mod configurations;
mod import;
mod plan;
mod settings;
mod status_bar;
mod view_options;

pub use compare::{CompareState, compare_ui};
pub use configurations::TablePanel;
pub use import::{ImportContext, import_ui};
pub use plan::{PlanContext, plan_ui};
pub use settings::LeftPanel;
pub use status_bar::StatusBar;

use super::plots;
use super::session::Session;
use crate::analysis::Indicator;
use crate::dataset::Split;
use crate::side::Side;
use crate::solver::{IterationRecord, Stage};
use eframe::egui::{self, Color32};

/// Colour of error messages.
const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 100);
/// Colour of warnings (the robot's).
const WARNING_COLOR: Color32 = Color32::from_rgb(235, 180, 90);

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

impl PlotsView {
    /// The plot area: its tabs and the plot of the one chosen, of the `session` shown and the
    /// convergence `history` shown.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        session: Option<&Session>,
        history: &[IterationRecord],
    ) {
        let view = self;
        ui.horizontal_wrapped(|ui| {
            ui.selectable_value(&mut view.tab, PlotTab::Convergence, "Convergence");
            ui.selectable_value(&mut view.tab, PlotTab::Accuracy, "Accuracy");
            ui.selectable_value(&mut view.tab, PlotTab::Summary, "Summary");
            ui.separator();
            if view.tab == PlotTab::Convergence {
                // The stages this dataset calls for (arms that share joints in one stage, one
                // arm measured alone, no base where it is not measurable).
                let planned =
                    session.map(|s| crate::solver::planned_stages(&s.dataset, &s.nominal.model));
                let stages: &[Stage] = planned.as_deref().unwrap_or(&plots::STAGES);
                if !stages.contains(&view.stage) {
                    view.stage = stages[0];
                }
                for &stage in stages {
                    ui.selectable_value(&mut view.stage, stage, stage.to_string());
                }
                return;
            }
            if view.tab == PlotTab::Accuracy {
                indicator_choice_ui(ui, "Figure:", "figure", &mut view.indicator);
            }
            ui.selectable_value(&mut view.split, Split::Cal, "cal split");
            ui.selectable_value(&mut view.split, Split::Ver, "ver split");
        });
        view.rect = Some(ui.available_rect_before_wrap());
        match (view.tab, session) {
            (PlotTab::Convergence, _) => plots::convergence_plot_ui(ui, history, view.stage),
            (PlotTab::Accuracy, Some(s)) => plots::accuracy_ui(ui, s, view.indicator, view.split),
            (PlotTab::Summary, Some(s)) => plots::accuracy_summary_ui(ui, s, view.split),
            (PlotTab::Accuracy | PlotTab::Summary, None) => {
                ui.label("No dataset.");
            }
        }
    }
}

/// A labelled combo box choosing an accuracy indicator.
fn indicator_choice_ui(ui: &mut egui::Ui, label: &str, id: &str, indicator: &mut Indicator) {
    let label = ui.label(label);
    egui::ComboBox::from_id_salt(id)
        .selected_text(indicator.label())
        .width(230.0)
        .show_ui(ui, |ui| {
            for f in Indicator::ALL {
                ui.selectable_value(indicator, f, f.label());
            }
        })
        .response
        .labelled_by(label.id);
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
