//! The generated types against their sources: the .msg files, Jazzy's type hashes, the
//! rosbag2 definition layout, the reference's observation layout
//! (docs/src/reference-facts.md §5), and round trips.

mod support;

use std::path::{Path, PathBuf};

use composuite_msgs::{ArrayKind, ElementType, MessageVisitor, RosMessage, TypeDescription, cdr};
use rand::SeedableRng;

/// The folders holding one folder per interface package besides composuite_msgs (as build.rs).
const PACKAGE_FOLDERS: [&str; 3] = ["standard", "ros2_control", "simulation_interfaces"];

fn msgs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The interface file a type comes from, and the part of it that is the type's own text.
fn source_text(ros_name: &str) -> Option<String> {
    let parts: Vec<&str> = ros_name.split('/').collect();
    let (package, kind, name) = (parts[0], parts[1], parts[2]);
    let base: PathBuf = if package == "composuite_msgs" {
        msgs_dir()
    } else {
        PACKAGE_FOLDERS
            .iter()
            .map(|folder| msgs_dir().join(folder).join(package))
            .find(|dir| dir.is_dir())?
    };
    if kind == "msg" {
        return std::fs::read_to_string(base.join("msg").join(format!("{name}.msg"))).ok();
    }
    let (file, part) = name.rsplit_once('_')?;
    let text = std::fs::read_to_string(base.join(kind).join(format!("{file}.{kind}"))).ok()?;
    let parts: Vec<&str> = text.split("---\n").collect();
    let index = match (kind, part) {
        ("srv", "Request") | ("action", "Goal") => 0,
        ("srv", "Response") | ("action", "Result") => 1,
        ("action", "Feedback") => 2,
        _ => return None, // `_Event` is synthesized, it has no file
    };
    parts.get(index).map(|p| p.to_string())
}

/// Field names of a .msg text by a plain line scan, independent of the code generator.
fn field_names_in(text: &str) -> Vec<String> {
    text.lines()
        .map(|l| l.split('#').next().unwrap().trim())
        .filter(|l| !l.is_empty())
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            let _type = words.next()?;
            let name = words.next()?;
            (!name.contains('=') && !words.next().is_some_and(|w| w.starts_with('=')))
                .then(|| name.to_string())
        })
        .collect()
}

struct All(
    Vec<(
        &'static str,
        &'static TypeDescription,
        &'static str,
        &'static str,
        &'static str,
    )>,
);
impl MessageVisitor for All {
    fn visit<T: RosMessage>(&mut self) {
        self.0.push((
            T::ROS_NAME,
            T::DESCRIPTION,
            T::DDS_NAME,
            T::DEFINITION,
            T::TYPE_HASH,
        ));
    }
}

fn all_types() -> Vec<(
    &'static str,
    &'static TypeDescription,
    &'static str,
    &'static str,
    &'static str,
)> {
    let mut all = All(Vec::new());
    composuite_msgs::visit_messages(&mut all);
    all.0
}

#[test]
fn every_interface_file_has_a_type_and_fields_match() {
    let types = all_types();
    let mut checked = 0;
    for (ros_name, desc, ..) in &types {
        let Some(text) = source_text(ros_name) else {
            assert!(
                ros_name.ends_with("_Event"),
                "{ros_name} has no source file"
            );
            continue;
        };
        let expected = field_names_in(&text);
        let actual: Vec<&str> = desc.fields.iter().map(|f| f.name).collect();
        if expected.is_empty() {
            assert_eq!(
                actual,
                vec!["structure_needs_at_least_one_member"],
                "{ros_name}"
            );
        } else {
            assert_eq!(
                actual, expected,
                "{ros_name}: generated fields differ from its file"
            );
        }
        checked += 1;
    }
    // Every .msg/.srv file on disk is covered.
    let mut files = 0;
    let mut count = |dir: &Path, ext: &str, per_file: usize| {
        for entry in std::fs::read_dir(dir).unwrap() {
            if entry.unwrap().path().extension().is_some_and(|e| e == ext) {
                files += per_file;
            }
        }
    };
    count(&msgs_dir().join("msg"), "msg", 1);
    count(&msgs_dir().join("srv"), "srv", 2);
    for folder in PACKAGE_FOLDERS {
        for package in std::fs::read_dir(msgs_dir().join(folder)).unwrap() {
            let package = package.unwrap().path();
            for (kind, per_file) in [("msg", 1), ("srv", 2), ("action", 3)] {
                if package.join(kind).is_dir() {
                    count(&package.join(kind), kind, per_file);
                }
            }
        }
    }
    assert_eq!(
        checked, files,
        "types with a source file vs. message parts on disk"
    );
}

