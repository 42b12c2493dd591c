//! The planning view's window: where the tracker stands and what the planner may choose from, then
//! per arm the chosen configurations in visiting order (one of them drawn in 3D with the tracker and
//! the lines of sight), the design's information against a random set's, the path with its via
//! points, the predicted σ, and "Save plan (.zip)…" — the files `dualcal plan` writes. State:
//! [`crate::app::plan_view`].

use super::{ERROR_COLOR, WARNING_COLOR};
use crate::app::command::Command;
use crate::app::plan_view::{ArmOutcome, PlanInputs, PlanView};
use crate::side::Side;
use eframe::egui::{self, Color32, RichText};

/// What the window needs besides the view.
pub struct PlanContext {
    /// A plan is being made.
    pub planning: bool,
    /// A dataset is loaded (its configurations can be extended).
    pub has_dataset: bool,
    /// What the plan is for: the robot's name and the reflectors.
    pub robot: String,
}

pub fn plan_ui(
    ctx: &egui::Context,
    view: &mut PlanView,
    state: PlanContext,
    commands: &mut Vec<Command>,
) {
    let mut open = view.open;
    egui::Window::new("Plan measurements")
        .open(&mut open)
        // Over the left panel and the plots (idle while planning), leaving the 3D view — where the
        // plan is drawn — in sight.
        .default_pos([8.0, ctx.content_rect().height() * 0.38])
        .default_width(470.0)
        .max_height(ctx.content_rect().height() * 0.58)
        .vscroll(true)
        .show(ctx, |ui| {
            ui.label(
                RichText::new(format!(
                    "For {}. Candidates are collision-free, their reflectors face the tracker and \
                     are seen from it; the planner picks the most informative (docs/planning.md).",
                    state.robot
                ))
                .small()
                .color(Color32::GRAY),
            );
            inputs_ui(ui, &mut view.inputs, state.has_dataset);
            ui.horizontal(|ui| {
                if ui
                    .add_enabled(!state.planning, egui::Button::new("Plan"))
                    .on_hover_text("Choose the configurations (dualcal plan)")
                    .clicked()
                {
                    commands.push(Command::StartPlan);
                }
                if state.planning {
                    ui.spinner();
                }
                let finished = view.result.as_ref().and_then(|r| r.plans()).is_some();
                if ui
                    .add_enabled(
                        finished && !state.planning,
                        egui::Button::new("Save plan (.zip)…"),
                    )
                    .on_hover_text(
                        "left.csv and right.csv to fill in with the measurement, the visiting \
                         sequences with their via points, dataset.toml, and for the YuMi RAPID \
                         modules of MoveAbsJ targets",
                    )
                    .clicked()
                {
                    commands.push(Command::SavePlan);
                }
            });
            if let Some(e) = &view.error {
                ui.label(RichText::new(e).color(ERROR_COLOR));
            }
            results_ui(ui, view, commands);
        });
    if !open {
        commands.push(Command::ShowPlan(false));
    }
}

