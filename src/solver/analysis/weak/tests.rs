use super::*;
use crate::kinematics::N_JOINTS;

fn arm() -> ArmModel {
    ArmModel::nominal_irb14000(crate::simulate::SimOptions::default_reflectors().to_vec())
}

/// Configurations that differ in the last joint only (it turns the flange about its own z).
fn last_joint_turned(degrees: &[f64]) -> Vec<Vec<f64>> {
    degrees
        .iter()
        .map(|d| {
            let mut q = vec![0.3; N_JOINTS];
            q[N_JOINTS - 1] = d.to_radians();
            q
        })
        .collect()
}

#[test]
fn the_last_joint_turns_the_flange_about_its_z_only() {
    let spread = orientation_spread_deg(&arm(), &last_joint_turned(&[-10.0, 5.0, 20.0]));
    assert!((spread[2] - 30.0).abs() < 1e-6, "{spread:?}");
    assert!(spread[0] < 1e-6 && spread[1] < 1e-6, "{spread:?}");
}

#[test]
fn a_reflector_offset_is_explained_by_the_turns_that_would_move_it() {
    let arm = arm();
    let qs = last_joint_turned(&[0.0, 12.0]);
    let off = arm.reflector_offset();
    // t_a.z: rotations about x and y move it; t_a.x: about y and z.
    let free = vec![off + 2, off];
    let cov = DMatrix::identity(2, 2);
    let spread = orientation_spread_deg(&arm, &qs);
    let z = reason(&arm, &qs, &free, &cov, 0, &spread);
    assert!(
        z.starts_with("the flange turned at most 0.0° about x and 0.0° about y")
            && z.ends_with("reflector a's offset along z is not determined"),
        "{z}"
    );
    let x = reason(&arm, &qs, &free, &cov, 1, &spread);
    assert!(x.contains("about y and 12.0° about z"), "{x}");
    assert!(x.ends_with("offset along x is not determined"), "{x}");
}

#[test]
fn a_joint_that_hardly_moved_is_named() {
    let arm = arm();
    let qs = last_joint_turned(&[0.0, 12.0]);
    // d7 (row 7's d): joint 7 moved 12° of its range.
    let free = vec![4 * 6 + 1, 0];
    let cov = DMatrix::identity(2, 2);
    let text = reason(&arm, &qs, &free, &cov, 0, &[0.0; 3]);
    assert!(
        text.starts_with("joint 7 moved over 12° of its ")
            && text.ends_with("d7 is not determined"),
        "{text}"
    );
}
