//! The left panel: dataset, robot, calibration settings and buttons, export, then the view options.

use super::view_options::view_options_ui;
use super::{WARNING_COLOR, choice_ui, grid_row_ui};
use crate::app::bundled_example_path;
use crate::app::command::{Command, Export, OpenKind};
use crate::app::compare::method_used;
use crate::app::session::{RobotMeshes, Session};
use crate::app::viewport::ViewportState;
use crate::dataset::Split;
use crate::kinematics::ErrorTerms;
use crate::side::Side;
use crate::solver::{BaseMethod, CalibrationSettings, Method, QpMethod, Reflector};
use eframe::egui::{self, Color32, RichText};
use std::path::Path;

/// The left panel and the state it shows: it edits the calibration settings and the view options in
/// place and pushes a [`Command`] for everything else.
pub struct LeftPanel<'a> {
    pub session: Option<&'a Session>,
    /// The robot description opened instead of the dataset's.
    pub urdf_override: Option<&'a Path>,
    pub loading: bool,
    pub calibrating: bool,
    /// Whether the comparison view is open.
    pub compare_open: bool,
    pub settings: &'a mut CalibrationSettings,
    pub viewport: &'a mut ViewportState,
}

impl LeftPanel<'_> {
    pub fn ui(self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        egui::ScrollArea::vertical().show(ui, |ui| {
            self.dataset_section_ui(ui, commands);
            ui.separator();
            self.robot_section_ui(ui, commands);
            ui.separator();
            ui.horizontal(|ui| {
                ui.heading("Calibration");
                self.compare_button_ui(ui, commands);
            });
            self.current_method_ui(ui);
            let names = self.session.map(|s| &s.dataset.reflector_names[..]);
            ui.add_enabled_ui(!self.calibrating, |ui| {
                calibration_settings_ui(ui, &mut *self.settings, names)
            });
            if let Some(s) = self.session
                && let Some(why) = crate::solver::default_method_reason(&s.dataset)
                && self.settings.method == crate::solver::default_method(&s.dataset)
            {
                ui.label(
                    RichText::new(format!(
                        "{}: the default for this data",
                        self.settings.method.name()
                    ))
                    .small()
                    .color(Color32::GRAY),
                )
                .on_hover_text(format!(
                    "{why}. Pick minimax for the distances alone (as the paper)."
                ));
            }
            self.calibration_buttons_ui(ui, commands);
            ui.separator();
            self.export_section_ui(ui, commands);
            ui.separator();
            view_options_ui(ui, self.session, &mut *self.viewport, commands);
        });
    }

    fn dataset_section_ui(&self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.heading("Dataset");
        match self.session {
            Some(s) => {
                let d = &s.dataset;
                ui.label(RichText::new(file_name(&d.dir)).strong())
                    .on_hover_text(d.dir.display().to_string());
                let count = |side: Side| {
                    if d.arm(side).is_measured() {
                        let n = |split: Split| d.arm(side).select(split).len();
                        format!("{side}: {} cal + {} ver", n(Split::Cal), n(Split::Ver))
                    } else {
                        format!("{side}: not measured")
                    }
                };
                ui.label(format!("{}\n{}", count(Side::Left), count(Side::Right)));
                ui.label(format!(
                    "tracker MPE {} µm + {} µm/m",
                    d.tracker.mpe_um, d.tracker.mpe_um_per_m
                ));
                let names = d.reflector_names.join(", ");
                let label = match d.reflector_count() {
                    1 => format!("1 reflector per arm ({names})"),
                    n => format!("{n} reflectors per arm ({names})"),
                };
                let orientation = crate::metrics::orientation_measurable(&d.nominal_reflectors_mm);
                ui.label(label).on_hover_text(if orientation {
                    "three or more reflectors: the flange's orientation is measured too"
                } else {
                    "fewer than three reflectors: the flange's orientation is not measurable; its \
                     figures read \"not measurable\""
                });
                if let [side] = d.measured_sides().as_slice() {
                    ui.label(
                        RichText::new(format!(
                            "one arm alone ({side}) — base and collaborative figures not \
                             measurable"
                        ))
                        .color(egui::Color32::from_rgb(230, 180, 80)),
                    )
                    .on_hover_text(format!(
                        "The dataset has the {side} arm's measurements only (one [[arms]] entry): \
                         step 1 calibrates it; the {} arm keeps its nominal parameters, step 2 is \
                         not run and there are no collaborative figures.",
                        side.other()
                    ));
                } else if !d.one_tracker_frame() {
                    ui.label(
                        RichText::new(format!(
                            "stations: left `{}`, right `{}` — base and collaborative figures not \
                             measurable",
                            d.arms.left.station.as_deref().unwrap_or(""),
                            d.arms.right.station.as_deref().unwrap_or("")
                        ))
                        .color(egui::Color32::from_rgb(230, 180, 80)),
                    )
                    .on_hover_text(
                        "The arms were measured from different tracker stations (dataset.toml \
                         `[[arms]] station`): each arm calibrates on its own; distances between the \
                         arms mean nothing, so step 2 is not run.",
                    );
                }
            }
            None => {
                ui.label("none loaded");
            }
        }
        ui.horizontal(|ui| {
            if ui
                .button("Open dataset…")
                .on_hover_text("Open a dualcal-dataset/1 dataset.toml (or drop one on the window)")
                .clicked()
            {
                commands.push(Command::ChooseFile(OpenKind::Dataset));
            }
            if ui
                .add_enabled(!self.loading, egui::Button::new("Example"))
                .on_hover_text("Open the bundled simulated example dataset")
                .clicked()
            {
                commands.push(Command::OpenDataset(bundled_example_path()));
            }
            if ui
                .add_enabled(!self.loading, egui::Button::new("Import…"))
                .on_hover_text(
                    "Make a dataset from tracker exports (SpatialAnalyzer, Leica, figaroh, any CSV) \
                     and joint logs, with a live preview: `dualcal import`",
                )
                .clicked()
            {
                commands.push(Command::ShowImport(true));
            }
        });
        if ui
            .button("Plan measurements…")
            .on_hover_text(
                "Choose the configurations to measure: collision-free, seen by the tracker, the \
                 most informative (`dualcal plan`), drawn in 3D with the tracker",
            )
            .clicked()
        {
            commands.push(Command::ShowPlan(true));
        }
    }

    /// Which robot and which arms the figures are of (the same as the command line's `robot:` line),
    /// its meshes and its warnings.
    fn robot_section_ui(&self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.heading("Robot");
        match self.session {
            Some(session) => robot_summary_ui(ui, session),
            None => {
                ui.label("built-in IRB 14000 (no dataset)");
            }
        }
        if let Some(urdf) = self.urdf_override {
            ui.label(
                RichText::new(format!(
                    "opened: {} (instead of the dataset's)",
                    file_name(urdf)
                ))
                .small()
                .color(Color32::GRAY),
            )
            .on_hover_text(urdf.display().to_string());
        }
        ui.horizontal(|ui| {
            if ui
                .add_enabled(!self.loading, egui::Button::new("Open URDF…"))
                .on_hover_text(
                    "Use another robot description (URDF) for this dataset; or drop a .urdf on the window",
                )
                .clicked()
            {
                commands.push(Command::ChooseFile(OpenKind::Urdf));
            }
            if self.urdf_override.is_some()
                && ui
                    .add_enabled(!self.loading, egui::Button::new("Dataset's robot"))
                    .on_hover_text("Go back to the robot the dataset names (or the built-in one)")
                    .clicked()
            {
                commands.push(Command::UseDatasetRobot);
            }
        });
    }

    fn calibration_buttons_ui(&self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let running = self.calibrating;
        ui.horizontal(|ui| {
            let calibrate =
                egui::Button::new(RichText::new("Calibrate").strong().color(Color32::WHITE))
                    .fill(Color32::from_rgb(38, 92, 160))
                    .min_size(egui::vec2(110.0, 26.0));
            if ui
                .add_enabled(!running && self.session.is_some(), calibrate)
                .on_hover_text(
                    "Run the two-step calibration (step 1 per arm, then step 2) on a worker thread",
                )
                .clicked()
            {
                commands.push(Command::StartCalibration);
            }
            if ui
                .add_enabled(
                    running,
                    egui::Button::new("Cancel").min_size(egui::vec2(80.0, 26.0)),
                )
                .on_hover_text("Stop the run; the previous result stays")
                .clicked()
            {
                commands.push(Command::CancelCalibration);
            }
        });
    }

    /// Open or close the comparison view.
    fn compare_button_ui(&self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let open = self.compare_open;
        let text = if open {
            "Back to the 3D view"
        } else {
            "Compare methods…"
        };
        if ui
            .add_enabled(self.session.is_some(), egui::Button::new(text))
            .on_hover_text(
                "Run several methods on this dataset and see their figures, histograms and box plots \
                 side by side; adopt one as the calibration",
            )
            .clicked()
        {
            commands.push(Command::ShowComparison(!open));
        }
    }

    /// The method of the current calibration, "current: nominal" before one: the line is always
    /// there, one line high (truncated; the whole on hover), so nothing below it moves when a run
    /// ends.
    fn current_method_ui(&self, ui: &mut egui::Ui) {
        let text = match self.session.and_then(|s| s.calibrated.as_ref()) {
            Some(c) => format!("current: {}", method_used(&c.result)),
            None => "current: nominal (not calibrated)".to_string(),
        };
        ui.add(egui::Label::new(RichText::new(text).small().color(Color32::GRAY)).truncate());
    }

    fn export_section_ui(&self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.heading("Export");
        let has_cal = self.session.is_some_and(|s| s.calibrated.is_some());
        let mut button = |ui: &mut egui::Ui, label: &str, hover: &str, what: Export| {
            let mut response = ui.button(label).on_hover_text(hover);
            if matches!(what, Export::Params | Export::Urdf | Export::Report) {
                response = response.on_disabled_hover_text("Calibrate first");
            }
            if response.clicked() {
                commands.push(Command::Export(what));
            }
        };
        ui.add_enabled_ui(has_cal, |ui| {
            button(
                ui,
                "Parameters (JSON)…",
                "dualcal-params/1 file of the calibrated model",
                Export::Params,
            );
            button(
                ui,
                "Calibrated URDF…",
                "A copy of the robot description whose joints reproduce the calibrated model",
                Export::Urdf,
            );
            button(
                ui,
                "Calibration report (HTML)…",
                "One self-contained HTML file, as `dualcal report` writes it: dataset, method, \
                 identifiability, parameters with σ, accuracy before and after, figures, worst \
                 configurations, screening, warnings",
                Export::Report,
            );
        });
        ui.add_enabled_ui(self.session.is_some(), |ui| {
            button(
                ui,
                "Configuration errors (CSV)…",
                "Per-configuration errors of the current model",
                Export::Csv,
            );
            button(
                ui,
                "Plots (PNG)…",
                "The plot area as shown",
                Export::PlotPng,
            );
        });
    }
}

