//! The controllers on the mock hardware: no physics, every command followed exactly.

use composuite_core::axes::Robot;
use composuite_core::physics::{ARM_DOF, RobotModel, pad_gap, robot_model};

use super::catalog::{self, Controller};
use super::gripper::{GripperFollowing, GripperGoal, GripperOutcome, GripperParams};
use super::running::{Controllers, End, Event, TRAJECTORY_PREEMPTED, TRAJECTORY_SUCCEEDED};
use super::trajectory::{
    Following, JointTolerance, Outcome, Tolerances, TrajectoryRequest, Waypoint, code,
    resolve_tolerances, validate,
};
use crate::sim::hardware::{
    ArmCommand, Command, GRIPPER, Hardware, JOINTS, JointSnapshot, MockHardware,
};

const PERIOD_NS: u64 = 50_000_000;

fn panda() -> &'static RobotModel {
    robot_model(Robot::Panda)
}

fn names(model: &RobotModel) -> Vec<String> {
    model.joints[..ARM_DOF]
        .iter()
        .map(|j| j.name.clone())
        .collect()
}

/// A start pose inside every Panda joint's limits.
fn home() -> [f64; JOINTS] {
    [0.0, 0.2, 0.0, -2.0, 0.0, 2.2, 0.8, 0.02]
}

fn waypoints(targets: &[[f64; ARM_DOF]]) -> Vec<Waypoint> {
    targets
        .iter()
        .enumerate()
        .map(|(i, t)| Waypoint {
            time_from_start_ns: (i as i64 + 1) * PERIOD_NS as i64,
            positions: t.to_vec(),
            ..Waypoint::default()
        })
        .collect()
}

fn request(model: &RobotModel, targets: &[[f64; ARM_DOF]]) -> TrajectoryRequest {
    TrajectoryRequest {
        joint_names: names(model),
        points: waypoints(targets),
        ..TrajectoryRequest::default()
    }
}

/// Run read → update → write until the outcome is decided (at most `limit` updates); the
/// final outcome (the mock keeps the commands written).
fn run(hardware: &mut MockHardware, following: &mut Following, limit: usize) -> Outcome {
    for _ in 0..limit {
        let state = hardware.read();
        let update = following.update(&state, PERIOD_NS);
        if update.outcome != Outcome::Running {
            return update.outcome;
        }
        let targets = update.command.expect("running: a command");
        hardware
            .write(&Command {
                arm: ArmCommand::Positions(targets),
                gripper: None,
            })
            .unwrap();
    }
    Outcome::Running
}

#[test]
fn waypoints_one_period_apart_are_commanded_exactly_then_the_goal_succeeds() {
    let model = panda();
    let start = home();
    let targets: Vec<[f64; ARM_DOF]> = (1..=4)
        .map(|k| std::array::from_fn(|j| start[j] + 0.01 * k as f64 * (j as f64 + 1.0) / 3.0))
        .collect();
    let trajectory = validate(&request(model, &targets), model, 0).unwrap();
    let mut following = Following::new(trajectory, Tolerances::default());
    let mut hardware = MockHardware::new(model, start, PERIOD_NS);
    assert_eq!(run(&mut hardware, &mut following, 20), Outcome::Succeeded);
    // One write per waypoint, each the waypoint itself, bit for bit (what joint_command sends).
    let written: Vec<[f64; ARM_DOF]> = hardware
        .written
        .iter()
        .map(|c| match c.arm {
            ArmCommand::Positions(p) => p,
            ArmCommand::Reference(_) => panic!("positions only"),
        })
        .collect();
    let bits = |v: &[[f64; ARM_DOF]]| -> Vec<Vec<u64>> {
        v.iter()
            .map(|p| p.iter().map(|x| x.to_bits()).collect())
            .collect()
    };
    assert_eq!(bits(&written), bits(&targets));
}

