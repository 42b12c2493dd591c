//! The command line on a robot description of the user's own (written by the test): `simulate --urdf
//! --left --right` → `evaluate` → `calibrate --urdf --overlay`, and the refusals that name the link,
//! joint, column or command.

#[path = "fixtures/robots.rs"]
mod robots;

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

/// Run a command that must fail; its standard error.
fn fails(args: &[&str]) -> String {
    let out = dualcal(args);
    assert!(!out.status.success(), "dualcal {args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn pos_rms(json: &str) -> [f64; 3] {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    ["relative_left", "relative_right", "collaborative"]
        .map(|k| v[k]["pos_rms_mm"].as_f64().unwrap())
}

#[test]
fn a_dual_ur_robot_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "dual_ur.urdf",
        robots::dual_ur_like_urdf().as_bytes(),
    );
    let data = dir.path().join("sim");
    let out = ok(&[
        "simulate",
        "--urdf",
        s(&urdf),
        "--left",
        "left_base_link:left_ee_link",
        "--right",
        "right_base_link:right_ee_link",
        "--out",
        s(&data),
    ]);
    assert!(
        out.contains("left_base_link → left_ee_link (6 joints)"),
        "{out}"
    );
    let manifest = std::fs::read_to_string(data.join("dataset.toml")).unwrap();
    assert!(
        manifest.contains("base_link = \"right_base_link\"")
            && manifest.contains("tip_link = \"right_ee_link\"")
            && manifest.contains("dual_ur.urdf"),
        "{manifest}"
    );
    let csv = std::fs::read_to_string(data.join("left.csv")).unwrap();
    assert!(csv.contains("id,q1,q2,q3,q4,q5,q6,ax,"), "{csv}");

    let nominal = pos_rms(&ok(&[
        "evaluate",
        s(&data),
        "--nominal",
        "--split",
        "ver",
        "--json",
    ]));
    let truth_file = data.join("truth.json");
    let truth = pos_rms(&ok(&[
        "evaluate",
        s(&data),
        "--params",
        s(&truth_file),
        "--split",
        "ver",
        "--json",
    ]));
    let (p, cal, yaml) = (
        dir.path().join("p.json"),
        dir.path().join("cal.urdf"),
        dir.path().join("cal.yaml"),
    );
    ok(&[
        "calibrate",
        s(&data),
        "--out",
        s(&p),
        "--urdf",
        s(&cal),
        "--overlay",
        s(&yaml),
        "-q",
    ]);
    let calibrated = pos_rms(&ok(&[
        "evaluate",
        s(&data),
        "--params",
        s(&p),
        "--split",
        "ver",
        "--json",
    ]));
    for k in 0..3 {
        assert!(nominal[k] > 20.0 * truth[k], "{nominal:?} {truth:?}");
        assert!(calibrated[k] < 1.1 * truth[k], "{calibrated:?} {truth:?}");
    }
    // The parameter file is the chain form, the overlay names the changed joints.
    let params: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    assert_eq!(
        params["arms"]["left"]["chain"]["tip_link"],
        serde_json::json!("left_ee_link")
    );
    assert_eq!(
        params["arms"]["left"]["chain"]["joints"]
            .as_array()
            .unwrap()
            .len(),
        6
    );
    let overlay = std::fs::read_to_string(&yaml).unwrap();
    assert!(
        overlay.contains("format: \"dualcal-urdf-overlay/1\"")
            && overlay.contains("name: \"right_shoulder_pan_joint\"")
            && overlay.contains("link: \"reflector_a_left_ee_link\""),
        "{overlay}"
    );
    // The calibrated URDF as the robot of the same data is the calibrated model.
    let manifest = manifest.replace(s(&urdf), s(&cal));
    std::fs::write(data.join("dataset.toml"), manifest).unwrap();
    let from_file = pos_rms(&ok(&[
        "evaluate",
        s(&data),
        "--nominal",
        "--split",
        "ver",
        "--json",
    ]));
    for k in 0..3 {
        assert!(
            (from_file[k] - calibrated[k]).abs() < 1e-6,
            "{from_file:?} {calibrated:?}"
        );
    }
    // A DH parameter file does not fit this robot: refused naming the field.
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example/truth.json");
    let err = fails(&["evaluate", s(&data), "--params", s(&example)]);
    assert!(
        err.contains("arms.left.dh") && err.contains("built-in"),
        "{err}"
    );
}

