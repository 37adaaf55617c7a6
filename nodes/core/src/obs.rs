//! Observations, factored as the reference benchmark factors them (docs/src/reference-facts.md §5):
//! object, obstacle, goal, task one-hots and robot proprioception, plus the flat vector its Gym
//! wrapper produces (93 values with the task indicator, 77 without). Quaternions are (x, y, z, w).

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};

use crate::TaskSpec;
use crate::axes::AxisElement;
use crate::physics::ARM_DOF;

/// Length of the flat vector with the task one-hots.
pub const FLAT_SIZE_WITH_TASK: usize = 93;
/// Length of the flat vector without them.
pub const FLAT_SIZE_WITHOUT_TASK: usize = 77;

/// A pose and the same pose seen from the end effector: 14 values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativePose {
    /// World position (m).
    pub position: [f64; 3],
    /// World orientation (x, y, z, w).
    pub orientation: [f64; 4],
    /// Position in the eef frame (m): R_eefᵀ (p − p_eef).
    pub position_in_eef: [f64; 3],
    /// Orientation in the eef frame: ±(q_eef⁻¹ ⊗ q), the sign chosen as the reference chooses
    /// it ([`reference_sign`]) (x, y, z, w).
    pub orientation_in_eef: [f64; 4],
}

/// The goal factor: the goal marker's relative pose and the object-to-goal vector (17 values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GoalFactor {
    /// The goal marker's pose.
    pub pose: RelativePose,
    /// Goal position minus object position, world frame (m).
    pub object_to_goal: [f64; 3],
}

/// The task factor: four one-hots in the reference's orders (16 values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskFactor {
    /// Over [Box, Dumbbell, Plate, Hollowbox].
    pub object_id: [f64; 4],
    /// Over [IIWA, Jaco, Panda, Kinova3].
    pub robot_id: [f64; 4],
    /// Over [None, ObjectWall, ObjectDoor, GoalWall].
    pub obstacle_id: [f64; 4],
    /// Over [PickPlace, Push, Shelf, Trashcan].
    pub objective_id: [f64; 4],
}

impl TaskFactor {
    /// The one-hots of a task.
    pub fn of(task: &TaskSpec) -> TaskFactor {
        fn one_hot(index: usize) -> [f64; 4] {
            std::array::from_fn(|i| if i == index { 1.0 } else { 0.0 })
        }
        TaskFactor {
            object_id: one_hot(task.object.names().one_hot_index),
            robot_id: one_hot(task.robot.names().one_hot_index),
            obstacle_id: one_hot(task.obstacle.names().one_hot_index),
            objective_id: one_hot(task.objective.names().one_hot_index),
        }
    }

    /// The task these one-hots name ([`TaskFactor::of`] turned around); `None` unless each of
    /// the four is exactly one 1 among 0s.
    pub fn task(&self) -> Option<TaskSpec> {
        fn element<E: crate::axes::AxisElement>(one_hot: &[f64; 4]) -> Option<E> {
            let ones: Vec<usize> = (0..4).filter(|&i| one_hot[i] == 1.0).collect();
            let zeros = one_hot.iter().filter(|&&v| v == 0.0).count();
            match ones[..] {
                [index] if zeros == 3 => E::TABLE
                    .iter()
                    .find(|row| row.one_hot_index == index)
                    .map(|row| row.element),
                _ => None,
            }
        }
        Some(TaskSpec::new(
            element(&self.robot_id)?,
            element(&self.object_id)?,
            element(&self.obstacle_id)?,
            element(&self.objective_id)?,
        ))
    }
}

/// Values in the robot factor, the last part of a flat observation.
pub const ROBOT_FACTOR_LEN: usize = 3 * ARM_DOF + 3 + 4 + 2 + 2;
/// Where `gripper_qpos` starts within the robot factor (after the joints' cos, sin and
/// velocities and the eef's position and orientation).
pub const GRIPPER_QPOS_IN_ROBOT: usize = 3 * ARM_DOF + 3 + 4;

