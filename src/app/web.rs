//! The workbench in a browser (wasm32): the entry point that starts eframe's web runner on the page's
//! canvas; the file seam (files picked or dropped are read into memory and mounted by
//! [`super::uploads`], exports are downloads); the `#dualcal-status` element the app publishes its
//! state to; and a mirror of egui's accessibility tree in the page (eframe 0.37's web runner has no
//! AccessKit adapter), so that tests and assistive tools find the widgets by role and name.
//!
//! The page (`web/index.html`) provides `<canvas id="dualcal-canvas">`, `<pre id="dualcal-status">`
//! and `<div id="dualcal-a11y">`.

use super::events::{AppEvent, EventSender};
use super::files::{FileAccess, FileReply, Io, OpenKind, SaveRequest};
use super::uploads::{Upload, mount};
use super::{AppLaunch, WorkbenchApp};
use crate::source::{Files, MemoryFiles};
use eframe::egui;
use std::cell::Cell;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;
use wasm_bindgen::{JsCast as _, JsValue, closure::Closure};

use super::example::IN_MEMORY_EXAMPLE_DIR;

#[cfg(not(feature = "web-fonts"))]
compile_error!(
    "the browser's workbench is built with the feature `web` or `web-webgpu` (`tools/web.sh build`): \
     its fonts are egui's, subset by build.rs, and it needs one wgpu backend"
);

const CANVAS_ID: &str = "dualcal-canvas";
const STATUS_ID: &str = "dualcal-status";
const A11Y_ID: &str = "dualcal-a11y";

/// Start the workbench on the page's canvas (the wasm binary's `main`).
pub fn start() {
    let runner = eframe::WebRunner::new();
    wasm_bindgen_futures::spawn_local(async move {
        if let Err(e) = runner_start(&runner).await {
            let message = e.as_string().unwrap_or_else(|| format!("{e:?}"));
            publish_status(
                &serde_json::json!({"phase": "failed", "errors": [message.clone()]}).to_string(),
            );
            web_sys::console::error_1(&format!("dualcal: cannot start: {message}").into());
        }
    });
}

async fn runner_start(runner: &eframe::WebRunner) -> Result<(), JsValue> {
    let canvas = document()
        .ok_or("no document")?
        .get_element_by_id(CANVAS_ID)
        .ok_or("no canvas #dualcal-canvas on the page")?
        .dyn_into::<web_sys::HtmlCanvasElement>()?;
    runner
        .start(
            canvas,
            eframe::WebOptions::default(),
            Box::new(|cc| {
                // wgpu's adapter, device and egui's painter are ready; then the app's creation.
                mark("dualcal:renderer-ready");
                let app = WorkbenchApp::new(cc, AppLaunch::default());
                mark("dualcal:app-created");
                Ok(Box::new(app))
            }),
        )
        .await
}

/// A `performance.mark` for `web/tests/first-frame.mjs` (where the time to the first frame goes).
fn mark(name: &str) {
    if let Some(performance) = web_sys::window().and_then(|w| w.performance()) {
        let _ = performance.mark(name);
    }
}

/// A number from the page's query string (`?name=N`).
pub fn query_number(name: &str) -> Option<f64> {
    let search = web_sys::window()?.location().search().ok()?;
    search
        .trim_start_matches('?')
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .find(|(key, _)| *key == name)
        .and_then(|(_, value)| value.parse().ok())
        .filter(|v: &f64| v.is_finite() && *v >= 0.0)
}

fn document() -> Option<web_sys::Document> {
    web_sys::window()?.document()
}

/// Files in memory with the example mounted, and the browser's file seam on them.
pub fn io(ctx: &egui::Context) -> Io {
    let memory = MemoryFiles::new();
    for (name, bytes) in super::example::example_files() {
        memory.insert(Path::new(IN_MEMORY_EXAMPLE_DIR).join(name), bytes);
    }
    Io {
        files: Files(Arc::new(memory.clone())),
        memory: Some(memory.clone()),
        dialogs: Box::new(WebFiles {
            memory,
            ctx: ctx.clone(),
            batches: Rc::new(Cell::new(0)),
        }),
    }
}

/// Set the text of `#dualcal-status`; the first call also records the time to the first frame
/// (`data-first-frame-ms`, ms since the navigation started).
pub fn publish_status(json: &str) {
    let Some(element) = document().and_then(|d| d.get_element_by_id(STATUS_ID)) else {
        return;
    };
    if !element.has_attribute("data-first-frame-ms")
        && let Some(performance) = web_sys::window().and_then(|w| w.performance())
    {
        let _ = element.set_attribute("data-first-frame-ms", &format!("{:.0}", performance.now()));
    }
    element.set_text_content(Some(json));
}

