//! Writing a dataset directory.

use super::error::DatasetError;
use super::units::Units;
use super::{
    ArmData, DATASET_FORMAT, Dataset, MANIFEST_FILE, MIN_CONFIGS, SPLIT_COLUMN, Split, csv_columns,
};
use crate::output::{FileError, Overwrite, refuse_existing, write_atomic};
use crate::side::PerSide;
use std::path::{Path, PathBuf};

/// Shortest text that parses back to exactly `x` (Rust's `{:?}` of f64: round-trip, `.0` on integers).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// A TOML basic string literal.
fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn check_finite(path: &Path, what: &str, values: &[f64]) -> Result<(), DatasetError> {
    if let Some(x) = values.iter().find(|x| !x.is_finite()) {
        return Err(DatasetError::Content {
            path: path.to_path_buf(),
            message: format!("cannot save {what}: {x} is not a finite number"),
        });
    }
    Ok(())
}

fn arm_csv(
    arm: &ArmData,
    reflectors: &[String],
    path: &Path,
    units: Units,
) -> Result<Vec<u8>, DatasetError> {
    let content_err = |message: String| DatasetError::Content {
        path: path.to_path_buf(),
        message,
    };
    if arm.measurements.len() < MIN_CONFIGS {
        return Err(DatasetError::TooFewConfigurations {
            path: path.to_path_buf(),
            side: arm.side,
            found: arm.measurements.len(),
            min: MIN_CONFIGS,
        });
    }
    let mut seen = std::collections::HashSet::new();
    let joints = arm.joint_count();
    let order = match &arm.links {
        None if joints == 7 => "chain order (ABB axes 1, 2, 7, 3, 4, 5, 6)".to_string(),
        None => "chain order".to_string(),
        Some(links) => format!("the chain order of {links}"),
    };
    let mut bytes = format!(
        "# {DATASET_FORMAT}: {} arm. q1..q{joints} in {order}, {}; {} {} in the tracker frame, \
         {}.\n",
        arm.side,
        units.angle.name(),
        if reflectors.len() == 1 {
            "reflector"
        } else {
            "reflectors"
        },
        reflectors.join(", "),
        units.length.name()
    )
    .into_bytes();
    {
        let mut w = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(&mut bytes);
        let mut header = csv_columns(joints, reflectors);
        header.push(SPLIT_COLUMN.to_string());
        w.write_record(&header)
            .map_err(|e| content_err(e.to_string()))?;
        for m in &arm.measurements {
            let id = m.id.as_str();
            if id.is_empty() || id.trim() != id || id.starts_with('#') || id.contains(['\n', '\r'])
            {
                return Err(content_err(format!(
                    "cannot save id {id:?}: ids must be non-empty, one line, without surrounding spaces and not start with `#`"
                )));
            }
            if !seen.insert(id) {
                return Err(content_err(format!("cannot save: duplicate id `{id}`")));
            }
            if m.q_rad.len() != joints {
                return Err(content_err(format!(
                    "cannot save configuration `{id}`: {} joint values, the arm's first configuration has {joints}",
                    m.q_rad.len()
                )));
            }
            check_finite(path, &format!("configuration `{id}`"), &m.q_rad)?;
            if m.tracker_points_mm.len() != reflectors.len() {
                return Err(content_err(format!(
                    "cannot save configuration `{id}`: {} reflector positions, the dataset has {} \
                     reflectors",
                    m.tracker_points_mm.len(),
                    reflectors.len()
                )));
            }
            for p in &m.tracker_points_mm {
                check_finite(path, &format!("configuration `{id}`"), p.as_slice())?;
            }
            let mut row = vec![id.to_string()];
            row.extend(m.q_rad.iter().enumerate().map(|(i, &q)| {
                num(if arm.is_linear_joint(i) {
                    units.length.from_mm(q)
                } else {
                    units.angle.from_rad(q)
                })
            }));
            for p in &m.tracker_points_mm {
                row.extend(p.iter().map(|&x| num(units.length.from_mm(x))));
            }
            if m.split == Split::All {
                return Err(content_err(format!(
                    "cannot save configuration `{id}`: its split must be `cal` or `ver`"
                )));
            }
            row.push(m.split.name().to_string());
            w.write_record(&row)
                .map_err(|e| content_err(e.to_string()))?;
        }
        w.flush().map_err(|error| FileError::write(path, error))?;
    }
    Ok(bytes)
}

