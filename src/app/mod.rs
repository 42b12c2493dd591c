//! The workbench: an egui/eframe app to load a dataset, calibrate, inspect every configuration in 3D
//! and export the result.
//!
//! Layout: settings on the left, the 3D viewport in the centre, the per-configuration table on the
//! right, convergence and accuracy plots below, a status bar at the bottom. The engine runs on a
//! worker thread ([`worker`]); file dialogs go through the [`files::FileAccess`] seam.

pub mod colormap;
pub mod export;
pub mod files;
mod panels;
pub mod plots;
pub mod session;
pub mod table;
pub mod viewport;
pub mod worker;

use crate::analysis::Indicator;
use crate::dataset::Split;
use crate::side::Side;
use crate::solver::{
    CalibrationEvent, CalibrationSettings, IterationRecord, Method, QpMethod, Stage,
};
use anyhow::Context as _;
use eframe::egui::{self, Color32, RichText};
use export::{Export, encode_png, export_csv, export_params, export_urdf};
use files::{FileAccess, FileReply, NativeFiles, OpenKind, SaveRequest};
use session::Session;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, channel};
use viewport::ViewportState;
use viewport::scene::Selection;
use worker::{CalibrationJob, Outcome, WorkerMessage};

/// What the window opens with.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AppLaunch {
    /// Dataset directory or `dataset.toml`; `None` opens the bundled example.
    pub dataset: Option<PathBuf>,
    /// Robot description overriding the dataset's; `None` uses the dataset's or the built-in one.
    pub urdf: Option<PathBuf>,
}

/// The bundled example dataset, compiled into the binary (it is ours: `dualcal simulate --seed 1`).
const EXAMPLE_FILES: [(&str, &[u8]); 4] = [
    (
        "dataset.toml",
        include_bytes!("../../assets/datasets/example/dataset.toml"),
    ),
    (
        "left.csv",
        include_bytes!("../../assets/datasets/example/left.csv"),
    ),
    (
        "right.csv",
        include_bytes!("../../assets/datasets/example/right.csv"),
    ),
    (
        "truth.json",
        include_bytes!("../../assets/datasets/example/truth.json"),
    ),
];

/// The bundled example dataset: in the source tree when the binary runs from it (`cargo run`), else a
/// copy of the compiled-in files in the user's cache directory (`$XDG_CACHE_HOME/dualcal` or
/// `~/.cache/dualcal`), so an installed or moved binary opens it too.
pub fn bundled_example_path() -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    if source.join("dataset.toml").is_file() {
        return source;
    }
    let cache_root = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    // If the copy cannot be written, the source path is returned and opening it reports the error.
    unpack_example(&cache_root.join("dualcal")).unwrap_or(source)
}

/// Write the compiled-in example into `root/example-<content hash>` (files already there are left
/// alone: the directory name changes with the content) and return that directory.
pub fn unpack_example(root: &Path) -> std::io::Result<PathBuf> {
    use std::hash::{Hash, Hasher};
    // A name for this version of the example (a new toolchain may rename it: then it is unpacked again).
    let mut hasher = std::hash::DefaultHasher::new();
    EXAMPLE_FILES.hash(&mut hasher);
    let dir = root.join(format!("example-{:016x}", hasher.finish()));
    std::fs::create_dir_all(&dir)?;
    for (name, bytes) in EXAMPLE_FILES {
        let path = dir.join(name);
        if !path.exists() {
            crate::atomic::write_atomic(&path, bytes)?;
        }
    }
    Ok(dir)
}

/// Open the workbench window (blocks until it is closed).
pub fn run_native(opts: AppLaunch) -> anyhow::Result<()> {
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
        Box::new(move |cc| Ok(Box::new(WorkbenchApp::new(cc, opts)))),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the workbench window: {e}"))
}

/// Tabs of the bottom area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlotTab {
    Convergence,
    Accuracy,
    Summary,
}

/// What the status bar says.
#[derive(Clone, Debug, PartialEq)]
enum Status {
    Idle(String),
    Running {
        stage: Option<Stage>,
        iteration: usize,
    },
}

/// What the in-app path prompt does with the path.
enum PromptAction {
    Open(OpenKind),
    Save(SaveRequest),
}

