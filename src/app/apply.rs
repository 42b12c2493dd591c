//! What the user asks for — in a panel, in the viewport, in the path prompt, through a file dialog or
//! by dropping a file — is a [`Command`], and [`WorkbenchApp::apply`] is the one place that carries
//! commands out (after the frame's UI is built). Widgets bound to view state (display options, plot
//! tabs, the calibration settings) edit it in place.

use super::command::{Command, Export, OpenKind};
use super::compare;
use super::events::AppEvent;
use super::files::{self, FileReply, PathPrompt, PromptAction, SaveRequest};
use super::job::calibration::{
    self, AdoptWork, AutoExcludeWork, CalibrationJob, CalibrationWork, RunKind,
};
use super::job::comparison::{ComparisonJob, ComparisonWork};
use super::job::{load, plan};
use super::session::Session;
use super::work::LiveRate;
use super::{WorkbenchApp, table};
use crate::side::ConfigId;
use eframe::egui;
use std::path::PathBuf;

impl WorkbenchApp {
    /// Carry out a command.
    pub fn apply(&mut self, command: Command) {
        match command {
            Command::OpenDataset(path) => self.start_load(path, self.urdf_override.clone()),
            Command::OpenUrdf(path) => match self.scene.get() {
                Some(session) => self.start_load(session.dataset.dir.clone(), Some(path)),
                // Nothing to reload: the robot is used for the next dataset.
                None => self.urdf_override = Some(path),
            },
            Command::UseDatasetRobot => match self.scene.get() {
                Some(session) => self.start_load(session.dataset.dir.clone(), None),
                None => self.urdf_override = None,
            },
            Command::ChooseFile(kind) => self.choose_file(kind),
            Command::StartCalibration => {
                if !self.jobs.is_running(CalibrationJob::lane()) {
                    self.start_calibration();
                }
            }
            Command::ToggleExclude(config) => {
                let Some(session) = self.scene.edit() else {
                    return;
                };
                match session.exclude.iter().position(|c| *c == config) {
                    Some(k) => {
                        session.exclude.remove(k);
                    }
                    None => session.exclude.push(config),
                }
                session.auto_exclusion = None;
                self.start_calibration();
            }
            Command::ClearExclusions => {
                if self.scene.get().is_none_or(|s| s.exclude.is_empty()) {
                    return;
                }
                if let Some(session) = self.scene.edit() {
                    session.exclude.clear();
                    session.auto_exclusion = None;
                }
                self.start_calibration();
            }
            Command::AutoExclude => self.start_auto_exclude(),
            Command::CancelCalibration => self.jobs.cancel(CalibrationJob::lane()),
            Command::Select {
                config,
                reveal_in_table,
            } => self.select(config, reveal_in_table),
            Command::SelectWorst => {
                if let Some(session) = self.scene.get() {
                    let worst = table::worst(session.current());
                    self.select(worst, true);
                }
            }
            Command::Export(Export::PlotPng) => self.request_screenshot(),
            Command::Export(what) => self.export(what),
            Command::ConfirmPrompt(path) => self.confirm_prompt(path),
            Command::ClosePrompt => self.prompt = None,
            Command::DismissError(k) => self.errors.dismiss(k),
            Command::ShowComparison(open) => self.compare.open = open,
            Command::StartComparison => self.start_comparison(),
            Command::CancelComparison => self.jobs.cancel(ComparisonJob::lane()),
            Command::AdoptCompared(key) => self.adopt_compared(key),
            Command::ShowImport(open) => {
                self.import.open = open;
                self.import.write_error = None;
            }
            Command::SetImportFile(slot, path) => self.import.set_file(slot, &path),
            Command::SetImportFolder(path) => self.import.out_dir = path.display().to_string(),
            Command::RefreshImport => self.refresh_import(true),
            Command::FinishImport => self.finish_import(),
            Command::ShowPlan(open) => self.plan_view.open = open,
            Command::StartPlan => {
                let target = self.plan_target();
                plan::start(&mut self.job_context(), target);
            }
            Command::SavePlan => match self.plan_view.zip() {
                Ok(bytes) => self.save(SaveRequest {
                    title: "Save plan (.zip)",
                    file_name: "plan.zip".into(),
                    filter_name: "ZIP archive",
                    extensions: &["zip"],
                    bytes,
                }),
                Err(e) => self.plan_view.error = Some(e),
            },
            Command::ShowPlannedPose(side, pose) => self.plan_view.shown[side] = pose,
            command => self.set_state(command),
        }
    }

