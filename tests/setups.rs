//! Measurement set-ups other than the paper's (issue 19): one or two reflectors per arm instead of
//! three. Simulated on the built-in IRB 14000 and on a YuMi-like URDF written by the tests; each
//! calibrated to within 10% of what the true parameters give on the verification split, the
//! orientation figures "not measurable" (absent, never zero) without three reflectors, the pose method
//! refused with a reason, and the three-reflector case unchanged.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Dataset, Split, Units};
use dualcal::kinematics::DualArmModel;
use dualcal::metrics::evaluate;
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationError, CalibrationSettings, Calibrator, Method};

/// Keep only the reflectors `keep` (indices into a, b, c) of a dataset and of a model.
fn keep_reflectors(ds: &mut Dataset, models: &mut [&mut DualArmModel], keep: &[usize]) {
    let pick = |v: &Vec<nalgebra::Vector3<f64>>| keep.iter().map(|&k| v[k]).collect::<Vec<_>>();
    ds.nominal_reflectors_mm = pick(&ds.nominal_reflectors_mm);
    let names: Vec<String> = keep
        .iter()
        .map(|&k| ds.reflector_names[k].clone())
        .collect();
    ds.reflector_names = names.clone().into();
    for (_, arm) in ds.arms.iter_mut() {
        for m in &mut arm.measurements {
            m.tracker_points_mm = pick(&m.tracker_points_mm);
        }
    }
    for model in models.iter_mut() {
        for side in Side::BOTH {
            let arm = model.arm_mut(side);
            arm.reflectors_mm = pick(&arm.reflectors_mm);
            arm.reflector_names = names.clone().into();
        }
    }
}

struct Case {
    robot: RobotDescription,
    dataset: Dataset,
    truth: DualArmModel,
}

fn simulate(robot: RobotDescription, seed: u64, keep: &[usize], dir: &std::path::Path) -> Case {
    let sim = simulate_with_robot(&paper_options(seed, 300, 200), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    let mut truth = sim.truth.clone();
    keep_reflectors(&mut ds, &mut [&mut truth], keep);
    // Through the files: the manifest and CSVs of a one- or two-reflector dataset read back.
    let out = dir.join(format!("data-{seed}-{}", keep.len()));
    dataset::save(&ds, &out, Units::MM_DEG).unwrap();
    let dataset = dataset::load(&out).unwrap();
    assert_eq!(dataset.reflector_count(), keep.len());
    for (_, arm) in dataset.arms.iter() {
        assert!(
            arm.measurements
                .iter()
                .all(|m| m.tracker_points_mm.len() == keep.len())
        );
    }
    Case {
        robot,
        dataset,
        truth,
    }
}

fn nominal(case: &Case) -> DualArmModel {
    case.robot.nominal_model_for(&case.dataset)
}

/// Relative and collaborative RMS on the verification split: calibrated within 10% of the truth's,
/// the nominal far off; orientation figures absent without three reflectors.
fn check_case(case: &Case, name: &str) {
    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let nominal = nominal(case);
    let result = common::calibrate(&case.dataset, &nominal, &settings);
    assert!(result.is_converged(), "{name}: {:?}", result.warnings());
    let at = |m: &DualArmModel| evaluate(&case.dataset, m, Split::Ver).unwrap();
    let (n, t, c) = (at(&nominal), at(&case.truth), at(&result.calibrated));
    assert!(c.collaborative.is_some());
    common::assert_near_truth(name, &n, &t, &c);
    let three = case.dataset.reflector_count() == 3;
    for r in [&n, &t, &c] {
        for stats in [
            &r.relative_left.unwrap(),
            &r.relative_right.unwrap(),
            &r.collaborative.unwrap(),
        ] {
            assert_eq!(
                stats.ori_rms_rad.is_some(),
                three,
                "{name}: orientation figures exist exactly with three reflectors"
            );
        }
    }
}

#[test]
fn one_and_two_reflectors_on_the_built_in_robot() {
    let dir = tempfile::tempdir().unwrap();
    for (seed, keep) in [(31, vec![0]), (32, vec![0, 2])] {
        let case = simulate(
            RobotDescription::builtin_irb14000(),
            seed,
            &keep,
            dir.path(),
        );
        check_case(&case, &format!("IRB 14000, {} reflector(s)", keep.len()));
    }
}

#[test]
fn one_and_two_reflectors_on_a_urdf_robot() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("yumi_like.urdf");
    std::fs::write(&urdf, robots::yumi_like_urdf()).unwrap();
    let options = LoadOptions {
        arms: PerSide::new(
            Some(ArmLinks::new("yumi_body", "yumi_link_7_l")),
            Some(ArmLinks::new("yumi_body", "yumi_link_7_r")),
        ),
        ..Default::default()
    };
    for (seed, keep) in [(41, vec![1]), (42, vec![0, 1])] {
        let robot = RobotDescription::load(urdf.as_path(), &options).unwrap();
        let case = simulate(robot, seed, &keep, dir.path());
        check_case(
            &case,
            &format!("YuMi-like URDF, {} reflector(s)", keep.len()),
        );
    }
}

