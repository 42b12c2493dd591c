//! The import view's window: each arm's tracker export and joint log, the options of `dualcal
//! import`, the live preview (what matched, what did not and why, or the error with its file and
//! line) and the button that writes the dataset and opens it. State: [`crate::app::import`].

use super::{ERROR_COLOR, WARNING_COLOR};
use crate::app::command::{Command, ImportSlot, OpenKind};
use crate::app::import::{ImportInputs, ImportView, Preview};
use crate::dataset::{AngleUnit, LengthUnit};
use crate::import::{ArmReport, MatchRule, PointUnit, PointsFormat};
use crate::side::Side;
use eframe::egui::{self, Color32, RichText};

/// What the window needs besides the view.
pub struct ImportContext {
    /// File dialogs (or a browser's picker) are available: "Browse…" buttons.
    pub dialogs: bool,
    /// The dataset is kept in memory (a browser), not written to a folder.
    pub in_memory: bool,
    /// A load is running: finishing waits.
    pub loading: bool,
}

/// The import window, while the view is open.
pub fn import_ui(
    ctx: &egui::Context,
    view: &mut ImportView,
    state: ImportContext,
    commands: &mut Vec<Command>,
) {
    let mut open = view.open;
    egui::Window::new("Import tracker files")
        .open(&mut open)
        .default_width(560.0)
        .default_height(ctx.content_rect().height() * 0.7)
        .max_height(ctx.content_rect().height() * 0.9)
        .vscroll(true)
        .show(ctx, |ui| {
            files_ui(ui, &mut view.inputs, &state, commands);
            egui::CollapsingHeader::new("Options")
                .default_open(false)
                .show(ui, |ui| options_ui(ui, &mut view.inputs));
            egui::CollapsingHeader::new("Both arms in one file")
                .default_open(false)
                .show(ui, |ui| one_file_options_ui(ui, &mut view.inputs));
            ui.separator();
            preview_ui(ui, view.preview(), commands);
            ui.separator();
            finish_ui(ui, view, &state, commands);
            report_ui(ui, view.preview());
        });
    if !open {
        commands.push(Command::ShowImport(false));
    }
}

fn files_ui(
    ui: &mut egui::Ui,
    inputs: &mut ImportInputs,
    state: &ImportContext,
    commands: &mut Vec<Command>,
) {
    ui.label(
        RichText::new(
            "Each arm's point file (SpatialAnalyzer, Leica Tracker Pilot, figaroh, or any CSV with a \
             column mapping) and its joint log (id,q1..qN as CSV, a spreadsheet or a ROS 2 bag; not needed when \
             the point file has the joints); one arm's files alone make a dataset of that arm. \
             docs/formats.md describes each format.",
        )
        .small()
        .color(Color32::GRAY),
    );
    egui::Grid::new("import files")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            for side in Side::BOTH {
                for joints in [false, true] {
                    let slot = ImportSlot { side, joints };
                    let (label, hint) = if joints {
                        (format!("{side} joints"), "joint log (optional)")
                    } else {
                        (format!("{side} points"), "tracker export")
                    };
                    // With a file picker the row's name is its button (one name per file).
                    if state.dialogs {
                        if ui
                            .button(format!("{label}…"))
                            .on_hover_text("Choose the file")
                            .clicked()
                        {
                            commands.push(Command::ChooseFile(OpenKind::ImportFile(slot)));
                        }
                    } else {
                        ui.label(label);
                    }
                    let field = if joints {
                        &mut inputs.joints[side]
                    } else {
                        &mut inputs.points[side]
                    };
                    ui.add(
                        egui::TextEdit::singleline(field)
                            .hint_text(hint)
                            .desired_width(380.0),
                    );
                    ui.end_row();
                }
            }
        });
}