/// The in-app replacement for a file dialog.
struct PathPrompt {
    action: PromptAction,
    text: String,
    error: Option<String>,
    /// Focus the text field on the first frame.
    focused: bool,
}

/// A dataset being loaded on a helper thread.
struct LoadJob {
    receiver: Receiver<Result<(Session, f64), String>>,
    /// The robot override to restore if loading fails (when the load was a URDF change).
    previous_override: Option<Option<PathBuf>>,
}

/// How often to print frame statistics (`DUALCAL_FRAME_STATS=1`).
const FRAME_STATS_WINDOW: usize = 30;

struct FrameStats {
    last: Option<std::time::Instant>,
    /// Time between frames (everything: egui, our render pass, egui's, presenting).
    samples_ms: Vec<f64>,
    /// Time spent building the UI on the CPU.
    ui_ms: Vec<f64>,
}

/// The workbench application.
pub struct WorkbenchApp {
    session: Option<Session>,
    /// Bumped whenever the session or its models change (the viewport rebuilds its scene).
    generation: u64,
    settings: CalibrationSettings,
    job: Option<CalibrationJob>,
    /// Iterations of the current (or last) run.
    history: Vec<IterationRecord>,
    status: Status,
    errors: Vec<String>,
    selection: Selection,
    scroll_table_to_selection: bool,
    viewport: ViewportState,
    table: table::TableState,
    plot_tab: PlotTab,
    plot_stage: Stage,
    figure: Indicator,
    figure_split: Split,
    files: Box<dyn FileAccess>,
    file_sender: Sender<FileReply>,
    file_receiver: Receiver<FileReply>,
    /// Rect of the plot area, for "Export plots as PNG".
    plot_rect: Option<egui::Rect>,
    screenshot_pending: bool,
    shot_sender: Sender<std::sync::Arc<egui::ColorImage>>,
    shot_receiver: Receiver<std::sync::Arc<egui::ColorImage>>,
    urdf_override: Option<PathBuf>,
    loading: Option<LoadJob>,
    prompt: Option<PathPrompt>,
    /// Side and bottom panels shown (off: the viewport fills the window).
    panels_visible: bool,
    /// Wakes the UI from helper threads (None before the first frame in some hosts).
    repaint: Option<egui::Context>,
    frame_stats: Option<FrameStats>,
}

impl WorkbenchApp {
    /// The app as `dualcal gui` opens it (4× MSAA in the viewport).
    pub fn new(cc: &eframe::CreationContext<'_>, launch: AppLaunch) -> Self {
        Self::with_msaa(cc, launch, true)
    }

    /// Like [`new`](Self::new); `msaa = false` gives pixel-stable snapshots in tests.
    pub fn with_msaa(cc: &eframe::CreationContext<'_>, launch: AppLaunch, msaa: bool) -> Self {
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        // 4× MSAA, except on a software renderer (lavapipe, llvmpipe) where it costs more than it
        // gives; `DUALCAL_MSAA=1` / `=4` override.
        let software = cc
            .wgpu_render_state
            .as_ref()
            .is_some_and(|rs| rs.adapter.get_info().device_type == eframe::wgpu::DeviceType::Cpu);
        let samples = match std::env::var("DUALCAL_MSAA").ok().as_deref() {
            Some("1") => 1,
            Some("4") => 4,
            _ if msaa && !software => 4,
            _ => 1,
        };
        viewport::install_gpu(cc.wgpu_render_state.as_ref(), samples);
        let (file_sender, file_receiver) = channel();
        let (shot_sender, shot_receiver) = channel();
        let mut app = Self {
            session: None,
            generation: 0,
            settings: CalibrationSettings::default(),
            job: None,
            history: Vec::new(),
            status: Status::Idle("Ready.".into()),
            errors: Vec::new(),
            selection: None,
            scroll_table_to_selection: false,
            viewport: ViewportState::default(),
            table: table::TableState::default(),
            plot_tab: PlotTab::Convergence,
            plot_stage: Stage::Arm(Side::Left),
            figure: Indicator::RelativePosition(Side::Left),
            figure_split: Split::Ver,
            files: Box::new(NativeFiles),
            file_sender,
            file_receiver,
            plot_rect: None,
            screenshot_pending: false,
            shot_sender,
            shot_receiver,
            urdf_override: launch.urdf.clone(),
            loading: None,
            prompt: None,
            panels_visible: true,
            repaint: Some(cc.egui_ctx.clone()),
            frame_stats: std::env::var_os("DUALCAL_FRAME_STATS").map(|_| FrameStats {
                last: None,
                samples_ms: Vec::new(),
                ui_ms: Vec::new(),
            }),
        };
        let dataset = launch.dataset.unwrap_or_else(bundled_example_path);
        app.open_dataset(&dataset);
        app
    }

