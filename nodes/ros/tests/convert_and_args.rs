//! Conversions to the wire types and the `--ros-args` parser.

use composuite_core::env::{Action, Env, EnvConfig, EpisodeLayout};
use composuite_msgs::{RosMessage, cdr, msg};
use composuite_ros::shared::convert::{self, JointCommandError};
use composuite_ros::shared::ros_args::{self, ParamValue};

fn args(text: &str) -> Vec<String> {
    text.split_whitespace().map(String::from).collect()
}

#[test]
fn observation_message_carries_the_same_numbers() {
    let mut env = Env::new(
        "Jaco/dumbbell/object_wall/trash_can".parse().unwrap(),
        EnvConfig::default(),
    );
    env.reset(5).unwrap();
    let step = env.step(&Action::Reference([0.1; 8])).unwrap();
    let stamp = convert::time_from_nanos(50_000_000);
    let m = convert::observation(&step.observation, stamp.clone(), env.episode(), env.steps());
    assert_eq!(m.flat, step.observation.flat());
    assert_eq!(m.flat.len() as u32, msg::Observation::FLAT_SIZE_WITH_TASK);
    assert_eq!(
        (m.header.stamp.sec, m.header.stamp.nanosec),
        (0, 50_000_000)
    );
    assert_eq!(m.header.frame_id, "world");
    assert_eq!(m.step, 1);
    // The factor fields sit where the flat vector has them.
    assert_eq!(
        [
            m.object.position.x,
            m.object.position.y,
            m.object.position.z
        ],
        m.flat[0..3]
    );
    assert_eq!(
        [m.obstacle.orientation.x, m.obstacle.orientation.w],
        [m.flat[17], m.flat[20]]
    );
    assert_eq!(m.goal.object_to_goal.z, m.flat[44]);
    assert_eq!(m.robot.gripper_qvel[1], m.flat[92]);
    // And it survives the wire.
    let back: msg::Observation = cdr::decode(&cdr::encode(&m).unwrap()).unwrap();
    assert_eq!(back, m);
}

#[test]
fn no_obstacle_keeps_the_zero_quaternion_on_the_wire() {
    let mut env = Env::new(
        "IIWA/box/no_obstacle/pick_place".parse().unwrap(),
        EnvConfig::default(),
    );
    let obs = env.reset(0).unwrap();
    let m = convert::observation(&obs, convert::time_from_nanos(0), 1, 0);
    let q = &m.obstacle.orientation;
    assert_eq!((q.x, q.y, q.z, q.w), (0.0, 0.0, 0.0, 0.0));
    let scene = convert::scene(&env.layout(), env.config(), 1, convert::time_from_nanos(0));
    // The layout alone (no physics world) gives the same scene.
    let layout = EpisodeLayout::new("IIWA/box/no_obstacle/pick_place".parse().unwrap(), 0).unwrap();
    assert_eq!(
        convert::scene(
            &layout,
            &EnvConfig::default(),
            1,
            convert::time_from_nanos(0)
        ),
        scene
    );
    assert_eq!(scene.obstacle_pose.orientation.w, 0.0);
    assert_eq!(scene.task.task_index, 0);
    assert_eq!(scene.horizon, 500);
    assert!((scene.control_period - 0.05).abs() < 1e-12);
    assert!(scene.parts.iter().any(|p| p.name.starts_with("bin1/")));
    assert!(
        scene.parts.iter().any(|p| !p.collides),
        "the goal marker is visual only"
    );
    assert_eq!(
        cdr::decode::<msg::Scene>(&cdr::encode(&scene).unwrap()).unwrap(),
        scene
    );
}

