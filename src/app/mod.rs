//! The workbench: an egui/eframe app to load a dataset, calibrate, inspect every configuration in 3D
//! and export the result.
//!
//! Layout: settings on the left, the 3D viewport in the centre, the per-configuration table on the
//! right, convergence and accuracy plots below, a status bar at the bottom.
//!
//! Each frame: [`logic`](eframe::App::logic) drains the one event channel ([`events`]) that the
//! background tasks ([`task`]: loading, calibrating), file dialogs and screenshots report to; then the
//! panels and the viewport are drawn and return [`Command`]s, applied in one place
//! ([`WorkbenchApp::apply`], in [`apply`]). Background work runs as jobs ([`job`]), one file each.

mod apply;
pub mod colormap;
pub mod command;
pub mod compare;
pub mod events;
mod example;
// The encoder is build.rs's (it includes the file), the decoder the browser's modules'.
#[cfg(any(feature = "web-fonts", test))]
#[allow(dead_code)]
mod example_codec;
pub mod export;
pub mod files;
mod frame_stats;
pub mod import;
pub mod job;
mod launch;
mod panels;
pub mod plan_view;
pub mod platform;
pub mod plots;
pub mod scene;
pub mod session;
mod status;
pub mod table;
pub mod task;
#[cfg(test)]
mod tests;
pub mod uploads;
pub mod viewport;
#[cfg(target_arch = "wasm32")]
pub mod web;
pub mod work;

pub use command::Command;
pub use example::{bundled_example_path, unpack_example};
pub use launch::LaunchOptions;

use crate::side::{ConfigId, Side};
use crate::solver::{CalibrationSettings, IterationRecord};
use crate::source::Files;
use eframe::egui;
use events::{AppEvent, EventChannel};
use files::{FileAccess, FileReply, PathPrompt};
use frame_stats::FrameStats;
use job::calibration::CalibrationJob;
use job::comparison::ComparisonJob;
use job::load::LoadJob;
use job::meshes::MeshJob;
use job::{JobContext, Jobs};
use panels::PlotsView;
use scene::Scene;
use session::Session;
use status::{Errors, RunTiming, StatusLine, StatusReport};
use std::path::PathBuf;
use task::{Execution, FrameBudget};
use viewport::ViewportState;

/// What the window opens with.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AppLaunch {
    /// Dataset directory or `dataset.toml`; `None` opens the bundled example.
    pub dataset: Option<PathBuf>,
    /// Robot description overriding the dataset's; `None` uses the dataset's or the built-in one.
    pub urdf: Option<PathBuf>,
}

