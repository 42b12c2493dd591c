//! The URDF description against the DH model: forward kinematics, the derived base transform,
//! the calibrated-URDF round trip, mesh resolution and loader errors.

mod common;

use dualcal::collision::CollisionWorld;
use dualcal::kinematics::{
    ArmModel, DualArmModel, N_JOINTS, N_PARAMS, joint_limits_rad, param_is_angle,
    rotation_angle_rad,
};
use dualcal::robot::{
    BUILTIN_IRB14000_URDF, GeometryKind, PackageMap, RobotDescription, RobotError, ShapeKind,
};
use dualcal::side::PerSide;
use dualcal::side::Side;
use dualcal::urdf_export::calibrated_urdf;
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn random_q(rng: &mut ChaCha8Rng) -> [f64; N_JOINTS] {
    let lim = joint_limits_rad();
    std::array::from_fn(|i| rng.random_range(lim[i].0..lim[i].1))
}

/// (translation error mm, rotation error rad) between two poses.
fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        rotation_angle_rad(&(a.rotation.inverse() * b.rotation).to_rotation_matrix()),
    )
}

/// Largest FK discrepancy between the URDF flange and `body_from_dh_base · model` over random q.
fn max_fk_error(
    robot: &RobotDescription,
    side: Side,
    arm: &ArmModel,
    base: &Isometry3<f64>,
    n: usize,
    seed: u64,
) -> (f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..n {
        let q = random_q(&mut rng);
        let (t, r) = pose_error(
            &robot.body_from_flange(side, &q),
            &(base * arm.base_from_flange(&q)),
        );
        worst = (worst.0.max(t), worst.1.max(r));
    }
    worst
}

#[test]
fn urdf_fk_equals_dh_fk() {
    let robot = RobotDescription::builtin_irb14000();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    let arm = ArmModel::nominal_irb14000(common::reflectors_mm());
    for (side, seed) in [(Side::Left, 1), (Side::Right, 2)] {
        let (t, r) = max_fk_error(&robot, side, &arm, &robot.body_from_dh_base(side), 50, seed);
        assert!(t < 1e-9, "{side}: {t:e} mm");
        assert!(r < 1e-12, "{side}: {r:e} rad");
    }
    // link_poses agrees with body_from_flange when both arms move.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (ql, qr) = (random_q(&mut rng), random_q(&mut rng));
    let poses = robot.link_poses(&ql, &qr);
    let get = |n: &str| poses.iter().find(|(name, _)| name == n).unwrap().1;
    let (t, r) = pose_error(
        &get("yumi_flange_l"),
        &robot.body_from_flange(Side::Left, &ql),
    );
    assert!(t < 1e-9 && r < 1e-12);
    let (t, r) = pose_error(
        &get("yumi_flange_r"),
        &robot.body_from_flange(Side::Right, &qr),
    );
    assert!(t < 1e-9 && r < 1e-12);
    assert_eq!(get("yumi_body"), Isometry3::identity());
}

#[test]
fn fk_check_detects_the_public_a3() {
    // Public YuMi URDFs have a3 = 41.88 mm instead of Table 3's 40.5 mm: the check must see it.
    let text = BUILTIN_IRB14000_URDF.replacen(
        "<origin xyz=\"0.0405 0 0.2515\"",
        "<origin xyz=\"0.04188 0 0.2515\"",
        2,
    );
    assert_ne!(text, BUILTIN_IRB14000_URDF);
    let robot = RobotDescription::load(
        dualcal::robot::RobotSource::Text {
            text: &text,
            path: None,
        },
        &Default::default(),
    )
    .unwrap();
    let arm = ArmModel::nominal_irb14000(common::reflectors_mm());
    let (t, _) = max_fk_error(
        &robot,
        Side::Left,
        &arm,
        &robot.body_from_dh_base(Side::Left),
        50,
        1,
    );
    assert!(t > 0.5, "{t}");
}

#[test]
fn derived_base_transform_matches_the_public_layout() {
    let robot = RobotDescription::builtin_irb14000();
    let b = robot.nominal_left_base_from_right_base();
    #[rustfmt::skip]
    let expected_r = Matrix3::new(
        0.2352, -0.8755, 0.4220,
        0.8746, 0.0012, -0.4849,
        0.4241, 0.4831, 0.7660,
    );
    let expected_t = Vector3::new(61.61, -70.77, -34.14);
    let r = b.rotation.to_rotation_matrix().into_inner();
    assert!((r - expected_r).abs().max() < 1e-3, "{r}");
    assert!(
        (b.translation.vector - expected_t).abs().max() < 0.01,
        "{}",
        b.translation.vector
    );
    // And the nominal model carries it.
    let model = robot.nominal_model(common::reflectors_mm());
    assert_eq!(model.left_base_from_right_base, b);
    assert_eq!(model.arms.left.reflectors_mm, common::reflectors_mm());
}

