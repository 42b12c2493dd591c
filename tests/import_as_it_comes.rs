//! `dualcal import` on files as they come (issue 45): a Leica Tracker Pilot export exactly as it
//! writes them (Windows-1252, its full header, no point names — the reflector's type and serial in
//! `Target` on every row —, a `Delete` column, rows ending with an empty field) of one SMR, with the
//! controller's joint values as a spreadsheet `j1 … j6` in degrees, one row per point in measurement
//! order: one arm alone, matched by order (the report says why), a repeated shot averaged, a deleted
//! row dropped and listed, U(95) summed up; counts that disagree refused with where the sequences part;
//! bad cells refused with file, row and field. Every file is written here (the .xlsx by a minimal
//! writer below); no third-party files.

#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Dataset};
use dualcal::import::{self, ArmFiles, ImportError, ImportOptions, Imported, MatchRule};
use dualcal::output::Overwrite;
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::source::OsFiles;
use nalgebra::Vector3;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Tracker Pilot's header, as it writes it.
const TRACKER_PILOT_HEADER: &str = "X  [mm],Y  [mm],Z  [mm],U(95)  [mm],U(95) X  [mm],U(95) Y  [mm],\
     U(95) Z  [mm],Tilt  [deg],Q0 ,Q1 ,Q2 ,Q3 ,Image RMS  [µm],Target,Temperature  [°C],\
     Pressure  [mBar],Humidity  [%],Time Stamp,OTG Applied,Delete";

/// The reflector's type and serial, on every row of the export.
const SMR: &str = "TMC 30-B #5320";

/// One row of the export.
#[derive(Clone)]
struct Shot {
    position_mm: Vector3<f64>,
    /// Seconds after the first shot.
    time_s: usize,
    u95_mm: f64,
    deleted: bool,
}

/// A number as the dataset writer writes it (shortest text that reads back exactly).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// A Tracker Pilot time stamp `t` seconds after 15:06:00.
fn stamp(t: usize) -> String {
    let t = 15 * 3600 + 6 * 60 + t;
    format!(
        "'11.10.2022 {:02}:{:02}:{:02}.043",
        t / 3600,
        t / 60 % 60,
        t % 60
    )
}

/// The export's bytes (Windows-1252, CRLF) and each shot's line.
fn tracker_pilot(shots: &[Shot]) -> (Vec<u8>, Vec<usize>) {
    let mut s = format!("{TRACKER_PILOT_HEADER}\r\n");
    let mut lines = Vec::new();
    for (k, shot) in shots.iter().enumerate() {
        let p = shot.position_mm;
        s += &format!(
            "{},{},{},{},{},{},{},0.0123,0.5,0.5,0.5,0.5,1.7,{SMR},20.4,1012.8,41.0,{},False,{},\r\n",
            num(p.x),
            num(p.y),
            num(p.z),
            num(shot.u95_mm),
            num(shot.u95_mm / 2.0),
            num(shot.u95_mm / 3.0),
            num(shot.u95_mm / 4.0),
            stamp(shot.time_s),
            if shot.deleted { "True" } else { "False" }
        );
        lines.push(k + 2);
    }
    let bytes = s
        .chars()
        .map(|c| match c {
            'µ' => 0xB5,
            '°' => 0xB0,
            c if c.is_ascii() => c as u8,
            c => panic!("{c} is not in the test's Windows-1252 table"),
        })
        .collect();
    (bytes, lines)
}

/// A cell of a sheet.
enum Cell {
    Num(f64),
    Text(String),
}

