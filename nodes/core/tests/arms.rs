//! The four arms with the gripper in rapier: URDF validity, kinematics against an independent
//! chain, holding, tracking, limits under random commands, determinism.

mod common;

use std::collections::{HashMap, HashSet};

use composuite_core::arena::{BIN1_POSITION, ROBOT_BASE_POSITION, arena_parts, object_geometry};
use composuite_core::axes::{AxisElement, Robot};
use composuite_core::axes::{Object, Objective, Obstacle};
use composuite_core::control::{ArmCommandError, validate_arm_targets, validate_gripper_width};
use composuite_core::physics::{ARM_DOF, GripperCommand, PhysicsParams, SimWorld, robot_model};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};

const URDF_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../urdf");

fn urdf_name(robot: Robot) -> &'static str {
    match robot {
        Robot::Iiwa => "iiwa",
        Robot::Jaco => "jaco",
        Robot::Gen3 => "gen3",
        Robot::Panda => "panda",
    }
}

fn read_urdf(name: &str) -> urdf_rs::Robot {
    urdf_rs::read_file(format!("{URDF_DIR}/{name}.urdf"))
        .unwrap_or_else(|e| panic!("{name}.urdf: {e}"))
}

#[test]
fn every_urdf_is_one_tree_with_unique_names() {
    for name in ["iiwa", "jaco", "gen3", "panda", "rethink_gripper"] {
        let robot = read_urdf(name);
        let links: HashSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(
            links.len(),
            robot.links.len(),
            "{name}: duplicate link names"
        );
        let joints: HashSet<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(
            joints.len(),
            robot.joints.len(),
            "{name}: duplicate joint names"
        );
        let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
        let unique_children: HashSet<&str> = children.iter().copied().collect();
        assert_eq!(
            unique_children.len(),
            children.len(),
            "{name}: a link has two parents"
        );
        let roots: Vec<&&str> = links
            .iter()
            .filter(|l| !unique_children.contains(*l))
            .collect();
        assert_eq!(roots.len(), 1, "{name}: roots {roots:?}");
        // A tree: every link reachable from the root, links = joints + 1.
        assert_eq!(robot.links.len(), robot.joints.len() + 1, "{name}");
        for joint in &robot.joints {
            assert!(
                links.contains(joint.parent.link.as_str())
                    && links.contains(joint.child.link.as_str())
            );
            if matches!(
                joint.joint_type,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Prismatic
            ) {
                assert!(
                    joint.limit.lower < joint.limit.upper,
                    "{name}/{}",
                    joint.name
                );
                assert!(
                    joint.limit.effort > 0.0 && joint.limit.velocity > 0.0,
                    "{name}/{}",
                    joint.name
                );
            }
        }
        for link in &robot.links {
            if link.inertial.mass.value > 0.0 {
                let i = &link.inertial.inertia;
                let m = nalgebra::Matrix3::new(
                    i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
                );
                let mut e: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
                e.sort_by(f64::total_cmp);
                assert!(
                    e[0] > 0.0,
                    "{name}/{}: inertia not positive definite",
                    link.name
                );
                assert!(
                    e[0] + e[1] >= e[2] * 0.999,
                    "{name}/{}: inertia breaks the triangle inequality",
                    link.name
                );
            }
        }
    }
}

#[test]
fn models_have_seven_arm_joints_and_two_coupled_fingers() {
    for robot in Robot::all() {
        let model = robot_model(robot);
        assert_eq!(model.joints.len(), 9, "{robot:?}");
        assert_eq!(&model.joints[7].name, "l_finger_joint");
        assert_eq!(&model.joints[8].name, "r_finger_joint");
        for name in [
            "grip_site",
            "right_hand",
            "gripper_base",
            "l_finger_tip",
            "r_finger_tip",
        ] {
            assert!(model.links.contains_key(name), "{robot:?}: {name}");
        }
        // Reference effort limits (docs/src/reference-facts.md §4.1).
        let efforts: Vec<f64> = model.joints[..7].iter().map(|j| j.effort).collect();
        let expected = match robot {
            Robot::Iiwa => vec![176.0, 176.0, 110.0, 110.0, 110.0, 40.0, 40.0],
            Robot::Jaco => vec![30.5, 30.5, 30.5, 30.5, 30.5, 6.8, 6.8],
            Robot::Gen3 => vec![32.0, 32.0, 32.0, 32.0, 32.0, 13.0, 13.0],
            Robot::Panda => vec![80.0, 80.0, 80.0, 80.0, 80.0, 12.0, 12.0],
        };
        assert_eq!(efforts, expected, "{robot:?}");
        for (q, joint) in robot.init_qpos().iter().zip(&model.joints) {
            if let Some((lo, hi)) = joint.limits {
                assert!(
                    (lo..=hi).contains(q),
                    "{robot:?}: init {q} outside {}",
                    joint.name
                );
            }
        }
    }
}

