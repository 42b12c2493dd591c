//! Matching points to configurations (`dualcal import --match name|order|time`): a point list's points
//! to the joint log's configurations by target name, file order or time stamp (repeated shots averaged),
//! or a table's rows (one configuration per row) as they are; what did not match goes to the report.

use super::*;

/// The reflector a target name ends in: `L012_a` is (`L012`, a) when `a` is a reflector.
fn split_target<'t>(target: &'t str, names: &[String]) -> Option<(&'t str, usize)> {
    let (id, r) = target.rsplit_once('_')?;
    let k = names.iter().position(|n| n == r)?;
    (!id.is_empty()).then_some((id, k))
}

/// Where point `p` (the `k`-th of its file) goes under the matching rule: its configuration and
/// reflector (`None`: a time-matched shot whose name gives no reflector), or why it matches none.
fn place(
    p: &Point,
    k: usize,
    log: &JointLog,
    ids: &std::collections::HashMap<&str, usize>,
    o: &ImportOptions,
) -> Result<(usize, Option<usize>), String> {
    let names = &o.reflector_names;
    let r = names.len();
    match o.matching {
        MatchRule::Name => {
            let target = p
                .target
                .as_ref()
                .ok_or("no target name (match by order or by time instead)")?;
            let (id, refl) = split_target(target, names).ok_or_else(|| {
                format!(
                    "the name is not `<id>_<reflector>` with a reflector of {}",
                    names.join(", ")
                )
            })?;
            match ids.get(id) {
                Some(&c) => Ok((c, Some(refl))),
                None => Err(format!("no configuration `{id}` in the joint log")),
            }
        }
        MatchRule::Order => {
            let c = k / r;
            if c < log.rows.len() {
                Ok((c, Some(k % r)))
            } else {
                Err(format!(
                    "beyond the joint log's {} configurations × {r} reflectors",
                    log.rows.len()
                ))
            }
        }
        MatchRule::Time => {
            let t = p.time_s.ok_or("no time stamp")?;
            let nearest = log
                .rows
                .iter()
                .enumerate()
                .filter_map(|(c, row)| Some((c, (row.time_s? - t).abs())))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match nearest {
                Some((c, dt)) if dt <= o.time_tolerance_s => {
                    let refl = p.target.as_deref().and_then(|name| {
                        split_target(name, names)
                            .map(|(_, k)| k)
                            .or_else(|| names.iter().position(|n| n == name))
                    });
                    Ok((c, refl))
                }
                Some((c, dt)) => Err(format!(
                    "the nearest configuration, `{}`, is {dt:.3} s away (tolerance {} s)",
                    log.rows[c].id, o.time_tolerance_s
                )),
                None => Err("no configuration has a time stamp".into()),
            }
        }
    }
}

/// How a point is named in the report: its target, else its number in the file.
fn label(p: &Point, k: usize) -> String {
    p.target.clone().unwrap_or_else(|| format!("#{}", k + 1))
}

/// Points assigned to (configuration, reflector); shots averaged.
pub(super) fn match_points(
    points_file: &Path,
    joints_file: Option<&Path>,
    pts: &[Point],
    log: &JointLog,
    o: &ImportOptions,
    report: &mut ArmReport,
) -> Result<Vec<Measurement>, ImportError> {
    let r = o.reflector_names.len();
    let ids: std::collections::HashMap<&str, usize> = log
        .rows
        .iter()
        .enumerate()
        .map(|(k, row)| (row.id.as_str(), k))
        .collect();
    if o.matching == MatchRule::Time && log.rows.iter().all(|row| row.time_s.is_none()) {
        return Err(ImportError::Options(format!(
            "{}: matching by time needs a time column (`time`) in the joint log",
            joints_file.unwrap_or(points_file).display()
        )));
    }
    // Per configuration: named shots per reflector, and shots without a reflector (time rule).
    let mut shots: Vec<Vec<Vec<&Point>>> = vec![vec![Vec::new(); r]; log.rows.len()];
    let mut unnamed: Vec<Vec<&Point>> = vec![Vec::new(); log.rows.len()];
    for (k, p) in pts.iter().enumerate() {
        match place(p, k, log, &ids, o) {
            Ok((c, Some(refl))) => shots[c][refl].push(p),
            Ok((c, None)) => unnamed[c].push(p),
            Err(reason) => report.unmatched_points.push(Unmatched {
                name: label(p, k),
                file: points_file.to_path_buf(),
                line: p.line,
                reason,
            }),
        }
    }
    let files = MatchFiles {
        points: points_file,
        joints: joints_file.unwrap_or(points_file),
    };
    let mut out = Vec::new();
    for (c, row) in log.rows.iter().enumerate() {
        let per = std::mem::take(&mut shots[c]);
        let loose = std::mem::take(&mut unnamed[c]);
        out.extend(measurement(row, per, loose, &files, o, report));
    }
    crate::sort::sort_by_key(&mut report.unmatched_points, |u| u.line);
    Ok(out)
}

