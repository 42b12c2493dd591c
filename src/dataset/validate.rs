//! Plausibility checks of a dataset's values, on parsed values (ids, joint vectors, points): what
//! [`super::load`] refuses beyond syntax — data files outside the dataset directory, absurd magnitudes,
//! coordinates that do not fit the declared unit, collinear or coincident reflectors, rows pasted twice —
//! and, once the robot is known, joint values outside its limits ([`check_joint_limits`]).
//! `docs/reliability.md` lists every rule and why it refuses rather than warns.

use super::error::DatasetError;
use super::units::LengthUnit;
use super::{ArmData, Dataset, Measurement};
use crate::kinematics::{reflector_pairs, reflector_sides};
use crate::side::PerSide;
use crate::textfile::excerpt;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// Largest accepted |coordinate| of a measured point, mm: 200 m, beyond the range of any laser tracker.
pub const MAX_COORDINATE_MM: f64 = 200_000.0;
/// Largest accepted tracker MPE term (`mpe_um`, `mpe_um_per_m`), µm: laser trackers measure to tens of
/// micrometres; 10 mm is no tracker (or the value is in another unit).
pub const MAX_MPE_UM: f64 = 10_000.0;
/// Largest accepted |joint value|, rad (about 16 turns): anything larger is not a joint reading.
pub const MAX_JOINT_RAD: f64 = 100.0;
/// How far a joint value may lie outside the robot description's limits before it is refused, rad
/// (0.5°: a controller may report a position slightly past a limit it was commanded to).
pub const JOINT_LIMIT_TOLERANCE_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// The same for a prismatic joint, mm.
pub const JOINT_LIMIT_TOLERANCE_MM: f64 = 0.5;
/// Accepted ratio of the measured reflector triangles' size (median over an arm's rows) to the nominal
/// triangle's: outside [1/2, 2] the coordinates do not fit the declared unit or the nominal reflectors.
pub const TRIANGLE_SCALE_RANGE: (f64, f64) = (0.5, 2.0);
/// A row's triangle is degenerate when its shortest side, or its smallest height, is below this
/// fraction of the nominal triangle's.
pub const DEGENERATE_FRACTION: f64 = 0.1;
/// The nominal reflector triangle must have sides of at least this, mm…
pub const MIN_NOMINAL_SIDE_MM: f64 = 1.0;
/// … and its reflectors must lie within this distance of the flange origin, mm.
pub const MAX_NOMINAL_REFLECTOR_MM: f64 = 2000.0;

/// Longest path accepted in the manifest, characters (and 255 bytes per component, as file systems
/// allow): the path is quoted in messages.
pub const MAX_PATH_CHARS: usize = 1024;
/// Longest configuration id, characters: ids are labels, quoted in reports.
pub const MAX_ID_CHARS: usize = 128;

/// A path written in the manifest is one line of printable characters of usable length. `Err` is the
/// message.
pub(super) fn usable_path(path: &str) -> Result<(), String> {
    let bad = |why: &str| format!("`{}` {why}", excerpt(path));
    if path.chars().count() > MAX_PATH_CHARS {
        return Err(bad(&format!(
            "is not a usable path ({} characters; at most {MAX_PATH_CHARS})",
            path.chars().count()
        )));
    }
    if path.split(['/', '\\']).any(|c| c.len() > 255) {
        return Err(bad("has a file or directory name longer than 255 bytes"));
    }
    if path.chars().any(char::is_control) {
        return Err(bad("contains a control character (a line break, a tab, …)"));
    }
    Ok(())
}

/// A configuration id read from a CSV: at most [`MAX_ID_CHARS`] characters, no control characters.
pub(super) fn usable_id(id: &str) -> Result<(), String> {
    if id.chars().count() > MAX_ID_CHARS {
        return Err(format!(
            "id `{}` is {} characters long; ids are labels of at most {MAX_ID_CHARS}",
            excerpt(id),
            id.chars().count()
        ));
    }
    if id.chars().any(char::is_control) {
        return Err(format!(
            "id `{}` contains a control character (a line break, a tab, …)",
            excerpt(id)
        ));
    }
    Ok(())
}

