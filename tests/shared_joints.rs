//! Arms that share joints (issue 19): a torso on both arms' chains — a revolute waist, and a waist
//! with a prismatic lift — moved in every configuration. Simulated on robots the tests write (the
//! YuMi-like URDF on a torso); step 1 is one fit of both arms with the shared joints' corrections
//! once ([`Stage::Arms`]); each case calibrated to within 10% of what the true parameters give on the
//! verification split, the shared joints' corrections the same in both arms, the calibrated URDF
//! keeping the robot (every link, visual and collision), changing the shared joints once, loading
//! back and accepted by ROS's `check_urdf`. A method without a fit of both arms says so.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{self, Dataset, Split, Units};
use dualcal::kinematics::DualArmModel;
use dualcal::metrics::evaluate;
use dualcal::robot::{ArmLinks, LoadOptions, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationError, CalibrationSettings, Calibrator, Method, Stage};

fn load_robot(path: &std::path::Path) -> RobotDescription {
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let options = LoadOptions {
        arms: PerSide::new(Some(ArmLinks::new(lb, lt)), Some(ArmLinks::new(rb, rt))),
        ..Default::default()
    };
    RobotDescription::load(path, &options).unwrap()
}

struct Case {
    robot: RobotDescription,
    dataset: Dataset,
    truth: DualArmModel,
}

