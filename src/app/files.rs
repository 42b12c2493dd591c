//! File access behind one seam: the native build uses rfd dialogs on helper threads and atomic
//! writes; a browser build can replace [`FileAccess`] with downloads and `<input type=file>`.
//! Replies arrive on the app's event channel, drained each frame, so the UI never waits on a dialog.
//! Where no dialog is available the app asks for a path itself ([`PathPrompt`]).

use super::command::Command;
pub use super::command::{FileReply, OpenKind};
#[cfg(not(target_arch = "wasm32"))]
use super::events::AppEvent;
use super::events::EventSender;
use eframe::egui::{self, Color32, RichText};
use std::path::PathBuf;

/// A file to save: suggested name, filter and contents.
pub struct SaveRequest {
    pub title: &'static str,
    pub file_name: String,
    pub filter_name: &'static str,
    pub extensions: &'static [&'static str],
    pub bytes: Vec<u8>,
}

/// How the app reads datasets and robot descriptions, and how it asks the user for files (the
/// platform's: [`super::platform::io`]).
pub struct Io {
    /// Where datasets, URDFs and meshes are read from.
    pub files: crate::source::Files,
    /// File dialogs (or a browser's file picker and downloads).
    pub dialogs: Box<dyn FileAccess>,
    /// In a browser: the files in memory that `files` reads, where an import's dataset is written
    /// (`None`: the file system, written with atomic writes).
    pub memory: Option<crate::source::MemoryFiles>,
}

pub trait FileAccess {
    /// Whether this seam can show dialogs at all; when it cannot, the app asks for a path itself.
    fn dialogs_available(&self) -> bool {
        true
    }
    /// Ask the user for a file to open; the reply goes to `reply`.
    fn open(&self, kind: OpenKind, reply: EventSender);
    /// Ask the user where to save and write the bytes; the reply goes to `reply`.
    fn save(&self, request: SaveRequest, reply: EventSender);
    /// Files dropped on the window: the paths to open now (on the desktop, where they are), or none
    /// when the seam reads them itself and replies on `reply` later (a browser).
    fn dropped(&self, files: &[egui::DroppedFileHandle], reply: EventSender) -> Vec<PathBuf> {
        let _ = reply;
        files.iter().map(|f| f.path().to_path_buf()).collect()
    }
}

/// Native dialogs (rfd) run on a helper thread; writes are atomic.
#[cfg(not(target_arch = "wasm32"))]
pub struct NativeFiles {
    /// Never show a dialog: the app asks for paths itself (the launch options' `path_prompt`,
    /// `DUALCAL_PATH_PROMPT`).
    pub path_prompt: bool,
}

#[cfg(not(target_arch = "wasm32"))]
impl FileAccess for NativeFiles {
    /// On Linux, rfd needs the desktop portal (on the session D-Bus) or `zenity`; a bare X server
    /// (e.g. Xvfb) has neither. `path_prompt` forces the in-app path prompt.
    fn dialogs_available(&self) -> bool {
        if self.path_prompt {
            return false;
        }
        if cfg!(target_os = "linux") {
            std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some() || on_path("zenity")
        } else {
            true
        }
    }

    fn open(&self, kind: OpenKind, reply: EventSender) {
        let spawned = std::thread::Builder::new()
            .name("dualcal-open-dialog".into())
            .spawn(move || {
                let dialog = rfd::FileDialog::new();
                let picked = match kind {
                    OpenKind::Dataset => dialog
                        .set_title("Open dataset (dataset.toml)")
                        .add_filter(
                            "dualcal dataset",
                            crate::source::FileKind::DatasetManifest.extensions(),
                        )
                        .pick_file(),
                    OpenKind::Urdf => dialog
                        .set_title("Open robot description (URDF)")
                        .add_filter(
                            "URDF",
                            crate::source::FileKind::robot_extensions().as_slice(),
                        )
                        .pick_file(),
                    OpenKind::ImportFile(slot) if slot.joints => dialog
                        .set_title("Joint log (CSV, spreadsheet or ROS 2 bag)")
                        .add_filter(
                            "Joint logs",
                            &[
                                "csv", "txt", "tsv", "dat", "asc", "xlsx", "xlsm", "xls", "ods",
                                "mcap",
                            ],
                        )
                        .add_filter("Any file", &["*"])
                        .pick_file(),
                    OpenKind::ImportFile(_) => dialog
                        .set_title("Tracker export (points)")
                        .add_filter("Text and CSV", &["txt", "csv", "tsv", "dat", "asc"])
                        .add_filter("Any file", &["*"])
                        .pick_file(),
                    OpenKind::ImportFolder => dialog
                        .set_title("Folder for the imported dataset")
                        .pick_folder(),
                };
                reply.send(AppEvent::File(match picked {
                    Some(path) => FileReply::Open(kind, path),
                    None => FileReply::Cancelled,
                }));
            });
        if let Err(e) = spawned {
            eprintln!("dualcal: cannot start the file dialog: {e}");
        }
    }

