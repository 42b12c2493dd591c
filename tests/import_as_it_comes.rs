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

/// A minimal .ods (the mimetype, the manifest and content.xml) of sheets (name, rows).
fn ods(sheets: &[(&str, Vec<Vec<Cell>>)]) -> Vec<u8> {
    let mut content = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?><office:document-content \
         xmlns:office=\"urn:oasis:names:tc:opendocument:xmlns:office:1.0\" \
         xmlns:table=\"urn:oasis:names:tc:opendocument:xmlns:table:1.0\" \
         xmlns:text=\"urn:oasis:names:tc:opendocument:xmlns:text:1.0\" office:version=\"1.2\">\
         <office:body><office:spreadsheet>",
    );
    for (name, rows) in sheets {
        content += &format!("<table:table table:name=\"{name}\">");
        for row in rows {
            content += "<table:table-row>";
            for cell in row {
                content += &match cell {
                    Cell::Num(v) => format!(
                        "<table:table-cell office:value-type=\"float\" office:value=\"{}\">\
                         <text:p>{}</text:p></table:table-cell>",
                        num(*v),
                        num(*v)
                    ),
                    Cell::Text(t) => format!(
                        "<table:table-cell office:value-type=\"string\"><text:p>{t}</text:p>\
                         </table:table-cell>"
                    ),
                };
            }
            content += "</table:table-row>";
        }
        content += "</table:table>";
    }
    content += "</office:spreadsheet></office:body></office:document-content>";
    let manifest = "<?xml version=\"1.0\" encoding=\"UTF-8\"?><manifest:manifest \
         xmlns:manifest=\"urn:oasis:names:tc:opendocument:xmlns:manifest:1.0\" manifest:version=\"1.2\">\
         <manifest:file-entry manifest:full-path=\"/\" \
         manifest:media-type=\"application/vnd.oasis.opendocument.spreadsheet\"/>\
         <manifest:file-entry manifest:full-path=\"content.xml\" manifest:media-type=\"text/xml\"/>\
         </manifest:manifest>";
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, text) in [
        ("mimetype", "application/vnd.oasis.opendocument.spreadsheet"),
        ("META-INF/manifest.xml", manifest),
        ("content.xml", content.as_str()),
    ] {
        zip.start_file(name, options).unwrap();
        zip.write_all(text.as_bytes()).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

#[test]
fn an_ods_sheet_chosen_by_name_is_read_with_its_rows_numbered() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, tracker_pilot(&shots(&ds)).0).unwrap();
    // The joints on the second sheet, in radians by the header's unit; the first sheet a decoy
    // with the same header and other values.
    let n = ds.arms.left.joint_count();
    let rows = |offset: f64| -> Vec<Vec<Cell>> {
        let mut rows = vec![(1..=n).map(|k| Cell::Text(format!("q{k} [rad]"))).collect()];
        for m in &ds.arms.left.measurements {
            rows.push(m.q_rad.iter().map(|q| Cell::Num(q + offset)).collect());
        }
        rows
    };
    let joints = dir.path().join("joints.ods");
    std::fs::write(
        &joints,
        ods(&[("Plan", rows(0.1)), ("Measured", rows(0.0))]),
    )
    .unwrap();
    let mut o = options(&robot, &urdf, &ds);
    o.sheet = Some("Measured".into());
    let imported =
        import::import_arms(&OsFiles, &left_only(points.clone(), joints.clone()), &o).unwrap();
    let report = imported.report.arms.left.as_ref().unwrap();
    assert_eq!(report.matched, 40, "{}", imported.report);
    assert!(
        has_note(&imported, "sheet: `Measured`"),
        "{}",
        imported.report
    );
    for (m, truth) in imported
        .dataset
        .arms
        .left
        .measurements
        .iter()
        .zip(&ds.arms.left.measurements)
    {
        assert_eq!(m.q_rad, truth.q_rad, "{}", m.id);
    }
    // The first sheet by default, named in the report; a text cell refused with its row.
    let mut default_sheet = o.clone();
    default_sheet.sheet = None;
    let first = import::import_arms(
        &OsFiles,
        &left_only(points.clone(), joints.clone()),
        &default_sheet,
    )
    .unwrap();
    assert!(
        has_note(&first, "sheet: `Plan`, the first of 2"),
        "{}",
        first.report
    );
    let moved = first.dataset.arms.left.measurements[3].q_rad[0];
    assert!((moved - ds.arms.left.measurements[3].q_rad[0] - 0.1).abs() < 1e-12);
    let mut bad = rows(0.0);
    bad[9][4] = Cell::Text("--".into());
    std::fs::write(&joints, ods(&[("Plan", rows(0.1)), ("Measured", bad)])).unwrap();
    let err = import::import_arms(&OsFiles, &left_only(points, joints.clone()), &o).unwrap_err();
    assert_eq!(err.path(), Some(joints.as_path()), "{err}");
    assert_eq!(err.line(), Some(10), "{err}");
    assert_eq!(err.field(), Some("q5"), "{err}");
}