/// The browser's file seam: `<input type=file multiple>` to open (a dataset is several files, or one
/// `.zip`), downloads to save, dropped files read into memory. Each batch is mounted under
/// `/uploads/<n>/` ([`super::uploads::mount`]) and opened from there.
struct WebFiles {
    memory: MemoryFiles,
    ctx: egui::Context,
    batches: Rc<Cell<usize>>,
}

impl WebFiles {
    fn clone_handle(&self) -> Self {
        Self {
            memory: self.memory.clone(),
            ctx: self.ctx.clone(),
            batches: self.batches.clone(),
        }
    }

    /// Read `files` into memory, mount them and reply with what to open.
    fn receive(&self, files: Vec<web_sys::File>, wanted: Option<OpenKind>, reply: EventSender) {
        let memory = self.memory.clone();
        let batches = self.batches.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let mut uploads = Vec::new();
            for file in files {
                // A folder's files carry their relative path; loose files only a name.
                let relative = js_sys::Reflect::get(&file, &"webkitRelativePath".into())
                    .ok()
                    .and_then(|v| v.as_string())
                    .filter(|p| !p.is_empty())
                    .unwrap_or_else(|| file.name());
                match wasm_bindgen_futures::JsFuture::from(file.array_buffer()).await {
                    Ok(buffer) => uploads.push(Upload {
                        path: relative,
                        bytes: js_sys::Uint8Array::new(&buffer).to_vec(),
                    }),
                    Err(e) => {
                        reply.send(AppEvent::File(FileReply::Failed(format!(
                            "{}: cannot be read: {}",
                            file.name(),
                            js_message(&e)
                        ))));
                        return;
                    }
                }
            }
            batches.set(batches.get() + 1);
            let dir = PathBuf::from(format!("/uploads/{}", batches.get()));
            reply.send(AppEvent::File(mount(&memory, &dir, uploads, wanted)));
        });
    }
}

fn js_message(e: &JsValue) -> String {
    e.as_string()
        .or_else(|| {
            e.dyn_ref::<js_sys::Error>()
                .map(|e| String::from(e.message()))
        })
        .unwrap_or_else(|| format!("{e:?}"))
}

impl FileAccess for WebFiles {
    fn open(&self, kind: OpenKind, reply: EventSender) {
        let Some(input) = document()
            .and_then(|d| d.create_element("input").ok())
            .and_then(|e| e.dyn_into::<web_sys::HtmlInputElement>().ok())
        else {
            reply.send(AppEvent::File(FileReply::Failed(
                "cannot create a file input".into(),
            )));
            return;
        };
        input.set_type("file");
        input.set_multiple(true);
        input.set_accept(match kind {
            OpenKind::Dataset => ".toml,.csv,.zip,.urdf,.stl,.dae,.obj",
            OpenKind::Urdf => ".urdf,.zip,.stl,.dae,.obj",
            OpenKind::ImportFile(_) => ".txt,.csv,.tsv,.dat,.asc",
            // The import view writes into memory in a browser: it asks for no folder.
            OpenKind::ImportFolder => "",
        });
        let this = self.clone_handle();
        let target = input.clone();
        let on_change = Closure::once_into_js(move || {
            target.remove();
            let files = target.files().map_or_else(Vec::new, |list| {
                (0..list.length()).filter_map(|i| list.get(i)).collect()
            });
            if files.is_empty() {
                reply.send(AppEvent::File(FileReply::Cancelled));
            } else {
                this.receive(files, Some(kind), reply);
            }
        });
        input.set_onchange(Some(on_change.unchecked_ref()));
        // In the document (hidden) while in use: some browsers ignore a detached file input.
        let _ = input.style().set_property("display", "none");
        if let Some(body) = document().and_then(|d| d.body()) {
            let _ = body.append_child(&input);
        }
        // Within the few seconds of user activation the click that asked for it gave.
        input.click();
    }

    fn save(&self, request: SaveRequest, reply: EventSender) {
        let reply_event = match download(&request.file_name, &request.bytes) {
            Ok(()) => {
                FileReply::Saved(PathBuf::from(format!("{} (downloaded)", request.file_name)))
            }
            Err(e) => FileReply::Failed(format!(
                "{}: cannot download: {}",
                request.file_name,
                js_message(&e)
            )),
        };
        reply.send(AppEvent::File(reply_event));
    }

    fn dropped(&self, files: &[egui::DroppedFileHandle], reply: EventSender) -> Vec<PathBuf> {
        let files: Vec<web_sys::File> =
            files.iter().filter_map(|f| f.web_file().cloned()).collect();
        if !files.is_empty() {
            self.receive(files, None, reply);
        }
        Vec::new()
    }
}

