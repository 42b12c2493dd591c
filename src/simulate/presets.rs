//! The simulations the command line, the studies, the tests and the benches share.

use super::{JointErrorModel, STREAM_RESTING, SimError, SimOptions, SimOutput, rng_for, simulate};
use crate::collision::CollisionWorld;
use crate::robot::{ModelForm, RobotDescription};
use crate::side::{PerSide, Side};
use nalgebra::{UnitQuaternion, Vector3};

/// Margin kept between the arms and the body or the other arm in simulated configurations, mm.
const CLEARANCE_MM: f64 = 5.0;
/// Random configurations tried per arm when its resting pose collides.
const RESTING_ATTEMPTS: usize = 2000;

/// The paper's protocol (§4.1) with this seed and `configs` configurations per arm, of which the first
/// `cal` are for calibration; every other option at its default.
pub fn paper_options(seed: u64, configs: usize, cal: usize) -> SimOptions {
    SimOptions {
        seed,
        n_configs: configs,
        n_cal: cal,
        ..SimOptions::default()
    }
}

/// The default reflectors of `robot`'s arms in their tip frames: [`SimOptions::default_reflectors`]
/// (a = (45, 0, 40), b = (−25, 40, 40), c = (−25, −40, 40) mm) for the built-in robot; for a chain the
/// same triangle turned so that its z axis is the chain's tool axis (the left arm's, so that both arms
/// share one set as a dataset needs).
pub fn default_reflectors_for(robot: &RobotDescription) -> [Vector3<f64>; 3] {
    let defaults = SimOptions::default_reflectors();
    if robot.model_form() == ModelForm::Dh {
        return defaults;
    }
    let axis = robot.arm(Side::Left).chain.tool_axis();
    if (axis.into_inner() - Vector3::z()).norm() < 1e-12 {
        return defaults;
    }
    let turn = UnitQuaternion::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    defaults.map(|t| turn * t)
}

/// Where each arm rests while the other is measured: [`RobotDescription::home_q_rad`], or — when
/// that collides — the first of a seeded series of random configurations that does not.
pub fn resting_poses(
    robot: &RobotDescription,
    world: &CollisionWorld,
    seed: u64,
) -> Result<PerSide<Vec<f64>>, SimError> {
    let mut rest = PerSide::from_fn(|side| robot.home_q_rad(side));
    let limits = PerSide::from_fn(|side| robot.joint_limits_rad(side));
    let mut rng = rng_for(seed, STREAM_RESTING);
    let mut attempts = 0;
    loop {
        let colliding = world.colliding_arms(&rest.left, &rest.right, CLEARANCE_MM);
        let Some(side) = Side::BOTH.into_iter().find(|&s| colliding[s]) else {
            break;
        };
        if attempts == RESTING_ATTEMPTS {
            return Err(SimError::NoRestingPose { side, attempts });
        }
        attempts += 1;
        // Draw new poses for every arm in a collision (both for one between them).
        for s in Side::BOTH.into_iter().filter(|&s| colliding[s]) {
            rest[s] = super::sampling::uniform_within(&mut rng, &limits[s]);
        }
    }
    Ok(rest)
}

/// Simulate `robot` (its nominal model with [`default_reflectors_for`]) with its collision model:
/// while one arm is measured the other rests ([`resting_poses`]).
pub fn simulate_with_robot(
    opts: &SimOptions,
    robot: &RobotDescription,
) -> Result<SimOutput, SimError> {
    let reflectors = default_reflectors_for(robot);
    let mut nominal = robot.nominal_model(reflectors);
    // One set of nominal reflectors for both arms (a dataset has one), even where the description
    // carries calibrated reflector links.
    for (_, arm) in nominal.arms.iter_mut() {
        arm.reflectors_mm = reflectors.to_vec();
    }
    let world = CollisionWorld::new(robot);
    let parked = resting_poses(robot, &world, opts.seed)?;
    // A joint both arms' chains hold (a torso) takes the measured arm's value.
    let shared = nominal.shared_joints();
    let collides = |side: Side, q: &[f64]| match side {
        Side::Left => world.in_collision(
            q,
            &shared.right_with_left_values(q, &parked.right),
            CLEARANCE_MM,
        ),
        Side::Right => world.in_collision(
            &shared.left_with_right_values(&parked.left, q),
            q,
            CLEARANCE_MM,
        ),
    };
    let mut opts = opts.clone();
    opts.body_from_left_base = robot.body_from_arm_base(Side::Left);
    simulate(&opts, &nominal, &collides)
}

/// The unmodelled joint errors of the robustness study: 1 mrad twice-per-revolution gear error and
/// 0.5 mrad/m compliance.
pub fn unmodelled_joint_errors() -> JointErrorModel {
    JointErrorModel {
        periodic_amplitude_mrad: 1.0,
        periods_per_rev: 2.0,
        compliance_mrad_per_m: 0.5,
    }
}
