//! Every malformed `dualcal-dataset/1` input gets a typed error naming the file, the line and the field;
//! nothing panics on any input.

use dualcal::dataset::{self, Dataset, DatasetError, MIN_CONFIGS, Split};
use dualcal::output::FileError;
use dualcal::side::Side;
use nalgebra::{UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

const MANIFEST: &str = r#"# test dataset
format = "dualcal-dataset/1"
[units]
length = "mm"
angle = "deg"
[tracker]
mpe_um = 16.0
mpe_um_per_m = 0.8
[reflectors]
a = [45.0, 0.0, 40.0]
b = [-25.0, 40.0, 40.0]
c = [-25.0, -40.0, 40]
[[arms]]
name = "left"
file = "left.csv"
[[arms]]
name = "right"
file = "right.csv"
"#;

const HEADER: &str = "id,q1,q2,q3,q4,q5,q6,q7,ax,ay,az,bx,by,bz,cx,cy,cz,split";

/// A valid CSV: two comment lines, the header on line 3, `n` rows on lines 4.. . Joint values are
/// random; each row's reflectors are the nominal triangle of `MANIFEST`, turned and placed at random.
fn csv_text(n: usize, seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let triangle = [
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ];
    let mut s = format!("# measured 2026-11-21\n# joints in deg, points in mm\n{HEADER}\n");
    for i in 0..n {
        let mut row = vec![format!("c{i}")];
        row.extend((0..7).map(|_| format!("{:.4}", rng.random_range(-90.0..90.0))));
        let turn =
            UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| rng.random_range(-3.0..3.0)));
        let centre = Vector3::from_fn(|_, _| rng.random_range(-2000.0..2000.0));
        for p in &triangle {
            let q = turn * p + centre;
            row.extend(q.iter().map(|x| format!("{x:.6}")));
        }
        row.push(if i % 3 == 2 { "ver" } else { "cal" }.into());
        s += &row.join(",");
        s.push('\n');
    }
    s
}

struct Fixture {
    dir: tempfile::TempDir,
}

