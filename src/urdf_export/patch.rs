//! The calibrated URDF of a description loaded from a file: a copy of the user's own text in which
//! only the arm joints' `<origin>` attributes change — each by the correction the calibration
//! identified — and the identified reflectors are added as fixed links on the tips. Comments,
//! `<gazebo>`, `<transmission>`, sensors, `xacro:` elements, attribute order and formatting are kept
//! byte for byte (the edits are byte ranges found with roxmltree).
//!
//! Per arm the corrected origin of joint k is `O_k · C_k Δ_k C_kᵀ`
//! ([`crate::kinematics::SerialChain::corrected_origins`]); the step-2 base correction goes into the
//! right arm's first joint origin ([`crate::kinematics::SerialChain::first_origin_with_base_correction`]),
//! so no link above the arms moves. Origins are written with full precision; near gimbal lock the
//! written roll and yaw can differ a lot from the original text for the same rotation — compare
//! rotations, never rpy text.

use super::{export_err, urdf_pose_from_isometry};
use crate::kinematics::DualArmModel;
use crate::robot::{LoadOptions, RobotDescription, RobotError};
use crate::side::Side;
use nalgebra::{Isometry3, Vector3};
use std::ops::Range;

/// Radius of the sphere drawn for a reflector, m (a 0.5" SMR).
pub(super) const REFLECTOR_RADIUS_M: f64 = 0.00635;

/// A number for a URDF attribute: the shortest text that reads back to the same `f64`.
fn fmt_num(v: f64) -> String {
    if v == 0.0 { "0".into() } else { format!("{v}") }
}

fn origin_attrs(origin_mm: &Isometry3<f64>) -> (String, String) {
    let pose = urdf_pose_from_isometry(origin_mm);
    (
        pose.xyz.0.map(fmt_num).join(" "),
        pose.rpy.0.map(fmt_num).join(" "),
    )
}

/// XML-escape an attribute value.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('"', "&quot;")
}

fn parse(text: &str) -> Result<roxmltree::Document<'_>, RobotError> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    roxmltree::Document::parse_with_options(text, options)
        .map_err(|e| export_err(format!("cannot parse the URDF text: {e}")))
}

/// The edits (byte range, replacement) that set the `<origin>` of joint `name` to `origin_mm`.
fn origin_edits(
    text: &str,
    root: roxmltree::Node,
    name: &str,
    origin_mm: &Isometry3<f64>,
    edits: &mut Vec<(Range<usize>, String)>,
) -> Result<(), RobotError> {
    let joint = root
        .children()
        .find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(name))
        .ok_or_else(|| export_err(format!("joint `{name}` not found in the URDF text")))?;
    let (xyz, rpy) = origin_attrs(origin_mm);
    match joint.children().find(|n| n.has_tag_name("origin")) {
        Some(o) => {
            let mut missing = String::new();
            for (attr, value) in [("xyz", &xyz), ("rpy", &rpy)] {
                match o.attributes().find(|a| a.name() == attr) {
                    Some(a) => edits.push((a.range_value(), value.clone())),
                    None => missing.push_str(&format!(" {attr}=\"{value}\"")),
                }
            }
            if !missing.is_empty() {
                // Insert after the tag name `<origin`.
                let at = o.range().start + "<origin".len();
                edits.push((at..at, missing));
            }
        }
        None => {
            // After the joint's start tag.
            let start = joint.range().start;
            let close = text[start..]
                .find('>')
                .map(|i| start + i)
                .ok_or_else(|| export_err(format!("joint `{name}`: malformed start tag")))?;
            if text[..close].ends_with('/') {
                return Err(export_err(format!(
                    "joint `{name}` is an empty element without parent and child"
                )));
            }
            edits.push((
                close + 1..close + 1,
                format!("\n    <origin xyz=\"{xyz}\" rpy=\"{rpy}\"/>"),
            ));
        }
    }
    Ok(())
}

/// A fixed link at `xyz_mm` on `tip`, as URDF text to insert before `</robot>`.
fn reflector_link_xml(link: &str, tip: &str, xyz_mm: &Vector3<f64>) -> String {
    let xyz = [xyz_mm.x, xyz_mm.y, xyz_mm.z]
        .map(|v| fmt_num(v / 1000.0))
        .join(" ");
    let (link, tip) = (escape(link), escape(tip));
    format!(
        "  <link name=\"{link}\">\n    <visual>\n      <geometry>\n        <sphere radius=\"{REFLECTOR_RADIUS_M}\"/>\n      \
         </geometry>\n      <material name=\"dualcal_reflector\">\n        <color rgba=\"0.85 0.12 0.1 1\"/>\n      \
         </material>\n    </visual>\n  </link>\n  <joint name=\"{link}_joint\" type=\"fixed\">\n    \
         <parent link=\"{tip}\"/>\n    <child link=\"{link}\"/>\n    <origin xyz=\"{xyz}\" rpy=\"0 0 0\"/>\n  \
         </joint>\n"
    )
}