#[test]
fn between_waypoints_the_command_is_interpolated_and_joint_order_follows_the_names() {
    let model = panda();
    let start = home();
    let mut goal = start;
    goal[3] += 0.4;
    // Names reversed: values must land on the right joints.
    let mut reversed = names(model);
    reversed.reverse();
    let mut positions: Vec<f64> = goal[..ARM_DOF].to_vec();
    positions.reverse();
    let request = TrajectoryRequest {
        joint_names: reversed,
        points: vec![Waypoint {
            time_from_start_ns: 4 * PERIOD_NS as i64,
            positions,
            ..Waypoint::default()
        }],
        ..TrajectoryRequest::default()
    };
    let mut following =
        Following::new(validate(&request, model, 0).unwrap(), Tolerances::default());
    let mut hardware = MockHardware::new(model, start, PERIOD_NS);
    assert_eq!(run(&mut hardware, &mut following, 20), Outcome::Succeeded);
    let first = match hardware.written[0].arm {
        ArmCommand::Positions(p) => p,
        ArmCommand::Reference(_) => unreachable!(),
    };
    // Linear from the start state: a quarter of the way after one period of four.
    assert!((first[3] - (start[3] + 0.1)).abs() < 1e-12, "{first:?}");
    assert_eq!(first[0], start[0]);
    assert_eq!(hardware.written.len(), 4);
    assert_eq!(hardware.read().positions[3], goal[3]);
}

#[test]
fn a_first_waypoint_at_time_zero_is_the_desired_state_at_once() {
    // As joint_trajectory_controller samples: at a waypoint's own time, the waypoint (not the
    // state the trajectory was picked up from, even when both are at the same instant).
    let model = panda();
    let start = home();
    let mut targets = [[0.0; ARM_DOF]; 2];
    for (k, target) in targets.iter_mut().enumerate() {
        *target = std::array::from_fn(|j| start[j] + 0.05 * (k as f64 + 1.0));
    }
    let mut goal = request(model, &targets);
    goal.points[0].time_from_start_ns = 0;
    let mut following = Following::new(validate(&goal, model, 0).unwrap(), Tolerances::default());
    let update = following.update(
        &MockHardware::new(model, start, PERIOD_NS).read(),
        PERIOD_NS,
    );
    let desired: Vec<f64> = update.desired.iter().map(|d| d.position).collect();
    assert_eq!(desired, targets[0].to_vec());
}

#[test]
fn invalid_goals_are_refused_with_the_reason() {
    let model = panda();
    let ok = request(model, &[[0.0, 0.2, 0.0, -2.0, 0.0, 2.2, 0.8]]);
    assert!(validate(&ok, model, 0).is_ok());
    let refused = |change: &dyn Fn(&mut TrajectoryRequest), want: &str| {
        let mut bad = ok.clone();
        change(&mut bad);
        let err = validate(&bad, model, 10 * PERIOD_NS).unwrap_err();
        assert!(err.contains(want), "`{err}` lacks `{want}`");
    };
    refused(
        &|r| r.joint_names[2] = "elbow".into(),
        "Incoming joint elbow",
    );
    refused(
        &|r| {
            r.joint_names.pop();
        },
        "don't match the controller joints",
    );
    refused(
        &|r| r.joint_names[1] = r.joint_names[0].clone(),
        "named twice",
    );
    refused(&|r| r.points.clear(), "Empty trajectory");
    refused(
        &|r| r.points.push(r.points[0].clone()),
        "not strictly increasing",
    );
    refused(
        &|r| {
            r.points[0].positions.pop();
        },
        "Mismatch",
    );
    refused(
        &|r| r.points[0].velocities = vec![0.1; ARM_DOF],
        "is not zero",
    );
    refused(&|r| r.points[0].effort = vec![1.0; ARM_DOF], "effort");
    refused(&|r| r.points[0].positions[3] = 1.0, "outside its limits");
    refused(&|r| r.points[0].positions[0] = f64::NAN, "non-finite");
    refused(&|r| r.start_ns = PERIOD_NS, "ends in the past");
}

#[test]
fn path_tolerance_violation_aborts_and_stops_commanding() {
    let model = panda();
    let start = home();
    let mut goal = request(model, &[std::array::from_fn(|j| start[j])]);
    goal.points[0].positions[0] += 0.5;
    goal.points[0].time_from_start_ns = 4 * PERIOD_NS as i64;
    let mut following = Following::new(
        validate(&goal, model, 0).unwrap(),
        Tolerances {
            path: [0.05; ARM_DOF],
            ..Tolerances::default()
        },
    );
    // A stuck arm: halfway through, 0.25 rad behind the desired position.
    let mut state = MockHardware::new(model, start, PERIOD_NS).read();
    assert_eq!(
        following.update(&state, PERIOD_NS).outcome,
        Outcome::Running
    );
    state.time_ns = 2 * PERIOD_NS;
    let update = following.update(&state, PERIOD_NS);
    match update.outcome {
        Outcome::Aborted { code: c, message } => {
            assert_eq!(c, code::PATH_TOLERANCE_VIOLATED);
            assert!(message.contains("path tolerance"), "{message}");
        }
        other => panic!("expected an abort, got {other:?}"),
    }
    assert_eq!(update.command, None);
}

