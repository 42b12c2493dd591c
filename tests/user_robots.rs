//! The user's own robot description, end to end, on robots the tests write themselves: a YuMi-like
//! URDF (the public `yumi_description`'s joint-origin structure, meshes behind `package://`) and a
//! dual-UR-like one (6-joint arms with parallel axes, on a table). For each: simulate → save → load
//! → calibrate → verification accuracy within 10% of the noise floor; the calibrated URDF changes
//! only the arm joints' origins, each by its correction, keeps every other byte, and — read alone by
//! an independent parser (`tools/urdf_fk.py`, numpy) — reproduces the calibrated accuracy.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Split, Units};
use dualcal::kinematics::DualArmModel;
use dualcal::metrics::{AccuracyReport, evaluate};
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::CalibrationSettings;
use dualcal::urdf_export::calibrated_urdf;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

fn links(arms: [(&str, &str); 2]) -> PerSide<Option<ArmLinks>> {
    PerSide::new(
        Some(ArmLinks::new(arms[0].0, arms[0].1)),
        Some(ArmLinks::new(arms[1].0, arms[1].1)),
    )
}

/// Reflector positions (base link frame, mm) of `side`'s configurations of `split`, computed by
/// `tools/urdf_fk.py` from the URDF file alone.
fn independent_points(
    urdf: &Path,
    arm: &ArmLinks,
    qs: &[Vec<f64>],
    dir: &Path,
) -> Vec<Vec<Vector3<f64>>> {
    let names: Vec<String> = ["a", "b", "c"]
        .iter()
        .map(|r| format!("reflector_{r}_{}", arm.tip_link))
        .collect();
    let v = common::urdf_fk(
        urdf,
        &arm.base_link,
        &arm.tip_link,
        qs,
        &names,
        &dir.join(format!("{}.json", arm.tip_link)),
    );
    v["configs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (0..names.len())
                .map(|k| {
                    let p = &c["links"][&names[k]];
                    Vector3::from_fn(|i, _| p[i].as_f64().unwrap())
                })
                .collect()
        })
        .collect()
}

/// Relative positioning RMS (largest reflector) of model points against the dataset's measurements.
fn relative_rms(measured: &[Vec<Vector3<f64>>], model: &[Vec<Vector3<f64>>]) -> f64 {
    let mut sum = [0.0; 3];
    let mut n = 0usize;
    for i in 0..measured.len() {
        for j in i + 1..measured.len() {
            for k in 0..3 {
                let d =
                    (measured[i][k] - measured[j][k]).norm() - (model[i][k] - model[j][k]).norm();
                sum[k] += d * d;
            }
            n += 1;
        }
    }
    sum.iter()
        .map(|s| (s / n as f64).sqrt())
        .fold(0.0, f64::max)
}

fn ds_reflectors(flow: &Flow) -> Vec<Vector3<f64>> {
    flow.dataset.nominal_reflectors_mm.clone()
}

struct Flow {
    robot: RobotDescription,
    dataset: dualcal::dataset::Dataset,
    truth: DualArmModel,
    calibrated: DualArmModel,
    urdf_path: PathBuf,
}