/// A minimal .xlsx (the parts a reader needs: content types, relationships, the workbook and its
/// worksheets with inline strings) of sheets (name, rows).
fn xlsx(sheets: &[(&str, Vec<Vec<Cell>>)]) -> Vec<u8> {
    const MAIN: &str = "http://schemas.openxmlformats.org/spreadsheetml/2006/main";
    const REL: &str = "http://schemas.openxmlformats.org/officeDocument/2006/relationships";
    const PKG: &str = "http://schemas.openxmlformats.org/package/2006/relationships";
    let mut types = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\
         <Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">\
         <Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>\
         <Default Extension=\"xml\" ContentType=\"application/xml\"/>\
         <Override PartName=\"/xl/workbook.xml\" ContentType=\"application/vnd.openxmlformats-officedocument.spreadsheetml.sheet.main+xml\"/>",
    );
    let mut book = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?><workbook xmlns=\"{MAIN}\" xmlns:r=\"{REL}\"><sheets>"
    );
    let mut rels =
        format!("<?xml version=\"1.0\" encoding=\"UTF-8\"?><Relationships xmlns=\"{PKG}\">");
    let mut parts = Vec::new();
    for (k, (name, rows)) in sheets.iter().enumerate() {
        let n = k + 1;
        types += &format!(
            "<Override PartName=\"/xl/worksheets/sheet{n}.xml\" \
             ContentType=\"application/vnd.openxmlformats-officedocument.spreadsheetml.worksheet+xml\"/>"
        );
        book += &format!("<sheet name=\"{name}\" sheetId=\"{n}\" r:id=\"rId{n}\"/>");
        rels += &format!(
            "<Relationship Id=\"rId{n}\" Type=\"{REL}/worksheet\" Target=\"worksheets/sheet{n}.xml\"/>"
        );
        let mut sheet = format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?><worksheet xmlns=\"{MAIN}\"><sheetData>"
        );
        for (r, row) in rows.iter().enumerate() {
            sheet += &format!("<row r=\"{}\">", r + 1);
            for (c, cell) in row.iter().enumerate() {
                let at = format!("{}{}", char::from(b'A' + c as u8), r + 1);
                sheet += &match cell {
                    Cell::Num(v) => format!("<c r=\"{at}\"><v>{}</v></c>", num(*v)),
                    Cell::Text(t) => {
                        format!("<c r=\"{at}\" t=\"inlineStr\"><is><t>{t}</t></is></c>")
                    }
                };
            }
            sheet += "</row>";
        }
        sheet += "</sheetData></worksheet>";
        parts.push((format!("xl/worksheets/sheet{n}.xml"), sheet));
    }
    types += "</Types>";
    book += "</sheets></workbook>";
    rels += "</Relationships>";
    parts.push(("[Content_Types].xml".into(), types));
    parts.push((
        "_rels/.rels".into(),
        format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?><Relationships xmlns=\"{PKG}\">\
             <Relationship Id=\"rId1\" Type=\"{REL}/officeDocument\" Target=\"xl/workbook.xml\"/>\
             </Relationships>"
        ),
    ));
    parts.push(("xl/workbook.xml".into(), book));
    parts.push(("xl/_rels/workbook.xml.rels".into(), rels));
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, text) in parts {
        zip.start_file(name, options).unwrap();
        zip.write_all(text.as_bytes()).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// The joint sheet: `j1 … jN` (no unit: degrees), one row per configuration.
fn joint_rows(ds: &Dataset, side: Side) -> Vec<Vec<Cell>> {
    let n = ds.arm(side).joint_count();
    let mut rows = vec![(1..=n).map(|k| Cell::Text(format!("j{k}"))).collect()];
    for m in &ds.arm(side).measurements {
        rows.push(m.q_rad.iter().map(|q| Cell::Num(q.to_degrees())).collect());
    }
    rows
}

/// The single 6-axis arm (a UR5-like robot on a stand, no second arm): its URDF in `dir`, the robot
/// and 40 simulated configurations of one SMR (reflector `a`).
fn six_axis_arm(dir: &Path) -> (PathBuf, RobotDescription, Dataset) {
    let urdf = dir.join("arm.urdf");
    std::fs::write(&urdf, robots::single_ur_like_urdf()).unwrap();
    let (base, tip) = robots::SINGLE_UR_ARM;
    let links = ArmLinks::new(base, tip);
    let robot = RobotDescription::load(
        urdf.as_path(),
        &LoadOptions {
            arms: PerSide::new(Some(links.clone()), Some(links)),
            ..Default::default()
        },
    )
    .unwrap();
    let ds = one_smr(
        simulate_with_robot(&paper_options(45, 40, 30), &robot)
            .unwrap()
            .dataset,
    );
    (urdf, robot, ds)
}

/// A dataset's first reflector alone (one SMR).
fn one_smr(mut ds: Dataset) -> Dataset {
    ds.reflector_names = vec!["a".to_string()].into();
    ds.nominal_reflectors_mm.truncate(1);
    for side in Side::BOTH {
        for m in &mut ds.arms[side].measurements {
            m.tracker_points_mm.truncate(1);
        }
    }
    ds
}

/// The left arm's shots: configuration i at 10 i s, U(95) growing with i.
fn shots(ds: &Dataset) -> Vec<Shot> {
    ds.arm(Side::Left)
        .measurements
        .iter()
        .enumerate()
        .map(|(i, m)| Shot {
            position_mm: m.tracker_points_mm[0],
            time_s: 10 * i,
            u95_mm: 0.010 + 0.0002 * i as f64,
            deleted: false,
        })
        .collect()
}

/// The shots of the export: a mis-shot marked deleted after configuration 9, configuration
/// 20 shot twice (±δ about its point).
fn shots_as_measured(ds: &Dataset) -> Vec<Shot> {
    let mut s = shots(ds);
    let delta = Vector3::new(0.004, -0.003, 0.002);
    let twice = s[20].clone();
    s[20].position_mm += delta;
    s.insert(
        21,
        Shot {
            position_mm: twice.position_mm - delta,
            time_s: twice.time_s + 2,
            ..twice
        },
    );
    let wrong = Shot {
        position_mm: s[9].position_mm + Vector3::new(50.0, 0.0, 0.0),
        time_s: s[9].time_s + 3,
        u95_mm: 0.5,
        deleted: true,
    };
    s.insert(10, wrong);
    s
}

fn options(robot: &RobotDescription, urdf: &Path, ds: &Dataset) -> ImportOptions {
    ImportOptions::for_robot(
        robot,
        Some(urdf),
        vec!["a".to_string()],
        ds.nominal_reflectors_mm.clone(),
    )
}

fn left_only(points: PathBuf, joints: PathBuf) -> PerSide<Option<ArmFiles>> {
    PerSide::new(
        Some(ArmFiles {
            points,
            joints: Some(joints),
        }),
        None,
    )
}

fn has_note(imported: &Imported, text: &str) -> bool {
    let arm = imported.report.arms.left.as_ref().unwrap();
    arm.notes.iter().any(|n| n.contains(text))
}

#[test]
fn a_tracker_pilot_export_and_a_joint_sheet_import_one_arm_by_order() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let shots = shots_as_measured(&ds);
    let (bytes, lines) = tracker_pilot(&shots);
    assert!(std::str::from_utf8(&bytes).is_err());
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, &bytes).unwrap();
    let joints = dir.path().join("joints.xlsx");
    let notes = vec![vec![Cell::Text("robot 1".into())]];
    std::fs::write(
        &joints,
        xlsx(&[("Joints", joint_rows(&ds, Side::Left)), ("Notes", notes)]),
    )
    .unwrap();
    let o = options(&robot, &urdf, &ds);
    let imported = import::import_arms(&OsFiles, &left_only(points.clone(), joints), &o).unwrap();
    assert!(imported.report.arms.right.is_none());
    let report = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(report.matched, 40, "{}", imported.report);
    assert!(report.unmatched_points.is_empty() && report.unmatched_configurations.is_empty());
    // The rule and why; what was guessed.
    for text in [
        "matching: by file order",
        &format!("one name, `{SMR}`, on every row"),
        "the joint log has no time stamps",
        "is not UTF-8: read as Windows-1252",
        "separator: `,`",
        "sheet: `Joints`, the first of 2",
        "no angle unit given or in the header: read as degrees",
    ] {
        assert!(has_note(&imported, text), "{text}: {}", imported.report);
    }
    // The deleted row dropped and listed; U(95) summed up over the rows kept.
    let deleted = shots.iter().position(|s| s.deleted).unwrap();
    assert!(
        has_note(&imported, &format!("(line {})", lines[deleted])),
        "{}",
        imported.report
    );
    let kept: Vec<(f64, usize)> = shots
        .iter()
        .zip(&lines)
        .filter(|(s, _)| !s.deleted)
        .map(|(s, &l)| (s.u95_mm, l))
        .collect();
    let (largest, line) = kept
        .iter()
        .copied()
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    let u95 = format!(
        "U(95) of the {} points: largest {largest:.4} mm (line {line})",
        kept.len()
    );
    assert!(has_note(&imported, &u95), "{u95}: {}", imported.report);
    // The repeated shot averaged; every configuration's joints and point as simulated.
    assert_eq!(report.repeated.len(), 1, "{}", imported.report);
    assert_eq!(report.repeated[0].shots, 2);
    let twice: Vec<usize> = (0..shots.len())
        .filter(|&k| !shots[k].deleted && shots[k].time_s / 10 == 20)
        .map(|k| lines[k])
        .collect();
    assert_eq!(report.repeated[0].lines, twice);
    let got = &imported.dataset.arms.left.measurements;
    for (m, truth) in got.iter().zip(&ds.arms.left.measurements) {
        assert!((m.tracker_points_mm[0] - truth.tracker_points_mm[0]).amax() < 1e-9);
        for (a, b) in m.q_rad.iter().zip(&truth.q_rad) {
            assert!((a - b).abs() < 1e-12, "{} {a} {b}", m.id);
        }
    }
    // Written as the dataset's one-arm form.
    let out = dir.path().join("dataset");
    let inputs = left_only(points, dir.path().join("joints.xlsx"));
    import::write_arms(&imported, &inputs, &out, Overwrite::Refuse).unwrap();
    let back = dataset::load(&out).unwrap();
    assert_eq!(back.measured_sides(), vec![Side::Left]);
    assert!(!out.join("right.csv").exists());
    let text = std::fs::read_to_string(out.join(import::REPORT_FILE)).unwrap();
    assert!(text.contains("right arm: not imported"), "{text}");
    assert!(text.contains("matching: by file order"), "{text}");
}