#[test]
fn dh_base_sits_on_the_joint1_axis_below_link1() {
    let robot = RobotDescription::builtin_irb14000();
    let zero = [0.0; N_JOINTS];
    let poses = robot.link_poses(&zero, &zero);
    for (side, link1) in [
        (Side::Left, "yumi_link_1_l"),
        (Side::Right, "yumi_link_1_r"),
    ] {
        let l1 = poses.iter().find(|(n, _)| n == link1).unwrap().1;
        let base = robot.body_from_dh_base(side);
        let z1 = l1.rotation * Vector3::z();
        // 66 mm below along the joint-1 axis, z axes aligned, x axes opposite (turned by π).
        assert!((l1.translation.vector - 66.0 * z1 - base.translation.vector).norm() < 1e-9);
        assert!(((base.rotation * Vector3::z()) - z1).norm() < 1e-12);
        assert!(((base.rotation * Vector3::x()) + l1.rotation * Vector3::x()).norm() < 1e-12);
    }
}

fn perturbed_model(robot: &RobotDescription, rng: &mut ChaCha8Rng) -> DualArmModel {
    let nominal = robot.nominal_model(common::reflectors_mm());
    let perturb = |arm: &ArmModel, rng: &mut ChaCha8Rng| {
        let mut v = arm.to_vector();
        for k in 0..N_PARAMS {
            v[k] += if param_is_angle(k) {
                rng.random_range(-0.01..0.01)
            } else {
                rng.random_range(-1.0..1.0)
            };
        }
        arm.with_vector(&v)
    };
    let db = Isometry3::from_parts(
        Translation3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ),
        UnitQuaternion::from_scaled_axis(Vector3::new(
            rng.random_range(-0.02..0.02),
            rng.random_range(-0.02..0.02),
            rng.random_range(-0.02..0.02),
        )),
    );
    DualArmModel {
        arms: PerSide::new(
            perturb(&nominal.arms.left, rng),
            perturb(&nominal.arms.right, rng),
        ),
        left_base_from_right_base: nominal.left_base_from_right_base * db,
    }
}

#[test]
fn calibrated_urdf_reproduces_the_model() {
    let robot = RobotDescription::builtin_irb14000();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let model = perturbed_model(&robot, &mut rng);
    let text = calibrated_urdf(&robot, &model).unwrap();
    assert!(text.contains("Calibrated by dualcal"));

    // Plain urdf-rs reads it.
    let raw = urdf_rs::read_from_string(&text).unwrap();
    assert!(raw.links.iter().any(|l| l.name == "reflector_c_r"));

    let back = RobotDescription::load(
        dualcal::robot::RobotSource::Text {
            text: &text,
            path: None,
        },
        &Default::default(),
    )
    .unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    // The left base stays; the right base moves to the calibrated place.
    let (t, r) = pose_error(
        &back.body_from_dh_base(Side::Left),
        &robot.body_from_dh_base(Side::Left),
    );
    assert!(t < 1e-9 && r < 1e-12, "{t} {r}");
    // Loaded from text, the description is the URDF's own chains; its DH reading is the model.
    let (t, r) = pose_error(
        &back
            .dh_model(common::reflectors_mm())
            .unwrap()
            .left_base_from_right_base,
        &model.left_base_from_right_base,
    );
    assert!(t < 1e-6 && r < 1e-9, "{t} {r}");
    // The original would fail the same test (the perturbation is visible).
    let (t0, _) = pose_error(
        &robot.nominal_left_base_from_right_base(),
        &model.left_base_from_right_base,
    );
    assert!(t0 > 1e-3);

    for (side, seed) in [(Side::Left, 21), (Side::Right, 22)] {
        let arm = model.arm(side);
        let body_from_base = back.body_from_dh_base(Side::Left) * model.left_base_from(side);
        let (t, r) = max_fk_error(&back, side, arm, &body_from_base, 50, seed);
        assert!(t < 1e-6, "{side}: {t:e} mm");
        assert!(r < 1e-9, "{side}: {r:e} rad");
        // The uncalibrated robot does not match the perturbed model.
        let (t0, _) = max_fk_error(&robot, side, arm, &body_from_base, 10, seed);
        assert!(t0 > 0.1, "{side}: {t0}");

        // Reflector links sit at the model's reflector points.
        let q = random_q(&mut rng);
        let (ql, qr) = match side {
            Side::Left => (q, [0.0; N_JOINTS]),
            Side::Right => ([0.0; N_JOINTS], q),
        };
        let poses = back.link_poses(&ql, &qr);
        let fk = arm.reflector_fk(&q);
        for (k, name) in ["a", "b", "c"].iter().enumerate() {
            let link = format!(
                "reflector_{name}_{}",
                if side == Side::Left { "l" } else { "r" }
            );
            let p = poses
                .iter()
                .find(|(n, _)| *n == link)
                .unwrap()
                .1
                .translation
                .vector;
            let expected = body_from_base * nalgebra::Point3::from(fk.points_mm[k]);
            assert!((p - expected.coords).norm() < 1e-6, "{link}");
        }
    }

    // Exporting again from the calibrated URDF (now the user's own description, a URDF chain per
    // arm) updates the reflectors instead of duplicating them.
    let again_model = back.nominal_model(common::reflectors_mm());
    for (a, b) in again_model
        .arms
        .left
        .reflectors_mm
        .iter()
        .zip(&model.arms.left.reflectors_mm)
    {
        assert!((a - b).norm() < 1e-9);
    }
    let again = calibrated_urdf(&back, &again_model).unwrap();
    let raw2 = urdf_rs::read_from_string(&again).unwrap();
    assert_eq!(raw2.links.len(), raw.links.len());
    assert_eq!(raw2.joints.len(), raw.joints.len());
}