/// The reflector links of `side` as edits: the origins of existing ones (a calibrated URDF exported
/// again: `reflector_{a,b,c}_<tip>`, or `reflector_{a,b,c}_{l,r}` as the built-in robot's export
/// names them), new links `reflector_{a,b,c}_<tip>` otherwise.
fn reflector_edits(
    root: roxmltree::Node,
    side: Side,
    tip: &str,
    arm: &crate::kinematics::ArmModel,
    text: &str,
    edits: &mut Vec<(Range<usize>, String)>,
    appended: &mut String,
) -> Result<(), RobotError> {
    for (r, t) in arm.reflector_names.iter().zip(&arm.reflectors_mm) {
        let link = format!("reflector_{r}_{tip}");
        let legacy = format!("reflector_{r}_{}", crate::robot::side_suffix(side));
        let carrier_of = |name: &str| {
            root.children().find(|n| {
                n.has_tag_name("joint")
                    && n.children()
                        .any(|c| c.has_tag_name("child") && c.attribute("link") == Some(name))
            })
        };
        let carrier = carrier_of(&link).or_else(|| {
            carrier_of(&legacy).filter(|j| {
                j.children()
                    .any(|c| c.has_tag_name("parent") && c.attribute("link") == Some(tip))
            })
        });
        match carrier {
            Some(joint) => {
                let parent = joint
                    .children()
                    .find(|c| c.has_tag_name("parent"))
                    .and_then(|c| c.attribute("link"));
                if parent != Some(tip) {
                    return Err(export_err(format!(
                        "link `{link}` exists but does not hang from `{tip}`"
                    )));
                }
                let name = joint.attribute("name").unwrap_or_default().to_string();
                origin_edits(
                    text,
                    root,
                    &name,
                    &Isometry3::translation(t.x, t.y, t.z),
                    edits,
                )?;
            }
            None => appended.push_str(&reflector_link_xml(&link, tip, t)),
        }
    }
    Ok(())
}

/// Apply `edits` (non-overlapping byte ranges) to `text`.
fn apply(text: &str, mut edits: Vec<(Range<usize>, String)>) -> String {
    crate::sort::sort_by_key(&mut edits, |(r, _)| std::cmp::Reverse(r.start));
    let mut out = text.to_string();
    for (range, replacement) in edits {
        out.replace_range(range, &replacement);
    }
    out
}