/// The session's robot: its file, each arm's chain, the nominal model, the meshes and the warnings.
fn robot_summary_ui(ui: &mut egui::Ui, session: &Session) {
    let robot = &session.robot;
    let name = match &session.robot_source {
        Some(path) => file_name(path),
        None => "built-in IRB 14000".into(),
    };
    ui.label(RichText::new(name).strong())
        .on_hover_text(robot.name());
    let shared = session.nominal.model.shared_joints();
    let one_arm = robot.is_one_arm();
    if one_arm {
        ui.label("one arm (a single robot)").on_hover_text(
            "The description has one arm: the dataset's one arm is its chain (a single robot \
             measured alone)",
        );
    } else if !shared.is_empty() {
        ui.label(format!("shared by both arms: {}", shared.names.join(", ")))
            .on_hover_text(
                "Joints on both arms' chains (a torso): one joint of the robot, its corrections \
                 identified once from both arms' data (step 1 fits both arms at once), changed once \
                 in the calibrated URDF; both arms' files carry its value",
            );
    }
    // The chain in monospace: the proportional font has no arrow glyph.
    let sides: &[Side] = if one_arm {
        &session.dataset.measured_sides()
    } else {
        &Side::BOTH
    };
    for &side in sides {
        let arm = robot.arm(side);
        let hover = format!(
            "The {side} arm: the chain from its base link to its tip link; its joints, in the CSV's order: {}",
            arm.joint_names().join(", ")
        );
        ui.label(format!("{side} arm:")).on_hover_text(&hover);
        ui.label(
            RichText::new(format!("{} ({} joints)", arm.links, arm.chain.dof()))
                .family(egui::FontFamily::Monospace)
                .size(10.5),
        )
        .on_hover_text(hover);
        egui::CollapsingHeader::new(format!("{side} joints and parameters"))
            .id_salt(("robot arm", side.name()))
            .show(ui, |ui| arm_details_ui(ui, session, side));
    }
    ui.label(
        RichText::new(if robot.is_builtin() {
            "nominal model: Table 3 (DH)"
        } else {
            "nominal model: the URDF's joint origins"
        })
        .color(Color32::GRAY),
    );
    let meshes = match &session.meshes {
        RobotMeshes::None => None,
        RobotMeshes::Loading => Some("meshes: loading…".to_string()),
        RobotMeshes::Loaded(m) => Some(format!(
            "meshes: {} files, {} triangles{} ({:.2} s)",
            m.visual_files,
            thousands(m.visual_triangles),
            match m.visual_missing {
                0 => String::new(),
                n => format!(", {n} missing"),
            },
            m.elapsed_secs
        )),
        RobotMeshes::Failed(why) => Some(format!("meshes not loaded: {why}")),
    };
    if let Some(text) = meshes {
        ui.label(RichText::new(text).color(Color32::GRAY))
            .on_hover_text(
                "The URDF's visual meshes, loaded in the background. A missing one is drawn as its \
                 link's collision mesh in amber, or as a box.",
            );
    }
    let mesh_warnings = match &session.meshes {
        RobotMeshes::Loaded(m) => m.warnings.as_slice(),
        _ => &[],
    };
    let warnings: Vec<&String> = robot.warnings.iter().chain(mesh_warnings).collect();
    if !warnings.is_empty() {
        egui::CollapsingHeader::new(
            RichText::new(format!(
                "{} warning{}",
                warnings.len(),
                if warnings.len() == 1 { "" } else { "s" }
            ))
            .color(WARNING_COLOR),
        )
        .id_salt("robot warnings")
        .show(ui, |ui| {
            for w in warnings {
                ui.label(RichText::new(w.as_str()).small().color(WARNING_COLOR));
            }
        });
    }
}

