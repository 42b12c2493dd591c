//! Robot descriptions as they come (issue 45): a mobile manipulator's lifting column whose measured
//! joint is a virtual leader on a side branch (`column_base → column_pseudo_tip`), the column's two
//! real stages on the arm's chain mimicking it. The leader is the arm's first joint column; the
//! description loads, its forward kinematics equal an independent parser's (`tools/urdf_fk.py`), the
//! simulator and the planner draw the column within the leader's limits, the calibration recovers
//! the simulated errors to the noise floor, and the calibrated URDF keeps every `<mimic>` as written
//! and the leader's origin as it was.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Dataset, Split, Units};
use dualcal::metrics::evaluate;
use dualcal::plan::{PlanOptions, plan_arm};
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{default_reflectors_for, paper_options, simulate_with_robot};
use dualcal::solver::CalibrationSettings;
use dualcal::workspace::Workspace;
use nalgebra::{Isometry3, Matrix4, Vector3};
use std::path::Path;
use std::process::Command;

const LEADER: &str = "column_prismatic_joint";

/// The column robot as a one-arm robot: its one chain stands for both sides (the simulator's form).
fn load(urdf: &Path) -> RobotDescription {
    let (base, tip) = robots::COLUMN_MIMIC_ARM;
    let links = ArmLinks::new(base, tip);
    RobotDescription::load(
        urdf,
        &LoadOptions {
            arms: PerSide::new(Some(links.clone()), Some(links)),
            ..Default::default()
        },
    )
    .unwrap()
}

/// Tip poses (base link frame, mm) of `qs` (URDF units: m for the column) by `tools/urdf_fk.py`,
/// and the joints it reads the values as.
fn independent_tips(urdf: &Path, qs: &[Vec<f64>], dir: &Path) -> (Vec<String>, Vec<Matrix4<f64>>) {
    let (base, tip) = robots::COLUMN_MIMIC_ARM;
    let v = common::urdf_fk(urdf, base, tip, qs, &[], &dir.join("configs.json"));
    let joints = v["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    let tips = v["configs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| Matrix4::from_fn(|i, j| c["tip"][i][j].as_f64().unwrap()))
        .collect();
    (joints, tips)
}

/// Values in the URDF's units: metres for a prismatic joint's mm.
fn urdf_units(q: &[f64], linear: &[bool]) -> Vec<f64> {
    q.iter()
        .zip(linear)
        .map(|(&v, &l)| if l { v / 1000.0 } else { v })
        .collect()
}

/// Every `<mimic …/>` element of `text`, as written.
fn mimics(text: &str) -> Vec<&str> {
    text.match_indices("<mimic")
        .map(|(i, _)| &text[i..i + text[i..].find("/>").unwrap() + 2])
        .collect()
}

/// The `<joint name="NAME" …>…</joint>` element of `text`, as written.
fn joint_element<'a>(text: &'a str, name: &str) -> &'a str {
    let start = text.find(&format!("<joint name=\"{name}\"")).unwrap();
    let end = start + text[start..].find("</joint>").unwrap() + "</joint>".len();
    &text[start..end]
}

#[test]
fn a_column_with_a_virtual_leader_loads_and_poses_as_an_independent_parser_does() {
    let dir = tempfile::tempdir().unwrap();
    let text = robots::column_mimic_urdf();
    let urdf = robots::write_file(dir.path(), "column.urdf", text.as_bytes());
    let robot = load(&urdf);
    let spec = robot.arm(Side::Left);
    assert_eq!(spec.joint_names()[0], LEADER);
    assert_eq!(spec.joint_names().len(), 7);
    assert_eq!(
        spec.linear_joints(),
        [true, false, false, false, false, false, false]
    );
    let (lo, hi) = robot.joint_limits_rad(Side::Left)[0];
    assert!((lo - 1412.0).abs() < 1e-9 && (hi - 2012.0).abs() < 1e-9);
    assert_eq!(
        robot.joint_limits_checked_rad(Side::Left)[0],
        (lo, hi),
        "a column's values are checked against its leader's limits"
    );
    // Several configurations over the limits: the model's tip equals the independent parser's.
    let limits = robot.joint_limits_rad(Side::Left);
    let qs: Vec<Vec<f64>> = (0..6)
        .map(|k| {
            limits
                .iter()
                .enumerate()
                .map(|(i, &(lo, hi))| {
                    let t = ((k * 7 + i * 3) % 11) as f64 / 10.0;
                    lo + t * (hi - lo)
                })
                .collect()
        })
        .collect();
    let linear = spec.linear_joints();
    let qs_urdf: Vec<Vec<f64>> = qs.iter().map(|q| urdf_units(q, &linear)).collect();
    let (joints, tips) = independent_tips(&urdf, &qs_urdf, dir.path());
    assert_eq!(joints, spec.joint_names());
    let nominal = robot.nominal_model(default_reflectors_for(&robot).to_vec());
    for (q, tip) in qs.iter().zip(&tips) {
        let ours = nominal.arm(Side::Left).base_from_flange(q).to_homogeneous();
        assert!((ours - tip).amax() < 1e-9, "{q:?}: {ours} vs {tip}");
    }
    // The robot's tree poses the leader's own link by its column too (the workbench's view): the
    // pseudo tip sits the column's value above the column base.
    let poses: std::collections::HashMap<String, Isometry3<f64>> =
        robot.link_poses(&qs[1], &[]).into_iter().collect();
    let rise = poses["column_base"].inverse() * poses["column_pseudo_tip"];
    assert!(
        (rise.translation.vector - Vector3::new(0.0, 0.0, qs[1][0])).norm() < 1e-9,
        "{rise}"
    );
}