fn inputs_ui(ui: &mut egui::Ui, i: &mut PlanInputs, has_dataset: bool) {
    egui::Grid::new("plan inputs")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("tracker (mm, root frame)");
            ui.horizontal(|ui| {
                for (v, axis) in i.tracker_mm.iter_mut().zip(["x", "y", "z"]) {
                    ui.add(
                        egui::DragValue::new(v)
                            .speed(10.0)
                            .prefix(format!("{axis} ")),
                    );
                }
            });
            ui.end_row();
            ui.label("configurations per arm");
            ui.add(egui::DragValue::new(&mut i.per_arm).range(2..=500));
            ui.end_row();
            ui.label("candidates per arm");
            ui.add(
                egui::DragValue::new(&mut i.candidates)
                    .range(2..=20_000)
                    .speed(10.0),
            );
            ui.end_row();
            ui.label("seed");
            ui.add(egui::DragValue::new(&mut i.seed));
            ui.end_row();
            ui.label("largest incidence");
            ui.add(
                egui::DragValue::new(&mut i.max_incidence_deg)
                    .range(1.0..=90.0)
                    .suffix("°"),
            );
            ui.end_row();
            ui.label("tracker range");
            ui.add(
                egui::DragValue::new(&mut i.max_range_m)
                    .range(0.1..=100.0)
                    .speed(0.1)
                    .suffix(" m"),
            );
            ui.end_row();
            ui.label("joint-limit margin");
            ui.add(
                egui::DragValue::new(&mut i.joint_margin)
                    .range(0.0..=0.4)
                    .speed(0.005)
                    .fixed_decimals(3),
            )
            .on_hover_text("The fraction of each joint's range kept clear at both ends");
            ui.end_row();
            ui.label("clearance");
            ui.add(
                egui::DragValue::new(&mut i.clearance_mm)
                    .range(0.0..=200.0)
                    .suffix(" mm"),
            );
            ui.end_row();
            ui.label("keep-out boxes");
            ui.add(
                egui::TextEdit::multiline(&mut i.keep_out)
                    .hint_text("X0,Y0,Z0,X1,Y1,Z1 (mm) per line")
                    .desired_rows(2)
                    .desired_width(280.0),
            );
            ui.end_row();
            if has_dataset {
                ui.label("extend");
                ui.checkbox(&mut i.extend, "add to the loaded dataset's configurations");
                ui.end_row();
            }
        });
}

fn results_ui(ui: &mut egui::Ui, view: &mut PlanView, commands: &mut Vec<Command>) {
    let Some(result) = &view.result else {
        return;
    };
    for side in Side::BOTH {
        ui.separator();
        let Some(arm) = &result.arms[side] else {
            ui.label(format!("{side} arm: planning…"));
            continue;
        };
        arm_ui(ui, side, arm, view.shown[side], commands);
    }
}

fn arm_ui(
    ui: &mut egui::Ui,
    side: Side,
    arm: &ArmOutcome,
    shown: Option<usize>,
    commands: &mut Vec<Command>,
) {
    let p = &arm.plan;
    ui.label(RichText::new(format!("{side} arm")).strong());
    ui.label(format!(
        "{} configurations from {} candidates ({} draws); log det {:.1} (a random set {:.1}); \
         I-criterion {:.4} after {} exchange swap(s) (greedy {:.4}); path {:.2} rad",
        p.configs.len(),
        p.candidates,
        p.attempts,
        p.log_det,
        p.log_det_random,
        p.criterion,
        p.swaps,
        p.criterion_greedy,
        p.path_length
    ));
    if !p.vias.is_empty() {
        ui.label(format!(
            "{} leg(s) re-routed through a via point (after {})",
            p.vias.len(),
            p.vias
                .iter()
                .map(|v| (v.leg + 1).to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !p.colliding_legs.is_empty() {
        ui.label(
            RichText::new(format!(
                "the straight motion of legs {:?} collides and no via point clears it",
                p.colliding_legs.iter().map(|k| k + 1).collect::<Vec<_>>()
            ))
            .color(WARNING_COLOR),
        );
    }
    if let Some(d) = &arm.sigma {
        let u = &d.uncertainty;
        let largest = |unit: &str| {
            u.largest(unit).map_or(String::new(), |s| {
                format!("{:.4} {unit} ({})", s.sigma, s.name)
            })
        };
        ui.label(format!(
            "predicted 1σ with {:.4} mm of tracker noise: largest {}, {}; condition {:.1}",
            d.point_sigma_mm,
            largest("mm"),
            largest("mrad"),
            u.condition
        ));
        if let Some(ratio) = d.verification_ratio {
            ui.label(format!(
                "predicted verification accuracy: {ratio:.3}× the noise floor (least squares; \
                 the true parameters give 1.000×)"
            ));
        }
    }
    if let Some(line) = crate::plan::bound_line(p) {
        ui.label(line);
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("show:");
        if ui.selectable_label(shown.is_none(), "home").clicked() {
            commands.push(Command::ShowPlannedPose(side, None));
        }
        let prefix = crate::plan::id_prefix(side, false);
        for k in 0..p.configs.len() {
            let name = format!("{prefix}{:03}", k + 1);
            if ui.selectable_label(shown == Some(k), name).clicked() {
                commands.push(Command::ShowPlannedPose(side, Some(k)));
            }
        }
    });
}
