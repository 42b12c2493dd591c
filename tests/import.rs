//! `dualcal import` (issue 22, "Import"): a simulated dataset written as a SpatialAnalyzer export, a
//! Leica Tracker Pilot CSV (Windows-1252 bytes) and a figaroh CSV with joint logs — every file written
//! here, no third-party data — imports into a dataset with the native dataset's measurements and
//! calibration; malformed files are refused naming file, line and field; unmatched targets are
//! reported; repeated shots are averaged with their spread.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, AngleUnit, Dataset, LengthUnit, Split, Units};
use dualcal::import::{
    self, ArmFiles, ColumnMap, ImportError, ImportOptions, Imported, MatchRule, PointsFormat,
    YUMI_ABB_ORDER,
};
use dualcal::output::Overwrite;
use dualcal::robot::RobotDescription;
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{SimOutput, paper_options, simulate_with_robot};
use dualcal::solver::CalibrationSettings;
use dualcal::source::OsFiles;
use std::path::{Path, PathBuf};
use std::process::Command;

fn simulated(seed: u64) -> SimOutput {
    simulate_with_robot(
        &paper_options(seed, 40, 30),
        &RobotDescription::builtin_irb14000(),
    )
    .unwrap()
}

/// The simulated dataset through its own files in `units` (what the native reader gives).
fn native(sim: &SimOutput, dir: &Path, units: Units) -> Dataset {
    let out = dir.join("native");
    dataset::save(&sim.dataset, &out, units).unwrap();
    dataset::load(&out).unwrap()
}

fn options(ds: &Dataset) -> ImportOptions {
    let robot = RobotDescription::builtin_irb14000();
    let mut o = ImportOptions::new(
        ds.reflector_names.to_vec(),
        ds.nominal_reflectors_mm.clone(),
    );
    o.tracker = ds.tracker;
    o.joint_names = PerSide::from_fn(|s| Some(robot.arm_joint_names(s)));
    o
}

/// A number as the dataset writer writes it (shortest text that reads back exactly).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// Joint log `id,q1..q7,split` in degrees, as the native CSV writes them; `order` permutes the columns
/// (the log's column `order[k]` holds chain joint k).
fn joint_log(ds: &Dataset, side: Side, order: Option<&[usize]>, time: bool) -> String {
    let arm = ds.arm(side);
    let n = arm.joint_count();
    let mut s = String::from("id");
    for k in 1..=n {
        s += &format!(",q{k}");
    }
    if time {
        s += ",time";
    }
    s += ",split\n";
    for (i, m) in arm.measurements.iter().enumerate() {
        let mut cols = vec![String::new(); n];
        for (k, q) in m.q_rad.iter().enumerate() {
            let c = order.map_or(k, |o| o[k] - 1);
            cols[c] = num(q.to_degrees());
        }
        s += &format!("{},{}", m.id, cols.join(","));
        if time {
            s += &format!(",{}", stamp(i, 0));
        }
        s += &format!(",{}\n", m.split.name());
    }
    s
}

/// A Tracker Pilot time stamp: configuration `i` at 10 s intervals, reflector `r` 1 s apart.
fn stamp(i: usize, r: usize) -> String {
    let t = 15 * 3600 + 6 * 60 + 10 * i + r;
    format!(
        "11.10.2022 {:02}:{:02}:{:02}.043",
        t / 3600,
        t / 60 % 60,
        t % 60
    )
}

/// A SpatialAnalyzer export of one arm: `//` header, `Collection Group Target X Y Z` and rows, some in
/// scientific notation, space separated.
fn spatial_analyzer(ds: &Dataset, side: Side) -> String {
    let mut s = String::from(
        "// SpatialAnalyzer ASCII export\n// Working Frame: World\n// Units: Millimeters\n\
         Collection Group Target X Y Z\n",
    );
    for (i, m) in ds.arm(side).measurements.iter().enumerate() {
        for (name, p) in ds.reflector_names.iter().zip(&m.tracker_points_mm) {
            let f = |x: f64| if i % 2 == 0 { num(x) } else { format!("{x:e}") };
            s += &format!(
                "A {side}_arm {}_{name}   {} {} {}\n",
                m.id,
                f(p.x),
                f(p.y),
                f(p.z)
            );
        }
    }
    s
}

const LEICA_HEADER: &str = "X  [mm],Y  [mm],Z  [mm],U(95)  [mm],U(95) X  [µm],Target,\
                            Temperature  [°C],Pressure  [hPa],Humidity  [%],Time Stamp,";

/// A Leica Tracker Pilot CSV of one arm, as Windows-1252 bytes.
fn leica(ds: &Dataset, side: Side) -> Vec<u8> {
    let mut s = format!("{LEICA_HEADER}\r\n");
    for (i, m) in ds.arm(side).measurements.iter().enumerate() {
        for (r, (name, p)) in ds
            .reflector_names
            .iter()
            .zip(&m.tracker_points_mm)
            .enumerate()
        {
            s += &format!(
                "{},{},{},0.0123,5.1,{}_{name},20.4,1012.8,41.0,'{},\r\n",
                num(p.x),
                num(p.y),
                num(p.z),
                m.id,
                stamp(i, r)
            );
        }
    }
    windows_1252(&s)
}

fn windows_1252(s: &str) -> Vec<u8> {
    s.chars()
        .map(|c| match c {
            'µ' => 0xB5,
            '°' => 0xB0,
            c if c.is_ascii() => c as u8,
            c => panic!("{c} is not in the test's Windows-1252 table"),
        })
        .collect()
}