/// World poses of every URDF link by walking the raw URDF joints (arm, then the gripper
/// grafted on `right_hand`), with nalgebra in f64: independent of the loader's body merging.
fn independent_link_poses(
    robot: Robot,
    q: &[f64; ARM_DOF],
    fingers: [f64; 2],
) -> HashMap<String, Isometry3<f64>> {
    let arm = read_urdf(urdf_name(robot));
    let gripper = read_urdf("rethink_gripper");
    // (parent, child, origin, axis, type, name) of every joint.
    type RawJoint = (
        String,
        String,
        Isometry3<f64>,
        Vector3<f64>,
        urdf_rs::JointType,
        String,
    );
    let mut joints: Vec<RawJoint> = Vec::new();
    for j in arm.joints.iter().chain(&gripper.joints) {
        let [x, y, z] = *j.origin.xyz;
        let [r, p, yaw] = *j.origin.rpy;
        let origin = Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(r, p, yaw),
        );
        let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
        joints.push((
            j.parent.link.clone(),
            j.child.link.clone(),
            origin,
            axis,
            j.joint_type.clone(),
            j.name.clone(),
        ));
    }
    joints.push((
        "right_hand".into(),
        "gripper_base".into(),
        Isometry3::identity(),
        Vector3::zeros(),
        urdf_rs::JointType::Fixed,
        "mount".into(),
    ));
    let values: HashMap<String, f64> = arm
        .joints
        .iter()
        .filter(|j| j.joint_type != urdf_rs::JointType::Fixed)
        .map(|j| j.name.clone())
        .zip(q.iter().copied())
        .chain([
            ("l_finger_joint".to_string(), fingers[0]),
            ("r_finger_joint".to_string(), fingers[1]),
        ])
        .collect();
    let mut poses = HashMap::new();
    let root = arm.links[0].name.clone();
    poses.insert(
        root,
        Isometry3::translation(
            ROBOT_BASE_POSITION[0],
            ROBOT_BASE_POSITION[1],
            ROBOT_BASE_POSITION[2],
        ),
    );
    while poses.len() < arm.links.len() + gripper.links.len() {
        for (parent, child, origin, axis, kind, name) in &joints {
            if let (Some(p), false) = (poses.get(parent).copied(), poses.contains_key(child)) {
                let v = values.get(name).copied().unwrap_or(0.0);
                let motion = match kind {
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                        Isometry3::from_parts(
                            Translation3::identity(),
                            UnitQuaternion::from_scaled_axis(axis * v),
                        )
                    }
                    urdf_rs::JointType::Prismatic => {
                        Isometry3::translation(axis.x * v, axis.y * v, axis.z * v)
                    }
                    _ => Isometry3::identity(),
                };
                poses.insert(child.clone(), p * origin * motion);
            }
        }
    }
    poses
}

fn random_q(robot: Robot, rng: &mut impl Rng) -> [f64; ARM_DOF] {
    let model = robot_model(robot);
    std::array::from_fn(|j| {
        let (lo, hi) = model.joints[j]
            .limits
            .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI));
        rng.random_range(lo..hi)
    })
}

#[test]
fn simulated_link_poses_match_an_independent_fk() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut worst: f64 = 0.0;
    for robot in Robot::all() {
        let mut world = SimWorld::new(robot, PhysicsParams::default());
        for _ in 0..20 {
            let q = random_q(robot, &mut rng);
            let finger = rng.random_range(-0.0115..0.020833);
            world.reset_arm(&q, finger);
            let expected = independent_link_poses(robot, &q, [finger, -finger]);
            for (link, pose) in &expected {
                let sim = world.link_world_pose(link).unwrap();
                let err = (sim.translation.vector - pose.translation.vector).norm();
                worst = worst.max(err);
                assert!(err <= 1e-6, "{robot:?} {link}: {err:.2e} m");
                assert!(
                    sim.rotation.angle_to(&pose.rotation) < 1e-5,
                    "{robot:?} {link}"
                );
            }
            // The crate's own FK (used by IK) agrees too.
            let kin = composuite_core::kinematics::link_pose(world.model, &q, "grip_site").unwrap();
            assert!(
                (kin.translation.vector - expected["grip_site"].translation.vector).norm() < 1e-9
            );
        }
    }
    eprintln!("worst link position error: {worst:.2e} m");
}

