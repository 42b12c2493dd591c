//! What the data cannot tell (issue 47): on configurations whose flange hardly turns, the
//! reflector's offsets are named as weak with the reason in words and held at their nominal values
//! (`keep_weak` keeps them free); on configurations that span the workspace nothing is weak.

use dualcal::kinematics::ArmModel;
use dualcal::side::Side;
use dualcal::{ArmArrays, Arrays, Calibrated, Calibration, Dataset, Robot};
use nalgebra::{UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The tracker's noise per axis, mm.
const NOISE_MM: f64 = 0.02;

/// `q` moved (least-norm steps of the flange's angular Jacobian) until the flange's orientation is
/// `target`; `None` when it does not get there within the joint limits.
fn turned_to(arm: &ArmModel, mut q: Vec<f64>, target: &UnitQuaternion<f64>) -> Option<Vec<f64>> {
    for _ in 0..50 {
        let (pose, jac) = arm.flange_jacobian(&q);
        let error = (target * pose.rotation.inverse()).scaled_axis();
        if error.norm() < 1e-12 {
            break;
        }
        let jw = jac.rows(3, 3).into_owned();
        let step = jw.transpose() * (&jw * jw.transpose()).try_inverse()? * error;
        for (v, d) in q.iter_mut().zip(step.iter()) {
            *v += d;
        }
    }
    let limits = arm.joint_limits_rad();
    let (pose, _) = arm.flange_jacobian(&q);
    let reached = (target * pose.rotation.inverse()).angle() < 1e-9;
    let within = q
        .iter()
        .zip(&limits)
        .all(|(v, (lo, hi))| v >= lo && v <= hi);
    (reached && within).then_some(q)
}

/// 40 left-arm configurations of the built-in robot: the first four joints drawn around the home
/// configuration, the flange then turned back to within `turn_deg` about each axis of one
/// orientation (`None`: no orientation constraint, the joints drawn within their limits); the
/// reflectors measured by the nominal model with Gaussian noise.
fn dataset(turn_deg: Option<f64>, seed: u64) -> Dataset {
    let robot = Robot::builtin_irb14000();
    let description = robot.description();
    let reflectors = dualcal::simulate::SimOptions::default_reflectors();
    let arm = description.nominal_model(reflectors).arms.left.clone();
    let home = description.home_q_rad(Side::Left);
    let limits = arm.joint_limits_rad();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, NOISE_MM).unwrap();
    let orientation = arm.base_from_flange(&home).rotation;
    let mut joints = Vec::new();
    while joints.len() < 40 {
        let q = match turn_deg {
            Some(turn) => {
                let mut q = home.clone();
                for v in q.iter_mut().take(4) {
                    *v += rng.random_range(-0.6..0.6);
                }
                let w = Vector3::from_fn(|_, _| rng.random_range(-turn..turn).to_radians());
                match turned_to(
                    &arm,
                    q,
                    &(orientation * UnitQuaternion::from_scaled_axis(w)),
                ) {
                    Some(q) => q,
                    None => continue,
                }
            }
            None => limits
                .iter()
                .map(|&(lo, hi)| rng.random_range(lo..hi))
                .collect(),
        };
        joints.push(q);
    }
    let points_mm = joints
        .iter()
        .map(|q| {
            arm.reflector_fk(q)
                .points_mm
                .iter()
                .map(|p| std::array::from_fn(|c| p[c] + noise.sample(&mut rng)))
                .collect()
        })
        .collect();
    Dataset::from_arrays(
        &robot,
        Arrays {
            reflector_names: ["a", "b", "c"].map(String::from).to_vec(),
            nominal_reflectors_mm: reflectors.iter().map(|t| [t.x, t.y, t.z]).collect(),
            left: Some(ArmArrays {
                joints,
                points_mm,
                split: Vec::new(),
                ids: Vec::new(),
            }),
            right: None,
            tracker: Default::default(),
            measured_together: false,
        },
    )
    .unwrap()
}