/// figaroh's calibration CSV of one arm: `x1,y1,z1,…` in metres, the joints by their URDF names in
/// radians.
fn figaroh(ds: &Dataset, side: Side) -> String {
    let robot = RobotDescription::builtin_irb14000();
    let joints = robot.arm_joint_names(side);
    let mut cols: Vec<String> = (1..=ds.reflector_count())
        .flat_map(|k| [format!("x{k}"), format!("y{k}"), format!("z{k}")])
        .collect();
    // The joint columns in reverse order: the reader puts them in chain order by their names.
    cols.extend(joints.iter().rev().cloned());
    let mut s = cols.join(",") + "\n";
    for m in &ds.arm(side).measurements {
        let mut row: Vec<String> = m
            .tracker_points_mm
            .iter()
            .flat_map(|p| [num(p.x / 1000.0), num(p.y / 1000.0), num(p.z / 1000.0)])
            .collect();
        row.extend(m.q_rad.iter().rev().map(|&q| num(q)));
        s += &(row.join(",") + "\n");
    }
    s
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Import, write into `dir/out`, load back.
fn import_and_load(
    dir: &Path,
    inputs: &PerSide<ArmFiles>,
    o: &ImportOptions,
) -> (Imported, Dataset) {
    let imported = import::import(&OsFiles, inputs, o).unwrap();
    let out = dir.join("imported");
    import::write(&imported, inputs, &out, Overwrite::Refuse).unwrap();
    let back = dataset::load(&out).unwrap();
    (imported, back)
}

/// The same configurations, joints, points (bit for bit) and splits; same reflectors and tracker.
fn assert_same_measurements(a: &Dataset, b: &Dataset, same_ids: bool, same_splits: bool) {
    assert_eq!(a.reflector_names, b.reflector_names);
    assert_eq!(a.nominal_reflectors_mm, b.nominal_reflectors_mm);
    assert_eq!(a.tracker, b.tracker);
    for side in Side::BOTH {
        let (x, y) = (a.arm(side), b.arm(side));
        assert_eq!(x.measurements.len(), y.measurements.len(), "{side}");
        for (m, n) in x.measurements.iter().zip(&y.measurements) {
            if same_ids {
                assert_eq!(m.id, n.id);
            }
            if same_splits {
                assert_eq!(m.split, n.split, "{}", m.id);
            }
            assert_eq!(m.q_rad, n.q_rad, "{}", m.id);
            assert_eq!(m.tracker_points_mm, n.tracker_points_mm, "{}", m.id);
        }
    }
}

/// Both datasets calibrated alike give the same parameters (within 1e-9).
fn assert_same_calibration(a: &Dataset, b: &Dataset, split: Split) {
    let robot = RobotDescription::builtin_irb14000();
    let settings = CalibrationSettings {
        split,
        ..CalibrationSettings::default()
    };
    let ra = common::calibrate(a, &robot.nominal_model_for(a), &settings);
    let rb = common::calibrate(b, &robot.nominal_model_for(b), &settings);
    for side in Side::BOTH {
        let (x, y) = (
            ra.calibrated.arm(side).to_vector(),
            rb.calibrated.arm(side).to_vector(),
        );
        assert_eq!(x.len(), y.len());
        // A calibration that moved the parameters, not the nominal model twice.
        assert!((&x - ra.nominal.arm(side).to_vector()).amax() > 1e-6);
        assert!((x - y).amax() <= 1e-9, "{side} arm parameters differ");
    }
    let (p, q) = (
        ra.calibrated.left_base_from_right_base,
        rb.calibrated.left_base_from_right_base,
    );
    assert!((p.translation.vector - q.translation.vector).amax() <= 1e-9);
    assert!(p.rotation.angle_to(&q.rotation) <= 1e-9);
}

#[test]
fn spatial_analyzer_export_imports_into_the_native_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(3);
    let native = native(&sim, dir.path(), Units::MM_DEG);
    let inputs = PerSide::from_fn(|side| ArmFiles {
        points: write(
            dir.path(),
            &format!("{side}.txt"),
            spatial_analyzer(&sim.dataset, side),
        ),
        joints: Some(write(
            dir.path(),
            &format!("{side}-joints.csv"),
            joint_log(&sim.dataset, side, None, false),
        )),
    });
    let (imported, back) = import_and_load(dir.path(), &inputs, &options(&native));
    let report = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(report.format, PointsFormat::SpatialAnalyzer);
    assert_eq!(report.frame.as_deref(), Some("World"));
    assert_eq!(report.points_read, 120);
    assert_eq!(report.matched, 40);
    assert!(report.unmatched_points.is_empty() && report.unmatched_configurations.is_empty());
    assert_same_measurements(&native, &back, true, true);
    assert_same_calibration(&native, &back, Split::Cal);
}

#[test]
fn leica_csv_in_windows_1252_imports_into_the_native_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(4);
    let native = native(&sim, dir.path(), Units::MM_DEG);
    // The joint log in the YuMi's ABB axis order 1…7, mapped back to chain order.
    let inputs = PerSide::from_fn(|side| ArmFiles {
        points: write(
            dir.path(),
            &format!("{side}.csv"),
            leica(&sim.dataset, side),
        ),
        joints: Some(write(
            dir.path(),
            &format!("{side}-joints.csv"),
            joint_log(&sim.dataset, side, Some(&YUMI_ABB_ORDER), false),
        )),
    });
    let bytes = std::fs::read(&inputs.left.points).unwrap();
    assert!(bytes.contains(&0xB5) && std::str::from_utf8(&bytes).is_err());
    let mut o = options(&native);
    o.joint_order = Some(YUMI_ABB_ORDER.to_vec());
    let (imported, back) = import_and_load(dir.path(), &inputs, &o);
    assert_eq!(
        imported.report.arms.right.as_ref().unwrap().format,
        PointsFormat::Leica
    );
    assert_eq!(imported.report.arms.right.as_ref().unwrap().matched, 40);
    assert_same_measurements(&native, &back, true, true);
    assert_same_calibration(&native, &back, Split::Cal);
    // The inputs are untouched.
    assert_eq!(std::fs::read(&inputs.left.points).unwrap(), bytes);
}

#[test]
fn figaroh_csv_imports_into_the_native_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(5);
    // figaroh writes metres and radians: the native dataset in the same units reads the same texts.
    let native = native(
        &sim,
        dir.path(),
        Units {
            length: LengthUnit::M,
            angle: AngleUnit::Rad,
        },
    );
    let inputs = PerSide::from_fn(|side| ArmFiles {
        points: write(
            dir.path(),
            &format!("{side}.csv"),
            figaroh(&sim.dataset, side),
        ),
        joints: None,
    });
    let (imported, back) = import_and_load(dir.path(), &inputs, &options(&native));
    assert_eq!(
        imported.report.arms.left.as_ref().unwrap().format,
        PointsFormat::Figaroh
    );
    // figaroh has no split: every configuration is a calibration configuration, so both datasets are
    // calibrated on all of theirs. Ids are made as the simulator makes them (L001, …).
    assert!(
        back.arm(Side::Left)
            .measurements
            .iter()
            .all(|m| m.split == Split::Cal)
    );
    assert_same_measurements(&native, &back, true, false);
    assert_same_calibration(&native, &back, Split::All);
}

#[test]
fn leica_points_match_by_time_stamp_within_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(6);
    let native = native(&sim, dir.path(), Units::MM_DEG);
    // Target names without ids: only the reflector; the time stamps find the configuration (the
    // reflectors are 0–2 s after the configuration's stamp).
    let inputs = PerSide::from_fn(|side| {
        let text = String::from_utf8(
            leica(&sim.dataset, side)
                .iter()
                .map(|&b| b as char)
                .collect::<String>()
                .into_bytes(),
        )
        .unwrap();
        let renamed: String = text
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                if f.len() > 5 && f[5].contains('_') {
                    let mut g = f.clone();
                    let r = f[5].rsplit_once('_').unwrap().1;
                    g[5] = r;
                    g.join(",") + "\n"
                } else {
                    l.to_string() + "\n"
                }
            })
            .collect();
        ArmFiles {
            points: write(dir.path(), &format!("{side}.csv"), windows_1252(&renamed)),
            joints: Some(write(
                dir.path(),
                &format!("{side}-joints.csv"),
                joint_log(&sim.dataset, side, None, true),
            )),
        }
    });
    let mut o = options(&native);
    o.matching = MatchRule::Time;
    o.time_tolerance_s = 2.5;
    let (_, back) = import_and_load(dir.path(), &inputs, &o);
    assert_same_measurements(&native, &back, true, true);
    // A tolerance below the reflectors' delays leaves configurations without reflectors.
    o.time_tolerance_s = 1.5;
    let imported = import::import(&OsFiles, &inputs, &o).unwrap();
    let left = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(left.matched, 0);
    assert_eq!(left.unmatched_configurations.len(), 40);
    // Reflector c (2 s after its configuration) is too late; a and b lack it.
    let late = left
        .unmatched_points
        .iter()
        .find(|u| u.name == "c")
        .unwrap();
    assert!(
        late.reason.contains("2.000 s away (tolerance 1.5 s)"),
        "{late:?}"
    );
    assert!(
        left.unmatched_configurations[0]
            .reason
            .contains("reflector c")
    );
    // Such an import says what did not match, and is not written: the dataset would not load.
    let out = dir.path().join("unmatched");
    let err = import::write(&imported, &inputs, &out, Overwrite::Refuse)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("left-joints.csv: the left arm has 0 configurations"),
        "{err}"
    );
    assert!(!out.exists());
}