fn assert_models_close(a: &DualArmModel, b: &DualArmModel, tol: f64) {
    for side in Side::BOTH {
        let (va, vb) = (a.arm(side).to_vector(), b.arm(side).to_vector());
        let worst = (&va - &vb).abs().max();
        assert!(worst < tol, "{side}: {worst:e}\n{va}\n{vb}");
    }
    let (t, r) = pose_error(&a.left_base_from_right_base, &b.left_base_from_right_base);
    assert!(t < tol && r < tol, "base {t:e} {r:e}");
}

#[test]
fn dh_model_reads_the_urdf_back() {
    let robot = RobotDescription::builtin_irb14000();
    // The built-in URDF encodes Table 3.
    let nominal = robot.nominal_model(common::reflectors_mm());
    assert_models_close(
        &robot.dh_model(common::reflectors_mm()).unwrap(),
        &nominal,
        1e-12,
    );

    // A calibrated URDF gives back the calibrated model, reflectors included.
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let model = perturbed_model(&robot, &mut rng);
    let back = RobotDescription::load(
        dualcal::robot::RobotSource::Text {
            text: &calibrated_urdf(&robot, &model).unwrap(),
            path: None,
        },
        &Default::default(),
    )
    .unwrap();
    assert_models_close(
        &back.dh_model(common::reflectors_mm()).unwrap(),
        &model,
        1e-9,
    );
    // ... which differs from the nominal one (the comparison can fail).
    let (va, vb) = (model.arms.left.to_vector(), nominal.arms.left.to_vector());
    assert!((va - vb).abs().max() > 1e-3);

    // A joint origin with a y offset has no DH reading.
    let text = BUILTIN_IRB14000_URDF.replacen(
        "<origin xyz=\"0.0405 0 0.2515\"",
        "<origin xyz=\"0.0405 0.01 0.2515\"",
        1,
    );
    let err = RobotDescription::load(
        dualcal::robot::RobotSource::Text {
            text: &text,
            path: None,
        },
        &Default::default(),
    )
    .unwrap()
    .dh_model(common::reflectors_mm())
    .unwrap_err();
    assert!(err.to_string().contains("yumi_joint_3_l"), "{err}");
}

#[test]
fn calibrated_urdf_refuses_non_finite_parameters() {
    let robot = RobotDescription::builtin_irb14000();
    let mut model = robot.nominal_model(common::reflectors_mm());
    model.arms.right.dh_mut().unwrap()[3].a_mm = f64::NAN;
    let err = calibrated_urdf(&robot, &model).unwrap_err();
    assert!(matches!(err, RobotError::Export { .. }), "{err}");
}