/// The files a match names in its report.
struct MatchFiles<'a> {
    points: &'a Path,
    joints: &'a Path,
}

/// Configuration `row`'s measurement from its shots per reflector (`per`) and its shots without a
/// reflector (`loose`, taken in order when they are all it has, one per reflector); `None` when a
/// reflector has no shot — the configuration and its points then go to the report. Repeated shots
/// are averaged and reported with their spread.
fn measurement<'p>(
    row: &JointRow,
    mut per: Vec<Vec<&'p Point>>,
    loose: Vec<&'p Point>,
    files: &MatchFiles,
    o: &ImportOptions,
    report: &mut ArmReport,
) -> Option<Measurement> {
    let names = &o.reflector_names;
    let r = names.len();
    let unused = |p: &Point, reason: String| Unmatched {
        name: label(p, 0),
        file: files.points.to_path_buf(),
        line: p.line,
        reason,
    };
    if !loose.is_empty() {
        if per.iter().all(Vec::is_empty) && loose.len() == r {
            for (k, p) in loose.into_iter().enumerate() {
                per[k].push(p);
            }
        } else {
            for p in loose {
                report.unmatched_points.push(unused(
                    p,
                    format!(
                        "no reflector in the name, and configuration `{}` does not have exactly \
                         {r} such points to take in order",
                        row.id
                    ),
                ));
            }
        }
    }
    let missing: Vec<&str> = names
        .iter()
        .zip(&per)
        .filter(|(_, s)| s.is_empty())
        .map(|(n, _)| n.as_str())
        .collect();
    if !missing.is_empty() {
        let found = per.iter().map(Vec::len).sum::<usize>();
        report.unmatched_configurations.push(Unmatched {
            name: row.id.clone(),
            file: files.joints.to_path_buf(),
            line: row.line,
            reason: if found == 0 {
                "no points".to_string()
            } else {
                format!("no point of reflector {}", missing.join(", "))
            },
        });
        // Its points are reported as unused too.
        for s in per.iter().flatten() {
            report.unmatched_points.push(unused(
                s,
                format!(
                    "configuration `{}` lacks reflector {}",
                    row.id,
                    missing.join(", ")
                ),
            ));
        }
        return None;
    }
    let mut tracker_points_mm = Vec::with_capacity(r);
    for (k, s) in per.iter().enumerate() {
        let mean = average(s.iter().map(|p| p.position_mm));
        if s.len() > 1 {
            let spread_mm = s
                .iter()
                .map(|p| (p.position_mm - mean).norm())
                .fold(0.0, f64::max);
            report.repeated.push(RepeatedShots {
                id: row.id.clone(),
                reflector: names[k].clone(),
                shots: s.len(),
                spread_mm,
                lines: s.iter().map(|p| p.line).collect(),
            });
        }
        tracker_points_mm.push(mean);
    }
    Some(Measurement {
        id: row.id.clone(),
        q_rad: row.q_rad.clone(),
        tracker_points_mm,
        split: row.split.unwrap_or(Split::Cal),
        line: row.line,
    })
}

