//! The import view's state: the tracker exports and joint logs the user picked, the options of
//! `dualcal import`, and a live preview — the engine's [`crate::import::import`] run again whenever a
//! file or an option changes, its report and its errors shown before anything is written. Finishing
//! writes the dataset ([`crate::import::write`], or in a browser the same files in memory) and opens
//! it. The view is drawn by [`super::panels::import_ui`].

use crate::dataset::{AngleUnit, LengthUnit};
use crate::import::{
    self, ArmFiles, ColumnMap, ImportOptions, Imported, MatchRule, PointUnit, PointsFormat,
};
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};
use crate::source::FileSource;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// A file of the import view: an arm's point file or its joint log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImportSlot {
    pub side: Side,
    pub joints: bool,
}

/// The robot and reflectors an import is made for: the workbench's current ones (or the built-in
/// IRB 14000 with the paper's reflectors).
pub struct ImportTarget<'a> {
    pub robot: &'a RobotDescription,
    /// Where the robot description is (`None`: built in); the dataset refers to it.
    pub robot_path: Option<&'a Path>,
    pub reflector_names: Vec<String>,
    pub nominal_reflectors_mm: Vec<Vector3<f64>>,
}

/// What the user has entered, as the command line's options.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportInputs {
    /// Per arm: the point file and the joint log (empty: none), as typed or picked.
    pub points: PerSide<String>,
    pub joints: PerSide<String>,
    /// `None`: recognised from each file.
    pub format: Option<PointsFormat>,
    /// The generic format's column mapping (`--columns`).
    pub columns: String,
    pub length_unit: Option<PointUnit>,
    pub angle_unit: Option<AngleUnit>,
    pub joint_length_unit: Option<LengthUnit>,
    pub decimal_comma: bool,
    /// `--joint-order`: empty (chain order), `yumi-abb` or `1,2,7,3,4,5,6`.
    pub joint_order: String,
    pub matching: MatchRule,
    pub time_tolerance_s: f64,
    /// Per arm: the tracker station (empty: one station for both).
    pub stations: PerSide<String>,
    /// Per arm: its own column mapping (`--left-columns`, `--right-columns`; empty: `columns`), as
    /// for one file of both arms.
    pub arm_columns: PerSide<String>,
    /// Both hands measured at one instant (`--measured-together`).
    pub measured_together: bool,
    /// `--verify-last N`: the last N configurations of each arm verify (empty: the file's split).
    pub verify_last: String,
    /// `--sheet NAME`: the sheet of spreadsheet joint logs (empty: the first).
    pub sheet: String,
    /// ROS 2 bag joint logs: `--joint-topic`, `--still-velocity`, `--still-secs` (the desktop's
    /// only: a browser refuses bags).
    #[cfg(not(target_arch = "wasm32"))]
    pub bag: import::BagOptions,
    /// `--clock-offset S` (empty: estimated).
    #[cfg(not(target_arch = "wasm32"))]
    pub clock_offset: String,
}

impl Default for ImportInputs {
    fn default() -> Self {
        Self {
            points: PerSide::default(),
            joints: PerSide::default(),
            format: None,
            columns: String::new(),
            length_unit: None,
            angle_unit: None,
            joint_length_unit: None,
            decimal_comma: false,
            joint_order: String::new(),
            matching: MatchRule::Auto,
            time_tolerance_s: 0.5,
            stations: PerSide::default(),
            arm_columns: PerSide::default(),
            measured_together: false,
            verify_last: String::new(),
            sheet: String::new(),
            #[cfg(not(target_arch = "wasm32"))]
            bag: import::BagOptions::default(),
            #[cfg(not(target_arch = "wasm32"))]
            clock_offset: String::new(),
        }
    }
}

/// The preview of the current inputs.
pub struct Preview {
    /// The import, or why it failed (the engine's message: file, line, field).
    pub result: Result<Imported, String>,
    /// Why the import cannot be written as it is: what the dataset reader would refuse (too few
    /// configurations, degenerate triangles, a row twice: [`import::check`]) or joint values
    /// outside the robot's limits.
    pub refused: Option<String>,
    /// The robot it was made for (its name, as the robot section shows it).
    pub robot: String,
}

impl Preview {
    /// The dataset to write, if the preview allows it.
    pub fn importable(&self) -> Option<&Imported> {
        match (&self.result, &self.refused) {
            (Ok(imported), None) => Some(imported),
            _ => None,
        }
    }
}