/// Resolve the data file `file` named in the manifest of `dir`: it must be a relative path that stays
/// inside the dataset directory, also after following links. `Err` is the message.
pub(super) fn data_file_in(dir: &Path, file: &str) -> Result<PathBuf, String> {
    usable_path(file)?;
    let rel = Path::new(file);
    let outside = |why: &str| {
        format!(
            "`{}` {why}; data files must be inside the dataset directory and named relative to it",
            excerpt(file)
        )
    };
    let mut depth = 0usize;
    for c in rel.components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir => {
                depth = depth
                    .checked_sub(1)
                    .ok_or_else(|| outside("leads outside the dataset directory"))?;
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err(outside("is an absolute path"));
            }
        }
    }
    let path = dir.join(rel);
    // A link inside the directory may still point outside it.
    if let (Ok(dir_c), Ok(path_c)) = (dir.canonicalize(), path.canonicalize())
        && !path_c.starts_with(&dir_c)
    {
        return Err(outside("is a link to a file outside the dataset directory"));
    }
    Ok(path)
}

/// Smallest height of a triangle (twice its area over its longest side), mm; 0 when degenerate; for
/// other than three points, infinite (no triangle to be flat).
pub(crate) fn min_height(p: &[Vector3<f64>]) -> f64 {
    if p.len() != 3 {
        return f64::INFINITY;
    }
    let longest = reflector_sides(p).into_iter().fold(0.0, f64::max);
    if longest > 0.0 {
        (p[1] - p[0]).cross(&(p[2] - p[0])).norm() / longest
    } else {
        0.0
    }
}

/// "a and b", the names of a pair of reflectors.
fn pair_name(names: &[String], (i, j): (usize, usize)) -> String {
    format!("{} and {}", names[i], names[j])
}

fn fmt_len(x_mm: f64) -> String {
    if x_mm.abs() >= 0.1 || x_mm == 0.0 {
        format!("{x_mm:.1} mm")
    } else {
        format!("{x_mm:.4} mm")
    }
}

/// The nominal reflector triangle of the manifest (mm; `unit` is the declared length unit): sides of at
/// least [`MIN_NOMINAL_SIDE_MM`], reflectors within [`MAX_NOMINAL_REFLECTOR_MM`] of the flange, not
/// collinear.
pub(super) fn nominal_triangle(t: &[Vector3<f64>], unit: LengthUnit) -> Result<(), String> {
    let s = reflector_sides(t);
    let shortest = s.iter().copied().fold(f64::INFINITY, f64::min);
    let farthest = t.iter().map(|p| p.norm()).fold(0.0, f64::max);
    if !s.is_empty() && shortest < MIN_NOMINAL_SIDE_MM {
        let hint = if unit == LengthUnit::Mm && s.iter().all(|&x| x < MIN_NOMINAL_SIDE_MM) {
            ": are these metres? (`units.length` says mm)"
        } else {
            ": two reflectors coincide"
        };
        return Err(format!(
            "two nominal reflectors are {} apart{hint}",
            fmt_len(shortest)
        ));
    }
    if farthest > MAX_NOMINAL_REFLECTOR_MM {
        let hint = if unit == LengthUnit::M {
            ": are these millimetres? (`units.length` says m)"
        } else {
            ""
        };
        return Err(format!(
            "a nominal reflector lies {:.1} m from the flange origin; reflectors are mounted on the \
             flange (within {} m){hint}",
            farthest / 1000.0,
            MAX_NOMINAL_REFLECTOR_MM / 1000.0
        ));
    }
    if min_height(t) < MIN_NOMINAL_SIDE_MM {
        return Err(
            "the nominal reflectors a, b, c are (nearly) collinear: they cannot give the flange's \
             orientation"
                .into(),
        );
    }
    Ok(())
}

/// A parsed value's magnitude: `Err` is the message for the field.
pub(super) fn coordinate_magnitude(text: &str, value_mm: f64) -> Result<(), String> {
    if value_mm.abs() > MAX_COORDINATE_MM {
        return Err(format!(
            "`{}` is not a plausible coordinate: {value_mm:.3e} mm is beyond the range of any laser \
             tracker (|value| ≤ {} m)",
            excerpt(text),
            MAX_COORDINATE_MM / 1000.0
        ));
    }
    Ok(())
}

/// A parsed joint value's magnitude, read as an angle (`value_rad`) and as a prismatic joint's length
/// (`value_mm`): `Err` (the message for the field) when it is implausible as both.
pub(super) fn joint_magnitude(text: &str, value_rad: f64, value_mm: f64) -> Result<(), String> {
    if value_rad.abs() > MAX_JOINT_RAD && value_mm.abs() > MAX_COORDINATE_MM {
        return Err(format!(
            "`{}` is not a plausible joint value: {:.3e} rad is more than {:.0} turns, and as a \
             prismatic joint's travel more than {} m",
            excerpt(text),
            value_rad,
            MAX_JOINT_RAD / std::f64::consts::TAU,
            MAX_COORDINATE_MM / 1000.0
        ));
    }
    Ok(())
}

