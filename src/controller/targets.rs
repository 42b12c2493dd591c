//! Target lists for [`super::compensate`]: a CSV of one arm's targets in, the compensated joint values
//! out.
//!
//! In: a header, then one target per row (`#` comment lines and blank lines skipped):
//! - **joint targets** `id,q1,…,qN` (or the joints' names in chain order instead of `q1…qN`): the
//!   nominal joint values, angles in degrees (or radians), a prismatic joint in mm (or m);
//! - **poses** `id,x,y,z,qw,qx,qy,qz` and optionally the seed joints `q1,…,qN`: the flange pose in
//!   the arm's model base frame as the nominal model places it (mm or m; a unit quaternion, scalar
//!   first), and the joint values to start from (without them, the previous row's result; the first
//!   row starts at the middle of every joint's range).
//!
//! Out: `id,q1,…,qN,largest_change,residual_mm,residual_mrad,status` — the compensated joints in the
//! units of the input, the largest joint change (same units: degrees or mm), the remaining pose error
//! of the calibrated model, and `ok` or the reason the target was refused (its joint columns then
//! empty).

use super::compensate::{Compensated, Refusal, Target};
use crate::dataset::{AngleUnit, LengthUnit};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A target list that cannot be read: the file, the line (1-based; 0: the file as a whole), the
/// field and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}:{line}: field `{field}`: {message}")]
pub struct TargetsError {
    pub path: PathBuf,
    pub line: usize,
    pub field: String,
    pub message: String,
}

/// One row of a target list.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetRow {
    pub id: String,
    pub line: usize,
    /// The target; a pose's seed is empty when the row gives none (filled by the caller).
    pub target: Target,
}

/// The units of a target list's joint values and lengths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetUnits {
    pub angle: AngleUnit,
    pub length: LengthUnit,
}

/// Read a target list of an arm whose joints are `joint_names` (chain order; `linear[i]`: joint i is
/// prismatic).
pub fn parse(
    path: &Path,
    text: &str,
    joint_names: &[String],
    linear: &[bool],
    units: TargetUnits,
) -> Result<Vec<TargetRow>, TargetsError> {
    let cx = Context {
        path,
        linear,
        units,
    };
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_line, header)) = rows.next() else {
        return Err(cx.err(
            0,
            "id",
            "an empty file: expected a header `id,q1,…` or `id,x,y,z,qw,qx,qy,qz`".into(),
        ));
    };
    let layout = cx.header(header_line, header, joint_names)?;
    let out = rows
        .map(|(line, text)| cx.row(&layout, line, text))
        .collect::<Result<Vec<_>, _>>()?;
    if out.is_empty() {
        return Err(cx.err(header_line, "id", "a header without targets".into()));
    }
    Ok(out)
}

/// What a target list's header says: its column names, whether rows are poses, where the joints are.
struct Layout {
    names: Vec<String>,
    pose: bool,
    joints: Option<Vec<usize>>,
}

/// The file and units the rows are read with.
struct Context<'a> {
    path: &'a Path,
    linear: &'a [bool],
    units: TargetUnits,
}

