//! One arm alone (issue 19): a dataset with a single `[[arms]]` entry — one arm of a dual-arm robot
//! calibrated on its own, or a single robot whose description has no second arm. Step 1 runs for the
//! measured arm and its relative figures are computed; step 2 and the collaborative figures are absent
//! (`null`, "not measurable"), never zero; the other arm keeps its nominal parameters; the calibrated
//! URDF keeps the robot and passes `check_urdf`.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Dataset, Split, Units};
use dualcal::metrics::evaluate;
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationSettings, Stage, planned_stages};
use dualcal::workspace::{Workspace, WorkspaceOptions};
use std::path::Path;
use std::process::Command;

fn dualcal() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dualcal"))
}

/// `dualcal calibrate DATA --out PARAMS --urdf URDF`: whether it succeeded, its stdout and stderr.
fn calibrate_cli(data: &Path, params: &Path, urdf: &Path) -> (bool, String, String) {
    let out = dualcal()
        .arg("calibrate")
        .arg(data)
        .arg("--out")
        .arg(params)
        .arg("--urdf")
        .arg(urdf)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `ds` with only `side`'s measurements, saved in `dir` (the manifest's one `[[arms]]` entry).
fn save_one_arm(ds: &Dataset, side: Side, dir: &Path) {
    let mut one = ds.clone();
    one.arms[side.other()] = dataset::ArmData::not_measured(side.other());
    dataset::save(&one, dir, Units::MM_DEG).unwrap();
    let manifest = std::fs::read_to_string(dir.join("dataset.toml")).unwrap();
    assert_eq!(manifest.matches("[[arms]]").count(), 1, "{manifest}");
    assert!(!dir.join(format!("{}.csv", side.other())).exists());
}

/// Calibrate the one-arm dataset in `dir`; the measured arm within 10% of the truth's relative RMS on
/// the verification split, the nominal far off; nothing for the other arm, the base or the
/// collaborative pairs.
fn check_one_arm(
    dir: &Path,
    options: &WorkspaceOptions,
    side: Side,
    truth: &dualcal::kinematics::DualArmModel,
    name: &str,
) -> dualcal::solver::CalibrationResult {
    let ws = Workspace::load(dir, options).unwrap();
    let ds = &ws.dataset;
    assert_eq!(ds.measured_sides(), vec![side], "{name}");
    assert!(!ds.both_measured() && !ds.one_tracker_frame());
    assert_eq!(planned_stages(ds, &ws.nominal), vec![Stage::Arm(side)]);
    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(ds, &ws.nominal, &settings);
    assert!(result.is_converged(), "{name}: {:?}", result.warnings());
    assert_eq!(result.stages.len(), 1, "{name}");
    let why = result.base_not_measurable.as_deref().unwrap();
    assert!(why.contains(&format!("only the {side} arm")), "{why}");
    // The other arm and the base stay nominal: no calibration result (a single robot's other side
    // is its one arm, the arm calibrated; on a torso the other arm's copy of the shared joints follows
    // the measured arm's).
    let shared = ws.nominal.shared_joints();
    let measured = result.calibrated.arm(side).to_vector();
    let mut other = if ws.nominal.is_one_arm() {
        measured.clone()
    } else {
        ws.nominal.arm(side.other()).to_vector()
    };
    for &(a, b) in &shared.params {
        let (from, to) = match side {
            Side::Left => (a, b),
            Side::Right => (b, a),
        };
        other[to] = measured[from];
    }
    assert_eq!(
        result.calibrated.arm(side.other()).to_vector(),
        other,
        "{name}"
    );
    assert_eq!(
        result.calibrated.left_base_from_right_base,
        ws.nominal.left_base_from_right_base
    );
    let at = |m: &dualcal::kinematics::DualArmModel| evaluate(ds, m, Split::Ver).unwrap();
    let (n, t, c) = (at(&ws.nominal), at(truth), at(&result.calibrated));
    for r in [&n, &t, &c] {
        assert!(r.relative(side.other()).is_none(), "{name}: {r:?}");
        assert!(r.collaborative.is_none(), "{name}");
    }
    let rms = |r: &dualcal::metrics::AccuracyReport| r.relative(side).unwrap().pos_rms_mm;
    eprintln!(
        "{name}: relative {side} on verification: nominal {:.4} mm, truth {:.4} mm, calibrated {:.4} mm",
        rms(&n),
        rms(&t),
        rms(&c)
    );
    assert!(rms(&c) <= 1.1 * rms(&t), "{name}");
    assert!(
        rms(&n) > 10.0 * rms(&t),
        "{name}: the nominal model is not off"
    );
    // Only the measured arm's uncertainty.
    let sigma = dualcal::solver::uncertainty::for_result(ds, &result);
    assert!(
        sigma[side].is_some() && sigma[side.other()].is_none(),
        "{name}"
    );
    result
}