/// A revolute joint's value (`linear` false, rad) or a prismatic joint's (mm): `Err` (the message
/// for the field) when implausible.
pub(super) fn joint_value_magnitude(value: f64, linear: bool) -> Result<(), String> {
    if linear && value.abs() > MAX_COORDINATE_MM {
        return Err(format!(
            "{value:.3e} mm is not a plausible travel of a prismatic joint (|value| ≤ {} m)",
            MAX_COORDINATE_MM / 1000.0
        ));
    }
    if !linear && value.abs() > MAX_JOINT_RAD {
        return Err(format!(
            "{value:.3e} rad is not a plausible joint value (more than {:.0} turns)",
            MAX_JOINT_RAD / std::f64::consts::TAU
        ));
    }
    Ok(())
}

/// Does `ratio` lie within a factor 1.5 of `factor`?
fn near(ratio: f64, factor: f64) -> bool {
    ratio > factor / 1.5 && ratio < factor * 1.5
}

/// One arm's rows against the manifest: the measured triangles' size fits the declared unit and the
/// nominal triangle, no row's triangle is degenerate, no row repeats another's coordinates.
/// The checks a dataset's CSV gets when it is loaded, for an arm's rows made elsewhere (an import):
/// at least [`super::MIN_CONFIGS`] configurations, plausible reflector distances (the unit), no
/// degenerate triangle, no row twice — each named by the arm's file and the row's line. Coordinates
/// in mm.
pub fn check_arm_rows(
    arm: &super::ArmData,
    nominal_mm: &[Vector3<f64>],
    names: &[String],
) -> Result<(), DatasetError> {
    if arm.measurements.len() < super::MIN_CONFIGS {
        return Err(DatasetError::TooFewConfigurations {
            path: arm.file.clone(),
            side: arm.side,
            found: arm.measurements.len(),
            min: super::MIN_CONFIGS,
        });
    }
    check_arm(
        &arm.file,
        &arm.measurements,
        LengthUnit::Mm,
        nominal_mm,
        names,
    )
}

pub(super) fn check_arm(
    path: &Path,
    rows: &[Measurement],
    unit: LengthUnit,
    nominal_mm: &[Vector3<f64>],
    names: &[String],
) -> Result<(), DatasetError> {
    let nominal_sides = reflector_sides(nominal_mm);
    let pairs = reflector_pairs(nominal_mm.len());
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    // With one reflector there is no distance on the flange to check the unit by.
    let nominal_mean = mean(&nominal_sides);
    let measured_mean = if pairs.is_empty() {
        nominal_mean
    } else {
        crate::stats::median(
            &rows
                .iter()
                .map(|m| mean(&reflector_sides(&m.tracker_points_mm)))
                .collect::<Vec<_>>(),
        )
    };
    let ratio = measured_mean / nominal_mean;
    if !pairs.is_empty() && !(TRIANGLE_SCALE_RANGE.0..=TRIANGLE_SCALE_RANGE.1).contains(&ratio) {
        let declared = unit.name();
        let hint = if near(ratio, 1e-3) && unit == LengthUnit::Mm {
            "the coordinates look like metres while `units.length` in dataset.toml says mm"
                .to_string()
        } else if near(ratio, 1e3) && unit == LengthUnit::M {
            "the coordinates look like millimetres while `units.length` in dataset.toml says m"
                .to_string()
        } else if near(ratio, 1e-3) || near(ratio, 1e3) {
            format!(
                "the CSV and `[reflectors]` differ by a factor of 1000: are both in {declared} (`units.length`)?"
            )
        } else if near(ratio, 25.4) || near(ratio, 1.0 / 25.4) {
            "the CSV and `[reflectors]` differ by a factor of 25.4: is one of them in inches?"
                .into()
        } else {
            "are the nominal reflectors in dataset.toml those of this flange?".into()
        };
        return Err(DatasetError::UnitMismatch {
            path: path.to_path_buf(),
            message: format!(
                "the measured reflector triangles have sides of {} on average (median over {} rows), \
                 the nominal triangle of `[reflectors]` {}: {hint}",
                fmt_len(measured_mean),
                rows.len(),
                fmt_len(nominal_mean)
            ),
        });
    }
    let nominal_shortest = nominal_sides.iter().copied().fold(f64::INFINITY, f64::min);
    let nominal_height = min_height(nominal_mm);
    let mut seen: HashMap<Vec<u64>, &Measurement> = HashMap::new();
    for m in rows {
        let p = &m.tracker_points_mm;
        let s = reflector_sides(p);
        let (k, shortest) = s
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |b, (k, x)| if x < b.1 { (k, x) } else { b },
            );
        let degenerate = if shortest < DEGENERATE_FRACTION * nominal_shortest {
            Some(format!(
                "reflectors {} are {} apart (the nominal reflectors' shortest distance is {}): the \
                 same reflector measured twice?",
                pair_name(names, pairs[k]),
                fmt_len(shortest),
                fmt_len(nominal_shortest)
            ))
        } else if min_height(p) < DEGENERATE_FRACTION * nominal_height {
            Some(format!(
                "reflectors {} are (nearly) collinear: the triangle's smallest height is {} (nominal {})",
                names.join(", "),
                fmt_len(min_height(p)),
                fmt_len(nominal_height)
            ))
        } else {
            None
        };
        if let Some(message) = degenerate {
            return Err(DatasetError::DegenerateTriangle {
                path: path.to_path_buf(),
                line: m.line,
                message: format!("configuration `{}`: {message}", excerpt(&m.id)),
            });
        }
        if let Some(first) = seen.insert(key(m), m) {
            return Err(duplicate(path, m, path, first));
        }
    }
    Ok(())
}