#[test]
fn staged_reward_and_world_state_messages() {
    let mut env = Env::new(
        "Panda/plate/goal_wall/shelf".parse().unwrap(),
        EnvConfig::default(),
    );
    env.reset(1).unwrap();
    let step = env.step(&Action::Reference([0.0; 8])).unwrap();
    let r = convert::staged_reward(
        &step.info.staged,
        &EnvConfig::default().reward,
        convert::time_from_nanos(50_000_000),
        1,
        1,
    );
    assert_eq!(
        r.stage_names,
        ["reach", "grasp", "lift", "align", "approach"]
    );
    assert_eq!(r.stage_maxima, [0.2, 0.3, 0.5, 0.8, 0.9]);
    assert_eq!(r.total, step.reward);
    assert_eq!(
        r.current_stage,
        step.info.staged.current_stage().map_or(-1, |i| i as i8)
    );
    let w = convert::world_state(
        &env.world_state(),
        convert::time_from_nanos(50_000_000),
        1,
        1,
    );
    assert_eq!(w.arm_joint_positions, env.world().arm_positions());
    assert_eq!(
        <msg::WorldState as RosMessage>::ROS_NAME,
        "composuite_msgs/msg/WorldState"
    );
}

#[test]
fn joint_commands_map_names_and_refuse_bad_ones() {
    let env = Env::new(
        "Panda/box/no_obstacle/push".parse().unwrap(),
        EnvConfig::default(),
    );
    let model = env.world().model;
    let mut cmd = convert::joint_state(model, &[0.0; 9], &[], convert::time_from_nanos(0));
    cmd.name.reverse(); // any order
    cmd.position = (0..9).map(|i| i as f64 / 10.0).collect();
    let (arm, gripper) = convert::arm_command(model, &cmd).unwrap();
    // Reversed: r_finger got 0.0, l_finger 0.1, joint7 0.2, ..., joint1 0.8. The left finger
    // sets the opening when both are given (range checks come later, in the core).
    assert_eq!(arm[0], 0.8);
    assert_eq!(arm[6], 0.2);
    assert_eq!(gripper, Some(composuite_core::physics::pad_gap(0.1)));

    cmd.name[0] = "elbow".into();
    let err = convert::arm_command(model, &cmd).unwrap_err();
    assert!(matches!(err, JointCommandError::UnknownJoint { .. }));
    assert!(err.to_string().contains("valid: joint1, joint2"), "{err}");
    cmd.name.pop();
    assert!(matches!(
        convert::arm_command(model, &cmd),
        Err(JointCommandError::LengthMismatch {
            names: 8,
            positions: 9
        })
    ));
    let partial = composuite_msgs::sensor_msgs::msg::JointState {
        name: vec!["joint1".into()],
        position: vec![0.1],
        ..Default::default()
    };
    let err = convert::arm_command(model, &partial).unwrap_err();
    assert!(err.to_string().contains("missing: joint2, joint3"), "{err}");
}

#[test]
fn ros_args_sections_are_parsed_like_rcl() {
    let a = ros_args::parse(&args(
        "--verbose --ros-args -r __ns:=/env_03 -r __node:=sim -r joint_states:=js -p mode:=lockstep \
         -p rate:=100 -p gain:=2.5 -p on:=true -p ids:=[1,2] --params-file params/sim.yaml --log-level DEBUG -- extra",
    ))
    .unwrap();
    assert_eq!(a.namespace.as_deref(), Some("/env_03"));
    assert_eq!(a.node_name.as_deref(), Some("sim"));
    assert_eq!(a.remapped("joint_states"), "js");
    assert_eq!(a.remapped("clock"), "clock");
    assert_eq!(
        a.param("mode"),
        Some(&ParamValue::String("lockstep".into()))
    );
    assert_eq!(a.param("rate"), Some(&ParamValue::Integer(100)));
    assert_eq!(a.param("gain"), Some(&ParamValue::Double(2.5)));
    assert_eq!(a.param("on"), Some(&ParamValue::Bool(true)));
    assert_eq!(
        a.param("ids"),
        Some(&ParamValue::Array(vec![
            ParamValue::Integer(1),
            ParamValue::Integer(2)
        ]))
    );
    assert_eq!(
        a.params_files,
        [std::path::PathBuf::from("params/sim.yaml")]
    );
    assert_eq!(a.log_level.as_deref(), Some("debug"));
    assert_eq!(a.other, ["--verbose", "extra"]);
}