    fn save(&self, request: SaveRequest, reply: EventSender) {
        let spawned = std::thread::Builder::new()
            .name("dualcal-save-dialog".into())
            .spawn(move || {
                let picked = rfd::FileDialog::new()
                    .set_title(request.title)
                    .set_file_name(&request.file_name)
                    .add_filter(request.filter_name, request.extensions)
                    .save_file();
                reply.send(AppEvent::File(match picked {
                    Some(path) => write(&path, &request.bytes),
                    None => FileReply::Cancelled,
                }));
            });
        if let Err(e) = spawned {
            eprintln!("dualcal: cannot start the file dialog: {e}");
        }
    }
}

/// Write a file atomically; the reply says how it went.
pub fn write(path: &std::path::Path, bytes: &[u8]) -> FileReply {
    match crate::output::write_atomic(path, bytes) {
        Ok(()) => FileReply::Saved(path.to_path_buf()),
        Err(e) => FileReply::Failed(format!("{}: {e}", path.display())),
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

/// What the in-app path prompt does with the path.
pub enum PromptAction {
    Open(OpenKind),
    Save(SaveRequest),
}

/// The in-app replacement for a file dialog.
pub struct PathPrompt {
    pub action: PromptAction,
    pub text: String,
    /// Why the last attempt failed.
    pub error: Option<String>,
    /// Focus the text field on the first frame.
    focused: bool,
}

impl PathPrompt {
    pub fn new(action: PromptAction, path: PathBuf) -> Self {
        Self {
            action,
            text: path.display().to_string(),
            error: None,
            focused: false,
        }
    }

    /// The prompt's window: [`Command::ConfirmPrompt`] with the typed path, or
    /// [`Command::ClosePrompt`].
    pub fn ui(&mut self, ctx: &egui::Context) -> Option<Command> {
        let (title, verb) = match &self.action {
            PromptAction::Open(OpenKind::Dataset) => ("Open dataset", "Open"),
            PromptAction::Open(OpenKind::Urdf) => ("Open robot description (URDF)", "Open"),
            PromptAction::Open(OpenKind::ImportFile(_)) => ("Import: a tracker file", "Choose"),
            PromptAction::Open(OpenKind::ImportFolder) => {
                ("Import: the dataset's folder", "Choose")
            }
            PromptAction::Save(r) => (r.title, "Save"),
        };
        let mut command = None;
        egui::Window::new(title)
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label("No file dialog is available here; type the path:");
                let r = ui.add(
                    egui::TextEdit::singleline(&mut self.text)
                        .desired_width(520.0)
                        .id_salt("path prompt"),
                );
                if !self.focused {
                    r.request_focus();
                    self.focused = true;
                }
                let entered = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                if let Some(e) = &self.error {
                    ui.label(RichText::new(e).color(Color32::from_rgb(255, 110, 100)));
                }
                ui.horizontal(|ui| {
                    if ui.button(verb).clicked() || entered {
                        command = Some(Command::ConfirmPrompt(PathBuf::from(self.text.trim())));
                    }
                    if ui.button("Cancel").clicked() {
                        command = Some(Command::ClosePrompt);
                    }
                });
            });
        command
    }
}