/// Simulate (paper size unless `configs` is smaller), write the dataset next to the URDF, load it
/// back, calibrate.
fn run_flow(urdf_path: &Path, arms: [(&str, &str); 2], seed: u64, configs: (usize, usize)) -> Flow {
    let options = LoadOptions {
        arms: links(arms),
        ..Default::default()
    };
    let robot = RobotDescription::load(urdf_path, &options).unwrap();
    let sim = simulate_with_robot(&paper_options(seed, configs.0, configs.1), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    ds.robot = Some(urdf_path.to_path_buf());
    for (side, a) in ds.arms.iter_mut() {
        a.links = robot.arm(side).links.clone().into();
    }
    let dir = urdf_path.parent().unwrap().join(format!("data-{seed}"));
    dataset::save(&ds, &dir, Units::MM_DEG).unwrap();
    // Loaded as a user's dataset is: the robot from the manifest, a prismatic joint's column read in
    // the length unit.
    let ws = dualcal::workspace::Workspace::load(&dir, &Default::default()).unwrap();
    let (dataset, robot) = (ws.dataset, ws.robot);
    for side in Side::BOTH {
        let (a, b) = (&dataset.arm(side).measurements, &ds.arm(side).measurements);
        for (m, n) in a.iter().zip(b) {
            for (x, y) in m.q_rad.iter().zip(&n.q_rad) {
                assert!((x - y).abs() < 1e-9, "{side} {}: {x} vs {y}", m.id);
            }
        }
    }
    let nominal = robot.nominal_model_for(&dataset);
    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(&dataset, &nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.warnings());
    Flow {
        robot,
        dataset,
        truth: sim.truth,
        calibrated: result.calibrated,
        urdf_path: urdf_path.to_path_buf(),
    }
}

fn stats(r: &AccuracyReport) -> [(&'static str, f64); 3] {
    [
        ("relative left", r.relative_left.unwrap().pos_rms_mm),
        ("relative right", r.relative_right.unwrap().pos_rms_mm),
        ("collaborative", r.collaborative.unwrap().pos_rms_mm),
    ]
}

/// Verification accuracy of the calibrated model within 10% of the truth's, far below the nominal's.
fn assert_noise_floor(flow: &Flow, name: &str) {
    let ds = &flow.dataset;
    let nominal = flow.robot.nominal_model_for(ds);
    let at = |m: &DualArmModel| evaluate(ds, m, Split::Ver).unwrap();
    let (n, t, c) = (at(&nominal), at(&flow.truth), at(&flow.calibrated));
    for ((label, n), ((_, t), (_, c))) in stats(&n)
        .into_iter()
        .zip(stats(&t).into_iter().zip(stats(&c)))
    {
        eprintln!("{name} {label}: nominal {n:.4} mm, truth {t:.4} mm, calibrated {c:.4} mm");
        assert!(n > 20.0 * t, "{name} {label}: nominal {n} vs truth {t}");
        assert!(c <= 1.1 * t, "{name} {label}: calibrated {c} vs truth {t}");
    }
}

/// The calibrated URDF: only arm joint origins change, each by at most a few mm and a degree; every
/// visual and collision element stays; read alone (reflectors from its links) it reproduces the
/// calibrated accuracy, here and in the independent parser.
fn assert_export(flow: &Flow, name: &str) {
    let text = calibrated_urdf(&flow.robot, &flow.calibrated).unwrap();
    let original = std::fs::read_to_string(&flow.urdf_path).unwrap();
    for tag in [
        "<visual",
        "<collision",
        "<mesh",
        "<gazebo",
        "<transmission",
        "<mimic",
        "<!--",
    ] {
        let added = if tag == "<visual" { 6 } else { 0 } + if tag == "<!--" { 1 } else { 0 };
        assert_eq!(
            text.matches(tag).count(),
            original.matches(tag).count() + added,
            "{name}: {tag}"
        );
    }
    // Line by line, only arm joints' <origin> lines differ until the appended reflector links (a
    // mimic joint's too: it has its own corrections).
    let arm_joints: Vec<String> = Side::BOTH
        .iter()
        .flat_map(|&s| {
            flow.robot
                .arm(s)
                .chain
                .joint_names()
                .into_iter()
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect();
    let (a, b): (Vec<&str>, Vec<&str>) = (original.lines().collect(), text.lines().collect());
    let robot_line = a.iter().position(|l| l.contains("<robot")).unwrap();
    assert!(
        b[robot_line].starts_with("<!-- Calibrated by dualcal"),
        "{name}"
    );
    let mut changed = 0;
    for (i, line) in a.iter().enumerate() {
        if line.contains("</robot>") {
            break;
        }
        let other = if i < robot_line { b[i] } else { b[i + 1] };
        if *line != other {
            assert!(
                line.trim_start().starts_with("<origin"),
                "{name}: {line} → {other}"
            );
            changed += 1;
        }
    }
    // Every arm joint but the left arm's first (a rigid motion of the arm, never identified).
    assert_eq!(changed, arm_joints.len() - 1, "{name}");
    // Each joint moved by its correction only.
    let dir = flow.urdf_path.parent().unwrap();
    let out = dir.join("calibrated.urdf");
    std::fs::write(&out, &text).unwrap();
    let options = LoadOptions {
        arms: flow.robot.arms().as_ref().map(|_, a| Some(a.links.clone())),
        ..Default::default()
    };
    let back = RobotDescription::load(&out, &options).unwrap();
    let mut largest = (0.0f64, 0.0f64);
    for side in Side::BOTH {
        let arm = flow.calibrated.arm(side);
        let chain = arm.chain().unwrap();
        let expected = chain.corrected_origins(arm.corrections().unwrap());
        for (k, (name_j, want)) in expected.iter().enumerate() {
            let o = |r: &RobotDescription| {
                let j = r.urdf.joints.iter().find(|j| &j.name == name_j).unwrap();
                dualcal::robot::isometry_from_urdf_pose(&j.origin)
            };
            let got = o(&back);
            let d = o(&flow.robot).inverse() * got;
            let (t, r) = (d.translation.vector.norm(), d.rotation.angle());
            largest = (largest.0.max(t), largest.1.max(r));
            // Exactly the identified correction (the right arm's first joint also carries the base
            // correction).
            if !(side == Side::Right && k == 0) {
                let e = want.inverse() * got;
                assert!(
                    e.translation.vector.norm() < 1e-9 && e.rotation.angle() < 1e-12,
                    "{name}: {name_j} is not its corrected origin"
                );
            }
            // The simulated robots carry paper-size errors (2.5–5.5 mm nominal RMS per arm): a few
            // mm and a degree or so per joint.
            assert!(
                t < 10.0 && r < 2f64.to_radians(),
                "{name}: {name_j} moved by {d}"
            );
        }
    }
    eprintln!(
        "{name}: largest joint-origin change {:.3} mm, {:.2} mrad",
        largest.0,
        largest.1 * 1e3
    );
    // Read alone, the file is the calibrated model.
    let again = back.nominal_model([Vector3::zeros(); 3]);
    let ver = |m: &DualArmModel| evaluate(&flow.dataset, m, Split::Ver).unwrap();
    for ((l, a), (_, c)) in stats(&ver(&again))
        .into_iter()
        .zip(stats(&ver(&flow.calibrated)))
    {
        assert!(
            (a - c).abs() < 1e-6,
            "{name} {l}: file {a} vs calibrated {c}"
        );
    }
    // And by an independent parser, relative accuracy per arm.
    for side in Side::BOTH {
        let ms: Vec<_> = flow
            .dataset
            .arm(side)
            .measurements
            .iter()
            .filter(|m| m.split == Split::Ver)
            .collect();
        // The URDF's own units for the independent parser: metres for a prismatic joint.
        let arm_data = flow.dataset.arm(side);
        let qs: Vec<Vec<f64>> = ms.iter().map(|m| m.q_rad.clone()).collect();
        let qs_urdf: Vec<Vec<f64>> = ms
            .iter()
            .map(|m| {
                m.q_rad
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| {
                        if arm_data.is_linear_joint(i) {
                            v / 1000.0
                        } else {
                            v
                        }
                    })
                    .collect()
            })
            .collect();
        let measured: Vec<Vec<Vector3<f64>>> =
            ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
        let points = independent_points(&out, &flow.robot.arm(side).links, &qs_urdf, dir);
        // The file's right base link sits where the URDF tree puts it; the base correction is in
        // its first joint: the model points seen from the nominal base link.
        let nominal_from_calibrated = flow
            .robot
            .nominal_model(ds_reflectors(flow))
            .left_base_from(side)
            .inverse()
            * flow.calibrated.left_base_from(side);
        let model: Vec<Vec<Vector3<f64>>> = qs
            .iter()
            .map(|q| {
                flow.calibrated
                    .arm(side)
                    .reflector_fk(q)
                    .points_mm
                    .iter()
                    .map(|p| nominal_from_calibrated.transform_point(&(*p).into()).coords)
                    .collect()
            })
            .collect();
        for (p, m) in points.iter().zip(&model) {
            for k in 0..3 {
                assert!(
                    (p[k] - m[k]).norm() < 1e-6,
                    "{name} {side}: {} vs {}",
                    p[k],
                    m[k]
                );
            }
        }
        let (file, cal) = (
            relative_rms(&measured, &points),
            relative_rms(&measured, &model),
        );
        assert!((file - cal).abs() < 1e-9, "{name} {side}: {file} vs {cal}");
    }
    // ROS's check_urdf accepts it.
    common::assert_check_urdf(&out, name);
}

#[test]
fn yumi_like_description_calibrates_to_the_noise_floor_and_exports_in_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_yumi_like(dir.path());
    for seed in [1, 2] {
        let flow = run_flow(&urdf, robots::YUMI_LIKE_ARMS, seed, (220, 120));
        assert_eq!(flow.robot.arm(Side::Left).chain.dof(), 7);
        assert_noise_floor(&flow, "yumi-like");
        assert_export(&flow, "yumi-like");
    }
}

/// A prismatic lift and a mimic (coupled) joint on each arm's chain (issue 19): the lift's CSV
/// column is a length, the coupled joint has none; both calibrated like the revolute joints, the
/// calibrated URDF changes their origins (the `<mimic>` and the `prismatic` type kept) and
/// `check_urdf` and the independent parser read it.
#[test]
fn lift_and_mimic_description_calibrates_to_the_noise_floor_and_exports_in_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "lift_mimic.urdf",
        robots::lift_mimic_urdf().as_bytes(),
    );
    for seed in [1, 2] {
        let flow = run_flow(&urdf, robots::LIFT_MIMIC_ARMS, seed, (500, 400));
        let chain = &flow.robot.arm(Side::Left).chain;
        assert_eq!((chain.dof(), chain.joint_count()), (6, 7));
        assert_eq!(
            flow.dataset.arm(Side::Right).linear_joints,
            [false, true, false, false, false, false]
        );
        // The lift's values are mm within its 0–300 mm travel.
        let lift: Vec<f64> = flow
            .dataset
            .arm(Side::Left)
            .measurements
            .iter()
            .map(|m| m.q_rad[1])
            .collect();
        assert!(lift.iter().all(|v| (0.0..=300.0).contains(v)));
        assert!(
            lift.iter().fold(0.0f64, |a, v| a.max(*v)) > 150.0,
            "{lift:?}"
        );
        assert_noise_floor(&flow, "lift-mimic");
        assert_export(&flow, "lift-mimic");
        let text = calibrated_urdf(&flow.robot, &flow.calibrated).unwrap();
        assert!(
            text.contains("<mimic joint=\"left_elbow_joint\" multiplier=\"0.5\" offset=\"0.2\"/>")
        );
        assert_eq!(text.matches("type=\"prismatic\"").count(), 2);
    }
}