/// Namespaces and security enclaves: `/`, or `/`-separated tokens of letters, digits and
/// underscores, none starting with a digit.
#[test]
fn fully_qualified_names_are_absolute_ros_names() {
    for good in ["/", "/talker", "/composuite/sim", "/_a/b_2"] {
        assert!(ros_args::is_fully_qualified_name(good), "{good}");
    }
    for bad in ["", "talker", "/talker/", "//x", "/2x", "/a-b", "/a b"] {
        assert!(!ros_args::is_fully_qualified_name(bad), "{bad}");
    }
}

#[test]
fn bad_ros_args_say_what_is_valid() {
    let err = |text: &str| ros_args::parse(&args(text)).unwrap_err().to_string();
    assert!(err("--ros-args -r __ns:=env").contains("must be absolute"));
    assert!(err("--ros-args -r __node:=9lives").contains("node name `9lives` is invalid"));
    assert!(err("--ros-args -p mode").contains("name:=value"));
    assert!(err("--ros-args -p").contains("needs a value"));
    assert!(err("--ros-args --log-level loud").contains("valid: debug, info, warn, error, fatal"));
    assert!(err("--ros-args --frobnicate").contains("unknown --ros-args option `--frobnicate`"));
    assert!(err("--ros-args -r a-b:=c").contains("not a valid ROS name"));
}

#[test]
fn ros_environment_is_read_and_checked() {
    use composuite_ros::shared::environment::{DiscoveryRange, RosEnvironment};
    let env = |pairs: &'static [(&'static str, &'static str)]| {
        move |k: &str| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    };
    let d = RosEnvironment::read(env(&[])).unwrap();
    assert_eq!(
        (d.domain_id, d.discovery_range),
        (0, DiscoveryRange::Subnet)
    );
    let d = RosEnvironment::read(env(&[
        ("ROS_DOMAIN_ID", "42"),
        ("ROS_AUTOMATIC_DISCOVERY_RANGE", "localhost"),
    ]))
    .unwrap();
    assert_eq!(
        (d.domain_id, d.discovery_range),
        (42, DiscoveryRange::Localhost)
    );
    let d = RosEnvironment::read(env(&[("ROS_LOCALHOST_ONLY", "1")])).unwrap();
    assert_eq!(d.discovery_range, DiscoveryRange::Localhost);
    let e = RosEnvironment::read(env(&[("ROS_DOMAIN_ID", "300")])).unwrap_err();
    assert!(e.to_string().contains("valid: 0..=232"), "{e}");
    let e = RosEnvironment::read(env(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LAN")])).unwrap_err();
    assert!(
        e.to_string().contains("valid: OFF, LOCALHOST, SUBNET"),
        "{e}"
    );
}

#[test]
fn qos_profiles_follow_ros_defaults() {
    use composuite_ros::shared::qos;
    use ros2_client::qos::{Durability, History, Reliability};
    assert!(matches!(
        qos::state().reliability,
        Reliability::Reliable { .. }
    ));
    assert_eq!(qos::state().durability, Durability::Volatile);
    assert_eq!(qos::state().history, History::KeepLast { depth: 10 });
    assert_eq!(qos::latched().durability, Durability::TransientLocal);
    assert_eq!(qos::latched().history, History::KeepLast { depth: 1 });
    assert_eq!(qos::clock().reliability, Reliability::BestEffort);
    for profile in [qos::state(), qos::latched(), qos::clock(), qos::services()] {
        assert_ne!(
            profile.history,
            History::KeepAll,
            "KeepAll readers drop data in ros2-client"
        );
    }
}