#[test]
fn names_follow_ros_2_conventions() {
    for (ros_name, _, dds_name, ..) in all_types() {
        let parts: Vec<&str> = ros_name.split('/').collect();
        assert_eq!(parts.len(), 3, "{ros_name}");
        assert!(matches!(parts[1], "msg" | "srv" | "action"), "{ros_name}");
        assert_eq!(
            dds_name,
            format!("{}::{}::dds_::{}_", parts[0], parts[1], parts[2])
        );
    }
    assert_eq!(
        <composuite_msgs::srv::ResetRequest as RosMessage>::DDS_NAME,
        "composuite_msgs::srv::dds_::Reset_Request_"
    );
}

/// Hashes read from the type-description files ROS 2 Jazzy's own generator installs
/// (`share/<pkg>/msg/<Type>.json` of the ros-jazzy wheels). The interop tests compare every
/// type; these pins make a regression visible without Python.
#[test]
fn jazzy_type_hashes_pinned() {
    use composuite_msgs::{
        builtin_interfaces, control_msgs, controller_manager_msgs, geometry_msgs, rcl_interfaces,
        rosgraph_msgs, sensor_msgs, service_msgs, std_msgs, trajectory_msgs, visualization_msgs,
    };
    let pins = [
        (
            builtin_interfaces::msg::Time::TYPE_HASH,
            "b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
        ),
        (
            std_msgs::msg::Header::TYPE_HASH,
            "f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
        ),
        (
            std_msgs::msg::Bool::TYPE_HASH,
            "feb91e995ff9ebd09c0cb3d2aed18b11077585839fb5db80193b62d74528f6c9",
        ),
        // The `reference_action` topic's type (and ros2_control's forward controllers').
        (
            std_msgs::msg::Float64MultiArray::TYPE_HASH,
            "1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f",
        ),
        (
            std_msgs::msg::MultiArrayLayout::TYPE_HASH,
            "4c66e6f78e740ac103a94cf63259f968e48c617e7699e829b63c21a5cb50dac6",
        ),
        (
            std_msgs::msg::MultiArrayDimension::TYPE_HASH,
            "5e773a60a4c7fc8a54985f307c7837aa2994252a126c301957a24e31282c9cbe",
        ),
        (
            sensor_msgs::msg::JointState::TYPE_HASH,
            "a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
        ),
        (
            geometry_msgs::msg::Pose::TYPE_HASH,
            "d501954e9476cea2996984e812054b68026ae0bfae789d9a10b23daf35cc90fa",
        ),
        // What simulation_interfaces' EntityState and SpawnEntity hold.
        (
            geometry_msgs::msg::Accel::TYPE_HASH,
            "dc448243ded9b1fcbcca24aba0c22f013dae06c354ba2d849571c0a2a3f57ca0",
        ),
        (
            geometry_msgs::msg::PoseStamped::TYPE_HASH,
            "10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
        ),
        (
            rosgraph_msgs::msg::Clock::TYPE_HASH,
            "692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564",
        ),
        // What every node publishes on /rosout and /parameter_events (recorded by `-a`).
        (
            rcl_interfaces::msg::Log::TYPE_HASH,
            "e28ce254ca8abc06abf92773b74602cdbf116ed34fbaf294fb9f81da9f318eac",
        ),
        (
            rcl_interfaces::msg::ParameterEvent::TYPE_HASH,
            "043e627780fcad87a22d225bc2a037361dba713fca6a6b9f4b869a5aa0393204",
        ),
        (
            rcl_interfaces::msg::Parameter::TYPE_HASH,
            "ddfe6442cffc462317adb5c92536a7b6dd55858c5c3e1e328165a6b73c2831af",
        ),
        (
            rcl_interfaces::msg::ParameterValue::TYPE_HASH,
            "115fc089a387e23c7ecd3525c9189c379109119d6ab82e8dfbde0fdf6a7f9b68",
        ),
        // ros2_control's interfaces (msgs/ros2_control/): the hashes a colcon build of
        // control_msgs 5.8.0 / controller_manager_msgs 4.46.0 / trajectory_msgs 5.3.5 generates.
        (
            trajectory_msgs::msg::JointTrajectory::TYPE_HASH,
            "179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e",
        ),
        (
            trajectory_msgs::msg::JointTrajectoryPoint::TYPE_HASH,
            "de8907036d8bd45aac6f30cc9044a3d4a329c42cbf719aff7d95a584cfa532d7",
        ),
        (
            control_msgs::action::FollowJointTrajectoryGoal::TYPE_HASH,
            "8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
        ),
        (
            control_msgs::action::FollowJointTrajectoryResult::TYPE_HASH,
            "8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
        ),
        (
            control_msgs::action::FollowJointTrajectoryFeedback::TYPE_HASH,
            "3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
        ),
        (
            control_msgs::action::GripperCommandGoal::TYPE_HASH,
            "607d9f41eb241e1922e90f02125e87ae6bfb78f7f64a71dc92630263d01f8b6d",
        ),
        (
            control_msgs::action::GripperCommandResult::TYPE_HASH,
            "bf512d5aa6a0e4fe4d8be22b2ec4a1973c3d250fa1f65e47450322c25c45c0a0",
        ),
        (
            control_msgs::action::GripperCommandFeedback::TYPE_HASH,
            "8f7c520077bab528bb9161ee3b83c81eee1f8aecadb8922ce82c79d667a819c4",
        ),
        (
            control_msgs::msg::GripperCommand::TYPE_HASH,
            "57eb8f326c9889ca8bb34ead82cc94cc09bf6bc5c3b6c09546dca3a00b589890",
        ),
        (
            control_msgs::msg::JointTolerance::TYPE_HASH,
            "c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
        ),
        (
            controller_manager_msgs::msg::ControllerState::TYPE_HASH,
            "9a8780ab9814b6032978a07c6c7033cf1a7894ac8d948a6fb72afea07b04cc83",
        ),
        (
            controller_manager_msgs::msg::HardwareInterface::TYPE_HASH,
            "b4c556991db81ca56a49338b5e8f0675a6707faee54fba161d2bbd4d963d418a",
        ),
        (
            <controller_manager_msgs::srv::ListControllers as composuite_msgs::RosService>::TYPE_HASH,
            "4f8e36bb1fa5afdeba45c2d56ae6a2097b1493a253f961dd6290c085033bd189",
        ),
        (
            <controller_manager_msgs::srv::ListHardwareInterfaces as composuite_msgs::RosService>::TYPE_HASH,
            "c3e561a6e8cc7b9d577d8065c783038e51f6950cbe9bed67fb117a3e2e04d8f1",
        ),
        // The scene as markers (`scene_markers`, `object_markers`): visualization_msgs 5.3.6.
        (
            visualization_msgs::msg::MarkerArray::TYPE_HASH,
            "86cb8800b6fb05b5eff1abd7a56f62a5641d3ae9a1c29e78e67e704f1d067dcf",
        ),
        (
            visualization_msgs::msg::Marker::TYPE_HASH,
            "45b13ccf791f225962bf74e746f9644518855d783a6f42ba0cc14fde2b4f3ce0",
        ),
        (
            visualization_msgs::msg::MeshFile::TYPE_HASH,
            "7710ece15a148fb7c9b546364cfb215bb06098087bd6394fe5b73a493508f8c4",
        ),
        (
            visualization_msgs::msg::UVCoordinate::TYPE_HASH,
            "f27f7ed21fe360c6066944f856b801a0c0d1e94e815b6886444b42d90b196a26",
        ),
        (
            sensor_msgs::msg::CompressedImage::TYPE_HASH,
            "15640771531571185e2efc8a100baf923961a4d15d5569652e6cb6691e8e371a",
        ),
        // The sim's camera topics.
        (
            sensor_msgs::msg::Image::TYPE_HASH,
            "d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47",
        ),
        (
            sensor_msgs::msg::CameraInfo::TYPE_HASH,
            "b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275",
        ),
        (
            sensor_msgs::msg::RegionOfInterest::TYPE_HASH,
            "ad16bcba5f9131dcdba6fbded19f726f5440e3c513b4fb586dd3027eeed8abb1",
        ),
        (
            std_msgs::msg::ColorRGBA::TYPE_HASH,
            "77a7a5b9ae477306097665106e0413ba74440245b1f3d0c6d6405fe5c7813fe8",
        ),
        (
            builtin_interfaces::msg::Duration::TYPE_HASH,
            "e8d009f659816f758b75334ee1a9ca5b5c0b859843261f14c7f937349599d93b",
        ),
        // `char[16]` hashes as uint8[16] in Jazzy.
        (
            service_msgs::msg::ServiceEventInfo::TYPE_HASH,
            "41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45",
        ),
    ];
    for (ours, jazzy) in pins {
        assert_eq!(ours, format!("RIHS01_{jazzy}"));
    }
}