#[test]
fn goal_tolerance_waits_for_the_goal_time_then_aborts() {
    let model = panda();
    let start = home();
    let mut goal = start;
    goal[1] += 0.2;
    let tolerances = Tolerances {
        goal: [1e-3; ARM_DOF],
        goal_time: 0.12,
        ..Tolerances::default()
    };
    let mut following = Following::new(
        validate(
            &request(model, &[std::array::from_fn(|j| goal[j])]),
            model,
            0,
        )
        .unwrap(),
        tolerances,
    );
    // A stuck arm: reads never change, so the goal tolerance is never met.
    let mut state = MockHardware::new(model, start, PERIOD_NS).read();
    let mut outcomes = Vec::new();
    for k in 0..6 {
        state.time_ns = k * PERIOD_NS;
        outcomes.push(following.update(&state, PERIOD_NS).outcome);
    }
    // End at 1 period; 0.12 s later (after the update at 3.4 periods) it aborts: update 4.
    assert!(
        outcomes[..4].iter().all(|o| *o == Outcome::Running),
        "{outcomes:?}"
    );
    assert!(matches!(
        &outcomes[4],
        Outcome::Aborted { code: c, .. } if *c == code::GOAL_TOLERANCE_VIOLATED
    ));
}

#[test]
fn goal_tolerances_resolve_as_the_controller_does() {
    let model = panda();
    let names = names(model);
    let defaults = Tolerances {
        path: [0.1; ARM_DOF],
        goal: [0.01; ARM_DOF],
        goal_time: 0.5,
    };
    let entry = |name: &str, position: f64| JointTolerance {
        name: name.into(),
        position,
        velocity: 0.0,
        acceleration: 0.0,
    };
    let mut goal = TrajectoryRequest {
        path_tolerance: vec![
            entry(&names[0], 0.3),
            entry(&names[1], -1.0),
            entry(&names[2], 0.0),
        ],
        goal_tolerance: vec![entry(&names[6], 0.002)],
        goal_time_tolerance_ns: 2_000_000_000,
        ..TrajectoryRequest::default()
    };
    let (resolved, warning) = resolve_tolerances(&goal, &defaults, model);
    assert_eq!(warning, None);
    assert_eq!(&resolved.path[..3], &[0.3, 0.0, 0.1]);
    assert_eq!(resolved.goal[6], 0.002);
    assert_eq!(resolved.goal[0], 0.01);
    assert_eq!(resolved.goal_time, 2.0);
    // Any invalid entry: every tolerance falls back to the defaults.
    goal.goal_tolerance.push(entry("wrist", 0.1));
    let (resolved, warning) = resolve_tolerances(&goal, &defaults, model);
    assert_eq!(resolved, defaults);
    assert!(warning.unwrap().contains("unknown joint `wrist`"));
    goal.goal_tolerance.pop();
    goal.path_tolerance.push(entry(&names[3], -2.0));
    assert!(resolve_tolerances(&goal, &defaults, model).1.is_some());
}

fn gripper_state(time_ns: u64, position: f64, velocity: f64) -> JointSnapshot {
    let mut state = MockHardware::new(panda(), home(), PERIOD_NS).read();
    state.time_ns = time_ns;
    state.positions[GRIPPER] = position;
    state.velocities[GRIPPER] = velocity;
    state
}