/// The mean of shots; one shot is returned as it is (no rounding).
fn average(shots: impl Iterator<Item = Vector3<f64>>) -> Vector3<f64> {
    let v: Vec<Vector3<f64>> = shots.collect();
    match v.as_slice() {
        [one] => *one,
        _ => v.iter().sum::<Vector3<f64>>() / v.len() as f64,
    }
}

/// Rows of whole configurations (figaroh, a mapping with reflector columns): joints from the rows or
/// from the joint log.
pub(super) fn match_rows(
    points_file: &Path,
    rows: &[ConfigRow],
    log: Option<&JointLog>,
    o: &ImportOptions,
    prefix: &str,
    joint_names: Option<&[String]>,
    report: &mut ArmReport,
) -> Result<Vec<Measurement>, ImportError> {
    let Some(log) = log else {
        let mut out = Vec::new();
        let mut seen = std::collections::HashMap::new();
        for (k, row) in rows.iter().enumerate() {
            let Some(q) = &row.q_rad else {
                return Err(ImportError::Options(format!(
                    "{}: no joint columns: give the arm's joint log, or map q1…qN",
                    points_file.display()
                )));
            };
            if let Some(names) = joint_names
                && names.len() != q.len()
            {
                return Err(ImportError::Field {
                    path: points_file.to_path_buf(),
                    line: row.line,
                    field: format!("q{}", q.len().min(names.len()) + 1),
                    expected: format!("{} joint values (the arm's joints)", names.len()),
                    found: format!("{} joint values", q.len()),
                });
            }
            let id = row
                .id
                .clone()
                .unwrap_or_else(|| format!("{prefix}{:03}", k + 1));
            if let Some(first_line) = seen.insert(id.clone(), row.line) {
                return Err(ImportError::DuplicateId {
                    path: points_file.to_path_buf(),
                    line: row.line,
                    id,
                    first_line,
                });
            }
            out.push(Measurement {
                id,
                q_rad: q.clone(),
                tracker_points_mm: row.points_mm.clone(),
                split: row.split.unwrap_or(Split::Cal),
                line: row.line,
            });
        }
        return Ok(out);
    };
    if rows.iter().any(|r| r.q_rad.is_some()) {
        report.notes.push(
            "the point file's joint columns are not used: the joint log gives the joints".into(),
        );
    }
    let by_id = o.matching == MatchRule::Name && rows.iter().all(|r| r.id.is_some());
    let mut used = vec![false; log.rows.len()];
    let mut out = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        let c = if by_id {
            let id = row.id.as_deref().unwrap_or_default();
            log.rows.iter().position(|j| j.id == id)
        } else if o.matching == MatchRule::Time {
            row.time_s.and_then(|t| {
                log.rows
                    .iter()
                    .enumerate()
                    .filter_map(|(c, j)| Some((c, (j.time_s? - t).abs())))
                    .filter(|&(_, dt)| dt <= o.time_tolerance_s)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(c, _)| c)
            })
        } else {
            (k < log.rows.len()).then_some(k)
        };
        match c {
            Some(c) if !used[c] => {
                used[c] = true;
                let j = &log.rows[c];
                out.push(Measurement {
                    id: j.id.clone(),
                    q_rad: j.q_rad.clone(),
                    tracker_points_mm: row.points_mm.clone(),
                    split: j.split.or(row.split).unwrap_or(Split::Cal),
                    line: j.line,
                });
            }
            Some(c) => report.unmatched_points.push(Unmatched {
                name: format!("row {}", k + 1),
                file: points_file.to_path_buf(),
                line: row.line,
                reason: format!("configuration `{}` already matched", log.rows[c].id),
            }),
            None => report.unmatched_points.push(Unmatched {
                name: row.id.clone().unwrap_or_else(|| format!("row {}", k + 1)),
                file: points_file.to_path_buf(),
                line: row.line,
                reason: "no configuration of the joint log matches".into(),
            }),
        }
    }
    for (c, j) in log.rows.iter().enumerate() {
        if !used[c] {
            report.unmatched_configurations.push(Unmatched {
                name: j.id.clone(),
                file: report.joints_file.clone().unwrap_or_default(),
                line: j.line,
                reason: "no row of the point file".into(),
            });
        }
    }
    Ok(out)
}