#[test]
fn one_arm_of_the_built_in_robot() {
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(41, 200, 100), &robot).unwrap();
    for side in Side::BOTH {
        let out = dir.path().join(side.name());
        save_one_arm(&sim.dataset, side, &out);
        check_one_arm(
            &out,
            &Default::default(),
            side,
            &sim.truth,
            &format!("IRB 14000, {side} arm alone"),
        );
    }
}

#[test]
fn the_command_line_on_one_arm() {
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(42, 150, 80), &robot).unwrap();
    let data = dir.path().join("right-alone");
    save_one_arm(&sim.dataset, Side::Right, &data);
    let params = dir.path().join("params.json");
    let urdf = dir.path().join("calibrated.urdf");
    let (ok, stdout, stderr) = calibrate_cli(&data, &params, &urdf);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("step 1 (right arm): converged"), "{stdout}");
    assert!(!stdout.contains("step 1 (left arm)"), "{stdout}");
    assert!(
        stdout.contains("relative left: not measurable from this data")
            && stdout.contains("collaborative: not measurable from this data"),
        "{stdout}"
    );
    assert!(
        stdout.contains("only the right arm was measured"),
        "{stdout}"
    );
    common::assert_check_urdf(&urdf, "one-arm calibration");
    // `evaluate --json`: the absent figures are null, never zero.
    let out = dualcal()
        .args(["evaluate", "--json"])
        .arg(&data)
        .arg("--params")
        .arg(&params)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["relative_left"].is_null(), "{json}");
    assert!(json["collaborative"].is_null(), "{json}");
    assert!(json["relative_right"]["pos_rms_mm"].as_f64().unwrap() < 0.05);
    // The report: only the measured arm's sections.
    let report = dir.path().join("report.html");
    let out = dualcal()
        .arg("report")
        .arg(&data)
        .arg("--params")
        .arg(&params)
        .arg("--out")
        .arg(&report)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.contains("one arm measured alone (right)"));
    assert!(!html.contains("<h3>left arm</h3>"));
}

