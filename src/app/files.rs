//! File access behind one seam: the native build uses rfd dialogs on helper threads and atomic
//! writes; a browser build can replace [`FileAccess`] with downloads and `<input type=file>`.
//! Replies arrive on a channel the app drains each frame, so the UI never waits on a dialog.

use std::path::PathBuf;
use std::sync::mpsc::Sender;

/// What the user wants to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpenKind {
    /// A `dataset.toml` (or its directory).
    Dataset,
    /// A robot description.
    Urdf,
}

/// The answer to a request.
#[derive(Debug)]
pub enum FileReply {
    Open(OpenKind, PathBuf),
    Saved(PathBuf),
    Failed(String),
    /// The user closed the dialog.
    Cancelled,
}

/// A file to save: suggested name, filter and contents.
pub struct SaveRequest {
    pub title: &'static str,
    pub file_name: String,
    pub filter_name: &'static str,
    pub extensions: &'static [&'static str],
    pub bytes: Vec<u8>,
}

pub trait FileAccess {
    /// Whether this seam can show dialogs at all; when it cannot, the app asks for a path itself.
    fn dialogs_available(&self) -> bool {
        true
    }
    /// Ask the user for a file to open; the reply goes to `reply`.
    fn open(&self, kind: OpenKind, reply: Sender<FileReply>);
    /// Ask the user where to save and write the bytes; the reply goes to `reply`.
    fn save(&self, request: SaveRequest, reply: Sender<FileReply>);
}

/// Native dialogs (rfd) run on a helper thread; writes are atomic.
pub struct NativeFiles;

impl FileAccess for NativeFiles {
    /// On Linux, rfd needs the desktop portal (on the session D-Bus) or `zenity`; a bare X server
    /// (e.g. Xvfb) has neither. `DUALCAL_PATH_PROMPT=1` forces the in-app path prompt.
    fn dialogs_available(&self) -> bool {
        if std::env::var_os("DUALCAL_PATH_PROMPT").is_some() {
            return false;
        }
        if cfg!(target_os = "linux") {
            std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some() || on_path("zenity")
        } else {
            true
        }
    }

    fn open(&self, kind: OpenKind, reply: Sender<FileReply>) {
        let spawned = std::thread::Builder::new()
            .name("dualcal-open-dialog".into())
            .spawn(move || {
                let dialog = rfd::FileDialog::new();
                let picked = match kind {
                    OpenKind::Dataset => dialog
                        .set_title("Open dataset (dataset.toml)")
                        .add_filter("dualcal dataset", &["toml"])
                        .pick_file(),
                    OpenKind::Urdf => dialog
                        .set_title("Open robot description (URDF)")
                        .add_filter("URDF", &["urdf", "xml"])
                        .pick_file(),
                };
                let _ = reply.send(match picked {
                    Some(path) => FileReply::Open(kind, path),
                    None => FileReply::Cancelled,
                });
            });
        if let Err(e) = spawned {
            eprintln!("dualcal: cannot start the file dialog: {e}");
        }
    }

    fn save(&self, request: SaveRequest, reply: Sender<FileReply>) {
        let spawned = std::thread::Builder::new()
            .name("dualcal-save-dialog".into())
            .spawn(move || {
                let picked = rfd::FileDialog::new()
                    .set_title(request.title)
                    .set_file_name(&request.file_name)
                    .add_filter(request.filter_name, request.extensions)
                    .save_file();
                let _ = reply.send(match picked {
                    Some(path) => match crate::atomic::write_atomic(&path, &request.bytes) {
                        Ok(()) => FileReply::Saved(path),
                        Err(e) => FileReply::Failed(format!("{}: {e}", path.display())),
                    },
                    None => FileReply::Cancelled,
                });
            });
        if let Err(e) = spawned {
            eprintln!("dualcal: cannot start the file dialog: {e}");
        }
    }
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}