/// The view.
#[derive(Default)]
pub struct ImportView {
    pub open: bool,
    pub inputs: ImportInputs,
    /// The folder the dataset is written to (native), as typed or picked.
    pub out_dir: String,
    /// Why the last "write and open" failed.
    pub write_error: Option<String>,
    /// The preview and the inputs (and robot) it was made of.
    preview: Option<(ImportInputs, String, Preview)>,
}

impl ImportView {
    /// Put a picked file into its slot.
    pub fn set_file(&mut self, slot: ImportSlot, path: &Path) {
        let text = path.display().to_string();
        let field = if slot.joints {
            &mut self.inputs.joints[slot.side]
        } else {
            &mut self.inputs.points[slot.side]
        };
        *field = text;
        if self.out_dir.is_empty()
            && !slot.joints
            && let Some(dir) = path.parent()
        {
            self.out_dir = dir.join("dataset").display().to_string();
        }
    }

    /// The preview of the inputs as they are (`None` until a point file is given: one arm's makes a
    /// dataset of that arm alone).
    pub fn preview(&self) -> Option<&Preview> {
        self.preview.as_ref().map(|(_, _, p)| p)
    }

    /// Import again when the inputs or the robot changed since the last preview (or `force`: the
    /// files may have changed on disk).
    pub fn refresh(&mut self, files: &dyn FileSource, target: &ImportTarget<'_>, force: bool) {
        let robot_key = format!("{:?} {}", target.robot_path, target.robot.name());
        let stale = match &self.preview {
            Some((inputs, robot, _)) => *inputs != self.inputs || *robot != robot_key,
            None => true,
        };
        if !(stale || force) {
            return;
        }
        if Side::BOTH
            .iter()
            .all(|&s| self.inputs.points[s].trim().is_empty())
        {
            self.preview = None;
            return;
        }
        let preview = preview(files, &self.inputs, target);
        self.preview = Some((self.inputs.clone(), robot_key, preview));
    }

    /// The arms' input files, as the engine takes them (`None`: no point file for that arm).
    pub fn arm_files(&self) -> PerSide<Option<ArmFiles>> {
        arm_files(&self.inputs)
    }
}

fn arm_files(inputs: &ImportInputs) -> PerSide<Option<ArmFiles>> {
    PerSide::from_fn(|s| {
        let points = inputs.points[s].trim();
        (!points.is_empty()).then(|| ArmFiles {
            points: PathBuf::from(points),
            joints: Some(inputs.joints[s].trim())
                .filter(|j| !j.is_empty())
                .map(PathBuf::from),
        })
    })
}

/// The engine's options from the inputs; an option that does not parse is an error naming it.
pub fn options(inputs: &ImportInputs, target: &ImportTarget<'_>) -> Result<ImportOptions, String> {
    let mut o = ImportOptions::for_robot(
        target.robot,
        target.robot_path,
        target.reflector_names.clone(),
        target.nominal_reflectors_mm.clone(),
    );
    o.points_format = inputs.format;
    let columns = inputs.columns.trim();
    if !columns.is_empty() {
        o.columns = Some(ColumnMap::parse(columns).map_err(|e| format!("column mapping: {e}"))?);
        o.points_format.get_or_insert(PointsFormat::Generic);
    }
    o.length_unit = inputs.length_unit;
    o.angle_unit = inputs.angle_unit;
    o.joint_length_unit = inputs.joint_length_unit;
    o.decimal_comma = inputs.decimal_comma;
    let order = inputs.joint_order.trim();
    if !order.is_empty() {
        o.joint_order =
            Some(import::parse_joint_order(order).map_err(|e| format!("joint order: {e}"))?);
    }
    o.matching = inputs.matching;
    o.time_tolerance_s = inputs.time_tolerance_s;
    o.stations = PerSide::from_fn(|s| {
        Some(inputs.stations[s].trim().to_string()).filter(|st| !st.is_empty())
    });
    for side in Side::BOTH {
        let spec = inputs.arm_columns[side].trim();
        if !spec.is_empty() {
            o.arm_columns[side] =
                Some(ColumnMap::parse(spec).map_err(|e| format!("{side} column mapping: {e}"))?);
            o.points_format.get_or_insert(PointsFormat::Generic);
        }
    }
    o.measured_together = inputs.measured_together;
    o.sheet = Some(inputs.sheet.trim().to_string()).filter(|s| !s.is_empty());
    #[cfg(not(target_arch = "wasm32"))]
    {
        o.bag = inputs.bag.clone();
        let offset = inputs.clock_offset.trim();
        if !offset.is_empty() {
            o.bag.clock_offset_s = Some(
                offset
                    .parse::<f64>()
                    .ok()
                    .filter(|d| d.is_finite())
                    .ok_or_else(|| {
                        format!("clock offset: `{offset}` is not a number of seconds")
                    })?,
            );
        }
    }
    let last = inputs.verify_last.trim();
    if !last.is_empty() {
        o.verify_last =
            Some(last.parse::<usize>().map_err(|_| {
                format!("verify the last: `{last}` is not a number of configurations")
            })?);
    }
    Ok(o)
}