#[test]
fn the_pose_method_says_why_it_cannot_run_without_three_reflectors() {
    let dir = tempfile::tempdir().unwrap();
    let case = simulate(
        RobotDescription::builtin_irb14000(),
        51,
        &[0, 1],
        dir.path(),
    );
    let settings = CalibrationSettings {
        method: Method::Pose,
        ..CalibrationSettings::default()
    };
    let err = Calibrator::new(&case.dataset, &nominal(&case))
        .settings(settings)
        .run()
        .unwrap_err();
    assert!(
        matches!(err, CalibrationError::NeedsThreeReflectors { found: 2, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("three reflectors"), "{err}");
}

#[test]
fn reflector_names_come_back_as_the_user_wrote_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut case = simulate(
        RobotDescription::builtin_irb14000(),
        61,
        &[0, 1],
        dir.path(),
    );
    case.dataset.reflector_names = vec!["smr_front".to_string(), "smr_back".to_string()].into();
    let out = dir.path().join("named");
    dataset::save(&case.dataset, &out, Units::MM_DEG).unwrap();
    let manifest = std::fs::read_to_string(out.join(dataset::MANIFEST_FILE)).unwrap();
    assert!(manifest.contains("smr_front = ["), "{manifest}");
    let csv = std::fs::read_to_string(out.join("left.csv")).unwrap();
    assert!(
        csv.contains("smr_frontx,smr_fronty,smr_frontz,smr_backx,smr_backy,smr_backz"),
        "{csv}"
    );
    let back = dataset::load(&out).unwrap();
    assert_eq!(&back.reflector_names[..], &case.dataset.reflector_names[..]);
    let model = nominal(&Case {
        robot: RobotDescription::builtin_irb14000(),
        dataset: back,
        truth: case.truth.clone(),
    });
    let arm = model.arm(Side::Left);
    let first = arm.reflector_offset();
    assert_eq!(arm.param_name(first), "t_smr_front.x");
    assert_eq!(arm.param_name(first + 5), "t_smr_back.z");
}

/// Each arm measured from its own tracker station (the tracker moved between them, its two frames
/// metres apart): each arm calibrates as usual; the base and the collaborative figures are not
/// measurable from such data and are reported so — never computed from the unrelated frames.
#[test]
fn arms_measured_from_two_stations() {
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(71, 300, 200), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    // The tracker moved 3 m and turned 40° before it measured the right arm.
    let moved = nalgebra::Isometry3::new(
        nalgebra::Vector3::new(3000.0, -1200.0, 150.0),
        nalgebra::Vector3::new(0.1, -0.2, 0.7),
    );
    for m in &mut ds.arms.right.measurements {
        for p in &mut m.tracker_points_mm {
            *p = moved.transform_point(&(*p).into()).coords;
        }
    }
    ds.arms.left.station = Some("north".into());
    ds.arms.right.station = Some("south".into());
    let out = dir.path().join("two-stations");
    dataset::save(&ds, &out, Units::MM_DEG).unwrap();
    let manifest = std::fs::read_to_string(out.join(dataset::MANIFEST_FILE)).unwrap();
    assert!(manifest.contains("station = \"south\""), "{manifest}");
    let ds = dataset::load(&out).unwrap();
    assert!(!ds.one_tracker_frame());
    let case = Case {
        robot,
        dataset: ds,
        truth: sim.truth.clone(),
    };
    let nominal = nominal(&case);
    let result = common::calibrate(&case.dataset, &nominal, &CalibrationSettings::default());
    assert!(result.is_converged(), "{:?}", result.warnings());
    assert!(result.stage(dualcal::solver::Stage::Base).is_none());
    let why = result.base_not_measurable.as_deref().unwrap();
    assert!(why.contains("north") && why.contains("south"), "{why}");
    assert!(
        result
            .warnings()
            .iter()
            .any(|w| w.contains("not measurable")),
        "{:?}",
        result.warnings()
    );
    // The base stays nominal: it is no calibration result.
    assert_eq!(
        result.calibrated.left_base_from_right_base,
        nominal.left_base_from_right_base
    );
    let at = |m: &DualArmModel| evaluate(&case.dataset, m, Split::Ver).unwrap();
    let (t, c) = (at(&case.truth), at(&result.calibrated));
    assert!(t.collaborative.is_none() && c.collaborative.is_none());
    for side in Side::BOTH {
        let (t, c) = (
            t.relative(side).unwrap().pos_rms_mm,
            c.relative(side).unwrap().pos_rms_mm,
        );
        eprintln!("two stations, relative {side}: truth {t:.4} mm, calibrated {c:.4} mm");
        assert!(c <= 1.1 * t, "{side}: calibrated {c} vs truth {t}");
    }
    let table = dualcal::metrics::format_table(&c);
    assert!(table.contains("not measurable"), "{table}");
    // Nothing warns that the arms' frames differ: the manifest says so.
    let ws = dualcal::workspace::Workspace::load(&out, &Default::default()).unwrap();
    assert!(
        ws.warnings()
            .iter()
            .all(|w| !w.contains("one tracker position")),
        "{:?}",
        ws.warnings()
    );
}

/// An arm's own nominal reflector coordinates (`[[arms]] reflectors = {…}`, the DLR data's markers sit
/// differently on each hand): read back from the files, the right arm's nominal model starts there,
/// the calibration reaches the truth's accuracy; naming a reflector the dataset does not have is
/// refused with the line and field.
#[test]
fn an_arm_with_its_own_reflector_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(73, 300, 200), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    let mut truth = sim.truth.clone();
    keep_reflectors(&mut ds, &mut [&mut truth], &[0]);
    // The right hand's marker sits 50 mm aside and 20 mm lower than the left's.
    let offset = nalgebra::Vector3::new(0.0, 50.0, -20.0);
    let tracker_from_right = sim.tracker_from_left_base * truth.left_base_from(Side::Right);
    for m in &mut ds.arms.right.measurements {
        let flange = tracker_from_right * truth.arm(Side::Right).base_from_flange(&m.q_rad);
        m.tracker_points_mm[0] += flange.rotation * offset;
    }
    truth.arm_mut(Side::Right).reflectors_mm[0] += offset;
    ds.arms.right.nominal_reflectors_mm = Some(vec![ds.nominal_reflectors_mm[0] + offset]);
    let out = dir.path().join("own-reflectors");
    dataset::save(&ds, &out, Units::MM_DEG).unwrap();
    let manifest = std::fs::read_to_string(out.join(dataset::MANIFEST_FILE)).unwrap();
    assert!(manifest.contains("reflectors = { a = ["), "{manifest}");
    let back = dataset::load(&out).unwrap();
    assert_eq!(
        back.arms.right.nominal_reflectors_mm,
        ds.arms.right.nominal_reflectors_mm
    );
    assert_eq!(back.arms.left.nominal_reflectors_mm, None);
    let case = Case {
        robot,
        dataset: back,
        truth,
    };
    let nominal = nominal(&case);
    assert_eq!(
        nominal.arm(Side::Right).reflectors_mm[0],
        ds.nominal_reflectors_mm[0] + offset
    );
    assert_eq!(
        nominal.arm(Side::Left).reflectors_mm[0],
        ds.nominal_reflectors_mm[0]
    );
    check_case(&case, "own reflector coordinates");

    // A reflector the dataset does not have: refused, naming the line and field.
    let bad = manifest.replace("reflectors = { a = [", "reflectors = { z = [");
    std::fs::write(out.join(dataset::MANIFEST_FILE), bad).unwrap();
    let err = dataset::load(&out).unwrap_err().to_string();
    assert!(
        err.contains("dataset.toml:") && err.contains("arms.reflectors") && err.contains(" z "),
        "{err}"
    );
}