#[test]
fn definitions_follow_the_rosbag2_layout() {
    let sep = "=".repeat(80);
    let js = <composuite_msgs::sensor_msgs::msg::JointState as RosMessage>::DEFINITION;
    let own = source_text("sensor_msgs/msg/JointState").unwrap();
    let header = source_text("std_msgs/msg/Header").unwrap();
    let time = source_text("builtin_interfaces/msg/Time").unwrap();
    assert_eq!(
        js,
        format!(
            "{own}\n{sep}\nMSG: std_msgs/Header\n{header}\n{sep}\nMSG: builtin_interfaces/Time\n{time}"
        )
    );

    // Dependencies: sorted at each level, depth-first, each once.
    let obs = <composuite_msgs::msg::Observation as RosMessage>::DEFINITION;
    let sections: Vec<&str> = obs
        .lines()
        .filter_map(|l| l.strip_prefix("MSG: "))
        .collect();
    assert_eq!(
        sections,
        [
            "composuite_msgs/GoalFactor",
            "geometry_msgs/Point",
            "geometry_msgs/Quaternion",
            "geometry_msgs/Vector3",
            "composuite_msgs/ObjectFactor",
            "composuite_msgs/ObstacleFactor",
            "composuite_msgs/RobotFactor",
            "composuite_msgs/TaskFactor",
            "std_msgs/Header",
            "builtin_interfaces/Time",
        ]
    );
    for (ros_name, _, _, definition, _) in all_types() {
        if let Some(text) = source_text(ros_name) {
            assert!(
                definition.starts_with(&text),
                "{ros_name}: definition must start with its file text"
            );
        }
    }
}