/// A joint's range: mm for a prismatic joint (its CSV column is a length), else degrees.
fn joint_range_ui(ui: &mut egui::Ui, linear: bool, (lo, hi): (f64, f64)) {
    if linear {
        ui.label(RichText::new(format!("{lo:.1} … {hi:.1} mm")).small())
            .on_hover_text("prismatic: its CSV column is a length");
    } else {
        ui.label(
            RichText::new(format!("{:.1}° … {:.1}°", lo.to_degrees(), hi.to_degrees())).small(),
        )
        .on_hover_text(format!("{lo:.4} … {hi:.4} rad"));
    }
}

/// One arm's joints (chain order, the CSV's `q1 … qN`) with their limits, and its calibration
/// parameters: how many, which distances cannot identify (and why), and after a calibration which
/// were identified. A leader off the chain (a column's measured joint that chain joints mimic) is a
/// column of the data: it stands before its first follower.
fn arm_details_ui(ui: &mut egui::Ui, session: &Session, side: Side) {
    joints_grid_ui(ui, session, side);
    parameters_ui(ui, session, side);
}

/// The arm's joints in chain order, each with its data column (or `mimic`) and limits; an off-chain
/// leader before its first follower.
fn joints_grid_ui(ui: &mut egui::Ui, session: &Session, side: Side) {
    let arm = &session.robot.arms()[side];
    let variables = arm.chain.variables();
    egui::Grid::new(("joints", side.name()))
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            let mut leaders_shown = Vec::new();
            for j in &arm.chain.joints {
                let leader = j.drive.leader().filter(|&k| {
                    variables.get(k).is_some_and(|v| v.is_off_chain())
                        && !leaders_shown.contains(&k)
                });
                if let Some(k) = leader {
                    leaders_shown.push(k);
                    let v = &variables[k];
                    ui.label(RichText::new(format!("q{}", k + 1)).small());
                    ui.label(RichText::new(v.name.as_str()).small().monospace())
                        .on_hover_text("off the chain: the joints mimicking it (below) follow it");
                    joint_range_ui(ui, v.kind.is_linear(), v.range());
                    ui.end_row();
                }
                match j.drive {
                    crate::kinematics::JointDrive::Variable(k) => {
                        ui.label(RichText::new(format!("q{}", k + 1)).small());
                    }
                    crate::kinematics::JointDrive::Mimic { .. } => {
                        ui.label(RichText::new("mimic").small())
                            .on_hover_text(format!(
                                "follows `{}` (URDF <mimic>): no CSV column",
                                j.mimics.as_deref().unwrap_or("?")
                            ));
                    }
                }
                ui.label(RichText::new(j.name.as_str()).small().monospace());
                joint_range_ui(ui, j.kind.is_linear(), j.range());
                ui.end_row();
            }
        });
}

