//! Conversions between the core's types and the wire types, in one place (STYLE D8): outbound
//! conversions are plain functions; inbound ones return errors that name the bad field and
//! what is valid.

use std::fmt;

use composuite_core::TaskSpec;
use composuite_core::arena::{Placed, Primitive};
use composuite_core::axes::AxisElement;
use composuite_core::env::{EnvConfig, EpisodeLayout, WorldState};
use composuite_core::obs::{self, RelativePose};
use composuite_core::physics::{ARM_DOF, FINGER_JOINTS, RobotModel};
use composuite_core::reward::{RewardConfig, StagedReward};
use composuite_msgs::builtin_interfaces::msg::Time;
use composuite_msgs::geometry_msgs::msg::{Point, Pose, Quaternion, Vector3};
use composuite_msgs::msg;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::std_msgs::msg::Header;
use nalgebra::Isometry3;

use crate::shared::names::WORLD_FRAME;

/// A `builtin_interfaces/Time` from nanoseconds of sim time (exact: no float rounding).
pub fn time_from_nanos(nanos: u64) -> Time {
    Time {
        sec: (nanos / 1_000_000_000) as i32,
        nanosec: (nanos % 1_000_000_000) as u32,
    }
}

/// A time as integer nanoseconds (negative times, which no stamp here has, count as 0).
pub fn nanos_of(t: &Time) -> u64 {
    (t.sec.max(0) as u64) * 1_000_000_000 + u64::from(t.nanosec)
}

/// A header in the world frame at `stamp`.
pub fn header(stamp: Time) -> Header {
    Header {
        stamp,
        frame_id: WORLD_FRAME.to_string(),
    }
}