/// The reference's grip site right after reset (docs/src/reference-facts.md §2.7: CompoSuite +
/// robosuite 1.4 + MuJoCo).
#[test]
fn grip_site_at_reset_matches_the_reference() {
    let check = [
        (Robot::Iiwa, [-0.03117, -0.1, 1.00666]),
        (Robot::Jaco, [-0.10350, -0.11636, 1.07581]),
        (Robot::Gen3, [-0.06700, -0.12485, 0.99267]),
        (Robot::Panda, [-0.04125, -0.1, 0.99914]),
    ];
    for (robot, expected) in check {
        let world = SimWorld::new(robot, PhysicsParams::default());
        let p = world.grip_site_pose().translation.vector;
        let err = (p - Vector3::from(expected)).norm();
        assert!(
            err < 0.01,
            "{robot:?}: grip site {p:?} is {err} m from the reference"
        );
        assert!(err < 0.001, "{robot:?}: {err} m (expected sub-millimetre)");
    }
}

#[test]
fn each_arm_holds_its_initial_pose_under_gravity() {
    for robot in Robot::all() {
        let mut world = SimWorld::new(robot, PhysicsParams::default());
        let q0 = world.arm_positions();
        for _ in 0..5000 {
            world.step(); // 10 s
        }
        for (j, (a, b)) in q0.iter().zip(world.arm_positions()).enumerate() {
            assert!(
                (b - a).abs() < 0.002,
                "{robot:?} joint {}: drifted {:.4} rad",
                j + 1,
                b - a
            );
        }
    }
}

#[test]
fn each_arm_tracks_a_step_on_every_joint() {
    for robot in Robot::all() {
        let mut world = SimWorld::new(robot, PhysicsParams::default());
        let start = world.arm_positions();
        let target: [f64; ARM_DOF] = std::array::from_fn(|j| {
            let up = start[j] + 0.3;
            match world.model.joints[j].limits {
                Some((_, hi)) if up > hi => start[j] - 0.3,
                _ => up,
            }
        });
        world.set_arm_targets(&target);
        let mut reached = [None; ARM_DOF];
        let mut peak = [0.0f64; ARM_DOF];
        for step in 1..=1000 {
            world.step();
            for (j, q) in world.arm_positions().iter().enumerate() {
                let progress = (q - start[j]) / (target[j] - start[j]);
                peak[j] = peak[j].max(progress);
                if reached[j].is_none() && progress >= 0.95 {
                    reached[j] = Some(step as f64 * 0.002);
                }
            }
        }
        for j in 0..ARM_DOF {
            let t = reached[j]
                .unwrap_or_else(|| panic!("{robot:?} joint {}: not at 95 % after 2 s", j + 1));
            assert!(t <= 1.0, "{robot:?} joint {}: 95 % after {t} s", j + 1);
            assert!(
                peak[j] < 1.10,
                "{robot:?} joint {}: overshoot {:.1} %",
                j + 1,
                (peak[j] - 1.0) * 100.0
            );
        }
    }
}

#[test]
fn bad_commands_are_refused_or_clamped_with_a_reason() {
    let model = robot_model(Robot::Panda);
    let err = validate_arm_targets(model, &[0.0; 6]).unwrap_err();
    assert!(matches!(err, ArmCommandError::WrongLength { got: 6, .. }));
    assert!(
        err.to_string()
            .contains("expected 7 (one per joint: joint1, joint2"),
        "{err}"
    );
    let mut q = Robot::Panda.init_qpos();
    q[2] = f64::NAN;
    let err = validate_arm_targets(model, &q).unwrap_err();
    assert!(err.to_string().contains("`joint3` is NaN"), "{err}");
    q[2] = f64::INFINITY;
    assert!(matches!(
        validate_arm_targets(model, &q),
        Err(ArmCommandError::NotFinite { .. })
    ));
    q[2] = 0.0;
    q[3] = 0.5; // joint4's range is [-3.0718, -0.0698]
    let (applied, clamped) = validate_arm_targets(model, &q).unwrap();
    assert_eq!(applied[3], -0.0698);
    assert_eq!(clamped.len(), 1);
    assert!(
        clamped[0]
            .to_string()
            .contains("outside its limits [-3.071800, -0.069800]; using -0.069800"),
        "{}",
        clamped[0]
    );

    let (w, c) = validate_gripper_width(model, 0.5, 0.0).unwrap();
    assert!((w - 0.078766).abs() < 1e-6 && c.is_some());
    assert!(
        validate_gripper_width(model, f64::NAN, 0.0)
            .unwrap_err()
            .to_string()
            .contains("position is NaN")
    );
    assert!(
        validate_gripper_width(model, 0.04, -1.0)
            .unwrap_err()
            .to_string()
            .contains(">= 0")
    );
}

