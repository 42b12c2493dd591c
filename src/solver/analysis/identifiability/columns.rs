//! Whose parameters a Gram matrix's columns are: one arm's, or both arms' of a robot whose arms share
//! joints (a shared joint's once), each followed, for the methods that fit absolute measurements, by
//! the six of the tracker-from-base transform. [`analyse_columns`] is the one place that tells
//! [`analyse`] the columns' order, names and physical reasons: the distance and absolute set-ups at the
//! start and the re-check at a solution all call it.

use super::analyse::{IdentifiabilityReport, ParameterInfo, analyse};
use crate::kinematics::ArmModel;
use crate::side::{PerSide, Side};
use crate::solver::problems::absolute_problem::transform_param_name;
use crate::solver::problems::tree_problem::TreeLayout;
use nalgebra::DMatrix;

/// The parameters of a Gram matrix's columns, in order.
#[derive(Clone, Copy)]
pub enum Columns<'a> {
    /// One arm's parameters; then, with `transform`, the six of that side's tracker-from-base
    /// transform.
    Arm {
        arm: &'a ArmModel,
        transform: Option<Side>,
    },
    /// Both arms' parameters as `layout` holds them; then, with `transform`, the six of the one
    /// tracker frame's transform (named as the left arm's base's).
    Tree {
        layout: &'a TreeLayout,
        arms: &'a PerSide<ArmModel>,
        transform: bool,
    },
}

impl Columns<'_> {
    /// The number of the robot's own parameters (the transform's six follow them).
    pub fn own_len(&self) -> usize {
        match self {
            Columns::Arm { arm, .. } => arm.param_count(),
            Columns::Tree { layout, .. } => layout.len,
        }
    }

    /// The side whose tracker-from-base transform the columns end with, if they do.
    fn transform(&self) -> Option<Side> {
        match *self {
            Columns::Arm { transform, .. } => transform,
            Columns::Tree { transform, .. } => transform.then_some(Side::Left),
        }
    }

    /// The robot's own parameters in the order of preference.
    fn own_order(&self) -> Vec<usize> {
        match self {
            Columns::Arm { arm, .. } => arm.identifiability_order(),
            Columns::Tree { layout, arms, .. } => layout.interleaved_order(arms),
        }
    }

    fn own_name(&self, x: usize) -> String {
        match self {
            Columns::Arm { arm, .. } => arm.param_name(x),
            Columns::Tree { layout, arms, .. } => layout.param_name(x, arms),
        }
    }

    fn own_reason(&self, x: usize) -> Option<String> {
        match self {
            Columns::Arm { arm, .. } => arm.unidentifiable_reason(x),
            Columns::Tree { layout, arms, .. } => {
                let (side, k) = layout.owner(x);
                arms[side].unidentifiable_reason(k)
            }
        }
    }
}

/// What the analysis is told besides the columns.
pub struct Analysis<'a> {
    /// Parameters that may be free at all (one per column).
    pub allowed: &'a [bool],
    /// What the method fits, for the reasons ([`ParameterInfo::DISTANCES`], `absolute positions`, …).
    pub data: &'a str,
    /// Why a parameter that is not allowed is fixed.
    pub not_allowed: &'a str,
}

impl Analysis<'_> {
    /// Every parameter in `allowed` allowed, the distances of all the reflectors.
    pub fn distances(allowed: &[bool]) -> Analysis<'_> {
        Analysis {
            allowed,
            data: ParameterInfo::DISTANCES,
            not_allowed: ParameterInfo::FIXED_BY_USER,
        }
    }
}

/// The analysis of `gram`, whose columns are `columns`: the transform's six first when there are
/// (what it absorbs, a rigid motion of the whole, is fixed in the arms), then the robot's own
/// parameters in their order of preference.
pub fn analyse_columns(
    gram: &DMatrix<f64>,
    columns: &Columns,
    analysis: &Analysis,
) -> IdentifiabilityReport {
    let n = columns.own_len();
    let transform = columns.transform();
    let mut order: Vec<usize> = match transform {
        Some(_) => (n..n + 6).collect(),
        None => Vec::new(),
    };
    order.extend(columns.own_order());
    let name = |x: usize| match transform {
        Some(side) if x >= n => transform_param_name(side, x - n),
        _ => columns.own_name(x),
    };
    let reason = |x: usize| (x < n).then(|| columns.own_reason(x)).flatten();
    analyse(
        gram,
        &ParameterInfo {
            order: &order,
            allowed: analysis.allowed,
            name: &name,
            reason: &reason,
            data: analysis.data,
            not_allowed: analysis.not_allowed,
        },
    )
}