/// Number of float64 values a type flattens to (the observation factors are all-float).
fn flat_len(desc: &TypeDescription) -> usize {
    desc.fields
        .iter()
        .map(|f| {
            let per = match &f.element {
                ElementType::Float64 => 1,
                ElementType::Nested(inner) => flat_len(inner),
                other => panic!("{}.{} is {other:?}, not float64", desc.ros_name, f.name),
            };
            match f.array {
                ArrayKind::Single => per,
                ArrayKind::Fixed(n) => n * per,
                other => panic!("{}.{} is a sequence ({other:?})", desc.ros_name, f.name),
            }
        })
        .sum()
}

/// docs/src/reference-facts.md §5: object 14, obstacle 14, goal 17, task one-hots 4 x 4, robot 32;
/// 93 with the task indicator, 77 without.
#[test]
fn observation_factors_have_the_reference_sizes() {
    use composuite_msgs::msg::*;
    let sizes = [
        flat_len(ObjectFactor::DESCRIPTION),
        flat_len(ObstacleFactor::DESCRIPTION),
        flat_len(GoalFactor::DESCRIPTION),
        flat_len(TaskFactor::DESCRIPTION),
        flat_len(RobotFactor::DESCRIPTION),
    ];
    assert_eq!(sizes, [14, 14, 17, 16, 32]);
    assert_eq!(
        sizes.iter().sum::<usize>(),
        Observation::FLAT_SIZE_WITH_TASK as usize
    );
    assert_eq!(
        sizes.iter().sum::<usize>() - sizes[3],
        Observation::FLAT_SIZE_WITHOUT_TASK as usize
    );
}

/// The bytes real rclpy 7.1.6 (Fast DDS) produced for this header.
#[test]
fn header_encodes_like_rclpy() {
    use composuite_msgs::std_msgs::msg::Header;
    let header = Header {
        stamp: composuite_msgs::builtin_interfaces::msg::Time { sec: 1, nanosec: 2 },
        frame_id: "ab".into(),
    };
    assert_eq!(
        support::hex(&cdr::encode(&header).unwrap()),
        "00010000010000000200000003000000616200"
    );
}

#[test]
fn defaults_come_from_the_msg_files() {
    let q = composuite_msgs::geometry_msgs::msg::Quaternion::default();
    assert_eq!((q.x, q.y, q.z, q.w), (0.0, 0.0, 0.0, 1.0));
    assert_eq!(composuite_msgs::msg::ScenePart::SHAPE_CYLINDER, 2);
}

#[test]
fn random_instances_round_trip_exactly() {
    struct RoundTrip(rand_chacha::ChaCha8Rng, usize);
    impl MessageVisitor for RoundTrip {
        fn visit<T: RosMessage>(&mut self) {
            for _ in 0..100 {
                let msg: T = support::random_message(&mut self.0, 4);
                let bytes = cdr::encode(&msg).unwrap();
                let back: T = cdr::decode(&bytes).unwrap();
                assert_eq!(cdr::encode(&back).unwrap(), bytes, "{}", T::ROS_NAME);
                assert_eq!(back, msg, "{}", T::ROS_NAME);
                self.1 += 1;
            }
        }
    }
    let mut visitor = RoundTrip(rand_chacha::ChaCha8Rng::seed_from_u64(7), 0);
    composuite_msgs::visit_messages(&mut visitor);
    assert_eq!(visitor.1, 100 * support::message_names().len());
}
