//! Why a calibration could not run.

use crate::side::Side;
use crate::solver::methods::table::Method;
use crate::solver::types::Stage;

/// Why a calibration could not run: bad input, non-finite values, rank deficiency. How a run ended
/// (converged, iteration limit, cancelled, stalled) is not an error but part of the
/// [`crate::solver::CalibrationResult`].
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    #[error(
        "{side} arm: {found} configurations in the selected split (after exclusions), at least {needed} \
         are needed to identify the arm's parameters by method `{}` ({}; {params} parameters; the paper \
         uses 120)", method.name(), method.count_rule()
    )]
    TooFewConfigurations {
        side: Side,
        found: usize,
        needed: usize,
        /// The arm's identifiable parameters (by distances).
        params: usize,
        method: Method,
    },
    #[error(
        "{side} arm: configuration `{id}` has {found} joint values, the arm's model has {expected} joints"
    )]
    JointCount {
        side: Side,
        id: String,
        found: usize,
        expected: usize,
    },
    #[error("{stage}: the identification Jacobian is rank deficient: {detail}")]
    RankDeficient { stage: Stage, detail: String },
    #[error("{stage}: non-finite value ({detail})")]
    NonFinite { stage: Stage, detail: String },
    /// The full-pose method builds a tool frame from three reflectors per configuration; the data have
    /// another number.
    #[error(
        "{side} arm: the pose method (ref. [19]) builds a tool frame from three reflectors per \
         configuration; the data have {found}: it cannot run on them (the distance and position \
         methods can)"
    )]
    NeedsThreeReflectors { side: Side, found: usize },
    /// The arms share joints (a torso) and the method has no fit of both arms at once.
    #[error(
        "the arms share joint(s) {joints}: their corrections must be identified once, from both arms' \
         data, and method `{}` cannot fit both arms at once; use {}", method.name(), tree_methods()
    )]
    SharedJointsUnsupported { joints: String, method: Method },
    /// Settings that do not fit together (e.g. a reflector chosen for a method that uses all three).
    #[error("invalid calibration settings: {0}")]
    InvalidSettings(String),
    /// The three measured reflectors of a configuration are (nearly) collinear or coincident, so no
    /// tool frame can be built from them (the full-pose method needs one per configuration).
    #[error(
        "{side} arm: configuration `{id}`: the three measured reflectors are collinear (triangle \
         area {area_mm2:.3e} mm²), no tool frame can be built from them"
    )]
    DegenerateReflectors {
        side: Side,
        id: String,
        area_mm2: f64,
    },
}

/// The methods that fit both arms at once (robots whose arms share joints), for messages.
fn tree_methods() -> String {
    Method::ALL
        .iter()
        .filter(|m| m.spec().tree_set_up.is_some())
        .map(|m| format!("`{}`", m.name()))
        .collect::<Vec<_>>()
        .join(" or ")
}