/// A `sensor_msgs/msg/JointState` as rmw serialises it (CDR, little-endian), written here from
/// the format's rules: the 4-byte encapsulation header, then every value aligned to its size
/// counted from the end of that header.
fn joint_state_cdr(time_ns: u64, names: &[String], position: &[f64], velocity: &[f64]) -> Vec<u8> {
    struct Out(Vec<u8>);
    impl Out {
        fn pad(&mut self, n: usize) {
            while !(self.0.len() - 4).is_multiple_of(n) {
                self.0.push(0);
            }
        }
        fn u32(&mut self, v: u32) {
            self.pad(4);
            self.0.extend(v.to_le_bytes());
        }
        fn text(&mut self, s: &str) {
            self.u32(s.len() as u32 + 1);
            self.0.extend(s.bytes().chain([0]));
        }
        fn floats(&mut self, v: &[f64]) {
            self.u32(v.len() as u32);
            for x in v {
                self.pad(8);
                self.0.extend(x.to_le_bytes());
            }
        }
    }
    let mut out = Out(vec![0, 1, 0, 0]);
    out.u32((time_ns / 1_000_000_000) as u32);
    out.u32((time_ns % 1_000_000_000) as u32);
    out.text("arm_base_link");
    out.u32(names.len() as u32);
    for n in names {
        out.text(n);
    }
    out.floats(position);
    out.floats(velocity);
    out.floats(&[]);
    out.0
}