/// The arm's calibration parameters: which distances cannot identify, and after a calibration which
/// were identified, held, weak, with their σ and the errors beyond geometry.
fn parameters_ui(ui: &mut egui::Ui, session: &Session, side: Side) {
    let model = session.nominal.model.arm(side);
    let n = model.param_count();
    let unidentifiable: Vec<(String, String)> = (0..n)
        .filter_map(|k| {
            model
                .unidentifiable_reason(k)
                .map(|why| (model.param_name(k), why))
        })
        .collect();
    ui.label(
        RichText::new(format!(
            "{n} parameters, {} identifiable by distances, {} not:",
            n - unidentifiable.len(),
            unidentifiable.len()
        ))
        .small(),
    )
    .on_hover_text(
        "The arm's calibration parameters (docs/solver.md): the kinematic ones and three coordinates per \
         reflector. Those distances between measured points cannot see are never identified.",
    );
    for (name, why) in &unidentifiable {
        ui.label(
            RichText::new(format!("{name}: {why}"))
                .small()
                .color(Color32::GRAY),
        );
    }
    if let Some(c) = &session.calibrated
        && let Some(report) = &c.result.identifiability[side]
    {
        // The parameters distances can never see are listed above: only the others the calibration
        // held (numerically dependent on this data) are listed again.
        let also: Vec<_> = report
            .fixed
            .iter()
            .filter(|f| !unidentifiable.iter().any(|(name, _)| *name == f.name))
            .collect();
        ui.label(
            RichText::new(format!(
                "last calibration: {} of {n} identified (condition {:.2e} with every parameter, {:.2e} with the identified ones){}",
                report.free.len(),
                report.condition_before,
                report.condition_after,
                if also.is_empty() {
                    "; none held besides those above"
                } else {
                    "; also held, as this data cannot tell them apart:"
                }
            ))
            .small(),
        );
        for f in also {
            ui.label(
                RichText::new(format!("{}: {}", f.name, f.reason))
                    .small()
                    .color(Color32::GRAY),
            );
        }
        // What the data cannot tell (docs/reliability.md, *Weak parameters*): nothing when none.
        for w in &c.result.weak[side] {
            ui.label(
                RichText::new(format!("weak {}", w.describe()))
                    .small()
                    .color(Color32::from_rgb(200, 140, 40)),
            )
            .on_hover_text(
                "Identified, but barely constrained by these configurations: its 1σ would move \
                 distances across the robot's workspace by more than 3× the tracker's noise",
            );
        }
        if let Some(u) = &c.uncertainty[side] {
            uncertainty_ui(ui, side, u);
        }
        errors_ui(
            ui,
            side,
            c.result.calibrated.arm(side),
            c.uncertainty[side].as_ref(),
        );
    }
}

