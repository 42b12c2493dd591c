//! The simulations the command line, the studies, the tests and the benches share.

use super::{JointErrorModel, SimError, SimOptions, SimOutput, simulate};
use crate::collision::CollisionWorld;
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};

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

/// Simulate `robot` (its nominal model with the default reflectors) with its collision model: while one
/// arm is measured the other rests in the home pose.
pub fn simulate_with_robot(
    opts: &SimOptions,
    robot: &RobotDescription,
) -> Result<SimOutput, SimError> {
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let world = CollisionWorld::new(robot);
    let parked = PerSide::from_fn(crate::robot::home_q_rad);
    let collides = |side: Side, q: &[f64; 7]| match side {
        Side::Left => world.in_collision(q, &parked.right, 5.0),
        Side::Right => world.in_collision(&parked.left, q, 5.0),
    };
    let mut opts = opts.clone();
    opts.body_from_left_base = robot.body_from_dh_base(Side::Left);
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