impl Fixture {
    fn new(manifest: &str, left: &str, right: &str) -> Self {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("dataset.toml"), manifest).unwrap();
        std::fs::write(dir.path().join("left.csv"), left).unwrap();
        std::fs::write(dir.path().join("right.csv"), right).unwrap();
        Fixture { dir }
    }

    fn valid() -> Self {
        Self::new(MANIFEST, &csv_text(6, 1), &csv_text(5, 2))
    }

    /// Valid manifest and right arm, this left CSV.
    fn with_left(left: &str) -> Self {
        Self::new(MANIFEST, left, &csv_text(5, 2))
    }

    fn with_manifest(manifest: &str) -> Self {
        Self::new(manifest, &csv_text(6, 1), &csv_text(5, 2))
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    fn file(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn load(&self) -> Result<Dataset, DatasetError> {
        dataset::load(self.path())
    }
}

/// The left CSV with line `line` (1-based) replaced.
fn left_with_line(line: usize, text: &str) -> String {
    let mut lines: Vec<String> = csv_text(6, 1).lines().map(String::from).collect();
    lines[line - 1] = text.to_string();
    lines.join("\n") + "\n"
}

/// Replace field `col` of data line `line` of the valid left CSV.
fn left_with_field(line: usize, col: usize, value: &str) -> String {
    let original = csv_text(6, 1);
    let mut fields: Vec<String> = original
        .lines()
        .nth(line - 1)
        .unwrap()
        .split(',')
        .map(String::from)
        .collect();
    fields[col] = value.to_string();
    left_with_line(line, &fields.join(","))
}

fn assert_names(err: &DatasetError, parts: &[&str]) {
    let msg = err.to_string();
    for p in parts {
        assert!(msg.contains(p), "message {msg:?} does not contain {p:?}");
    }
}

// ---------------------------------------------------------------------------------------------------
// Valid input

#[test]
fn valid_dataset_loads_and_converts_units() {
    let f = Fixture::valid();
    let d = f.load().unwrap();
    assert_eq!(d.arms.left.measurements.len(), 6);
    assert_eq!(d.arms.right.measurements.len(), 5);
    let m = &d.arms.left.measurements[0];
    assert_eq!(m.line, 4);
    assert_eq!(m.id, "c0");
    // Recompute the first row from the CSV text independently.
    let text = csv_text(6, 1);
    let row: Vec<f64> = text
        .lines()
        .nth(3)
        .unwrap()
        .split(',')
        .skip(1)
        .take(16)
        .map(|s| s.parse().unwrap())
        .collect();
    for (q_rad, q_deg) in m.q_rad.iter().zip(&row[..7]) {
        assert!((q_rad - q_deg * std::f64::consts::PI / 180.0).abs() < 1e-15);
    }
    assert_eq!(m.tracker_points_mm[1].y, row[7 + 4]);
    assert_eq!(d.arms.left.measurements[2].split, Split::Ver);
    assert_eq!(d.tracker.mpe_um, 16.0);
    assert_eq!(d.nominal_reflectors_mm[2].z, 40.0);
    assert_eq!(d.robot, None);
}

/// `csv_text` with the reflector coordinates in metres.
fn csv_text_in_m(n: usize, seed: u64) -> String {
    csv_text(n, seed)
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.starts_with("id,") {
                return l.to_string();
            }
            l.split(',')
                .enumerate()
                .map(|(i, f)| match i {
                    8..=16 => format!("{}", f.parse::<f64>().unwrap() / 1000.0),
                    _ => f.to_string(),
                })
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn metres_are_converted_to_mm_and_manifest_path_is_accepted() {
    let manifest = MANIFEST
        .replace("length = \"mm\"", "length = \"m\"")
        .replace("angle = \"deg\"", "angle = \"rad\"")
        .replace("[45.0, 0.0, 40.0]", "[0.045, 0.0, 0.04]")
        .replace("[-25.0, 40.0, 40.0]", "[-0.025, 0.04, 0.04]")
        .replace("[-25.0, -40.0, 40]", "[-0.025, -0.04, 0.04]");
    let f = Fixture::new(&manifest, &csv_text_in_m(6, 1), &csv_text_in_m(5, 2));
    let d = dataset::load(&f.file("dataset.toml")).unwrap();
    assert_eq!(d.nominal_reflectors_mm[0].x, 45.0);
    let text = csv_text(6, 1);
    let row: Vec<f64> = text
        .lines()
        .nth(3)
        .unwrap()
        .split(',')
        .skip(1)
        .take(16)
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(d.arms.left.measurements[0].q_rad[0], row[0]);
    assert!((d.arms.left.measurements[0].tracker_points_mm[0].x - row[7]).abs() < 1e-9);
}

#[test]
fn byte_order_mark_and_crlf_are_accepted() {
    let left = format!("\u{feff}{}", csv_text(6, 1).replace('\n', "\r\n"));
    let f = Fixture::new(&format!("\u{feff}{MANIFEST}"), &left, &csv_text(5, 2));
    let d = f.load().unwrap();
    assert_eq!(d.arms.left.measurements.len(), 6);
    assert_eq!(d.arms.left.measurements[5].line, 9);
}

#[test]
fn robot_path_is_resolved_relative_to_the_dataset() {
    let manifest = MANIFEST.replace("[units]", "robot = \"robot/my.urdf\"\n[units]");
    let f = Fixture::with_manifest(&manifest);
    std::fs::create_dir(f.file("robot")).unwrap();
    std::fs::write(f.file("robot/my.urdf"), "<robot/>").unwrap();
    let d = f.load().unwrap();
    assert_eq!(d.robot, Some(f.file("robot/my.urdf")));
}

#[test]
fn split_column_is_optional_and_defaults_to_cal() {
    let text: String = csv_text(6, 1)
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                l.to_string()
            } else {
                l.rsplit_once(',').unwrap().0.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let d = Fixture::with_left(&text).load().unwrap();
    assert!(
        d.arms
            .left
            .measurements
            .iter()
            .all(|m| m.split == Split::Cal)
    );
}

// ---------------------------------------------------------------------------------------------------
// Missing files

#[test]
fn missing_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let err = dataset::load(dir.path()).unwrap_err();
    assert!(
        matches!(err, DatasetError::File(FileError::Read { ref path, .. }) if path.ends_with("dataset.toml"))
    );
    assert_names(&err, &["dataset.toml", "cannot read"]);
}

#[test]
fn missing_csv_file() {
    let f = Fixture::valid();
    std::fs::remove_file(f.file("right.csv")).unwrap();
    let err = f.load().unwrap_err();
    assert!(
        matches!(err, DatasetError::File(FileError::Read { ref path, .. }) if path.ends_with("right.csv"))
    );
    assert_names(&err, &["right.csv"]);
}

#[test]
fn missing_robot_file() {
    let manifest = MANIFEST.replace("[units]", "robot = \"nope.urdf\"\n[units]");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(3), ref field, .. } if field == "robot")
    );
    assert_names(&err, &["dataset.toml:3", "`robot`", "nope.urdf"]);
}

// ---------------------------------------------------------------------------------------------------
// dataset.toml

#[test]
fn toml_syntax_error_names_the_line() {
    let manifest = MANIFEST.replace("angle = \"deg\"", "angle = \"deg");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Toml { line: Some(5), .. }),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml:5", "angle"]);
}

#[test]
fn toml_wrong_type_names_line_and_field() {
    let manifest = MANIFEST.replace("mpe_um = 16.0", "mpe_um = \"sixteen\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Toml { line: Some(7), .. }),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml:7", "mpe_um"]);
}