/// The calibrated model's errors beyond geometry (`Model` other than geometric): each identified
/// compliance and harmonic amplitude with its 1σ.
fn errors_ui(
    ui: &mut egui::Ui,
    side: Side,
    arm: &crate::kinematics::ArmModel,
    u: Option<&crate::solver::uncertainty::ArmUncertainty>,
) {
    let Some(model) = &arm.errors.model else {
        return;
    };
    let off = arm.error_offset();
    egui::CollapsingHeader::new(
        RichText::new(format!(
            "beyond geometry: the `{}` model's compliances and harmonics",
            model.terms.name()
        ))
        .small(),
    )
    .id_salt(("beyond geometry", side))
    .show(ui, |ui| {
        ui.label(
            RichText::new(
                "Compliances in mrad/(N·m) of the held lumped masses (1 kg at each next joint; only \
                 compliance × mass shows in the data); harmonics in rad. Held ones (the data do not \
                 see them) show no σ.",
            )
            .small()
            .color(Color32::GRAY),
        );
        egui::Grid::new(("errors grid", side))
            .num_columns(2)
            .show(ui, |ui| {
                for (i, value) in arm.errors.values.iter().enumerate() {
                    let name = arm.param_name(off + i);
                    let unit = model.param_unit(i);
                    let sigma = u
                        .and_then(|u| u.parameters.iter().find(|p| p.name == name))
                        .map(|p| p.sigma);
                    let text = match (unit, sigma) {
                        ("rad", Some(s)) => format!("{:.4} ± {s:.4} mrad", value * 1000.0),
                        ("rad", None) => format!("{:.4} mrad (held)", value * 1000.0),
                        (unit, Some(s)) => format!("{value:.4} ± {s:.4} {unit}"),
                        (unit, None) => format!("{value:.4} {unit} (held)"),
                    };
                    ui.label(RichText::new(name).small().monospace());
                    ui.label(RichText::new(text).small());
                    ui.end_row();
                }
            });
    });
}

