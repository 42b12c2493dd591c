//! The panels around the viewport: settings, view options, plots, the configuration table and the
//! status bar.

use super::*;

impl WorkbenchApp {
    pub(super) fn panels_ui(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("status bar").show(ui, |ui| self.status_bar_ui(ui));
        egui::Panel::left("settings")
            .default_size(270.0)
            .resizable(true)
            .show(ui, |ui| self.settings_panel_ui(ui));
        egui::Panel::right("table")
            .default_size(450.0)
            .resizable(true)
            .show(ui, |ui| self.table_ui(ui));
        egui::Panel::bottom("plots")
            .default_size(300.0)
            .resizable(true)
            .show(ui, |ui| self.plots_ui(ui));
    }

    fn settings_panel_ui(&mut self, ui: &mut egui::Ui) {
        let running = self.job.is_some();
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("Dataset");
            match &self.session {
                Some(s) => {
                    let d = &s.dataset;
                    let count = |side: Side, split: Split| d.arm(side).select(split).len();
                    ui.label(
                        RichText::new(
                            d.dir
                                .file_name()
                                .map_or_else(|| d.dir.display().to_string(), |n| n.to_string_lossy().into()),
                        )
                        .strong(),
                    )
                    .on_hover_text(d.dir.display().to_string());
                    ui.label(format!(
                        "left: {} cal + {} ver\nright: {} cal + {} ver",
                        count(Side::Left, Split::Cal),
                        count(Side::Left, Split::Ver),
                        count(Side::Right, Split::Cal),
                        count(Side::Right, Split::Ver),
                    ));
                    ui.label(format!(
                        "tracker MPE {} µm + {} µm/m",
                        d.tracker.mpe_um, d.tracker.mpe_um_per_m
                    ));
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
                    self.open_dialog(OpenKind::Dataset);
                }
                if ui
                    .add_enabled(self.loading.is_none(), egui::Button::new("Example"))
                    .on_hover_text("Open the bundled simulated example dataset")
                    .clicked()
                {
                    self.open_dataset(&bundled_example_path());
                }
            });