#[test]
fn a_gripper_goal_within_tolerance_is_reached() {
    let goal = GripperGoal {
        position: 0.015,
        max_effort: 15.0,
    };
    let mut following = GripperFollowing::new(goal, GripperParams::default());
    // Written once, at the first update, as the pad opening of that finger position.
    let target = following.command().expect("the goal is written first");
    assert_eq!(target.opening, pad_gap(0.015));
    assert_eq!(following.command(), None);
    assert_eq!(
        following.update(&gripper_state(0, 0.0, 0.05)),
        GripperOutcome::Running
    );
    match following.update(&gripper_state(PERIOD_NS, 0.0105, 0.0)) {
        GripperOutcome::Done { succeeded, result } => {
            assert!(succeeded);
            assert!(result.reached_goal && !result.stalled);
            assert_eq!(result.position, 0.0105);
            assert_eq!(result.effort, 15.0);
        }
        other => panic!("expected reached, got {other:?}"),
    }
}

#[test]
fn a_gripper_held_open_by_an_object_stalls_after_the_timeout() {
    let params = GripperParams::default();
    let mut following = GripperFollowing::new(
        GripperGoal {
            position: 0.0,
            max_effort: 0.0,
        },
        params,
    );
    // Closing for two periods, then stopped 0.015 m short (an object between the pads).
    assert_eq!(
        following.update(&gripper_state(0, 0.02, -0.1)),
        GripperOutcome::Running
    );
    assert_eq!(
        following.update(&gripper_state(PERIOD_NS, 0.017, -0.1)),
        GripperOutcome::Running
    );
    let stopped_at = PERIOD_NS;
    let timeout_ns = (params.stall_timeout * 1e9) as u64;
    // Not moving for exactly the timeout is not yet a stall; one period more is.
    assert_eq!(
        following.update(&gripper_state(stopped_at + timeout_ns, 0.015, 0.0005)),
        GripperOutcome::Running
    );
    match following.update(&gripper_state(
        stopped_at + timeout_ns + PERIOD_NS,
        0.015,
        0.0,
    )) {
        GripperOutcome::Done { succeeded, result } => {
            assert!(!succeeded, "stalling aborts unless allow_stalling");
            assert!(result.stalled && !result.reached_goal);
        }
        other => panic!("expected stalled, got {other:?}"),
    }
}

/// Read → update → write on the mock until no goal runs (at most `limit` periods); the events.
fn run_controllers(
    hardware: &mut MockHardware,
    controllers: &mut Controllers<u32>,
    limit: usize,
) -> Vec<Event<u32>> {
    let mut events = Vec::new();
    for _ in 0..limit {
        let state = hardware.read();
        let (command, new) = controllers.update(&state, PERIOD_NS);
        events.extend(new);
        if !controllers.running() {
            break;
        }
        hardware.write(&command).unwrap();
    }
    events
}

fn ended(events: &[Event<u32>]) -> Vec<(Option<u32>, End, i32, String)> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::TrajectoryEnded {
                goal,
                end,
                code,
                message,
            } => Some((*goal, *end, *code, message.clone())),
            _ => None,
        })
        .collect()
}

#[test]
fn a_trajectory_goal_writes_one_period_per_waypoint_then_succeeds_with_feedback() {
    let model = panda();
    let start = home();
    let targets: Vec<[f64; ARM_DOF]> = (1..=3)
        .map(|k| std::array::from_fn(|j| start[j] - 0.02 * k as f64))
        .collect();
    let following = Following::new(
        validate(&request(model, &targets), model, 0).unwrap(),
        Tolerances::default(),
    );
    let mut hardware = MockHardware::new(model, start, PERIOD_NS);
    let mut controllers = Controllers::holding(std::array::from_fn(|j| start[j]));
    assert_eq!(controllers.start_trajectory(following, Some(7)), None);
    let events = run_controllers(&mut hardware, &mut controllers, 20);
    // Three writes (no write once decided), four updates of feedback.
    assert_eq!(hardware.written.len(), 3);
    let feedback = events
        .iter()
        .filter(|e| matches!(e, Event::TrajectoryFeedback { goal: 7, .. }))
        .count();
    assert_eq!(feedback, 4);
    assert_eq!(
        ended(&events),
        vec![(
            Some(7),
            End::Succeeded,
            code::SUCCESSFUL,
            TRAJECTORY_SUCCEEDED.to_string()
        )]
    );
    // Held at the last waypoint afterwards.
    let (command, _) = controllers.update(&hardware.read(), PERIOD_NS);
    assert_eq!(command.arm, ArmCommand::Positions(targets[2]));
}

