//! The paper's comparison methods (its Table 1) through the one engine: ref. [26]'s single-reflector
//! distances, ref. [19]'s full poses and ref. [18]'s absolute positions in step 1; ref. [26]'s
//! collaborative distances and ref. [28]'s bases in the tracker frame in step 2. Each recovers known
//! parameters from noise-free data, reaches the noise floor where its model can on paper-like data,
//! and fails with a typed error or termination on data it cannot use.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::{Dataset, Split};
use dualcal::metrics::{AccuracyReport, evaluate};
use dualcal::robot::RobotDescription;
use dualcal::side::Side;
use dualcal::simulate::{self, SimOptions, SimOutput};
use dualcal::solver::{
    BaseMethod, CalibrationError, CalibrationResult, CalibrationSettings, Calibrator, Method,
    Reflector, Stage, Termination,
};
use nalgebra::{Isometry3, Vector3};

fn settings(method: Method, base_method: BaseMethod) -> CalibrationSettings {
    CalibrationSettings {
        method,
        base_method,
        ..CalibrationSettings::default()
    }
}

/// The built-in robot's simulation without collision checks (fast), `n` configurations of which `cal`
/// are for calibration; tracker noise scaled by `noise` (1 = the FARO Vantage's MPE).
fn sim(seed: u64, n: usize, cal: usize, noise: f64) -> SimOutput {
    let robot = RobotDescription::builtin_irb14000();
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let mut opts = simulate::paper_options(seed, n, cal);
    opts.tracker.mpe_um *= noise;
    opts.tracker.mpe_um_per_m *= noise;
    simulate::simulate(&opts, &nominal, &|_, _| false).expect("simulation")
}

fn run(ds: &Dataset, sim: &SimOutput, s: CalibrationSettings) -> CalibrationResult {
    let r = common::calibrate(ds, &sim.nominal, &s);
    for st in &r.stages {
        assert!(
            st.termination.is_converged(),
            "{:?}/{:?}: {st:?}",
            s.method,
            s.base_method
        );
    }
    r
}

/// The true transforms `tracker_from_<side>_base` of a simulation.
fn true_tracker_frames(sim: &SimOutput) -> [Isometry3<f64>; 2] {
    [
        sim.tracker_from_left_base,
        sim.tracker_from_left_base * sim.truth.left_base_from_right_base,
    ]
}

fn iso_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let d = a.inverse() * b;
    (d.translation.vector.norm(), d.rotation.angle())
}

