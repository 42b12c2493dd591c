//! What a dataset calls for unless told otherwise: the step-1 method ([`default_method`], and why) and
//! the stages of its run ([`planned_stages`]).

use crate::dataset::Dataset;
use crate::kinematics::DualArmModel;
use crate::side::Side;
use crate::solver::methods::table::Method;
use crate::solver::types::Stage;

/// The step-1 method a calibration of `dataset` uses unless told otherwise: the paper's minimax on
/// distances, or the absolute positions ([`Method::Position`]) where the data call for it
/// ([`default_method_reason`]).
pub fn default_method(dataset: &Dataset) -> Method {
    if default_method_reason(dataset).is_some() {
        Method::Position
    } else {
        Method::Minimax
    }
}

/// Why [`default_method`] is the absolute positions for `dataset`, if it is: one marker per hand and
/// both hands measured together in one tracker frame (a motion-capture camera, as DLR's data) —
/// distances of one marker see a third of what three do and nothing of the camera frame, which the
/// absolute positions identify with the arms.
pub fn default_method_reason(dataset: &Dataset) -> Option<&'static str> {
    (dataset.reflector_count() == 1 && dataset.measured_together && dataset.one_tracker_frame())
        .then_some(
            "one marker per hand, both measured together in one tracker frame: the absolute \
             positions, the camera frame identified with the arms",
        )
}

/// The arm measured alone, when `dataset` has one arm only.
pub(super) fn alone_arm(dataset: &Dataset) -> Option<Side> {
    match dataset.measured_sides().as_slice() {
        [side] => Some(*side),
        _ => None,
    }
}

/// The stages a calibration of `dataset` from `nominal` runs, in order: each arm's step 1 (one stage
/// of both where their chains share joints; the one arm's where one arm was measured alone), then
/// step 2 unless the data cannot measure the base ([`Dataset::base_not_measurable`]).
pub fn planned_stages(dataset: &Dataset, nominal: &DualArmModel) -> Vec<Stage> {
    let mut plan = match alone_arm(dataset) {
        Some(side) => vec![Stage::Arm(side)],
        None if nominal.shared_joints().is_empty() => {
            vec![Stage::Arm(Side::Left), Stage::Arm(Side::Right)]
        }
        None => vec![Stage::Arms],
    };
    if dataset.base_not_measurable().is_none() {
        plan.push(Stage::Base);
    }
    plan
}