/// Simulate `lift` (a waist, or a waist and a lift) with the reflectors `keep` (indices into a, b, c),
/// written and read back through the dataset files.
fn simulate(
    dir: &std::path::Path,
    lift: bool,
    seed: u64,
    keep: &[usize],
    (configs, cal): (usize, usize),
) -> Case {
    let urdf = dir.join(format!("torso-{lift}.urdf"));
    std::fs::write(&urdf, robots::shared_torso_urdf(lift)).unwrap();
    let robot = load_robot(&urdf);
    let sim = simulate_with_robot(&paper_options(seed, configs, cal), &robot).unwrap();
    let mut ds = sim.dataset.clone();
    let mut truth = sim.truth.clone();
    let pick = |v: &Vec<nalgebra::Vector3<f64>>| keep.iter().map(|&k| v[k]).collect::<Vec<_>>();
    let names: Vec<String> = keep
        .iter()
        .map(|&k| ds.reflector_names[k].clone())
        .collect();
    ds.nominal_reflectors_mm = pick(&ds.nominal_reflectors_mm);
    ds.reflector_names = names.clone().into();
    for (_, arm) in ds.arms.iter_mut() {
        for m in &mut arm.measurements {
            m.tracker_points_mm = pick(&m.tracker_points_mm);
        }
    }
    for side in Side::BOTH {
        let arm = truth.arm_mut(side);
        arm.reflectors_mm = pick(&arm.reflectors_mm);
        arm.reflector_names = names.clone().into();
    }
    let out = dir.join(format!("data-{lift}-{seed}"));
    dataset::save(&ds, &out, Units::MM_DEG).unwrap();
    // Through the load pipeline: the lift's column is a length, known from the robot.
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let ws = dualcal::workspace::Workspace::load(
        &out,
        &dualcal::workspace::WorkspaceOptions {
            robot: Some(urdf.clone()),
            arms: PerSide::new(Some(ArmLinks::new(lb, lt)), Some(ArmLinks::new(rb, rt))),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(ws.refusals().is_empty(), "{:?}", ws.refusals());
    let dataset = ws.dataset;
    Case {
        robot,
        dataset,
        truth,
    }
}

fn check(case: &Case, name: &str, dir: &std::path::Path) {
    let nominal = case.robot.nominal_model_for(&case.dataset);
    let shared = nominal.shared_joints();
    assert!(!shared.is_empty(), "{name}: the torso is on both chains");
    // The truth's torso is one joint, and the arms move it differently in their configurations.
    let (tl, tr) = (
        case.truth.arm(Side::Left).to_vector(),
        case.truth.arm(Side::Right).to_vector(),
    );
    assert!(shared.params.iter().all(|&(a, b)| tl[a] == tr[b]));
    let torso_values = |side: Side| {
        let arm = &case.dataset.arms[side];
        let (a, b) = shared.variables[0];
        let col = if side == Side::Left { a } else { b };
        let v: Vec<f64> = arm.measurements.iter().map(|m| m.q_rad[col]).collect();
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    assert!(torso_values(Side::Left) > 0.5 && torso_values(Side::Right) > 0.5);

    let settings = CalibrationSettings {
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(&case.dataset, &nominal, &settings);
    assert!(result.is_converged(), "{name}: {:?}", result.warnings());
    let stages: Vec<Stage> = result.stages.iter().map(|s| s.stage).collect();
    assert_eq!(stages, [Stage::Arms, Stage::Base], "{name}");
    // The shared joints' corrections: one value, in both arms' models.
    let (cl, cr) = (
        result.calibrated.arm(Side::Left).to_vector(),
        result.calibrated.arm(Side::Right).to_vector(),
    );
    for &(a, b) in &shared.params {
        assert_eq!(cl[a], cr[b], "{name}: shared parameter {a}");
    }
    // Both arms' identifiability reports hold the shared parameters alike.
    let reports = result
        .identifiability
        .as_ref()
        .map(|_, r| r.clone().unwrap());
    for &(a, b) in &shared.params {
        assert_eq!(
            reports.left.free.contains(&a),
            reports.right.free.contains(&b),
            "{name}: shared parameter {a} / {b}"
        );
    }
    // The base of two chains from one link stays nominal: step 2's correction is the right arm's
    // mounting on the torso.
    assert_eq!(
        result.calibrated.left_base_from_right_base,
        nominal.left_base_from_right_base
    );

    let at = |m: &DualArmModel| evaluate(&case.dataset, m, Split::Ver).unwrap();
    let (n, t, c) = (at(&nominal), at(&case.truth), at(&result.calibrated));
    assert!(c.collaborative.is_some());
    common::assert_near_truth(name, &n, &t, &c);
    // Both hands measured together: the pairs of one instant have their own figures.
    assert_eq!(
        c.collaborative_same_instant.is_some(),
        case.dataset.measured_together,
        "{name}"
    );
    if let (Some(ns), Some(ts), Some(cs)) = (
        n.collaborative_same_instant,
        t.collaborative_same_instant,
        c.collaborative_same_instant,
    ) {
        eprintln!(
            "{name}, same instant: nominal {:.4} mm, truth {:.4} mm, calibrated {:.4} mm ({} pairs)",
            ns.pos_rms_mm, ts.pos_rms_mm, cs.pos_rms_mm, cs.n_pairs
        );
        assert!(cs.pos_rms_mm <= 1.1 * ts.pos_rms_mm && ns.pos_rms_mm > 10.0 * ts.pos_rms_mm);
        assert!(cs.n_pairs > 0 && cs.n_pairs < c.collaborative.unwrap().n_pairs);
        // The workbench's sweep gives the same figures as `evaluate`, to the bit.
        let sweep = dualcal::metrics::sweep(&case.dataset, &result.calibrated).unwrap();
        assert_eq!(
            sweep.ver.unwrap().report.collaborative_same_instant,
            Some(cs)
        );
    }

    // The calibrated URDF: the robot kept, the shared joints changed once, loads back to the model.
    let text = dualcal::urdf_export::calibrated_urdf(&case.robot, &result.calibrated).unwrap();
    let original = &case.robot.text;
    for tag in ["<link ", "<visual>", "<collision>", "<joint "] {
        assert_eq!(
            text.matches(tag).count(),
            original.matches(tag).count()
                + if tag == "<visual>" || tag == "<link " || tag == "<joint " {
                    // The identified reflectors are written as links on fixed joints (with a visual).
                    text.matches("<link name=\"reflector_").count()
                } else {
                    0
                },
            "{name}: {tag}"
        );
    }
    for joint in &shared.names {
        assert_eq!(
            text.matches(&format!("<joint name=\"{joint}\"")).count(),
            1,
            "{name}: {joint}"
        );
    }
    assert!(text.contains("once"), "{name}: the header says so");
    let out = dir.join(format!("{}.urdf", name.replace(' ', "-")));
    std::fs::write(&out, &text).unwrap();
    let back = load_robot(&out);
    let model = back.nominal_model_named(
        &result.calibrated.arm(Side::Left).reflector_names,
        &result.calibrated.arm(Side::Left).reflectors_mm,
    );
    let back_figures = at(&model);
    for ((_, c), (_, b)) in common::position_figures(&c)
        .into_iter()
        .zip(common::position_figures(&back_figures))
    {
        assert!(
            (c - b).abs() < 1e-6,
            "{name}: model {c} vs written URDF {b}"
        );
    }
    common::assert_check_urdf(&out, name);
}

#[test]
fn a_moving_revolute_torso_shared_by_both_arms() {
    let dir = tempfile::tempdir().unwrap();
    let case = simulate(dir.path(), false, 91, &[0, 1, 2], (300, 200));
    check(&case, "revolute torso", dir.path());
}

#[test]
fn a_waist_and_prismatic_lift_shared_by_both_arms_with_one_reflector_per_arm() {
    let dir = tempfile::tempdir().unwrap();
    // One marker per hand gives a third of the distances: as many configurations as the DLR data has.
    let case = simulate(dir.path(), true, 92, &[0], (500, 400));
    check(&case, "waist and lift, one reflector", dir.path());
}

#[test]
fn a_method_without_a_fit_of_both_arms_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let case = simulate(dir.path(), false, 93, &[0, 1, 2], (60, 40));
    let nominal = case.robot.nominal_model_for(&case.dataset);
    let settings = CalibrationSettings {
        method: Method::DistanceSingle,
        ..CalibrationSettings::default()
    };
    let err = Calibrator::new(&case.dataset, &nominal)
        .settings(settings)
        .run()
        .unwrap_err();
    assert!(
        matches!(err, CalibrationError::SharedJointsUnsupported { .. }),
        "{err}"
    );
    let text = err.to_string();
    assert!(
        text.contains("yumi_base_link_to_body") && text.contains("`minimax`"),
        "{text}"
    );
}

/// The command line on a torso robot: `simulate --urdf` → `calibrate --urdf` → `evaluate` →
/// `report`, the run's one step-1 stage and the shared joint said once.
#[test]
fn a_shared_torso_from_the_command_line() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("torso.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(false)).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_owned();
    let ok = |args: &[String]| {
        let out = Command::new(env!("CARGO_BIN_EXE_dualcal"))
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "dualcal {args:?}:\n{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let args = |v: &[&str]| v.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let data = dir.path().join("sim");
    ok(&args(&[
        "simulate",
        "--urdf",
        &s(&urdf),
        "--left",
        &format!("{lb}:{lt}"),
        "--right",
        &format!("{rb}:{rt}"),
        "--out",
        &s(&data),
    ]));
    let (p, cal, report) = (
        dir.path().join("p.json"),
        dir.path().join("cal.urdf"),
        dir.path().join("report.html"),
    );
    let out = ok(&args(&[
        "calibrate",
        &s(&data),
        "--out",
        &s(&p),
        "--urdf",
        &s(&cal),
    ]));
    assert!(out.contains("step 1 (both arms, shared joints)"), "{out}");
    assert!(!out.contains("step 1 (left arm)"), "{out}");
    assert!(out.contains("yumi_base_link_to_body"), "{out}");
    let rms = |json: &str| {
        let v: serde_json::Value = serde_json::from_str(json).unwrap();
        ["relative_left", "relative_right", "collaborative"]
            .map(|k| v[k]["pos_rms_mm"].as_f64().unwrap())
    };
    let evaluate = |params: &std::path::Path| {
        rms(&ok(&args(&[
            "evaluate",
            &s(&data),
            "--params",
            &s(params),
            "--split",
            "ver",
            "--json",
        ])))
    };
    let (truth, calibrated) = (evaluate(&data.join("truth.json")), evaluate(&p));
    for k in 0..3 {
        assert!(calibrated[k] < 1.1 * truth[k], "{calibrated:?} {truth:?}");
    }
    let text = std::fs::read_to_string(&cal).unwrap();
    assert_eq!(
        text.matches("<joint name=\"yumi_base_link_to_body\"")
            .count(),
        1
    );
    ok(&args(&[
        "report",
        &s(&data),
        "--params",
        &s(&p),
        "--out",
        &s(&report),
    ]));
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.contains("yumi_base_link_to_body"));
}

/// The predicted σ of a tree fit (both arms' sums in one covariance, a shared parameter one column)
/// against the spread over repeated measurements: one simulated lift robot and set of configurations,
/// fresh 20 µm noise per trial, least squares (the fit the formula describes).
#[test]
fn the_predicted_sigma_of_shared_parameters_match_their_spread() {
    use dualcal::solver::uncertainty::for_result;
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("lift.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(true)).unwrap();
    let robot = load_robot(&urdf);
    let sim = simulate_with_robot(&paper_options(21, 160, 120), &robot).unwrap();
    let shared = sim.nominal.shared_joints();
    let settings = CalibrationSettings {
        method: Method::LeastSquares,
        split: Split::Cal,
        ..CalibrationSettings::default()
    };
    let trials = 16;
    let mut vectors = Vec::new();
    let mut predicted = None;
    for t in 0..trials {
        let ds = common::renoised(&sim, 300 + t, 0.02);
        let result = common::calibrate(&ds, &sim.nominal, &settings);
        assert_eq!(result.stages[0].stage, Stage::Arms);
        if t == 0 {
            let u = for_result(&ds, &result);
            let (l, r) = (u.left.clone().unwrap(), u.right.clone().unwrap());
            // A shared parameter has one σ, reported by both arms.
            for p in l
                .parameters
                .iter()
                .filter(|p| p.name.starts_with("yumi_lift"))
            {
                let q = r.parameters.iter().find(|q| q.name == p.name).unwrap();
                assert_eq!(p.sigma, q.sigma, "{}", p.name);
            }
            assert!(l.condition.is_finite() && r.condition.is_finite());
            assert!(
                (l.point_sigma_mm / 0.02 - 1.0).abs() < 0.2,
                "{}",
                l.point_sigma_mm
            );
            predicted = Some((l, result.identifiability.left.clone().unwrap().free));
        }
        vectors.push(result.calibrated.arm(Side::Left).to_vector());
    }
    let (predicted, free) = predicted.unwrap();
    let arm = sim.nominal.arm(Side::Left);
    let mut ratios = Vec::new();
    for (c, &k) in free.iter().enumerate() {
        let mean = vectors.iter().map(|v| v[k]).sum::<f64>() / trials as f64;
        let var = vectors.iter().map(|v| (v[k] - mean).powi(2)).sum::<f64>() / (trials - 1) as f64;
        let unit = if arm.param_is_angle(k) { 1000.0 } else { 1.0 };
        let ratio = var.sqrt() * unit / predicted.parameters[c].sigma;
        if arm.param_name(k).starts_with("yumi_lift") {
            eprintln!("{}: spread / predicted σ = {ratio:.2}", arm.param_name(k));
        }
        ratios.push(ratio);
    }
    assert!(shared.params.iter().any(|&(a, _)| free.contains(&a)));
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    eprintln!(
        "tree fit, {} parameters: spread / predicted σ median {median:.2} ({:.2} … {:.2})",
        ratios.len(),
        ratios[0],
        ratios[ratios.len() - 1]
    );
    assert!((0.7..1.4).contains(&median), "{median}");
}

/// Both hands measured at one instant (`measured_together = true`): a left and a right row of one id
/// are one pose, so the torso has one value in them — calibrated as any other data; a row whose torso
/// value disagrees is refused naming the file, its line and the column.
#[test]
fn measured_together_rows_hold_one_torso_value() {
    use nalgebra::{Point3, Vector3};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("torso.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(false)).unwrap();
    let robot = load_robot(&urdf);
    let sim = simulate_with_robot(&paper_options(94, 300, 200), &robot).unwrap();
    let shared = sim.nominal.shared_joints();
    let mut ds = sim.dataset.clone();
    // Row i of each arm becomes one pose: the right row takes the left row's id, split and torso
    // value, and its points are measured again there (the truth, fresh 20 µm noise).
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(94);
    let noise = Normal::new(0.0, 0.02).unwrap();
    let tracker_from_right = sim.tracker_from_left_base * sim.truth.left_base_from(Side::Right);
    let left = ds.arms.left.measurements.clone();
    for (r, l) in ds.arms.right.measurements.iter_mut().zip(&left) {
        r.id = l.id.clone();
        r.split = l.split;
        r.q_rad = shared.right_with_left_values(&l.q_rad, &r.q_rad);
        let fk = sim.truth.arm(Side::Right).reflector_fk(&r.q_rad);
        for (p, t) in r.tracker_points_mm.iter_mut().zip(&fk.points_mm) {
            *p = tracker_from_right.transform_point(&Point3::from(*t)).coords
                + Vector3::from_fn(|_, _| noise.sample(&mut rng));
        }
    }
    ds.measured_together = true;
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let options = dualcal::workspace::WorkspaceOptions {
        robot: Some(urdf.clone()),
        arms: PerSide::new(Some(ArmLinks::new(lb, lt)), Some(ArmLinks::new(rb, rt))),
        ..Default::default()
    };
    let out = dir.path().join("together");
    dataset::save(&ds, &out, Units::MM_DEG).unwrap();
    let manifest = std::fs::read_to_string(out.join(dataset::MANIFEST_FILE)).unwrap();
    assert!(manifest.contains("measured_together = true"), "{manifest}");
    let ws = dualcal::workspace::Workspace::load(&out, &options).unwrap();
    assert!(ws.dataset.measured_together);
    let case = Case {
        robot: ws.robot.clone(),
        dataset: ws.dataset.clone(),
        truth: sim.truth.clone(),
    };
    check(&case, "measured together", dir.path());

    // One right row's torso a milliradian off its left row's: refused, naming file, line, column.
    let mut bad = ds.clone();
    let (_, b) = shared.variables[0];
    bad.arms.right.measurements[7].q_rad[b] += 1e-3;
    let out = dir.path().join("disagree");
    dataset::save(&bad, &out, Units::MM_DEG).unwrap();
    let err = dualcal::workspace::Workspace::load(&out, &options).unwrap_err();
    let text = format!("{err:#}");
    let line = bad.arms.right.measurements[7].line;
    let id = &bad.arms.right.measurements[7].id;
    eprintln!("{text}");
    assert!(
        text.contains("right.csv")
            && text.contains("field `q1`")
            && text.contains("yumi_base_link_to_body")
            && text.contains(&format!("`{id}`"))
            && text.contains("measured_together")
            && text.contains(" deg here but "),
        "{text} (line {line})"
    );
    // Without the declaration the same rows are two moments: nothing to check.
    bad.measured_together = false;
    let out = dir.path().join("apart");
    dataset::save(&bad, &out, Units::MM_DEG).unwrap();
    assert!(dualcal::workspace::Workspace::load(&out, &options).is_ok());
}

/// `dualcal plan` on a torso robot: each arm's planned configurations are collision-free with the
/// torso where that arm's own values put it (the other arm resting), and a YuMi-named robot on a
/// torso gets no RAPID module (its controller's 6 + 1 axes per arm would not take these targets).
#[test]
fn planning_a_robot_whose_arms_share_a_torso() {
    use dualcal::plan::{PlanOptions, plan};
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("lift.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(true)).unwrap();
    let robot = load_robot(&urdf);
    let shared = robot.shared_joints();
    assert_eq!(shared.names, ["yumi_base_link_to_body", "yumi_lift"]);
    let options = PlanOptions {
        per_arm: 8,
        candidates: 60,
        tracker_in_body_mm: nalgebra::Vector3::new(2000.0, 0.0, 500.0),
        ..PlanOptions::default()
    };
    let reflectors = dualcal::simulate::default_reflectors_for(&robot);
    let planned = plan(&robot, &reflectors, &options).unwrap();
    let world = dualcal::collision::CollisionWorld::new(&robot);
    let home = PerSide::from_fn(|side| robot.home_q_rad(side));
    for side in Side::BOTH {
        assert_eq!(planned[side].configs.len(), 8);
        for q in &planned[side].configs {
            let (ql, qr) = match side {
                Side::Left => (q.clone(), shared.right_with_left_values(q, &home.right)),
                Side::Right => (shared.left_with_right_values(&home.left, q), q.clone()),
            };
            assert!(
                !world.in_collision(&ql, &qr, options.clearance_mm),
                "{side} {q:?}"
            );
        }
    }
    assert!(!dualcal::plan::is_yumi(&robot));
}

/// Compensated targets of a torso robot hold the shared joints (moving the torso for one arm's target
/// would move the other arm): the arm's own joints reach the pose the nominal model meant.
#[test]
fn compensation_holds_the_shared_torso() {
    use dualcal::controller::compensate::{CompensationSettings, Target, compensate};
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("lift.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(true)).unwrap();
    let robot = load_robot(&urdf);
    let sim = simulate_with_robot(&paper_options(95, 40, 30), &robot).unwrap();
    let shared = sim.nominal.shared_joints();
    let settings = CompensationSettings::default();
    for side in Side::BOTH {
        let names: Vec<String> = robot
            .arm(side)
            .chain
            .joint_names()
            .iter()
            .map(|n| n.to_string())
            .collect();
        let mut reached = 0;
        for m in sim.dataset.arm(side).measurements.iter().take(10) {
            let done = match compensate(
                &sim.nominal,
                &sim.truth,
                side,
                &Target::Joints(m.q_rad.clone()),
                &names,
                &settings,
            ) {
                Ok(done) => done,
                Err(why) => {
                    eprintln!("{side} {}: {why}", m.id);
                    continue;
                }
            };
            reached += 1;
            for &(a, b) in &shared.variables {
                let k = if side == Side::Left { a } else { b };
                assert_eq!(done.q[k], m.q_rad[k], "{side}: shared joint moved");
            }
            let want =
                sim.nominal.left_base_from(side) * sim.nominal.arm(side).base_from_flange(&m.q_rad);
            let got =
                sim.truth.left_base_from(side) * sim.truth.arm(side).base_from_flange(&done.q);
            let d = want.inverse() * got;
            assert!(d.translation.vector.norm() < 0.01, "{side}: {d:?}");
        }
        eprintln!("{side}: {reached} of 10 targets compensated with the torso held");
        assert!(reached >= 8, "{side}: {reached} of 10");
    }
}

/// The absolute positions (ref. [18], `--method position`) of a torso robot with one marker per hand
/// — the DLR data's set-up: both arms and one tracker (camera) frame in one fit, the shared joints
/// once; the relative and collaborative figures as the distance methods reach them, and the absolute
/// position error near the noise.
#[test]
fn the_position_method_fits_both_arms_and_one_tracker_frame() {
    let dir = tempfile::tempdir().unwrap();
    let case = simulate(dir.path(), true, 94, &[0], (400, 300));
    let nominal = case.robot.nominal_model_for(&case.dataset);
    let shared = nominal.shared_joints();
    let settings = CalibrationSettings {
        method: Method::Position,
        max_iterations: 400,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(&case.dataset, &nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.warnings());
    assert_eq!(result.stages[0].stage, Stage::Arms);
    let (cl, cr) = (
        result.calibrated.arm(Side::Left).to_vector(),
        result.calibrated.arm(Side::Right).to_vector(),
    );
    for &(a, b) in &shared.params {
        assert_eq!(cl[a], cr[b], "shared parameter {a}");
    }
    let frames = result.tracker_from_base;
    let (tl, tr) = (frames.left.unwrap(), frames.right.unwrap());
    assert!((tl.translation.vector - tr.translation.vector).norm() < 1e-9);
    let at = |m: &DualArmModel| evaluate(&case.dataset, m, Split::Ver).unwrap();
    let (n, t, c) = (at(&nominal), at(&case.truth), at(&result.calibrated));
    common::assert_near_truth("position method, torso, one marker", &n, &t, &c);
    let abs =
        dualcal::metrics::absolute_stats(&case.dataset, &result.calibrated, &frames, Split::Ver)
            .unwrap()
            .unwrap();
    // Noise: σ = MPE/2 per axis ≈ 0.009 mm at 2 m, so |e| ≈ 0.016 mm on average.
    eprintln!(
        "position method, torso, one marker: absolute error on verification mean {:.4} mm, RMS {:.4} \
         mm, max {:.4} mm ({} points)",
        abs.mean_mm, abs.rms_mm, abs.max_mm, abs.n_points
    );
    assert!(abs.mean_mm < 0.03 && abs.n_points == 2 * 100, "{abs:?}");
    // Without a frame there are no absolute figures.
    assert!(
        dualcal::metrics::absolute_stats(&case.dataset, &nominal, &PerSide::default(), Split::Ver)
            .unwrap()
            .is_none()
    );
}

/// `--hold-kinematics`: only the tracker frame and the reflectors are fitted (the nominal robot's
/// figure with its frame and markers known); refused with a method that does not see the frame.
#[test]
fn holding_the_kinematics_fits_only_the_frame_and_the_reflectors() {
    let dir = tempfile::tempdir().unwrap();
    let case = simulate(dir.path(), false, 95, &[0], (120, 80));
    let nominal = case.robot.nominal_model_for(&case.dataset);
    let settings = CalibrationSettings {
        method: Method::Position,
        hold_kinematics: true,
        ..CalibrationSettings::default()
    };
    let result = common::calibrate(&case.dataset, &nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.warnings());
    let stages: Vec<Stage> = result.stages.iter().map(|s| s.stage).collect();
    assert_eq!(stages, [Stage::Arms], "no step 2");
    for side in Side::BOTH {
        let (arm, start) = (result.calibrated.arm(side), nominal.arm(side));
        let (now, was) = (arm.to_vector(), start.to_vector());
        let k = start.reflector_offset();
        assert_eq!(now.rows(0, k), was.rows(0, k), "{side}: kinematics held");
        assert!((now.rows(k, now.len() - k) - was.rows(k, was.len() - k)).norm() > 1e-3);
        assert!(result.tracker_from_base[side].is_some());
    }
    assert_eq!(
        result.calibrated.left_base_from_right_base,
        nominal.left_base_from_right_base
    );
    let err = Calibrator::new(&case.dataset, &nominal)
        .settings(CalibrationSettings {
            hold_kinematics: true,
            ..CalibrationSettings::default()
        })
        .run()
        .unwrap_err();
    assert!(err.to_string().contains("`position` or `pose`"), "{err}");
}

/// Without `--method`: the absolute positions for one marker per hand measured together in one
/// frame (the camera frame is what such data can give), the paper's minimax otherwise.
#[test]
fn the_default_method_follows_the_data() {
    use dualcal::solver::{default_method, default_method_reason};
    let dir = tempfile::tempdir().unwrap();
    let mut ds = simulate(dir.path(), false, 96, &[0], (60, 40)).dataset;
    assert_eq!(
        default_method(&ds),
        Method::Minimax,
        "not measured together"
    );
    ds.measured_together = true;
    assert_eq!(default_method(&ds), Method::Position);
    assert!(
        default_method_reason(&ds)
            .unwrap()
            .contains("one marker per hand")
    );
    ds.arms.right.station = Some("B".into());
    ds.arms.left.station = Some("A".into());
    assert_eq!(
        default_method(&ds),
        Method::Minimax,
        "two stations: no one frame"
    );
    let three = simulate(dir.path(), true, 97, &[0, 1, 2], (60, 40)).dataset;
    let mut three = three;
    three.measured_together = true;
    assert_eq!(default_method(&three), Method::Minimax, "three reflectors");
}