/// A ROS 2 bag (MCAP, written with the mcap crate) of messages (topic, log time ns, data).
fn mcap_bag(messages: &[(&str, u64, Vec<u8>)]) -> Vec<u8> {
    let mut writer = mcap::Writer::new(std::io::Cursor::new(Vec::new())).unwrap();
    let schema = writer
        .add_schema(
            "sensor_msgs/msg/JointState",
            "ros2msg",
            b"std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n\
              float64[] effort\n",
        )
        .unwrap();
    let mut channels = std::collections::BTreeMap::new();
    for (k, (topic, log_time, data)) in messages.iter().enumerate() {
        let channel = match channels.get(topic) {
            Some(&c) => c,
            None => {
                let c = writer
                    .add_channel(schema, topic, "cdr", &Default::default())
                    .unwrap();
                channels.insert(*topic, c);
                c
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: *log_time,
            publish_time: *log_time,
        };
        writer.write_to_known_channel(&header, data).unwrap();
    }
    writer.finish().unwrap();
    writer.into_inner().into_inner()
}

/// The robot's clock minus the tracker PC's in the bags written here (a time zone and a drift).
const CLOCK_OFFSET_S: f64 = 3600.0 + 12.345;

/// The left arm's joint states at 50 Hz on the robot's clock, as the arm went through `ds`'s
/// configurations for the shots of [`shots`] (configuration i shot at 10 i s): parked at zero,
/// still ±3 s about each shot, 4 s moves between, parked again at the end. Names in reverse chain
/// order, a gripper's messages on the same topic between, positions with a tiny ripple.
fn joint_bag(
    ds: &Dataset,
    names: &[String],
    tracker_t0_s: f64,
) -> Vec<(&'static str, u64, Vec<u8>)> {
    let configs: Vec<&Vec<f64>> = ds.arms.left.measurements.iter().map(|m| &m.q_rad).collect();
    let zero = vec![0.0; names.len()];
    // Still poses (tracker-relative times): parked, each configuration, parked.
    let mut stills: Vec<(f64, f64, &Vec<f64>)> = vec![(-20.0, -7.0, &zero)];
    for (i, q) in configs.iter().enumerate() {
        stills.push((10.0 * i as f64 - 3.0, 10.0 * i as f64 + 3.0, q));
    }
    let end = 10.0 * configs.len() as f64 - 3.0;
    stills.push((end, end + 20.0, &zero));
    let reversed: Vec<String> = names.iter().rev().cloned().collect();
    let mut out = Vec::new();
    let mut k = 0u64;
    loop {
        let t = -20.0 + k as f64 * 0.02;
        if t > end + 20.0 {
            break;
        }
        let (q, v): (Vec<f64>, Vec<f64>) = match stills.iter().position(|s| t <= s.1) {
            Some(i) if t >= stills[i].0 || i == 0 => (stills[i].2.clone(), zero.clone()),
            Some(i) => {
                let (a, b) = (&stills[i - 1], &stills[i]);
                let f = (t - a.1) / (b.0 - a.1);
                let q = a.2.iter().zip(b.2).map(|(x, y)| x + f * (y - x)).collect();
                let v =
                    a.2.iter()
                        .zip(b.2)
                        .map(|(x, y)| (y - x) / (b.0 - a.1))
                        .collect();
                (q, v)
            }
            None => unreachable!(),
        };
        let ripple = 1e-7 * (k as f64).sin();
        let q: Vec<f64> = q.iter().rev().map(|x| x + ripple).collect();
        let v: Vec<f64> = v.into_iter().rev().collect();
        let time_ns = ((tracker_t0_s + t + CLOCK_OFFSET_S) * 1e9).round() as u64;
        out.push((
            "/joint_states",
            time_ns,
            joint_state_cdr(time_ns, &reversed, &q, &v),
        ));
        if k % 10 == 5 {
            let gripper = ["gripper_joint".to_string()];
            out.push((
                "/joint_states",
                time_ns,
                joint_state_cdr(time_ns, &gripper, &[0.01], &[]),
            ));
        }
        k += 1;
    }
    out
}

/// A note's number after `prefix` (up to the next space).
fn note_number(imported: &Imported, prefix: &str) -> f64 {
    let arm = imported.report.arms.left.as_ref().unwrap();
    let note = arm.notes.iter().find(|n| n.contains(prefix)).unwrap();
    let rest = &note[note.find(prefix).unwrap() + prefix.len()..];
    rest.split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn a_ros2_bag_gives_one_configuration_per_still_interval_with_the_clock_offset_estimated() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let shots = shots_as_measured(&ds);
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, tracker_pilot(&shots).0).unwrap();
    let tracker_t0_s = import::text::time_s(&stamp(0)[1..]).unwrap();
    let names = robot.arm_joint_names(Side::Left);
    let bag = dir.path().join("run.mcap");
    std::fs::write(&bag, mcap_bag(&joint_bag(&ds, &names, tracker_t0_s))).unwrap();
    let o = options(&robot, &urdf, &ds);
    let imported = import::import_arms(&OsFiles, &left_only(points.clone(), bag.clone()), &o)
        .unwrap_or_else(|e| panic!("{e}"));
    let report = imported.report.arms.left.as_ref().unwrap();
    let n = ds.arms.left.measurements.len();
    assert_eq!(report.matched, n, "{}", imported.report);
    // The parked intervals before and after: still, but no shots.
    assert_eq!(report.configurations_read, n + 2, "{}", imported.report);
    assert_eq!(
        report.unmatched_configurations.len(),
        2,
        "{}",
        imported.report
    );
    assert_eq!(report.repeated.len(), 1, "{}", imported.report);
    for text in [
        "ROS 2 bag: topic `/joint_states`",
        "messages on the topic without the arm's joints skipped",
        "still intervals: 42",
        "matching: by time stamp",
    ] {
        assert!(has_note(&imported, text), "{text}: {}", imported.report);
    }
    let offset = note_number(&imported, "the robot's clock minus the tracker PC's = ");
    assert!(
        (offset - CLOCK_OFFSET_S).abs() < 0.5,
        "{offset}: {}",
        imported.report
    );
    for (m, truth) in imported
        .dataset
        .arms
        .left
        .measurements
        .iter()
        .zip(&ds.arms.left.measurements)
    {
        assert!((m.tracker_points_mm[0] - truth.tracker_points_mm[0]).amax() < 0.01);
        for (a, b) in m.q_rad.iter().zip(&truth.q_rad) {
            assert!((a - b).abs() < 1e-6, "{} {a} {b}", m.id);
        }
    }
    // Written, the report says the same.
    let out = dir.path().join("dataset");
    import::write_arms(
        &imported,
        &left_only(points.clone(), bag.clone()),
        &out,
        Overwrite::Refuse,
    )
    .unwrap();
    let text = std::fs::read_to_string(out.join(import::REPORT_FILE)).unwrap();
    assert!(text.contains("clock offset: the robot's clock"), "{text}");
    // A given offset is taken as it is.
    let mut given = o.clone();
    given.bag.clock_offset_s = Some(CLOCK_OFFSET_S + 1.0);
    let imported = import::import_arms(&OsFiles, &left_only(points, bag), &given).unwrap();
    assert_eq!(imported.report.arms.left.as_ref().unwrap().matched, n);
    assert!(
        has_note(&imported, "(--clock-offset)"),
        "{}",
        imported.report
    );
}