#[test]
fn each_new_method_recovers_known_parameters_from_noise_free_data() {
    let sim = sim(11, 60, 40, 1e-9);
    let ver = |r: &CalibrationResult| evaluate(&sim.dataset, &r.calibrated, Split::Ver).unwrap();
    // Position and pose: the whole model, and both tracker frames.
    for method in [Method::Position, Method::Pose] {
        let r = run(&sim.dataset, &sim, settings(method, BaseMethod::Absolute));
        let v = ver(&r);
        for s in [
            v.relative_left.unwrap(),
            v.relative_right.unwrap(),
            v.collaborative.unwrap(),
        ] {
            assert!(s.pos_rms_mm < 1e-5, "{method:?}: {s:?}");
            assert!(s.ori_rms_rad.unwrap() < 1e-7, "{method:?}: {s:?}");
        }
        // The transforms identified absorb what the arm's model fixes: joint 1's d and θ (a shift
        // along and a turn about the first axis move the whole arm rigidly).
        for (side, truth) in Side::BOTH.into_iter().zip(true_tracker_frames(&sim)) {
            let found = r.tracker_from_base[side].expect("identified");
            let (t, n) = (
                sim.truth.arm(side).dh().unwrap(),
                sim.nominal.arm(side).dh().unwrap(),
            );
            let absorbed = Isometry3::new(
                Vector3::z() * (t[0].d_mm - n[0].d_mm),
                Vector3::z() * (t[0].theta_rad - n[0].theta_rad),
            );
            let (dt, dr) = iso_distance(&found, &(truth * absorbed));
            assert!(
                dt < 1e-5 && dr < 1e-8,
                "{method:?} {side}: {dt} mm, {dr} rad"
            );
            // With the calibrated arm it reproduces the measured points themselves.
            let arm = r.calibrated.arm(side);
            for m in &sim.dataset.arm(side).measurements {
                let p = arm.reflector_fk(&m.q_rad).points_mm;
                for (pk, mk) in p.iter().zip(&m.tracker_points_mm) {
                    let e = (found.transform_point(&(*pk).into()).coords - mk).norm();
                    assert!(e < 1e-5, "{method:?} {side} {}: {e} mm", m.id);
                }
            }
        }
        // The parameters the data see are those of the truth (the fixed ones stay nominal, so the
        // comparison is of the predictions above, plus the identified reflector triangle).
        for side in Side::BOTH {
            let (t, c) = (
                &sim.truth.arm(side).reflectors_mm,
                &r.calibrated.arm(side).reflectors_mm,
            );
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let d = ((t[a] - t[b]).norm() - (c[a] - c[b]).norm()).abs();
                assert!(
                    d < 1e-6,
                    "{method:?} {side}: triangle side {a}{b} off by {d} mm"
                );
            }
        }
    }
    // One reflector's distances: that reflector's distances are reproduced exactly; the others'
    // coordinates are nominal and the report says so.
    for reflector in Reflector::ALL {
        let s = CalibrationSettings {
            reflector: Some(reflector),
            ..settings(Method::DistanceSingle, BaseMethod::Distance)
        };
        let r = run(&sim.dataset, &sim, s);
        let v = ver(&r);
        let k = reflector.index();
        for side in Side::BOTH {
            assert_eq!(r.reflector_used[side], Some(reflector));
            let rms = v.relative(side).unwrap().pos_rms_per_reflector_mm[k];
            assert!(rms < 1e-5, "reflector {reflector} {side}: {rms}");
            let rep = r.identifiability[side].as_ref().unwrap();
            let others: Vec<_> = rep
                .fixed
                .iter()
                .filter(|f| f.reason.starts_with("not observed"))
                .collect();
            assert_eq!(others.len(), 6, "{:?}", rep.fixed);
            assert_eq!(
                r.calibrated.arm(side).reflectors_mm[(k + 1) % 3],
                sim.nominal.arm(side).reflectors_mm[(k + 1) % 3]
            );
        }
        assert!(r.tracker_from_base.left.is_none());
    }
}

#[test]
fn new_methods_work_on_a_urdf_chain() {
    let dir = tempfile::tempdir().unwrap();
    let robot =
        RobotDescription::load(&robots::write_yumi_like(dir.path()), &Default::default()).unwrap();
    let mut opts = simulate::paper_options(5, 60, 40);
    opts.tracker.mpe_um = 1e-6;
    opts.tracker.mpe_um_per_m = 0.0;
    let sim = simulate::simulate_with_robot(&opts, &robot).unwrap();
    for (method, base) in [
        (Method::Position, BaseMethod::Absolute),
        (Method::Pose, BaseMethod::Distance),
        (Method::DistanceSingle, BaseMethod::Minimax),
    ] {
        let mut s = settings(method, base);
        s.progress_tolerance = 0.0;
        let r = Calibrator::new(&sim.dataset, &sim.nominal)
            .settings(s)
            .run()
            .unwrap();
        assert!(r.is_converged(), "{method:?}: {:?}", r.warnings());
        let v = evaluate(&sim.dataset, &r.calibrated, Split::Ver).unwrap();
        let k = r.reflector_used.left.map(|r| r.index());
        for side in Side::BOTH {
            let rms = match k {
                Some(k) => v.relative(side).unwrap().pos_rms_per_reflector_mm[k],
                None => v.relative(side).unwrap().pos_rms_mm,
            };
            assert!(rms < 1e-4, "{method:?} {side}: {rms} mm");
        }
        if base != BaseMethod::Minimax || method != Method::DistanceSingle {
            assert!(v.collaborative.unwrap().pos_rms_per_reflector_mm[k.unwrap_or(0)] < 1e-3);
        }
    }
}