fn options_ui(ui: &mut egui::Ui, inputs: &mut ImportInputs) {
    egui::Grid::new("import options")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("point format");
            combo(
                ui,
                "format",
                &mut inputs.format,
                &[
                    (None, "recognised from each file"),
                    (Some(PointsFormat::SpatialAnalyzer), "SpatialAnalyzer"),
                    (Some(PointsFormat::Leica), "Leica Tracker Pilot"),
                    (Some(PointsFormat::Figaroh), "figaroh"),
                    (Some(PointsFormat::Generic), "generic (column mapping)"),
                ],
            );
            ui.end_row();
            ui.label("column mapping");
            ui.add(
                egui::TextEdit::singleline(&mut inputs.columns)
                    .hint_text("target=1,x=2,y=3,z=4")
                    .desired_width(300.0),
            )
            .on_hover_text(
                "A generic CSV/TXT: `target=1,x=2,y=3,z=4` (a point per row) or \
                 `id=1,a.x=2,a.y=3,a.z=4,…,q=11-17` (a configuration per row); columns by 1-based \
                 number or header name; elements of numpy vector and matrix cells `COL[i]`, \
                 `COL[i][j]`, `q=COL[i-j]`; a computed joint `q4=-joints[1]-joints[2]` \
                 (docs/formats.md, \"Generic CSV/TXT\")",
            );
            ui.end_row();
            ui.label("point unit");
            combo(
                ui,
                "length",
                &mut inputs.length_unit,
                &[
                    (None, "the file's, else mm"),
                    (Some(PointUnit::Mm), "mm"),
                    (Some(PointUnit::M), "m"),
                    (Some(PointUnit::Um), "µm"),
                    (Some(PointUnit::In), "in"),
                    (Some(PointUnit::Ft), "ft"),
                ],
            );
            ui.end_row();
            ui.label("joint angles");
            combo(
                ui,
                "angle",
                &mut inputs.angle_unit,
                &[
                    (None, "the header's, else deg"),
                    (Some(AngleUnit::Deg), "deg"),
                    (Some(AngleUnit::Rad), "rad"),
                ],
            );
            ui.end_row();
            ui.label("prismatic joints");
            combo(
                ui,
                "joint length",
                &mut inputs.joint_length_unit,
                &[
                    (None, "mm"),
                    (Some(LengthUnit::Mm), "mm"),
                    (Some(LengthUnit::M), "m"),
                ],
            );
            ui.end_row();
            ui.label("joint order");
            ui.add(
                egui::TextEdit::singleline(&mut inputs.joint_order)
                    .hint_text("chain order; yumi-abb or 1,2,7,3,4,5,6")
                    .desired_width(300.0),
            );
            ui.end_row();
            ui.label("sheet");
            ui.add(
                egui::TextEdit::singleline(&mut inputs.sheet)
                    .hint_text("spreadsheet joint logs: the first sheet")
                    .desired_width(300.0),
            );
            ui.end_row();
            ui.label("decimal comma");
            ui.checkbox(&mut inputs.decimal_comma, "1234,56");
            ui.end_row();
            #[cfg(not(target_arch = "wasm32"))]
            bag_ui(ui, inputs);
            matching_ui(ui, inputs);
            for side in Side::BOTH {
                ui.label(format!("{side} station"));
                ui.add(
                    egui::TextEdit::singleline(&mut inputs.stations[side])
                        .hint_text("one station for both")
                        .desired_width(200.0),
                );
                ui.end_row();
            }
        });
}

