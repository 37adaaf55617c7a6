//! Scripted-grasp helpers shared by the integration tests.
#![allow(dead_code)]

use composuite_core::kinematics::{IkTarget, frame_from_axes, solve_ik};
use composuite_core::physics::{ARM_DOF, GRIP_SITE_LINK, SimWorld};
use nalgebra::{UnitQuaternion, Vector3};

/// The pads' centre is 6.6 mm above the grip site (docs/src/reference-facts.md §4.4: the pads span
/// 0.0859..0.1189 from the gripper mount, the grip site is at 0.109).
pub const PAD_CENTRE_ABOVE_GRIP_SITE: f64 = 0.109 - (0.0859 + 0.1189) / 2.0;

/// The grip-site orientation that points the gripper straight down, keeping the fingers'
/// current heading (so the wrist turns as little as possible).
pub fn pointing_down(world: &SimWorld) -> UnitQuaternion<f64> {
    let gripper = world.link_world_pose("gripper_base").unwrap();
    let mut finger_axis = gripper.rotation * Vector3::y();
    finger_axis.z = 0.0;
    frame_from_axes(-Vector3::z(), finger_axis)
        * UnitQuaternion::from_euler_angles(0.0, 0.0, -std::f64::consts::FRAC_PI_2)
}

/// Joint positions that put the pads' centre at `pad_centre` with `orientation`.
pub fn pads_at(
    world: &SimWorld,
    pad_centre: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    seed: &[f64; ARM_DOF],
) -> [f64; ARM_DOF] {
    let target = IkTarget {
        position: pad_centre - Vector3::new(0.0, 0.0, PAD_CENTRE_ABOVE_GRIP_SITE),
        orientation: Some(orientation),
        orientation_weight: 0.5,
    };
    let r = solve_ik(world.model, GRIP_SITE_LINK, &target, seed, 300).unwrap();
    assert!(
        r.position_error < 1e-4 && r.orientation_error < 1e-3,
        "IK failed: {r:?}"
    );
    r.q
}

/// Joint targets from `start` to `target` in control steps of 50 ms over `seconds` (smoothstep).
pub fn path(start: &[f64; ARM_DOF], target: &[f64; ARM_DOF], seconds: f64) -> Vec<[f64; ARM_DOF]> {
    let steps = (seconds / 0.05).round() as usize;
    (1..=steps)
        .map(|k| {
            let s = k as f64 / steps as f64;
            let s = s * s * (3.0 - 2.0 * s);
            std::array::from_fn(|j| start[j] + (target[j] - start[j]) * s)
        })
        .collect()
}
