//! Beyond geometry (issue 21): simulated data whose joints give under gravity and whose gears are off
//! by a twice-per-revolution error (the simulator's `JointErrorModel`, the robustness study's sizes:
//! 0.5 mrad per metre of gravity lever, 1 mrad gear amplitude, 20 µm tracker noise), calibrated with the
//! geometric model and with the full model (`elastic` + `harmonic`).
//!
//! The noise floor is what the *true* full model gives on the verification configurations: the true
//! geometry with the simulator's compliance and gear errors written as the error model's parameters
//! (the simulator's torque proxy is one unit mass at each frame origin downstream of the joint — the
//! error model's held lumped masses — so `κ = c/g` mrad/(N·m) for `c` mrad/m, and
//! `A sin(2q + φ) = A sin φ cos 2q + A cos φ sin 2q`). The test prints every figure.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::dataset::Split;
use dualcal::kinematics::{DualArmModel, ErrorTerms, joint_errors::STANDARD_GRAVITY_M_S2};
use dualcal::metrics::{AccuracyReport, evaluate};
use dualcal::robot::RobotDescription;
use dualcal::side::Side;
use dualcal::simulate::{
    SimOptions, SimOutput, paper_options, simulate_with_robot, unmodelled_joint_errors,
};
use dualcal::solver::{CalibrationSettings, Method};
use nalgebra::Vector3;

fn simulate(seed: u64) -> (SimOutput, RobotDescription) {
    let robot = RobotDescription::builtin_irb14000();
    let opts = SimOptions {
        joint_error: Some(unmodelled_joint_errors()),
        ..paper_options(seed, 220, 120)
    };
    (
        simulate_with_robot(&opts, &robot).expect("simulation"),
        robot,
    )
}

/// The true model with the simulator's joint errors as the full model's parameters.
fn true_full_model(sim: &SimOutput, gravity_in_left_base: Vector3<f64>) -> DualArmModel {
    let j = unmodelled_joint_errors();
    assert_eq!(j.periods_per_rev, 2.0);
    let full = ErrorTerms::from_name("full").unwrap();
    let mut model = sim
        .truth
        .clone()
        .with_error_terms(full, gravity_in_left_base);
    for side in Side::BOTH {
        let arm = model.arm(side);
        let off = arm.error_offset();
        let mut v = arm.to_vector();
        for k in off..arm.param_count() {
            let name = arm.param_name(k);
            let joint = |n: &str| n[1..2].parse::<usize>().unwrap() - 1;
            let phase = |n: &str| sim.joint_error_phases_rad[side][joint(n)];
            v[k] = if name.ends_with(".k_axis") {
                j.compliance_mrad_per_m / STANDARD_GRAVITY_M_S2
            } else if name.ends_with(".h2_cos") {
                j.periodic_amplitude_mrad * 1e-3 * phase(&name).sin()
            } else if name.ends_with(".h2_sin") {
                j.periodic_amplitude_mrad * 1e-3 * phase(&name).cos()
            } else {
                v[k] // no bending, no first harmonic (the masses are the model's: 1 kg per link)
            };
        }
        *model.arm_mut(side) = arm.with_vector(&v);
    }
    model
}

fn rms(r: &AccuracyReport) -> [f64; 2] {
    [
        r.relative_left.unwrap().pos_rms_mm,
        r.relative_right.unwrap().pos_rms_mm,
    ]
}

