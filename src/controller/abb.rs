//! ABB controllers: the arms' base frames as the controller's motion configuration (MOC) holds them.
//!
//! Each mechanical unit's `ROBOT` instance carries `-base_frame_pos_x/_y/_z` (metres, in the world
//! frame) and `-base_frame_orient_u0 … _u3` (a unit quaternion, scalar first) — the attributes ABB's
//! own calibration modules and ros-industrial's abb_librws read and write. [`to_cfg`] writes them as
//! a `MOC.cfg` fragment of `ROBOT` instances holding only those attributes, [`parse_cfg`] reads them
//! back from such a fragment or from a whole `MOC.cfg`. The quaternion is written with u0 ≥ 0 and 12
//! decimals, positions with 10 (0.1 nm).

use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::fmt::Write as _;

/// One mechanical unit's base frame: the `ROBOT` instance `name`, its position in metres and its
/// orientation `[u0, u1, u2, u3]` (w, x, y, z).
#[derive(Clone, Debug, PartialEq)]
pub struct BaseFrame {
    pub name: String,
    pub pos_m: Vector3<f64>,
    pub orient: [f64; 4],
}

impl BaseFrame {
    /// A frame given in mm (our unit) as the controller writes it.
    pub fn from_isometry_mm(name: &str, world_from_base_mm: &Isometry3<f64>) -> Self {
        let q = world_from_base_mm.rotation;
        let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
        Self {
            name: name.to_string(),
            pos_m: world_from_base_mm.translation.vector / 1000.0,
            orient: [sign * q.w, sign * q.i, sign * q.j, sign * q.k],
        }
    }

    /// The frame in mm. The quaternion is normalised (a controller's file holds a few digits).
    pub fn isometry_mm(&self) -> Isometry3<f64> {
        let [w, x, y, z] = self.orient;
        Isometry3::from_parts(
            Translation3::from(self.pos_m * 1000.0),
            UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
        )
    }
}

/// The default `ROBOT` instance names: the IRB 14000's arms.
pub const YUMI_UNIT_NAMES: [&str; 2] = ["ROB_L", "ROB_R"];

/// The names of the two arms' mechanical units (`ROB_L`, `ROB_R` for the YuMi).
pub fn unit_names(names: Option<&PerSide<String>>) -> PerSide<String> {
    names.cloned().unwrap_or_else(|| {
        PerSide::new(
            YUMI_UNIT_NAMES[0].to_string(),
            YUMI_UNIT_NAMES[1].to_string(),
        )
    })
}

/// A `MOC.cfg` fragment: the header line, a comment, and one `ROBOT` instance per frame.
pub fn to_cfg(frames: &[BaseFrame], comment: &str) -> String {
    let mut s = String::from("MOC:CFG_1.0:6:0::\n#\n");
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    s.push_str("#\nROBOT:\n");
    for f in frames {
        let [u0, u1, u2, u3] = f.orient.map(|u| number(u, 12));
        let [x, y, z] = [f.pos_m.x, f.pos_m.y, f.pos_m.z].map(|v| number(v, 10));
        let _ = write!(
            s,
            "\n      -name \"{}\" -base_frame_pos_x {x} -base_frame_pos_y {y}\\\n      \
             -base_frame_pos_z {z} -base_frame_orient_u0 {u0}\\\n      \
             -base_frame_orient_u1 {u1} -base_frame_orient_u2 {u2}\\\n      \
             -base_frame_orient_u3 {u3}\n",
            f.name
        );
    }
    s
}

/// `v` with `decimals` decimals, trailing zeros dropped (0.1 nm and 1e-12 of a quaternion: far below
/// what a controller resolves, and a file a person can read).
fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        "-0" | "" => "0".to_string(),
        s => s.to_string(),
    }
}

/// Why a configuration file could not be read: the line (1-based) and what was wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct CfgError {
    pub line: usize,
    pub message: String,
}

/// The `-name … -base_frame_…` attributes of every `ROBOT` instance of a `MOC.cfg` (a whole file or
/// a fragment), in file order. An instance without base-frame attributes is skipped (a controller's
/// file may omit them, meaning the identity); one with some but not all seven is refused.
pub fn parse_cfg(text: &str) -> Result<Vec<BaseFrame>, CfgError> {
    const KEYS: [&str; 7] = [
        "base_frame_pos_x",
        "base_frame_pos_y",
        "base_frame_pos_z",
        "base_frame_orient_u0",
        "base_frame_orient_u1",
        "base_frame_orient_u2",
        "base_frame_orient_u3",
    ];
    let mut frames = Vec::new();
    let mut in_robot = false;
    // Instances: lines joined over trailing backslashes, each with the line it starts on.
    let mut instances: Vec<(usize, String)> = Vec::new();
    let mut open: Option<(usize, String)> = None;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim_end_matches('\r');
        let t = line.trim();
        if open.is_none() {
            if t.starts_with('#') || t.is_empty() {
                continue;
            }
            if let Some(topic) = t.strip_suffix(':').filter(|s| !s.starts_with('-')) {
                in_robot = topic == "ROBOT";
                continue;
            }
        }
        if !in_robot {
            continue;
        }
        let (body, continues) = match t.strip_suffix('\\') {
            Some(b) => (b, true),
            None => (t, false),
        };
        match &mut open {
            Some((_, acc)) => {
                acc.push(' ');
                acc.push_str(body);
            }
            None => open = Some((k + 1, body.to_string())),
        }
        if !continues && let Some(done) = open.take() {
            instances.push(done);
        }
    }
    if let Some(done) = open.take() {
        instances.push(done);
    }
    for (line, instance) in instances {
        let attrs = attributes(&instance).map_err(|message| CfgError { line, message })?;
        let get = |key: &str| {
            attrs
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        };
        let Some(name) = get("name") else { continue };
        let found: Vec<Option<&str>> = KEYS.iter().map(|k| get(k)).collect();
        if found.iter().all(Option::is_none) {
            continue;
        }
        let mut values = [0.0; 7];
        for (v, (key, text)) in values.iter_mut().zip(KEYS.iter().zip(&found)) {
            let text = text.ok_or_else(|| CfgError {
                line,
                message: format!("ROBOT \"{name}\": `-{key}` missing (the others are given)"),
            })?;
            *v = text
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| CfgError {
                    line,
                    message: format!(
                        "ROBOT \"{name}\": `-{key}`: expected a number, found `{text}`"
                    ),
                })?;
        }
        let orient = [values[3], values[4], values[5], values[6]];
        let norm = orient.iter().map(|u| u * u).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(CfgError {
                line,
                message: format!(
                    "ROBOT \"{name}\": the base frame's quaternion has norm {norm}: expected a unit \
                     quaternion (u0 … u3)"
                ),
            });
        }
        frames.push(BaseFrame {
            name: name.to_string(),
            pos_m: Vector3::new(values[0], values[1], values[2]),
            orient,
        });
    }
    Ok(frames)
}