#[test]
fn trajectories_end_on_preemption_cancel_and_direct_commands_with_the_reason() {
    let model = panda();
    let start = home();
    let far: [f64; ARM_DOF] = std::array::from_fn(|j| start[j] + 0.1);
    let slow = || {
        let mut goal = request(model, &[far]);
        goal.points[0].time_from_start_ns = 10 * PERIOD_NS as i64;
        Following::new(validate(&goal, model, 0).unwrap(), Tolerances::default())
    };
    let mut hardware = MockHardware::new(model, start, PERIOD_NS);
    let mut controllers = Controllers::holding(std::array::from_fn(|j| start[j]));
    controllers.start_trajectory(slow(), Some(1));
    run_controllers(&mut hardware, &mut controllers, 2);
    // A new goal preempts: the old one is aborted as joint_trajectory_controller words it.
    let preempted = controllers.start_trajectory(slow(), Some(2)).unwrap();
    assert_eq!(
        ended(&[preempted]),
        vec![(
            Some(1),
            End::Aborted,
            code::INVALID_GOAL,
            TRAJECTORY_PREEMPTED.to_string()
        )]
    );
    run_controllers(&mut hardware, &mut controllers, 2);
    // Canceling another goal does nothing; canceling the running one holds the arm where it is.
    let state = hardware.read();
    assert_eq!(controllers.cancel_trajectory(1, &state), None);
    let canceled = controllers.cancel_trajectory(2, &state).unwrap();
    assert!(matches!(
        canceled,
        Event::TrajectoryEnded {
            goal: Some(2),
            end: End::Canceled,
            ..
        }
    ));
    assert!(!controllers.running());
    let (command, _) = controllers.update(&state, PERIOD_NS);
    assert_eq!(
        command.arm,
        ArmCommand::Positions(std::array::from_fn(|j| state.positions[j]))
    );
    // A direct command ends a running trajectory and names its source.
    controllers.start_trajectory(slow(), Some(3));
    let superseded = controllers
        .command_arm(ArmCommand::Positions(far), "joint_command")
        .unwrap();
    let (_, end, code_, message) = ended(&[superseded]).remove(0);
    assert_eq!((end, code_), (End::Aborted, code::INVALID_GOAL));
    assert!(message.contains("`joint_command`"), "{message}");
}

#[test]
fn a_new_gripper_goal_cancels_the_running_one() {
    let mut hardware = MockHardware::new(panda(), home(), PERIOD_NS);
    let mut controllers: Controllers<u32> = Controllers::holding([0.0; ARM_DOF]);
    let goal = |position| {
        GripperFollowing::new(
            GripperGoal {
                position,
                max_effort: 0.0,
            },
            GripperParams::default(),
        )
    };
    let state = hardware.read();
    // Home has the fingers open (0.02 m): close, then (replacing that goal) half-close.
    assert_eq!(controllers.start_gripper(goal(-0.0115), 1, &state), None);
    let replaced = controllers.start_gripper(goal(0.0), 2, &state).unwrap();
    assert!(matches!(
        replaced,
        Event::GripperEnded {
            goal: 1,
            end: End::Canceled,
            ..
        }
    ));
    // The mock moves the finger to its target at once: reached at the next update.
    let events = run_controllers(&mut hardware, &mut controllers, 5);
    assert!(matches!(
        events.as_slice(),
        [Event::GripperEnded {
            goal: 2,
            end: End::Succeeded,
            ..
        }]
    ));
    assert_eq!(hardware.written.len(), 1);
}

#[test]
fn the_controllers_parameter_names_known_controllers_once() {
    let names = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        catalog::parse_list(&names(&[
            "gripper_action_controller",
            "joint_trajectory_controller"
        ])),
        Ok(vec![Controller::JointTrajectory, Controller::GripperAction])
    );
    let err = catalog::parse_list(&names(&["jtc"])).unwrap_err();
    assert!(
        err.contains("unknown controller `jtc`") && err.contains("forward_position_controller")
    );
    assert!(
        catalog::parse_list(&names(&["forward_position_controller"; 2]))
            .unwrap_err()
            .contains("twice")
    );
    let model = panda();
    assert_eq!(
        Controller::GripperAction.command_interfaces(model),
        vec![format!("{}/position", model.joints[ARM_DOF].name)]
    );
    assert_eq!(catalog::state_interfaces(model).len(), 16);
}