#[test]
fn dual_ur_like_description_calibrates_to_the_noise_floor_and_exports_in_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "dual_ur.urdf",
        robots::dual_ur_like_urdf().as_bytes(),
    );
    for seed in [1, 2] {
        let flow = run_flow(&urdf, robots::DUAL_UR_ARMS, seed, (220, 120));
        assert_eq!(flow.robot.arm(Side::Right).chain.dof(), 6);
        assert_noise_floor(&flow, "dual-ur");
        assert_export(&flow, "dual-ur");
    }
}

/// The lift's column in the file's length unit (metres here, radians for the angles), read back to
/// the same mm; and a `<mimic>` loop in the description refused with the file, the line and the
/// joint.
#[test]
fn prismatic_columns_follow_the_length_unit_and_mimic_loops_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "lift_mimic.urdf",
        robots::lift_mimic_urdf().as_bytes(),
    );
    let options = LoadOptions {
        arms: links(robots::LIFT_MIMIC_ARMS),
        ..Default::default()
    };
    let robot = RobotDescription::load(urdf.as_path(), &options).unwrap();
    let sim = simulate_with_robot(&paper_options(5, 40, 20), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    ds.robot = Some(urdf.clone());
    for (side, a) in ds.arms.iter_mut() {
        a.links = robot.arm(side).links.clone().into();
    }
    let m_rad = Units {
        length: dataset::LengthUnit::M,
        angle: dataset::AngleUnit::Rad,
    };
    let out = dir.path().join("m-rad");
    dataset::save(&ds, &out, m_rad).unwrap();
    let csv = std::fs::read_to_string(out.join("left.csv")).unwrap();
    let first = csv
        .lines()
        .find(|l| !l.starts_with('#') && !l.starts_with("id"))
        .unwrap();
    let lift: f64 = first.split(',').nth(2).unwrap().parse().unwrap();
    let lift_mm = ds.arms.left.measurements[0].q_rad[1];
    assert!(
        (lift - lift_mm / 1000.0).abs() < 1e-9,
        "{lift} m vs {lift_mm} mm"
    );
    let ws = dualcal::workspace::Workspace::load(&out, &Default::default()).unwrap();
    for side in Side::BOTH {
        for (a, b) in ws
            .dataset
            .arm(side)
            .measurements
            .iter()
            .zip(&ds.arm(side).measurements)
        {
            for (x, y) in a.q_rad.iter().zip(&b.q_rad) {
                assert!((x - y).abs() < 1e-9, "{x} vs {y}");
            }
        }
    }
    // Read as a plain dataset (no robot) the lift is still in radians' clothing; the robot fixes it.
    let plain = dataset::load(&out).unwrap();
    assert!((plain.arms.left.measurements[0].q_rad[1] - lift).abs() < 1e-12);

    // A lift beyond its 0–300 mm travel: refused in mm, with the file, line and column.
    let mut beyond = ds.clone();
    beyond.arms.right.measurements[3].q_rad[1] = 350.0;
    let out = dir.path().join("beyond");
    dataset::save(&beyond, &out, Units::MM_DEG).unwrap();
    let err = dualcal::workspace::Workspace::load(&out, &Default::default())
        .unwrap_err()
        .to_string();
    let id = &beyond.arms.right.measurements[3].id;
    let text = std::fs::read_to_string(out.join("right.csv")).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with(&format!("{id},")))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!("right.csv:{line}:"))
            && err.contains(
                "field `q2`: 350.000 mm is outside the prismatic joint's limits [0.000, 300.000] mm"
            ),
        "{err}"
    );
    assert!(!err.contains('°'), "{err}");

    let looped = robots::lift_mimic_urdf().replace(
        "<child link=\"right_forearm\"/>",
        "<child link=\"right_forearm\"/>\n    <mimic joint=\"right_coupled_joint\"/>",
    );
    let bad = robots::write_file(dir.path(), "looped.urdf", looped.as_bytes());
    let err = RobotDescription::load(bad.as_path(), &options).unwrap_err();
    let text = err.to_string();
    let line = looped
        .lines()
        .position(|l| l.contains("name=\"right_elbow_joint\""))
        .unwrap()
        + 1;
    assert!(
        text.contains(&format!("looped.urdf, line {line}:")),
        "{text}"
    );
    assert!(
        text.contains("right_elbow_joint") && text.contains("loop"),
        "{text}"
    );
}