    // ---- state access (tests, embedding) -------------------------------------------------------

    pub fn session(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    pub fn is_calibrating(&self) -> bool {
        self.job.is_some()
    }

    /// Error messages currently shown.
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    pub fn selection(&self) -> Selection {
        self.selection
    }

    pub fn history(&self) -> &[IterationRecord] {
        &self.history
    }

    pub fn settings_mut(&mut self) -> &mut CalibrationSettings {
        &mut self.settings
    }

    pub fn viewport(&self) -> &ViewportState {
        &self.viewport
    }

    /// The measurement index arm `side_index` (0 left, 1 right) is drawn in.
    pub fn viewport_pose(&self, side_index: usize) -> Option<usize> {
        self.viewport.poses.get(side_index).copied().flatten()
    }

    /// The viewport's camera and display options.
    pub fn viewport_mut(&mut self) -> &mut ViewportState {
        &mut self.viewport
    }

    /// Show or hide everything but the viewport (for snapshots and presentations).
    pub fn set_panels_visible(&mut self, visible: bool) {
        self.panels_visible = visible;
    }

    /// Replace the file-dialog seam (a browser build, or tests).
    pub fn set_file_access(&mut self, files: Box<dyn FileAccess>) {
        self.files = files;
    }

    // ---- actions -------------------------------------------------------------------------------

    /// Load a dataset on a helper thread; on failure the error is shown and the current session
    /// stays.
    pub fn open_dataset(&mut self, path: &Path) {
        self.start_load(path, None);
    }

    /// Use another robot description for the current dataset (and later ones).
    pub fn open_urdf(&mut self, path: &Path) {
        let previous = self.urdf_override.replace(path.to_path_buf());
        if let Some(dir) = self.session.as_ref().map(|s| s.dataset.dir.clone()) {
            self.start_load(&dir, Some(previous));
        }
    }

    fn start_load(&mut self, path: &Path, previous_override: Option<Option<PathBuf>>) {
        let (sender, receiver) = channel();
        let dataset = path.to_path_buf();
        let urdf = self.urdf_override.clone();
        let repaint = self.repaint.clone();
        let spawned = std::thread::Builder::new()
            .name("dualcal-load".into())
            .spawn(move || {
                let started = std::time::Instant::now();
                let result = Session::load(&dataset, urdf.as_deref())
                    .with_context(|| format!("cannot open dataset {}", dataset.display()))
                    .map(|s| (s, started.elapsed().as_secs_f64()))
                    .map_err(|e| format!("{e:#}"));
                let _ = sender.send(result);
                if let Some(ctx) = repaint {
                    ctx.request_repaint();
                }
            });
        match spawned {
            Ok(_) => {
                self.status = Status::Idle(format!("Loading {}…", path.display()));
                self.loading = Some(LoadJob {
                    receiver,
                    previous_override,
                });
            }
            Err(e) => self.errors.push(format!("cannot start loading: {e}")),
        }
    }

    /// Whether a dataset is being loaded.
    pub fn is_loading(&self) -> bool {
        self.loading.is_some()
    }

    fn poll_loading(&mut self) {
        let Some(job) = &self.loading else {
            return;
        };
        let result = match job.receiver.try_recv() {
            Ok(r) => r,
            Err(std::sync::mpsc::TryRecvError::Empty) => return,
            Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                Err("the loading thread stopped unexpectedly".into())
            }
        };
        let Some(job) = self.loading.take() else {
            return;
        };
        match result {
            Ok((session, secs)) => {
                self.job = None;
                self.history.clear();
                self.selection = None;
                self.viewport.poses = [Some(0), Some(0)];
                self.viewport.auto_scale(&session);
                let d = &session.dataset;
                self.status = Status::Idle(format!(
                    "Loaded {} ({} left + {} right configurations) in {secs:.2} s.",
                    d.dir.display(),
                    d.arms.left.measurements.len(),
                    d.arms.right.measurements.len(),
                ));
                self.errors
                    .extend(session.robot.warnings.iter().map(|w| format!("robot: {w}")));
                self.session = Some(session);
                self.generation += 1;
            }
            Err(e) => {
                if let Some(previous) = job.previous_override {
                    self.urdf_override = previous;
                }
                self.status = Status::Idle("Loading failed; the previous dataset stays.".into());
                self.errors.push(e);
            }
        }
    }