fn manifest_text(
    dataset: &Dataset,
    dir: &Path,
    path: &Path,
    units: Units,
) -> Result<String, DatasetError> {
    let content_err = |message: String| DatasetError::Content {
        path: path.to_path_buf(),
        message,
    };
    let mut s = format!("format = {}\n", toml_str(DATASET_FORMAT));
    if let Some(robot) = &dataset.robot {
        // Relative to the output directory when the robot lives inside it, else absolute.
        let p = match robot.strip_prefix(dir) {
            Ok(rel) => rel.to_path_buf(),
            Err(_) => robot.canonicalize().unwrap_or_else(|_| robot.clone()),
        };
        let p = p
            .to_str()
            .ok_or_else(|| content_err(format!("robot path {} is not valid UTF-8", p.display())))?;
        s += &format!("robot = {}\n", toml_str(p));
    }
    if dataset.measured_together {
        s += "measured_together = true\n";
    }
    s += &format!(
        "\n[units]\nlength = {}\nangle = {}\n",
        toml_str(units.length.name()),
        toml_str(units.angle.name())
    );
    let t = dataset.tracker;
    check_finite(path, "the tracker MPE", &[t.mpe_um, t.mpe_um_per_m])?;
    s += &format!(
        "\n[tracker]\nmpe_um = {}\nmpe_um_per_m = {}\n",
        num(t.mpe_um),
        num(t.mpe_um_per_m)
    );
    s += "\n[reflectors]\n";
    for (name, r) in dataset
        .reflector_names
        .iter()
        .zip(&dataset.nominal_reflectors_mm)
    {
        check_finite(path, "the nominal reflectors", r.as_slice())?;
        let v: Vec<String> = r.iter().map(|&x| num(units.length.from_mm(x))).collect();
        s += &format!("{name} = [{}]\n", v.join(", "));
    }
    // An arm not measured (a dataset of one arm) has no entry.
    for side in dataset.measured_sides() {
        s += &format!(
            "\n[[arms]]\nname = {}\nfile = {}\n",
            toml_str(side.name()),
            toml_str(&format!("{side}.csv"))
        );
        if let Some(links) = &dataset.arms[side].links {
            s += &format!(
                "base_link = {}\ntip_link = {}\n",
                toml_str(&links.base_link),
                toml_str(&links.tip_link)
            );
        }
        if let Some(station) = &dataset.arms[side].station {
            s += &format!("station = {}\n", toml_str(station));
        }
        if let Some(own) = &dataset.arms[side].nominal_reflectors_mm {
            check_finite(
                path,
                "an arm's nominal reflectors",
                &own.iter()
                    .flat_map(|r| r.iter().copied())
                    .collect::<Vec<_>>(),
            )?;
            let entries: Vec<String> = dataset
                .reflector_names
                .iter()
                .zip(own)
                .map(|(name, r)| {
                    let v: Vec<String> = r.iter().map(|&x| num(units.length.from_mm(x))).collect();
                    format!("{name} = [{}]", v.join(", "))
                })
                .collect();
            s += &format!("reflectors = {{ {} }}\n", entries.join(", "));
        }
    }
    Ok(s)
}

/// Write `dataset` as a `dualcal-dataset/1` directory (`dataset.toml`, `left.csv`, `right.csv`, with a
/// `split` column) in the given units. Creates `dir` if needed and refuses to replace an existing dataset
/// there (see [`save_with`]). Numbers are written with full f64 precision.
pub fn save(dataset: &Dataset, dir: &Path, units: Units) -> Result<(), DatasetError> {
    save_with(dataset, dir, units, Overwrite::Refuse)
}

/// Like [`save`]; with [`Overwrite::Allow`] existing `dataset.toml`/`left.csv`/`right.csv` in `dir` are
/// replaced. Each file is written atomically; the manifest is written last.
pub fn save_with(
    dataset: &Dataset,
    dir: &Path,
    units: Units,
    overwrite: Overwrite,
) -> Result<(), DatasetError> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let csv_paths = PerSide::from_fn(|s| dir.join(format!("{s}.csv")));
    refuse_existing(
        &[&manifest_path, &csv_paths.left, &csv_paths.right],
        overwrite,
    )?;
    // Build everything before touching the disk.
    let files = dataset_files(dataset, dir, units)?;
    std::fs::create_dir_all(dir).map_err(|error| FileError::write(dir, error))?;
    for (path, bytes) in &files {
        write_atomic(path, bytes).map_err(|error| FileError::write(path, error))?;
    }
    Ok(())
}

/// The files [`save`] writes for `dataset` in `dir` — `left.csv`, `right.csv` (each measured arm's),
/// then `dataset.toml` —
/// with their contents, written nowhere (a browser keeps them in memory).
pub fn dataset_files(
    dataset: &Dataset,
    dir: &Path,
    units: Units,
) -> Result<Vec<(PathBuf, Vec<u8>)>, DatasetError> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let csv_paths = PerSide::from_fn(|s| dir.join(format!("{s}.csv")));
    let manifest = manifest_text(dataset, dir, &manifest_path, units)?;
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    for s in dataset.measured_sides() {
        let csv = arm_csv(
            &dataset.arms[s],
            &dataset.reflector_names,
            &csv_paths[s],
            units,
        )?;
        files.push((csv_paths[s].clone(), csv));
    }
    files.push((manifest_path, manifest.into_bytes()));
    Ok(files)
}