/// A point from an array (m).
pub fn point(p: [f64; 3]) -> Point {
    Point {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// A quaternion from (x, y, z, w), kept as is (the no-obstacle zero quaternion stays zero).
pub fn quaternion(q: [f64; 4]) -> Quaternion {
    Quaternion {
        x: q[0],
        y: q[1],
        z: q[2],
        w: q[3],
    }
}

/// A pose from an isometry.
pub fn pose(p: &Isometry3<f64>) -> Pose {
    Pose {
        position: point(p.translation.vector.into()),
        orientation: quaternion(obs::xyzw(&p.rotation)),
    }
}

fn vector3(v: [f64; 3]) -> Vector3 {
    Vector3 {
        x: v[0],
        y: v[1],
        z: v[2],
    }
}

/// The wire form of a task.
pub fn task_spec(task: &TaskSpec) -> msg::TaskSpec {
    msg::TaskSpec {
        robot: task.robot.wire_name().into(),
        object: task.object.wire_name().into(),
        obstacle: task.obstacle.wire_name().into(),
        objective: task.objective.wire_name().into(),
        robot_index: task.robot.index() as u8,
        object_index: task.object.index() as u8,
        obstacle_index: task.obstacle.index() as u8,
        objective_index: task.objective.index() as u8,
        task_index: task.task_index() as u16,
        reference_task_id: task.reference_task_id() as u16,
    }
}

fn object_factor(p: &RelativePose) -> msg::ObjectFactor {
    msg::ObjectFactor {
        position: point(p.position),
        orientation: quaternion(p.orientation),
        position_in_eef: point(p.position_in_eef),
        orientation_in_eef: quaternion(p.orientation_in_eef),
    }
}

fn obstacle_factor(p: &RelativePose) -> msg::ObstacleFactor {
    msg::ObstacleFactor {
        position: point(p.position),
        orientation: quaternion(p.orientation),
        position_in_eef: point(p.position_in_eef),
        orientation_in_eef: quaternion(p.orientation_in_eef),
    }
}

/// The wire form of an observation.
pub fn observation(o: &obs::Observation, stamp: Time, episode: u32, step: u32) -> msg::Observation {
    let r = &o.robot;
    msg::Observation {
        header: header(stamp),
        episode,
        step,
        robot: msg::RobotFactor {
            joint_pos_cos: r.joint_pos_cos,
            joint_pos_sin: r.joint_pos_sin,
            joint_vel: r.joint_vel,
            eef_position: point(r.eef_position),
            eef_orientation: quaternion(r.eef_orientation),
            gripper_qpos: r.gripper_qpos,
            gripper_qvel: r.gripper_qvel,
        },
        object: object_factor(&o.object),
        obstacle: obstacle_factor(&o.obstacle),
        goal: msg::GoalFactor {
            position: point(o.goal.pose.position),
            orientation: quaternion(o.goal.pose.orientation),
            position_in_eef: point(o.goal.pose.position_in_eef),
            orientation_in_eef: quaternion(o.goal.pose.orientation_in_eef),
            object_to_goal: vector3(o.goal.object_to_goal),
        },
        task: msg::TaskFactor {
            object_id: o.task.object_id,
            robot_id: o.task.robot_id,
            obstacle_id: o.task.obstacle_id,
            objective_id: o.task.objective_id,
        },
        includes_task: o.includes_task,
        flat: o.flat(),
    }
}

/// The wire form of a staged reward; `total` is the reward an agent gets under `config`.
pub fn staged_reward(
    r: &StagedReward,
    config: &RewardConfig,
    stamp: Time,
    episode: u32,
    step: u32,
) -> msg::StagedReward {
    msg::StagedReward {
        header: header(stamp),
        episode,
        step,
        objective: r.objective.wire_name().into(),
        stage_names: r.stages.iter().map(|s| s.name.to_string()).collect(),
        stage_values: r.stages.iter().map(|s| s.value).collect(),
        stage_maxima: r.stages.iter().map(|s| s.max).collect(),
        current_stage: r.current_stage().map_or(-1, |i| i as i8),
        total: config.reward(r),
        success: r.success,
    }
}

/// The wire form of the privileged world state.
pub fn world_state(w: &WorldState, stamp: Time, episode: u32, step: u32) -> msg::WorldState {
    msg::WorldState {
        header: header(stamp),
        episode,
        step,
        object_pose: pose(&w.object_pose),
        object_linear_velocity: vector3(w.object_linear_velocity.into()),
        object_angular_velocity: vector3(w.object_angular_velocity.into()),
        eef_pose: pose(&w.eef_pose),
        left_pad_contact: w.contacts.left_pad,
        right_pad_contact: w.contacts.right_pad,
        left_finger_contact: w.contacts.left_finger,
        right_finger_contact: w.contacts.right_finger,
        grasping: w.grasping,
        last_gripper_action: w.last_gripper_action,
        gripper_target: w.gripper_target,
        arm_joint_positions: w.arm_joint_positions,
        arm_joint_velocities: w.arm_joint_velocities,
        finger_joint_positions: w.finger_joint_positions,
    }
}

/// The wire form of a placed primitive.
pub fn scene_part(p: &Placed) -> msg::ScenePart {
    let (shape, half_size) = match p.shape {
        Primitive::Box { half_extents: h } => (msg::ScenePart::SHAPE_BOX, [h.x, h.y, h.z]),
        Primitive::Cylinder {
            radius,
            half_length,
        } => (msg::ScenePart::SHAPE_CYLINDER, [radius, 0.0, half_length]),
    };
    msg::ScenePart {
        name: p.name.into(),
        shape,
        half_size: vector3(half_size),
        pose: pose(&p.pose),
        collides: p.collides,
    }
}

/// The scene of episode `episode`, laid out as `layout`, run with `config`.
pub fn scene(layout: &EpisodeLayout, config: &EnvConfig, episode: u32, stamp: Time) -> msg::Scene {
    let task = layout.task;
    let obstacle_pose = match task.obstacle {
        composuite_core::axes::Obstacle::NoObstacle => Pose {
            position: point([0.0; 3]),
            orientation: quaternion([0.0; 4]),
        },
        other => pose(&composuite_core::arena::obstacle_geometry(other).body_pose()),
    };
    let at = |p: nalgebra::Point3<f64>| pose(&Isometry3::translation(p.x, p.y, p.z));
    msg::Scene {
        header: header(stamp),
        task: task_spec(&task),
        seed: layout.seed,
        episode,
        horizon: config.horizon,
        control_period: config.control_period(),
        physics_period: config.physics.dt,
        robot_base_pose: pose(&composuite_core::arena::robot_base_pose()),
        object_start_pose: at(layout.object_start),
        goal_pose: at(layout.goal),
        obstacle_pose,
        parts: layout.parts().iter().map(scene_part).collect(),
    }
}

/// The joint names `joint_states` and `joint_command` use: the URDF arm joints, then the fingers.
pub fn joint_names(model: &RobotModel) -> Vec<String> {
    model.joints.iter().map(|j| j.name.clone()).collect()
}

/// `sensor_msgs/JointState` for the arm and fingers.
pub fn joint_state(
    model: &RobotModel,
    positions: &[f64],
    velocities: &[f64],
    stamp: Time,
) -> JointState {
    JointState {
        header: header(stamp),
        name: joint_names(model),
        position: positions.to_vec(),
        velocity: velocities.to_vec(),
        effort: Vec::new(),
    }
}

/// A `joint_command` that cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum JointCommandError {
    /// `name` and `position` have different lengths.
    LengthMismatch {
        /// Names given.
        names: usize,
        /// Positions given.
        positions: usize,
    },
    /// A name that is no joint of this arm.
    UnknownJoint {
        /// The name.
        name: String,
        /// The valid names.
        valid: Vec<String>,
    },
    /// A joint named twice.
    Duplicate(String),
    /// Not every arm joint was given (a command sets all seven).
    MissingArmJoints(Vec<String>),
}

impl fmt::Display for JointCommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            JointCommandError::LengthMismatch { names, positions } => {
                write!(
                    f,
                    "joint_command has {names} names but {positions} positions; they must match"
                )
            }
            JointCommandError::UnknownJoint { name, valid } => {
                write!(
                    f,
                    "joint_command names unknown joint `{name}`; valid: {}",
                    valid.join(", ")
                )
            }
            JointCommandError::Duplicate(name) => write!(f, "joint_command names `{name}` twice"),
            JointCommandError::MissingArmJoints(missing) => {
                write!(
                    f,
                    "joint_command must set every arm joint; missing: {}",
                    missing.join(", ")
                )
            }
        }
    }
}