/// The error of importing `left` points/joints texts (the right arm valid).
fn import_error(dir: &Path, points: &[u8], joints: Option<&str>, o: &ImportOptions) -> ImportError {
    let sim = simulated(7);
    let ds = &sim.dataset;
    let inputs = PerSide::new(
        ArmFiles {
            points: write(dir, "bad-points.txt", points),
            joints: joints.map(|j| write(dir, "bad-joints.csv", j)),
        },
        ArmFiles {
            points: write(dir, "right.txt", spatial_analyzer(ds, Side::Right)),
            joints: Some(write(
                dir,
                "right-joints.csv",
                joint_log(ds, Side::Right, None, false),
            )),
        },
    );
    import::import(&OsFiles, &inputs, o).unwrap_err()
}

#[test]
fn malformed_inputs_are_refused_with_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(7);
    let ds = &sim.dataset;
    let o = options(ds);
    let sa = spatial_analyzer(ds, Side::Left);
    let log = joint_log(ds, Side::Left, None, false);

    // A coordinate that is no number: line 7 is the third point (4 header lines).
    let bad: String = sa
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 6 {
                let mut f: Vec<&str> = l.split_whitespace().collect();
                f[4] = "12.3.4";
                f.join(" ") + "\n"
            } else {
                l.to_string() + "\n"
            }
        })
        .collect();
    let e = import_error(dir.path(), bad.as_bytes(), Some(&log), &o);
    assert_eq!((e.line(), e.field()), (Some(7), Some("Y")), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("bad-points.txt:7") && msg.contains("12.3.4"),
        "{msg}"
    );

    // A row cut short.
    let cut = sa.lines().take(9).collect::<Vec<_>>().join("\n") + "\nA left_arm L002_c 1.0 2.0\n";
    let e = import_error(dir.path(), cut.as_bytes(), Some(&log), &o);
    assert!(
        matches!(
            e,
            ImportError::FieldCount {
                line: 10,
                found: 5,
                ..
            }
        ),
        "{e}"
    );

    // A Leica header without Z.
    let leica_bytes = leica(ds, Side::Left);
    let no_z = String::from_utf8_lossy(&leica_bytes).replacen("Z  [mm]", "Q  [mm]", 1);
    let e = import_error(dir.path(), no_z.as_bytes(), Some(&log), &o);
    assert_eq!((e.line(), e.field()), (Some(1), Some("Z  [mm]")), "{e}");
    // A format forced on a file of another: figaroh's marker columns are missing.
    let mut forced = options(ds);
    forced.points_format = Some(PointsFormat::Figaroh);
    let e = import_error(dir.path(), sa.as_bytes(), Some(&log), &forced);
    assert_eq!((e.line(), e.field()), (Some(1), Some("x1")), "{e}");

    // A joint value that is no number, on the log's line 4 (header, then rows).
    let bad_log = log.replacen(
        &log.lines()
            .nth(3)
            .unwrap()
            .split(',')
            .nth(3)
            .unwrap()
            .to_string(),
        "abc",
        1,
    );
    let e = import_error(dir.path(), sa.as_bytes(), Some(&bad_log), &o);
    assert_eq!((e.line(), e.field()), (Some(4), Some("q3")), "{e}");
    assert!(e.to_string().contains("bad-joints.csv:4"), "{e}");

    // Six joint columns for a seven-joint arm.
    let six: String = log
        .lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(7);
            f.join(",") + "\n"
        })
        .collect();
    let e = import_error(dir.path(), sa.as_bytes(), Some(&six), &o);
    assert!(matches!(e, ImportError::Header { line: 1, .. }), "{e}");
    assert!(e.to_string().contains("the arm has 7 joints"), "{e}");

    // A duplicate id.
    let second = log
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    let dup = log.replacen(
        &format!("{second},"),
        &format!("{},", ds.arms.left.measurements[0].id),
        1,
    );
    let e = import_error(dir.path(), sa.as_bytes(), Some(&dup), &o);
    assert!(
        matches!(
            e,
            ImportError::DuplicateId {
                line: 3,
                first_line: 2,
                ..
            }
        ),
        "{e}"
    );

    // figaroh without one of the arm's joints.
    let fig = figaroh(ds, Side::Left);
    let joint = RobotDescription::builtin_irb14000().arm_joint_names(Side::Left)[2].clone();
    let e = import_error(
        dir.path(),
        fig.replacen(&joint, "elbow", 1).as_bytes(),
        None,
        &o,
    );
    assert_eq!(
        (e.line(), e.field()),
        (Some(1), Some(joint.as_str())),
        "{e}"
    );
    // A figaroh value that is no number.
    let mut lines: Vec<String> = fig.lines().map(str::to_string).collect();
    let mut f: Vec<String> = lines[5].split(',').map(str::to_string).collect();
    f[4] = "n/a".into();
    lines[5] = f.join(",");
    let e = import_error(dir.path(), (lines.join("\n") + "\n").as_bytes(), None, &o);
    assert_eq!((e.line(), e.field()), (Some(6), Some("y2")), "{e}");

    // UTF-16 is refused, not misread.
    let e = import_error(dir.path(), &[0xFF, 0xFE, b'X', 0], Some(&log), &o);
    assert!(matches!(e, ImportError::Encoding { .. }), "{e}");

    // Points without a joint log.
    let e = import_error(dir.path(), sa.as_bytes(), None, &o);
    assert!(e.to_string().contains("--left-joints"), "{e}");
}

#[test]
fn unmatched_targets_are_reported_and_repeated_shots_averaged() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(8);
    let ds = &sim.dataset;
    let first = &ds.arms.left.measurements[0];
    let second = &ds.arms.left.measurements[1];
    let mut sa = spatial_analyzer(ds, Side::Left);
    // Two more shots of the first configuration's reflector a, 0.01 mm either side in x.
    let a = first.tracker_points_mm[0];
    for dx in [0.01, -0.01] {
        sa += &format!(
            "A left_arm {}_a {} {} {}\n",
            first.id,
            num(a.x + dx),
            num(a.y),
            num(a.z)
        );
    }
    // A target of no configuration, a name without a reflector, and the second configuration's
    // reflector c left out.
    sa += "A left_arm X999_a 1.0 2.0 3.0\nA left_arm stray 1.0 2.0 3.0\n";
    let c_line = format!("A left_arm {}_c ", second.id);
    let sa: String = sa
        .lines()
        .filter(|l| !l.starts_with(&c_line))
        .map(|l| l.to_string() + "\n")
        .collect();
    let inputs = PerSide::new(
        ArmFiles {
            points: write(dir.path(), "left.txt", &sa),
            joints: Some(write(
                dir.path(),
                "left-joints.csv",
                joint_log(ds, Side::Left, None, false),
            )),
        },
        ArmFiles {
            points: write(dir.path(), "right.txt", spatial_analyzer(ds, Side::Right)),
            joints: Some(write(
                dir.path(),
                "right-joints.csv",
                joint_log(ds, Side::Right, None, false),
            )),
        },
    );
    let imported = import::import(&OsFiles, &inputs, &options(ds)).unwrap();
    let r = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(r.matched, 39);
    assert_eq!(r.unmatched_configurations.len(), 1);
    assert_eq!(r.unmatched_configurations[0].name, second.id);
    assert!(r.unmatched_configurations[0].reason.contains("reflector c"));
    let reason = |name: &str| {
        r.unmatched_points
            .iter()
            .find(|u| u.name == name)
            .unwrap_or_else(|| panic!("{name} not reported: {r}"))
            .reason
            .clone()
    };
    assert!(reason("X999_a").contains("no configuration `X999`"));
    assert!(reason("stray").contains("<id>_<reflector>"));
    // The second configuration's a and b are reported unused.
    assert!(reason(&format!("{}_a", second.id)).contains("lacks reflector c"));
    assert_eq!(r.repeated.len(), 1);
    let rep = &r.repeated[0];
    assert_eq!(
        (rep.id.as_str(), rep.reflector.as_str(), rep.shots),
        (first.id.as_str(), "a", 3)
    );
    assert!((rep.spread_mm - 0.01).abs() < 1e-9, "{}", rep.spread_mm);
    let got = imported.dataset.arms.left.measurements[0].tracker_points_mm[0];
    assert!((got - a).amax() < 1e-9);
    let text = imported.report.to_string();
    assert!(
        text.contains("3 shots averaged, spread 0.0100 mm"),
        "{text}"
    );
    assert!(text.contains("unmatched point `stray`"), "{text}");
}

