//! `dualcal calibrate --timings`: the wall time of each phase of the command, on standard error.

/// Wall time per phase of a command, for `--timings`.
pub(super) struct Phases {
    started: std::time::Instant,
    last: std::time::Instant,
    pub(super) done: Vec<(&'static str, std::time::Duration)>,
}

impl Phases {
    pub(super) fn new() -> Self {
        let now = std::time::Instant::now();
        Self {
            started: now,
            last: now,
            done: Vec::new(),
        }
    }

    /// The phase `name` ends now.
    pub(super) fn end(&mut self, name: &'static str) {
        let now = std::time::Instant::now();
        self.done.push((name, now - self.last));
        self.last = now;
    }

    pub(super) fn print(&self) {
        eprintln!("timings (wall, ms):");
        for (name, d) in &self.done {
            eprintln!("  {name:<50} {:9.1}", d.as_secs_f64() * 1e3);
        }
        eprintln!(
            "  {:<50} {:9.1}",
            "total (from the start of the command)",
            self.started.elapsed().as_secs_f64() * 1e3
        );
    }
}