/// The bit patterns of a row's reflector coordinates (what a paste repeats exactly).
fn key(m: &Measurement) -> Vec<u64> {
    m.tracker_points_mm
        .iter()
        .flat_map(|p| p.iter().map(|x| x.to_bits()))
        .collect()
}

fn duplicate(path: &Path, m: &Measurement, first_path: &Path, first: &Measurement) -> DatasetError {
    DatasetError::DuplicateRow {
        path: path.to_path_buf(),
        line: m.line,
        id: excerpt(&m.id),
        first_path: first_path.to_path_buf(),
        first_line: first.line,
        first_id: excerpt(&first.id),
    }
}

/// No row of the right arm repeats a row of the left arm (a row pasted into the other arm's file).
pub fn check_both(arms: &PerSide<ArmData>) -> Result<(), DatasetError> {
    let left: HashMap<Vec<u64>, &Measurement> =
        arms.left.measurements.iter().map(|m| (key(m), m)).collect();
    for m in &arms.right.measurements {
        if let Some(first) = left.get(&key(m)) {
            return Err(duplicate(&arms.right.file, m, &arms.left.file, first));
        }
    }
    Ok(())
}

/// Is every value within its limits? A joint whose limits are not a proper range — missing (a
/// continuous joint has none), NaN, or `lower >= upper` — is not checked.
/// `linear` flags the prismatic joints' positions (their values and limits in mm).
fn within(q: &[f64], limits: &[(f64, f64)], linear: &[bool]) -> bool {
    q.iter()
        .zip(limits)
        .enumerate()
        .all(|(i, (&v, &(lo, hi)))| {
            let proper = lo < hi; // false for NaN too
            let tol = if linear.get(i).copied().unwrap_or(false) {
                JOINT_LIMIT_TOLERANCE_MM
            } else {
                JOINT_LIMIT_TOLERANCE_RAD
            };
            !proper || (v >= lo - tol && v <= hi + tol)
        })
}

/// The first joint value of `arm` outside `limits`, as (row, joint).
fn first_violation(arm: &ArmData, limits: &[(f64, f64)]) -> Option<(usize, usize)> {
    arm.measurements.iter().enumerate().find_map(|(r, m)| {
        m.q_rad
            .iter()
            .zip(limits)
            .enumerate()
            .position(|(i, (&v, &l))| !within(&[v], &[l], &[arm.is_linear_joint(i)]))
            .map(|j| (r, j))
    })
}

/// Joint values against the robot description's limits (rad, per arm in the CSV's column order; a
/// bound may be infinite, and a joint without a proper range is not checked): the first value outside its limits by more than
/// [`JOINT_LIMIT_TOLERANCE_RAD`] is refused, with the number of others and a likely cause — two columns
/// swapped in that row, degrees in a file declared in radians, or the columns in ABB axis order.
pub fn check_joint_limits(
    dataset: &Dataset,
    limits_rad: &PerSide<Vec<(f64, f64)>>,
) -> Result<(), DatasetError> {
    for (side, arm) in dataset.arms.iter() {
        let limits = &limits_rad[side];
        let Some((row, j)) = first_violation(arm, limits) else {
            continue;
        };
        let hints = joint_limit_hints(arm, limits, row);
        return Err(joint_limit_error(arm, limits, row, j, &hints));
    }
    Ok(())
}