/// What the acceptance compares: positioning RMS* and orientation RMS on the verification split.
fn figures(r: &AccuracyReport) -> [(f64, f64); 3] {
    [
        r.relative_left.unwrap(),
        r.relative_right.unwrap(),
        r.collaborative.unwrap(),
    ]
    .map(|s| (s.pos_rms_mm, s.ori_rms_rad.unwrap()))
}

#[test]
fn paper_like_data_every_method_reaches_the_noise_floor_where_its_model_can() {
    let sim = sim(21, 220, 120, 1.0);
    let ds = &sim.dataset;
    let floor = evaluate(ds, &sim.truth, Split::Ver).unwrap();
    let minimax = run(ds, &sim, CalibrationSettings::default());
    let minimax_ver = evaluate(ds, &minimax.calibrated, Split::Ver).unwrap();
    let within = |what: &str, got: f64, truth: f64| {
        eprintln!(
            "{what}: {got:.6} (truth {truth:.6}, ratio {:.3})",
            got / truth
        );
        assert!(got <= 1.1 * truth, "{what}: {got} vs the truth's {truth}");
    };
    let t = figures(&floor);
    // Step 1 methods that see the whole arm, each with the paper's step 2.
    for method in [
        Method::Minimax,
        Method::LeastSquares,
        Method::Pose,
        Method::Position,
    ] {
        let r = run(ds, &sim, settings(method, BaseMethod::Minimax));
        let v = figures(&evaluate(ds, &r.calibrated, Split::Ver).unwrap());
        for (i, name) in ["left", "right", "collaborative"].iter().enumerate() {
            within(&format!("{method:?} {name} pos RMS* mm"), v[i].0, t[i].0);
            within(&format!("{method:?} {name} ori RMS rad"), v[i].1, t[i].1);
        }
    }
    // Step 2 methods with the paper's step 1.
    for base in [BaseMethod::Distance, BaseMethod::Absolute] {
        let r = run(ds, &sim, settings(Method::Minimax, base));
        let v = figures(&evaluate(ds, &r.calibrated, Split::Ver).unwrap());
        within(
            &format!("{base:?} collaborative pos RMS* mm"),
            v[2].0,
            t[2].0,
        );
        within(
            &format!("{base:?} collaborative ori RMS rad"),
            v[2].1,
            t[2].1,
        );
    }
    // One reflector: its own distances at the floor; the orientation it cannot see at least twice
    // minimax's error (paper Table 5: 0.0142 against 0.0048 rad, right arm).
    let r = run(
        ds,
        &sim,
        settings(Method::DistanceSingle, BaseMethod::Minimax),
    );
    let v = evaluate(ds, &r.calibrated, Split::Ver).unwrap();
    for side in Side::BOTH {
        let k = r.reflector_used[side].unwrap().index();
        within(
            &format!("distance-single {side} reflector {k} pos RMS mm"),
            v.relative(side).unwrap().pos_rms_per_reflector_mm[k],
            floor.relative(side).unwrap().pos_rms_per_reflector_mm[k],
        );
        let (single, paper) = (
            v.relative(side).unwrap().ori_rms_rad.unwrap(),
            minimax_ver.relative(side).unwrap().ori_rms_rad.unwrap(),
        );
        eprintln!("distance-single {side} ori RMS {single:.6} rad, minimax {paper:.6} rad");
        assert!(single >= 2.0 * paper, "{side}: {single} vs minimax {paper}");
    }
}

