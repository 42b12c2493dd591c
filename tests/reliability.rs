//! The acceptance corpus: broken copies of the bundled example, as a user would make them,
//! through `dualcal calibrate`. Each is refused with a message naming the file and the line (exit 1,
//! nothing written), or calibrated with the suspect configurations flagged by arm and id (and left
//! out by `--auto-exclude`), or calibrated with a warning; never a panic. Also: outputs that would
//! replace an input or cannot be written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const EXAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example");

fn dualcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run dualcal")
}

/// A copy of the example in a temporary directory.
struct Case {
    _tmp: tempfile::TempDir,
    dir: PathBuf,
}

impl Case {
    fn new() -> Self {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("data");
        std::fs::create_dir(&dir).unwrap();
        for f in ["dataset.toml", "left.csv", "right.csv"] {
            std::fs::copy(Path::new(EXAMPLE).join(f), dir.join(f)).unwrap();
        }
        Case { _tmp: tmp, dir }
    }

    fn file(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    fn text(&self, name: &str) -> String {
        std::fs::read_to_string(self.file(name)).unwrap()
    }

    fn write(&self, name: &str, text: &str) -> &Self {
        std::fs::write(self.file(name), text).unwrap();
        self
    }

    /// Edit the lines of a file (0-based indices; line `n` of the file is index `n − 1`).
    fn lines(&self, name: &str, edit: impl FnOnce(&mut Vec<String>)) -> &Self {
        let mut lines: Vec<String> = self.text(name).lines().map(String::from).collect();
        edit(&mut lines);
        self.write(name, &(lines.join("\n") + "\n"))
    }

    /// Edit the fields of line `line` (1-based) of a CSV.
    fn fields(&self, name: &str, line: usize, edit: impl FnOnce(&mut Vec<String>)) -> &Self {
        self.lines(name, |l| {
            let mut f: Vec<String> = l[line - 1].split(',').map(String::from).collect();
            edit(&mut f);
            l[line - 1] = f.join(",");
        })
    }

    fn manifest(&self, from: &str, to: &str) -> &Self {
        let text = self.text("dataset.toml");
        assert!(text.contains(from), "{from}");
        self.write("dataset.toml", &text.replacen(from, to, 1))
    }

    fn calibrate(&self, extra: &[&str]) -> (Output, PathBuf) {
        let out = self._tmp.path().join("params.json");
        let mut args = vec![
            "calibrate",
            self.dir.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ];
        args.extend(extra);
        (dualcal(&args), out)
    }
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Refused: exit 1, the message names every part of `parts` (e.g. `left.csv:13`), nothing written.
fn refused(name: &str, case: &Case, parts: &[&str]) {
    let (out, params) = case.calibrate(&[]);
    let (stdout, stderr) = text(&out);
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    assert_eq!(out.status.code(), Some(1), "{name}: {stdout}\n{stderr}");
    for p in parts {
        assert!(stderr.contains(p), "{name}: {p:?} not in {stderr}");
    }
    assert!(
        stderr.lines().all(|l| l.chars().count() < 600),
        "{name}: a message line quotes too much: {stderr}"
    );
    assert!(!params.exists(), "{name}: a parameter file was written");
}

/// Calibrated with `ids` flagged (and `words` in the report); `--auto-exclude` leaves them out.
fn flagged(name: &str, case: &Case, ids: &[&str], words: &[&str]) {
    let (out, params) = case.calibrate(&[]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{name}: {stdout}\n{stderr}");
    let all = format!("{stdout}{stderr}");
    for w in ids.iter().chain(words) {
        assert!(all.contains(w), "{name}: {w:?} not in\n{all}");
    }
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&params).unwrap()).unwrap();
    let flags = file["quality"]["flags"].as_array().unwrap();
    for id in ids {
        assert!(
            flags.iter().any(|f| f["id"] == *id),
            "{name}: {id} not in the file's flags"
        );
    }
    let (out, params) = case.calibrate(&["--auto-exclude"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{name}: {stdout}\n{stderr}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&params).unwrap()).unwrap();
    let excluded: Vec<&str> = file["quality"]["excluded"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_str().unwrap())
        .collect();
    assert_eq!(
        excluded, ids,
        "{name}: --auto-exclude left out {excluded:?}"
    );
}

/// Calibrated (exit 0) with a warning naming `words`.
/// `calibrate` succeeds and warns with all of `words`, each warning once.
fn warned(name: &str, case: &Case, words: &[&str]) {
    let (out, _) = case.calibrate(&[]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{name}: {stdout}\n{stderr}");
    for w in words {
        assert!(stderr.contains(w), "{name}: {w:?} not in\n{stderr}");
    }
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    for (k, w) in warnings.iter().enumerate() {
        assert!(
            !warnings[..k].contains(w),
            "{name}: printed twice: {w}\n{stderr}"
        );
    }
}

// Rows of the example: L001 is on line 3, L0nn on line nn + 2. Columns: 0 id, 1–7 q1..q7 (deg),
// 8–16 ax..cz (mm), 17 split.

#[test]
fn missing_empty_and_header_only_files() {
    let c = Case::new();
    std::fs::remove_file(c.file("dataset.toml")).unwrap();
    refused("no manifest", &c, &["dataset.toml", "cannot read"]);
    refused(
        "empty csv",
        Case::new().write("left.csv", ""),
        &["left.csv", "empty"],
    );
    refused(
        "header only",
        Case::new().lines("left.csv", |l| l.truncate(2)),
        &["left.csv", "0 configurations"],
    );
    let c = Case::new();
    std::fs::remove_file(c.file("right.csv")).unwrap();
    refused("missing csv", &c, &["right.csv", "cannot read"]);
}

#[test]
fn columns_rows_and_values() {
    refused(
        "missing column",
        Case::new().lines("left.csv", |l| {
            for x in l.iter_mut().skip(1) {
                let f: Vec<&str> = x.split(',').collect();
                *x = [&f[..16], &f[17..]].concat().join(",");
            }
        }),
        &["left.csv:2", "`split`", "cz"],
    );
    refused(
        "extra column",
        Case::new().lines("left.csv", |l| {
            for x in l.iter_mut().skip(1) {
                x.push_str(",1");
            }
        }),
        &["left.csv:2", "position 19"],
    );
    refused(
        "reordered columns",
        Case::new().fields("left.csv", 2, |f| f.swap(1, 2)),
        &["left.csv:2", "`q2` is in position 2"],
    );
    refused(
        "short row",
        Case::new().fields("left.csv", 17, |f| {
            f.pop();
            f.pop();
        }),
        &["left.csv:17", "expected 18 fields", "found 16"],
    );
    refused(
        "long row",
        Case::new().fields("left.csv", 18, |f| f.push("7".into())),
        &["left.csv:18", "found 19"],
    );
    refused(
        "not a number",
        Case::new().fields("left.csv", 19, |f| f[3] = "12.5.1".into()),
        &["left.csv:19", "`q3`", "12.5.1"],
    );
    refused(
        "NaN",
        Case::new().fields("right.csv", 20, |f| f[12] = "NaN".into()),
        &["right.csv:20", "`by`", "not a finite number"],
    );
    refused(
        "infinity",
        Case::new().fields("right.csv", 21, |f| f[5] = "-inf".into()),
        &["right.csv:21", "`q5`"],
    );
    refused(
        "absurd coordinate",
        Case::new().fields("left.csv", 21, |f| f[9] = "1e12".into()),
        &["left.csv:21", "`ay`", "1e12"],
    );
    refused(
        "absurd joint value",
        Case::new().fields("left.csv", 22, |f| f[6] = "-9e9".into()),
        &["left.csv:22", "`q6`"],
    );
    refused(
        "unknown split",
        Case::new().fields("left.csv", 23, |f| f[17] = "test".into()),
        &["left.csv:23", "`split`"],
    );
}

#[test]
fn duplicates() {
    refused(
        "duplicate id",
        Case::new().fields("left.csv", 30, |f| f[0] = "L003".into()),
        &["left.csv:30", "duplicate id `L003`", "line 5"],
    );
    refused(
        "row pasted twice",
        Case::new().lines("left.csv", |l| {
            let row = l[9].replacen("L008", "L008b", 1);
            l.push(row);
        }),
        &["left.csv:223", "L008b", "left.csv:10", "pasted twice"],
    );
    // A left row pasted into the right file.
    let c = Case::new();
    let row = c
        .text("left.csv")
        .lines()
        .nth(40)
        .unwrap()
        .replacen("L039", "R999", 1);
    c.lines("right.csv", |l| l.push(row));
    refused(
        "row of the other file",
        &c,
        &["right.csv:223", "left.csv:41"],
    );
}

#[test]
fn manifest_problems() {
    refused(
        "unknown length unit",
        Case::new().manifest("length = \"mm\"", "length = \"inch\""),
        &["dataset.toml:4", "units.length", "inch"],
    );
    refused(
        "unknown format tag",
        Case::new().manifest("dualcal-dataset/1", "dualcal-dataset/7"),
        &["dataset.toml:1", "format", "dualcal-dataset/7"],
    );
    refused(
        "TOML syntax error",
        Case::new().manifest("angle = \"deg\"", "angle = \"deg"),
        &["dataset.toml:5"],
    );
    refused(
        "duplicate arm",
        Case::new().manifest("name = \"right\"", "name = \"left\""),
        &["dataset.toml:21", "duplicate arm"],
    );
    let c = Case::new();
    c.manifest("file = \"left.csv\"", "file = \"../../../../etc/passwd\"");
    refused(
        "data file outside the directory",
        &c,
        &[
            "dataset.toml:18",
            "arms.file",
            "outside the dataset directory",
        ],
    );
    let (out, _) = c.calibrate(&[]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("root:"));
    refused(
        "metres declared as millimetres",
        Case::new().lines("left.csv", |l| {
            for x in l.iter_mut().skip(2) {
                let mut f: Vec<String> = x.split(',').map(String::from).collect();
                for v in &mut f[8..17] {
                    *v = format!("{}", v.parse::<f64>().unwrap() / 1000.0);
                }
                *x = f.join(",");
            }
        }),
        &["left.csv", "look like metres", "units.length"],
    );
    refused(
        "radians declared as degrees",
        Case::new()
            .lines("left.csv", |l| {
                for x in l.iter_mut().skip(2) {
                    let mut f: Vec<String> = x.split(',').map(String::from).collect();
                    for v in &mut f[1..8] {
                        *v = format!("{}", v.parse::<f64>().unwrap().to_radians());
                    }
                    *x = f.join(",");
                }
            })
            .lines("right.csv", |l| {
                for x in l.iter_mut().skip(2) {
                    let mut f: Vec<String> = x.split(',').map(String::from).collect();
                    for v in &mut f[1..8] {
                        *v = format!("{}", v.parse::<f64>().unwrap().to_radians());
                    }
                    *x = f.join(",");
                }
            }),
        &["left.csv", "nominal model disagrees", "fit as radians"],
    );
}

#[test]
fn encodings_and_truncation() {
    let c = Case::new();
    let bytes = std::fs::read(c.file("left.csv")).unwrap();
    let mut bad = bytes.clone();
    let pos = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(6)
        .unwrap()
        .0
        + 3;
    bad[pos] = 0xFF; // on line 8
    std::fs::write(c.file("left.csv"), bad).unwrap();
    refused("invalid UTF-8", &c, &["left.csv:8", "UTF-8"]);
    let c = Case::new();
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(
            String::from_utf8(bytes.clone())
                .unwrap()
                .encode_utf16()
                .flat_map(u16::to_le_bytes),
        )
        .collect();
    std::fs::write(c.file("right.csv"), utf16).unwrap();
    refused("UTF-16", &c, &["right.csv", "UTF-16", "save it as UTF-8"]);
    let c = Case::new();
    let text = c.text("left.csv");
    let cut = &text[..text.len() - 60];
    c.write("left.csv", cut);
    refused("cut off mid-row", &c, &["left.csv:222", "cut off"]);
    // CRLF line ends and a byte-order mark are fine.
    let c = Case::new();
    let crlf = format!("\u{feff}{}", c.text("left.csv").replace('\n', "\r\n"));
    c.write("left.csv", &crlf);
    let (out, params) = c.calibrate(&[]);
    assert!(out.status.success(), "{}", text_of(&out));
    assert!(params.exists());
}

fn text_of(out: &Output) -> String {
    let (a, b) = text(out);
    format!("{a}\n{b}")
}

#[test]
fn geometry_and_robot_problems() {
    refused(
        "joint outside its limits",
        Case::new().fields("left.csv", 13, |f| f[4] = "212.0".into()),
        &["left.csv:13", "`q4`", "212.00°", "limits"],
    );
    refused(
        "collinear reflectors",
        Case::new().fields("left.csv", 31, |f| {
            for c in 0..3 {
                let (a, b): (f64, f64) = (f[8 + c].parse().unwrap(), f[11 + c].parse().unwrap());
                f[14 + c] = format!("{}", 2.0 * b - a);
            }
        }),
        &["left.csv:31", "collinear"],
    );
    refused(
        "coincident reflectors",
        Case::new().fields("right.csv", 40, |f| {
            for c in 0..3 {
                f[11 + c] = f[8 + c].clone();
            }
        }),
        &["right.csv:40", "a and b", "apart"],
    );
    refused(
        "fewer configurations than the parameters need",
        Case::new().lines("left.csv", |l| {
            for (i, x) in l.iter_mut().enumerate().skip(2) {
                if i >= 7 {
                    *x = x.replace(",cal", ",ver");
                }
            }
        }),
        &["left arm", "5 configurations", "at least 6"],
    );
    // A robot description that is UTF-16.
    let c = Case::new();
    let urdf: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(
            dualcal::robot::BUILTIN_IRB14000_URDF
                .encode_utf16()
                .flat_map(u16::to_le_bytes),
        )
        .collect();
    std::fs::write(c.file("robot.urdf"), urdf).unwrap();
    c.manifest("[units]", "robot = \"robot.urdf\"\n\n[units]");
    refused("UTF-16 robot", &c, &["robot.urdf", "UTF-16"]);
}

#[test]
fn outliers_are_flagged_and_left_out() {
    // A reflector triangle 25 mm off.
    flagged(
        "triangle 25 mm off",
        Case::new().fields("left.csv", 41, |f| {
            f[13] = format!("{}", f[13].parse::<f64>().unwrap() + 25.0)
        }),
        &["L039"],
        &["reflector b"],
    );
    // A reflector misread by 0.8 mm.
    flagged(
        "misread by 0.8 mm",
        Case::new().fields("right.csv", 70, |f| {
            f[15] = format!("{}", f[15].parse::<f64>().unwrap() + 0.8)
        }),
        &["R068"],
        &["reflector c"],
    );
    // Labels b and c swapped in one row.
    flagged(
        "labels swapped",
        Case::new().fields("left.csv", 60, |f| {
            for c in 0..3 {
                f.swap(11 + c, 14 + c);
            }
        }),
        &["L058"],
        &["labels look swapped (b↔c)"],
    );
    // Two joint columns swapped in one row (both values within either joint's limits).
    flagged(
        "joints swapped",
        Case::new().fields("left.csv", 53, |f| f.swap(5, 6)),
        &["L051"],
        &["q5 and q6 look swapped"],
    );
    // A re-measured row of the right arm in the left arm's file.
    let c = Case::new();
    let mut row: Vec<String> = c
        .text("right.csv")
        .lines()
        .nth(11)
        .unwrap()
        .split(',')
        .map(String::from)
        .collect();
    row[0] = "L221".into();
    for v in &mut row[8..17] {
        *v = format!("{}", v.parse::<f64>().unwrap() + 0.004);
    }
    c.lines("left.csv", |l| l.push(row.join(",")));
    flagged(
        "row of the other arm",
        &c,
        &["L221"],
        &["right arm's measurements"],
    );
}

#[test]
fn frames_that_moved_are_reported() {
    // The tracker bumped (0.3 mm, 0.05°) after the 110th left configuration.
    let bump = |f: &mut Vec<String>| {
        let (c, s) = (0.05f64.to_radians().cos(), 0.05f64.to_radians().sin());
        for k in 0..3 {
            let x: f64 = f[8 + 3 * k].parse().unwrap();
            let y: f64 = f[9 + 3 * k].parse().unwrap();
            f[8 + 3 * k] = format!("{}", c * x - s * y + 0.3);
            f[9 + 3 * k] = format!("{}", s * x + c * y);
        }
    };
    let c = Case::new();
    c.lines("left.csv", |l| {
        for x in l.iter_mut().skip(112) {
            let mut f: Vec<String> = x.split(',').map(String::from).collect();
            bump(&mut f);
            *x = f.join(",");
        }
    });
    warned(
        "tracker bumped",
        &c,
        &["left.csv", "moved between lines 112 and 113"],
    );
    // The right arm measured from another tracker position.
    let c = Case::new();
    c.lines("right.csv", |l| {
        for x in l.iter_mut().skip(2) {
            let mut f: Vec<String> = x.split(',').map(String::from).collect();
            for k in 0..3 {
                f[8 + 3 * k] = format!("{}", f[8 + 3 * k].parse::<f64>().unwrap() + 150.0);
            }
            *x = f.join(",");
        }
    });
    warned("arms in two frames", &c, &["one tracker position", "148."]);
}

#[test]
fn the_bundled_example_is_clean() {
    let c = Case::new();
    let (out, params) = c.calibrate(&[]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(!stdout.contains("Suspect"), "{stdout}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(params).unwrap()).unwrap();
    assert_eq!(file["quality"]["flags"].as_array().unwrap().len(), 0);
}

#[test]
fn exclude_by_id() {
    let c = Case::new();
    let (out, params) = c.calibrate(&["--exclude", "L011,right:R042"]);
    assert!(out.status.success(), "{}", text_of(&out));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(params).unwrap()).unwrap();
    let ids: Vec<&str> = file["method"]["excluded"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, ["L011", "R042"]);
    // Unknown ids are refused.
    let (out, params) = c.calibrate(&["--exclude", "L011,X7"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no configuration with id `X7`"));
    let _ = params;
}

#[test]
fn outputs_never_replace_inputs_and_failures_keep_the_old_file() {
    let c = Case::new();
    let data = c.dir.to_str().unwrap();
    let before = std::fs::read(c.file("left.csv")).unwrap();
    // --out over an input, --urdf over --out.
    let left = c.file("left.csv");
    let out = dualcal(&["calibrate", data, "--out", left.to_str().unwrap(), "-q"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("refusing to overwrite the input"));
    assert_eq!(std::fs::read(&left).unwrap(), before);
    let p = c._tmp.path().join("p.json");
    let out = dualcal(&[
        "calibrate",
        data,
        "--out",
        p.to_str().unwrap(),
        "--urdf",
        p.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text_of(&out));
    assert!(!p.exists());
    // An output that is a directory, and one in a missing directory.
    let d = c._tmp.path().join("outdir");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(d.join("keep"), "x").unwrap();
    let out = dualcal(&["calibrate", data, "--out", d.to_str().unwrap(), "-q"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The reason once (the error chain once printed it twice).
    assert_eq!(
        stderr.matches("the output path is a directory").count(),
        1,
        "{}",
        text_of(&out)
    );
    assert!(d.join("keep").exists());
    let missing = c._tmp.path().join("no/such/dir/p.json");
    let out = dualcal(&["calibrate", data, "--out", missing.to_str().unwrap(), "-q"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("nothing was written"),
        "{}",
        text_of(&out)
    );
}