/// What [`check_joint_limits`] adds to the refusal of `arm`'s first value outside its limits (in row
/// `row`): how many others are outside theirs, and a likely cause.
fn joint_limit_hints(arm: &ArmData, limits: &[(f64, f64)], row: usize) -> Vec<String> {
    let bad_values = arm
        .measurements
        .iter()
        .map(|m| {
            m.q_rad
                .iter()
                .zip(limits)
                .enumerate()
                .filter(|(i, (v, l))| !within(&[**v], &[**l], &[arm.is_linear_joint(*i)]))
                .count()
        })
        .sum::<usize>();
    let mut hints = Vec::new();
    if bad_values > 1 {
        hints.push(format!(
            "{} more value(s) of this file are outside their limits",
            bad_values - 1
        ));
    }
    hints.extend(joint_limit_cause(arm, limits, &arm.measurements[row]));
    hints
}

/// The likely cause of joint values outside their limits, where one fits: degrees in a file declared
/// in radians, the columns in ABB axis order, or two columns swapped in the row `m`.
fn joint_limit_cause(arm: &ArmData, limits: &[(f64, f64)], m: &Measurement) -> Option<String> {
    let linear = &arm.linear_joints;
    let n = m.q_rad.len().min(limits.len());
    let rows_within = |f: &dyn Fn(&[f64]) -> Vec<f64>| {
        arm.measurements
            .iter()
            .all(|m| within(&f(&m.q_rad), limits, linear))
    };
    // The angles only: a prismatic joint's travel is mm whatever `units.angle` says.
    let max_abs = arm
        .measurements
        .iter()
        .flat_map(|m| m.q_rad.iter().enumerate())
        .filter(|(i, _)| !arm.is_linear_joint(*i))
        .fold(0.0f64, |a, (_, v)| a.max(v.abs()));
    if max_abs > std::f64::consts::TAU
        && rows_within(&|q| {
            q.iter()
                .enumerate()
                .map(|(i, v)| {
                    if arm.is_linear_joint(i) {
                        *v
                    } else {
                        v.to_radians()
                    }
                })
                .collect()
        })
    {
        Some(
            "every value of the file would be within the limits in degrees: does `units.angle` \
             in dataset.toml say rad for a file in degrees?"
                .into(),
        )
    } else if n == crate::kinematics::ABB_AXIS_OF_CHAIN.len()
        && linear.is_empty()
        && rows_within(&|q| {
            crate::kinematics::ABB_AXIS_OF_CHAIN
                .iter()
                .map(|&axis| q[axis - 1])
                .collect()
        })
    {
        Some(
            "the columns look like ABB axis order 1–7; q1..q7 are in chain order (ABB axes 1, 2, \
             7, 3, 4, 5, 6)"
                .into(),
        )
    } else {
        let swaps: Vec<String> = (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .filter(|&(a, b)| {
                let mut q = m.q_rad.to_vec();
                q.swap(a, b);
                within(&q, limits, linear)
            })
            .map(|(a, b)| format!("q{} and q{}", a + 1, b + 1))
            .take(3)
            .collect();
        let (first, others) = swaps.split_first()?;
        let others = if others.is_empty() {
            String::new()
        } else {
            format!(" (or {})", others.join(", or "))
        };
        Some(format!(
            "swapping {first}{others} would put this row within the limits: a joint logged \
             in the wrong column?"
        ))
    }
}

/// The refusal of joint `j`'s value in row `row` of `arm`, outside its limits: a travel (mm) for a
/// prismatic joint, an angle otherwise.
fn joint_limit_error(
    arm: &ArmData,
    limits: &[(f64, f64)],
    row: usize,
    j: usize,
    hints: &[String],
) -> DatasetError {
    let m = &arm.measurements[row];
    let (lo, hi) = limits[j];
    let hint: String = hints.iter().map(|h| format!("; {h}")).collect();
    if arm.is_linear_joint(j) {
        return DatasetError::JointTravel {
            path: arm.file.clone(),
            line: m.line,
            field: format!("q{}", j + 1),
            value_mm: m.q_rad[j],
            lower_mm: lo,
            upper_mm: hi,
            hint,
        };
    }
    DatasetError::JointLimit {
        path: arm.file.clone(),
        line: m.line,
        field: format!("q{}", j + 1),
        value_rad: m.q_rad[j],
        lower_rad: lo,
        upper_rad: hi,
        hint,
    }
}

/// Rows measured together (the manifest's `measured_together = true`): a left row and a right row with
/// the same id are one pose of the robot, so each joint both arms share (`shared`: a torso) has one
/// value in them. The first disagreement (beyond 1e-9 of the value, rad or mm) is refused naming the
/// right file, its line and column and the left row it disagrees with; so is a dataset that declares
/// it and has no id in both files. Without the declaration nothing is checked.
/// The values are printed in the file's `units`.
pub fn check_measured_together(
    dataset: &Dataset,
    shared: &crate::kinematics::SharedJoints,
    units: crate::dataset::Units,
) -> Result<(), DatasetError> {
    if !dataset.measured_together {
        return Ok(());
    }
    let (left, right) = (&dataset.arms.left, &dataset.arms.right);
    let by_id: std::collections::HashMap<&str, &crate::dataset::Measurement> = left
        .measurements
        .iter()
        .map(|m| (m.id.as_str(), m))
        .collect();
    let mut pairs = 0;
    for r in &right.measurements {
        let Some(l) = by_id.get(r.id.as_str()) else {
            continue;
        };
        pairs += 1;
        for (k, &(a, b)) in shared.variables.iter().enumerate() {
            let (Some(&va), Some(&vb)) = (l.q_rad.get(a), r.q_rad.get(b)) else {
                continue;
            };
            if (va - vb).abs() > 1e-9 * (1.0 + va.abs()) {
                let (show, unit) = if right.is_linear_joint(b) {
                    (units.length.from_mm(1.0), units.length.name())
                } else {
                    (units.angle.from_rad(1.0), units.angle.name())
                };
                let (va, vb) = (va * show, vb * show);
                return Err(DatasetError::Field {
                    path: right.file.clone(),
                    line: r.line,
                    field: format!("q{}", b + 1),
                    message: format!(
                        "row `{}`: joint `{}`, which both arms share, is {vb} {unit} here but {va} \
                         {unit} in {} line {} (q{}); the dataset says both hands were measured \
                         together (`measured_together = true`), so a shared joint has one value per \
                         id",
                        r.id,
                        shared.variable_names.get(k).map_or("?", |n| n.as_str()),
                        left.file.display(),
                        l.line,
                        a + 1
                    ),
                });
            }
        }
    }
    if pairs == 0 {
        return Err(DatasetError::Field {
            path: right.file.clone(),
            line: 1,
            field: "id".into(),
            message: format!(
                "the dataset says both hands were measured together (`measured_together = true`), \
                 but no id of this file is in {}: rows measured at one instant carry one id in both \
                 files",
                left.file.display()
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_files_stay_inside_the_directory() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        assert_eq!(data_file_in(d, "left.csv").unwrap(), d.join("left.csv"));
        assert!(data_file_in(d, "sub/../left.csv").is_ok());
        assert!(data_file_in(d, "./sub/x.csv").is_ok());
        for bad in [
            "../left.csv",
            "sub/../../x",
            "/etc/passwd",
            "../../../../etc/passwd",
        ] {
            let msg = data_file_in(d, bad).unwrap_err();
            assert!(msg.contains("inside the dataset directory"), "{bad}: {msg}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("/etc/hostname", d.join("link.csv")).unwrap();
            let msg = data_file_in(d, "link.csv").unwrap_err();
            assert!(msg.contains("link"), "{msg}");
        }
    }

    #[test]
    fn nominal_triangles() {
        let t = [
            Vector3::new(45.0, 0.0, 40.0),
            Vector3::new(-25.0, 40.0, 40.0),
            Vector3::new(-25.0, -40.0, 40.0),
        ];
        nominal_triangle(&t, LengthUnit::Mm).unwrap();
        let m = t.map(|p| p / 1000.0);
        assert!(
            nominal_triangle(&m, LengthUnit::Mm)
                .unwrap_err()
                .contains("metres")
        );
        let big = t.map(|p| p * 1000.0);
        assert!(
            nominal_triangle(&big, LengthUnit::M)
                .unwrap_err()
                .contains("millimetres")
        );
        let line = [t[0], (t[0] + t[1]) / 2.0, t[1]];
        assert!(
            nominal_triangle(&line, LengthUnit::Mm)
                .unwrap_err()
                .contains("collinear")
        );
    }
}