/// Import with these inputs and check the joint limits, as `dualcal import` does before writing.
fn preview(files: &dyn FileSource, inputs: &ImportInputs, target: &ImportTarget<'_>) -> Preview {
    let robot = target.robot.name();
    let result = options(inputs, target).and_then(|o| {
        import::import_arms(files, &arm_files(inputs), &o).map_err(|e| format!("{e:#}"))
    });
    let refused = result.as_ref().ok().and_then(|imported| {
        let limits = PerSide::from_fn(|s| target.robot.joint_limits_checked_rad(s));
        import::check(imported)
            .map_err(|e| format!("{e:#}"))
            .and_then(|()| {
                crate::dataset::check_joint_limits(&imported.dataset, &limits)
                    .map_err(|e| e.to_string())
            })
            .err()
    });
    Preview {
        result,
        refused,
        robot,
    }
}

/// Write the previewed import into `out` (refusing a non-empty folder and the input files) — the
/// command line's `dualcal import --out`.
pub fn write(view: &ImportView, out: &Path) -> Result<(), String> {
    let Some(imported) = view.preview().and_then(Preview::importable) else {
        return Err("nothing to write: the preview shows why".to_string());
    };
    import::write_arms(
        imported,
        &view.arm_files(),
        out,
        crate::output::Overwrite::Refuse,
    )
    .map_err(|e| format!("{e:#}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::MemoryFiles;

    /// A SpatialAnalyzer-style export and a joint log per arm, in memory: `n` configurations of
    /// the built-in robot with reflectors a, b, c.
    fn files(n: usize) -> MemoryFiles {
        let memory = MemoryFiles::new();
        for side in ["left", "right"] {
            let mut points = String::from("// SpatialAnalyzer export\n// units: mm\n");
            let mut joints = String::from("id,q1,q2,q3,q4,q5,q6,q7\n");
            for k in 0..n {
                let id = format!("{}{k:03}", &side[..1].to_uppercase());
                // The nominal triangle (a, b, c) moved about: every side as the reflectors'.
                let centre = Vector3::new(
                    300.0 + k as f64 * 7.0 + if side == "left" { 0.0 } else { 500.0 },
                    -200.0 + k as f64 * 3.0,
                    400.0 + (k as f64).sin() * 50.0,
                );
                let nominal = [
                    Vector3::new(45.0, 0.0, 40.0),
                    Vector3::new(-25.0, 40.0, 40.0),
                    Vector3::new(-25.0, -40.0, 40.0),
                ];
                for (p, name) in nominal.iter().zip(["a", "b", "c"]) {
                    let x = centre + p;
                    points += &format!("{id}_{name} {:.3} {:.3} {:.3}\n", x.x, x.y, x.z);
                }
                joints += &format!(
                    "{id},{},{},{},{},{},{},{}\n",
                    k as f64 * 0.5,
                    -10.0 + k as f64,
                    5.0,
                    -20.0,
                    10.0,
                    30.0,
                    -5.0
                );
            }
            memory.insert(format!("/in/{side}-points.txt"), points.into_bytes());
            memory.insert(format!("/in/{side}-joints.csv"), joints.into_bytes());
        }
        memory
    }

    fn target(robot: &RobotDescription) -> ImportTarget<'_> {
        ImportTarget {
            robot,
            robot_path: None,
            reflector_names: vec!["a".into(), "b".into(), "c".into()],
            nominal_reflectors_mm: crate::simulate::default_reflectors_for(robot).to_vec(),
        }
    }

    /// Both arms in one file: each arm's own mapping, measured together, the last rows verifying —
    /// as `--left-columns`, `--right-columns`, `--measured-together`, `--verify-last`.
    #[test]
    fn one_file_of_both_arms_imports_with_per_arm_mappings() {
        let memory = MemoryFiles::new();
        let names = ["a", "b", "c"];
        let mut header = String::from("id");
        for arm in ["l", "r"] {
            header += &(1..=7).map(|j| format!(",{arm}q{j}")).collect::<String>();
            for n in names {
                header += &format!(",{arm}{n}x,{arm}{n}y,{arm}{n}z");
            }
        }
        let mut text = header + "\n";
        let nominal =
            crate::simulate::default_reflectors_for(&RobotDescription::builtin_irb14000());
        for k in 0..8 {
            text += &format!("P{k}");
            for arm in 0..2 {
                text += &(0..7)
                    .map(|j| format!(",{}", (k * 3 + j + arm) as f64 * 0.7))
                    .collect::<String>();
                let centre = Vector3::new(300.0 + 9.0 * k as f64, 500.0 * arm as f64, 400.0);
                for p in &nominal {
                    let x = centre + p;
                    text += &format!(",{},{},{}", x.x, x.y, x.z);
                }
            }
            text += "\n";
        }
        memory.insert("/in/both.csv", text.into_bytes());
        let mapping = |arm: &str| {
            let mut m = String::from("id=id");
            for j in 1..=7 {
                m += &format!(",q{j}={arm}q{j}");
            }
            for n in names {
                m += &format!(",{n}.x={arm}{n}x,{n}.y={arm}{n}y,{n}.z={arm}{n}z");
            }
            m
        };
        let mut inputs = ImportInputs {
            points: PerSide::new("/in/both.csv".into(), "/in/both.csv".into()),
            arm_columns: PerSide::new(mapping("l"), mapping("r")),
            measured_together: true,
            verify_last: "3".into(),
            ..ImportInputs::default()
        };
        let robot = RobotDescription::builtin_irb14000();
        let target = target(&robot);
        let preview = super::preview(&memory, &inputs, &target);
        let imported = preview.result.as_ref().expect("imported");
        assert!(imported.dataset.measured_together);
        for side in Side::BOTH {
            let arm = &imported.dataset.arms[side];
            assert_eq!(arm.measurements.len(), 8, "{side}");
            let ver = arm
                .measurements
                .iter()
                .filter(|m| m.split == crate::dataset::Split::Ver)
                .count();
            assert_eq!(ver, 3, "{side}");
            assert_eq!(arm.measurements[0].id, "P0");
        }
        // The right arm's joints are its own columns.
        let q = |side: Side| imported.dataset.arms[side].measurements[1].q_rad[0];
        assert!((q(Side::Right) - q(Side::Left) - 0.7f64.to_radians()).abs() < 1e-12);
        inputs.verify_last = "three".into();
        let err = options(&inputs, &target).unwrap_err();
        assert!(err.contains("verify the last"), "{err}");
    }

    #[test]
    fn the_preview_follows_the_inputs_and_names_what_is_wrong() {
        let memory = files(6);
        let robot = RobotDescription::builtin_irb14000();
        let target = target(&robot);
        let mut view = ImportView::default();
        view.refresh(&memory, &target, false);
        assert!(view.preview().is_none(), "no files yet");
        for side in Side::BOTH {
            view.set_file(
                ImportSlot {
                    side,
                    joints: false,
                },
                Path::new(&format!("/in/{side}-points.txt")),
            );
            view.set_file(
                ImportSlot { side, joints: true },
                Path::new(&format!("/in/{side}-joints.csv")),
            );
        }
        assert_eq!(view.out_dir, "/in/dataset");
        view.refresh(&memory, &target, false);
        let preview = view.preview().unwrap();
        let imported = preview.importable().expect("imports");
        assert_eq!(imported.dataset.arms.left.measurements.len(), 6);
        assert_eq!(imported.dataset.arms.right.measurements.len(), 6);
        assert_eq!(
            imported.report.arms.left.as_ref().unwrap().format,
            PointsFormat::SpatialAnalyzer
        );

        // A bad option: named, nothing importable.
        view.inputs.joint_order = "1,2,x".into();
        view.refresh(&memory, &target, false);
        let err = view.preview().unwrap().result.as_ref().unwrap_err();
        assert!(err.starts_with("joint order:"), "{err}");
        view.inputs.joint_order.clear();
        view.refresh(&memory, &target, false);
        assert!(view.preview().unwrap().importable().is_some());

        // A damaged file: the engine's message with file and line; the preview is made again only
        // when asked (the inputs did not change).
        memory.insert(
            "/in/left-joints.csv",
            b"id,q1,q2,q3,q4,q5,q6,q7\nL000,1,2,3,x,5,6,7\n".to_vec(),
        );
        view.refresh(&memory, &target, false);
        assert!(view.preview().unwrap().importable().is_some());
        view.refresh(&memory, &target, true);
        let err = view.preview().unwrap().result.as_ref().unwrap_err();
        assert!(err.contains("/in/left-joints.csv:2"), "{err}");

        // Joint values outside the limits: imported, but refused as `dualcal import` refuses them.
        memory.insert(
            "/in/left-joints.csv",
            b"id,q1,q2,q3,q4,q5,q6,q7\nL000,1,2,3,4,5,6,7\nL001,1,2,3,4,5,6,7\nL002,1,2,3,4,5,6,7\nL003,1,2,3,4,5,6,7\nL004,1,2,3,4,5,6,7\nL005,400,2,3,4,5,6,7\n"
                .to_vec(),
        );
        view.refresh(&memory, &target, true);
        let preview = view.preview().unwrap();
        assert!(preview.result.is_ok());
        assert!(
            preview
                .refused
                .as_deref()
                .is_some_and(|e| e.contains("/in/left-joints.csv:7: field `q1`")),
            "{:?}",
            preview.refused
        );
        assert!(preview.importable().is_none());

        // Too few configurations for a dataset: the report is there, the dataset refused.
        memory.insert(
            "/in/left-joints.csv",
            b"id,q1,q2,q3,q4,q5,q6,q7\nL000,1,2,3,4,5,6,7\nL001,1,2,3,4,5,6,8\n".to_vec(),
        );
        view.refresh(&memory, &target, true);
        let preview = view.preview().unwrap();
        let imported = preview.result.as_ref().unwrap();
        assert_eq!(imported.report.arms.left.as_ref().unwrap().matched, 2);
        assert!(
            preview
                .refused
                .as_deref()
                .is_some_and(|e| e.contains("/in/left-joints.csv: the left arm has 2")),
            "{:?}",
            preview.refused
        );
        assert!(preview.importable().is_none());
    }

    #[test]
    fn the_written_dataset_is_the_command_lines() {
        let memory = files(8);
        let robot = RobotDescription::builtin_irb14000();
        let target = target(&robot);
        let mut view = ImportView::default();
        for side in Side::BOTH {
            view.inputs.points[side] = format!("/in/{side}-points.txt");
            view.inputs.joints[side] = format!("/in/{side}-joints.csv");
        }
        view.refresh(&memory, &target, false);
        let imported = view.preview().unwrap().importable().unwrap().clone();
        // The files a browser keeps in memory are the ones written to disk.
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        let inputs = view.arm_files();
        import::write_arms(&imported, &inputs, &out, crate::output::Overwrite::Refuse).unwrap();
        for (path, bytes) in import::files_of(&imported, &out).unwrap() {
            assert_eq!(std::fs::read(&path).unwrap(), bytes, "{}", path.display());
        }
        // Refused a second time: the folder is not empty.
        let err = import::write_arms(&imported, &inputs, &out, crate::output::Overwrite::Refuse)
            .unwrap_err()
            .to_string();
        assert!(err.contains(&out.display().to_string()), "{err}");
        let back = crate::dataset::load(&out).unwrap();
        assert_eq!(back.arms.left.measurements.len(), 8);
    }

    #[test]
    fn one_arms_files_preview_and_write_a_dataset_of_that_arm_alone() {
        let memory = files(8);
        let robot = RobotDescription::builtin_irb14000();
        let target = target(&robot);
        let mut view = ImportView::default();
        view.refresh(&memory, &target, false);
        assert!(view.preview().is_none());
        view.inputs.points.right = "/in/right-points.txt".into();
        view.inputs.joints.right = "/in/right-joints.csv".into();
        view.refresh(&memory, &target, false);
        let imported = view.preview().unwrap().importable().unwrap().clone();
        assert!(imported.report.arms.left.is_none());
        assert_eq!(imported.report.arms.right.as_ref().unwrap().matched, 8);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        write(&view, &out).unwrap();
        let back = crate::dataset::load(&out).unwrap();
        assert_eq!(back.measured_sides(), vec![Side::Right]);
        assert_eq!(back.arms.right.measurements.len(), 8);
        assert!(!out.join("left.csv").exists());
    }
}