#[test]
fn toml_unknown_key_is_refused() {
    let manifest = MANIFEST.replace("angle = \"deg\"", "angel = \"deg\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Toml { line: Some(5), .. }),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml:5", "angel"]);
}

#[test]
fn unknown_format_tag() {
    let manifest = MANIFEST.replace("dualcal-dataset/1", "dualcal-dataset/2");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(2), ref field, .. } if field == "format")
    );
    assert_names(&err, &["dataset.toml:2", "`format`", "dualcal-dataset/2"]);
}

#[test]
fn missing_format_tag() {
    let manifest = MANIFEST.replace("format = \"dualcal-dataset/1\"\n", "");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(matches!(err, DatasetError::Manifest { ref field, .. } if field == "format"));
    assert_names(&err, &["dataset.toml", "`format`", "missing"]);
}

#[test]
fn unknown_length_unit() {
    let manifest = MANIFEST.replace("length = \"mm\"", "length = \"inch\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(4), ref field, .. } if field == "units.length")
    );
    assert_names(&err, &["dataset.toml:4", "units.length", "inch"]);
}

#[test]
fn unknown_angle_unit() {
    let manifest = MANIFEST.replace("angle = \"deg\"", "angle = \"grad\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(5), ref field, .. } if field == "units.angle")
    );
    assert_names(&err, &["dataset.toml:5", "units.angle", "grad"]);
}

#[test]
fn missing_units_table() {
    let manifest = MANIFEST.replace("[units]\nlength = \"mm\"\nangle = \"deg\"\n", "");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(matches!(err, DatasetError::Manifest { ref field, .. } if field == "units"));
    assert_names(&err, &["dataset.toml", "`units`"]);
}

#[test]
fn negative_tracker_mpe() {
    let manifest = MANIFEST.replace("mpe_um_per_m = 0.8", "mpe_um_per_m = -0.8");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(8), ref field, .. } if field == "tracker.mpe_um_per_m")
    );
    assert_names(&err, &["dataset.toml:8", "tracker.mpe_um_per_m"]);
}

#[test]
fn reflector_with_two_coordinates() {
    let manifest = MANIFEST.replace("b = [-25.0, 40.0, 40.0]", "b = [-25.0, 40.0]");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(11), ref field, .. } if field == "reflectors.b")
    );
    assert_names(&err, &["dataset.toml:11", "reflectors.b", "3 numbers"]);
}

#[test]
fn reflector_with_a_string_or_nan() {
    for bad in ["[1.0, \"x\", 2.0]", "[1.0, nan, 2.0]", "\"45,0,40\""] {
        let manifest = MANIFEST.replace("a = [45.0, 0.0, 40.0]", &format!("a = {bad}"));
        let err = Fixture::with_manifest(&manifest).load().unwrap_err();
        assert!(
            matches!(err, DatasetError::Manifest { line: Some(10), ref field, .. } if field == "reflectors.a"),
            "{bad}: {err:?}"
        );
        assert_names(&err, &["dataset.toml:10", "reflectors.a"]);
    }
}

/// A manifest without `c` declares two reflectors: the CSV's `cx, cy, cz` columns are then unknown.
#[test]
fn columns_of_an_undeclared_reflector() {
    let manifest = MANIFEST.replace("c = [-25.0, -40.0, 40]\n", "");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "cx"),
        "{err}"
    );
    assert_names(&err, &["left.csv:3", "cx", "bz"]);
}

/// A declared reflector whose columns the CSV lacks.
#[test]
fn reflector_declared_but_its_columns_missing() {
    let manifest = MANIFEST.replace(
        "c = [-25.0, -40.0, 40]\n",
        "c = [-25.0, -40.0, 40]\nd = [0, 0, 90]\n",
    );
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "dx" || field == "split"),
        "{err}"
    );
    assert_names(&err, &["left.csv:3", "dx"]);
}

#[test]
fn reflector_names_and_an_empty_table_are_checked() {
    let manifest = MANIFEST.replace("b = [", "2b = [");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::Toml { .. } | DatasetError::Manifest { .. }
        ),
        "{err}"
    );
    let manifest = MANIFEST.replace("b = [", "\"b-2\" = [");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(11), ref field, .. } if field == "reflectors.b-2"),
        "{err}"
    );
    assert_names(&err, &["dataset.toml:11", "letter"]);
    let start = MANIFEST.find("a = [").unwrap();
    let end = MANIFEST.find("[[arms]]").unwrap();
    let manifest = format!("{}{}", &MANIFEST[..start], &MANIFEST[end..]);
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { ref field, .. } if field == "reflectors"),
        "{err}"
    );
    assert_names(&err, &["no reflector"]);
}