fn dualcal(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn the_command_imports_and_refuses_a_non_empty_out() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(9);
    let ds = &sim.dataset;
    let files: Vec<PathBuf> = Side::BOTH
        .iter()
        .flat_map(|&side| {
            [
                write(dir.path(), &format!("{side}.csv"), leica(ds, side)),
                write(
                    dir.path(),
                    &format!("{side}-joints.csv"),
                    joint_log(ds, side, None, false),
                ),
            ]
        })
        .collect();
    let f: Vec<&str> = files.iter().map(|p| p.to_str().unwrap()).collect();
    let out = dir.path().join("out");
    let refl: Vec<String> = ds
        .reflector_names
        .iter()
        .zip(&ds.nominal_reflectors_mm)
        .map(|(n, p)| format!("{n}={},{},{}", p.x, p.y, p.z))
        .collect();
    let mut args = vec![
        "import",
        "--left-points",
        f[0],
        "--left-joints",
        f[1],
        "--right-points",
        f[2],
        "--right-joints",
        f[3],
        "--angle-unit",
        "deg",
        "--out",
        out.to_str().unwrap(),
    ];
    for r in &refl {
        args.extend(["--reflector", r]);
    }
    let o = dualcal(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("40 configurations matched"), "{stdout}");
    assert!(out.join(import::REPORT_FILE).is_file());
    let back = dataset::load(&out).unwrap();
    assert_eq!(back.arms.right.measurements.len(), 40);
    // Again into the same directory: refused, unless --force.
    let o = dualcal(&args);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("already exists"));
    args.push("--force");
    assert!(dualcal(&args).status.success());
    // A malformed log: non-zero exit naming file and line.
    let bad = write(
        dir.path(),
        "bad.csv",
        "id,q1,q2,q3,q4,q5,q6,q7\nL001,1,2,x,4,5,6,7\n",
    );
    let mut bad_args = args.clone();
    bad_args[4] = bad.to_str().unwrap();
    let o = dualcal(&bad_args);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv:2: field `q3`"), "{err}");
}