#[test]
fn a_skipped_configuration_is_refused_naming_both_counts_and_where_they_part() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let mut shots = shots(&ds);
    let skipped = 17;
    shots.remove(skipped);
    let (bytes, lines) = tracker_pilot(&shots);
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, bytes).unwrap();
    let joints = dir.path().join("joints.xlsx");
    std::fs::write(&joints, xlsx(&[("Sheet1", joint_rows(&ds, Side::Left))])).unwrap();
    let o = options(&robot, &urdf, &ds);
    let err = import::import_arms(&OsFiles, &left_only(points.clone(), joints.clone()), &o)
        .unwrap_err()
        .to_string();
    let n = ds.arms.left.measurements.len();
    for text in [
        &format!("{} shots", n - 1),
        &format!("{n} configurations × 1 reflector = {n}"),
        &format!(
            "the shots part at line {}: 20.0 s after the configuration before (line {})",
            lines[skipped],
            lines[skipped - 1]
        ),
        "--match order",
        &points.display().to_string(),
        &joints.display().to_string(),
    ] {
        assert!(err.contains(text), "{text}: {err}");
    }
    // Forced by name: nothing matches, and the report says what to do.
    let mut by_name = o.clone();
    by_name.matching = MatchRule::Name;
    let imported = import::import_arms(&OsFiles, &left_only(points, joints), &by_name).unwrap();
    assert_eq!(imported.report.arms.left.as_ref().unwrap().matched, 0);
    assert!(has_note(&imported, "--match order"), "{}", imported.report);
}