/// One reflector per arm: `a` alone, its three columns.
#[test]
fn a_one_reflector_dataset_loads() {
    let start = MANIFEST.find("b = [").unwrap();
    let end = MANIFEST.find("[[arms]]").unwrap();
    let manifest = format!("{}{}", &MANIFEST[..start], &MANIFEST[end..]);
    let keep_a = |text: &str| -> String {
        text.lines()
            .map(|l| {
                if l.starts_with('#') {
                    return l.to_string();
                }
                let f: Vec<&str> = l.split(',').collect();
                let mut out: Vec<&str> = f[..11].to_vec();
                out.push(f[17]);
                out.join(",")
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    };
    let fx = Fixture::new(
        &manifest,
        &keep_a(&csv_text(6, 1)),
        &keep_a(&csv_text(5, 2)),
    );
    let ds = fx.load().unwrap();
    assert_eq!(ds.reflector_count(), 1);
    assert_eq!(&ds.reflector_names[..], &["a".to_string()]);
    assert_eq!(ds.arms.left.measurements[0].tracker_points_mm.len(), 1);
    assert!(ds.one_tracker_frame());
}

#[test]
fn stations_on_both_arms_or_neither() {
    let manifest = MANIFEST.replace(
        "file = \"left.csv\"\n",
        "file = \"left.csv\"\nstation = \"east\"\n",
    );
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(16), ref field, .. } if field == "arms.station"),
        "{err}"
    );
    assert_names(&err, &["dataset.toml:16", "arms.station", "left arm"]);
    let both = manifest.replace(
        "file = \"right.csv\"\n",
        "file = \"right.csv\"\nstation = \"west\"\n",
    );
    let ds = Fixture::with_manifest(&both).load().unwrap();
    assert_eq!(ds.arms.left.station.as_deref(), Some("east"));
    assert!(!ds.one_tracker_frame());
    let same = both.replace("\"west\"", "\"east\"");
    assert!(
        Fixture::with_manifest(&same)
            .load()
            .unwrap()
            .one_tracker_frame()
    );
}

#[test]
fn one_arm_alone_and_no_arm() {
    // One entry: a dataset of that arm alone (the other arm not measured, not an error).
    let manifest = MANIFEST.replace("[[arms]]\nname = \"right\"\nfile = \"right.csv\"\n", "");
    let ds = Fixture::with_manifest(&manifest).load().unwrap();
    assert_eq!(ds.measured_sides(), vec![Side::Left]);
    assert!(!ds.arm(Side::Right).is_measured() && !ds.one_tracker_frame());
    assert!(
        ds.base_not_measurable()
            .unwrap()
            .contains("only the left arm")
    );
    // An arm alone may name its station.
    let station = manifest.replace(
        "file = \"left.csv\"\n",
        "file = \"left.csv\"\nstation = \"A\"\n",
    );
    assert!(Fixture::with_manifest(&station).load().is_ok());
    // No entry at all: refused.
    let none = manifest.replace("[[arms]]\nname = \"left\"\nfile = \"left.csv\"\n", "");
    assert!(!none.contains("[[arms]]"), "{none}");
    let err = Fixture::with_manifest(&none).load().unwrap_err();
    assert!(matches!(err, DatasetError::Manifest { ref field, .. } if field == "arms"));
    assert_names(&err, &["dataset.toml", "`arms`", "left", "right"]);
}

#[test]
fn duplicate_arm() {
    let manifest = MANIFEST.replace("name = \"right\"", "name = \"left\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(17), ref field, .. } if field == "arms.name")
    );
    assert_names(
        &err,
        &["dataset.toml:17", "arms.name", "duplicate", "line 14"],
    );
}

#[test]
fn unknown_arm_name() {
    let manifest = MANIFEST.replace("name = \"right\"", "name = \"middle\"");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(17), ref field, .. } if field == "arms.name")
    );
    assert_names(&err, &["dataset.toml:17", "arms.name", "middle"]);
}

#[test]
fn arm_without_file() {
    let manifest = MANIFEST.replace("file = \"right.csv\"\n", "");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(_), ref field, .. } if field == "arms.file")
    );
    assert_names(&err, &["dataset.toml:", "arms.file"]);
}

#[test]
fn empty_and_binary_manifests() {
    let err = Fixture::with_manifest("").load().unwrap_err();
    assert!(matches!(err, DatasetError::Manifest { ref field, .. } if field == "format"));
    let f = Fixture::valid();
    std::fs::write(
        f.file("dataset.toml"),
        b"format = \"dualcal-dataset/1\"\n\xff\xfe\n",
    )
    .unwrap();
    let err = f.load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Encoding { line: 2, .. }),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml:2", "UTF-8"]);
}

// ---------------------------------------------------------------------------------------------------
// CSV header

