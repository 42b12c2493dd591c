//! The planning view's window: where the tracker stands and what the planner may choose from, then
//! per arm the chosen configurations in visiting order (one of them drawn in 3D with the tracker and
//! the lines of sight), the design's information against a random set's, the path with its via
//! points, the predicted σ, and "Save plan (.zip)…" — the files `dualcal plan` writes. State:
//! [`crate::app::plan_view`].

use super::{ERROR_COLOR, WARNING_COLOR};
use crate::app::command::Command;
use crate::app::plan_view::{ArmOutcome, PlanInputs, PlanView};
use crate::plan::{ArmPlan, PlanOptions};
use crate::side::Side;
use eframe::egui::{self, Color32, RichText};
use egui_plot::{HLine, Line, Plot, PlotPoints};

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
            ui.add_enabled(
                i.target.is_none(),
                egui::DragValue::new(&mut i.per_arm).range(2..=500),
            );
            ui.end_row();
            ui.label("target accuracy");
            ui.horizontal(|ui| {
                let mut on = i.target.is_some();
                if ui
                    .checkbox(&mut on, "fewest configurations reaching")
                    .on_hover_text(
                        "The smallest number of configurations per arm whose predicted accuracy \
                         over the region (the default method's mean, × the noise floor) reaches \
                         the target, and the curve N → predicted accuracy (dualcal plan --target)",
                    )
                    .changed()
                {
                    i.target = on.then_some(i.target.unwrap_or(1.1));
                }
                if let Some(t) = &mut i.target {
                    ui.add(
                        egui::DragValue::new(t)
                            .range(1.01..=3.0)
                            .speed(0.005)
                            .fixed_decimals(3)
                            .suffix("×"),
                    );
                }
            });
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
        arm_ui(ui, side, arm, &result.options, view.shown[side], commands);
    }
}

fn arm_ui(
    ui: &mut egui::Ui,
    side: Side,
    arm: &ArmOutcome,
    options: &PlanOptions,
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
    }
    if let Some(line) = crate::plan::bound_line(p) {
        ui.label(line);
    }
    prediction_ui(ui, side, options, p);
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

/// What the design predicts over the region (× the noise floor, over draws of the robot's errors and
/// the noise: mean and 10–90 %), as `dualcal plan` prints it; with a target, whether it is reached and
/// the curve N → predicted accuracy of the designs tried.
fn prediction_ui(ui: &mut egui::Ui, side: Side, options: &PlanOptions, p: &ArmPlan) {
    let region = options.region.describe(p.region_count);
    match &p.prediction {
        Some(pred) => ui.label(format!(
            "predicted over the region ({region}; {} draws of the robot's errors and the noise, \
             10–90 %; 1.000× = the true parameters): {}",
            pred.draws,
            pred.summary()
        )),
        None => ui.label(
            RichText::new(format!(
                "predicted over the region ({region}): not predictable (singular fit)"
            ))
            .color(WARNING_COLOR),
        ),
    };
    let Some(target) = options.target else {
        return;
    };
    let n = p.configs.len();
    if p.prediction
        .as_ref()
        .is_some_and(|q| q.default_method.mean <= target)
    {
        ui.label(format!(
            "target {target:.3}×: {n} configurations reach it (the default method's mean)"
        ));
    } else {
        ui.label(
            RichText::new(format!(
                "target {target:.3}×: not reached with up to {n} configurations"
            ))
            .color(WARNING_COLOR),
        );
    }
    curve_plot(ui, side, target, &p.curve);
}

/// The curve N → predicted accuracy of the designs the target search tried: the default method's
/// mean with its 10–90 % band, the position fit's mean, and the target.
fn curve_plot(
    ui: &mut egui::Ui,
    side: Side,
    target: f64,
    curve: &[(usize, Option<crate::plan::region::RegionPrediction>)],
) {
    let points = |f: &dyn Fn(&crate::plan::region::RegionPrediction) -> f64| -> Vec<[f64; 2]> {
        curve
            .iter()
            .filter_map(|(n, p)| p.as_ref().map(|p| [*n as f64, f(p)]))
            .collect()
    };
    let mean = points(&|p| p.default_method.mean);
    if mean.len() < 2 {
        return;
    }
    let lo = points(&|p| p.default_method.lo);
    let hi = points(&|p| p.default_method.hi);
    let position = points(&|p| p.position.mean);
    // From the noise floor to three times the target's distance from it: the smallest designs
    // predict many times the floor and would flatten the rest (they are named below the plot).
    let top = 1.0 + 3.0 * (target - 1.0);
    let default_color = Color32::from_rgb(90, 160, 255);
    let position_color = Color32::from_rgb(230, 150, 60);
    // The key in words above the plot: a legend would cover a plot this small.
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 0.0;
        let key = |ui: &mut egui::Ui, text: &str, color: Color32| {
            ui.label(RichText::new(text).small().color(color));
        };
        key(ui, "predicted accuracy against N: ", Color32::GRAY);
        key(ui, "default method (mean, dashed 10–90 %)", default_color);
        key(ui, ", ", Color32::GRAY);
        key(ui, "by positions (mean)", position_color);
        key(ui, ", target (grey)", Color32::GRAY);
    });
    Plot::new(format!("plan curve {side}"))
        .height(150.0)
        .default_y_bounds(1.0, top)
        .x_axis_label("configurations per arm")
        .y_axis_label("× floor")
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .show(ui, |plot| {
            plot.line(
                Line::new("default method (mean)", PlotPoints::from(mean))
                    .color(default_color)
                    .width(2.0),
            );
            for band in [lo, hi] {
                plot.line(
                    Line::new("default method (10–90 %)", PlotPoints::from(band))
                        .color(default_color.gamma_multiply(0.5))
                        .style(egui_plot::LineStyle::dashed_dense()),
                );
            }
            plot.line(
                Line::new("by positions (mean)", PlotPoints::from(position)).color(position_color),
            );
            plot.hline(HLine::new("target", target).color(Color32::GRAY));
        });
    let above: Vec<String> = curve
        .iter()
        .filter_map(|(n, p)| {
            p.as_ref()
                .filter(|p| p.default_method.mean > top)
                .map(|p| format!("N = {n}: {:.2}×", p.default_method.mean))
        })
        .collect();
    if !above.is_empty() {
        ui.label(
            RichText::new(format!("above the plot: {}", above.join(", ")))
                .small()
                .color(Color32::GRAY),
        );
    }
}