#[test]
fn time_stamps_in_both_files_match_by_time() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let shots = shots_as_measured(&ds);
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, tracker_pilot(&shots).0).unwrap();
    // The controller's log with its own time stamps (1 s before each shot).
    let mut log = String::from("j1,j2,j3,j4,j5,j6,time\n");
    for (i, m) in ds.arms.left.measurements.iter().enumerate() {
        let q: Vec<String> = m.q_rad.iter().map(|q| num(q.to_degrees())).collect();
        log += &format!("{},{}\n", q.join(","), &stamp(10 * i + 1)[1..]);
    }
    let joints = dir.path().join("joints.csv");
    std::fs::write(&joints, log).unwrap();
    let mut o = options(&robot, &urdf, &ds);
    o.time_tolerance_s = 3.5;
    let imported = import::import_arms(&OsFiles, &left_only(points, joints), &o).unwrap();
    let report = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(
        report.matched,
        ds.arms.left.measurements.len(),
        "{}",
        imported.report
    );
    assert!(
        has_note(&imported, "matching: by time stamp"),
        "{}",
        imported.report
    );
    assert!(has_note(&imported, "both files have time stamps"));
    assert_eq!(report.repeated.len(), 1, "{}", imported.report);
}

#[test]
fn bad_cells_and_rows_are_refused_with_file_row_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let o = options(&robot, &urdf, &ds);
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, tracker_pilot(&shots(&ds)).0).unwrap();
    // A text cell in a joint column: the sheet's row and the column.
    let mut rows = joint_rows(&ds, Side::Left);
    rows[5][2] = Cell::Text("n/a".into());
    let joints = dir.path().join("joints.xlsx");
    std::fs::write(&joints, xlsx(&[("Joints", rows)])).unwrap();
    let err =
        import::import_arms(&OsFiles, &left_only(points.clone(), joints.clone()), &o).unwrap_err();
    assert!(matches!(err, ImportError::Field { .. }), "{err}");
    assert_eq!(err.path(), Some(joints.as_path()));
    assert_eq!(err.line(), Some(6));
    assert_eq!(err.field(), Some("j3"));
    assert!(err.to_string().contains("`n/a`"), "{err}");
    // A sheet that is not there: the sheets it has.
    let mut named = o.clone();
    named.sheet = Some("Robot".into());
    let err = import::import_arms(&OsFiles, &left_only(points.clone(), joints), &named)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no sheet `Robot`; its sheets: Joints"),
        "{err}"
    );
    // A `Delete` field that is neither: its line and the column.
    let (bytes, lines) = tracker_pilot(&shots(&ds));
    let text: String = bytes.iter().map(|&b| char::from(b)).collect();
    let bad: String = text
        .split_inclusive("\r\n")
        .enumerate()
        .map(|(k, l)| {
            if k + 1 == lines[7] {
                l.replace("False,\r\n", "maybe,\r\n")
            } else {
                l.to_string()
            }
        })
        .collect();
    let bad_bytes: Vec<u8> = bad.chars().map(|c| c as u32 as u8).collect();
    std::fs::write(&points, bad_bytes).unwrap();
    let csv = dir.path().join("joints.csv");
    std::fs::write(&csv, "j1,j2,j3,j4,j5,j6\n1,2,3,4,5,6\n").unwrap();
    let err = import::import_arms(&OsFiles, &left_only(points.clone(), csv), &o).unwrap_err();
    assert_eq!(err.line(), Some(lines[7]), "{err}");
    assert_eq!(err.field(), Some("Delete"), "{err}");
    assert_eq!(err.path(), Some(points.as_path()));
}