/// The identified parameters' 1σ, the strongly correlated pairs and the condition number.
fn uncertainty_ui(ui: &mut egui::Ui, side: Side, u: &crate::solver::uncertainty::ArmUncertainty) {
    egui::CollapsingHeader::new(
        RichText::new(format!(
            "1σ of the identified parameters (point noise {:.4} mm, condition {:.1})",
            u.point_sigma_mm, u.condition
        ))
        .small(),
    )
    .id_salt(("uncertainty", side))
    .show(ui, |ui| {
        ui.label(
            RichText::new(
                "From the residuals at the solution: the covariance of the least-squares fit \
                 linearised there (docs/solver.md, Uncertainty).",
            )
            .small()
            .color(Color32::GRAY),
        );
        egui::Grid::new(("uncertainty grid", side))
            .num_columns(2)
            .show(ui, |ui| {
                for p in &u.parameters {
                    ui.label(RichText::new(p.name.as_str()).small().monospace());
                    ui.label(RichText::new(format!("{:.4} {}", p.sigma, p.unit)).small());
                    ui.end_row();
                }
            });
        for c in &u.correlations {
            ui.label(
                RichText::new(format!(
                    "{} and {} correlated {:+.2}",
                    c.a, c.b, c.correlation
                ))
                .small()
                .color(Color32::from_rgb(200, 140, 40)),
            );
        }
    });
}