#[test]
fn random_targets_never_give_nan_or_leave_the_limits() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for robot in Robot::all() {
        let mut world = SimWorld::new(robot, PhysicsParams::default());
        let model = world.model;
        let mut worst: f64 = 0.0;
        for _ in 0..2500 {
            // Anything, including far outside the limits: validation clamps.
            let raw: Vec<f64> = (0..ARM_DOF).map(|_| rng.random_range(-7.0..7.0)).collect();
            let (targets, _) = validate_arm_targets(model, &raw).unwrap();
            world.set_arm_targets(&targets);
            world.step_control();
            for (j, q) in world.arm_positions().iter().enumerate() {
                assert!(q.is_finite(), "{robot:?} joint {}: {q}", j + 1);
                if let Some((lo, hi)) = model.joints[j].limits {
                    worst = worst.max(lo - q).max(q - hi);
                }
            }
        }
        assert!(
            worst <= 0.05,
            "{robot:?}: a joint went {worst:.3} rad past its limit"
        );
    }
}

#[test]
fn same_inputs_give_bit_identical_states() {
    let run = || {
        let mut world = SimWorld::new(Robot::Jaco, PhysicsParams::default());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut trace = Vec::new();
        for _ in 0..40 {
            let q = random_q(Robot::Jaco, &mut rng);
            world.set_arm_targets(&q);
            world.step_control();
            trace.extend(world.arm_positions().map(f64::to_bits));
            trace.extend(world.finger_positions().map(f64::to_bits));
        }
        trace
    };
    assert_eq!(run(), run());
}

/// Move the servo targets to `target` over `seconds`, control step by control step.
fn move_to(world: &mut SimWorld, target: &[f64; ARM_DOF], seconds: f64) {
    for q in common::path(&world.arm_targets(), target, seconds) {
        world.set_arm_targets(&q);
        world.step_control();
    }
}

/// The grasp rig: each arm, gripper pointing down, closes on the box resting on the bin-1 floor,
/// lifts it 15 cm and holds it 2 s. The box must not slip in the grip (< 5 mm) nor sink into
/// anything (< 2 mm), with arm-table collisions on.
#[test]
fn each_arm_grasps_lifts_and_holds_the_box() {
    let box_z = object_geometry(Object::Box).spawn_z();
    let box_position = Vector3::new(BIN1_POSITION[0], BIN1_POSITION[1], box_z);
    for robot in Robot::all() {
        let mut world = SimWorld::new(robot, PhysicsParams::default());
        world.add_arena(&arena_parts(Objective::PickPlace, Obstacle::NoObstacle));
        world.add_object(
            Object::Box,
            &Isometry3::translation(box_position.x, box_position.y, box_position.z),
        );
        for _ in 0..50 {
            world.step();
        }
        let rest = world.object_pose().unwrap().translation.vector;
        assert!(
            (rest - box_position).norm() < 0.002,
            "{robot:?}: box settled at {rest:?}"
        );

        let down = common::pointing_down(&world);
        let above = common::pads_at(
            &world,
            box_position + Vector3::new(0.0, 0.0, 0.12),
            down,
            &world.arm_positions(),
        );
        let at = common::pads_at(&world, box_position, down, &above);
        let lifted = common::pads_at(
            &world,
            box_position + Vector3::new(0.0, 0.0, 0.15),
            down,
            &at,
        );
        move_to(&mut world, &above, 2.0);
        move_to(&mut world, &at, 1.5);
        world.set_gripper(GripperCommand::Width {
            width: 0.0,
            max_effort: 0.0,
        });
        for _ in 0..10 {
            world.step_control();
        }
        let contacts = world.finger_contacts();
        assert!(
            contacts.left_pad && contacts.right_pad,
            "{robot:?}: both pads should touch the box: {contacts:?}"
        );
        assert!(contacts.grasping(Object::Box));
        move_to(&mut world, &lifted, 1.5);
        let grip_start = world.grip_site_pose().inverse() * world.object_pose().unwrap();
        let mut deepest: f64 = 0.0;
        for _ in 0..40 {
            for _ in 0..25 {
                world.step();
                deepest = deepest.max(world.object_penetration());
            }
        }
        let grip_end = world.grip_site_pose().inverse() * world.object_pose().unwrap();
        let slip = (grip_end.translation.vector - grip_start.translation.vector).norm();
        assert!(
            world.finger_contacts().grasping(Object::Box),
            "{robot:?}: grasp lost while holding"
        );
        let height = world.object_pose().unwrap().translation.z - box_z;
        eprintln!(
            "{robot:?}: lifted {height:.4} m, slip {:.2} mm, deepest contact {:.2} mm",
            slip * 1e3,
            deepest * 1e3
        );
        assert!(
            (height - 0.15).abs() < 0.01,
            "{robot:?}: box is {height} m above its start"
        );
        assert!(slip < 0.005, "{robot:?}: box slipped {slip} m in 2 s");
        assert!(
            deepest < 0.002,
            "{robot:?}: a contact went {deepest} m deep"
        );
    }
}

