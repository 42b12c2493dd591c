//! Robots given as DH tables: the `dualcal-dh/1` file (TOML, docs/formats.md) and the equivalent URDF
//! it is read as.
//!
//! Each arm is frame 0 (its `base`, in the body frame) and one row per joint, in the standard
//! convention `Rz(θ + q) · Tz(d) · Tx(a) · Rx(α)` or the modified one (Craig)
//! `Rx(α) · Tx(a) · Rz(θ + q) · Tz(d)` — for a prismatic joint `q` adds to `d` instead — then the
//! `tool` (the flange in the last frame). A joint may follow another of its arm linearly
//! (`mimic = { joint, multiplier, offset }`, a URDF `<mimic>`), or several (a list: coaxial mimic
//! joints in a row, one per leader, that add up). An optional `[torso]` (its `base` in
//! the body frame and its rows, the same way) carries both arms: each arm's `base` is then in the
//! torso's last frame, and both arms' chains hold the torso's joints (shared joints, identified once).
//!
//! The URDF ([`to_urdf`]): link `body`; per arm a fixed joint `<arm>_base` to `<arm>_link_0` (frame
//! 0), the joints by their names from `<arm>_link_{k-1}` to `<arm>_link_k`, each about its z axis, and a
//! fixed joint to `<arm>_flange`. A link frame is the frame right after its joint's motion; what a DH
//! row puts after the motion (`Tz(d)·Tx(a)·Rx(α)` in the standard convention, `Tz(d)` in the modified
//! one) goes into the next joint's origin. Its forward kinematics is the table's (a test holds it to
//! 1e-9 mm on the IRB 14000's Table 3). The file carries no geometry: the URDF has no visuals or
//! collision shapes.

use crate::kinematics::rpy_from_rotation;
use crate::side::Side;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::fmt::Write as _;

/// The format tag.
pub const DH_FORMAT: &str = "dualcal-dh/1";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    format: String,
    name: Option<String>,
    convention: Convention,
    units: RawUnits,
    torso: Option<RawTorso>,
    arms: Vec<RawArm>,
}