    /// The `Set…` commands: what the views' widgets edit in place, in one go.
    fn set_state(&mut self, command: Command) {
        match command {
            Command::SetSettings(settings) => {
                if settings.method != self.settings.method {
                    self.method_picked = true;
                }
                self.settings = *settings;
            }
            Command::PickComparedMethods(keys) => {
                let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
                self.compare.pick(&keys);
            }
            Command::SetViewOptions(options) => self.viewport.options = *options,
            Command::SetCamera(camera) => self.viewport.camera = *camera,
            Command::SetAutoScale(on) => self.viewport.auto_scale = on,
            Command::SetImportInputs(inputs) => self.import.inputs = *inputs,
            Command::SetPlanInputs(inputs) => self.plan_view.inputs = *inputs,
            // Carried out by `apply`.
            _ => {}
        }
    }

    /// Load on a background task, from the app's files; on failure the error is shown and the current
    /// session stays.
    fn start_load(&mut self, dataset: PathBuf, urdf: Option<PathBuf>) {
        let files = self.input_files.clone();
        load::start(&mut self.job_context(), dataset, urdf, files);
    }

    /// Run the picked methods on the session (with the current settings' split, limits and
    /// tolerances and the session's exclusions); the last comparison is replaced as the new one's
    /// rows arrive. Not while a calibration runs (the two would share the two cores).
    fn start_comparison(&mut self) {
        let Some(session) = self.scene.get() else {
            self.errors.push("Open a dataset first.");
            return;
        };
        if self.is_calibrating() || self.is_comparing() {
            return;
        }
        if let Some(refusal) = refusal(session) {
            self.errors.push(refusal);
            return;
        }
        let entries = self.compare.picked_entries();
        if entries.is_empty() {
            self.errors.push("Pick at least one method to compare.");
            return;
        }
        let common = compare::common_settings(&session.run_settings(&self.settings));
        let work = ComparisonWork::new(session, entries, common);
        match self
            .job_context()
            .start_job("comparison", ComparisonJob, work)
        {
            Ok(()) => {
                self.compare.open = true;
                self.compare.adopted = None;
                self.compare.progress = None;
                self.status.idle("Comparing methods…");
            }
            Err(e) => self
                .errors
                .push(format!("cannot start the comparison thread: {e}")),
        }
    }

    /// Take a compared method's result as the current calibration (its figures are computed in the
    /// background, then it is shown and exported like a calibration of its own).
    fn adopt_compared(&mut self, key: &'static str) {
        let Some(session) = self.scene.get() else {
            return;
        };
        if self.is_calibrating() || self.is_comparing() {
            return;
        }
        let Some(run) = self
            .compare
            .comparison
            .as_ref()
            .and_then(|c| c.method(key))
            .and_then(|m| m.run())
        else {
            return;
        };
        let work = AdoptWork::new(session, run.result.clone());
        self.compare.adopted = Some(key);
        calibration::start_run(&mut self.job_context(), RunKind::Adopt, work);
    }

    /// Calibrate the session with the current settings and its exclusions; a running calibration is
    /// replaced (its events are ignored from now on).
    fn start_calibration(&mut self) {
        if !self.calibration_allowed() {
            return;
        }
        let Some(session) = self.scene.get() else {
            return;
        };
        let settings = session.run_settings(&self.settings);
        #[cfg_attr(not(test), expect(unused_mut))]
        let mut work =
            CalibrationWork::new(session, settings, LiveRate::for_execution(self.execution));
        #[cfg(test)]
        {
            work.panic_at_start = std::mem::take(&mut self.panic_in_next_calibration);
        }
        calibration::start_run(&mut self.job_context(), RunKind::Calibration, work);
    }