#[test]
fn the_grasp_rule_follows_the_reference() {
    use composuite_core::physics::FingerContacts;
    let only = |left_pad, right_pad, left_finger, right_finger| FingerContacts {
        left_pad,
        right_pad,
        left_finger,
        right_finger,
    };
    for object in [Object::Box, Object::HollowBox, Object::Dumbbell] {
        assert!(only(true, true, true, true).grasping(object));
        assert!(
            !only(true, false, true, true).grasping(object),
            "one pad is not a grasp"
        );
        assert!(
            !only(false, false, true, true).grasping(object),
            "finger bodies are not pads"
        );
    }
    // The plate: a pad on one side and any part of the other finger.
    assert!(only(true, false, true, true).grasping(Object::Plate));
    assert!(only(false, true, true, false).grasping(Object::Plate));
    assert!(!only(true, false, true, false).grasping(Object::Plate));
    assert!(!only(false, false, true, true).grasping(Object::Plate));
}

/// The null-space motion of the 7-joint arms keeps the grip site's pose (to first order) while
/// the elbow still moves for most poses: what the expert swings the forearm off walls with.
#[test]
fn null_space_motion_holds_the_gripper_and_moves_the_elbow() {
    use composuite_core::kinematics::{body_poses, link_pose, null_space_motion};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let eps = 1e-4;
    for robot in Robot::all() {
        let model = robot_model(robot);
        let mut elbow_moves = 0;
        for _ in 0..10 {
            let q = random_q(robot, &mut rng);
            let dq = nalgebra::SVector::<f64, ARM_DOF>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let swing = null_space_motion(model, "grip_site", &q, &dq).unwrap();
            let norm = swing.norm();
            assert!(norm > 1e-3, "{robot:?}: no null space at {q:?}");
            let mut moved = q;
            for j in 0..ARM_DOF {
                moved[j] += eps * swing[j] / norm;
            }
            let a = link_pose(model, &q, "grip_site").unwrap();
            let b = link_pose(model, &moved, "grip_site").unwrap();
            let shift = (a.translation.vector - b.translation.vector).norm();
            let turn = a.rotation.angle_to(&b.rotation);
            assert!(
                shift < 1e-3 * eps && turn < 1e-3 * eps,
                "{robot:?}: the gripper moved {shift:.2e} m, {turn:.2e} rad"
            );
            // The elbow (body 4) moves ≥ 2 cm per radian of swing, unless the arm is near a
            // pose where the swing only turns the wrist.
            let elbow = |q: &[f64; ARM_DOF]| body_poses(model, q, [0.0, 0.0])[4].translation.vector;
            if (elbow(&q) - elbow(&moved)).norm() > 0.02 * eps {
                elbow_moves += 1;
            }
        }
        assert!(
            elbow_moves >= 5,
            "{robot:?}: the elbow moved in {elbow_moves} of 10 poses"
        );
    }
}