#[test]
fn the_command_line_imports_one_arm_of_the_yumi_from_a_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotDescription::builtin_irb14000();
    let ds = one_smr(
        simulate_with_robot(&paper_options(46, 40, 30), &robot)
            .unwrap()
            .dataset,
    );
    let points = dir.path().join("right.csv");
    let mut shots = shots(&ds);
    for (s, m) in shots.iter_mut().zip(&ds.arms.right.measurements) {
        s.position_mm = m.tracker_points_mm[0];
    }
    std::fs::write(&points, tracker_pilot(&shots).0).unwrap();
    let joints = dir.path().join("right.xlsx");
    std::fs::write(&joints, xlsx(&[("Joints", joint_rows(&ds, Side::Right))])).unwrap();
    let a = ds.nominal_reflectors_mm[0];
    let out = dir.path().join("dataset");
    let run = Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .arg("import")
        .arg("--right-points")
        .arg(&points)
        .arg("--right-joints")
        .arg(&joints)
        .arg("--reflector")
        .arg(format!("a={},{},{}", a.x, a.y, a.z))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("40 configurations of the right arm alone"),
        "{stdout}"
    );
    assert!(stdout.contains("matching: by file order"), "{stdout}");
    let back = dataset::load(&out).unwrap();
    assert_eq!(back.measured_sides(), vec![Side::Right]);
    let manifest = std::fs::read_to_string(out.join("dataset.toml")).unwrap();
    assert_eq!(manifest.matches("[[arms]]").count(), 1, "{manifest}");
    // Neither arm's files: refused, naming what to give.
    let run = Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(["import", "--out"])
        .arg(dir.path().join("none"))
        .output()
        .unwrap();
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("give one arm's point file"), "{stderr}");
}