#[test]
fn csv_missing_column() {
    let header = HEADER.replace(",cz,split", "");
    // Drop the last two fields of every row as well, so only the header matters.
    let text: String = csv_text(6, 1)
        .lines()
        .map(|l| {
            if l.starts_with("c") {
                let v: Vec<&str> = l.split(',').collect();
                v[..16].join(",")
            } else if l.starts_with("id") {
                header.clone()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let err = Fixture::with_left(&text).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "cz"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:3", "`cz`", "missing"]);
}

#[test]
fn csv_header_wrong_order() {
    let header = HEADER.replace("q2,q3", "q3,q2");
    let err = Fixture::with_left(&left_with_line(3, &header))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "q3"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:3", "`q3`", "`q2`", "order"]);
}

#[test]
fn csv_header_unknown_column() {
    let header = HEADER.replace("ay", "a_y");
    let err = Fixture::with_left(&left_with_line(3, &header))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "a_y"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:3", "a_y", "unknown"]);
    let header = HEADER.replace(',', ";");
    let err = Fixture::with_left(&left_with_line(3, &header))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, .. }),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:3", "use commas"]);
    let header = HEADER.replace("split", "set");
    let err = Fixture::with_left(&left_with_line(3, &header))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "set"),
        "{err:?}"
    );
}

#[test]
fn csv_without_header() {
    for text in ["", "# only a comment\n", "\n\n"] {
        let err = Fixture::with_left(text).load().unwrap_err();
        assert!(
            matches!(err, DatasetError::Header { ref field, .. } if field == "id"),
            "{err:?}"
        );
        assert_names(&err, &["left.csv:", "missing header"]);
    }
    // Data where the header should be.
    let text: String = csv_text(6, 1)
        .lines()
        .filter(|l| !l.starts_with("id"))
        .collect::<Vec<_>>()
        .join("\n");
    let err = Fixture::with_left(&text).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Header { line: 3, ref field, .. } if field == "c0"),
        "{err:?}"
    );
}

// ---------------------------------------------------------------------------------------------------
// CSV rows

#[test]
fn csv_non_numeric() {
    // "12,5x" adds a field: a field-count error, not a number error.
    let err = Fixture::with_left(&left_with_field(6, 3, "12,5x"))
        .load()
        .unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::FieldCount {
                line: 6,
                expected: 18,
                found: 19,
                ..
            }
        ),
        "{err:?}"
    );
    let err = Fixture::with_left(&left_with_field(6, 3, "twelve"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 6, ref field, .. } if field == "q3"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:6", "`q3`", "twelve", "not a number"]);
}

#[test]
fn csv_nan_and_infinity() {
    for (col, name, bad) in [(9, "ay", "NaN"), (16, "cz", "inf"), (2, "q2", "-infinity")] {
        let err = Fixture::with_left(&left_with_field(5, col, bad))
            .load()
            .unwrap_err();
        assert!(
            matches!(err, DatasetError::Field { line: 5, ref field, .. } if field == name),
            "{err:?}"
        );
        assert_names(&err, &["left.csv:5", &format!("`{name}`"), "finite"]);
    }
}

#[test]
fn csv_empty_value() {
    let err = Fixture::with_left(&left_with_field(4, 11, ""))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 4, ref field, .. } if field == "bx"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:4", "`bx`", "empty"]);
}

#[test]
fn csv_wrong_field_count() {
    let row = csv_text(6, 1).lines().nth(6).unwrap().to_string();
    let short = row.rsplit_once(',').unwrap().0.to_string();
    let err = Fixture::with_left(&left_with_line(7, &short))
        .load()
        .unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::FieldCount {
                line: 7,
                expected: 18,
                found: 17,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:7", "expected 18 fields", "found 17"]);
    let long = format!("{row},extra");
    let err = Fixture::with_left(&left_with_line(7, &long))
        .load()
        .unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::FieldCount {
                line: 7,
                expected: 18,
                found: 19,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn csv_duplicate_id() {
    let err = Fixture::with_left(&left_with_field(8, 0, "c1"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::DuplicateId { line: 8, first_line: 5, ref id, .. } if id == "c1"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:8", "`id`", "c1", "line 5"]);
}

#[test]
fn csv_empty_id() {
    let err = Fixture::with_left(&left_with_field(4, 0, ""))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 4, ref field, .. } if field == "id"),
        "{err:?}"
    );
}

#[test]
fn csv_unknown_split() {
    let err = Fixture::with_left(&left_with_field(9, 17, "test"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 9, ref field, .. } if field == "split"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:9", "`split`", "test", "`cal` or `ver`"]);
}

#[test]
fn csv_too_few_configurations() {
    let f = Fixture::new(MANIFEST, &csv_text(6, 1), &csv_text(MIN_CONFIGS - 1, 2));
    let err = f.load().unwrap_err();
    assert!(
        matches!(err, DatasetError::TooFewConfigurations { found: 3, min: 4, ref path, .. } if path.ends_with("right.csv")),
        "{err:?}"
    );
    assert_names(
        &err,
        &["right.csv", "right arm", "3 configurations", "at least 4"],
    );
    // Exactly the minimum is fine.
    Fixture::new(MANIFEST, &csv_text(6, 1), &csv_text(MIN_CONFIGS, 2))
        .load()
        .unwrap();
}

#[test]
fn csv_not_utf8() {
    let mut bytes = csv_text(6, 1).into_bytes();
    let pos = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(4)
        .unwrap()
        .0
        + 2;
    bytes[pos] = 0xff; // on line 6
    let f = Fixture::valid();
    std::fs::write(f.file("left.csv"), &bytes).unwrap();
    let err = f.load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Encoding { line: 6, .. }),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:6", "UTF-8"]);
}

#[test]
fn csv_comment_lines_between_rows_keep_line_numbers() {
    let mut text = csv_text(6, 1);
    text = text.replacen("\nc2,", "\n# a remark\n\nc2,", 1);
    // c4 is now on line 10 (two extra lines before c2 on old line 6).
    let text = text.replacen("\nc4,", "\nc4,x", 1);
    let err = Fixture::with_left(&text).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 10, ref field, .. } if field == "q1"),
        "{err:?}"
    );
}