/// Open the workbench window (blocks until it is closed).
#[cfg(not(target_arch = "wasm32"))]
pub fn run_native(opts: AppLaunch, launch_options: LaunchOptions) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("dualcal workbench")
            .with_inner_size([1400.0, 900.0])
            .with_min_inner_size([900.0, 600.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    eframe::run_native(
        "dualcal workbench",
        options,
        Box::new(move |cc| {
            Ok(Box::new(WorkbenchApp::with_options(
                cc,
                opts,
                launch_options,
            )))
        }),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the workbench window: {e}"))
}

/// The workbench application.
pub struct WorkbenchApp {
    ctx: egui::Context,
    /// The session, changed only through its one mutator ([`Scene::edit`], [`Scene::replace`]: the
    /// viewport rebuilds its scene when the revision they bump changes).
    scene: Scene,
    settings: CalibrationSettings,
    /// The robot description used instead of the dataset's (set by a successful "Open URDF").
    urdf_override: Option<PathBuf>,
    events: EventChannel,
    execution: Execution,
    /// The background jobs running (loading, meshes, calibrating, comparing).
    jobs: Jobs,
    /// The comparison view.
    compare: compare::CompareView,
    status: StatusLine,
    /// Has the user picked the step-1 method (else it follows each dataset's default)?
    method_picked: bool,
    errors: Errors,
    selection: Option<ConfigId>,
    scroll_table_to_selection: bool,
    viewport: ViewportState,
    table: table::TableState,
    plots: PlotsView,
    files: Box<dyn FileAccess>,
    /// Where datasets and robots are read from (the file system; in a browser, files in memory).
    input_files: Files,
    /// In a browser: the memory `input_files` reads, where an import's dataset is written.
    memory_files: Option<crate::source::MemoryFiles>,
    /// The import view (tracker exports and joint logs to a dataset, with a live preview).
    import: import::ImportView,
    /// The planning view (`dualcal plan` in a window, the plan drawn in 3D).
    plan_view: plan_view::PlanView,
    /// The built-in robot, made when the import view needs it without a session.
    builtin_robot: Option<std::sync::Arc<crate::robot::RobotDescription>>,
    /// The GPU adapter (name and backend), for the status a browser page publishes.
    renderer: String,
    frame_budget: FrameBudget,
    last_run: Option<RunTiming>,
    /// The status last published to the page (see [`platform::publish_status`]).
    published_status: String,
    prompt: Option<PathPrompt>,
    screenshot_pending: bool,
    /// Side and bottom panels shown (off: the viewport fills the window).
    panels_visible: bool,
    frame_stats: Option<FrameStats>,
    /// Fault injection for tests: the next calibration worker panics.
    #[cfg(test)]
    panic_in_next_calibration: bool,
}

impl WorkbenchApp {
    /// The app as `dualcal gui` opens it with the default launch options (4× MSAA in the viewport).
    pub fn new(cc: &eframe::CreationContext<'_>, launch: AppLaunch) -> Self {
        Self::with_options(cc, launch, LaunchOptions::default())
    }

    /// The app with the launch `options` (`src/main.rs` reads them from the environment; tests force
    /// one sample, no MSAA, for pixel-stable snapshots).
    pub fn with_options(
        cc: &eframe::CreationContext<'_>,
        launch: AppLaunch,
        options: LaunchOptions,
    ) -> Self {
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        // 4× MSAA, except on a software renderer (lavapipe, llvmpipe) where it costs more than it
        // gives; the launch options may force a count.
        let adapter = cc
            .wgpu_render_state
            .as_ref()
            .map(|rs| rs.adapter.get_info());
        // A browser's software WebGL2 (SwiftShader) reports no CPU device type.
        let software = adapter.as_ref().is_some_and(|a| {
            a.device_type == eframe::wgpu::DeviceType::Cpu
                || a.name.to_ascii_lowercase().contains("swiftshader")
        });
        let renderer = adapter.map_or_else(
            || "none".to_string(),
            |a| format!("{:?}: {}", a.backend, a.name),
        );
        platform::init_context(&cc.egui_ctx);
        let io = platform::io(&cc.egui_ctx, &options);
        viewport::install_gpu(cc.wgpu_render_state.as_ref(), options.samples(software));
        let mut viewport = ViewportState::default();
        viewport.software_renderer = software;
        if let Some(detail) = options.mesh_detail {
            viewport.options.mesh_detail = detail;
        }
        let mut app = Self {
            ctx: cc.egui_ctx.clone(),
            scene: Scene::default(),
            settings: CalibrationSettings::default(),
            urdf_override: launch.urdf,
            events: EventChannel::new(Some(cc.egui_ctx.clone())),
            execution: Execution::default(),
            jobs: Jobs::default(),
            compare: compare::CompareView::default(),
            status: StatusLine::new("Ready."),
            method_picked: false,
            errors: Errors::default(),
            selection: None,
            scroll_table_to_selection: false,
            viewport,
            table: table::TableState::default(),
            plots: PlotsView::default(),
            files: io.dialogs,
            input_files: io.files,
            memory_files: io.memory,
            import: import::ImportView::default(),
            plan_view: plan_view::PlanView::default(),
            builtin_robot: None,
            renderer,
            frame_budget: platform::frame_budget(),
            last_run: None,
            published_status: String::new(),
            prompt: None,
            screenshot_pending: false,
            panels_visible: true,
            frame_stats: options.frame_stats.then(FrameStats::default),
            #[cfg(test)]
            panic_in_next_calibration: false,
        };
        let dataset = launch.dataset.unwrap_or_else(platform::example_dataset);
        app.apply(Command::OpenDataset(dataset));
        app
    }

    // ---- state access (tests, embedding) -------------------------------------------------------

    pub fn session(&self) -> Option<&Session> {
        self.scene.get()
    }

    /// Whether a dataset is being loaded.
    pub fn is_loading(&self) -> bool {
        self.jobs.is_running(LoadJob::lane())
    }

    /// Whether the robot's meshes are being loaded.
    pub fn is_loading_meshes(&self) -> bool {
        self.jobs.is_running(MeshJob::lane())
    }

    pub fn is_calibrating(&self) -> bool {
        self.jobs.is_running(CalibrationJob::lane())
    }

    /// Whether a comparison of methods is running.
    pub fn is_comparing(&self) -> bool {
        self.jobs.is_running(ComparisonJob::lane())
    }

    // ---- the jobs' view of the app ---------------------------------------------------------------

    /// What a job may change ([`JobContext`]), lent for one of its events or to start one.
    fn job_context(&mut self) -> JobContext<'_> {
        JobContext {
            status: &mut self.status,
            errors: &mut self.errors,
            scene: &mut self.scene,
            settings: &mut self.settings,
            method_picked: self.method_picked,
            viewport: &mut self.viewport,
            plot_stage: &mut self.plots.stage,
            compare: &mut self.compare,
            plan_view: &mut self.plan_view,
            selection: &mut self.selection,
            urdf_override: &mut self.urdf_override,
            last_run: &mut self.last_run,
            jobs: &mut self.jobs,
            events: self.events.sender(),
            execution: self.execution,
        }
    }

    /// The comparison view: the methods picked, the last comparison.
    pub fn compare_view(&self) -> &compare::CompareView {
        &self.compare
    }

    /// The planning view: its inputs, the plan, the pose shown.
    pub fn plan_view(&self) -> &plan_view::PlanView {
        &self.plan_view
    }

    /// The import view: its inputs and preview.
    pub fn import_view(&self) -> &import::ImportView {
        &self.import
    }

    /// Error messages currently shown.
    pub fn errors(&self) -> &[String] {
        self.errors.list()
    }

    pub fn selection(&self) -> Option<ConfigId> {
        self.selection
    }

    /// The convergence history shown: the running calibration's iterations so far, else the
    /// session's calibration's ([`job::calibration::history`]).
    pub fn history(&self) -> &[IterationRecord] {
        job::calibration::history(&self.jobs, self.scene.get())
    }

    /// The state as JSON, as a browser page publishes it ([`status`]).
    pub fn status_json(&self) -> serde_json::Value {
        StatusReport {
            loading: self.is_loading(),
            calibrating: self.is_calibrating(),
            status: self.status.get(),
            errors: self.errors.list(),
            renderer: &self.renderer,
            iterations: self.history().len(),
            session: self.scene.get(),
            last_run: self.last_run,
        }
        .json()
    }

    /// Publish the state when it changed.
    fn publish_status(&mut self) {
        let text = self.status_json().to_string();
        if text != self.published_status {
            platform::publish_status(&text);
            self.published_status = text;
        }
    }

    /// Run background tasks on threads (native) or stepped in frames (as in a browser).
    pub fn set_execution(&mut self, execution: Execution) {
        self.execution = execution;
    }

    pub fn settings(&self) -> &CalibrationSettings {
        &self.settings
    }

    pub fn viewport(&self) -> &ViewportState {
        &self.viewport
    }

    /// The measurement index the `side` arm is drawn in (`None`: home pose).
    pub fn viewport_pose(&self, side: Side) -> Option<usize> {
        self.viewport.poses[side]
    }

    /// Show or hide everything but the viewport (for snapshots and presentations).
    pub fn set_panels_visible(&mut self, visible: bool) {
        self.panels_visible = visible;
    }

    /// Replace the file-dialog seam (a browser build, or tests).
    pub fn set_file_access(&mut self, files: Box<dyn FileAccess>) {
        self.files = files;
    }

    /// Fault injection for tests: the next calibration's worker panics in its first step (a bug in
    /// the engine, as the workbench would meet it).
    #[cfg(test)]
    fn inject_panic_in_next_calibration(&mut self) {
        self.panic_in_next_calibration = true;
    }

    // ---- events ----------------------------------------------------------------------------------

    /// Handle everything the tasks, dialogs and screenshots reported since the last frame, and
    /// files dropped on the window.
    fn poll_events(&mut self) {
        for event in self.events.drain() {
            match event {
                AppEvent::Task(id, report) => {
                    job::on_task_report(&mut self.job_context(), id, report)
                }
                AppEvent::File(reply) => self.on_file_reply(reply),
                AppEvent::Screenshot(image) => self.on_screenshot(&image),
            }
        }
        // A robot description (a `.urdf`; a `.xacro` too, to be told how to expand it) replaces the
        // robot, anything else is taken as a dataset. (In a browser the file seam reads dropped files
        // itself and answers with what to open.)
        let dropped_files = self.ctx.input(|i| i.raw.dropped_files.clone());
        let dropped: Vec<PathBuf> = if dropped_files.is_empty() {
            Vec::new()
        } else {
            self.files
                .dropped(&dropped_files, self.events.sender().clone())
        };
        for path in dropped {
            let is_robot = crate::source::FileKind::of(&path).is_robot();
            self.apply(if is_robot {
                Command::OpenUrdf(path)
            } else {
                Command::OpenDataset(path)
            });
        }
        // Keep polling while a screenshot is pending: its callback fires mid-paint, when a repaint
        // request from it can be lost.
        if self.screenshot_pending {
            self.ctx
                .request_repaint_after(std::time::Duration::from_millis(50));
        }
    }

    fn on_file_reply(&mut self, reply: FileReply) {
        match reply {
            FileReply::Open(kind, path) => self.apply(Command::open(kind, path)),
            FileReply::Saved(path) => self.status.idle(format!("Saved {}.", path.display())),
            FileReply::Failed(e) => self.errors.push(format!("save failed: {e}")),
            FileReply::Cancelled => {}
        }
    }

    /// The requested screenshot: save the plot area of it.
    fn on_screenshot(&mut self, image: &egui::ColorImage) {
        if !std::mem::take(&mut self.screenshot_pending) {
            return;
        }
        let region = match self.plots.rect {
            Some(rect) => image.region(&rect, Some(self.ctx.pixels_per_point())),
            None => image.clone(),
        };
        match export::encode_png(&region) {
            Ok(bytes) => self.save(export::Export::PlotPng.save_request(bytes)),
            Err(e) => self.errors.push(format!("plot export: {e}")),
        }
    }

    /// The panels around the viewport, each given the state it shows ([`panels`]): the status bar;
    /// settings on the left at full height (a long form); the plots below the viewport and the table
    /// (the histograms and the summary table need the width); the table on the right. Default sizes
    /// follow the window (1280 × 800 up to 1920 × 1080 and beyond); every panel is resizable within
    /// limits that leave the viewport a usable size.
    fn panels_ui(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let window = ui.available_size();
        let loading = self.is_loading();
        let calibrating = self.is_calibrating();
        let session = self.scene.get();
        egui::Panel::bottom("status bar").show(ui, |ui| {
            panels::StatusBar {
                errors: self.errors.list(),
                status: self.status.get(),
                loading,
                calibration: self.jobs.task(CalibrationJob::lane()),
                session,
            }
            .ui(ui, commands)
        });
        let method_before = self.settings.method;
        egui::Panel::left("settings")
            .default_size((window.x * 0.19).clamp(230.0, 300.0))
            .size_range(200.0..=(window.x * 0.3).max(240.0))
            .resizable(true)
            .show(ui, |ui| {
                // A side panel is as wide as its contents: fill it, or it shrinks to them.
                ui.set_min_width(ui.available_width());
                panels::LeftPanel {
                    session,
                    urdf_override: self.urdf_override.as_deref(),
                    loading,
                    calibrating,
                    compare_open: self.compare.open,
                    settings: &mut self.settings,
                    viewport: &mut self.viewport,
                }
                .ui(ui, commands)
            });
        if self.settings.method != method_before {
            self.method_picked = true;
        }
        if self.compare.open {
            // The comparison takes the rest of the window.
            return;
        }
        let history = job::calibration::history(&self.jobs, session);
        egui::Panel::bottom("plots")
            .default_size((window.y * 0.36).clamp(220.0, 420.0))
            .size_range(140.0..=(window.y * 0.6).max(200.0))
            .resizable(true)
            .show(ui, |ui| self.plots.ui(ui, session, history));
        egui::Panel::right("table")
            .default_size((window.x * 0.36).clamp(320.0, 480.0))
            .size_range(220.0..=(window.x * 0.4).max(260.0))
            .resizable(true)
            .show(ui, |ui| {
                ui.set_min_width(ui.available_width());
                panels::TablePanel {
                    session,
                    selection: self.selection,
                    table: &mut self.table,
                    reveal_selection: &mut self.scroll_table_to_selection,
                    loading,
                }
                .ui(ui, commands)
            });
    }

    /// Step the tasks that run in frames, within the frame's budget ([`FrameBudget`]).
    fn step_tasks_in_frame(&mut self) {
        let budget = &self.frame_budget;
        let stepped = self
            .jobs
            .step_in_frame(|| budget.next(web_time::Instant::now()));
        if stepped {
            self.ctx.request_repaint();
        }
        self.frame_budget
            .slice_done(stepped.then(web_time::Instant::now));
    }
}

impl eframe::App for WorkbenchApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        // The first frame draws before any task stepped in frames runs: in a browser the workbench
        // shows at once, and the example's load (one step, ~0.25 s) runs in the next frame instead of
        // holding the first one back (docs/performance.md, issue 18). Natively tasks run on threads.
        if ctx.cumulative_frame_nr() == 0 {
            ctx.request_repaint();
        } else {
            self.step_tasks_in_frame();
        }
        self.poll_events();
        self.refresh_import(false);
        if platform::PUBLISHES_STATUS {
            self.publish_status();
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let calibrating = self.is_calibrating();
        if let Some(stats) = &mut self.frame_stats {
            stats.frame_started(ui.ctx().cumulative_frame_nr(), calibrating);
            ui.ctx().request_repaint();
        }
        let ui_started = web_time::Instant::now();
        let mut commands = Vec::new();
        if self.panels_visible {
            self.panels_ui(ui, &mut commands);
        }
        if self.panels_visible && self.import.open {
            let state = panels::ImportContext {
                dialogs: self.files.dialogs_available(),
                in_memory: self.memory_files.is_some(),
                loading: self.jobs.is_running(LoadJob::lane()),
            };
            panels::import_ui(ui.ctx(), &mut self.import, state, &mut commands);
        }
        if self.panels_visible && self.plan_view.open {
            let state = panels::PlanContext {
                planning: self.jobs.is_running(job::plan::PlanJob::lane()),
                has_dataset: self.scene.get().is_some(),
                robot: self
                    .scene
                    .get()
                    .map_or_else(|| "the built-in IRB 14000".to_string(), |s| s.robot.name()),
            };
            panels::plan_ui(ui.ctx(), &mut self.plan_view, state, &mut commands);
        }
        if let Some(overlay) = self.plan_view.overlay_if_changed() {
            let robot = self
                .plan_view
                .result
                .as_ref()
                .map(|r| r.target.robot.clone());
            match robot {
                Some(robot) => self.viewport.set_plan(overlay, &robot),
                None => self.viewport.plan = None,
            }
        }
        if let Some(prompt) = &mut self.prompt {
            commands.extend(prompt.ui(ui.ctx()));
        }
        // X excludes (or includes again) the selected configuration, picked in the table or the view.
        if let Some(config) = self.selection
            && !ui.ctx().egui_wants_keyboard_input()
            && ui.ctx().input(|i| i.key_pressed(egui::Key::X))
        {
            commands.push(Command::ToggleExclude(config));
        }
        if self.panels_visible && self.compare.open {
            let state = panels::CompareState {
                has_session: self.scene.get().is_some(),
                comparing: self.is_comparing(),
                calibrating: self.is_calibrating(),
            };
            egui::CentralPanel::default().show(ui, |ui| {
                panels::compare_ui(ui, &mut self.compare, state, &mut commands)
            });
        } else {
            egui::CentralPanel::default()
                .frame(egui::Frame::NONE)
                .show(ui, |ui| {
                    let session = self.scene.get();
                    let clicked =
                        self.viewport
                            .ui(ui, frame, session, self.scene.revision(), self.selection);
                    commands.extend(clicked);
                });
        }
        if !commands.is_empty() {
            // Draw the new state in this frame: egui builds the UI again (with no input) instead
            // of showing this pass, so nothing is laid out a frame late.
            ui.ctx().request_discard("commands applied");
        }
        for command in commands {
            self.apply(command);
        }
        if let Some(stats) = &mut self.frame_stats {
            stats.ui_built(ui_started.elapsed().as_secs_f64() * 1e3);
        }
    }
}
