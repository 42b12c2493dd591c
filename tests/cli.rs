//! The `dualcal` command line end to end: simulate → evaluate → calibrate → evaluate, exports, and
//! failures with a non-zero exit and a message naming the file.

use std::path::Path;
use std::process::{Command, Output};

fn dualcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run dualcal")
}

fn ok(args: &[&str]) -> String {
    let out = dualcal(args);
    assert!(
        out.status.success(),
        "dualcal {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}):\n{text}"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The command line's round trip on the paper's protocol (220 configurations per arm, 120 for
/// calibration): the calibrated parameters bring the verification accuracy to the noise floor (the
/// true parameters' figures), within 10% as every calibration test holds it.
#[test]
fn simulate_evaluate_calibrate_evaluate() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("sim");
    ok(&["simulate", "--out", s(&data), "--seed", "3"]);
    assert!(data.join("dataset.toml").is_file() && data.join("truth.json").is_file());

    // Refuses to overwrite without --force.
    let again = dualcal(&[
        "simulate",
        "--out",
        s(&data),
        "--seed",
        "4",
        "--configs",
        "60",
        "--cal",
        "40",
    ]);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("dataset.toml"));

    let nominal = json(&ok(&[
        "evaluate",
        s(&data),
        "--nominal",
        "--split",
        "ver",
        "--json",
    ]));
    let nominal_rms = nominal["relative_left"]["pos_rms_mm"].as_f64().unwrap();
    assert!(
        (0.5..20.0).contains(&nominal_rms),
        "nominal RMS {nominal_rms}"
    );
    for key in ["relative_left", "relative_right", "collaborative"] {
        for field in [
            "pos_rms_mm",
            "pos_max_mm",
            "ori_rms_rad",
            "ori_max_rad",
            "pos_within_0_3mm_frac",
            "pos_within_0_6mm_frac",
            "ori_within_0_005rad_frac",
            "ori_within_0_01rad_frac",
        ] {
            assert!(nominal[key][field].is_number(), "{key}.{field}");
        }
    }
    let table = ok(&["evaluate", s(&data), "--nominal"]);
    assert!(
        table.contains("collaborative") || table.contains("Collaborative"),
        "{table}"
    );

    let params = dir.path().join("params.json");
    let urdf = dir.path().join("calibrated.urdf");
    let out = ok(&[
        "calibrate",
        s(&data),
        "--out",
        s(&params),
        "--urdf",
        s(&urdf),
        "--quiet",
    ]);
    assert!(
        out.contains("fixed"),
        "identifiability report missing:\n{out}"
    );
    assert!(
        out.contains("verification"),
        "summary table missing:\n{out}"
    );
    let p = json(&std::fs::read_to_string(&params).unwrap());
    assert_eq!(p["format"], "dualcal-params/1");
    assert_eq!(p["arms"]["left"]["dh"].as_array().unwrap().len(), 7);
    assert!(
        p["fixed_parameters"]["left"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["name"] == "theta1")
    );
    assert!(urdf_rs::read_file(&urdf).is_ok());

    let after = json(&ok(&[
        "evaluate",
        s(&data),
        "--params",
        s(&params),
        "--split",
        "ver",
        "--json",
    ]));
    let truth = json(&ok(&[
        "evaluate",
        s(&data),
        "--params",
        s(data.join("truth.json").as_path()),
        "--split",
        "ver",
        "--json",
    ]));
    for key in ["relative_left", "relative_right", "collaborative"] {
        let t = truth[key]["pos_rms_mm"].as_f64().unwrap();
        let c = after[key]["pos_rms_mm"].as_f64().unwrap();
        let n = nominal[key]["pos_rms_mm"].as_f64().unwrap();
        // The nominal model starts far above the floor, so reaching it is the calibration's doing.
        assert!(n > 50.0 * t, "{key}: nominal {n} vs truth {t}");
        assert!(c <= 1.1 * t, "{key}: calibrated {c} vs truth {t}");
    }
}

#[test]
fn bad_inputs_fail_with_a_message_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // Missing dataset.
    let out = dualcal(&["evaluate", s(&dir.path().join("nope")), "--nominal"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope"));

    // A dataset with a broken CSV line.
    let data = dir.path().join("sim");
    ok(&[
        "simulate",
        "--out",
        s(&data),
        "--seed",
        "5",
        "--configs",
        "12",
        "--cal",
        "8",
    ]);
    let csv = data.join("left.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    // Corrupt one field of one data row (comment lines contain commas too).
    let broken: String = text
        .lines()
        .map(|l| {
            if l.starts_with("L003,") {
                l.replacen(',', ",x", 1)
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&csv, broken).unwrap();
    let out = dualcal(&[
        "calibrate",
        s(&data),
        "--out",
        s(&dir.path().join("p.json")),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("left.csv"), "{err}");
    assert!(!dir.path().join("p.json").exists());

    // Never overwrite an input.
    std::fs::write(&csv, text).unwrap();
    let before = std::fs::read(&csv).unwrap();
    let out = dualcal(&["calibrate", s(&data), "--out", s(&csv)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("refusing to overwrite the input") && err.contains("left.csv"),
        "{err}"
    );
    assert_eq!(std::fs::read(&csv).unwrap(), before);

    // A bad parameter file.
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"format\": \"dualcal-params/1\", \"arms\": 3}").unwrap();
    let out = dualcal(&["evaluate", s(&data), "--params", s(&bad)]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.json"));
}

#[test]
fn bundled_example_is_reproducible() {
    // The shipped example is exactly what `dualcal simulate --seed 1` writes.
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("ex");
    ok(&["simulate", "--out", s(&data), "--seed", "1"]);
    for f in ["dataset.toml", "left.csv", "right.csv", "truth.json"] {
        let a = std::fs::read_to_string(example.join(f)).unwrap();
        let b = std::fs::read_to_string(data.join(f)).unwrap();
        // truth.json carries a timestamp and path in its provenance; compare the parameters only.
        if f == "truth.json" {
            let (a, b) = (json(&a), json(&b));
            assert_eq!(a["arms"], b["arms"]);
            assert_eq!(a["right_base_in_left"], b["right_base_in_left"]);
        } else {
            assert!(a == b, "{f} differs from a fresh simulation");
        }
    }
}

/// `--timings` adds where the time went, on standard error, and changes nothing else.
#[test]
fn calibrate_timings_name_every_phase_and_change_nothing_else() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let dir = tempfile::tempdir().unwrap();
    let (plain, timed) = (dir.path().join("a.json"), dir.path().join("b.json"));
    let a = dualcal(&["calibrate", s(&example), "--out", s(&plain), "--quiet"]);
    let b = dualcal(&[
        "calibrate",
        s(&example),
        "--out",
        s(&timed),
        "--quiet",
        "--timings",
    ]);
    assert!(a.status.success() && b.status.success());
    let err = String::from_utf8_lossy(&b.stderr);
    let phases = [
        "load, checks, nominal model, screening",
        "calibration, the screening of its result, its uncertainty, the accuracy tables",
        "of which the calibration",
        "the parameter file's quality record",
        "writing",
        "total",
    ];
    let ms = |line: &str| -> f64 {
        let figure = line.split_whitespace().last().unwrap();
        figure.parse().unwrap_or_else(|_| panic!("{line}"))
    };
    for phase in phases {
        let line = err
            .lines()
            .find(|l| l.trim_start().starts_with(phase))
            .unwrap_or_else(|| panic!("no `{phase}` line in:\n{err}"));
        assert!(ms(line) >= 0.0, "{line}");
    }
    assert!(!String::from_utf8_lossy(&a.stderr).contains("timings"));
    // Standard output is the same but for the reported times and the file name.
    let strip = |o: &Output, out: &Path| -> Vec<String> {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.starts_with("total time"))
            .map(|l| l.replace(s(out), "OUT"))
            .collect()
    };
    assert_eq!(strip(&a, &plain), strip(&b, &timed));
}

/// `dualcal … | head`: a reader that goes away ends the command quietly (exit 141, like a Unix tool
/// killed by SIGPIPE), not with a panic.
#[test]
fn a_closed_output_pipe_ends_the_command_without_a_panic() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let mut child = Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(["evaluate", s(&example), "--nominal", "--split", "all"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run dualcal");
    // Close the read end before the process can have written anything (it still has to load the
    // dataset): its first write fails with EPIPE.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(141), "{stderr}");
}

/// A run that stops at the iteration limit is a result, not an error: the summary is printed, the
/// parameter file is written and marked `"converged": false`, each stage that did not converge gets a
/// warning, and the command exits with status 2 (1 is for errors).
#[test]
fn a_calibration_that_does_not_converge_writes_its_result_marked_and_exits_2() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("p.json");
    let out = dualcal(&[
        "calibrate",
        s(&example),
        "--out",
        s(&out_path),
        "--max-iterations",
        "2",
        "--quiet",
    ]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(2), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("iteration limit reached after 2 iterations"),
        "{stdout}"
    );
    assert!(
        stdout.contains("Accuracy on the verification configurations"),
        "{stdout}"
    );
    assert!(
        stderr.contains("warning: step 1 (left arm) stopped at the iteration limit"),
        "{stderr}"
    );
    assert!(stderr.contains("did not converge"), "{stderr}");
    let file = json(&std::fs::read_to_string(&out_path).unwrap());
    assert_eq!(file["converged"], serde_json::json!(false));
    let stops: Vec<&str> = file["termination"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["termination"].as_str().unwrap())
        .collect();
    assert_eq!(stops, ["MaxIterations"; 3]);

    // The converged run's file carries no marker.
    ok(&["calibrate", s(&example), "--out", s(&out_path), "--quiet"]);
    let file = json(&std::fs::read_to_string(&out_path).unwrap());
    assert!(file.get("converged").is_none(), "{file}");
}

/// The user's reflector names come back in the progress lines (`F_<name>`), the tables and the
/// parameter file — here a dataset whose reflectors are `front`, `left_smr` and `back`.
#[test]
fn reflector_names_in_progress_tables_and_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("named");
    ok(&[
        "simulate",
        "--out",
        s(&data),
        "--seed",
        "3",
        "--configs",
        "60",
        "--cal",
        "40",
    ]);
    let rename = |text: &str| {
        text.replace("\na = [", "\nfront = [")
            .replace("\nb = [", "\nleft_smr = [")
            .replace("\nc = [", "\nback = [")
            .replace(
                "ax,ay,az,bx,by,bz,cx,cy,cz",
                "frontx,fronty,frontz,left_smrx,left_smry,left_smrz,backx,backy,backz",
            )
    };
    for file in ["dataset.toml", "left.csv", "right.csv"] {
        let path = data.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let renamed = rename(&text);
        assert_ne!(renamed, text, "{file}: nothing renamed");
        std::fs::write(&path, renamed).unwrap();
    }
    let params = dir.path().join("p.json");
    let out = dualcal(&["calibrate", s(&data), "--out", s(&params)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    let line = stderr
        .lines()
        .find(|l| l.contains("ψ"))
        .unwrap_or_else(|| panic!("no progress line:\n{stderr}"));
    assert!(
        line.contains("F_front") && line.contains("F_left_smr") && line.contains("F_back"),
        "{line}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("left_smr"), "{stdout}");
    let p = json(&std::fs::read_to_string(&params).unwrap());
    let text = p.to_string();
    assert!(
        text.contains("\"left_smr\"") && !text.contains("\"t_a\""),
        "{text}"
    );
    // The single-reflector method takes a reflector by its name; an unknown name is refused with
    // the dataset's names.
    let single = dir.path().join("single.json");
    ok(&[
        "calibrate",
        s(&data),
        "--method",
        "distance-single",
        "--reflector",
        "left_smr",
        "--out",
        s(&single),
        "--quiet",
    ]);
    let used = json(&std::fs::read_to_string(&single).unwrap()).to_string();
    assert!(
        used.contains("\"b\""),
        "the second reflector is the one used: {used}"
    );
    let out = dualcal(&[
        "calibrate",
        s(&data),
        "--method",
        "distance-single",
        "--reflector",
        "nope",
        "--out",
        s(&dir.path().join("never.json")),
        "--quiet",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--reflector nope") && err.contains("front, left_smr, back"),
        "{err}"
    );
}

/// `--gear-ratio JOINT=RATIO` adds the motor's harmonics to a harmonic model: the command says which,
/// the parameter file carries the ratios and the terms, and `evaluate` reads the model back. A joint
/// the arms do not have, a ratio that is not a number, and a model without harmonics are refused
/// with a non-zero exit naming the option.
#[test]
fn gear_ratios_add_the_motors_harmonics() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("params.json");
    let out = ok(&[
        "calibrate",
        s(&example),
        "--model",
        "harmonic",
        "--gear-ratio",
        "j1=100,j2=-80",
        "--gear-ratio",
        "j4=1",
        "--quiet",
        "--out",
        s(&params),
    ]);
    assert!(
        out.contains(
            "motor-side harmonics (gear ratio, motor turns per joint turn): j1 100, j2 -80\n"
        ),
        "{out}"
    );
    let file = json(&std::fs::read_to_string(&params).unwrap());
    for side in ["left", "right"] {
        let errors = &file["arms"][side]["errors"];
        assert_eq!(errors["gear_ratios"]["j1"], 100.0);
        assert_eq!(errors["gear_ratios"]["j4"], 1.0);
        let names: Vec<&String> = errors["parameters"].as_object().unwrap().keys().collect();
        assert!(names.iter().any(|n| *n == "j2.m2_sin"), "{names:?}");
        assert!(!names.iter().any(|n| n.starts_with("j4.m")), "{names:?}");
    }
    ok(&["evaluate", s(&example), "--params", s(&params)]);
    for (args, expected) in [
        (
            vec!["--model", "harmonic", "--gear-ratio", "j9=100"],
            "`j9` is not a movable joint of either arm",
        ),
        (
            vec!["--model", "harmonic", "--gear-ratio", "j1=fast"],
            "expected a number",
        ),
        (
            vec!["--gear-ratio", "j1=100"],
            "the `geometric` model has no harmonics",
        ),
    ] {
        let refused = dir.path().join("refused.json");
        let mut all = vec!["calibrate", s(&example), "--out", s(&refused)];
        all.extend(args);
        let run = dualcal(&all);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{all:?}");
        assert!(stderr.contains(expected), "{all:?}: {stderr}");
        assert!(!refused.exists(), "{all:?} wrote its output");
    }
}