// ---------------------------------------------------------------------------------------------------
// Nothing panics

#[test]
fn random_mutations_never_panic() {
    let mut rng = ChaCha8Rng::seed_from_u64(20261122);
    let f = Fixture::valid();
    let csv = csv_text(6, 1).into_bytes();
    let pieces: [&[u8]; 12] = [
        b",",
        b"\n",
        b"\r",
        b"#",
        b"\"",
        b"nan",
        b"1e999",
        b"\xff",
        b"\xef\xbb\xbf",
        b"[",
        b"=",
        b"\0",
    ];
    let mut errors = 0;
    for round in 0..400 {
        let mutate_manifest = round % 2 == 0;
        let mut bytes = if mutate_manifest {
            MANIFEST.as_bytes().to_vec()
        } else {
            csv.clone()
        };
        for _ in 0..rng.random_range(1..6) {
            if bytes.is_empty() {
                break;
            }
            let pos = rng.random_range(0..bytes.len());
            match rng.random_range(0..4) {
                0 => {
                    bytes.remove(pos);
                }
                1 => {
                    let p = pieces[rng.random_range(0..pieces.len())];
                    bytes.splice(pos..pos, p.iter().copied());
                }
                2 => bytes[pos] = rng.random(),
                _ => {
                    let end = (pos + rng.random_range(0..40)).min(bytes.len());
                    bytes.drain(pos..end);
                }
            }
        }
        if rng.random_range(0..20) == 0 {
            bytes.truncate(rng.random_range(0..bytes.len().max(1)));
        }
        let (name, restore) = if mutate_manifest {
            ("dataset.toml", MANIFEST.as_bytes().to_vec())
        } else {
            ("left.csv", csv.clone())
        };
        std::fs::write(f.file(name), &bytes).unwrap();
        let result = std::panic::catch_unwind(|| dataset::load(f.path()));
        let result = result.unwrap_or_else(|_| {
            panic!(
                "load panicked on {name}: {:?}",
                String::from_utf8_lossy(&bytes)
            )
        });
        if let Err(e) = result {
            errors += 1;
            let msg = e.to_string();
            let dir = f.path().display().to_string();
            assert!(msg.contains(&dir), "{msg}");
        }
        std::fs::write(f.file(name), &restore).unwrap();
    }
    // The mutations must actually exercise the error paths.
    assert!(errors > 200, "only {errors} of 400 mutations were refused");
    f.load().unwrap();
}

// ---------------------------------------------------------------------------------------------------
// Plausibility (docs/reliability.md)

/// The values of data line `line` (1-based) of the valid left CSV.
fn left_row(line: usize) -> Vec<String> {
    csv_text(6, 1)
        .lines()
        .nth(line - 1)
        .unwrap()
        .split(',')
        .map(String::from)
        .collect()
}