/// Offer `bytes` as a download named `file_name`.
fn download(file_name: &str, bytes: &[u8]) -> Result<(), JsValue> {
    let document = document().ok_or("no document")?;
    let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(bytes));
    let blob = web_sys::Blob::new_with_u8_array_sequence(&parts)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob)?;
    let anchor = document
        .create_element("a")?
        .dyn_into::<web_sys::HtmlAnchorElement>()?;
    anchor.set_href(&url);
    anchor.set_download(file_name);
    anchor.click();
    web_sys::Url::revoke_object_url(&url)
}

/// egui's default fonts and families as epaint's `default_fonts` sets them, from the subsets build.rs
/// writes (the feature `web-fonts`: Latin, Greek, Cyrillic, punctuation, arrows, mathematical symbols
/// in Ubuntu Light; Hack, the monospace font, narrower — its missing characters come from Ubuntu Light,
/// the next font of the monospace family).
pub fn fonts() -> egui::FontDefinitions {
    use egui::{FontData, FontFamily, FontTweak};
    macro_rules! subset {
        ($file:literal) => {
            include_bytes!(concat!(env!("OUT_DIR"), "/web-fonts/", $file))
        };
    }
    let mut fonts = egui::FontDefinitions::empty();
    for (name, data) in [
        ("Hack", FontData::from_static(subset!("Hack-Regular.ttf"))),
        (
            "Ubuntu-Light",
            FontData::from_static(subset!("Ubuntu-Light.ttf")),
        ),
        (
            "egui-icons",
            FontData::from_static(subset!("egui-icons.ttf")).tweak(FontTweak {
                scale: 0.90,
                ..Default::default()
            }),
        ),
    ] {
        fonts.font_data.insert(name.to_owned(), Arc::new(data));
    }
    let family = |names: &[&str]| names.iter().map(|n| (*n).to_owned()).collect::<Vec<_>>();
    fonts.families.insert(
        FontFamily::Monospace,
        family(&["Hack", "Ubuntu-Light", "egui-icons"]),
    );
    fonts.families.insert(
        FontFamily::Proportional,
        family(&["Ubuntu-Light", "egui-icons"]),
    );
    fonts
}

/// Turn on egui's accessibility tree and mirror it into `#dualcal-a11y` after every frame.
pub fn mirror_accessibility_tree(ctx: &egui::Context) {
    ctx.enable_accesskit();
    ctx.add_plugin(AccessMirror::default());
}

/// Writes the widgets of egui's accessibility tree (those with a name) into the page as elements
/// with their role and name (`<button aria-label="Calibrate" data-bounds="x0 y0 x1 y1">`, bounds
/// in CSS pixels from the canvas' corner), only when they changed. They are visually hidden but in
/// the page's accessibility tree; activating them does nothing yet (the canvas takes the input).
#[derive(Default)]
struct AccessMirror {
    last: String,
}

impl egui::Plugin for AccessMirror {
    fn debug_name(&self) -> &'static str {
        "dualcal accessibility mirror"
    }

    fn output_hook(&mut self, _ctx: &egui::Context, output: &mut egui::FullOutput) {
        let Some(update) = &output.platform_output.accesskit_update else {
            return;
        };
        let html = mirror_html(update);
        if html != self.last
            && let Some(element) = document().and_then(|d| d.get_element_by_id(A11Y_ID))
        {
            element.set_inner_html(&html);
            self.last = html;
        }
    }
}

fn mirror_html(update: &egui::accesskit::TreeUpdate) -> String {
    use egui::accesskit::{Role, Toggled};
    let mut html = String::new();
    for (_, node) in &update.nodes {
        let Some(name) = node.label().or_else(|| node.value()) else {
            continue;
        };
        let role = match node.role() {
            Role::Button | Role::DefaultButton => "button",
            Role::CheckBox => "checkbox",
            Role::RadioButton => "radio",
            Role::Tab => "tab",
            Role::Link => "link",
            Role::Slider | Role::SpinButton => "slider",
            Role::TextInput | Role::MultilineTextInput => "textbox",
            Role::Label => "note",
            _ => continue,
        };
        let bounds = node
            .bounds()
            .map(|b| format!("{:.1} {:.1} {:.1} {:.1}", b.x0, b.y0, b.x1, b.y1))
            .unwrap_or_default();
        let _ = write!(
            html,
            "<div role=\"{role}\" aria-label=\"{}\" data-bounds=\"{bounds}\"",
            escape(name)
        );
        if node.is_disabled() {
            html.push_str(" aria-disabled=\"true\"");
        }
        if let Some(toggled) = node.toggled() {
            let state = if toggled == Toggled::True {
                "true"
            } else {
                "false"
            };
            let attribute = if role == "tab" {
                "aria-selected"
            } else {
                "aria-checked"
            };
            let _ = write!(html, " {attribute}=\"{state}\"");
        }
        html.push_str("></div>");
    }
    html
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