    /// Start a calibration of the current session with the current settings.
    pub fn start_calibration(&mut self, ctx: &egui::Context) {
        if self.job.is_some() {
            return;
        }
        let Some(session) = &self.session else {
            self.errors.push("Open a dataset first.".into());
            return;
        };
        let ctx = ctx.clone();
        match CalibrationJob::spawn(
            session.dataset.clone(),
            session.nominal.model.clone(),
            self.settings.clone(),
            session.body_from_left_base(),
            move || ctx.request_repaint(),
        ) {
            Ok(job) => {
                self.history.clear();
                self.status = Status::Running {
                    stage: None,
                    iteration: 0,
                };
                self.job = Some(job);
            }
            Err(e) => self
                .errors
                .push(format!("cannot start the calibration thread: {e}")),
        }
    }

    pub fn cancel_calibration(&mut self) {
        if let Some(job) = &mut self.job {
            job.cancel();
        }
    }

    fn select(&mut self, selection: Selection, from_viewport: bool) {
        self.selection = selection;
        if let Some((side, index)) = selection {
            self.viewport.poses[viewport::scene::side_index(side)] = Some(index);
        }
        self.scroll_table_to_selection = from_viewport;
    }

    /// Select the configuration with the worst |Δd| of the current model.
    pub fn select_worst(&mut self) {
        if let Some(session) = &self.session {
            let worst = table::worst(session.current());
            self.select(worst, true);
        }
    }

    fn poll_worker(&mut self) {
        let Some(job) = &mut self.job else {
            return;
        };
        let started = job.started;
        let cancel_requested = job.cancel_requested;
        for message in job.drain() {
            match message {
                WorkerMessage::Progress(CalibrationEvent::StageStarted { stage, .. }) => {
                    self.status = Status::Running {
                        stage: Some(stage),
                        iteration: 0,
                    };
                    self.plot_stage = stage;
                }
                WorkerMessage::Progress(CalibrationEvent::Iteration(record)) => {
                    self.status = Status::Running {
                        stage: Some(record.stage),
                        iteration: record.iteration,
                    };
                    self.history.push(record);
                }
                WorkerMessage::Progress(CalibrationEvent::StageFinished { .. }) => {}
                WorkerMessage::Finished(Outcome::Calibrated(calibrated)) => {
                    let secs = started.elapsed().as_secs_f64();
                    let terms: Vec<String> = calibrated
                        .result
                        .stages
                        .iter()
                        .map(|s| format!("{}: {} after {}", s.stage, s.termination, s.iterations))
                        .collect();
                    let advice: String = calibrated
                        .result
                        .warnings()
                        .iter()
                        .map(|w| format!(" Warning: {w}."))
                        .collect();
                    // The solver's own history is complete even if progress events were dropped.
                    self.history = calibrated.result.history.clone();
                    if let Some(session) = &mut self.session {
                        session.calibrated = Some(*calibrated);
                        self.viewport.auto_scale(session);
                    }
                    self.generation += 1;
                    self.status = Status::Idle(format!(
                        "Calibration done in {secs:.1} s ({}).{advice}",
                        terms.join(", ")
                    ));
                }
                WorkerMessage::Finished(Outcome::Cancelled) => {
                    let latency = cancel_requested
                        .map(|t| format!(" {:.0} ms after Cancel", t.elapsed().as_secs_f64() * 1e3))
                        .unwrap_or_default();
                    self.status = Status::Idle(format!(
                        "Calibration cancelled{latency}; the previous result is kept."
                    ));
                }
                WorkerMessage::Finished(Outcome::Failed(message)) => {
                    self.status =
                        Status::Idle("Calibration failed; the previous result is kept.".into());
                    self.errors.push(format!("calibration: {message}"));
                }
            }
        }
        if self.job.as_ref().is_some_and(|j| j.finished) {
            self.job = None;
        }
    }

