//! Frame statistics printed to stderr when the launch options ask for them (`DUALCAL_FRAME_STATS`,
//! see docs/performance.md); the app then repaints continuously.

// std's `Instant::now` panics in a browser (wasm32-unknown-unknown); web-time is std's on native targets.
use web_time::Instant;

/// How many frames one printed line covers.
const FRAME_STATS_WINDOW: usize = 30;

/// No frame measured yet by default.
#[derive(Default)]
pub struct FrameStats {
    /// The frame being measured (egui may build a frame's UI in more than one pass).
    frame_nr: Option<u64>,
    last: Option<Instant>,
    /// Time between frames (everything: egui, our render pass, egui's, presenting).
    samples_ms: Vec<f64>,
    /// Time spent building the UI on the CPU.
    ui_ms: Vec<f64>,
}

impl FrameStats {
    /// Frame `frame_nr` begins (again, when egui builds it in another pass); every
    /// [`FRAME_STATS_WINDOW`] frames a line is printed (`busy` marks it "[calibrating]").
    pub fn frame_started(&mut self, frame_nr: u64, busy: bool) {
        if self.frame_nr.replace(frame_nr) == Some(frame_nr) {
            return;
        }
        let now = Instant::now();
        if let Some(last) = self.last {
            self.samples_ms.push((now - last).as_secs_f64() * 1e3);
        }
        self.last = Some(now);
        if self.samples_ms.len() >= FRAME_STATS_WINDOW {
            self.print(busy);
        }
        self.ui_ms.push(0.0);
    }

    fn print(&mut self, busy: bool) {
        let mut s = std::mem::take(&mut self.samples_ms);
        crate::sort::sort_f64(&mut s);
        let mean = s.iter().sum::<f64>() / s.len() as f64;
        let p95 = s[(s.len() * 95 / 100).min(s.len() - 1)];
        let ui = std::mem::take(&mut self.ui_ms);
        let ui_mean = ui.iter().sum::<f64>() / ui.len().max(1) as f64;
        eprintln!(
            "frame time over {} frames: mean {mean:.1} ms, p95 {p95:.1} ms, max {:.1} ms (UI build on the CPU: mean {ui_mean:.1} ms){}",
            s.len(),
            s[s.len() - 1],
            if busy { " [calibrating]" } else { "" }
        );
    }

    /// A pass of this frame's UI took `ms` to build.
    pub fn ui_built(&mut self, ms: f64) {
        if let Some(frame_ms) = self.ui_ms.last_mut() {
            *frame_ms += ms;
        }
    }
}
