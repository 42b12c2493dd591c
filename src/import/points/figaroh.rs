//! figaroh's calibration CSV: `x1,y1,z1,…` per marker, the joints by their URDF names.

use super::*;

pub(super) fn read_figaroh(
    path: &Path,
    text: &str,
    o: &ReadOptions,
) -> Result<PointFile, ImportError> {
    let mut it = lines(text).filter(|(_, t)| !t.starts_with('#'));
    let Some((hl, header)) = it.next() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "empty file: expected figaroh's header `x1,y1,z1,…,<joint names>`".to_string(),
        });
    };
    let delimiter = Delimiter::of_line(header, false);
    let names = text::split(header, delimiter);
    let col = |n: &str| names.iter().position(|m| m == n);
    let mut markers = Vec::new();
    for k in 1.. {
        let cols = [format!("x{k}"), format!("y{k}"), format!("z{k}")];
        let found: Vec<Option<usize>> = cols.iter().map(|c| col(c)).collect();
        match found.as_slice() {
            [Some(x), Some(y), Some(z)] => markers.push([*x, *y, *z]),
            [None, None, None] => break,
            _ => {
                let missing = cols.iter().zip(&found).find(|(_, f)| f.is_none());
                return Err(ImportError::Header {
                    path: path.to_path_buf(),
                    line: hl,
                    field: missing.map_or_else(String::new, |(c, _)| c.clone()),
                    message: format!("marker {k} needs the three columns x{k}, y{k}, z{k}"),
                });
            }
        }
    }
    if markers.is_empty() {
        return Err(ImportError::Header {
            path: path.to_path_buf(),
            line: hl,
            field: "x1".to_string(),
            message: "expected figaroh's marker columns `x1,y1,z1,…`".to_string(),
        });
    }
    if markers.len() != o.reflector_names.len() {
        return Err(ImportError::Header {
            path: path.to_path_buf(),
            line: hl,
            field: format!("x{}", markers.len()),
            message: format!(
                "{} markers, the dataset has {} reflectors ({}): name as many reflectors",
                markers.len(),
                o.reflector_names.len(),
                o.reflector_names.join(", ")
            ),
        });
    }
    let marker_cols: Vec<usize> = markers.iter().flatten().copied().collect();
    // figaroh's pose markers add orientation columns (`phi1`, …): not used.
    let is_orientation = |n: &str| {
        ["phi", "theta", "psi"].iter().any(|p| {
            n.strip_prefix(p)
                .is_some_and(|r| !r.is_empty() && r.chars().all(|c| c.is_ascii_digit()))
        })
    };
    let mut notes = Vec::new();
    let other: Vec<usize> = (0..names.len())
        .filter(|k| {
            !marker_cols.contains(k) && !names[*k].is_empty() && !is_orientation(&names[*k])
        })
        .collect();
    let joint_cols: Vec<usize> = match o.joint_names {
        Some(joints) => {
            let mut cols = Vec::new();
            for j in joints {
                match col(j) {
                    Some(c) => cols.push(c),
                    None => {
                        return Err(ImportError::Header {
                            path: path.to_path_buf(),
                            line: hl,
                            field: j.clone(),
                            message: format!(
                                "no column for the arm's joint `{j}`: figaroh names one column per \
                                 joint as in the URDF (the arm's joints: {})",
                                joints.join(", ")
                            ),
                        });
                    }
                }
            }
            let ignored: Vec<&str> = other
                .iter()
                .filter(|k| !cols.contains(k))
                .map(|&k| names[k].as_str())
                .collect();
            if !ignored.is_empty() {
                notes.push(format!(
                    "columns not of this arm, ignored: {}",
                    ignored.join(", ")
                ));
            }
            cols
        }
        None => other,
    };
    let unit = o.unit.unwrap_or(PointUnit::M);
    let needed = marker_cols
        .iter()
        .chain(&joint_cols)
        .max()
        .copied()
        .unwrap_or(0)
        + 1;
    let mut rows = Vec::new();
    for (line, t) in it {
        let fields = text::split(t, delimiter);
        let mut points_mm = Vec::new();
        for (m, cols) in markers.iter().enumerate() {
            let mut p = Vector3::zeros();
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let name = format!("{axis}{}", m + 1);
                p[k] = coordinate(path, line, &fields, cols[k], needed, &name, unit, false)?;
            }
            points_mm.push(p);
        }
        let mut q_rad = Vec::new();
        for &c in &joint_cols {
            let f = field(path, line, &fields, c, needed)?;
            q_rad.push(text::number(f, false).ok_or_else(|| ImportError::Field {
                path: path.to_path_buf(),
                line,
                field: names[c].clone(),
                expected: "a joint value in rad".to_string(),
                found: crate::textfile::excerpt(f),
            })?);
        }
        rows.push(ConfigRow {
            id: None,
            points_mm,
            q_rad: Some(q_rad),
            time_s: None,
            split: None,
            line,
        });
    }
    Ok(PointFile {
        format: PointsFormat::Figaroh,
        unit,
        frame: None,
        table: PointTable::Rows(rows),
        notes,
    })
}
