//! The reachability facts the object-wall Push plan rests on, checked pose by pose: for each
//! held-object position along bin 1 and bin 2, whether some IK solution of a side grasp keeps
//! the whole arm clear of the arena (the clearance model; no physics).

#![cfg(test)]

use nalgebra::{Point3, UnitQuaternion, Vector3};

use super::clearance::Clearance;
use super::grasp::{GraspInput, Headings, grasp_candidates};
use super::motion::pad_ik_solutions;
use crate::axes::{Object, Objective, Obstacle, Robot};
use crate::physics::robot_model;

/// The most clearance (m) any IK solution of a side grasp pointing along `heading` keeps
/// with the object held at (0.15, `y`, 0.885) behind the object wall (−∞: none reaches).
fn best_clearance(robot: Robot, object: Object, heading: Vector3<f64>, y: f64) -> f64 {
    let model = robot_model(robot);
    let clearance = Clearance::new(model, Objective::Push, Obstacle::ObjectWall);
    let q0 = robot.init_qpos();
    let input = GraspInput {
        model,
        q: q0,
        object,
        objective: Objective::Push,
        obstacle: Obstacle::ObjectWall,
        position: Point3::new(0.15, y, 0.885),
        rotation: UnitQuaternion::identity(),
        tilt: 0.0,
        headings: Headings::AlongBin1,
    };
    grasp_candidates(&input)
        .iter()
        .filter(|g| (g.approach - heading).norm() < 1e-9)
        .flat_map(|g| pad_ik_solutions(model, &q0, g.pad, g.orientation))
        .map(|q| clearance.at(model, &q))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Behind the object wall every arm can hold the plate and the dumbbell pointing −y from
/// where they start to where they are set down, and pointing +x−y from there to the goal —
/// while pointing +y (the grasp that reaches the shelf) none can at the start.
#[test]
fn behind_the_object_wall_minus_y_then_plus_x_minus_y_reaches_the_goal() {
    let d = std::f64::consts::FRAC_1_SQRT_2;
    for robot in [Robot::Iiwa, Robot::Jaco, Robot::Gen3, Robot::Panda] {
        for object in [Object::Plate, Object::Dumbbell] {
            for y in [-0.32, -0.24, -0.16] {
                let gap = best_clearance(robot, object, -Vector3::y(), y);
                assert!(gap >= 0.0, "{robot:?} {object:?} −y at y {y}: {gap}");
            }
            for y in [-0.20, -0.1, 0.0, 0.13] {
                let gap = best_clearance(robot, object, Vector3::new(d, -d, 0.0), y);
                assert!(gap >= 0.0, "{robot:?} {object:?} +x−y at y {y}: {gap}");
            }
            let gap = best_clearance(robot, object, Vector3::y(), -0.32);
            assert!(gap < 0.0, "{robot:?} {object:?} +y at y −0.32: {gap}");
        }
    }
}