/// `ds` with only the left arm's measurements, saved in `dir`, the robot and its chain named.
fn save_one_arm(ds: &Dataset, urdf: &Path, dir: &Path) {
    let mut one = ds.clone();
    one.robot = Some(urdf.to_path_buf());
    let (base, tip) = robots::COLUMN_MIMIC_ARM;
    one.arms.left.links = Some(ArmLinks::new(base, tip));
    one.arms.right = dataset::ArmData::not_measured(Side::Right);
    dataset::save(&one, dir, Units::MM_DEG).unwrap();
}

#[test]
fn a_column_with_a_virtual_leader_simulates_calibrates_and_exports_its_mimics_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let text = robots::column_mimic_urdf();
    let urdf = robots::write_file(dir.path(), "column.urdf", text.as_bytes());
    let robot = load(&urdf);
    let sim = simulate_with_robot(&paper_options(45, 300, 150), &robot).unwrap();
    let data = dir.path().join("data");
    save_one_arm(&sim.dataset, &urdf, &data);
    let ws = Workspace::load(&data, &Default::default()).unwrap();
    let ds = &ws.dataset;
    // The simulator drew the column within its leader's limits, over most of them.
    let column: Vec<f64> = ds
        .arms
        .left
        .measurements
        .iter()
        .map(|m| m.q_rad[0])
        .collect();
    assert!(
        column.iter().all(|v| (1412.0..=2012.0).contains(v)),
        "{column:?}"
    );
    let spread = column.iter().fold(f64::MIN, |a, &v| a.max(v))
        - column.iter().fold(f64::MAX, |a, &v| a.min(v));
    assert!(spread > 300.0, "{spread}");
    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(ds, &ws.nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.warnings());
    let rms = |m: &dualcal::kinematics::DualArmModel| {
        evaluate(ds, m, Split::Ver)
            .unwrap()
            .relative(Side::Left)
            .unwrap()
            .pos_rms_mm
    };
    let (n, t, c) = (rms(&ws.nominal), rms(&sim.truth), rms(&result.calibrated));
    eprintln!(
        "column: relative left on verification: nominal {n:.4}, truth {t:.4}, calibrated {c:.4} mm"
    );
    assert!(n > 10.0 * t, "the nominal model is not off: {n} vs {t}");
    assert!(c <= 1.1 * t, "calibrated {c} vs truth {t}");

    // The calibrated URDF: every <mimic> byte for byte, the leader's joint as written, the second
    // stage's origin moved by its correction (the first stage's is a rigid motion of the arm).
    let out_text = dualcal::urdf_export::calibrated_urdf(&ws.robot, &result.calibrated).unwrap();
    assert_eq!(mimics(&out_text), mimics(&text));
    assert_eq!(mimics(&text).len(), 3);
    assert_eq!(&mimics(&text)[..2], robots::COLUMN_MIMICS);
    assert_eq!(
        joint_element(&out_text, LEADER),
        joint_element(&text, LEADER)
    );
    assert_ne!(
        joint_element(&out_text, "column_top_joint"),
        joint_element(&text, "column_top_joint")
    );
    let out = dir.path().join("calibrated.urdf");
    std::fs::write(&out, &out_text).unwrap();
    common::assert_check_urdf(&out, "column with a virtual leader");
    // Read alone, the file is the calibrated model: here and in the independent parser.
    let back = load(&out);
    let again = back.nominal_model(vec![Vector3::zeros(); 3]);
    let linear = back.arm(Side::Left).linear_joints();
    let qs: Vec<Vec<f64>> = ds
        .arms
        .left
        .measurements
        .iter()
        .take(8)
        .map(|m| m.q_rad.clone())
        .collect();
    let qs_urdf: Vec<Vec<f64>> = qs.iter().map(|q| urdf_units(q, &linear)).collect();
    let (_, tips) = independent_tips(&out, &qs_urdf, dir.path());
    for (q, tip) in qs.iter().zip(&tips) {
        let calibrated = result
            .calibrated
            .arm(Side::Left)
            .base_from_flange(q)
            .to_homogeneous();
        let file = again.arm(Side::Left).base_from_flange(q).to_homogeneous();
        assert!((calibrated - file).amax() < 1e-6, "{q:?}");
        assert!((calibrated - tip).amax() < 1e-6, "{q:?}");
    }
}

/// The planner and `dualcal simulate --urdf` take the column's leader as the arm's first column.
#[test]
fn the_planner_and_the_command_line_simulator_draw_the_column_within_its_leader() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "column.urdf",
        robots::column_mimic_urdf().as_bytes(),
    );
    let robot = load(&urdf);
    let options = PlanOptions {
        per_arm: 15,
        candidates: 120,
        ..Default::default()
    };
    let plan = plan_arm(
        &robot,
        &default_reflectors_for(&robot),
        &options,
        Side::Left,
    )
    .unwrap();
    assert_eq!(plan.configs.len(), 15);
    for q in &plan.configs {
        assert_eq!(q.len(), 7);
        assert!((1412.0..=2012.0).contains(&q[0]), "{q:?}");
    }
    let (base, tip) = robots::COLUMN_MIMIC_ARM;
    let chain = format!("{base}:{tip}");
    let out = dir.path().join("sim");
    let run = Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .arg("simulate")
        .arg("--urdf")
        .arg(&urdf)
        .args(["--left", &chain, "--right", &chain, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let ds = dataset::load(&out).unwrap();
    assert!(!ds.arms.left.measurements.is_empty());
    for m in &ds.arms.left.measurements {
        assert_eq!(m.q_rad.len(), 7);
    }
}
