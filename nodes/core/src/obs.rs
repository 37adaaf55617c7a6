//! Observations, factored as the reference benchmark factors them (composuite-facts §5): object,
//! obstacle, goal, task one-hots and robot proprioception, plus the flat vector its Gym wrapper
//! produces (93 values with the task indicator, 77 without). Quaternions are (x, y, z, w).

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
    /// Orientation in the eef frame: q_eef⁻¹ ⊗ q (x, y, z, w).
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
}

/// The robot factor (32 values).
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
            orientation_in_eef: xyzw(&(eef.rotation.inverse() * orientation)),
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

impl Observation {
    /// The flat vector in the reference order: object, obstacle, goal, [object_id, robot_id,
    /// obstacle_id, objective_id], robot.
    pub fn flat(&self) -> Vec<f64> {
        let size = if self.includes_task {
            FLAT_SIZE_WITH_TASK
        } else {
            FLAT_SIZE_WITHOUT_TASK
        };
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
        out
    }
}