impl Context<'_> {
    fn err(&self, line: usize, field: &str, message: String) -> TargetsError {
        TargetsError {
            path: self.path.to_path_buf(),
            line,
            field: field.to_string(),
            message,
        }
    }

    /// The header: `id`, then the joints (numbered or by name) or the pose and optional seeds.
    fn header(
        &self,
        line: usize,
        header: &str,
        joint_names: &[String],
    ) -> Result<Layout, TargetsError> {
        let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
        let n = joint_names.len();
        if names.first().map(String::as_str) != Some("id") {
            return Err(self.err(
                line,
                names.first().map_or("", String::as_str),
                "expected `id` as the first column".into(),
            ));
        }
        let numbered: Vec<String> = (1..=n).map(|k| format!("q{k}")).collect();
        let joint_columns = |from: usize| -> Option<Vec<usize>> {
            let given = &names[from..];
            (given.len() == n && (given == numbered.as_slice() || given == joint_names))
                .then(|| (from..from + n).collect())
        };
        const POSE: [&str; 7] = ["x", "y", "z", "qw", "qx", "qy", "qz"];
        let pose = names.len() >= 8 && names[1..8].iter().zip(POSE).all(|(a, b)| a == b);
        let joints = if pose {
            if names.len() == 8 {
                None
            } else {
                Some(joint_columns(8).ok_or_else(|| {
                    self.err(
                        line,
                        &names[8],
                        format!("after the pose, expected the {n} seed joints q1…q{n} (or none)"),
                    )
                })?)
            }
        } else {
            Some(joint_columns(1).ok_or_else(|| {
                self.err(
                    line,
                    names.get(1).map_or("", String::as_str),
                    format!(
                        "expected `id` and the arm's {n} joints `q1…q{n}` (or by name: {}), or a \
                         pose `id,x,y,z,qw,qx,qy,qz`",
                        joint_names.join(", ")
                    ),
                )
            })?)
        };
        Ok(Layout {
            names,
            pose,
            joints,
        })
    }

    /// One target row.
    fn row(&self, layout: &Layout, line: usize, text: &str) -> Result<TargetRow, TargetsError> {
        let names = &layout.names;
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(self.err(
                line,
                "",
                format!(
                    "expected {} fields as the header, found {}",
                    names.len(),
                    fields.len()
                ),
            ));
        }
        let number = |c: usize| -> Result<f64, TargetsError> {
            fields[c]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    self.err(
                        line,
                        &names[c],
                        format!(
                            "expected a number, found `{}`",
                            crate::textfile::excerpt(fields[c])
                        ),
                    )
                })
        };
        let id = fields[0].to_string();
        if id.is_empty() {
            return Err(self.err(line, "id", "an empty id".into()));
        }
        let joint_value = |i: usize, v: f64| {
            if self.linear.get(i).copied().unwrap_or(false) {
                self.units.length.to_mm(v)
            } else {
                self.units.angle.to_rad(v)
            }
        };
        let q = match &layout.joints {
            Some(cols) => cols
                .iter()
                .enumerate()
                .map(|(i, &c)| number(c).map(|v| joint_value(i, v)))
                .collect::<Result<Vec<f64>, _>>()?,
            None => Vec::new(),
        };
        let target = if layout.pose {
            let v = (1..8).map(number).collect::<Result<Vec<f64>, _>>()?;
            let quat = Quaternion::new(v[3], v[4], v[5], v[6]);
            let norm = quat.norm();
            if (norm - 1.0).abs() > 1e-3 {
                return Err(self.err(
                    line,
                    "qw",
                    format!(
                        "the quaternion has norm {norm}: expected a unit quaternion (qw, qx, qy, qz)"
                    ),
                ));
            }
            let mm = |k: usize| self.units.length.to_mm(v[k]);
            Target::Pose {
                base_from_flange: Isometry3::from_parts(
                    Translation3::new(mm(0), mm(1), mm(2)),
                    UnitQuaternion::from_quaternion(quat),
                ),
                seed: q,
            }
        } else {
            Target::Joints(q)
        };
        Ok(TargetRow { id, line, target })
    }
}

/// The output table (module documentation): one row per target, `results[k]` for `rows[k]`.
pub fn to_csv(
    rows: &[TargetRow],
    results: &[Result<Compensated, Refusal>],
    joint_names: &[String],
    linear: &[bool],
    units: TargetUnits,
) -> String {
    let n = joint_names.len();
    let mut s = String::from("id");
    for k in 1..=n {
        let _ = write!(s, ",q{k}");
    }
    s.push_str(",largest_change,residual_mm,residual_mrad,status\n");
    let value = |i: usize, v: f64| {
        if linear.get(i).copied().unwrap_or(false) {
            units.length.from_mm(v)
        } else {
            units.angle.from_rad(v)
        }
    };
    for (row, result) in rows.iter().zip(results) {
        s.push_str(&row.id);
        match result {
            Ok(c) => {
                for (i, &q) in c.q.iter().enumerate() {
                    let _ = write!(s, ",{:?}", value(i, q));
                }
                // The largest change in the unit of the joint it belongs to.
                let start = row.target.start();
                let change =
                    c.q.iter()
                        .zip(start)
                        .enumerate()
                        .map(|(i, (a, b))| (value(i, *a) - value(i, *b)).abs())
                        .fold(0.0, f64::max);
                let _ = writeln!(
                    s,
                    ",{change:?},{:?},{:?},ok",
                    c.residual_mm,
                    c.residual_rad * 1000.0
                );
            }
            Err(e) => {
                s.push_str(&",".repeat(n + 3));
                let _ = writeln!(s, ",\"refused: {}\"", e.to_string().replace('"', "'"));
            }
        }
    }
    s
}