/// The built-in URDF with a mesh visual and a mesh collision added to the body.
fn with_meshes(visual: &str, collision: &str) -> String {
    BUILTIN_IRB14000_URDF.replacen(
        "<link name=\"yumi_body\">",
        &format!(
            "<link name=\"yumi_body\">\n    <visual><geometry><mesh filename=\"{visual}\" scale=\"0.001 0.001 0.001\"/></geometry></visual>\n    \
             <collision><geometry><mesh filename=\"{collision}\"/></geometry></collision>"
        ),
        1,
    )
}

#[test]
fn missing_meshes_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("robot.urdf");
    std::fs::write(
        &path,
        with_meshes("package://missing/x.stl", "meshes/none.stl"),
    )
    .unwrap();
    let robot = RobotDescription::load(&path, &Default::default()).unwrap();
    assert!(
        robot
            .warnings
            .iter()
            .any(|w| w.contains("package://missing/x.stl")),
        "{:?}",
        robot.warnings
    );
    assert!(
        robot.warnings.iter().any(|w| w.contains("meshes/none.stl")),
        "{:?}",
        robot.warnings
    );
    let zero = [0.0; N_JOINTS];
    let shapes = robot.shapes(&zero, &zero, GeometryKind::Visual);
    let mesh = shapes
        .iter()
        .find(|s| matches!(s.kind, ShapeKind::Mesh { .. }))
        .expect("the mesh is still returned");
    match &mesh.kind {
        ShapeKind::Mesh {
            resolved, scale, ..
        } => {
            assert!(resolved.is_none());
            assert_eq!(*scale, Vector3::new(0.001, 0.001, 0.001));
        }
        _ => unreachable!(),
    }
    assert_eq!(mesh.link, "yumi_body");
    // Collision checking ignores the mesh with a warning and still works.
    let world = CollisionWorld::new(&robot);
    assert!(!world.warnings.is_empty());
    assert!(world.in_collision(&zero, &zero, 0.0));
}