/// The point readers on the variants users' exports take: name columns `Group Target`, `Target` or
/// none, comma or space separated, units from the header, decimal commas, a generic mapping.
#[test]
fn point_file_variants_read_alike() {
    use dualcal::import::points::{ReadOptions, read};
    use dualcal::import::{ColumnMap, PointTable, PointUnit};
    let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
    let o = ReadOptions {
        format: None,
        unit: None,
        decimal_comma: false,
        columns: None,
        reflector_names: &names,
        joint_names: None,
        angle_unit: AngleUnit::Deg,
    };
    let p = Path::new("points.txt");
    let points = |text: &str, o: &ReadOptions| match read(p, text, o).unwrap().table {
        PointTable::Points(v) => v
            .into_iter()
            .map(|q| (q.target, q.position_mm))
            .collect::<Vec<_>>(),
        PointTable::Rows(_) => panic!("rows"),
    };
    let want = vec![
        (
            Some("L1_a".to_string()),
            nalgebra::Vector3::new(1000.5, -2.0, 30.0),
        ),
        (
            Some("L1_b".to_string()),
            nalgebra::Vector3::new(1.0, 2.0, 3.0),
        ),
    ];
    // Group Target X Y Z, comma separated, scientific notation, extra columns.
    assert_eq!(
        points(
            "Group,Target,X,Y,Z,Tol\nG,L1_a,1.0005e3,-2,30,0.1\nG,L1_b,1,2,3,0.1\n",
            &o
        ),
        want
    );
    // Target only, no header, space separated.
    assert_eq!(points("L1_a 1000.5 -2 30\nL1_b 1 2 3\n", &o), want);
    // Meters in the `//` header.
    assert_eq!(
        points(
            "// Units: Meters\nL1_a 1.0005 -0.002 0.03\nL1_b 0.001 0.002 0.003\n",
            &o
        ),
        want
    );
    // No names at all.
    let unnamed = points("1000.5 -2 30\n", &o);
    assert_eq!(unnamed, vec![(None, want[0].1)]);
    // Decimal commas with `;` (Leica in a German locale), µm forced by the header.
    let leica = "X  [mm];Y  [mm];Z  [mm];Target;Time Stamp\n1000,5;-2;30;L1_a;'11.10.2022 15:06:48.043\n\
                 1;2;3;L1_b;'11.10.2022 15:06:49.043\n";
    assert_eq!(points(leica, &o), want);
    let file = read(p, leica, &o).unwrap();
    assert_eq!(
        (file.format, file.unit),
        (PointsFormat::Leica, PointUnit::Mm)
    );
    // A generic file, one point per row, columns by header name, decimal commas and inches.
    let map = ColumnMap::parse("target=Name,x=3,y=4,z=5").unwrap();
    let g = ReadOptions {
        columns: Some(&map),
        unit: Some(PointUnit::In),
        decimal_comma: true,
        ..o.clone()
    };
    let got = points("Name;Station;East;North;Up\nL1_a;S1;10;0,5;-1\n", &g);
    assert_eq!(got[0].0.as_deref(), Some("L1_a"));
    assert!((got[0].1 - nalgebra::Vector3::new(254.0, 12.7, -25.4)).amax() < 1e-12);
    // A generic file of whole configurations: id, reflectors, joints in degrees, split.
    let map = ColumnMap::parse(
        "id=1,a.x=2,a.y=3,a.z=4,b.x=5,b.y=6,b.z=7,c.x=8,c.y=9,c.z=10,q=11-12,split=13",
    )
    .unwrap();
    let g = ReadOptions {
        columns: Some(&map),
        ..o.clone()
    };
    let file = read(p, "P1,1,2,3,4,5,6,7,8,9,90,-45,ver\n", &g).unwrap();
    let PointTable::Rows(rows) = file.table else {
        panic!("points")
    };
    assert_eq!(rows[0].id.as_deref(), Some("P1"));
    assert_eq!(rows[0].points_mm[2], nalgebra::Vector3::new(7.0, 8.0, 9.0));
    let q = rows[0].q_rad.as_ref().unwrap();
    assert!(
        (q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15
            && (q[1] + std::f64::consts::FRAC_PI_4).abs() < 1e-15
    );
    assert_eq!(rows[0].split, Some(Split::Ver));
    // Mappings that cannot work are refused with the reason.
    assert!(
        ColumnMap::parse("x=1,a.x=2")
            .unwrap_err()
            .contains("either")
    );
    assert!(
        ColumnMap::parse("x=0,y=1,z=2")
            .unwrap_err()
            .contains("from 1")
    );
    assert!(
        ColumnMap::parse("x=1,y=2,z=3,w=4")
            .unwrap_err()
            .contains("unknown role")
    );
}

/// A joint log with a header naming the URDF joints in another order is put in chain order by the
/// names; a `[rad]` header sets the unit; the YuMi mapping and its preset name agree.
#[test]
fn joint_logs_by_names_units_and_mappings() {
    use dualcal::import::joints::{JointLogOptions, read};
    let robot = RobotDescription::builtin_irb14000();
    let names = robot.arm_joint_names(Side::Left);
    let mut header: Vec<String> = vec!["time".into(), "id".into()];
    header.extend(names.iter().rev().map(|n| format!("{n} [rad]")));
    let text = format!("{}\n0.5,P1,7,6,5,4,3,2,1\n", header.join(","));
    let o = JointLogOptions {
        joint_names: Some(&names),
        id_prefix: "L",
        ..Default::default()
    };
    let log = read(Path::new("j.csv"), &text, &o).unwrap();
    assert_eq!(log.angle_unit, AngleUnit::Rad);
    assert_eq!(log.rows[0].id, "P1");
    assert_eq!(log.rows[0].q_rad, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    assert_eq!(log.rows[0].time_s, Some(0.5));
    assert_eq!(
        import::parse_joint_order("yumi-abb").unwrap(),
        YUMI_ABB_ORDER
    );
    assert_eq!(
        import::parse_joint_order("1,2,7,3,4,5,6").unwrap(),
        YUMI_ABB_ORDER
    );
    assert!(import::parse_joint_order("1,2,2").is_err());
    // A log of ABB axes 1…7 (axis 7 third in chain order), no header, degrees.
    let order = YUMI_ABB_ORDER;
    let o = JointLogOptions {
        joint_order: Some(&order),
        id_prefix: "L",
        ..Default::default()
    };
    let log = read(Path::new("j.csv"), "P1,10,20,30,40,50,60,70\n", &o).unwrap();
    let deg: Vec<f64> = log.rows[0]
        .q_rad
        .iter()
        .map(|q| q.to_degrees().round())
        .collect();
    assert_eq!(deg, [10.0, 20.0, 70.0, 30.0, 40.0, 50.0, 60.0]);
}

/// Garbage and damaged files are refused or read, never a panic: random bytes, and valid files of each
/// format with bytes changed, cut or repeated, through every reader.
#[test]
fn damaged_files_never_panic() {
    use dualcal::import::joints::{self, JointLogOptions};
    use dualcal::import::points::{ReadOptions, read};
    use rand::{Rng, SeedableRng};
    let sim = simulated(10);
    let ds = &sim.dataset;
    let names = ds.reflector_names.to_vec();
    let joint_names = RobotDescription::builtin_irb14000().arm_joint_names(Side::Left);
    let map =
        ColumnMap::parse("id=1,a.x=2,a.y=3,a.z=4,b.x=5,b.y=6,b.z=7,c.x=8,c.y=9,c.z=10,q=11-17")
            .unwrap();
    let seeds: Vec<Vec<u8>> = vec![
        spatial_analyzer(ds, Side::Left).into_bytes(),
        leica(ds, Side::Left),
        figaroh(ds, Side::Left).into_bytes(),
        joint_log(ds, Side::Left, None, true).into_bytes(),
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(22);
    let alphabet = b"0123456789.,;:_ -+eE'\"\t\r\n#/[]abcxyzXYZ\xB5\xB0\xFF";
    for round in 0..400 {
        let mut bytes = seeds[round % seeds.len()].clone();
        bytes.truncate(bytes.len().min(3000));
        for _ in 0..rng.random_range(1..8) {
            let k = rng.random_range(0..bytes.len().max(1));
            match rng.random_range(0..4) {
                0 if !bytes.is_empty() => {
                    let at = k.min(bytes.len() - 1);
                    bytes[at] = alphabet[rng.random_range(0..alphabet.len())];
                }
                1 => bytes.truncate(k),
                2 if k < bytes.len() => {
                    let tail = bytes[k..].to_vec();
                    bytes.extend(tail.into_iter().take(200));
                }
                _ => bytes.insert(
                    k.min(bytes.len()),
                    alphabet[rng.random_range(0..alphabet.len())],
                ),
            }
        }
        if round % 10 == 0 {
            bytes = (0..rng.random_range(0..300))
                .map(|_| rng.random())
                .collect();
        }
        let path = Path::new("damaged.csv");
        let Ok(text) = import::text::decode(path, &bytes) else {
            continue;
        };
        for format in [
            None,
            Some(PointsFormat::SpatialAnalyzer),
            Some(PointsFormat::Leica),
            Some(PointsFormat::Figaroh),
            Some(PointsFormat::Generic),
        ] {
            let o = ReadOptions {
                format,
                unit: None,
                decimal_comma: round % 3 == 0,
                columns: Some(&map),
                reflector_names: &names,
                joint_names: Some(&joint_names),
                angle_unit: AngleUnit::Deg,
            };
            let _ = read(path, &text, &o);
        }
        let order = YUMI_ABB_ORDER;
        let _ = joints::read(
            path,
            &text,
            &JointLogOptions {
                joint_order: (round % 2 == 0).then_some(&order[..]),
                joint_names: Some(&joint_names),
                id_prefix: "L",
                ..Default::default()
            },
        );
    }
}

/// A robot with a prismatic lift and a mimic joint (issue 19's test robot): figaroh's file gives the
/// lift in metres (the URDF's units) and the arm's joints by name (the mimic follower has no column);
/// a SpatialAnalyzer export with a joint log in degrees gives it in mm, or in metres with
/// `joint_length_unit`. Each imports into the dataset's own values (mm), which the native reader
/// loads back.
#[test]
fn a_prismatic_joint_imports_in_its_length_unit() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = write(dir.path(), "lift_mimic.urdf", robots::lift_mimic_urdf());
    let arms = PerSide::from_fn(|side| {
        let (base, tip) = robots::LIFT_MIMIC_ARMS[usize::from(side == Side::Right)];
        Some(dualcal::robot::ArmLinks::new(base, tip))
    });
    let robot = RobotDescription::load(
        &urdf,
        &dualcal::robot::LoadOptions {
            arms: arms.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    let sim = simulate_with_robot(&paper_options(3, 12, 8), &robot).unwrap();
    let ds = &sim.dataset;
    let joints = PerSide::from_fn(|s| robot.arm_joint_names(s));
    let linear = PerSide::from_fn(|s| robot.arm(s).linear_joints());
    assert_eq!(linear.left, [false, true, false, false, false, false]);
    assert_eq!(joints.left.len(), 6, "the mimic follower is not a column");
    let mut o = ImportOptions::new(
        ds.reflector_names.to_vec(),
        ds.nominal_reflectors_mm.clone(),
    );
    o.tracker = ds.tracker;
    o.joint_names = PerSide::from_fn(|s| Some(joints[s].clone()));
    o.linear_joints = linear.clone();
    o.robot = Some(urdf.clone());
    o.links = arms;
    // The same joint values, each in a unit: angles in `deg`/`rad`, the lift in `mm`/`m`.
    let value = |side: Side, k: usize, q: f64, metres: bool, radians: bool| -> String {
        match (linear[side][k], metres, radians) {
            (true, true, _) => num(q / 1000.0),
            (true, false, _) => num(q),
            (false, _, true) => num(q),
            (false, _, false) => num(q.to_degrees()),
        }
    };
    let close = |a: &Dataset, what: &str| {
        for side in Side::BOTH {
            for (m, n) in a
                .arm(side)
                .measurements
                .iter()
                .zip(&ds.arm(side).measurements)
            {
                for (k, (x, y)) in m.q_rad.iter().zip(&n.q_rad).enumerate() {
                    assert!(
                        (x - y).abs() < 1e-9,
                        "{what} {side} {} q{}: {x} vs {y}",
                        m.id,
                        k + 1
                    );
                }
            }
            assert_eq!(a.arm(side).linear_joints, linear[side], "{what}");
        }
    };
    // figaroh: metres and radians, columns by name (reversed).
    let figaroh_inputs = PerSide::from_fn(|side| {
        let mut cols: Vec<String> = (1..=ds.reflector_count())
            .flat_map(|k| [format!("x{k}"), format!("y{k}"), format!("z{k}")])
            .collect();
        cols.extend(joints[side].iter().rev().cloned());
        let mut text = cols.join(",") + "\n";
        for m in &ds.arm(side).measurements {
            let mut row: Vec<String> = m
                .tracker_points_mm
                .iter()
                .flat_map(|p| [num(p.x / 1000.0), num(p.y / 1000.0), num(p.z / 1000.0)])
                .collect();
            let n = m.q_rad.len();
            row.extend((0..n).rev().map(|k| value(side, k, m.q_rad[k], true, true)));
            text += &(row.join(",") + "\n");
        }
        ArmFiles {
            points: write(dir.path(), &format!("figaroh-{side}.csv"), text),
            joints: None,
        }
    });
    let imported = import::import(&OsFiles, &figaroh_inputs, &o).unwrap();
    close(&imported.dataset, "figaroh");
    // SpatialAnalyzer + a joint log in degrees, the lift in mm and then in metres.
    for metres in [false, true] {
        let inputs = PerSide::from_fn(|side| {
            let mut log = String::from("id");
            for k in 1..=joints[side].len() {
                log += &format!(",q{k}");
            }
            log += ",split\n";
            for m in &ds.arm(side).measurements {
                let q: Vec<String> = (0..m.q_rad.len())
                    .map(|k| value(side, k, m.q_rad[k], metres, false))
                    .collect();
                log += &format!("{},{},{}\n", m.id, q.join(","), m.split.name());
            }
            ArmFiles {
                points: write(
                    dir.path(),
                    &format!("sa-{side}.txt"),
                    spatial_analyzer(ds, side),
                ),
                joints: Some(write(dir.path(), &format!("log-{side}-{metres}.csv"), log)),
            }
        });
        let mut o = o.clone();
        o.joint_length_unit = metres.then_some(LengthUnit::M);
        let imported = import::import(&OsFiles, &inputs, &o).unwrap();
        close(
            &imported.dataset,
            if metres { "log in m" } else { "log in mm" },
        );
        if !metres {
            // Written and loaded back as a user's dataset: the lift's column is read as a length.
            let out = dir.path().join("imported-lift");
            import::write(&imported, &inputs, &out, Overwrite::Refuse).unwrap();
            let ws = dualcal::workspace::Workspace::load(&out, &Default::default()).unwrap();
            close(&ws.dataset, "written and loaded");
        }
    }
}

/// A float as numpy prints it in scientific notation (`9.665453830000000e-01`), with 16 significant
/// digits (numpy's default is 8; more here so that the simulated poses survive the text).
fn numpy_float(x: f64) -> String {
    let s = format!("{x:.15e}");
    let (mantissa, exponent) = s.split_once('e').unwrap();
    let e: i32 = exponent.parse().unwrap();
    format!("{mantissa}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
}

/// A vector as numpy prints it: `[ 1.0e+00 -2.0e+00 …]`, the elements right-aligned to one width
/// (a positive number gets the sign's space), lines wrapped at 75 characters with `wrap`.
fn numpy_vector(items: &[String], wrap: bool) -> String {
    let w = items.iter().map(String::len).max().unwrap_or(0);
    let mut out = String::from("[");
    let mut line = 1;
    for (k, item) in items.iter().enumerate() {
        if k > 0 {
            if wrap && line + 1 + w > 75 {
                out += "\n ";
                line = 1;
            } else {
                out.push(' ');
                line += 1;
            }
        }
        out += &format!("{item:>w$}");
        line += w;
    }
    out + "]"
}

/// Both hands of [`robots::coupled_torso_dh`] measured at one instant, with one marker each: per pose
/// the 19 joint values in DLR's order (torso 3, right arm 7, left arm 7, head 2) and the markers
/// (right hand first), as written to the file, with the true model of one reflector.
struct TogetherPoses {
    /// The nominal position of reflector `a` in the tip frame, mm.
    nominal_mm: nalgebra::Vector3<f64>,
    joints: Vec<Vec<f64>>,
    markers_m: Vec<[[f64; 3]; 2]>,
    truth: dualcal::kinematics::DualArmModel,
}

/// Simulate `n` poses of the robot: each simulated left row's torso made coupled (the passive joint
/// `−(tilt 1 + tilt 2)`) and given to the right row of the same index, both hands' marker (reflector
/// `a`) measured there (the true model, 20 µm noise).
fn together_poses(robot: &RobotDescription, seed: u64, n: usize) -> TogetherPoses {
    use nalgebra::Point3;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let sim = simulate_with_robot(&paper_options(seed, n, n / 2), robot).unwrap();
    let shared = sim.nominal.shared_joints();
    assert_eq!(shared.variables, [(0, 0), (1, 1), (2, 2), (3, 3)]);
    let mut truth = sim.truth.clone();
    for side in Side::BOTH {
        let arm = truth.arm_mut(side);
        arm.reflectors_mm.truncate(1);
        arm.reflector_names = vec!["a".to_string()].into();
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.02).unwrap();
    let mut poses = TogetherPoses {
        nominal_mm: sim.dataset.nominal_reflectors_mm[0],
        joints: Vec::new(),
        markers_m: Vec::new(),
        truth,
    };
    for (l, r) in sim
        .dataset
        .arms
        .left
        .measurements
        .iter()
        .zip(&sim.dataset.arms.right.measurements)
    {
        let mut ql = l.q_rad.clone();
        ql[3] = -(ql[1] + ql[2]);
        let qr = shared.right_with_left_values(&ql, &r.q_rad);
        let mut marker = |side: Side, q: &[f64]| {
            let p = poses.truth.arm(side).reflector_fk(q).points_mm[0];
            let t = sim.tracker_from_left_base * poses.truth.left_base_from(side);
            let p = t.transform_point(&Point3::from(p)).coords;
            [0, 1, 2].map(|k| (p[k] + noise.sample(&mut rng)) / 1000.0)
        };
        let markers = [marker(Side::Right, &qr), marker(Side::Left, &ql)];
        let mut j: Vec<f64> = ql[..3].to_vec();
        j.extend(&qr[4..]);
        j.extend(&ql[4..]);
        j.extend([0.0, 0.0]);
        poses.joints.push(j);
        poses.markers_m.push(markers);
    }
    poses
}

/// The poses in DLR's layout, as pandas writes a frame of numpy arrays: header `,joints,markers`, an
/// unnamed index column, the joints vector (every third row wrapped over lines, and so quoted), the
/// markers a quoted two-line matrix. Returns the file and the values as written (read back from
/// their text).
fn dlr_layout(poses: &TogetherPoses) -> (String, Vec<Vec<f64>>) {
    let mut text = String::from(",joints,markers\n");
    let mut written = Vec::new();
    for (i, (j, m)) in poses.joints.iter().zip(&poses.markers_m).enumerate() {
        let mut items: Vec<String> = j.iter().map(|&x| numpy_float(x)).collect();
        // The head's zeros as numpy prints them in fixed notation, in some rows.
        if i % 2 == 1 {
            items[17] = "0.".to_string();
            items[18] = "0.".to_string();
        }
        written.push(items.iter().map(|s| s.parse::<f64>().unwrap()).collect());
        let joints = numpy_vector(&items, i % 3 == 0);
        let joints = if joints.contains('\n') {
            format!("\"{joints}\"")
        } else {
            joints
        };
        let row = |p: &[f64; 3]| numpy_vector(&p.map(|x| format!("{x:?}")), false);
        text += &format!("{i},{joints},\"[{}\n {}]\"\n", row(&m[0]), row(&m[1]));
    }
    (text, written)
}

/// The imported dataset holds the values as written: the torso, the computed passive joint and the
/// arm's own seven joints; the marker of the arm's hand (right: row 0) in mm; the last `verify`
/// poses verification; one id per pose on both arms, measured together.
fn assert_imported_as_written(
    ds: &Dataset,
    poses: &TogetherPoses,
    written: &[Vec<f64>],
    verify: usize,
) {
    assert!(ds.measured_together);
    let n = written.len();
    for side in Side::BOTH {
        let (arm_cols, row) = if side == Side::Right { (3, 0) } else { (10, 1) };
        let ms = &ds.arm(side).measurements;
        assert_eq!(ms.len(), n, "{side}");
        for (i, m) in ms.iter().enumerate() {
            let w = &written[i];
            let mut want: Vec<f64> = w[..3].to_vec();
            want.push(-w[1] - w[2]);
            want.extend(&w[arm_cols..arm_cols + 7]);
            assert_eq!(m.q_rad.len(), 11);
            for (k, (got, want)) in m.q_rad.iter().zip(&want).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-9,
                    "{side} {i} q{}: {got} vs {want}",
                    k + 1
                );
            }
            let p = poses.markers_m[i][row].map(|x| x * 1000.0);
            assert!((m.tracker_points_mm[0] - nalgebra::Vector3::from(p)).amax() <= 1e-9);
            assert_eq!(m.id, i.to_string());
            let ver = i >= n - verify;
            assert_eq!(
                m.split,
                if ver { Split::Ver } else { Split::Cal },
                "{side} {i}"
            );
        }
    }
}

const DLR_LEFT: &str = "id=1,q=joints[0-2],q=-joints[1]-joints[2],q=joints[10-16],\
                        a.x=markers[1][0],a.y=markers[1][1],a.z=markers[1][2]";
const DLR_RIGHT: &str = "id=1,q=joints[0-2],q=-joints[1]-joints[2],q=joints[3-9],\
                         a.x=markers[0][0],a.y=markers[0][1],a.z=markers[0][2]";

/// DLR's Agile Justin file layout (issue 20) — numpy vectors and a quoted two-line markers matrix per
/// row, both hands measured at one instant — written here from a simulated Justin-like robot (a DH
/// file with a torso whose fourth joint is passive, `−(tilt 1 + tilt 2)`), imported by `dualcal
/// import` with per-arm mappings, `--measured-together` and `--verify-last`, loaded as a workspace
/// and calibrated: the imported values are the written ones, the calibration reaches the truth's
/// accuracy. A mapping whose torso disagrees between the arms, and a `--verify-last` that leaves
/// nothing to calibrate with, are refused.
#[test]
fn a_numpy_printed_file_of_both_hands_imports_and_calibrates() {
    let dir = tempfile::tempdir().unwrap();
    let robot_path = write(
        dir.path(),
        "justin-like.dh.toml",
        robots::coupled_torso_dh(),
    );
    let robot = RobotDescription::load(&robot_path, &Default::default()).unwrap();
    let (n, verify) = (300, 100);
    let poses = together_poses(&robot, 41, n);
    let (text, written) = dlr_layout(&poses);
    assert!(text.lines().count() > 2 * n, "quoted cells span lines");
    let file = write(dir.path(), "measurements.csv", &text);
    let out = dir.path().join("imported");
    let a = poses.nominal_mm;
    let reflector = format!("a={},{},{}", a.x, a.y, a.z);
    let args = |left: &str, right: &str, verify: usize, out: &Path| -> Vec<String> {
        let f = file.to_str().unwrap();
        [
            "import",
            "--robot",
            robot_path.to_str().unwrap(),
            "--left-points",
            f,
            "--right-points",
            f,
            "--left-columns",
            left,
            "--right-columns",
            right,
            "--length-unit",
            "m",
            "--angle-unit",
            "rad",
            "--reflector",
            &reflector,
            "--measured-together",
            "--verify-last",
            &verify.to_string(),
            "--out",
            out.to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |a: Vec<String>| dualcal(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(args(DLR_LEFT, DLR_RIGHT, verify, &out));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.contains(&format!("{n} configurations matched")),
        "{stdout}"
    );

    let ws = dualcal::workspace::Workspace::load(&out, &Default::default()).unwrap();
    assert!(ws.refusals().is_empty(), "{:?}", ws.refusals());
    let ds = &ws.dataset;
    assert_imported_as_written(ds, &poses, &written, verify);

    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(ds, &ws.nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.warnings());
    let at = |m: &dualcal::kinematics::DualArmModel| {
        dualcal::metrics::evaluate(ds, m, Split::Ver).unwrap()
    };
    let (nominal, truth, calibrated) = (at(&ws.nominal), at(&poses.truth), at(&result.calibrated));
    common::assert_near_truth("justin-like", &nominal, &truth, &calibrated);

    // The right arm's torso taken from other elements: the rows of one pose disagree, refused
    // naming the file, the line and the column.
    let wrong = DLR_RIGHT.replace("q=joints[0-2]", "q=joints[0],q=joints[2],q=joints[1]");
    let o = run(args(DLR_LEFT, &wrong, verify, &dir.path().join("wrong")));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("measurements.csv:2: field `q2`") && err.contains("measured_together"),
        "{err}"
    );
    // Nothing left to calibrate with.
    let o = run(args(DLR_LEFT, DLR_RIGHT, n, &dir.path().join("all-ver")));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains(&format!(
            "--verify-last {n}: the left arm has {n} configurations"
        )),
        "{err}"
    );
}

/// Both arms in one plain table of another layout — `;`-separated with decimal commas, a pose per
/// row, each arm's joints and reflectors in columns named its own way — imported with per-arm
/// mappings (columns by name and by number, a `q=` range and single joints appended): the native
/// dataset's measurements, and its calibration.
#[test]
fn a_plain_table_of_both_arms_imports_with_per_arm_mappings() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(12);
    let native = native(&sim, dir.path(), Units::MM_DEG);
    let ds = &sim.dataset;
    let names = &ds.reflector_names;
    let comma = |x: f64| num(x).replace('.', ",");
    let mut header = vec!["Nr".to_string(), "Zeit".to_string()];
    for side in ["L", "R"] {
        header.extend((1..=7).map(|k| format!("J{k} {side}")));
    }
    for side in ["L", "R"] {
        for n in names.iter() {
            header.extend(["X", "Y", "Z"].map(|a| format!("{side} {n}{a} [mm]")));
        }
    }
    header.push("Split".into());
    let mut text = header.join(";") + "\n";
    let (left, right) = (&ds.arms.left.measurements, &ds.arms.right.measurements);
    for (k, (l, r)) in left.iter().zip(right).enumerate() {
        assert_eq!(l.split, r.split);
        let mut row = vec![format!("P{k}"), format!("{k},5")];
        row.extend(
            l.q_rad
                .iter()
                .chain(&r.q_rad)
                .map(|q| comma(q.to_degrees())),
        );
        for m in [l, r] {
            row.extend(
                m.tracker_points_mm
                    .iter()
                    .flat_map(|p| [p.x, p.y, p.z])
                    .map(comma),
            );
        }
        row.push(l.split.name().to_string());
        text += &(row.join(";") + "\n");
    }
    let file = write(dir.path(), "poses.txt", &text);
    // Left: joints by a range of column numbers; right: by name, one at a time, then a range.
    let reflectors = |side: &str| -> String {
        names
            .iter()
            .flat_map(|n| {
                // The header's names without their bracketed units.
                ["x", "y", "z"].map(|a| format!("{n}.{a}={side} {n}{}", a.to_uppercase()))
            })
            .collect::<Vec<_>>()
            .join(",")
    };
    let left_map = format!("id=Nr,q=3-9,{},split=Split", reflectors("L"));
    let right_map = format!(
        "id=1,q=J1 R,q=J2 R,q=12-16,{},split=${}",
        reflectors("R"),
        header.len()
    );
    let out = dir.path().join("imported");
    let f = file.to_str().unwrap();
    let mut args = vec![
        "import",
        "--left-points",
        f,
        "--right-points",
        f,
        "--left-columns",
        &left_map,
        "--right-columns",
        &right_map,
        "--angle-unit",
        "deg",
        "--out",
        out.to_str().unwrap(),
    ];
    let refl: Vec<String> = names
        .iter()
        .zip(&ds.nominal_reflectors_mm)
        .map(|(n, p)| format!("{n}={},{},{}", p.x, p.y, p.z))
        .collect();
    for r in &refl {
        args.extend(["--reflector", r]);
    }
    let o = dualcal(&args);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let back = dataset::load(&out).unwrap();
    assert!(!back.measured_together);
    assert_eq!(back.arms.right.measurements[3].id, "P3");
    assert_same_measurements(&native, &back, false, true);
    assert_same_calibration(&native, &back, Split::Cal);
}

/// A small file in DLR's layout with records on lines 2, 4, 6, 8 (each two lines long, the
/// markers a quoted matrix); `bad_joints`, `bad_markers` replace record 2's (line 6) cells, `tail`
/// follows.
fn small_dlr_file(bad_joints: Option<&str>, bad_markers: Option<&str>, tail: &str) -> String {
    let vector = |i: usize| -> String {
        let v: Vec<String> = (0..19)
            .map(|k| format!("{}", i as f64 + k as f64 / 10.0))
            .collect();
        format!("[{}]", v.join(" "))
    };
    let markers = |i: usize| format!("\"[[{i}.1 {i}.2 {i}.3]\n [{i}.4 {i}.5 {i}.6]]\"");
    let mut text = String::from(",joints,markers\n");
    for i in 0..4 {
        let (j, m) = if i == 2 {
            (
                bad_joints.map_or_else(|| vector(i), String::from),
                bad_markers.map_or_else(|| markers(i), String::from),
            )
        } else {
            (vector(i), markers(i))
        };
        text += &format!("{i},{j},{m}\n");
    }
    text + tail
}

/// The malformed-cell cases: (file, mapping, line, column, what the message says).
fn malformed_cell_cases() -> Vec<(String, String, usize, &'static str, &'static str)> {
    let file = small_dlr_file;
    let good = DLR_LEFT.replace("q=joints[0-2],q=-joints[1]-joints[2],", "");
    vec![
        (
            file(Some("[0.5 1.5 2.5"), None, ""),
            good.clone(),
            6,
            "joints",
            "`[` not closed",
        ),
        (
            file(None, Some("\"[[1 2 3]\n [4 5]]\""), ""),
            good.clone(),
            6,
            "markers",
            "row 1 has 2 values, row 0 has 3",
        ),
        (
            file(Some("[1 2 x 4]"), None, ""),
            good.clone(),
            6,
            "joints",
            "element 2 `x` is not a finite number",
        ),
        (
            file(Some("0.5"), None, ""),
            good.clone(),
            6,
            "joints",
            "an element reference on a plain cell `0.5`",
        ),
        (
            file(None, None, ""),
            good.replace("joints[10-16]", "joints[10-19]"),
            2,
            "joints",
            "joints[19] (for q10): index [19] is beyond the vector's 19 values (indices 0…18)",
        ),
        (
            file(None, None, ""),
            good.replace("markers[1][0]", "markers[1]"),
            2,
            "markers",
            "[1] is a row; write [1][j]",
        ),
        (
            file(None, None, ""),
            good.replace("markers[1][2]", "markers[2][2]"),
            2,
            "markers",
            "row index [2] is beyond the matrix's 2 rows",
        ),
        (
            file(None, None, ""),
            good.replace("q=joints[10-16]", "q=joints"),
            2,
            "joints",
            "is a vector or matrix cell: map one of its elements for q1, e.g. joints[0]",
        ),
        (
            file(None, None, "4,[1 2],\"[[1 2 3]\n [4 5 6]]\n"),
            good.clone(),
            10,
            "markers",
            "a quote (`\"`) opened in this record is not closed",
        ),
    ]
}

/// Malformed vector and matrix cells, and element references that do not fit the cells, are refused
/// naming the file, the record's first line (records span lines: a quoted matrix has two) and the
/// column, and saying what is wrong.
#[test]
fn malformed_vector_and_matrix_cells_are_refused_with_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let good = DLR_LEFT.replace("q=joints[0-2],q=-joints[1]-joints[2],", "");
    let cases = malformed_cell_cases();
    for (k, (text, mapping, line, column, what)) in cases.into_iter().enumerate() {
        let path = write(dir.path(), &format!("measurements-{k}.csv"), &text);
        let inputs = PerSide::from_fn(|_| ArmFiles {
            points: path.clone(),
            joints: None,
        });
        let mut o = ImportOptions::new(
            vec!["a".into()],
            vec![nalgebra::Vector3::new(45.0, 0.0, 40.0)],
        );
        o.arm_columns = PerSide::from_fn(|_| Some(ColumnMap::parse(&mapping).unwrap()));
        o.length_unit = Some(dualcal::import::PointUnit::M);
        o.angle_unit = Some(AngleUnit::Rad);
        let err = import::import(&OsFiles, &inputs, &o).unwrap_err();
        let msg = err.to_string();
        eprintln!("{msg}");
        let at = format!("measurements-{k}.csv:{line}: column `{column}`: ");
        assert!(msg.contains(&at) && msg.contains(what), "case {k}: {msg}");
        assert_eq!(
            (err.line(), err.field()),
            (Some(line), Some(column)),
            "case {k}"
        );
        assert!(matches!(err, ImportError::Cell { .. }), "case {k}");
    }
    // The same file, well formed: every record read, at its first line.
    let path = write(
        dir.path(),
        "measurements.csv",
        small_dlr_file(None, None, ""),
    );
    let map = ColumnMap::parse(&good).unwrap();
    let names = vec!["a".to_string()];
    let o = dualcal::import::points::ReadOptions {
        format: None,
        unit: Some(dualcal::import::PointUnit::M),
        decimal_comma: false,
        columns: Some(&map),
        reflector_names: &names,
        joint_names: None,
        angle_unit: AngleUnit::Rad,
    };
    let read =
        dualcal::import::points::read(&path, &std::fs::read_to_string(&path).unwrap(), &o).unwrap();
    let dualcal::import::PointTable::Rows(rows) = read.table else {
        panic!("points")
    };
    assert_eq!(
        rows.iter().map(|r| r.line).collect::<Vec<_>>(),
        [2, 4, 6, 8]
    );
    assert_eq!(rows[2].q_rad.as_ref().unwrap()[0], 2.0 + 1.0);
    assert!((rows[3].points_mm[0] - nalgebra::Vector3::new(3400.0, 3500.0, 3600.0)).amax() < 1e-9);
}