/// The robot factor ([`ROBOT_FACTOR_LEN`] = 32 values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotFactor {
    /// cos of the arm joint positions.
    pub joint_pos_cos: [f64; ARM_DOF],
    /// sin of the arm joint positions.
    pub joint_pos_sin: [f64; ARM_DOF],
    /// Arm joint velocities (rad/s).
    pub joint_vel: [f64; ARM_DOF],
    /// Grip-site position, world (m).
    pub eef_position: [f64; 3],
    /// Hand orientation, world (x, y, z, w).
    pub eef_orientation: [f64; 4],
    /// Finger positions (m), left then right.
    pub gripper_qpos: [f64; 2],
    /// Finger velocities (m/s), left then right.
    pub gripper_qvel: [f64; 2],
}

/// One observation.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Object factor.
    pub object: RelativePose,
    /// Obstacle factor (zero position and zero quaternion without an obstacle).
    pub obstacle: RelativePose,
    /// Goal factor.
    pub goal: GoalFactor,
    /// Task one-hots.
    pub task: TaskFactor,
    /// Robot factor.
    pub robot: RobotFactor,
    /// Whether [`Observation::flat`] includes the task one-hots.
    pub includes_task: bool,
}

/// xyzw of a unit quaternion.
pub fn xyzw(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

/// The reference's sign for a quaternion it derives from a rotation matrix: robosuite's
/// `mat2pose` → `mat2quat` takes the eigenvector of the largest eigenvalue of a 4×4 matrix built
/// from the rotation, whose sign is arbitrary, and negates it when w < 0. So its eef-relative
/// quaternions have w ≥ 0, while q_eef⁻¹ ⊗ q may come out either way (at the start pose, hand
/// pointing down, w ≈ 0 and the product's sign follows tiny tilts).
///
/// At a half turn (w = 0 to float32 precision) the reference keeps whatever sign its float32
/// LAPACK eigen-solver produced, which is rounding noise: the same matrix gives opposite signs
/// under numba's eigh (scipy's OpenBLAS, robosuite's default) and numpy's (measured on the iiwa's
/// start pose, `docs/src/differences-from-reference.md`). Here a half turn gets the sign whose
/// first non-zero vector component is positive, which is what the reference gives on every start
/// pose recorded in `tests/reference/data/step0.json.gz`.
pub fn reference_sign(q: UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    let flip = if q.w.abs() < HALF_TURN_W {
        [q.i, q.j, q.k]
            .into_iter()
            .find(|c| c.abs() >= HALF_TURN_W)
            .is_some_and(|c| c < 0.0)
    } else {
        q.w < 0.0
    };
    if flip {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        q
    }
}

/// Below this |w| a quaternion is a half turn as far as float32 can tell (its resolution at 1).
const HALF_TURN_W: f64 = 1e-7;

impl RelativePose {
    /// `pose` in the world and seen from `eef`.
    pub fn new(
        position: Point3<f64>,
        orientation: UnitQuaternion<f64>,
        eef: &Isometry3<f64>,
    ) -> RelativePose {
        let in_eef = eef.rotation.inverse() * (position.coords - eef.translation.vector);
        RelativePose {
            position: position.coords.into(),
            orientation: xyzw(&orientation),
            position_in_eef: in_eef.into(),
            orientation_in_eef: xyzw(&reference_sign(eef.rotation.inverse() * orientation)),
        }
    }

    /// The reference's "no obstacle" values: position 0 and a zero (not unit) quaternion, but the
    /// eef-relative part computed as for an identity pose at the world origin.
    pub fn absent(eef: &Isometry3<f64>) -> RelativePose {
        RelativePose {
            position: [0.0; 3],
            orientation: [0.0; 4],
            ..RelativePose::new(Point3::origin(), UnitQuaternion::identity(), eef)
        }
    }

    fn extend(&self, out: &mut Vec<f64>) {
        out.extend(self.position);
        out.extend(self.orientation);
        out.extend(self.position_in_eef);
        out.extend(self.orientation_in_eef);
    }
}

impl GoalFactor {
    /// The goal marker at `goal` (identity orientation) for an object at `object`.
    pub fn new(goal: Point3<f64>, object: Point3<f64>, eef: &Isometry3<f64>) -> GoalFactor {
        let to_goal: Vector3<f64> = goal - object;
        GoalFactor {
            pose: RelativePose::new(goal, UnitQuaternion::identity(), eef),
            object_to_goal: to_goal.into(),
        }
    }
}

/// Values in a flat observation with the task one-hots (93) or without them (77).
pub fn flat_size(includes_task: bool) -> usize {
    if includes_task {
        FLAT_SIZE_WITH_TASK
    } else {
        FLAT_SIZE_WITHOUT_TASK
    }
}

impl Observation {
    /// The flat vector in the reference order: object, obstacle, goal, [object_id, robot_id,
    /// obstacle_id, objective_id], robot.
    pub fn flat(&self) -> Vec<f64> {
        let size = flat_size(self.includes_task);
        let mut out = Vec::with_capacity(size);
        self.object.extend(&mut out);
        self.obstacle.extend(&mut out);
        self.goal.pose.extend(&mut out);
        out.extend(self.goal.object_to_goal);
        if self.includes_task {
            out.extend(self.task.object_id);
            out.extend(self.task.robot_id);
            out.extend(self.task.obstacle_id);
            out.extend(self.task.objective_id);
        }
        let r = &self.robot;
        out.extend(r.joint_pos_cos);
        out.extend(r.joint_pos_sin);
        out.extend(r.joint_vel);
        out.extend(r.eef_position);
        out.extend(r.eef_orientation);
        out.extend(r.gripper_qpos);
        out.extend(r.gripper_qvel);
        debug_assert_eq!(out.len(), size);
        debug_assert_eq!(
            out[size - ROBOT_FACTOR_LEN + GRIPPER_QPOS_IN_ROBOT].to_bits(),
            r.gripper_qpos[0].to_bits()
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_task_one_hots_name_their_task_back() {
        for task in crate::all_tasks() {
            assert_eq!(TaskFactor::of(&task).task(), Some(task));
        }
        let mut bad = TaskFactor::of(&crate::all_tasks()[7]);
        bad.robot_id = [0.0; 4];
        assert_eq!(bad.task(), None);
        bad.robot_id = [1.0, 1.0, 0.0, 0.0];
        assert_eq!(bad.task(), None);
    }

    /// A hand pointing down, tilted a little either way, sees an upright object rotated by
    /// about half a turn: w is tiny and its sign follows the tilt. The reference's value always
    /// has w ≥ 0 and is the same rotation.
    #[test]
    fn eef_relative_quaternions_take_the_references_sign() {
        for tilt in [-0.01, -1e-4, 1e-4, 0.01, 0.0] {
            let hand_down =
                UnitQuaternion::from_euler_angles(std::f64::consts::PI + tilt, 0.0, 0.3);
            let eef = Isometry3::from_parts(Vector3::new(0.0, 0.0, 1.0).into(), hand_down);
            let object = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.7);
            let pose = RelativePose::new(Point3::new(0.1, 0.0, 0.8), object, &eef);
            let [x, y, z, w] = pose.orientation_in_eef;
            if tilt == 0.0 {
                // A half turn: the sign whose first non-zero component is positive.
                assert!(w.abs() < 1e-12 && x > 0.0, "half turn: {:?}", [x, y, z, w]);
            } else {
                assert!(w > 0.0, "tilt {tilt}: w = {w}");
            }
            let product = hand_down.inverse() * object;
            assert!(
                (product.angle_to(&UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                    w, x, y, z
                ))))
                .abs()
                    < 1e-12,
                "tilt {tilt}: a different rotation"
            );
        }
    }
}