#[test]
fn too_few_configurations_are_refused_per_method() {
    let sim = sim(3, 30, 30, 1.0);
    for (method, needed) in [
        (Method::DistanceSingle, 11),
        (Method::Position, 5),
        (Method::Pose, 7),
    ] {
        let ds = sim.dataset.with_cal_subset(needed - 1);
        let err = Calibrator::new(&ds, &sim.nominal)
            .settings(settings(method, BaseMethod::Minimax))
            .run()
            .unwrap_err();
        assert!(
            matches!(err, CalibrationError::TooFewConfigurations { found, needed: n, method: m, .. }
                if found == needed - 1 && n == needed && m == method.name()),
            "{method:?}: {err}"
        );
        assert!(err.to_string().contains(method.name()), "{err}");
        let ds = sim.dataset.with_cal_subset(needed);
        Calibrator::new(&ds, &sim.nominal)
            .settings(settings(method, BaseMethod::Minimax))
            .run()
            .unwrap_or_else(|e| panic!("{method:?} with {needed}: {e}"));
    }
}

#[test]
fn identical_configurations_are_rank_deficient() {
    let mut sim = sim(4, 30, 30, 1.0);
    for arm in [&mut sim.dataset.arms.left, &mut sim.dataset.arms.right] {
        let first = arm.measurements[0].clone();
        for m in arm.measurements.iter_mut() {
            m.q_rad = first.q_rad.clone();
            m.tracker_points_mm = first.tracker_points_mm.clone();
        }
    }
    for &method in Method::ALL {
        let err = Calibrator::new(&sim.dataset, &sim.nominal)
            .settings(settings(method, BaseMethod::Minimax))
            .run()
            .unwrap_err();
        assert!(
            matches!(
                err,
                CalibrationError::RankDeficient {
                    stage: Stage::Arm(Side::Left),
                    ..
                }
            ),
            "{method:?}: {err}"
        );
    }
}

#[test]
fn a_joint_that_never_moves_fixes_what_it_hides_and_the_rest_converges() {
    let mut sim = sim(5, 80, 80, 1.0);
    // Joint 6 (chain order) held at one value on the left arm: re-measure with it held.
    let t = sim.tracker_from_left_base;
    let arm = sim.truth.arm(Side::Left).clone();
    for m in sim.dataset.arms.left.measurements.iter_mut() {
        m.q_rad[5] = 0.4;
        m.tracker_points_mm = arm
            .reflector_fk(&m.q_rad)
            .points_mm
            .iter()
            .map(|p| t.transform_point(&(*p).into()).coords)
            .collect();
    }
    for method in [Method::DistanceSingle, Method::Position, Method::Pose] {
        let r = Calibrator::new(&sim.dataset, &sim.nominal)
            .settings(settings(method, BaseMethod::Minimax))
            .run()
            .unwrap();
        let left = r.stage(Stage::Arm(Side::Left)).unwrap();
        assert!(left.termination.is_converged(), "{method:?}: {left:?}");
        let fixed = r.identifiability.left.as_ref().unwrap().fixed.len();
        let right = r.identifiability.right.as_ref().unwrap().fixed.len();
        assert!(
            fixed > right,
            "{method:?}: {fixed} fixed on the left (joint 6 still), {right} on the right"
        );
    }
}

#[test]
fn collinear_measured_reflectors_are_refused_by_the_pose_method() {
    let mut sim = sim(6, 30, 30, 1.0);
    let m = &mut sim.dataset.arms.right.measurements[7];
    let (a, c) = (m.tracker_points_mm[0], m.tracker_points_mm[2]);
    m.tracker_points_mm[1] = (a + c) * 0.5;
    let err = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(settings(Method::Pose, BaseMethod::Minimax))
        .run()
        .unwrap_err();
    assert!(
        matches!(&err, CalibrationError::DegenerateReflectors { side: Side::Right, id, .. } if id == "R008"),
        "{err}"
    );
    // The other methods do not build tool frames: the bad row is only a large residual.
    for method in [Method::Position, Method::DistanceSingle] {
        let r = Calibrator::new(&sim.dataset, &sim.nominal)
            .settings(settings(method, BaseMethod::Minimax))
            .run()
            .unwrap();
        assert!(
            r.stages
                .iter()
                .all(|s| s.termination != Termination::NonFinite)
        );
    }
}

