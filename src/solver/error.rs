//! Why a calibration could not run.

use crate::side::Side;
use crate::solver::types::Stage;

/// Why a calibration could not run: bad input, non-finite values, rank deficiency. How a run ended
/// (converged, iteration limit, cancelled, stalled) is not an error but part of the
/// [`crate::solver::CalibrationResult`].
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    #[error(
        "{side} arm: {found} configurations in the selected split (after exclusions), at least {needed} \
         are needed to identify the arm's parameters by method `{method}` ({count_rule}; {params} \
         parameters; the paper uses 120)"
    )]
    TooFewConfigurations {
        side: Side,
        found: usize,
        needed: usize,
        /// The arm's identifiable parameters (by distances).
        params: usize,
        /// The method's name.
        method: &'static str,
        /// How the method counts what it needs ([`crate::solver::Method::count_rule`]).
        count_rule: &'static str,
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
         data, and method `{method}` cannot fit both arms at once; use {alternatives}"
    )]
    SharedJointsUnsupported {
        joints: String,
        /// The method's name.
        method: &'static str,
        /// The methods that can (`\`minimax\` or \`lsq\``).
        alternatives: String,
    },
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