#[test]
fn meshes_resolve_through_package_map_and_relative_paths() {
    let dir = tempfile::tempdir().unwrap();
    let urdf_dir = dir.path().join("my_robot_description").join("urdf");
    std::fs::create_dir_all(urdf_dir.join("meshes")).unwrap();
    std::fs::write(
        urdf_dir.join("meshes").join("body.stl"),
        b"solid x\nendsolid x\n",
    )
    .unwrap();
    let pkg = dir.path().join("elsewhere").join("mypkg");
    std::fs::create_dir_all(pkg.join("meshes")).unwrap();
    std::fs::write(pkg.join("meshes").join("a.stl"), b"solid a\nendsolid a\n").unwrap();

    // package:// through the explicit map, relative to the URDF's directory.
    let path = urdf_dir.join("robot.urdf");
    std::fs::write(
        &path,
        with_meshes("package://mypkg/meshes/a.stl", "meshes/body.stl"),
    )
    .unwrap();
    let mut packages = PackageMap::new();
    packages.insert("mypkg".into(), pkg.clone());
    let robot = RobotDescription::load(
        &path,
        &dualcal::robot::LoadOptions {
            packages: packages.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    let zero = [0.0; N_JOINTS];
    let resolved: Vec<_> = [GeometryKind::Visual, GeometryKind::Collision]
        .iter()
        .flat_map(|&k| robot.shapes(&zero, &zero, k))
        .filter_map(|s| match s.kind {
            ShapeKind::Mesh { resolved, .. } => Some(resolved.expect("resolved")),
            _ => None,
        })
        .collect();
    assert_eq!(resolved.len(), 2);
    assert_eq!(resolved[0], pkg.join("meshes").join("a.stl"));
    assert_eq!(resolved[1], urdf_dir.join("meshes").join("body.stl"));

    // package:// through the URDF directory's ancestors (the package is the parent directory).
    std::fs::write(
        &path,
        with_meshes(
            "package://my_robot_description/urdf/meshes/body.stl",
            "meshes/body.stl",
        ),
    )
    .unwrap();
    let robot = RobotDescription::load(&path, &Default::default()).unwrap();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
}

#[test]
fn malformed_xml_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.urdf");
    std::fs::write(
        &path,
        "<robot name=\"x\">\n  <link name=\"a\">\n  <joint name=\"j\"\n</robot>\n",
    )
    .unwrap();
    let err = RobotDescription::load(&path, &Default::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, RobotError::Parse { .. }), "{msg}");
    assert!(msg.contains("broken.urdf"), "{msg}");

    // A syntax error deep in the file carries its line.
    let path = dir.path().join("syntax.urdf");
    std::fs::write(
        &path,
        "<robot name=\"x\">\n  <link name=\"a\"/>\n  <link name=\"b\" =/>\n</robot>\n",
    )
    .unwrap();
    let err = RobotDescription::load(&path, &Default::default()).unwrap_err();
    match &err {
        RobotError::Parse { file, line, .. } => {
            assert!(file.ends_with("syntax.urdf"));
            // the parser reports where it noticed the error: the bad line or the next one
            assert!(matches!(line, Some(3 | 4)), "{err}");
        }
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains(", line "), "{err}");

    // A missing file is an I/O error naming the path.
    let err =
        RobotDescription::load(&dir.path().join("nope.urdf"), &Default::default()).unwrap_err();
    assert!(
        matches!(err, RobotError::Io { .. }) && err.to_string().contains("nope.urdf"),
        "{err}"
    );

    // Well-formed XML without the YuMi names asks which chains the arms are.
    let path = dir.path().join("other.urdf");
    std::fs::write(&path, "<robot name=\"other\"><link name=\"base\"/></robot>").unwrap();
    let err = RobotDescription::load(&path, &Default::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, RobotError::NoArms { .. }), "{msg}");
    assert!(
        msg.contains("other.urdf") && msg.contains("base_link") && msg.contains("tip_link"),
        "{msg}"
    );
    // An incomplete YuMi names the missing joints.
    let path = dir.path().join("half.urdf");
    std::fs::write(
        &path,
        "<robot name=\"half\"><link name=\"a\"/><link name=\"b\"/><joint name=\"yumi_joint_1_l\" \
         type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
    )
    .unwrap();
    let err = RobotDescription::load(&path, &Default::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, RobotError::MissingJoints { .. }), "{msg}");
    assert!(
        msg.contains("half.urdf")
            && msg.contains("yumi_joint_2_l")
            && msg.contains("yumi_joint_6_r"),
        "{msg}"
    );

    // Garbage never panics.
    for text in [
        "",
        "not xml",
        "<robot>",
        "<robot name=\"x\"><joint/></robot>",
        "\u{0}\u{1}<<>>",
    ] {
        assert!(
            RobotDescription::load(
                dualcal::robot::RobotSource::Text {
                    text,
                    path: Some(Path::new("g.urdf"))
                },
                &Default::default()
            )
            .is_err(),
            "{text:?}"
        );
    }
}

#[test]
fn non_finite_origin_is_a_joint_error() {
    let text = BUILTIN_IRB14000_URDF.replacen(
        "<origin xyz=\"0.0405 0 0.2515\"",
        "<origin xyz=\"NaN 0 0.2515\"",
        1,
    );
    let err = RobotDescription::load(
        dualcal::robot::RobotSource::Text {
            text: &text,
            path: Some(Path::new("nan.urdf")),
        },
        &Default::default(),
    )
    .unwrap_err();
    match err {
        RobotError::BadJoint {
            joint, file, line, ..
        } => {
            assert_eq!(joint, "yumi_joint_3_l");
            assert_eq!(file, "nan.urdf");
            assert!(line.is_some());
        }
        other => panic!("{other}"),
    }
}

#[test]
fn builtin_urdf_is_what_the_generator_writes() {
    // assets/irb14000.urdf is generated by tools/gen_urdf.py: a hand edit (or a generator change
    // without regenerating) fails here, and so does a generator that cannot run (no python3, a crash).
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gen_urdf.py");
    let python = common::python("math, sys");
    let out = std::process::Command::new(&python)
        .arg(&script)
        .output()
        .unwrap_or_else(|e| panic!("run {python} {}: {e}", script.display()));
    assert!(
        out.status.success(),
        "{python} {} failed ({}):\n{}",
        script.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let generated = String::from_utf8(out.stdout).expect("the generator writes UTF-8");
    assert!(
        generated == BUILTIN_IRB14000_URDF,
        "assets/irb14000.urdf is not what tools/gen_urdf.py writes; regenerate: \
         python3 tools/gen_urdf.py > assets/irb14000.urdf"
    );
}

#[test]
fn descriptions_and_worlds_can_be_shared_across_threads() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<RobotDescription>();
    send_sync::<CollisionWorld>();
}