impl std::error::Error for JointCommandError {}

/// Arm targets (URDF order) and, if the fingers were named, a gripper opening (m), from a
/// `joint_command` addressed by joint name in any order. Values are not range-checked here;
/// the core's limits module does that.
pub fn arm_command(
    model: &RobotModel,
    cmd: &JointState,
) -> Result<([f64; ARM_DOF], Option<f64>), JointCommandError> {
    if cmd.name.len() != cmd.position.len() {
        return Err(JointCommandError::LengthMismatch {
            names: cmd.name.len(),
            positions: cmd.position.len(),
        });
    }
    let names = joint_names(model);
    let mut values: Vec<Option<f64>> = vec![None; names.len()];
    for (name, &value) in cmd.name.iter().zip(&cmd.position) {
        let index = names.iter().position(|n| n == name).ok_or_else(|| {
            JointCommandError::UnknownJoint {
                name: name.clone(),
                valid: names.clone(),
            }
        })?;
        if values[index].replace(value).is_some() {
            return Err(JointCommandError::Duplicate(name.clone()));
        }
    }
    let missing: Vec<String> = (0..ARM_DOF)
        .filter(|&j| values[j].is_none())
        .map(|j| names[j].clone())
        .collect();
    if !missing.is_empty() {
        return Err(JointCommandError::MissingArmJoints(missing));
    }
    let arm = std::array::from_fn(|j| values[j].expect("checked above"));
    // Either finger joint sets the opening (they are coupled: q_right = −q_left).
    let left = names
        .iter()
        .position(|n| n == FINGER_JOINTS[0])
        .and_then(|i| values[i]);
    let right = names
        .iter()
        .position(|n| n == FINGER_JOINTS[1])
        .and_then(|i| values[i]);
    let finger = left.or(right.map(|r| -r));
    Ok((arm, finger.map(composuite_core::physics::pad_gap)))
}

/// What the reward and termination need, read back from a `world_state` message. Every number
/// passes through the message unchanged, so the result equals the sim's own snapshot bit for bit.
pub fn snapshot(w: &msg::WorldState) -> composuite_core::reward::WorldSnapshot {
    let p = |p: &Point| nalgebra::Point3::new(p.x, p.y, p.z);
    let q = &w.eef_pose.orientation;
    let hand =
        nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z));
    composuite_core::reward::WorldSnapshot {
        object_position: p(&w.object_pose.position),
        grip_site_position: p(&w.eef_pose.position),
        hand_z_axis: hand * nalgebra::Vector3::z(),
        grasping: w.grasping,
        last_gripper_action: w.last_gripper_action,
    }
}

/// A `tf` transform of `child` in `parent`'s frame at `stamp`, from `child`'s pose there.
pub fn transform_in(
    parent: &str,
    child: &str,
    p: &Pose,
    stamp: Time,
) -> composuite_msgs::geometry_msgs::msg::TransformStamped {
    use composuite_msgs::geometry_msgs::msg::{Transform, TransformStamped};
    TransformStamped {
        header: Header {
            stamp,
            frame_id: parent.into(),
        },
        child_frame_id: child.into(),
        transform: Transform {
            translation: Vector3 {
                x: p.position.x,
                y: p.position.y,
                z: p.position.z,
            },
            rotation: p.orientation.clone(),
        },
    }
}

/// A `tf` transform of `child` in the world frame.
pub fn world_transform(
    child: &str,
    p: &Pose,
    stamp: Time,
) -> composuite_msgs::geometry_msgs::msg::TransformStamped {
    transform_in(WORLD_FRAME, child, p, stamp)
}

/// The task a `TaskSpec` message names (by its wire names; any spelling is accepted).
pub fn task_of(spec: &msg::TaskSpec) -> Result<TaskSpec, composuite_core::TaskParseError> {
    TaskSpec::from_names(&spec.robot, &spec.object, &spec.obstacle, &spec.objective)
}