/// `295618` as `295 618`.
fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// The settings grid: method, QP solver, split, iteration limit, tolerances.
fn calibration_settings_ui(
    ui: &mut egui::Ui,
    settings: &mut CalibrationSettings,
    reflector_names: Option<&[String]>,
) {
    egui::Grid::new("settings grid").num_columns(2).show(ui, |ui| {
        grid_row_ui(
            ui,
            "Method",
            "Step 1, each arm's geometry: what the fit minimises (hover over a choice for what it \
             minimises and what it cannot see)",
            |ui| method_choice_ui(ui, settings),
        );
        grid_row_ui(
            ui,
            "Model",
            "What is identified with the geometry: joints giving under gravity (elastic), gear \
             harmonics of each joint angle, or both (full); hover over a choice. The calibrated URDF \
             keeps the geometry only; the parameter file has the whole model.",
            |ui| model_choice_ui(ui, &mut settings.model),
        );
        if settings.method.spec().takes_reflector {
            grid_row_ui(
                ui,
                "Reflector",
                "The one reflector whose distance errors ref. [26] fits. auto: per arm, the one with \
                 the largest nominal error (the summary names the one used).",
                |ui| {
                    // The dataset's reflectors by name (a, b, c without a dataset).
                    let mut choices = vec![(None, "auto")];
                    choices.extend(Reflector::ALL.iter().filter_map(|&r| {
                        let name = match reflector_names {
                            Some(names) => names.get(r.index())?.as_str(),
                            None => r.name(),
                        };
                        Some((Some(r), name))
                    }));
                    choice_ui(ui, "reflector", &mut settings.reflector, &choices)
                },
            );
        } else {
            // Only a single-reflector method takes one; the solver refuses one with any other.
            settings.reflector = None;
        }
        grid_row_ui(
            ui,
            "Base method",
            "Step 2, the right-arm base in the left-arm base (hover over a choice for what it \
             minimises and what it cannot see)",
            |ui| base_method_choice_ui(ui, &mut settings.base_method),
        );
        grid_row_ui(
            ui,
            "QP solver",
            "exact: active-set solution of each SQP subproblem.\npaper: the primal-dual subgradient method of eqs. (29)–(31) (slow, inexact).",
            |ui| {
                choice_ui(
                    ui,
                    "qp",
                    &mut settings.qp,
                    &[(QpMethod::Exact, "exact"), (QpMethod::Paper, "paper")],
                )
            },
        );
        grid_row_ui(
            ui,
            "Split",
            "Configurations used for identification: the calibration split only, or all of them",
            |ui| {
                choice_ui(
                    ui,
                    "split",
                    &mut settings.split,
                    &[(Split::Cal, "cal"), (Split::All, "all")],
                )
            },
        );
        grid_row_ui(
            ui,
            "Iteration limit",
            "Outer SQP iterations per stage",
            |ui| ui.add(egui::DragValue::new(&mut settings.max_iterations).range(1..=10_000)),
        );
        grid_row_ui(
            ui,
            "Step tolerance",
            "Stop a stage when the scaled parameter step norm falls below this",
            |ui| {
                ui.add(
                    egui::DragValue::new(&mut settings.step_tolerance)
                        .range(1e-14..=1e-2)
                        .speed(0.0)
                        .custom_formatter(|v, _| format!("{v:.1e}"))
                        .custom_parser(|s| s.trim().parse::<f64>().ok()),
                )
            },
        );
        if settings.qp == QpMethod::Paper {
            grid_row_ui(
                ui,
                "QP iterations",
                "Subgradient iterations of the paper's QP solver per outer iteration",
                |ui| {
                    ui.add(
                        egui::DragValue::new(&mut settings.max_qp_iterations)
                            .range(10..=1_000_000),
                    )
                },
            );
        }
    });
}

/// A step-1 method's label and what it minimises and cannot see (the choices' hover text), from the
/// methods' table.
pub(super) fn method_help(method: Method) -> (&'static str, &'static str) {
    (method.spec().label, method.spec().summary)
}

/// A step-2 method's label and what it minimises and cannot see, from the methods' table.
pub(super) fn base_method_help(method: BaseMethod) -> (&'static str, &'static str) {
    (method.spec().label, method.spec().summary)
}

/// The step-1 method combo: every method, each with what it minimises and cannot see on hover.
fn method_choice_ui(ui: &mut egui::Ui, settings: &mut CalibrationSettings) -> egui::Response {
    egui::ComboBox::from_id_salt("method")
        .selected_text(settings.method.name())
        .show_ui(ui, |ui| {
            for &m in Method::ALL {
                let (name, help) = method_help(m);
                ui.selectable_value(&mut settings.method, m, name)
                    .on_hover_text(help);
            }
        })
        .response
        .on_hover_text(method_help(settings.method).1)
}

/// The model combo: the named models of [`ErrorTerms::NAMED`], each described on hover.
fn model_choice_ui(ui: &mut egui::Ui, terms: &mut ErrorTerms) -> egui::Response {
    let help = |t: &ErrorTerms| {
        ErrorTerms::NAMED
            .iter()
            .find(|(_, n, _)| n == t)
            .map_or("", |(_, _, h)| *h)
    };
    egui::ComboBox::from_id_salt("model")
        .selected_text(format!("{} model", terms.name()))
        .show_ui(ui, |ui| {
            for (name, t, h) in ErrorTerms::NAMED {
                ui.selectable_value(terms, t, format!("{name} model"))
                    .on_hover_text(h);
            }
        })
        .response
        .on_hover_text(help(terms))
}

/// The step-2 method combo.
fn base_method_choice_ui(ui: &mut egui::Ui, base: &mut BaseMethod) -> egui::Response {
    egui::ComboBox::from_id_salt("base method")
        .selected_text(base.name())
        .show_ui(ui, |ui| {
            for &m in BaseMethod::ALL {
                let (name, help) = base_method_help(m);
                ui.selectable_value(base, m, name).on_hover_text(help);
            }
        })
        .response
        .on_hover_text(base_method_help(*base).1)
}

/// A path's last component (the whole path when it has none).
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    )
}