#[test]
fn refusals_name_the_link_joint_column_or_command() {
    let dir = tempfile::tempdir().unwrap();
    let yumi = robots::write_yumi_like(dir.path());
    let out = dir.path().join("out");
    let simulate = |left: &str| {
        fails(&[
            "simulate",
            "--urdf",
            s(&yumi),
            "--left",
            left,
            "--right",
            "yumi_body:yumi_link_7_r",
            "--out",
            s(&out),
        ])
    };
    // A link that does not exist.
    let err = simulate("yumi_body:yumi_link_9_l");
    assert!(
        err.contains("`yumi_link_9_l`") && err.contains("yumi.urdf"),
        "{err}"
    );
    // A mimic joint whose leader is not on the chain (the gripper's second finger, following the first
    // finger's joint) is no refusal any more: the leader becomes the arm's joint column where its
    // follower stands (issue 45) — eight columns, the last the gripper's.
    let finger = dir.path().join("finger");
    ok(&[
        "simulate",
        "--urdf",
        s(&yumi),
        "--left",
        "yumi_body:gripper_l_finger_l",
        "--right",
        "yumi_body:yumi_link_7_r",
        "--configs",
        "30",
        "--cal",
        "20",
        "--out",
        s(&finger),
    ]);
    let header = std::fs::read_to_string(finger.join("left.csv")).unwrap();
    let header = header.lines().find(|l| l.starts_with("id,")).unwrap().to_string();
    assert!(header.contains(",q8,") && !header.contains(",q9,"), "{header}");
    // Not BASE:TIP.
    let err = simulate("yumi_body");
    assert!(err.contains("BASE:TIP"), "{err}");
    // A floating joint.
    let floating = robots::write_file(
        dir.path(),
        "floating.urdf",
        robots::yumi_like_urdf()
            .replace(
                "name=\"yumi_base_link_to_body\" type=\"fixed\"",
                "name=\"yumi_base_link_to_body\" type=\"floating\"",
            )
            .as_bytes(),
    );
    let err = fails(&[
        "simulate",
        "--urdf",
        s(&floating),
        "--left",
        "world:yumi_link_7_l",
        "--right",
        "yumi_body:yumi_link_7_r",
        "--out",
        s(&out),
    ]);
    assert!(
        err.contains("`yumi_base_link_to_body`") && err.contains("floating"),
        "{err}"
    );
    // A xacro file: the command to run first.
    let xacro = robots::write_file(dir.path(), "robot.urdf.xacro", b"<robot/>");
    let err = fails(&["simulate", "--urdf", s(&xacro), "--out", s(&out)]);
    assert!(
        err.contains("xacro") && err.contains("> robot.urdf"),
        "{err}"
    );

    // A dataset whose CSV has another joint count than its chain: names the CSV, columns, joints.
    let data = dir.path().join("sim");
    ok(&[
        "simulate",
        "--urdf",
        s(&yumi),
        "--out",
        s(&data),
        "--configs",
        "20",
        "--cal",
        "10",
    ]);
    let manifest = std::fs::read_to_string(data.join("dataset.toml")).unwrap();
    std::fs::write(
        data.join("dataset.toml"),
        manifest.replace(
            "tip_link = \"yumi_link_7_l\"",
            "tip_link = \"yumi_link_6_l\"",
        ),
    )
    .unwrap();
    let err = fails(&["evaluate", s(&data), "--nominal"]);
    assert!(
        err.contains("left.csv")
            && err.contains("q1 … q7")
            && err.contains("6 movable joints")
            && err.contains("yumi_joint_5_l"),
        "{err}"
    );
    // base_link without tip_link.
    std::fs::write(
        data.join("dataset.toml"),
        manifest.replace("tip_link = \"yumi_link_7_l\"\n", ""),
    )
    .unwrap();
    let err = fails(&["evaluate", s(&data), "--nominal"]);
    assert!(err.contains("arms.tip_link"), "{err}");
}
