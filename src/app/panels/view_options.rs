//! The "View" section of the left panel: what the viewport draws, which model, how errors are
//! scaled, the pose each arm is drawn in.

use crate::app::command::Command;
use crate::app::session::Session;
use crate::app::viewport::ViewportState;
use crate::app::viewport::scene::{MeshDetail, SceneOptions};
use crate::side::{PerSide, Side};
use eframe::egui::{self, Color32, RichText};

/// The view options of `view` (edited in place) for the `session` shown.
pub(super) fn view_options_ui(
    ui: &mut egui::Ui,
    session: Option<&Session>,
    view: &mut ViewportState,
    commands: &mut Vec<Command>,
) {
    ui.heading("View");
    let has_cal = session.is_some_and(|s| s.after().is_some());
    layers_ui(ui, &mut view.options);
    model_choice_ui(ui, &mut view.options, has_cal);
    mesh_detail_ui(ui, &mut view.options, view.software_renderer);
    ui.checkbox(&mut view.auto_scale, "auto scale")
            .on_hover_text("Set the vector exaggeration and colour range from the current errors whenever a model is loaded or calibrated");
    error_scale_ui(ui, &mut view.options);
    if let Some(session) = session {
        arm_poses_ui(ui, session, &mut view.poses);
    }
    ui.horizontal(|ui| {
        if ui
            .button("Reset view")
            .on_hover_text("Also: double-click the viewport")
            .clicked()
        {
            view.camera = view.home_camera;
        }
        if ui
            .button("Select worst")
            .on_hover_text("Select the configuration with the largest |Δd| of the current model")
            .clicked()
        {
            commands.push(Command::SelectWorst);
        }
    });
    ui.label(
        RichText::new(
            "drag: orbit · right/middle or shift-drag: pan · wheel: zoom · click: select",
        )
        .small()
        .color(Color32::GRAY),
    );
}

/// What is drawn: robot, grid, reflector triangles, error vectors; which splits and arms.
fn layers_ui(ui: &mut egui::Ui, o: &mut SceneOptions) {
    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut o.show_robot, "robot");
        ui.checkbox(&mut o.show_grid, "grid");
        ui.checkbox(&mut o.show_measured, "measured")
            .on_hover_text("Measured reflector triangles (tracker points registered to the robot), coloured by error");
        ui.checkbox(&mut o.show_model, "model")
            .on_hover_text("Model reflector triangles (forward kinematics)");
        ui.checkbox(&mut o.show_vectors, "error vectors")
            .on_hover_text("From each model point towards the measured one, exaggerated");
        ui.checkbox(&mut o.show_flags, "flags").on_hover_text(
            "Configurations the screening flags in magenta to red by severity (size over threshold), outlined",
        );
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut o.show_cal, "cal");
        ui.checkbox(&mut o.show_ver, "ver");
        for side in Side::BOTH {
            ui.checkbox(&mut o.show_arm[side], side.name());
        }
    });
}

/// Nominal or calibrated. What is drawn: the calibrated model only once one exists (the preference
/// is kept, so a finished calibration switches the view to it).
fn model_choice_ui(ui: &mut egui::Ui, o: &mut SceneOptions, has_cal: bool) {
    ui.horizontal(|ui| {
        ui.label("Model:");
        let showing_calibrated = o.use_calibrated && has_cal;
        if ui
            .selectable_label(!showing_calibrated, "nominal")
            .clicked()
        {
            o.use_calibrated = false;
        }
        ui.add_enabled_ui(has_cal, |ui| {
            if ui
                .selectable_label(showing_calibrated, "calibrated")
                .on_hover_text(
                    "The last calibration; while one runs, the model it has reached (live)",
                )
                .on_disabled_hover_text("Calibrate first")
                .clicked()
            {
                o.use_calibrated = true;
            }
        });
    });
}

/// Which copy of the robot's meshes is drawn: auto (simplified on a software renderer), full or
/// simplified.
fn mesh_detail_ui(ui: &mut egui::Ui, o: &mut SceneOptions, software_renderer: bool) {
    ui.horizontal(|ui| {
        ui.label("Meshes:");
        for detail in MeshDetail::ALL {
            let hover = match detail {
                MeshDetail::Auto if software_renderer => {
                    "Simplified: this adapter renders on the CPU"
                }
                MeshDetail::Auto => "Full: this adapter is a GPU (simplified on a software renderer)",
                MeshDetail::Full => "The robot's meshes as loaded",
                MeshDetail::Simplified => {
                    "A simplified copy of each mesh (about 20 000 triangles per robot; not in the browser build); collision checks and exports keep the full meshes"
                }
            };
            ui.selectable_value(&mut o.mesh_detail, detail, detail.label())
                .on_hover_text(hover);
        }
    });
}

/// Error-vector exaggeration and the top of the colour bar.
fn error_scale_ui(ui: &mut egui::Ui, o: &mut SceneOptions) {
    ui.add(
        egui::Slider::new(&mut o.exaggeration, 1.0..=5000.0)
            .logarithmic(true)
            .text("× vectors"),
    )
    .on_hover_text("Error vectors are drawn this many times their true length");
    ui.add(
        egui::Slider::new(&mut o.color_max_mm, 0.005..=50.0)
            .logarithmic(true)
            .text("mm colour max"),
    )
    .on_hover_text("Error at the top of the colour bar, mm");
}

/// The pose each arm is drawn in: a configuration (follows the selection) or home.
fn arm_poses_ui(ui: &mut egui::Ui, session: &Session, poses: &mut PerSide<Option<usize>>) {
    for side in Side::BOTH {
        let measurements = &session.dataset.arm(side).measurements;
        if measurements.is_empty() {
            continue;
        }
        let pose = &mut poses[side];
        ui.horizontal(|ui| {
            let label = ui.label(format!("{side} arm pose:"));
            let mut index = pose.unwrap_or(0);
            let r = ui
                .add(
                    egui::DragValue::new(&mut index)
                        .range(0..=measurements.len() - 1)
                        .custom_formatter(|v, _| {
                            measurements
                                .get(v as usize)
                                .map_or_else(String::new, |m| m.id.clone())
                        })
                        .custom_parser(|t| {
                            measurements
                                .iter()
                                .position(|m| m.id == t.trim())
                                .map(|i| i as f64)
                        }),
                )
                .labelled_by(label.id)
                .on_hover_text(
                    "Drag or type a configuration id; selecting a configuration also poses its arm",
                );
            if r.changed() {
                *pose = Some(index);
            }
            if ui
                .selectable_label(pose.is_none(), "home")
                .on_hover_text("ABB's synchronisation pose")
                .clicked()
            {
                *pose = None;
            }
        });
    }
}