fn reflector_weak(result: &Calibrated) -> Vec<&dualcal::solver::weak::WeakParameter> {
    result
        .weak(Side::Left)
        .iter()
        .filter(|w| w.name.starts_with("t_"))
        .collect()
}

#[test]
fn a_flange_that_hardly_turns_leaves_the_reflector_offsets_weak_and_held() {
    let ds = dataset(Some(1.0), 3);
    let held = Calibration::new(&ds).run().unwrap();
    for w in held.weak(Side::Left) {
        eprintln!("weak {}", w.describe());
    }
    let weak = reflector_weak(&held);
    assert!(!weak.is_empty(), "{:#?}", held.weak(Side::Left));
    for w in &weak {
        assert!(w.held, "{w:?}");
        assert!(
            w.reason.starts_with("the flange turned at most ")
                && w.reason.contains("across these configurations: reflector ")
                && w.reason.contains("'s offset along "),
            "{}",
            w.reason
        );
        assert!(w.workspace_mm > 3.0 * w.noise_mm, "{w:?}");
    }
    // Held: at the nominal value, not identified; the parameter file and the fixed list say why.
    let parameters = held.parameters(Side::Left);
    for w in held.weak(Side::Left) {
        let p = parameters.iter().find(|p| p.name == w.name).unwrap();
        assert!(!p.identified, "{}", p.name);
        assert_eq!(p.calibrated, p.nominal, "{}", p.name);
    }
    let json = held.params_json();
    assert!(json.contains("\"weak_parameters\""), "{json}");
    assert!(json.contains("held at its nominal value: a weak parameter"));

    // Kept free: the same parameters named, fitted.
    let kept = Calibration::new(&ds).keep_weak(true).run().unwrap();
    let kept_weak = reflector_weak(&kept);
    let names = |w: &[&dualcal::solver::weak::WeakParameter]| -> Vec<String> {
        w.iter().map(|w| w.name.clone()).collect()
    };
    assert_eq!(names(&kept_weak), names(&weak));
    let parameters = kept.parameters(Side::Left);
    for w in &kept_weak {
        assert!(!w.held);
        let p = parameters.iter().find(|p| p.name == w.name).unwrap();
        assert!(p.identified, "{}", p.name);
        assert_ne!(p.calibrated, p.nominal, "{}", p.name);
    }
}

#[test]
fn configurations_across_the_workspace_leave_nothing_weak() {
    let ds = dataset(None, 3);
    let result = Calibration::new(&ds).run().unwrap();
    assert!(
        result.weak(Side::Left).is_empty(),
        "{:#?}",
        result.weak(Side::Left)
    );
    assert!(!result.params_json().contains("weak_parameters"));
}

#[test]
fn nothing_is_weak_on_the_paper_size_simulation() {
    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let sim = dualcal::simulate::simulate_with_robot(
        &dualcal::simulate::paper_options(7, 220, 120),
        &robot,
    )
    .unwrap();
    let result = dualcal::solver::Calibrator::new(&sim.dataset, &sim.nominal)
        .run()
        .unwrap();
    for side in Side::BOTH {
        assert!(result.weak[side].is_empty(), "{:#?}", result.weak[side]);
        // The margin: the largest workspace effect over the noise (docs/reliability.md).
        let qs: Vec<Vec<f64>> = sim
            .dataset
            .arm(side)
            .select(dualcal::Split::Cal)
            .iter()
            .map(|m| m.q_rad.clone())
            .collect();
        let free = &result.identifiability[side].as_ref().unwrap().free;
        let ratios =
            dualcal::solver::weak::workspace_noise_ratios(result.calibrated.arm(side), &qs, free)
                .unwrap();
        let (k, largest) = ratios
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        let name = result.calibrated.arm(side).param_name(free[k]);
        eprintln!("{side} arm: largest workspace effect {largest:.2}× the noise ({name})");
        assert!(*largest < dualcal::solver::weak::WEAK_NOISE_RATIO);
    }
}