#[test]
fn the_full_model_reaches_the_noise_floor_where_geometry_stays_far_above() {
    let (sim, robot) = simulate(5);
    let gravity = Vector3::from(robot.gravity_in_left_base(None));
    let truth = true_full_model(&sim, gravity);
    let ver = |m: &DualArmModel| evaluate(&sim.dataset, m, Split::Ver).unwrap();
    let floor = rms(&ver(&truth));
    // The true geometry alone (what a perfect geometric calibration could at best explain).
    let geometry_truth = rms(&ver(&sim.truth));
    let run = |model: &str, method: Method| {
        let settings = CalibrationSettings {
            method,
            model: ErrorTerms::from_name(model).unwrap(),
            gravity_in_left_base: Some(gravity.into()),
            ..Default::default()
        };
        let result = common::calibrate(&sim.dataset, &sim.nominal, &settings);
        assert!(
            result.is_converged(),
            "{model} {method:?}: {:?}",
            result.stages
        );
        assert_eq!(result.calibrated.error_terms(), settings.model);
        rms(&ver(&result.calibrated))
    };
    let geometric = run("geometric", Method::Minimax);
    let full = run("full", Method::Minimax);
    let full_lsq = run("full", Method::LeastSquares);
    let geometric_lsq = run("geometric", Method::LeastSquares);
    for (i, side) in ["left", "right"].into_iter().enumerate() {
        eprintln!(
            "relative {side} RMS on verification, mm: noise floor (true full model) {:.4}, true \
             geometry alone {:.4}, geometric minimax {:.4} ({:.1}×), geometric lsq {:.4} ({:.1}×), full \
             minimax {:.4} ({:.2}×), full lsq {:.4} ({:.2}×)",
            floor[i],
            geometry_truth[i],
            geometric[i],
            geometric[i] / floor[i],
            geometric_lsq[i],
            geometric_lsq[i] / floor[i],
            full[i],
            full[i] / floor[i],
            full_lsq[i],
            full_lsq[i] / floor[i],
        );
        assert!(
            geometric[i] > 10.0 * floor[i],
            "{side}: {geometric:?} vs {floor:?}"
        );
        assert!(full[i] <= 1.2 * floor[i], "{side}: {full:?} vs {floor:?}");
        assert!(
            full_lsq[i] <= 1.2 * floor[i],
            "{side}: {full_lsq:?} vs {floor:?}"
        );
    }
}

#[test]
fn the_full_model_survives_the_parameter_file_and_leaves_the_urdf_geometric() {
    let (sim, robot) = simulate(6);
    let settings = CalibrationSettings {
        model: ErrorTerms::from_name("elastic").unwrap(),
        gravity_in_left_base: Some(robot.gravity_in_left_base(None)),
        ..Default::default()
    };
    let result = common::calibrate(&sim.dataset, &sim.nominal, &settings);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("params.json");
    let file = dualcal::params::ParamsFile::from_calibration(&result, &sim.dataset);
    file.write(&path).unwrap();
    let back = dualcal::params::read_model_for(&path, &robot).unwrap();
    assert_eq!(back.error_terms(), settings.model);
    for side in Side::BOTH {
        assert_eq!(
            back.arm(side).to_vector(),
            result.calibrated.arm(side).to_vector(),
            "{side}"
        );
        let masses = |m: &DualArmModel| {
            m.arm(side)
                .errors
                .model
                .as_ref()
                .unwrap()
                .link_masses()
                .to_vec()
        };
        assert_eq!(masses(&back), masses(&result.calibrated), "{side}");
    }
    let a = evaluate(&sim.dataset, &back, Split::Ver).unwrap();
    let b = evaluate(&sim.dataset, &result.calibrated, Split::Ver).unwrap();
    // The same figures (the base transform goes through the file's rounding).
    for (x, y) in rms(&a).into_iter().zip(rms(&b)) {
        assert!((x - y).abs() <= 1e-9 * y, "{x} vs {y}");
    }
    // A compliance in the file that is not the model's is refused with its field.
    let text = std::fs::read_to_string(&path).unwrap();
    let bad = text.replacen("\"j1.k_axis\"", "\"j9.k_axis\"", 1);
    assert_ne!(bad, text);
    std::fs::write(&path, bad).unwrap();
    let err = dualcal::params::read_model_for(&path, &robot)
        .unwrap_err()
        .to_string();
    assert!(err.contains("j9.k_axis"), "{err}");
    // The overlay carries them for the software that compensates: both arms, every parameter.
    let overlay = dualcal::urdf_export::calibrated_overlay(&robot, &result.calibrated).unwrap();
    assert_eq!(overlay.beyond_geometry.len(), 2);
    let left = result.calibrated.arm(Side::Left);
    let k = (left.error_offset()..left.param_count())
        .find(|&k| left.param_name(k) == "j2.k_axis")
        .unwrap();
    assert!(
        overlay.beyond_geometry[0]
            .parameters
            .contains(&("j2.k_axis".to_string(), left.to_vector()[k]))
    );
    let yaml = overlay.to_yaml();
    assert!(
        yaml.contains("beyond_geometry:\n  - arm: \"left\"\n    model: \"elastic\""),
        "{yaml}"
    );
    assert!(yaml.contains(&format!("\"j2.k_axis\": {:?}", left.to_vector()[k])));
    // The URDF holds the geometry and says so.
    let urdf = dualcal::urdf_export::calibrated_urdf(&robot, &result.calibrated).unwrap();
    assert!(urdf.contains("a URDF cannot hold them"), "{}", &urdf[..400]);
    let geometric =
        dualcal::urdf_export::calibrated_urdf(&robot, &result.calibrated.geometric()).unwrap();
    assert!(!geometric.contains("a URDF cannot hold them"));
}

