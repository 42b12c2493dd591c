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
    let header = Header {
        path,
        line: hl,
        names: &names,
    };
    let markers = header.markers(o)?;
    let mut notes = Vec::new();
    let joint_cols = header.joints(&markers, o, &mut notes)?;
    let unit = o.unit.unwrap_or(PointUnit::M);
    let needed = markers
        .iter()
        .flatten()
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

/// figaroh's header line: its column names, where it is (for messages).
struct Header<'a> {
    path: &'a Path,
    line: usize,
    names: &'a [String],
}

impl Header<'_> {
    fn col(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|m| m == name)
    }

    fn error(&self, field: String, message: String) -> ImportError {
        ImportError::Header {
            path: self.path.to_path_buf(),
            line: self.line,
            field,
            message,
        }
    }

    /// The columns `x_k, y_k, z_k` of each marker `k = 1, 2, …`, as many as the dataset's reflectors.
    fn markers(&self, o: &ReadOptions) -> Result<Vec<[usize; 3]>, ImportError> {
        let mut markers = Vec::new();
        for k in 1.. {
            let cols = [format!("x{k}"), format!("y{k}"), format!("z{k}")];
            let found: Vec<Option<usize>> = cols.iter().map(|c| self.col(c)).collect();
            match found.as_slice() {
                [Some(x), Some(y), Some(z)] => markers.push([*x, *y, *z]),
                [None, None, None] => break,
                _ => {
                    let missing = cols.iter().zip(&found).find(|(_, f)| f.is_none());
                    return Err(self.error(
                        missing.map_or_else(String::new, |(c, _)| c.clone()),
                        format!("marker {k} needs the three columns x{k}, y{k}, z{k}"),
                    ));
                }
            }
        }
        if markers.is_empty() {
            return Err(self.error(
                "x1".to_string(),
                "expected figaroh's marker columns `x1,y1,z1,…`".to_string(),
            ));
        }
        if markers.len() != o.reflector_names.len() {
            return Err(self.error(
                format!("x{}", markers.len()),
                format!(
                    "{} markers, the dataset has {} reflectors ({}): name as many reflectors",
                    markers.len(),
                    o.reflector_names.len(),
                    o.reflector_names.join(", ")
                ),
            ));
        }
        Ok(markers)
    }

    /// The joint columns: the arm's joints by their URDF names when known (the other columns noted as
    /// ignored), else every column that is no marker coordinate or orientation.
    fn joints(
        &self,
        markers: &[[usize; 3]],
        o: &ReadOptions,
        notes: &mut Vec<String>,
    ) -> Result<Vec<usize>, ImportError> {
        let marker_cols: Vec<usize> = markers.iter().flatten().copied().collect();
        // figaroh's pose markers add orientation columns (`phi1`, …): not used.
        let is_orientation = |n: &str| {
            ["phi", "theta", "psi"].iter().any(|p| {
                n.strip_prefix(p)
                    .is_some_and(|r| !r.is_empty() && r.chars().all(|c| c.is_ascii_digit()))
            })
        };
        let names = self.names;
        let other: Vec<usize> = (0..names.len())
            .filter(|k| {
                !marker_cols.contains(k) && !names[*k].is_empty() && !is_orientation(&names[*k])
            })
            .collect();
        let Some(joints) = o.joint_names else {
            return Ok(other);
        };
        let mut cols = Vec::new();
        for j in joints {
            let Some(c) = self.col(j) else {
                return Err(self.error(
                    j.clone(),
                    format!(
                        "no column for the arm's joint `{j}`: figaroh names one column per joint as \
                         in the URDF (the arm's joints: {})",
                        joints.join(", ")
                    ),
                ));
            };
            cols.push(c);
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
        Ok(cols)
    }
}