    /// Auto-exclude: the rule's calibration replaces the current one.
    fn start_auto_exclude(&mut self) {
        if !self.calibration_allowed() {
            return;
        }
        let Some(session) = self.scene.get() else {
            return;
        };
        let work = AutoExcludeWork::new(session, session.run_settings(&self.settings));
        calibration::start_run(&mut self.job_context(), RunKind::Calibration, work);
    }

    /// Select a configuration and pose its arm in it.
    fn select(&mut self, config: Option<ConfigId>, reveal_in_table: bool) {
        self.selection = config;
        if let Some(config) = config {
            self.viewport.poses[config.side] = Some(config.index);
        }
        self.scroll_table_to_selection = reveal_in_table;
    }

    fn choose_file(&mut self, kind: OpenKind) {
        if self.files.dialogs_available() {
            self.files.open(kind, self.events.sender().clone());
            return;
        }
        let suggested = match (kind, self.scene.get()) {
            (OpenKind::Dataset, Some(s)) => s.dataset.dir.join(crate::dataset::MANIFEST_FILE),
            (OpenKind::Urdf, Some(s)) => s.dataset.dir.join("robot.urdf"),
            (OpenKind::ImportFile(_) | OpenKind::ImportFolder, _) | (_, None) => {
                std::env::current_dir().unwrap_or_default()
            }
        };
        self.prompt = Some(PathPrompt::new(PromptAction::Open(kind), suggested));
    }

    /// Ask where to save: the native dialog, or the in-app path prompt without one.
    pub(super) fn save(&mut self, request: SaveRequest) {
        if self.files.dialogs_available() {
            self.files.save(request, self.events.sender().clone());
        } else {
            let suggested = std::env::current_dir()
                .unwrap_or_default()
                .join(&request.file_name);
            self.prompt = Some(PathPrompt::new(PromptAction::Save(request), suggested));
        }
    }

    fn export(&mut self, what: Export) {
        let Some(session) = self.scene.get() else {
            return;
        };
        match what.contents(session) {
            Some(Ok(bytes)) => self.save(what.save_request(bytes)),
            Some(Err(e)) => self.errors.push(format!("export: {e:#}")),
            None => {}
        }
    }

    /// "Export plots as PNG": the screenshot is taken when the next frame is painted and arrives as
    /// an event.
    fn request_screenshot(&mut self) {
        if self.scene.get().is_none() {
            return;
        }
        self.screenshot_pending = true;
        let events = self.events.sender().clone();
        self.ctx
            .send_viewport_cmd(egui::ViewportCommand::Screenshot(
                egui::ScreenshotCallback::new(move |image| {
                    events.send(AppEvent::Screenshot(image))
                }),
            ));
        self.ctx.request_repaint();
    }

    fn confirm_prompt(&mut self, path: PathBuf) {
        let Some(mut prompt) = self.prompt.take() else {
            return;
        };
        match &prompt.action {
            PromptAction::Open(kind) => self.apply(Command::open(*kind, path)),
            PromptAction::Save(request) => match files::write(&path, &request.bytes) {
                FileReply::Failed(e) => {
                    prompt.error = Some(e);
                    self.prompt = Some(prompt);
                }
                reply => self.on_file_reply(reply),
            },
        }
    }

    /// Whether there is a session the screening does not refuse; if not, the reason is shown.
    fn calibration_allowed(&mut self) -> bool {
        let reason = match self.scene.get() {
            None => "Open a dataset first.".to_string(),
            Some(session) => match refusal(session) {
                None => return true,
                Some(refusal) => refusal,
            },
        };
        self.errors.push(reason);
        false
    }
}

/// Why `dualcal calibrate` would refuse this session's data (the nominal screening's errors), if it
/// would.
fn refusal(session: &Session) -> Option<String> {
    let refusals = session.refusals();
    (!refusals.is_empty()).then(|| {
        format!(
            "calibration refused, as by dualcal calibrate: {}",
            refusals.join("; ")
        )
    })
}