/// The matching rule and, where time stamps may be used, the tolerance (rows of the options' grid).
/// A ROS 2 bag's options (`--joint-topic`, `--still-velocity`, `--still-secs`, `--clock-offset`),
/// shown when a joint log is a bag.
#[cfg(not(target_arch = "wasm32"))]
fn bag_ui(ui: &mut egui::Ui, inputs: &mut ImportInputs) {
    let bag = inputs
        .joints
        .values()
        .any(|j| crate::import::bag::is_bag(std::path::Path::new(j.trim())));
    if !bag {
        return;
    }
    ui.label("ROS 2 bag topic");
    ui.add(
        egui::TextEdit::singleline(&mut inputs.bag.topic)
            .hint_text(crate::import::bag::DEFAULT_TOPIC)
            .desired_width(300.0),
    );
    ui.end_row();
    ui.label("still when");
    ui.horizontal(|ui| {
        ui.label("every joint below");
        ui.add(
            egui::DragValue::new(&mut inputs.bag.still_velocity)
                .range(1e-6..=1.0)
                .speed(0.0005)
                .suffix(" rad/s"),
        );
        ui.label("for");
        ui.add(
            egui::DragValue::new(&mut inputs.bag.still_secs)
                .range(0.0..=60.0)
                .speed(0.05)
                .suffix(" s"),
        );
    });
    ui.end_row();
    ui.label("clock offset");
    ui.add(
        egui::TextEdit::singleline(&mut inputs.clock_offset)
            .hint_text("robot minus tracker PC, s: estimated (the report says)")
            .desired_width(300.0),
    );
    ui.end_row();
}

fn matching_ui(ui: &mut egui::Ui, inputs: &mut ImportInputs) {
    ui.label("match points by");
    combo(
        ui,
        "match",
        &mut inputs.matching,
        &[
            (MatchRule::Auto, "automatic (the report says which)"),
            (MatchRule::Name, "target name <id>_<reflector>"),
            (MatchRule::Order, "file order"),
            (MatchRule::Time, "time stamp"),
        ],
    );
    ui.end_row();
    if matches!(inputs.matching, MatchRule::Time | MatchRule::Auto) {
        ui.label("time tolerance");
        ui.add(
            egui::DragValue::new(&mut inputs.time_tolerance_s)
                .range(0.001..=3600.0)
                .speed(0.05)
                .suffix(" s"),
        );
        ui.end_row();
    }
}

/// Both arms in one file (a motion-capture export): each arm's own mapping, measured together, the
/// verification rows — `dualcal import`'s `--left-columns`, `--right-columns`, `--measured-together`,
/// `--verify-last`.
fn one_file_options_ui(ui: &mut egui::Ui, inputs: &mut ImportInputs) {
    egui::Grid::new("import one-file options")
        .num_columns(2)
        .show(ui, |ui| {
            for side in Side::BOTH {
                ui.label(format!("{side} mapping"));
                ui.add(
                    egui::TextEdit::singleline(&mut inputs.arm_columns[side])
                        .hint_text("the column mapping above")
                        .desired_width(300.0),
                )
                .on_hover_text(
                    "This arm's own mapping (one file holding both arms: give it as both arms' \
                     point file), e.g. `id=1,q=joints[0-2],q=joints[10-16],m.x=markers[1][0],…`",
                );
                ui.end_row();
            }
            ui.label("measured together");
            ui.checkbox(&mut inputs.measured_together, "both hands at one instant")
                .on_hover_text(
                    "Rows of both arms with the same id are one pose (a motion-capture system \
                     seeing both markers): the joints both arms share must agree",
                );
            ui.end_row();
            ui.label("verify the last");
            ui.add(
                egui::TextEdit::singleline(&mut inputs.verify_last)
                    .hint_text("the file's split")
                    .desired_width(80.0),
            )
            .on_hover_text("The last N configurations of each arm verify, the others calibrate");
            ui.end_row();
        });
}

fn combo<T: PartialEq + Copy>(ui: &mut egui::Ui, id: &str, value: &mut T, choices: &[(T, &str)]) {
    let shown = choices
        .iter()
        .find(|(v, _)| v == value)
        .map_or("", |(_, label)| label);
    egui::ComboBox::from_id_salt(("import", id))
        .selected_text(shown)
        .show_ui(ui, |ui| {
            for (v, label) in choices {
                ui.selectable_value(value, *v, *label);
            }
        });
}