            ui.separator();
            ui.heading("Robot");
            let robot_label = self
                .session
                .as_ref()
                .and_then(|s| s.robot_source.as_ref())
                .map_or_else(
                    || "built-in IRB 14000".to_string(),
                    |p| p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into()),
                );
            ui.label(robot_label);
            if ui
                .button("Open URDF…")
                .on_hover_text("Use another robot description (URDF) for this dataset")
                .clicked()
            {
                self.open_dialog(OpenKind::Urdf);
            }

            ui.separator();
            ui.heading("Calibration");
            ui.add_enabled_ui(!running, |ui| {
                egui::Grid::new("settings grid").num_columns(2).show(ui, |ui| {
                    let l_method = ui.label("Method").on_hover_text(
                        "Minimax: the paper's min over parameters of the max over reflectors of the summed squared distance errors.\nLeast squares: all distance errors (Levenberg–Marquardt), for comparison.",
                    );
                    egui::ComboBox::from_id_salt("method")
                        .selected_text(match self.settings.method {
                            Method::Minimax => "minimax",
                            Method::LeastSquares => "least squares",
                        })
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut self.settings.method, Method::Minimax, "minimax");
                            ui.selectable_value(
                                &mut self.settings.method,
                                Method::LeastSquares,
                                "least squares",
                            );
                        })
                        .response
                        .labelled_by(l_method.id);
                    ui.end_row();
                    let l_qp_solver = ui.label("QP solver").on_hover_text(
                        "exact: active-set solution of each SQP subproblem.\npaper: the primal-dual subgradient method of eqs. (29)–(31) (slow, inexact).",
                    );
                    egui::ComboBox::from_id_salt("qp")
                        .selected_text(match self.settings.qp {
                            QpMethod::Exact => "exact",
                            QpMethod::Paper => "paper",
                        })
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut self.settings.qp, QpMethod::Exact, "exact");
                            ui.selectable_value(&mut self.settings.qp, QpMethod::Paper, "paper");
                        })
                        .response
                        .labelled_by(l_qp_solver.id);
                    ui.end_row();
                    let l_split = ui.label("Split").on_hover_text(
                        "Configurations used for identification: the calibration split only, or all of them",
                    );
                    egui::ComboBox::from_id_salt("split")
                        .selected_text(self.settings.split.name())
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut self.settings.split, Split::Cal, "cal");
                            ui.selectable_value(&mut self.settings.split, Split::All, "all");
                        })
                        .response
                        .labelled_by(l_split.id);
                    ui.end_row();
                    let l_iteration_limit = ui.label("Iteration limit").on_hover_text("Outer SQP iterations per stage");
                    ui.add(egui::DragValue::new(&mut self.settings.max_iterations).range(1..=10_000))
                        .labelled_by(l_iteration_limit.id);
                    ui.end_row();
                    let l_step_tolerance = ui.label("Step tolerance").on_hover_text(
                        "Stop a stage when the scaled parameter step norm falls below this",
                    );
                    ui.add(
                        egui::DragValue::new(&mut self.settings.step_tolerance)
                            .range(1e-14..=1e-2)
                            .speed(0.0)
                            .custom_formatter(|v, _| format!("{v:.1e}"))
                            .custom_parser(|s| s.trim().parse::<f64>().ok()),
                    )
                    .labelled_by(l_step_tolerance.id);
                    ui.end_row();
                    if self.settings.qp == QpMethod::Paper {
                        let l_qp_iterations = ui.label("QP iterations").on_hover_text(
                            "Subgradient iterations of the paper's QP solver per outer iteration",
                        );
                        ui.add(
                            egui::DragValue::new(&mut self.settings.max_qp_iterations)
                                .range(10..=1_000_000),
                        )
                        .labelled_by(l_qp_iterations.id);
                        ui.end_row();
                    }
                });
            });
            ui.horizontal(|ui| {
                let can_start = !running && self.session.is_some();
                if ui
                    .add_enabled(can_start, egui::Button::new(RichText::new("Calibrate").strong().color(Color32::WHITE))
                            .fill(Color32::from_rgb(38, 92, 160))
                            .min_size(egui::vec2(110.0, 26.0)))
                    .on_hover_text("Run the two-step calibration (step 1 per arm, then step 2) on a worker thread")
                    .clicked()
                {
                    self.start_calibration(ui.ctx());
                }
                if ui
                    .add_enabled(running, egui::Button::new("Cancel").min_size(egui::vec2(80.0, 26.0)))
                    .on_hover_text("Stop the run; the previous result stays")
                    .clicked()
                {
                    self.cancel_calibration();
                }
            });

            ui.separator();
            ui.heading("Export");
            let has_cal = self.session.as_ref().is_some_and(|s| s.calibrated.is_some());
            let ctx = ui.ctx().clone();
            ui.add_enabled_ui(has_cal, |ui| {
                if ui
                    .button("Parameters (JSON)…")
                    .on_hover_text("dualcal-params/1 file of the calibrated model")
                    .on_disabled_hover_text("Calibrate first")
                    .clicked()
                {
                    self.export(Export::Params, &ctx);
                }
                if ui
                    .button("Calibrated URDF…")
                    .on_hover_text("A copy of the robot description whose joints reproduce the calibrated model")
                    .on_disabled_hover_text("Calibrate first")
                    .clicked()
                {
                    self.export(Export::Urdf, &ctx);
                }
            });
            ui.add_enabled_ui(self.session.is_some(), |ui| {
                if ui
                    .button("Configuration errors (CSV)…")
                    .on_hover_text("Per-configuration errors of the current model")
                    .clicked()
                {
                    self.export(Export::Csv, &ctx);
                }
                if ui
                    .button("Plots (PNG)…")
                    .on_hover_text("The plot area as shown")
                    .clicked()
                {
                    self.export(Export::PlotPng, &ctx);
                }
            });

            ui.separator();
            self.view_options_ui(ui);
        });
    }

    fn view_options_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("View");
        let has_cal = self
            .session
            .as_ref()
            .is_some_and(|s| s.calibrated.is_some());
        let o = &mut self.viewport.options;
        ui.horizontal_wrapped(|ui| {
            ui.checkbox(&mut o.show_robot, "robot");
            ui.checkbox(&mut o.show_grid, "grid");
            ui.checkbox(&mut o.show_measured, "measured")
                .on_hover_text("Measured reflector triangles (tracker points registered to the robot), coloured by error");
            ui.checkbox(&mut o.show_model, "model")
                .on_hover_text("Model reflector triangles (forward kinematics)");
            ui.checkbox(&mut o.show_vectors, "error vectors")
                .on_hover_text("From each model point towards the measured one, exaggerated");
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut o.show_cal, "cal");
            ui.checkbox(&mut o.show_ver, "ver");
            ui.checkbox(&mut o.show_arm[0], "left");
            ui.checkbox(&mut o.show_arm[1], "right");
        });
        ui.horizontal(|ui| {
            ui.label("Model:");
            // What is drawn: the calibrated model only once one exists (the preference is kept, so a
            // finished calibration switches the view to it).
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
                    .on_disabled_hover_text("Calibrate first")
                    .clicked()
                {
                    o.use_calibrated = true;
                }
            });
        });
        ui.checkbox(&mut self.viewport.auto_scale, "auto scale")
            .on_hover_text("Set the vector exaggeration and colour range from the current errors whenever a model is loaded or calibrated");
        let o = &mut self.viewport.options;
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
        // The pose each arm is drawn in: a configuration (follows the selection) or home.
        if let Some(session) = &self.session {
            for (k, side) in Side::BOTH.into_iter().enumerate() {
                let measurements = &session.dataset.arm(side).measurements;
                if measurements.is_empty() {
                    continue;
                }
                ui.horizontal(|ui| {
                    let label = ui.label(format!("{side} arm pose:"));
                    let pose = &mut self.viewport.poses[k];
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
                        .on_hover_text("Drag or type a configuration id; selecting a configuration also poses its arm");
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
        ui.horizontal(|ui| {
            if ui
                .button("Reset view")
                .on_hover_text("Also: double-click the viewport")
                .clicked()
            {
                self.viewport.camera = viewport::camera::OrbitCamera::default();
            }
            if ui
                .button("Select worst")
                .on_hover_text(
                    "Select the configuration with the largest |Δd| of the current model",
                )
                .clicked()
            {
                self.select_worst();
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

    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.plot_tab, PlotTab::Convergence, "Convergence");
            ui.selectable_value(&mut self.plot_tab, PlotTab::Accuracy, "Accuracy");
            ui.selectable_value(&mut self.plot_tab, PlotTab::Summary, "Summary");
            ui.separator();
            match self.plot_tab {
                PlotTab::Convergence => {
                    for stage in plots::STAGES {
                        ui.selectable_value(&mut self.plot_stage, stage, stage.to_string());
                    }
                }
                PlotTab::Summary => {
                    ui.selectable_value(&mut self.figure_split, Split::Cal, "cal split");
                    ui.selectable_value(&mut self.figure_split, Split::Ver, "ver split");
                }
                PlotTab::Accuracy => {
                    let label = ui.label("Figure:");
                    egui::ComboBox::from_id_salt("figure")
                        .selected_text(self.figure.label())
                        .width(230.0)
                        .show_ui(ui, |ui| {
                            for f in Indicator::ALL {
                                ui.selectable_value(&mut self.figure, f, f.label());
                            }
                        })
                        .response
                        .labelled_by(label.id);
                    ui.selectable_value(&mut self.figure_split, Split::Cal, "cal split");
                    ui.selectable_value(&mut self.figure_split, Split::Ver, "ver split");
                }
            }
        });
        let rect = ui.available_rect_before_wrap();
        self.plot_rect = Some(rect);
        match self.plot_tab {
            PlotTab::Convergence => plots::convergence_plot_ui(ui, &self.history, self.plot_stage),
            PlotTab::Accuracy => match &self.session {
                Some(s) => plots::accuracy_ui(ui, s, self.figure, self.figure_split),
                None => {
                    ui.label("No dataset.");
                }
            },
            PlotTab::Summary => match &self.session {
                Some(s) => plots::accuracy_summary_ui(ui, s, self.figure_split),
                None => {
                    ui.label("No dataset.");
                }
            },
        }
    }

    fn table_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.heading("Configurations");
            if ui
                .button("Select worst")
                .on_hover_text("Select the configuration with the largest |Δd|")
                .clicked()
            {
                self.select_worst();
            }
        });
        let Some(session) = &self.session else {
            ui.label("No dataset.");
            return;
        };
        let label = if session.calibrated.is_some() {
            "errors of the calibrated model"
        } else {
            "errors of the nominal model"
        };
        ui.label(RichText::new(label).small().color(Color32::GRAY));
        if let Some((side, index)) = self.selection
            && let Some(row) = session
                .current()
                .configs
                .iter()
                .find(|r| r.config.side == side && r.config.index == index)
        {
            let e = row.point_errors_mm();
            ui.label(format!(
                "selected: {} ({} arm, {}), point errors a/b/c = {:.3} / {:.3} / {:.3} mm",
                row.id,
                side,
                if row.split == Split::Cal {
                    "cal"
                } else {
                    "ver"
                },
                e[0],
                e[1],
                e[2]
            ));
        }
        let clicked = table::config_table_ui(
            ui,
            session.current(),
            &mut self.table,
            self.selection,
            self.scroll_table_to_selection,
        );
        self.scroll_table_to_selection = false;
        if let Some(sel) = clicked {
            self.select(sel, false);
        }
    }

    fn status_bar_ui(&mut self, ui: &mut egui::Ui) {
        let mut dismiss = None;
        for (k, e) in self.errors.iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.small_button("×").on_hover_text("Dismiss").clicked() {
                    dismiss = Some(k);
                }
                ui.label(RichText::new(e).color(Color32::from_rgb(255, 110, 100)));
            });
        }
        if let Some(k) = dismiss {
            self.errors.remove(k);
        }
        ui.horizontal(|ui| {
            match &self.status {
                Status::Idle(text) => {
                    if self.loading.is_some() {
                        ui.spinner();
                    }
                    ui.label(text);
                }
                Status::Running { stage, iteration } => {
                    ui.spinner();
                    let elapsed = self.job.as_ref().map_or(0.0, |j| j.started.elapsed().as_secs_f64());
                    let cancelling = self.job.as_ref().is_some_and(|j| j.is_cancelling());
                    ui.label(match stage {
                        Some(stage) => format!(
                            "Calibrating: {stage}, iteration {iteration} ({elapsed:.1} s){}",
                            if cancelling { " — cancelling…" } else { "" }
                        ),
                        None => "Calibrating: starting…".into(),
                    });
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