/// The import view's work: its preview and its end.
impl WorkbenchApp {
    /// Preview the import again when its inputs or the robot changed (or `force`: read the files
    /// again).
    pub(super) fn refresh_import(&mut self, force: bool) {
        if !self.import.open {
            return;
        }
        let (robot, robot_path, names, positions) = match self.scene.get() {
            Some(s) => (
                s.robot.clone(),
                s.robot_source.clone(),
                s.dataset.reflector_names.to_vec(),
                s.dataset.nominal_reflectors_mm.clone(),
            ),
            None => {
                let robot = self.builtin_robot();
                let positions = crate::simulate::default_reflectors_for(&robot).to_vec();
                let names = crate::kinematics::default_reflector_names(positions.len()).to_vec();
                (robot, None, names, positions)
            }
        };
        let target = super::import::ImportTarget {
            robot: &robot,
            robot_path: robot_path.as_deref(),
            reflector_names: names,
            nominal_reflectors_mm: positions,
        };
        self.import.refresh(&*self.input_files.0, &target, force);
    }

    /// Write the previewed import — into the folder chosen, or in a browser into memory — and open
    /// it as the current dataset; on failure the view stays open with the reason.
    fn finish_import(&mut self) {
        self.import.write_error = None;
        let written = match &self.memory_files {
            Some(memory) => {
                let dir = PathBuf::from(format!("/imports/{}", self.scene.revision() + 1));
                match self.import.preview().and_then(|p| p.importable()) {
                    Some(imported) => crate::import::files_of(imported, &dir)
                        .map(|files| {
                            for (path, bytes) in files {
                                memory.insert(path, bytes);
                            }
                            dir
                        })
                        .map_err(|e| format!("{e:#}")),
                    None => Err("nothing to import: the preview shows why".to_string()),
                }
            }
            None => {
                let out = PathBuf::from(self.import.out_dir.trim());
                if out.as_os_str().is_empty() {
                    Err("choose the folder to write the dataset to".to_string())
                } else {
                    super::import::write(&self.import, &out).map(|()| out)
                }
            }
        };
        match written {
            Ok(dir) => {
                self.import.open = false;
                // The dataset names its robot (the one it was imported for).
                self.start_load(dir, None);
            }
            Err(e) => self.import.write_error = Some(e),
        }
    }
}

impl WorkbenchApp {
    /// What a plan is made for: the session's robot, reflectors, tracker and configurations (the
    /// built-in IRB 14000 with the paper's reflectors before any).
    fn plan_target(&mut self) -> super::plan_view::PlanTarget {
        match self.scene.get() {
            Some(s) => super::plan_view::PlanTarget {
                robot: s.robot.clone(),
                robot_path: s.robot_source.clone(),
                reflectors_mm: s.dataset.nominal_reflectors_mm.clone(),
                tracker: s.dataset.tracker,
                existing: crate::side::PerSide::from_fn(|side| {
                    s.dataset
                        .arm(side)
                        .measurements
                        .iter()
                        .map(|m| m.q_rad.clone())
                        .collect()
                }),
            },
            None => {
                let robot = self.builtin_robot();
                super::plan_view::PlanTarget {
                    reflectors_mm: crate::simulate::default_reflectors_for(&robot).to_vec(),
                    robot,
                    robot_path: None,
                    tracker: crate::dataset::TrackerSpec::default(),
                    existing: crate::side::PerSide::new(Vec::new(), Vec::new()),
                }
            }
        }
    }
}

impl WorkbenchApp {
    /// The built-in IRB 14000, made once (what the import and planning windows are for without a
    /// dataset).
    fn builtin_robot(&mut self) -> std::sync::Arc<crate::robot::RobotDescription> {
        self.builtin_robot
            .get_or_insert_with(|| {
                std::sync::Arc::new(crate::robot::RobotDescription::builtin_irb14000())
            })
            .clone()
    }
}