fn preview_ui(ui: &mut egui::Ui, preview: Option<&Preview>, commands: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        ui.heading("Preview");
        if preview.is_some()
            && ui
                .small_button("Read again")
                .on_hover_text("Read the files again (after editing them)")
                .clicked()
        {
            commands.push(Command::RefreshImport);
        }
    });
    let Some(preview) = preview else {
        ui.label("Choose a point file: one arm's for a dataset of that arm alone, or both arms'.");
        return;
    };
    ui.label(
        RichText::new(format!("for the robot: {}", preview.robot))
            .small()
            .color(Color32::GRAY),
    );
    match &preview.result {
        Err(e) => {
            ui.label(RichText::new(e).color(ERROR_COLOR));
        }
        Ok(imported) => {
            for arm in imported.report.imported() {
                arm_line(ui, arm);
            }
            if let [side] = imported.dataset.measured_sides().as_slice() {
                ui.label(format!("the {side} arm alone (a dataset of one arm)"));
            }
            if let Some(refused) = &preview.refused {
                ui.label(RichText::new(refused).color(ERROR_COLOR));
            }
        }
    }
}

/// The whole import report (`import-report.txt`), folded.
fn report_ui(ui: &mut egui::Ui, preview: Option<&Preview>) {
    let Some(Ok(imported)) = preview.map(|p| &p.result) else {
        return;
    };
    egui::CollapsingHeader::new("Report")
        .default_open(false)
        .show(ui, |ui| {
            egui::ScrollArea::vertical()
                .max_height(220.0)
                .show(ui, |ui| {
                    ui.label(RichText::new(imported.report.to_string()).monospace());
                });
        });
}

/// One arm's outcome in a line: format, matched, and what was left over.
fn arm_line(ui: &mut egui::Ui, arm: &ArmReport) {
    let leftover = arm.unmatched_points.len() + arm.unmatched_configurations.len();
    let text = format!(
        "{}: {} configurations ({}, {}; {} points read{}{})",
        arm.side,
        arm.matched,
        arm.format.name(),
        arm.length_unit.name(),
        arm.points_read,
        if leftover > 0 {
            format!(
                ", {} points and {} configurations unmatched",
                arm.unmatched_points.len(),
                arm.unmatched_configurations.len()
            )
        } else {
            String::new()
        },
        if arm.repeated.is_empty() {
            String::new()
        } else {
            format!(", {} repeated shots averaged", arm.repeated.len())
        },
    );
    let color = if arm.matched == 0 {
        ERROR_COLOR
    } else if leftover > 0 {
        WARNING_COLOR
    } else {
        ui.visuals().text_color()
    };
    ui.label(RichText::new(text).color(color));
    // What the import guessed or decided (encoding, unit, separator, matching rule, sheet, rows
    // deleted, U(95)), as the report writes it.
    for note in &arm.notes {
        ui.label(
            RichText::new(format!("  {note}"))
                .small()
                .color(Color32::GRAY),
        );
    }
}

fn finish_ui(
    ui: &mut egui::Ui,
    view: &mut ImportView,
    state: &ImportContext,
    commands: &mut Vec<Command>,
) {
    let ready = view.preview().and_then(Preview::importable).is_some();
    let label = if state.in_memory {
        "Open in the workbench"
    } else {
        ui.horizontal(|ui| {
            ui.label("write to");
            ui.add(
                egui::TextEdit::singleline(&mut view.out_dir)
                    .hint_text("a new or empty folder")
                    .desired_width(330.0),
            );
            if state.dialogs && ui.button("Choose folder…").clicked() {
                commands.push(Command::ChooseFile(OpenKind::ImportFolder));
            }
        });
        "Write dataset and open"
    };
    let enabled = ready && !state.loading && (state.in_memory || !view.out_dir.trim().is_empty());
    if ui
        .add_enabled(enabled, egui::Button::new(label))
        .on_hover_text(
            "The dataset.toml, left.csv, right.csv and import-report.txt that `dualcal import` \
             writes; then the dataset is opened",
        )
        .clicked()
    {
        commands.push(Command::FinishImport);
    }
    if let Some(e) = &view.write_error {
        ui.label(RichText::new(e).color(ERROR_COLOR));
    }
}