/// The calibrated copy of a chain-form `robot`'s text for `model` (see the module documentation).
/// The result is checked by loading it back: its own nominal model must reproduce `model`.
pub(super) fn calibrated_chain_urdf(
    robot: &RobotDescription,
    model: &DualArmModel,
) -> Result<String, RobotError> {
    let text: &str = &robot.text;
    let doc = parse(text)?;
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(export_err("the root element is not <robot>".into()));
    }
    // Joints on both chains (a torso) are written once, from the left arm's model; the base
    // correction of such a robot is how the right arm sits on them (`SharedJoints::fold_base`).
    let shared = model.shared_joints();
    let folded;
    let model = if shared.is_empty() {
        model
    } else {
        let (l, r) = (
            model.arm(Side::Left).to_vector(),
            model.arm(Side::Right).to_vector(),
        );
        if let Some(&(a, b)) = shared.params.iter().find(|&&(a, b)| l[a] != r[b]) {
            return Err(export_err(format!(
                "the arms' models disagree on the shared joint parameter `{}` ({} and {}): a \
                 shared joint has one correction",
                model.arm(Side::Left).param_name(a),
                l[a],
                r[b]
            )));
        }
        folded = shared.fold_base(model, &robot.nominal_left_base_from_right_base());
        &folded
    };
    let mut edits: Vec<(Range<usize>, String)> = Vec::new();
    let mut appended = String::new();
    for side in Side::BOTH {
        let arm = model.arm(side);
        let (Some(chain), Some(corrections)) = (arm.chain(), arm.corrections()) else {
            return Err(export_err(format!(
                "the {side} arm's model is not a URDF chain"
            )));
        };
        if chain.joint_names() != robot.arm(side).chain.joint_names() {
            return Err(export_err(format!(
                "the {side} arm's model is for the chain {}, the robot's is {}",
                chain.describe(),
                robot.arm(side).chain.describe()
            )));
        }
        let mut origins = chain.corrected_origins(corrections);
        if side == Side::Right && shared.is_empty() {
            origins[0].1 = chain.first_origin_with_base_correction(
                &origins[0].1,
                &robot.nominal_left_base_from_right_base(),
                &model.left_base_from_right_base,
            );
        }
        for (k, (name, origin)) in origins.iter().enumerate() {
            // A joint without correction (the first one, always fixed) keeps its text.
            let moved = corrections[k].iter().any(|v| *v != 0.0)
                || (side == Side::Right && k == 0 && shared.is_empty());
            let written_by_left = side == Side::Right && shared.joints.iter().any(|j| j.1 == k);
            if moved && !written_by_left {
                origin_edits(text, root, name, origin, &mut edits)?;
            }
        }
        if side == Side::Right && model.is_one_arm() {
            // A single-arm robot: its one arm's reflectors are the left's, written already.
            continue;
        }
        reflector_edits(
            root,
            side,
            &chain.tip_link,
            arm,
            text,
            &mut edits,
            &mut appended,
        )?;
    }
    if !appended.is_empty() {
        let end = root.range().end;
        let close = text[..end]
            .rfind("</")
            .ok_or_else(|| export_err("<robot> has no closing tag".into()))?;
        edits.push((close..close, appended));
    }
    let from = robot.name().replace("--", "- -");
    let names = &model.arm(Side::Left).reflector_names;
    let reflector_links = match names.len() {
        1 => format!("link reflector_{}_<tip>", names[0]),
        _ => format!("links reflector_{{{}}}_<tip>", names.join(",")),
    }
    .replace("--", "- -");
    edits.push((
        root.range().start..root.range().start,
        format!(
            "<!-- Calibrated by dualcal {} from {from}: only the arm joints' origins differ (each by the \
             identified correction; {}); the identified reflectors are the {reflector_links}. -->\n",
            env!("CARGO_PKG_VERSION"),
            if shared.is_empty() {
                "the right arm's first joint also by the base correction".to_string()
            } else {
                format!(
                    "the joints both arms share ({}) once; the right arm's first joint of its own \
                     also by the base correction",
                    shared.names.join(", ").replace("--", "- -")
                )
            }
        ),
    ));
    let out = apply(text, edits);
    verify(robot, model, &out)?;
    Ok(out)
}

/// Load `text` back and check that its nominal model reproduces `model`: tip poses and reflectors
/// of both arms at random configurations, within 1e-6 mm.
fn verify(robot: &RobotDescription, model: &DualArmModel, text: &str) -> Result<(), RobotError> {
    let options = LoadOptions {
        arms: robot.arms().as_ref().map(|_, a| Some(a.links.clone())),
        ..Default::default()
    };
    let back = RobotDescription::load(
        crate::robot::RobotSource::Text {
            text,
            path: robot.source.as_deref(),
        },
        &options,
    )
    .map_err(|e| export_err(format!("the written URDF does not load back: {e}")))?;
    let again = back.nominal_model_named(
        &model.arm(Side::Left).reflector_names,
        &model.arm(Side::Left).reflectors_mm,
    );
    for side in Side::BOTH {
        let limits = robot.joint_limits_rad(side);
        for k in 0..8 {
            // Deterministic spread over the joint ranges.
            let q: Vec<f64> = limits
                .iter()
                .enumerate()
                .map(|(j, (lo, hi))| lo + (hi - lo) * (((k * 7 + j * 3) % 11) as f64 / 10.0))
                .collect();
            let want =
                model.left_base_from(side) * model.arm(side).reflector_fk(&q).base_from_flange;
            let got =
                again.left_base_from(side) * again.arm(side).reflector_fk(&q).base_from_flange;
            let dt = (want.translation.vector - got.translation.vector).norm();
            let dr = (want.rotation.inverse() * got.rotation).angle();
            let refl = &model.arm(side).reflectors_mm;
            let dp = (0..refl.len())
                .map(|r| (refl[r] - again.arm(side).reflectors_mm[r]).norm())
                .fold(0.0, f64::max);
            if !(dt < 1e-6 && dr < 1e-9 && dp < 1e-6) {
                return Err(export_err(format!(
                    "the written URDF does not reproduce the calibrated {side} arm ({dt:.2e} mm, \
                     {dr:.2e} rad, reflectors {dp:.2e} mm)"
                )));
            }
        }
    }
    Ok(())
}