/// What the data cannot separate is held and named: a waist turning about the vertical carries no
/// gravity torque about its axis, so its axis compliance is unidentifiable (its bending across the axis
/// is not); the torso's compliances are identified once, for both arms, and the calibration converges.
#[test]
fn a_vertical_waist_has_no_axis_compliance_to_identify() {
    use dualcal::robot::{ArmLinks, LoadOptions};
    use dualcal::side::PerSide;
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("torso.urdf");
    std::fs::write(&urdf, robots::shared_torso_urdf(false)).unwrap();
    let [(lb, lt), (rb, rt)] = robots::SHARED_TORSO_ARMS;
    let options = LoadOptions {
        arms: PerSide::new(Some(ArmLinks::new(lb, lt)), Some(ArmLinks::new(rb, rt))),
        ..Default::default()
    };
    let robot = RobotDescription::load(&urdf, &options).unwrap();
    let sim = simulate_with_robot(&paper_options(8, 220, 120), &robot).unwrap();
    let settings = CalibrationSettings {
        model: ErrorTerms::from_name("elastic").unwrap(),
        gravity_in_left_base: Some(robot.gravity_in_left_base(None)),
        ..Default::default()
    };
    let result = common::calibrate(&sim.dataset, &sim.nominal, &settings);
    assert!(result.is_converged(), "{:?}", result.stages);
    let report = result.identifiability.left.as_ref().unwrap();
    let waist = "yumi_base_link_to_body";
    let axis = report
        .fixed
        .iter()
        .find(|f| f.name == format!("{waist}.k_axis"))
        .unwrap_or_else(|| panic!("{waist}.k_axis is not held: {:?}", report.fixed));
    eprintln!("{}: {}", axis.name, axis.reason);
    assert!(
        axis.reason.contains("do not depend on it"),
        "{}",
        axis.reason
    );
    let left = result.calibrated.arm(Side::Left);
    let free: Vec<String> = report.free.iter().map(|&k| left.param_name(k)).collect();
    assert!(free.contains(&format!("{waist}.k_x")), "{free:?}");
    // One torso: its compliances are the robot's, identified once from both arms' data and carried
    // by both arms' models alike; the arms' own are theirs.
    let right = result.calibrated.arm(Side::Right);
    let shared = result.calibrated.shared_joints();
    let value = |arm: &dualcal::kinematics::ArmModel, name: &str| {
        (arm.error_offset()..arm.param_count())
            .find(|&k| arm.param_name(k) == name)
            .map(|k| arm.to_vector()[k])
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let k_x = format!("{waist}.k_x");
    assert!(value(left, &k_x) != 0.0);
    assert_eq!(value(left, &k_x), value(right, &k_x));
    let error_pairs: Vec<String> = shared
        .params
        .iter()
        .filter(|&&(a, _)| a >= left.error_offset())
        .map(|&(a, b)| {
            assert_eq!(left.param_name(a), right.param_name(b));
            left.param_name(a)
        })
        .collect();
    assert!(error_pairs.contains(&k_x), "{error_pairs:?}");
    assert!(
        error_pairs.iter().all(|n| n.starts_with(waist)),
        "only the torso's error parameters are shared: {error_pairs:?}"
    );
}

/// Where the URDF has inertials, the held masses are its links': each movable joint carries its child
/// link and everything fixed to it, lumped in the next joint's frame, and the torque follows.
#[test]
fn urdf_inertials_are_the_held_masses() {
    use dualcal::robot::{ArmLinks, LoadOptions};
    use dualcal::side::PerSide;
    // One revolute joint about y; the upper link 2 kg at 0.5 m, a tool fixed at its end 1 kg 0.1 m
    // further: 1.6 kg·m of lever in all.
    let urdf = r#"<robot name="one">
      <link name="base"/>
      <link name="upper"><inertial><origin xyz="0.5 0 0"/><mass value="2"/>
        <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
      <link name="tool"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
        <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="upper"/>
        <origin xyz="0 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="fix" type="fixed"><parent link="upper"/><child link="tool"/><origin xyz="0.5 0 0"/></joint>
    </robot>"#;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("one.urdf");
    std::fs::write(&path, urdf).unwrap();
    let arm = Some(ArmLinks::new("base", "tool"));
    let options = LoadOptions {
        arms: PerSide::new(arm.clone(), arm),
        ..Default::default()
    };
    let robot = RobotDescription::load(&path, &options).unwrap();
    let masses = robot
        .lumped_masses(Side::Left)
        .expect("the URDF's inertials");
    assert_eq!(masses.len(), 1);
    let (m, s) = masses[0];
    assert!((m - 3.0).abs() < 1e-12, "{m}");
    // In the tip (tool) frame: the upper link's centre at its origin, the tool's 100 mm out.
    assert!((nalgebra::Vector3::from(s) - nalgebra::Vector3::new(100.0, 0.0, 0.0)).norm() < 1e-9);
    // The joint's deflection under 0.1 mrad/(N·m): 1.6 kg·m · g.
    let nominal = robot.nominal_model([nalgebra::Vector3::zeros()]);
    let model = nominal
        .with_error_terms(
            ErrorTerms::from_name("elastic-axis").unwrap(),
            -Vector3::z(),
        )
        .with_held_masses(&PerSide::new(Some(masses.clone()), Some(masses)));
    let arm = model.arm(Side::Left);
    let mut v = arm.to_vector();
    v[arm.error_offset()] = 0.1;
    let arm = arm.with_vector(&v);
    let inc = arm.errors.increments(&[0.0]).unwrap();
    let expected = 0.1e-3 * 1.6 * STANDARD_GRAVITY_M_S2;
    assert!(
        (inc.slots[0].1.abs() - expected).abs() < 1e-12,
        "{:?}",
        inc.slots
    );
}

/// Motor-side transmission errors (issue 21: "and of the motor angle where a gear ratio is given"):
/// data whose joints are off by a once-per-motor-turn error seen through a 1:100 reduction (an
/// eccentric motor gear or encoder: 0.3 mrad at the joint, random phases, on ABB axes 1, 2, 3 and 5 of
/// both arms) and 20 µm tracker noise, measured in the left arm's base frame. The joint-side
/// harmonics cannot follow an error that turns a hundred times faster; with the gear ratios given,
/// the harmonic model identifies the motor's harmonics and reaches the noise floor.
#[test]
fn motor_side_harmonics_need_the_gear_ratio_and_then_reach_the_noise_floor() {
    use rand::{Rng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let robot = RobotDescription::builtin_irb14000();
    let mut sim = simulate_with_robot(&paper_options(6, 220, 120), &robot).expect("simulation");
    let ratios: Vec<(String, f64)> = ["j1", "j2", "j3", "j5"]
        .iter()
        .map(|j| (j.to_string(), 100.0))
        .collect();
    let harmonic = ErrorTerms::from_name("harmonic").unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(61);
    let mut truth = sim
        .truth
        .clone()
        .with_error_terms(harmonic, -Vector3::z())
        .with_gear_ratios(&ratios);
    for side in Side::BOTH {
        let arm = truth.arm(side);
        let mut v = arm.to_vector();
        let mut motor = 0;
        for k in arm.error_offset()..arm.param_count() {
            let name = arm.param_name(k);
            if name.ends_with(".m1_cos") {
                let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                v[k] = 0.3e-3 * phase.cos();
                v[k + 1] = 0.3e-3 * phase.sin();
                motor += 1;
            }
        }
        assert_eq!(motor, 4, "{side:?}: one motor term per geared joint");
        *truth.arm_mut(side) = arm.with_vector(&v);
    }
    // Every point measured with the true model in the left arm's base (the tracker frame of this
    // test), with 20 µm noise per axis.
    let noise = Normal::new(0.0, 0.02).unwrap();
    for side in Side::BOTH {
        let left_from_arm = match side {
            Side::Left => nalgebra::Isometry3::identity(),
            Side::Right => truth.left_base_from_right_base,
        };
        for m in &mut sim.dataset.arms[side].measurements {
            let fk = truth.arm(side).reflector_fk(&m.q_rad);
            for (p, model) in m.tracker_points_mm.iter_mut().zip(&fk.points_mm) {
                *p = (left_from_arm * nalgebra::Point3::from(*model)).coords
                    + Vector3::from_fn(|_, _| noise.sample(&mut rng));
            }
        }
    }
    let ver = |m: &DualArmModel| rms(&evaluate(&sim.dataset, m, Split::Ver).unwrap());
    let floor = ver(&truth);
    let run = |gear_ratios: Vec<(String, f64)>| {
        let settings = CalibrationSettings {
            model: harmonic,
            gear_ratios,
            ..Default::default()
        };
        let result = common::calibrate(&sim.dataset, &sim.nominal, &settings);
        assert!(result.is_converged(), "{:?}", result.stages);
        (ver(&result.calibrated), result)
    };
    let (without, _) = run(Vec::new());
    let (with, result) = run(ratios.clone());
    for (i, side) in ["left", "right"].into_iter().enumerate() {
        eprintln!(
            "relative {side} RMS on verification, mm: noise floor {:.4}, harmonic without gear ratios \
             {:.4} ({:.2}×), with them {:.4} ({:.2}×)",
            floor[i],
            without[i],
            without[i] / floor[i],
            with[i],
            with[i] / floor[i]
        );
        assert!(
            without[i] > 2.0 * floor[i],
            "{side}: {without:?} vs {floor:?}"
        );
        assert!(with[i] <= 1.2 * floor[i], "{side}: {with:?} vs {floor:?}");
    }
    // The identified motor amplitudes are the true ones (axes 1–3 within 10 % of the 0.3 mrad
    // amplitude; axis 5's short lever to the reflectors sees them less: within a third), and the
    // ratios travel with the model.
    for side in Side::BOTH {
        let (t, c) = (truth.arm(side), result.calibrated.arm(side));
        let m = c.errors.model.as_ref().unwrap();
        assert_eq!(m.gear_ratios(), ratios);
        for k in c.error_offset()..c.param_count() {
            if c.param_name(k).contains(".m1_") {
                let (truth_rad, found) = (t.to_vector()[k], c.to_vector()[k]);
                eprintln!(
                    "{side:?} {}: {found:.3e} vs true {truth_rad:.3e}",
                    c.param_name(k)
                );
                let tolerance = if c.param_name(k).starts_with("j5.") {
                    0.1e-3
                } else {
                    0.03e-3
                };
                assert!(
                    (truth_rad - found).abs() < tolerance,
                    "{side:?} {}: {found} vs {truth_rad}",
                    c.param_name(k)
                );
            }
        }
    }
    // The parameter file and the overlay carry the ratios; the file read back is the same model.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("params.json");
    dualcal::params::ParamsFile::from_calibration(&result, &sim.dataset)
        .write(&path)
        .unwrap();
    let back = dualcal::params::read_model_for(&path, &robot).unwrap();
    for side in Side::BOTH {
        let arm = back.arm(side);
        assert_eq!(arm.to_vector(), result.calibrated.arm(side).to_vector());
        assert_eq!(arm.errors.model.as_ref().unwrap().gear_ratios(), ratios);
    }
    let yaml = dualcal::urdf_export::calibrated_overlay(&robot, &result.calibrated)
        .unwrap()
        .to_yaml();
    assert!(
        yaml.contains("    gear_ratios:\n      \"j1\": 100.0\n"),
        "{yaml}"
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let bad = text.replacen("\"j2\": 100.0", "\"j2\": 0.0", 1);
    assert_ne!(bad, text);
    std::fs::write(&path, bad).unwrap();
    let err = dualcal::params::read_model_for(&path, &robot)
        .unwrap_err()
        .to_string();
    assert!(err.contains("gear_ratios.j2"), "{err}");
}