#[test]
fn a_single_robot_with_no_second_arm() {
    let dir = tempfile::tempdir().unwrap();
    let urdf_path = dir.path().join("single_ur.urdf");
    std::fs::write(&urdf_path, robots::single_ur_like_urdf()).unwrap();
    let (base, tip) = robots::SINGLE_UR_ARM;
    let links = ArmLinks::new(base, tip);
    // The simulator needs two sides: the one arm's chain stands for both (only the left's data are
    // kept).
    let robot = RobotDescription::load(
        urdf_path.as_path(),
        &LoadOptions {
            arms: PerSide::new(Some(links.clone()), Some(links.clone())),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(robot.is_one_arm());
    let sim = simulate_with_robot(&paper_options(43, 200, 100), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    ds.robot = Some(urdf_path.clone());
    ds.arms.left.links = Some(links);
    let data = dir.path().join("data");
    save_one_arm(&ds, Side::Left, &data);
    // Without a second arm the description alone names no arms: it loads for the one-arm dataset.
    assert!(RobotDescription::load(urdf_path.as_path(), &LoadOptions::default()).is_err());
    check_one_arm(
        &data,
        &Default::default(),
        Side::Left,
        &sim.truth,
        "single UR-like robot",
    );

    let params = dir.path().join("params.json");
    let out_urdf = dir.path().join("calibrated.urdf");
    let (ok, stdout, stderr) = calibrate_cli(&data, &params, &out_urdf);
    let text = format!("{stdout}\n{stderr}");
    assert!(ok, "{text}");
    assert!(
        text.contains("one arm arm_base_link → arm_ee_link (6 joints)"),
        "{text}"
    );
    assert!(!text.contains("shared by both arms"), "{text}");
    common::assert_check_urdf(&out_urdf, "single robot");
    // The calibrated URDF keeps the robot: every link and joint, the reflectors once, the joint
    // origins moved by calibration-sized amounts.
    let written = std::fs::read_to_string(&out_urdf).unwrap();
    let original = robots::single_ur_like_urdf();
    for name in [
        "shoulder_pan",
        "shoulder_lift",
        "elbow",
        "wrist_1",
        "wrist_2",
        "wrist_3",
    ] {
        assert!(written.contains(&format!("name=\"arm_{name}_joint\"")));
    }
    assert_eq!(
        written
            .matches("<link name=\"reflector_a_arm_ee_link\"")
            .count(),
        1,
        "{written}"
    );
    let count = |text: &str| text.matches("<link ").count();
    assert_eq!(count(&written), count(&original) + 3);
    let back = RobotDescription::load(
        out_urdf.as_path(),
        &LoadOptions {
            arms: PerSide::new(Some(ArmLinks::new(base, tip)), None),
            ..Default::default()
        },
    );
    assert!(
        back.is_err(),
        "still one arm: the description alone names none"
    );
    let ws = Workspace::load(
        &data,
        &WorkspaceOptions {
            robot: Some(out_urdf.clone()),
            ..Default::default()
        },
    )
    .unwrap();
    let before = Workspace::load(&data, &Default::default()).unwrap();
    let moved_mm = ws
        .nominal
        .arm(Side::Left)
        .reflector_fk(&[0.3; 6])
        .points_mm
        .iter()
        .zip(
            before
                .nominal
                .arm(Side::Left)
                .reflector_fk(&[0.3; 6])
                .points_mm,
        )
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        moved_mm > 0.05 && moved_mm < 20.0,
        "calibration-sized change: {moved_mm} mm"
    );
}

#[test]
fn one_arm_of_a_robot_on_a_shared_torso() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("torso.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(false)).unwrap();
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let arms = PerSide::new(Some(ArmLinks::new(lb, lt)), Some(ArmLinks::new(rb, rt)));
    let robot = RobotDescription::load(
        urdf.as_path(),
        &LoadOptions {
            arms: arms.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    let sim = simulate_with_robot(&paper_options(44, 250, 150), &robot).unwrap();
    let data = dir.path().join("data");
    save_one_arm(&sim.dataset, Side::Right, &data);
    let options = WorkspaceOptions {
        robot: Some(urdf.clone()),
        arms,
        ..Default::default()
    };
    let result = check_one_arm(
        &data,
        &options,
        Side::Right,
        &sim.truth,
        "torso, right arm alone",
    );
    // The right arm's fit moved the waist; the calibrated URDF changes it once and loads back.
    let ws = Workspace::load(&data, &options).unwrap();
    let text = dualcal::urdf_export::calibrated_urdf(&ws.robot, &result.calibrated).unwrap();
    let out = dir.path().join("calibrated.urdf");
    std::fs::write(&out, &text).unwrap();
    common::assert_check_urdf(&out, "torso, one arm");
    assert_eq!(
        text.matches("<joint name=\"yumi_base_link_to_body\"")
            .count(),
        1
    );
}