#[test]
fn bad_bags_are_refused_with_file_time_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let (urdf, robot, ds) = six_axis_arm(dir.path());
    let points = dir.path().join("tracker.csv");
    std::fs::write(&points, tracker_pilot(&shots(&ds)).0).unwrap();
    let tracker_t0_s = import::text::time_s(&stamp(0)[1..]).unwrap();
    let names = robot.arm_joint_names(Side::Left);
    let messages = joint_bag(&ds, &names, tracker_t0_s);
    let o = options(&robot, &urdf, &ds);
    let bag = dir.path().join("run.mcap");
    let import = |messages: &[(&str, u64, Vec<u8>)], o: &ImportOptions| {
        std::fs::write(&bag, mcap_bag(messages)).unwrap();
        import::import_arms(&OsFiles, &left_only(points.clone(), bag.clone()), o).unwrap_err()
    };
    // No topic: the topics found.
    let other: Vec<_> = messages
        .iter()
        .take(30)
        .map(|(_, t, d)| ("/robot/joint_states", *t, d.clone()))
        .collect();
    let err = import(&other, &o).to_string();
    assert!(
        err.contains("no messages on topic `/joint_states`"),
        "{err}"
    );
    assert!(err.contains("`/robot/joint_states` (30 messages)"), "{err}");
    assert!(err.contains(&bag.display().to_string()), "{err}");
    // Fewer still intervals than configurations: only the parked ones last 7 s.
    let mut long = o.clone();
    long.bag.still_secs = 7.0;
    let err = import(&messages, &long);
    assert!(matches!(err, ImportError::Stream { .. }), "{err}");
    assert_eq!(err.path(), Some(bag.as_path()));
    assert_eq!(err.field(), Some("velocity"));
    let text = err.to_string();
    assert!(text.contains("2 still intervals"), "{text}");
    assert!(text.contains("40 configurations"), "{text}");
    // Time going backwards: the message, its time and the field.
    // (Message k+1 is the arm's where its time is after message k's; a gripper's repeats its time.)
    let arm_message = |from: usize| {
        (from..)
            .find(|&k| messages[k].1 < messages[k + 1].1)
            .unwrap()
            + 1
    };
    let k = arm_message(100) - 1;
    let t_k = messages[k].1;
    let mut swapped = messages.clone();
    let (a, b) = (swapped[k].2.clone(), swapped[k + 1].2.clone());
    swapped[k].2 = b;
    swapped[k + 1].2 = a;
    let err = import(&swapped, &o);
    assert_eq!(err.field(), Some("header.stamp"), "{err}");
    assert_eq!(err.path(), Some(bag.as_path()));
    let text = err.to_string();
    assert!(text.contains("goes backwards"), "{text}");
    assert!(
        text.contains(&format!("{:.3}", t_k as f64 * 1e-9)),
        "{text}"
    );
    // A message cut short: its number, time and the field it ends in.
    let mut cut = messages.clone();
    let k = arm_message(200);
    let len = cut[k].2.len();
    cut[k].2.truncate(len - 30);
    let err = import(&cut, &o);
    assert!(matches!(err, ImportError::Stream { .. }), "{err}");
    assert_eq!(err.path(), Some(bag.as_path()));
    let text = err.to_string();
    assert!(
        err.field()
            .is_some_and(|f| ["velocity", "position"].contains(&f)),
        "{text}"
    );
    assert!(text.contains("message "), "{text}");
}
