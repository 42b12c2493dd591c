//! The "Compare methods" view: the methods of [`crate::comparison::METHODS`] the user picks, run one
//! after another on the loaded dataset in the background ([`super::job::comparison::ComparisonWork`], one outer iteration per
//! step, so it is stepped in frames where there are no threads), side by side: a summary table
//! (nominal first, the best figure of each column highlighted), a histogram per method and a box plot
//! per method; any method's result can be adopted as the current calibration (then the exports write
//! it). The engine does the work ([`crate::comparison`]: the methods table, the figures, the box
//! statistics); this is the view's state and the task around it (the view is drawn by
//! [`super::panels::compare_ui`]).

use crate::analysis::Indicator;
use crate::comparison::{self, Comparison, METHODS, MethodEntry};
use crate::dataset::Split;
use crate::side::Side;
use crate::solver::{BaseMethod, CalibrationResult, CalibrationSettings, Method, Stage};

/// The method a calibration used, for the status line and the comparison: step 1 (with the reflector
/// each arm used, for distance-single) and step 2.
pub fn method_used(result: &CalibrationResult) -> String {
    let s = &result.settings;
    let reflectors: Vec<String> = Side::BOTH
        .iter()
        .filter_map(|&side| result.reflector_used[side].map(|r| format!("{side} {r}")))
        .collect();
    let reflector = if reflectors.is_empty() {
        String::new()
    } else {
        format!(" (reflector {})", reflectors.join(", "))
    };
    format!(
        "method {}{reflector}, base {}",
        s.method.name(),
        s.base_method.name()
    )
}

/// What the view shows and which methods are picked.
pub struct CompareView {
    /// The view replaces the 3D view, the table and the plots.
    pub open: bool,
    /// Per [`METHODS`] entry: whether it is run.
    pub picked: Vec<bool>,
    pub split: Split,
    /// The indicator of the histograms and box plots.
    pub indicator: Indicator,
    /// The running or last comparison (methods are added as they finish).
    pub comparison: Option<Comparison>,
    /// The running comparison's progress.
    pub progress: Option<CompareProgress>,
    /// The entry whose result was adopted last (by key).
    pub adopted: Option<&'static str>,
}

impl Default for CompareView {
    fn default() -> Self {
        Self {
            open: false,
            picked: paper_set(),
            split: Split::Ver,
            indicator: Indicator::CollaborativePosition,
            comparison: None,
            progress: None,
            adopted: None,
        }
    }
}

/// The paper's comparison: every method it has a column for.
pub fn paper_set() -> Vec<bool> {
    METHODS.iter().map(|m| m.paper.is_some()).collect()
}

impl CompareView {
    /// The picked entries, in the table's order.
    pub fn picked_entries(&self) -> Vec<MethodEntry> {
        METHODS
            .iter()
            .zip(&self.picked)
            .filter(|(_, picked)| **picked)
            .map(|(m, _)| *m)
            .collect()
    }

    /// Pick exactly the entries whose keys are given (unknown keys are ignored).
    pub fn pick(&mut self, keys: &[&str]) {
        self.picked = METHODS.iter().map(|m| keys.contains(&m.key)).collect();
    }
}

/// Where a running comparison is.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareProgress {
    pub index: usize,
    pub total: usize,
    pub key: &'static str,
    pub stage: Option<Stage>,
    pub iteration: usize,
}

impl CompareProgress {
    pub fn label(&self) -> String {
        let title = comparison::method(self.key).map_or(self.key.to_string(), |m| m.title());
        let at = match self.stage {
            Some(stage) => format!(", {stage}, iteration {}", self.iteration),
            None => String::new(),
        };
        format!(
            "Comparing: method {} of {} — {title}{at}",
            self.index + 1,
            self.total
        )
    }
}

/// The settings the comparison's methods share: a run's settings (the user's split, limits and
/// tolerances and the session's exclusions: [`Session::run_settings`]); each entry sets its own method
/// on top.
pub fn common_settings(run: &CalibrationSettings) -> CalibrationSettings {
    CalibrationSettings {
        method: Method::Minimax,
        base_method: BaseMethod::Minimax,
        reflector: None,
        ..run.clone()
    }
}
