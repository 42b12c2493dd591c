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
        // Order and Auto are resolved before points are placed: `k` is the point's shot group.
        MatchRule::Order | MatchRule::Auto => {
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
                .filter_map(|(c, row)| Some((c, row.time_distance_s(t)?)))
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
    let files = MatchFiles {
        points: points_file,
        joints: joints_file.unwrap_or(points_file),
    };
    let rule = resolve_rule(pts, log, &ids, o, &files, report)?;
    if rule == MatchRule::Time && log.rows.iter().all(|row| row.time_s.is_none()) {
        return Err(ImportError::Options(format!(
            "{}: matching by time needs a time column (`time`) in the joint log",
            files.joints.display()
        )));
    }
    let o = &ImportOptions {
        matching: rule,
        ..o.clone()
    };
    // Per configuration: named shots per reflector, and shots without a reflector (time rule).
    let mut shots: Vec<Vec<Vec<&Point>>> = vec![vec![Vec::new(); r]; log.rows.len()];
    let mut unnamed: Vec<Vec<&Point>> = vec![Vec::new(); log.rows.len()];
    // By order, the k-th group of shots (one shot, or one repeated) is placed.
    let all: Vec<&Point> = pts.iter().collect();
    let groups: Vec<Vec<usize>> = match rule {
        MatchRule::Order => shot_groups(&all),
        _ => (0..pts.len()).map(|k| vec![k]).collect(),
    };
    for (g, group) in groups.iter().enumerate() {
        for &k in group {
            let p = &pts[k];
            match place(p, g, log, &ids, o) {
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
    }
    if rule == MatchRule::Name && shots.iter().flatten().all(Vec::is_empty) && !pts.is_empty() {
        report.notes.push(
            "no target name carries a configuration id of the joint log: match by file order \
             (--match order) or by time stamps (--match time), or leave --match out to choose"
                .to_string(),
        );
    }
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
        let groups = shot_groups(&loose);
        if per.iter().all(Vec::is_empty) && groups.len() == r {
            for (k, group) in groups.into_iter().enumerate() {
                per[k].extend(group.into_iter().map(|i| loose[i]));
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
    let rule = rows_rule(rows, log, o, report);
    let by_id = rule == MatchRule::Name && rows.iter().all(|r| r.id.is_some());
    let mut used = vec![false; log.rows.len()];
    let mut out = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        let c = if by_id {
            let id = row.id.as_deref().unwrap_or_default();
            log.rows.iter().position(|j| j.id == id)
        } else if rule == MatchRule::Time {
            row.time_s.and_then(|t| {
                log.rows
                    .iter()
                    .enumerate()
                    .filter_map(|(c, j)| Some((c, j.time_distance_s(t)?)))
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

/// The rule a table's rows are matched to the joint log by: the one forced, else by id where every
/// row has one and one of them is the log's, by time where every row and configuration has a time
/// stamp, else by order. Noted in the report.
fn rows_rule(
    rows: &[ConfigRow],
    log: &JointLog,
    o: &ImportOptions,
    report: &mut ArmReport,
) -> MatchRule {
    if o.matching != MatchRule::Auto {
        return o.matching;
    }
    let ids_match = rows.iter().all(|r| r.id.is_some())
        && rows
            .iter()
            .any(|r| log.rows.iter().any(|j| Some(&j.id) == r.id.as_ref()));
    let timed =
        rows.iter().all(|r| r.time_s.is_some()) && log.rows.iter().all(|j| j.time_s.is_some());
    let (rule, why) = if ids_match {
        (MatchRule::Name, "by id (the rows' ids are the joint log's)")
    } else if timed {
        (
            MatchRule::Time,
            "by time stamp (the rows' ids are not the joint log's; both files have time stamps)",
        )
    } else {
        (
            MatchRule::Order,
            "by file order (the rows' ids are not the joint log's, and not both files have time \
             stamps)",
        )
    };
    report.notes.push(format!("matching: {why}"));
    rule
}

/// Consecutive shots closer than this to the one before are one shot repeated (a tracker's noise is
/// hundredths of a millimetre; the arm between configurations, and the reflectors of one
/// configuration, are centimetres apart), mm.
pub const REPEAT_MM: f64 = 1.0;

/// The shots in file order grouped: consecutive shots within [`REPEAT_MM`] of the one before are
/// one group (a shot repeated). Indices into `pts`.
pub(super) fn shot_groups(pts: &[&Point]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, p) in pts.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if k > 0 && (p.position_mm - pts[k - 1].position_mm).norm() < REPEAT_MM => {
                g.push(k);
            }
            _ => groups.push(vec![k]),
        }
    }
    groups
}

/// What the points' names are, for the report: none, one name on every row, or names of no form
/// that gives a configuration id.
fn describe_names(pts: &[Point]) -> String {
    let names: Vec<&str> = pts.iter().filter_map(|p| p.target.as_deref()).collect();
    match names.first() {
        None => "the points have no names".to_string(),
        Some(first) if names.len() == pts.len() && names.iter().all(|n| n == first) => {
            format!("one name, `{first}`, on every row")
        }
        Some(first) => format!(
            "no name (`{first}`, …) is `<id>_<reflector>` with a configuration id of the joint log"
        ),
    }
}

/// The rule points are matched by: the one forced, else (`Auto`) by name where a name carries a
/// configuration id of the log, by time where every point and configuration has a time stamp, by
/// order where the counts agree (repeated shots merged). The rule and why go to the report's notes;
/// counts that disagree are an error naming both and where the sequences part.
fn resolve_rule(
    pts: &[Point],
    log: &JointLog,
    ids: &std::collections::HashMap<&str, usize>,
    o: &ImportOptions,
    files: &MatchFiles,
    report: &mut ArmReport,
) -> Result<MatchRule, ImportError> {
    let names = &o.reflector_names;
    let rule_name = |rule: MatchRule| match rule {
        MatchRule::Name => "by target name",
        MatchRule::Time => "by time stamp",
        MatchRule::Order | MatchRule::Auto => "by file order",
    };
    if o.matching != MatchRule::Auto {
        report
            .notes
            .push(format!("matching: {} (--match)", rule_name(o.matching)));
        return Ok(o.matching);
    }
    let named = pts.iter().any(|p| {
        p.target
            .as_deref()
            .and_then(|t| split_target(t, names))
            .is_some_and(|(id, _)| ids.contains_key(id))
    });
    if named {
        report.notes.push(
            "matching: by target name (the names carry the joint log's configuration ids)"
                .to_string(),
        );
        return Ok(MatchRule::Name);
    }
    let why = describe_names(pts);
    let pts_timed = !pts.is_empty() && pts.iter().all(|p| p.time_s.is_some());
    let log_timed = !log.rows.is_empty() && log.rows.iter().all(|r| r.time_s.is_some());
    if pts_timed && log_timed {
        report.notes.push(format!(
            "matching: by time stamp ({why}; both files have time stamps; tolerance {} s)",
            o.time_tolerance_s
        ));
        return Ok(MatchRule::Time);
    }
    let untimed = match (pts_timed, log_timed) {
        (false, false) => "neither file has time stamps",
        (false, true) => "the point file has no time stamps",
        _ => "the joint log has no time stamps",
    };
    let all: Vec<&Point> = pts.iter().collect();
    let groups = shot_groups(&all);
    let (r, rows) = (names.len(), log.rows.len());
    let repeated = pts.len() - groups.len();
    let merged = if repeated > 0 {
        format!(
            " ({} points, {repeated} of them a shot repeated)",
            pts.len()
        )
    } else {
        String::new()
    };
    if groups.len() == rows * r {
        report.notes.push(format!(
            "matching: by file order ({why}; {untimed}; {} shots{merged} for {rows} \
             configurations × {r} reflector{})",
            groups.len(),
            if r == 1 { "" } else { "s" }
        ));
        return Ok(MatchRule::Order);
    }
    Err(ImportError::Content {
        path: files.points.to_path_buf(),
        message: format!(
            "{why} and {untimed}, so the points would be matched by file order, but the counts \
             disagree: {} shots{merged} in {}, {rows} configurations × {r} reflector{} = {} in {}; \
             {}. Name the points `<id>_<reflector>`, give both files time stamps, or force a rule \
             with --match order or --match time",
            groups.len(),
            files.points.display(),
            if r == 1 { "" } else { "s" },
            rows * r,
            files.joints.display(),
            parting(pts, &groups, log, r)
        ),
    })
}

/// Where a point file's shot groups and a joint log first part, as far as the files show it: a time
/// gap among the shots or the configurations (a configuration skipped), a jump in joint values.
fn parting(pts: &[Point], groups: &[Vec<usize>], log: &JointLog, r: usize) -> String {
    // The first shot of each configuration (every r-th group).
    let starts: Vec<&Point> = groups
        .iter()
        .step_by(r.max(1))
        .map(|g| &pts[g[0]])
        .collect();
    let shot_times: Vec<Option<f64>> = starts.iter().map(|p| p.time_s).collect();
    if let Some((k, dt, median)) = first_gap(&shot_times) {
        return format!(
            "the shots part at line {}: {dt:.1} s after the configuration before (line {}), where \
             configurations are {median:.1} s apart — a configuration skipped, or measured again",
            starts[k].line,
            starts[k - 1].line
        );
    }
    let row_times: Vec<Option<f64>> = log.rows.iter().map(|row| row.time_s).collect();
    if let Some((k, dt, median)) = first_gap(&row_times) {
        let row = &log.rows[k];
        return format!(
            "the joint log parts at configuration `{}` (line {}): {dt:.1} s after the one before, \
             where configurations are {median:.1} s apart",
            row.id, row.line
        );
    }
    let steps: Vec<Option<f64>> = log
        .rows
        .windows(2)
        .map(|w| {
            let d = w[1]
                .q_rad
                .iter()
                .zip(&w[0].q_rad)
                .map(|(a, b)| (a - b).abs());
            Some(d.fold(0.0, f64::max))
        })
        .collect();
    let cumulative: Vec<Option<f64>> = std::iter::once(Some(0.0))
        .chain(steps.iter().scan(0.0, |t, s| {
            *t += s.unwrap_or(0.0);
            Some(Some(*t))
        }))
        .collect();
    if let Some((k, step, median)) = first_gap(&cumulative) {
        let row = &log.rows[k];
        return format!(
            "the joint log jumps at configuration `{}` (line {}): {:.1}° from the one before, \
             where steps are {:.1}° — a configuration not measured",
            row.id,
            row.line,
            step.to_degrees(),
            median.to_degrees()
        );
    }
    "neither time stamps nor joint values show where they part".to_string()
}

/// The first step of a sequence more than 1.5 times the median step (and the step and the median), when
/// every value is known and there are at least three steps.
fn first_gap(values: &[Option<f64>]) -> Option<(usize, f64, f64)> {
    let v: Vec<f64> = values.iter().copied().collect::<Option<_>>()?;
    let steps: Vec<f64> = v.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.len() < 3 {
        return None;
    }
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    if median <= 0.0 {
        return None;
    }
    let k = steps.iter().position(|&s| s > 1.5 * median)?;
    Some((k + 1, steps[k], median))
}