/// `[torso]`: rows both arms hang from.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTorso {
    base: Option<RawPose>,
    joints: Vec<RawJoint>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum Convention {
    Standard,
    Modified,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawUnits {
    length: String,
    angle: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPose {
    xyz: [f64; 3],
    rpy: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawArm {
    name: String,
    base: Option<RawPose>,
    tool: Option<RawPose>,
    joints: Vec<RawJoint>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: String,
    #[serde(rename = "type", default)]
    kind: Option<String>,
    d: f64,
    theta: f64,
    a: f64,
    alpha: f64,
    limits: Option<[f64; 2]>,
    mimic: Option<MimicSpec>,
}

/// A joint's coupling: one leader (a URDF `<mimic>`), or several — `q = Σ multiplierᵢ · leaderᵢ +
/// Σ offsetᵢ` (DLR's passive torso joint, `−(q₁ + q₂)`) — written as that many coaxial joints in a
/// row, each mimicking one leader (turns about one axis add up).
#[derive(Deserialize)]
#[serde(untagged)]
enum MimicSpec {
    One(RawMimic),
    Many(Vec<RawMimic>),
}

impl MimicSpec {
    fn leaders(&self) -> &[RawMimic] {
        match self {
            MimicSpec::One(m) => std::slice::from_ref(m),
            MimicSpec::Many(v) => v,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMimic {
    joint: String,
    multiplier: Option<f64>,
    offset: Option<f64>,
}

/// Is `text` a DH robot file (its `format` key)?
pub fn is_dh_file(text: &str) -> bool {
    text.lines().any(|l| {
        let l = l.trim();
        l.starts_with("format") && l.contains(DH_FORMAT)
    })
}

/// The URDF of a `dualcal-dh/1` file (module documentation), or what is wrong with the file.
pub fn to_urdf(text: &str) -> Result<String, String> {
    let raw: RawFile = toml::from_str(text).map_err(|e| e.to_string())?;
    if raw.format != DH_FORMAT {
        return Err(format!("format `{}`: expected `{DH_FORMAT}`", raw.format));
    }
    let mm_per = match raw.units.length.as_str() {
        "mm" => 1.0,
        "m" => 1000.0,
        other => return Err(format!("units.length `{other}`: expected `mm` or `m`")),
    };
    let rad_per = match raw.units.angle.as_str() {
        "deg" => 1f64.to_radians(),
        "rad" => 1.0,
        other => return Err(format!("units.angle `{other}`: expected `deg` or `rad`")),
    };
    let names: Vec<&str> = raw.arms.iter().map(|a| a.name.as_str()).collect();
    if names.len() != 2 || !names.contains(&"left") || !names.contains(&"right") {
        return Err(format!(
            "arms {names:?}: expected exactly one arm named `left` and one named `right`"
        ));
    }
    let robot = raw.name.as_deref().unwrap_or("dh_robot");
    let mut urdf = format!(
        "<?xml version=\"1.0\"?>\n<!-- Written by dualcal from a {DH_FORMAT} table ({} DH). -->\n\
         <robot name=\"{}\">\n  <link name=\"body\"/>\n",
        match raw.convention {
            Convention::Standard => "standard",
            Convention::Modified => "modified",
        },
        escape(robot)
    );
    // The torso, written as a chain `torso` from the body; the arms hang from its last frame.
    let torso = raw.torso.map(|t| RawArm {
        name: "torso".into(),
        base: t.base,
        tool: None,
        joints: t.joints,
    });
    let mut all_names: Vec<&str> = Vec::new();
    let mut parent = "body";
    for arm in torso.iter().chain(&raw.arms) {
        for j in &arm.joints {
            if all_names.contains(&j.name.as_str()) {
                return Err(format!("joint `{}` named twice", j.name));
            }
            all_names.push(&j.name);
        }
        urdf += &arm_urdf(arm, raw.convention, mm_per, rad_per, parent)?;
        if arm.name == "torso" {
            parent = "torso_flange";
        }
    }
    urdf += "</robot>\n";
    Ok(urdf)
}

/// The arm `left`/`right` of a DH file's URDF: `body` to `<arm>_flange`.
pub fn arm_links(side: Side) -> crate::kinematics::ArmLinks {
    crate::kinematics::ArmLinks::new("body", format!("{}_flange", side.name()))
}

fn pose(
    p: Option<&RawPose>,
    mm_per: f64,
    rad_per: f64,
    what: &str,
) -> Result<Isometry3<f64>, String> {
    let Some(p) = p else {
        return Ok(Isometry3::identity());
    };
    if p.xyz.iter().chain(&p.rpy).any(|v| !v.is_finite()) {
        return Err(format!("{what}: expected finite numbers"));
    }
    let t = Vector3::from(p.xyz) * mm_per;
    let r = UnitQuaternion::from_euler_angles(
        p.rpy[0] * rad_per,
        p.rpy[1] * rad_per,
        p.rpy[2] * rad_per,
    );
    Ok(Isometry3::from_parts(Translation3::from(t), r))
}

fn rot_z(a: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a),
    )
}

fn rot_x(a: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a),
    )
}

/// The URDF of one arm (or the torso) of a DH file, from `parent` (`body`, or the torso's last frame)
/// to `<arm>_flange`.
fn arm_urdf(
    arm: &RawArm,
    convention: Convention,
    mm_per: f64,
    rad_per: f64,
    parent: &str,
) -> Result<String, String> {
    let n = &arm.name;
    let base = pose(
        arm.base.as_ref(),
        mm_per,
        rad_per,
        &format!("arms.{n}.base"),
    )?;
    let tool = pose(
        arm.tool.as_ref(),
        mm_per,
        rad_per,
        &format!("arms.{n}.tool"),
    )?;
    let mut s = String::new();
    fixed(
        &mut s,
        &format!("{n}_base"),
        parent,
        &format!("{n}_link_0"),
        &base,
    );
    // What the previous row left after its motion.
    let mut tail = Isometry3::identity();
    for k in 0..arm.joints.len() {
        let units = Units { mm_per, rad_per };
        let (xml, after) = joint_urdf(arm, k, convention, units, &tail)?;
        s += &xml;
        tail = after;
    }
    let last = arm.joints.len();
    fixed(
        &mut s,
        &format!("{n}_flange_joint"),
        &format!("{n}_link_{last}"),
        &format!("{n}_flange"),
        &(tail * tool),
    );
    Ok(format!(
        "  <link name=\"{n}_link_0\"/>\n  <link name=\"{n}_flange\"/>\n{s}"
    ))
}

/// The file's units: mm and rad per unit.
#[derive(Clone, Copy)]
struct Units {
    mm_per: f64,
    rad_per: f64,
}

/// Joint `k` of `arm` (its link and joint elements) after `tail`, and what its row leaves after
/// the motion.
fn joint_urdf(
    arm: &RawArm,
    k: usize,
    convention: Convention,
    Units { mm_per, rad_per }: Units,
    tail: &Isometry3<f64>,
) -> Result<(String, Isometry3<f64>), String> {
    let (n, j) = (&arm.name, &arm.joints[k]);
    let field = format!("arms.{n}.joints[{k}] `{}`", j.name);
    if [j.d, j.theta, j.a, j.alpha].iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "{field}: d, theta, a, alpha: expected finite numbers"
        ));
    }
    let prismatic = match j.kind.as_deref() {
        None | Some("revolute") => false,
        Some("prismatic") => true,
        Some(other) => {
            return Err(format!(
                "{field}: type `{other}`: expected `revolute` or `prismatic`"
            ));
        }
    };
    let (d, theta, a, alpha) = (
        j.d * mm_per,
        j.theta * rad_per,
        j.a * mm_per,
        j.alpha * rad_per,
    );
    let tz = |v: f64| Isometry3::translation(0.0, 0.0, v);
    let tx = |v: f64| Isometry3::translation(v, 0.0, 0.0);
    // The joint's origin (up to its motion) and what follows its motion.
    let (origin, after) = match (convention, prismatic) {
        (Convention::Standard, false) => (tail * rot_z(theta), tz(d) * tx(a) * rot_x(alpha)),
        (Convention::Standard, true) => (tail * rot_z(theta) * tz(d), tx(a) * rot_x(alpha)),
        (Convention::Modified, false) => (tail * rot_x(alpha) * tx(a) * rot_z(theta), tz(d)),
        (Convention::Modified, true) => (
            tail * rot_x(alpha) * tx(a) * rot_z(theta) * tz(d),
            Isometry3::identity(),
        ),
    };
    let unit = if prismatic { mm_per / 1000.0 } else { rad_per };
    let limits = match j.limits {
        Some([lo, hi]) if lo.is_finite() && hi.is_finite() && lo < hi => {
            Some((lo * unit, hi * unit))
        }
        Some(_) => {
            return Err(format!(
                "{field}: limits: expected [lower, upper], lower < upper"
            ));
        }
        None if prismatic => return Err(format!("{field}: a prismatic joint needs its limits")),
        None => None,
    };
    let kind = match (prismatic, limits) {
        (true, _) => "prismatic",
        (false, Some(_)) => "revolute",
        (false, None) => "continuous",
    };
    let leaders = j.mimic.as_ref().map_or(&[][..], MimicSpec::leaders);
    if j.mimic.is_some() && leaders.is_empty() {
        return Err(format!(
            "{field}: mimic: expected a leader (or a list of leaders)"
        ));
    }
    for m in leaders {
        if !arm.joints[..k].iter().any(|o| o.name == m.joint) {
            return Err(format!(
                "{field}: mimic joint `{}`: expected an earlier joint of the same arm",
                m.joint
            ));
        }
        if !m.multiplier.unwrap_or(1.0).is_finite() || !m.offset.unwrap_or(0.0).is_finite() {
            return Err(format!(
                "{field}: mimic joint `{}`: expected finite multiplier and offset",
                m.joint
            ));
        }
    }
    let mimic_xml = |m: &RawMimic| {
        format!(
            "\n    <mimic joint=\"{}\" multiplier=\"{:?}\" offset=\"{:?}\"/>",
            escape(&m.joint),
            m.multiplier.unwrap_or(1.0),
            m.offset.unwrap_or(0.0) * unit
        )
    };
    let limit = limits.map_or(String::new(), |(lo, hi)| {
        format!("\n    <limit lower=\"{lo:?}\" upper=\"{hi:?}\" effort=\"100\" velocity=\"1\"/>")
    });
    // With several leaders the row's motion is split over coaxial joints, one per leader: the first
    // carries the row's name and origin, the others (`<name>_coupling_<i>`) sit on it.
    let parts = leaders.len().max(1);
    let child = |i: usize| {
        if i + 1 == parts {
            format!("{n}_link_{}", k + 1)
        } else {
            format!("{n}_link_{}_coupling_{}", k + 1, i + 1)
        }
    };
    let mut xml = String::new();
    for i in 0..parts {
        let (name, parent, origin) = if i == 0 {
            (j.name.clone(), format!("{n}_link_{k}"), origin_xml(&origin))
        } else {
            (
                format!("{}_coupling_{}", j.name, i + 1),
                child(i - 1),
                origin_xml(&Isometry3::identity()),
            )
        };
        let _ = write!(
            xml,
            "  <link name=\"{}\"/>\n  <joint name=\"{}\" type=\"{kind}\">\n    <parent \
             link=\"{}\"/>\n    <child link=\"{}\"/>\n    {origin}\n    <axis xyz=\"0 0 \
             1\"/>{limit}{}\n  </joint>\n",
            escape(&child(i)),
            escape(&name),
            escape(&parent),
            escape(&child(i)),
            leaders.get(i).map_or(String::new(), mimic_xml)
        );
    }
    Ok((xml, after))
}

fn fixed(s: &mut String, name: &str, parent: &str, child: &str, origin: &Isometry3<f64>) {
    let _ = write!(
        s,
        "  <joint name=\"{name}\" type=\"fixed\">\n    <parent link=\"{parent}\"/>\n    <child \
         link=\"{child}\"/>\n    {}\n  </joint>\n",
        origin_xml(origin)
    );
}

/// `<origin xyz rpy>` in metres and radians, every digit kept.
fn origin_xml(iso: &Isometry3<f64>) -> String {
    let t = iso.translation.vector / 1000.0;
    let [r, p, y] = rpy_from_rotation(&iso.rotation.to_rotation_matrix());
    format!(
        "<origin xyz=\"{:?} {:?} {:?}\" rpy=\"{r:?} {p:?} {y:?}\"/>",
        t.x, t.y, t.z
    )
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