    fn poll_files(&mut self, ctx: &egui::Context) {
        while let Ok(reply) = self.file_receiver.try_recv() {
            match reply {
                FileReply::Open(OpenKind::Dataset, path) => self.open_dataset(&path),
                FileReply::Open(OpenKind::Urdf, path) => self.open_urdf(&path),
                FileReply::Saved(path) => {
                    self.status = Status::Idle(format!("Saved {}.", path.display()));
                }
                FileReply::Failed(e) => self.errors.push(format!("save failed: {e}")),
                FileReply::Cancelled => {}
            }
        }
        // Drag and drop: a URDF replaces the robot, anything else is taken as a dataset.
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        for path in dropped {
            let is_urdf = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
            if is_urdf {
                self.open_urdf(&path);
            } else {
                self.open_dataset(&path);
            }
        }
        // A requested screenshot of the plots. Keep polling while it is pending: the callback fires
        // mid-paint, when a repaint request from it can be lost.
        if self.screenshot_pending {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
        if self.screenshot_pending
            && let Ok(image) = self.shot_receiver.try_recv()
        {
            self.screenshot_pending = false;
            let ppp = ctx.pixels_per_point();
            let region = self
                .plot_rect
                .map_or_else(|| (*image).clone(), |r| image.region(&r, Some(ppp)));
            match encode_png(&region) {
                Ok(bytes) => self.save(SaveRequest {
                    title: "Export plots as PNG",
                    file_name: "dualcal-plots.png".into(),
                    filter_name: "PNG image",
                    extensions: &["png"],
                    bytes,
                }),
                Err(e) => self.errors.push(format!("plot export: {e}")),
            }
        }
    }

    /// Ask for a file to open: the native dialog, or the in-app path prompt without one.
    fn open_dialog(&mut self, kind: OpenKind) {
        if self.files.dialogs_available() {
            self.files.open(kind, self.file_sender.clone());
        } else {
            let text = match (kind, &self.session) {
                (OpenKind::Dataset, Some(s)) => s.dataset.dir.join("dataset.toml"),
                (OpenKind::Urdf, Some(s)) => s.dataset.dir.join("robot.urdf"),
                (_, None) => std::env::current_dir().unwrap_or_default(),
            };
            self.prompt = Some(PathPrompt {
                action: PromptAction::Open(kind),
                text: text.display().to_string(),
                error: None,
                focused: false,
            });
        }
    }

    /// Ask where to save: the native dialog, or the in-app path prompt without one.
    fn save(&mut self, request: SaveRequest) {
        if self.files.dialogs_available() {
            self.files.save(request, self.file_sender.clone());
        } else {
            let dir = std::env::current_dir().unwrap_or_default();
            self.prompt = Some(PathPrompt {
                text: dir.join(&request.file_name).display().to_string(),
                action: PromptAction::Save(request),
                error: None,
                focused: false,
            });
        }
    }

    /// The in-app path prompt (used where no native file dialog is available).
    fn path_prompt_ui(&mut self, ctx: &egui::Context) {
        let Some(prompt) = &mut self.prompt else {
            return;
        };
        let (title, verb) = match &prompt.action {
            PromptAction::Open(OpenKind::Dataset) => ("Open dataset", "Open"),
            PromptAction::Open(OpenKind::Urdf) => ("Open robot description (URDF)", "Open"),
            PromptAction::Save(r) => (r.title, "Save"),
        };
        let mut done = false;
        let mut confirmed = false;
        egui::Window::new(title)
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label("No file dialog is available here; type the path:");
                let r = ui.add(
                    egui::TextEdit::singleline(&mut prompt.text)
                        .desired_width(520.0)
                        .id_salt("path prompt"),
                );
                if !prompt.focused {
                    r.request_focus();
                    prompt.focused = true;
                }
                if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                    confirmed = true;
                }
                if let Some(e) = &prompt.error {
                    ui.label(RichText::new(e).color(Color32::from_rgb(255, 110, 100)));
                }
                ui.horizontal(|ui| {
                    if ui.button(verb).clicked() {
                        confirmed = true;
                    }
                    if ui.button("Cancel").clicked() {
                        done = true;
                    }
                });
            });
        if confirmed {
            let path = PathBuf::from(prompt.text.trim());
            match &prompt.action {
                PromptAction::Open(kind) => {
                    let _ = self.file_sender.send(FileReply::Open(*kind, path));
                    done = true;
                }
                PromptAction::Save(request) => {
                    match crate::atomic::write_atomic(&path, &request.bytes) {
                        Ok(()) => {
                            let _ = self.file_sender.send(FileReply::Saved(path));
                            done = true;
                        }
                        Err(e) => prompt.error = Some(format!("{}: {e}", path.display())),
                    }
                }
            }
        }
        if done {
            self.prompt = None;
        }
    }

    fn export(&mut self, what: Export, ctx: &egui::Context) {
        let Some(session) = &self.session else {
            return;
        };
        let result: anyhow::Result<SaveRequest> = match what {
            Export::Params => {
                let Some(cal) = &session.calibrated else {
                    return;
                };
                export_params(session, cal).map(|bytes| SaveRequest {
                    title: "Export parameters (dualcal-params/1)",
                    file_name: "params.json".into(),
                    filter_name: "JSON",
                    extensions: &["json"],
                    bytes,
                })
            }
            Export::Urdf => {
                let Some(cal) = &session.calibrated else {
                    return;
                };
                export_urdf(session, cal).map(|bytes| SaveRequest {
                    title: "Export calibrated URDF",
                    file_name: "calibrated.urdf".into(),
                    filter_name: "URDF",
                    extensions: &["urdf"],
                    bytes,
                })
            }
            Export::Csv => export_csv(session).map(|bytes| SaveRequest {
                title: "Export per-configuration errors (CSV)",
                file_name: "configurations.csv".into(),
                filter_name: "CSV",
                extensions: &["csv"],
                bytes,
            }),
            Export::PlotPng => {
                self.screenshot_pending = true;
                let sender = self.shot_sender.clone();
                let repaint = ctx.clone();
                ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(
                    egui::ScreenshotCallback::new(move |image| {
                        let _ = sender.send(image);
                        repaint.request_repaint();
                    }),
                ));
                // The screenshot is taken when the next frame is painted.
                ctx.request_repaint();
                return;
            }
        };
        match result {
            Ok(request) => self.save(request),
            Err(e) => self.errors.push(format!("export: {e:#}")),
        }
    }

    fn record_frame_time(&mut self, ctx: &egui::Context) {
        let Some(stats) = &mut self.frame_stats else {
            return;
        };
        let now = std::time::Instant::now();
        if let Some(last) = stats.last {
            stats.samples_ms.push((now - last).as_secs_f64() * 1e3);
        }
        stats.last = Some(now);
        if stats.samples_ms.len() >= FRAME_STATS_WINDOW {
            let mut s = std::mem::take(&mut stats.samples_ms);
            s.sort_by(f64::total_cmp);
            let mean = s.iter().sum::<f64>() / s.len() as f64;
            let p95 = s[(s.len() * 95 / 100).min(s.len() - 1)];
            let ui = std::mem::take(&mut stats.ui_ms);
            let ui_mean = ui.iter().sum::<f64>() / ui.len().max(1) as f64;
            eprintln!(
                "frame time over {} frames: mean {mean:.1} ms, p95 {p95:.1} ms, max {:.1} ms (UI build on the CPU: mean {ui_mean:.1} ms){}",
                s.len(),
                s[s.len() - 1],
                if self.job.is_some() {
                    " [calibrating]"
                } else {
                    ""
                }
            );
        }
        ctx.request_repaint();
    }
}

impl eframe::App for WorkbenchApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.poll_loading();
        self.poll_worker();
        self.poll_files(ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.record_frame_time(ui.ctx());
        let ui_started = std::time::Instant::now();
        if self.panels_visible {
            self.panels_ui(ui);
        }
        self.path_prompt_ui(&ui.ctx().clone());
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                let response = self.viewport.ui(
                    ui,
                    frame,
                    self.session.as_ref(),
                    self.generation,
                    self.selection,
                );
                if let Some(sel) = response.clicked {
                    self.select(sel, true);
                }
            });
        if let Some(stats) = &mut self.frame_stats {
            stats.ui_ms.push(ui_started.elapsed().as_secs_f64() * 1e3);
        }
    }
}