#[test]
fn a_reflector_for_a_method_that_uses_all_three_is_refused() {
    let sim = sim(7, 30, 30, 1.0);
    let err = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(CalibrationSettings {
            reflector: Some(Reflector::B),
            ..settings(Method::Position, BaseMethod::Minimax)
        })
        .run()
        .unwrap_err();
    assert!(matches!(err, CalibrationError::InvalidSettings(_)), "{err}");
    assert!(err.to_string().contains("distance-single"), "{err}");
}

#[test]
fn cancel_stops_a_comparison_method() {
    let sim = sim(8, 60, 60, 1.0);
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let f = flag.clone();
    let mut obs = move |e: &dualcal::solver::CalibrationEvent| {
        if let dualcal::solver::CalibrationEvent::Iteration(_) = e {
            f.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    };
    let r = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(settings(Method::Position, BaseMethod::Absolute))
        .observer(&mut obs)
        .cancel(flag)
        .run()
        .unwrap();
    assert_eq!(r.stages.len(), 1);
    assert_eq!(r.stages[0].termination, Termination::Cancelled);
    assert!(!r.is_converged());
}

fn dualcal(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_dualcal"))
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

#[test]
fn the_command_line_runs_every_method_and_evaluate_reads_what_it_writes() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("sim");
    let data = data.to_str().unwrap();
    ok(&[
        "simulate",
        "--out",
        data,
        "--seed",
        "9",
        "--configs",
        "50",
        "--cal",
        "35",
    ]);
    let json = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    for (method, base, reflector) in [
        ("position", "absolute", None),
        ("pose", "distance", None),
        ("distance-single", "minimax", Some("b")),
        ("lsq", "distance", None),
    ] {
        let out = dir.path().join(format!("{method}-{base}.json"));
        let mut args = vec![
            "calibrate",
            data,
            "--method",
            method,
            "--base-method",
            base,
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(r) = reflector {
            args.extend(["--reflector", r]);
        }
        let summary = ok(&args);
        assert!(
            summary.contains(&format!("method: step 1 `{method}`, step 2 `{base}`")),
            "{summary}"
        );
        let file = json(&out);
        assert_eq!(file["method"]["arm_method"], method);
        assert_eq!(file["method"]["base_method"], base);
        let frames = &file["tracker_frames"];
        if method == "position" || method == "pose" || base == "absolute" {
            assert!(
                frames["tracker_from_left_base"]["rotation"].is_array(),
                "{file}"
            );
            assert!(frames["tracker_from_right_base"]["translation"].is_array());
            assert!(
                summary.contains("tracker_from_left_base: translation"),
                "{summary}"
            );
        } else {
            assert!(frames.is_null());
        }
        if let Some(r) = reflector {
            assert_eq!(file["method"]["reflector"]["left"], r);
            assert!(
                summary.contains(&format!("reflector {r} used")),
                "{summary}"
            );
            let fixed = file["fixed_parameters"]["left"].to_string();
            assert!(fixed.contains("not observed"), "{fixed}");
        }
        let table = ok(&[
            "evaluate",
            data,
            "--params",
            out.to_str().unwrap(),
            "--split",
            "ver",
        ]);
        assert!(table.contains("Accuracy of the parameters"), "{table}");
    }
    // A reflector with a method that uses all three: refused, non-zero exit, naming the method.
    let out = dir.path().join("bad.json");
    let bad = dualcal(&[
        "calibrate",
        data,
        "--method",
        "minimax",
        "--reflector",
        "a",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("distance-single"));
    assert!(!out.exists());
    // Unknown method names are clap's business: the accepted ones are listed.
    let bad = dualcal(&["calibrate", data, "--method", "nope", "--out", "x.json"]);
    let err = String::from_utf8_lossy(&bad.stderr).into_owned();
    for name in ["minimax", "lsq", "distance-single", "pose", "position"] {
        assert!(err.contains(name), "{err}");
    }
}