/// `-key value` pairs of one instance; a value may be a quoted string.
fn attributes(instance: &str) -> Result<Vec<(String, String)>, String> {
    let mut out = Vec::new();
    let mut rest = instance.trim();
    while !rest.is_empty() {
        let Some(after) = rest.strip_prefix('-') else {
            return Err(format!(
                "expected `-attribute value`, found `{}`",
                crate::textfile::excerpt(rest)
            ));
        };
        let (key, tail) = after.split_once(char::is_whitespace).unwrap_or((after, ""));
        let tail = tail.trim_start();
        let (value, tail) = if let Some(quoted) = tail.strip_prefix('"') {
            let end = quoted
                .find('"')
                .ok_or_else(|| format!("`-{key}`: a quoted value without its closing quote"))?;
            (quoted[..end].to_string(), &quoted[end + 1..])
        } else if tail.starts_with('-') && tail[1..].starts_with(|c: char| c.is_ascii_alphabetic())
        {
            // A flag without a value.
            (String::new(), tail)
        } else {
            let end = tail.find(char::is_whitespace).unwrap_or(tail.len());
            (tail[..end].to_string(), &tail[end..])
        };
        out.push((key.to_string(), value));
        rest = tail.trim_start();
    }
    Ok(out)
}

/// The frame of `side` among `frames` by its unit name.
pub fn frame_of<'f>(
    frames: &'f [BaseFrame],
    names: &PerSide<String>,
    side: Side,
) -> Option<&'f BaseFrame> {
    frames.iter().find(|f| f.name == names[side])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_fragment_reads_back_exactly() {
        let frames = [
            BaseFrame::from_isometry_mm(
                "ROB_L",
                &Isometry3::from_parts(
                    Translation3::new(53.55, 72.5, 414.92),
                    UnitQuaternion::from_euler_angles(-0.9795, -0.5682, -2.3155),
                ),
            ),
            BaseFrame::from_isometry_mm(
                "ROB_R",
                &Isometry3::from_parts(
                    Translation3::new(53.55, -72.5, 414.92),
                    UnitQuaternion::from_euler_angles(0.9781, -0.5716, 2.3180),
                ),
            ),
        ];
        let text = to_cfg(&frames, "test\nsecond line");
        let back = parse_cfg(&text).unwrap();
        for (b, f) in back.iter().zip(&frames) {
            assert_eq!(b.name, f.name);
            let d = b.isometry_mm().inverse() * f.isometry_mm();
            assert!(d.translation.vector.norm() < 1e-6 && d.rotation.angle() < 1e-11);
        }
        assert!(frames.iter().all(|f| f.orient[0] >= 0.0));
    }

    #[test]
    fn a_whole_moc_file_is_read_and_bad_values_are_refused_with_their_line() {
        let text = "MOC:CFG_1.0:6:0::\n#\nARM:\n\n      -name \"rob_l_1\" -use_arm_type \"x\"\n\n\
                    ROBOT:\n\n      -name \"ROB_L\" -use_robot_serial_number \"rob_l\"\\\n      \
                    -use_robot_type \"ROB_L_14000_0.5_0.5\" -base_frame_pos_x 0.0476\\\n      \
                    -base_frame_pos_y 0.07 -base_frame_pos_z 0.4115 -base_frame_orient_u0 0.5\\\n      \
                    -base_frame_orient_u1 -0.5 -base_frame_orient_u2 0.5\\\n      \
                    -base_frame_orient_u3 -0.5 -upper_bound 1\n\n      -name \"ROB_R\" -use_robot_type \"R\"\n";
        let frames = parse_cfg(text).unwrap();
        assert_eq!(frames.len(), 1);
        assert_eq!(frames[0].name, "ROB_L");
        assert_eq!(frames[0].pos_m, Vector3::new(0.0476, 0.07, 0.4115));
        let bad = text.replace("-base_frame_pos_y 0.07", "-base_frame_pos_y 0,07");
        let e = parse_cfg(&bad).unwrap_err();
        assert_eq!(e.line, 9);
        assert!(e.message.contains("base_frame_pos_y"), "{e}");
        let partial = text.replace(" -base_frame_orient_u3 -0.5", "");
        assert!(
            parse_cfg(&partial)
                .unwrap_err()
                .message
                .contains("orient_u3")
        );
        let unnormalised = text.replace("-base_frame_orient_u0 0.5", "-base_frame_orient_u0 0.9");
        assert!(parse_cfg(&unnormalised).is_err());
    }
}