#[test]
fn data_file_outside_the_dataset_directory_is_refused_without_reading_it() {
    for file in [
        "../../../../etc/passwd",
        "/etc/passwd",
        "sub/../../left.csv",
    ] {
        let manifest = MANIFEST.replace("file = \"left.csv\"", &format!("file = \"{file}\""));
        let err = Fixture::with_manifest(&manifest).load().unwrap_err();
        assert!(
            matches!(err, DatasetError::Manifest { line: Some(15), ref field, .. } if field == "arms.file"),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(msg.contains("inside the dataset directory"), "{msg}");
        assert!(!msg.contains("root:"), "{msg}");
    }
}

#[test]
fn utf16_files_are_refused_with_a_save_as_utf8_hint() {
    let csv = csv_text(6, 1);
    let with_bom: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(csv.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let without_bom: Vec<u8> = csv.encode_utf16().flat_map(u16::to_be_bytes).collect();
    for bytes in [with_bom, without_bom] {
        let f = Fixture::valid();
        std::fs::write(f.file("left.csv"), &bytes).unwrap();
        let err = f.load().unwrap_err();
        assert!(matches!(err, DatasetError::Text { .. }), "{err:?}");
        assert_names(&err, &["left.csv", "UTF-16", "save it as UTF-8"]);
    }
    let manifest: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(MANIFEST.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let f = Fixture::valid();
    std::fs::write(f.file("dataset.toml"), manifest).unwrap();
    assert_names(&f.load().unwrap_err(), &["dataset.toml", "UTF-16"]);
}

#[test]
fn binary_data_is_refused_with_its_line() {
    let text = csv_text(6, 1).replacen("\nc3,", "\nc3\0,", 1);
    let err = Fixture::with_left(&text).load().unwrap_err();
    assert!(matches!(err, DatasetError::Text { .. }), "{err:?}");
    assert_names(&err, &["left.csv", "line 7", "binary"]);
}

#[test]
fn empty_and_header_only_files() {
    let err = Fixture::with_left("").load().unwrap_err();
    assert!(matches!(err, DatasetError::Header { .. }), "{err:?}");
    assert_names(&err, &["left.csv", "the file is empty"]);
    let err = Fixture::with_left(&format!("{HEADER}\n"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::TooFewConfigurations { found: 0, .. }),
        "{err:?}"
    );
}

#[test]
fn a_file_cut_off_inside_a_row_says_so() {
    let text = csv_text(6, 1);
    let cut = &text[..text.trim_end().rfind(',').unwrap() - 30];
    let err = Fixture::with_left(cut).load().unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::FieldCount {
                line: 9,
                truncated: true,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:9", "cut off"]);
    // A short row in the middle is not called truncated.
    let err = Fixture::with_left(&left_with_line(5, "c1,1,2,3"))
        .load()
        .unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::FieldCount {
                line: 5,
                truncated: false,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn absurd_magnitudes_are_refused() {
    let err = Fixture::with_left(&left_with_field(6, 9, "1e12"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 6, ref field, .. } if field == "ay"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:6", "`ay`", "1e12", "tracker"]);
    let err = Fixture::with_left(&left_with_field(5, 3, "-4e9"))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 5, ref field, .. } if field == "q3"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:5", "`q3`", "joint value"]);
}

#[test]
fn collinear_and_coincident_reflectors_are_refused() {
    // c on the line through a and b.
    let mut row = left_row(7);
    let v = |i: usize| -> f64 { row[i].parse().unwrap() };
    let mid: Vec<String> = (0..3)
        .map(|c| format!("{}", 2.0 * v(11 + c) - v(8 + c)))
        .collect();
    row.splice(14..17, mid);
    let err = Fixture::with_left(&left_with_line(7, &row.join(",")))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::DegenerateTriangle { line: 7, .. }),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:7", "collinear", "`c3`"]);
    // b where a is.
    let mut row = left_row(5);
    let a: Vec<String> = row[8..11].to_vec();
    row.splice(11..14, a);
    let err = Fixture::with_left(&left_with_line(5, &row.join(",")))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::DegenerateTriangle { line: 5, .. }),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:5", "a and b", "0.0"]);
}

#[test]
fn a_row_pasted_twice_is_refused() {
    let mut row = left_row(8);
    row[0] = "c5-again".into();
    let text = format!("{}{}\n", csv_text(6, 1), row.join(","));
    let err = Fixture::with_left(&text).load().unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::DuplicateRow {
                line: 10,
                first_line: 8,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names(
        &err,
        &["left.csv:10", "c5-again", "left.csv:8", "pasted twice"],
    );
    // A left row in the right arm's file.
    let mut row = left_row(4);
    row[0] = "r-extra".into();
    let right = format!("{}{}\n", csv_text(5, 2), row.join(","));
    let err = Fixture::new(MANIFEST, &csv_text(6, 1), &right)
        .load()
        .unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::DuplicateRow {
                line: 9,
                first_line: 4,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names(&err, &["right.csv:9", "left.csv:4"]);
}

#[test]
fn coordinates_in_another_unit_than_declared_are_refused() {
    // A metre file declared as millimetres.
    let f = Fixture::new(MANIFEST, &csv_text_in_m(6, 1), &csv_text(5, 2));
    let err = f.load().unwrap_err();
    assert!(matches!(err, DatasetError::UnitMismatch { .. }), "{err:?}");
    assert_names(&err, &["left.csv", "look like metres", "units.length"]);
    // Nominal reflectors in metres declared as millimetres.
    let manifest = MANIFEST
        .replace("[45.0, 0.0, 40.0]", "[0.045, 0.0, 0.04]")
        .replace("[-25.0, 40.0, 40.0]", "[-0.025, 0.04, 0.04]")
        .replace("[-25.0, -40.0, 40]", "[-0.025, -0.04, 0.04]");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { ref field, .. } if field == "reflectors"),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml", "metres"]);
}

#[test]
fn joint_values_outside_the_robots_limits_are_refused_after_loading() {
    use dualcal::robot::RobotDescription;
    use dualcal::side::PerSide;
    let robot = RobotDescription::builtin_irb14000();
    let limits = PerSide::from_fn(|s| robot.joint_limits_rad(s));
    // q2 of ABB axis 2 is limited to [-143.5°, 43.5°]; the fixture draws ±90°.
    let mut text = String::new();
    for l in csv_text(6, 1).lines() {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        if f.len() > 8 && !l.starts_with("id") && !l.starts_with('#') {
            f[2] = "-10".into();
            f[4] = "-20".into();
        }
        text += &(f.join(",") + "\n");
    }
    let ds = Fixture::with_left(&text).load().unwrap();
    let err = dataset::check_joint_limits(&ds, &limits).unwrap_err();
    // The right arm's rows are untouched and fail; the left arm's pass.
    assert!(
        matches!(err, DatasetError::JointLimit { ref path, .. } if path.ends_with("right.csv")),
        "{err:?}"
    );
    // One value far outside: named with its line, column and the limits.
    let mut ds = Fixture::valid().load().unwrap();
    for arm in [&mut ds.arms.left, &mut ds.arms.right] {
        for m in &mut arm.measurements {
            m.q_rad = vec![0.1, -0.5, 0.2, -0.3, 0.4, 0.5, 0.6];
        }
    }
    ds.arms.left.measurements[2].q_rad[3] = 212f64.to_radians();
    let err = dataset::check_joint_limits(&ds, &limits).unwrap_err();
    assert!(
        matches!(err, DatasetError::JointLimit { line: 6, ref field, .. } if field == "q4"),
        "{err:?}"
    );
    assert_names(&err, &["left.csv:6", "`q4`", "212.00°", "80.00°"]);
    // Two columns swapped in a row: the message says so.
    ds.arms.left.measurements[2].q_rad = vec![2.0, 1.3, 2.0, -0.5, 2.0, 2.0, 2.0];
    let err = dataset::check_joint_limits(&ds, &limits).unwrap_err();
    assert_names(&err, &["`q2`", "swapping q2 and q4"]);
    // Degrees in a file declared in radians.
    for m in ds.arms.left.measurements.iter_mut() {
        m.q_rad = vec![10.0, -30.0, 20.0, -40.0, 50.0, 60.0, 70.0];
    }
    let err = dataset::check_joint_limits(&ds, &limits).unwrap_err();
    assert_names(&err, &["in degrees", "units.angle"]);
    // Within the limits: accepted.
    for m in ds.arms.left.measurements.iter_mut() {
        m.q_rad = vec![0.1, -0.5, 0.2, -0.3, 0.4, 0.5, 0.6];
    }
    dataset::check_joint_limits(&ds, &limits).unwrap();
}

#[test]
fn implausible_tracker_mpe_is_refused() {
    let manifest = MANIFEST.replace("mpe_um_per_m = 0.8", "mpe_um_per_m = 8e5");
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { line: Some(8), ref field, .. } if field == "tracker.mpe_um_per_m"),
        "{err:?}"
    );
    assert_names(&err, &["dataset.toml:8", "plausible"]);
}

/// Found by fuzzing: text of the file that ends up in a message (a path in the manifest, an id, a
/// URDF link name) is bounded, so no message quotes kilobytes.
#[test]
fn long_paths_and_ids_are_refused_with_a_short_message() {
    let long = "x".repeat(2000);
    let manifest = MANIFEST.replace("file = \"left.csv\"", &format!("file = \"{long}.csv\""));
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(
        matches!(err, DatasetError::Manifest { ref field, .. } if field == "arms.file"),
        "{err:?}"
    );
    assert!(err.to_string().len() < 300, "{err}");
    let manifest = MANIFEST.replace("[units]", &format!("robot = \"a/{long}\"\n[units]"));
    let err = Fixture::with_manifest(&manifest).load().unwrap_err();
    assert!(err.to_string().len() < 300, "{err}");
    let manifest = MANIFEST.replace("file = \"left.csv\"", "file = \"left\\n.csv\"");
    assert_names(
        &Fixture::with_manifest(&manifest).load().unwrap_err(),
        &["control character"],
    );
    let err = Fixture::with_left(&left_with_field(5, 0, &"i".repeat(500)))
        .load()
        .unwrap_err();
    assert!(
        matches!(err, DatasetError::Field { line: 5, ref field, .. } if field == "id"),
        "{err:?}"
    );
    assert!(err.to_string().len() < 300, "{err}");
    let err = Fixture::with_left(&left_with_field(6, 0, "\"c\tx\""))
        .load()
        .unwrap_err();
    assert_names(&err, &["left.csv:6", "control character"]);
}
