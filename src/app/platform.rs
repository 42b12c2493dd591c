//! What differs between the desktop and the browser, in one place: where input files are read from
//! and how the user picks and saves files ([`io`]), where the bundled example is, how long work
//! stepped in frames may take of a frame ([`frame_budget`]), and the state a browser page shows its
//! tests ([`publish_status`]). Threads or frames is [`super::task::Execution`]'s business. The rest of
//! the app is the same code on both.

use super::LaunchOptions;
use super::files::Io;
use super::task::FrameBudget;
use eframe::egui;
use std::path::PathBuf;

/// The desktop: the file system and native dialogs.
#[cfg(not(target_arch = "wasm32"))]
pub fn io(_ctx: &egui::Context, options: &LaunchOptions) -> Io {
    Io {
        files: crate::source::Files::default(),
        dialogs: Box::new(super::files::NativeFiles {
            path_prompt: options.path_prompt,
        }),
        memory: None,
    }
}

/// The browser: files in memory (the compiled-in example, then what the user picks or drops) and
/// downloads.
#[cfg(target_arch = "wasm32")]
pub fn io(ctx: &egui::Context, _options: &LaunchOptions) -> Io {
    super::web::io(ctx)
}

/// The bundled example dataset: in the source tree or unpacked into the cache directory on the
/// desktop, in memory in a browser ([`super::bundled_example_path`]).
pub fn example_dataset() -> PathBuf {
    super::bundled_example_path()
}

/// The per-frame budget of work stepped in frames: adaptive ([`FrameBudget`]), or in a browser the
/// page's `?budget_ms=N` (tests: 0 steps once per frame, a large N runs the work in one go).
pub fn frame_budget() -> FrameBudget {
    #[cfg(target_arch = "wasm32")]
    if let Some(ms) = super::web::query_number("budget_ms") {
        return FrameBudget::fixed(std::time::Duration::from_secs_f64(ms / 1e3));
    }
    FrameBudget::default()
}

/// Whether the app publishes its state ([`publish_status`]): in a browser, for tests and embedding
/// pages.
pub const PUBLISHES_STATUS: bool = cfg!(target_arch = "wasm32");

/// Show the app's state (JSON) to the page: the text of its `#dualcal-status` element.
pub fn publish_status(json: &str) {
    #[cfg(target_arch = "wasm32")]
    super::web::publish_status(json);
    #[cfg(not(target_arch = "wasm32"))]
    let _ = json;
}

/// Set-up of the egui context the platform needs: in a browser, egui's fonts subset at build time
/// ([`super::web::fonts`]) and the accessibility tree mirrored into the page (eframe's web runner has
/// no AccessKit adapter).
pub fn init_context(ctx: &egui::Context) {
    #[cfg(target_arch = "wasm32")]
    {
        ctx.set_fonts(super::web::fonts());
        super::web::mirror_accessibility_tree(ctx);
    }
    #[cfg(not(target_arch = "wasm32"))]
    let _ = ctx;
}
