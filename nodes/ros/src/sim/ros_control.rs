//! The ros2_control interfaces' messages, to and from the controllers' ROS-free types:
//! `FollowJointTrajectory` goals and feedback, `GripperCommand` results, and what
//! `controller_manager`'s `list_controllers` / `list_hardware_interfaces` answer.

use composuite_core::physics::{ARM_DOF, RobotModel};
use composuite_msgs::builtin_interfaces::msg::Duration as DurationMsg;
use composuite_msgs::control_msgs::action::{
    FollowJointTrajectoryFeedback, FollowJointTrajectoryGoal, GripperCommandResult,
};
use composuite_msgs::control_msgs::msg::JointTolerance as JointToleranceMsg;
use composuite_msgs::controller_manager_msgs::msg::{ControllerState, HardwareInterface};
use composuite_msgs::controller_manager_msgs::srv::{
    ListControllersResponse, ListHardwareInterfacesResponse,
};
use composuite_msgs::trajectory_msgs::msg::{JointTrajectory, JointTrajectoryPoint};

use crate::shared::convert;
use crate::sim::controllers::catalog::{self, Controller};
use crate::sim::controllers::gripper::GripperResult;
use crate::sim::controllers::trajectory::{JointTolerance, TrajectoryRequest, Update, Waypoint};

/// Nanoseconds of a `builtin_interfaces/Duration`.
pub fn duration_ns(d: &DurationMsg) -> i64 {
    i64::from(d.sec) * 1_000_000_000 + i64::from(d.nanosec)
}

/// A trajectory as received on the `joint_trajectory` topic (no tolerances).
pub fn topic_request(trajectory: &JointTrajectory) -> TrajectoryRequest {
    TrajectoryRequest {
        joint_names: trajectory.joint_names.clone(),
        points: trajectory
            .points
            .iter()
            .map(|p: &JointTrajectoryPoint| Waypoint {
                time_from_start_ns: duration_ns(&p.time_from_start),
                positions: p.positions.clone(),
                velocities: p.velocities.clone(),
                accelerations: p.accelerations.clone(),
                effort: p.effort.clone(),
            })
            .collect(),
        start_ns: convert::nanos_of(&trajectory.header.stamp),
        ..TrajectoryRequest::default()
    }
}

/// A trajectory action goal, or why it is refused before validation (the parts this controller
/// does not take).
pub fn goal_request(goal: &FollowJointTrajectoryGoal) -> Result<TrajectoryRequest, String> {
    if !goal.multi_dof_trajectory.joint_names.is_empty() {
        return Err(
            "multi_dof_trajectory is not supported: the arm has single-DOF joints only".into(),
        );
    }
    let tolerances = |entries: &[JointToleranceMsg]| -> Vec<JointTolerance> {
        entries
            .iter()
            .map(|t| JointTolerance {
                name: t.name.clone(),
                position: t.position,
                velocity: t.velocity,
                acceleration: t.acceleration,
            })
            .collect()
    };
    Ok(TrajectoryRequest {
        path_tolerance: tolerances(&goal.path_tolerance),
        goal_tolerance: tolerances(&goal.goal_tolerance),
        goal_time_tolerance_ns: duration_ns(&goal.goal_time_tolerance),
        ..topic_request(&goal.trajectory)
    })
}

/// The feedback of one update: desired, actual and error in the controller's joint order.
pub fn feedback(model: &RobotModel, update: &Update) -> FollowJointTrajectoryFeedback {
    let time_from_start = DurationMsg {
        sec: update.time_from_start_ns.div_euclid(1_000_000_000) as i32,
        nanosec: update.time_from_start_ns.rem_euclid(1_000_000_000) as u32,
    };
    let point =
        |positions: Vec<f64>, velocities: Vec<f64>, accelerations: Vec<f64>| JointTrajectoryPoint {
            positions,
            velocities,
            accelerations,
            effort: Vec::new(),
            time_from_start: time_from_start.clone(),
        };
    let desired = &update.desired;
    FollowJointTrajectoryFeedback {
        header: convert::header(convert::time_from_nanos(update.time_ns)),
        joint_names: convert::joint_names(model)[..ARM_DOF].to_vec(),
        desired: point(
            desired.iter().map(|s| s.position).collect(),
            desired.iter().map(|s| s.velocity).collect(),
            desired.iter().map(|s| s.acceleration).collect(),
        ),
        actual: point(
            update.actual_positions.to_vec(),
            update.actual_velocities.to_vec(),
            Vec::new(),
        ),
        error: point(
            (0..ARM_DOF)
                .map(|j| desired[j].position - update.actual_positions[j])
                .collect(),
            (0..ARM_DOF)
                .map(|j| desired[j].velocity - update.actual_velocities[j])
                .collect(),
            Vec::new(),
        ),
        ..FollowJointTrajectoryFeedback::default()
    }
}

/// A gripper goal's result message.
pub fn gripper_result(result: &GripperResult) -> GripperCommandResult {
    GripperCommandResult {
        position: result.position,
        effort: result.effort,
        stalled: result.stalled,
        reached_goal: result.reached_goal,
    }
}

/// `list_controllers`: the broadcaster and the controllers up, all active. Interfaces are listed
/// once a robot is loaded (the first scene). Trajectory and forward controllers both claim the
/// arm: here they share it (the last command wins), where ros2_control would let one be active.
pub fn list_controllers(
    up: &[Controller],
    model: Option<&RobotModel>,
    update_rate_hz: u16,
) -> ListControllersResponse {
    let interfaces = |f: fn(Controller, &RobotModel) -> Vec<String>, c: Controller| {
        model.map(|m| f(c, m)).unwrap_or_default()
    };
    ListControllersResponse {
        controller: std::iter::once(Controller::JointStateBroadcaster)
            .chain(up.iter().copied())
            .map(|c| ControllerState {
                name: c.name().into(),
                state: "active".into(),
                r#type: c.type_name().into(),
                update_rate: update_rate_hz,
                claimed_interfaces: interfaces(Controller::command_interfaces, c),
                required_command_interfaces: interfaces(Controller::command_interfaces, c),
                required_state_interfaces: interfaces(Controller::state_interfaces, c),
                ..ControllerState::default()
            })
            .collect(),
    }
}

/// `list_hardware_interfaces`: every command and state interface (none before the first scene);
/// a command interface is claimed when a controller that is up uses it.
pub fn list_hardware_interfaces(
    up: &[Controller],
    model: Option<&RobotModel>,
) -> ListHardwareInterfacesResponse {
    let Some(model) = model else {
        return ListHardwareInterfacesResponse::default();
    };
    let claimed: Vec<String> = up
        .iter()
        .flat_map(|c| c.command_interfaces(model))
        .collect();
    let entry = |name: String, is_claimed: bool| HardwareInterface {
        name,
        data_type: "double".into(),
        is_available: true,
        is_claimed,
    };
    ListHardwareInterfacesResponse {
        command_interfaces: catalog::command_interfaces(model)
            .into_iter()
            .map(|name| {
                let is_claimed = claimed.contains(&name);
                entry(name, is_claimed)
            })
            .collect(),
        state_interfaces: catalog::state_interfaces(model)
            .into_iter()
            .map(|name| entry(name, false))
            .collect(),
    }
}
