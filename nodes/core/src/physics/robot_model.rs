//! An arm with its gripper as plain data, read from the project's URDFs.
//!
//! The URDF links are grouped into rigid bodies: a link joined to its parent by a fixed joint
//! is merged into the parent's body (its inertial and collisions moved into the body frame), so
//! the simulated multibody has one body per moving part. The model is parsed once per arm and
//! cached; building a world clones nothing but this description.

use std::collections::HashMap;
use std::sync::OnceLock;

use nalgebra::{Isometry3, Matrix3, Vector3};

use super::urdf::{ModelError, join_capsules, urdf_pose};
use crate::axes::{AxisElement, Robot};

/// The URDF texts, compiled in so the binaries do not depend on the working directory.
fn urdf_text(robot: Robot) -> &'static str {
    match robot {
        Robot::Iiwa => include_str!("../../../../urdf/iiwa.urdf"),
        Robot::Jaco => include_str!("../../../../urdf/jaco.urdf"),
        Robot::Gen3 => include_str!("../../../../urdf/gen3.urdf"),
        Robot::Panda => include_str!("../../../../urdf/panda.urdf"),
    }
}

/// Number of arm joints.
pub const ARM_DOF: usize = 7;

const GRIPPER_URDF: &str = include_str!("../../../../urdf/rethink_gripper.urdf");
/// The arm link the gripper's root is mounted on, with an identity pose.
pub const GRIPPER_MOUNT_LINK: &str = "right_hand";
/// The gripper's root link.
pub const GRIPPER_ROOT_LINK: &str = "gripper_base";
/// The end-effector point of the reference (`eef_pos`, reach distances).
pub const GRIP_SITE_LINK: &str = "grip_site";
/// The arm's hand frame whose orientation the reference reports as `eef_quat`.
pub const HAND_LINK: &str = "right_hand";
/// Finger joint names (left opens with +q, right with -q).
pub const FINGER_JOINTS: [&str; 2] = ["l_finger_joint", "r_finger_joint"];
/// The most rigid bodies an arm model may have (each arm has 10: the base, 7 links, 2
/// fingers), so per-step work can keep per-body values on the stack.
pub const MAX_BODIES: usize = 12;

/// A collision primitive in its body's frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// Half-extents (m).
    Box(Vector3<f64>),
    /// Along local z: radius and half-length of the straight part (m).
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Half the distance between the cap centres (m).
        half_length: f64,
    },
    /// Along local z: radius and half-length (m).
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Half the length (m).
        half_length: f64,
    },
    /// Radius (m).
    Sphere(f64),
}

/// A named collision primitive placed in a body's frame.
#[derive(Debug, Clone)]
pub struct CollisionShape {
    /// The URDF collision name (e.g. `l_fingerpad`, `link3_capsule`, `mount_pedestal`).
    pub name: String,
    /// The shape.
    pub shape: Shape,
    /// Pose in the body frame.
    pub pose: Isometry3<f64>,
}

/// One rigid body of the multibody (one or more merged URDF links).
#[derive(Debug, Clone)]
pub struct BodyModel {
    /// The URDF link that defines the body frame.
    pub name: String,
    /// Total mass (kg).
    pub mass: f64,
    /// Centre of mass in the body frame (m).
    pub com: Vector3<f64>,
    /// Inertia tensor about the centre of mass, body axes (kg·m²).
    pub inertia: Matrix3<f64>,
    /// Collision primitives.
    pub collisions: Vec<CollisionShape>,
}

/// Kind of a moving joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointKind {
    /// Rotation about the axis (rad), with limits unless continuous.
    Revolute,
    /// Translation along the axis (m).
    Prismatic,
}

/// A moving joint between two bodies.
#[derive(Debug, Clone)]
pub struct JointModel {
    /// URDF joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Index of the parent body.
    pub parent: usize,
    /// Index of the child body.
    pub child: usize,
    /// Pose of the child body frame in the parent body frame at q = 0.
    pub origin: Isometry3<f64>,
    /// Joint axis in the child frame (unit).
    pub axis: Vector3<f64>,
    /// Position limits, `None` for continuous joints.
    pub limits: Option<(f64, f64)>,
    /// Effort limit (N·m or N).
    pub effort: f64,
    /// Velocity limit (rad/s or m/s).
    pub velocity: f64,
}

/// An arm with the gripper mounted, as bodies and joints in tree order (parents first).
#[derive(Debug, Clone)]
pub struct RobotModel {
    /// Which arm.
    pub robot: Robot,
    /// Bodies; index 0 is the fixed base (with the mount pedestal).
    pub bodies: Vec<BodyModel>,
    /// Moving joints, parents before children: the 7 arm joints, then the two finger joints.
    pub joints: Vec<JointModel>,
    /// Every URDF link: (body index, pose of the link frame in the body frame).
    pub links: HashMap<String, (usize, Isometry3<f64>)>,
    /// Every URDF joint, fixed ones included, parents before children: the link tree as
    /// robot_state_publisher walks it (one `tf` transform per entry).
    pub tree: Vec<LinkJoint>,
}

/// One joint of the URDF link tree, moving or fixed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkJoint {
    /// URDF joint name.
    pub name: String,
    /// Parent link.
    pub parent: String,
    /// Child link.
    pub child: String,
    /// Whether the joint is fixed (its child is merged into the parent's body).
    pub fixed: bool,
}

/// The cached model of an arm with its gripper (parsed on first use).
pub fn robot_model(robot: Robot) -> &'static RobotModel {
    static CACHE: [OnceLock<RobotModel>; 4] = [
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
    ];
    CACHE[robot.index()].get_or_init(|| {
        build_model(robot, urdf_text(robot), GRIPPER_URDF)
            .unwrap_or_else(|e| panic!("the shipped URDF of {robot:?} is invalid: {e}"))
    })
}

/// One URDF of the arm with its gripper mounted, as `robot_description` carries it for RViz
/// and Foxglove: the arm's file with the gripper's links and joints appended and joined by the
/// same fixed `gripper_mount` joint [`build_model`] adds.
pub fn robot_description(robot: Robot) -> String {
    let arm = urdf_text(robot);
    let arm_body = &arm[..arm
        .rfind("</robot>")
        .expect("the arm URDF ends with </robot>")];
    let open = GRIPPER_URDF
        .find("<robot")
        .expect("the gripper URDF has a <robot> element");
    let body_start = open + GRIPPER_URDF[open..].find('>').expect("<robot ...>") + 1;
    let body_end = GRIPPER_URDF
        .rfind("</robot>")
        .expect("the gripper URDF ends with </robot>");
    format!(
        "{arm_body}  <!-- the gripper (urdf/rethink_gripper.urdf) -->\n  <joint name=\"gripper_mount\" type=\"fixed\">\n    \
         <parent link=\"{GRIPPER_MOUNT_LINK}\"/>\n    <child link=\"{GRIPPER_ROOT_LINK}\"/>\n  </joint>{}</robot>\n",
        &GRIPPER_URDF[body_start..body_end]
    )
}

/// Parse an arm URDF and the gripper URDF and merge them into a [`RobotModel`].
pub fn build_model(
    robot: Robot,
    arm_urdf: &str,
    gripper_urdf: &str,
) -> Result<RobotModel, ModelError> {
    let mut arm =
        urdf_rs::read_from_string(arm_urdf).map_err(|e| ModelError(format!("arm URDF: {e}")))?;
    let mut gripper = urdf_rs::read_from_string(gripper_urdf)
        .map_err(|e| ModelError(format!("gripper URDF: {e}")))?;
    join_capsules(&mut arm)?;
    join_capsules(&mut gripper)?;
    let mut links: Vec<urdf_rs::Link> = arm.links.clone();
    links.extend(gripper.links.iter().cloned());
    let mut joints: Vec<urdf_rs::Joint> = arm.joints.clone();
    joints.extend(gripper.joints.iter().cloned());
    joints.push(urdf_rs::Joint {
        name: "gripper_mount".into(),
        joint_type: urdf_rs::JointType::Fixed,
        origin: urdf_rs::Pose::default(),
        parent: urdf_rs::LinkName {
            link: GRIPPER_MOUNT_LINK.into(),
        },
        child: urdf_rs::LinkName {
            link: GRIPPER_ROOT_LINK.into(),
        },
        axis: urdf_rs::Axis::default(),
        limit: urdf_rs::JointLimit::default(),
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    });
    merge(robot, &links, &joints)
}

fn merge(
    robot: Robot,
    links: &[urdf_rs::Link],
    joints: &[urdf_rs::Joint],
) -> Result<RobotModel, ModelError> {
    let mut by_name: HashMap<&str, &urdf_rs::Link> = HashMap::new();
    for link in links {
        if by_name.insert(&link.name, link).is_some() {
            return Err(ModelError(format!("link `{}` is defined twice", link.name)));
        }
    }
    let mut children: HashMap<&str, Vec<&urdf_rs::Joint>> = HashMap::new();
    let mut has_parent: HashMap<&str, &str> = HashMap::new();
    for joint in joints {
        for end in [&joint.parent.link, &joint.child.link] {
            if !by_name.contains_key(end.as_str()) {
                return Err(ModelError(format!(
                    "joint `{}` names unknown link `{end}`",
                    joint.name
                )));
            }
        }
        if let Some(previous) = has_parent.insert(&joint.child.link, &joint.name) {
            return Err(ModelError(format!(
                "link `{}` has two parent joints: `{previous}`, `{}`",
                joint.child.link, joint.name
            )));
        }
        children.entry(&joint.parent.link).or_default().push(joint);
    }
    let roots: Vec<&str> = links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !has_parent.contains_key(n))
        .collect();
    let [root] = roots.as_slice() else {
        return Err(ModelError(format!(
            "expected exactly one root link, found {roots:?}"
        )));
    };

    let mut model = RobotModel {
        robot,
        bodies: Vec::new(),
        joints: Vec::new(),
        links: HashMap::new(),
        tree: Vec::new(),
    };
    let mut accumulators: Vec<MassAccumulator> = Vec::new();
    // Depth-first from the root, parents before children, children in file order. A link
    // reached through a moving joint starts a new body, and that joint is recorded then, so
    // joints come out in body order.
    // (link, body it merges into, its pose in that body, the joint that starts its own body)
    type Visit<'a> = (&'a str, Option<usize>, Isometry3<f64>, Option<JointModel>);
    let mut stack: Vec<Visit> = vec![(root, None, Isometry3::identity(), None)];
    while let Some((name, merged_into, link_in_body, pending_joint)) = stack.pop() {
        let link = by_name[name];
        let body = if let Some(body) = merged_into {
            body
        } else {
            model.bodies.push(BodyModel {
                name: name.to_string(),
                mass: 0.0,
                com: Vector3::zeros(),
                inertia: Matrix3::zeros(),
                collisions: Vec::new(),
            });
            accumulators.push(MassAccumulator::default());
            let body = model.bodies.len() - 1;
            if let Some(joint) = pending_joint {
                model.joints.push(JointModel {
                    child: body,
                    ..joint
                });
            }
            body
        };
        model.links.insert(name.to_string(), (body, link_in_body));
        if link.inertial.mass.value > 0.0 {
            accumulators[body].add(&link.inertial, &link_in_body);
        }
        for (i, collision) in link.collision.iter().enumerate() {
            let shape = match &collision.geometry {
                urdf_rs::Geometry::Box { size } => {
                    Shape::Box(Vector3::new(size[0], size[1], size[2]) / 2.0)
                }
                urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
                    radius: *radius,
                    half_length: length / 2.0,
                },
                urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                    radius: *radius,
                    half_length: length / 2.0,
                },
                urdf_rs::Geometry::Sphere { radius } => Shape::Sphere(*radius),
                urdf_rs::Geometry::Mesh { filename, .. } => {
                    return Err(ModelError(format!(
                        "link `{name}`: meshes are not supported ({filename}); use primitives"
                    )));
                }
            };
            model.bodies[body].collisions.push(CollisionShape {
                name: collision
                    .name
                    .clone()
                    .unwrap_or_else(|| format!("{name}_collision{i}")),
                shape,
                pose: link_in_body * urdf_pose(&collision.origin),
            });
        }
        let own_joints = children.get(name).map(Vec::as_slice).unwrap_or_default();
        model.tree.extend(own_joints.iter().map(|joint| LinkJoint {
            name: joint.name.clone(),
            parent: name.to_string(),
            child: joint.child.link.clone(),
            fixed: joint.joint_type == urdf_rs::JointType::Fixed,
        }));
        // Push children in reverse so they pop in file order.
        for joint in children
            .get(name)
            .map(Vec::as_slice)
            .unwrap_or_default()
            .iter()
            .rev()
        {
            let origin = link_in_body * urdf_pose(&joint.origin);
            match joint.joint_type {
                urdf_rs::JointType::Fixed => {
                    stack.push((&joint.child.link, Some(body), origin, None))
                }
                urdf_rs::JointType::Revolute
                | urdf_rs::JointType::Continuous
                | urdf_rs::JointType::Prismatic => {
                    let axis =
                        Vector3::new(joint.axis.xyz[0], joint.axis.xyz[1], joint.axis.xyz[2]);
                    let norm = axis.norm();
                    if norm < 1e-9 {
                        return Err(ModelError(format!(
                            "joint `{}` has a zero axis",
                            joint.name
                        )));
                    }
                    let limits = match joint.joint_type {
                        urdf_rs::JointType::Continuous => None,
                        _ if joint.limit.lower < joint.limit.upper => {
                            Some((joint.limit.lower, joint.limit.upper))
                        }
                        _ => {
                            return Err(ModelError(format!(
                                "joint `{}`: lower limit {} is not below upper limit {}",
                                joint.name, joint.limit.lower, joint.limit.upper
                            )));
                        }
                    };
                    if joint.limit.effort <= 0.0 {
                        return Err(ModelError(format!(
                            "joint `{}` needs a positive effort limit",
                            joint.name
                        )));
                    }
                    let pending = JointModel {
                        name: joint.name.clone(),
                        kind: if joint.joint_type == urdf_rs::JointType::Prismatic {
                            JointKind::Prismatic
                        } else {
                            JointKind::Revolute
                        },
                        parent: body,
                        child: usize::MAX, // the child body is created when the link is visited
                        origin,
                        axis: axis / norm,
                        limits,
                        effort: joint.limit.effort,
                        velocity: joint.limit.velocity,
                    };
                    stack.push((
                        &joint.child.link,
                        None,
                        Isometry3::identity(),
                        Some(pending),
                    ));
                }
                ref other => {
                    return Err(ModelError(format!(
                        "joint `{}`: type {other:?} is not supported",
                        joint.name
                    )));
                }
            }
        }
    }
    for (body, acc) in model.bodies.iter_mut().zip(&accumulators) {
        (body.mass, body.com, body.inertia) = acc.finish();
    }
    if model.bodies.len() > MAX_BODIES {
        return Err(ModelError(format!(
            "{} rigid bodies after merging fixed links; at most {MAX_BODIES} are supported",
            model.bodies.len()
        )));
    }
    Ok(model)
}

/// Sums inertials given in different frames into one about the combined centre of mass.
#[derive(Default)]
struct MassAccumulator {
    parts: Vec<(f64, Vector3<f64>, Matrix3<f64>)>,
}

impl MassAccumulator {
    fn add(&mut self, inertial: &urdf_rs::Inertial, link_in_body: &Isometry3<f64>) {
        let origin = link_in_body * urdf_pose(&inertial.origin);
        let i = &inertial.inertia;
        let local = Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        );
        let r = origin.rotation.to_rotation_matrix();
        let rotated = r.matrix() * local * r.matrix().transpose();
        self.parts
            .push((inertial.mass.value, origin.translation.vector, rotated));
    }

    fn finish(&self) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let mass: f64 = self.parts.iter().map(|p| p.0).sum();
        if mass <= 0.0 {
            return (0.0, Vector3::zeros(), Matrix3::zeros());
        }
        let com = self.parts.iter().map(|p| p.1 * p.0).sum::<Vector3<f64>>() / mass;
        // Parallel-axis theorem: I_com = Σ (I_i + m_i (|d|² E − d dᵀ)).
        let inertia = self
            .parts
            .iter()
            .fold(Matrix3::zeros(), |acc, (m, c, inertia)| {
                let d = c - com;
                acc + inertia + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * *m
            });
        (mass, com, inertia)
    }
}

#[cfg(test)]
mod description_tests {
    use super::*;

    #[test]
    fn robot_description_is_one_urdf_with_arm_and_gripper() {
        for robot in Robot::all() {
            let text = robot_description(robot);
            let urdf = urdf_rs::read_from_string(&text).expect("robot_description parses");
            let moving: Vec<&str> = urdf
                .joints
                .iter()
                .filter(|j| !matches!(j.joint_type, urdf_rs::JointType::Fixed))
                .map(|j| j.name.as_str())
                .collect();
            let model = robot_model(robot);
            let expected: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
            assert_eq!(moving, expected, "{robot:?}");
            assert!(urdf.links.iter().any(|l| l.name == GRIPPER_ROOT_LINK));
        }
    }

    /// The link tree holds every joint of `robot_description`, each link but the root once as a
    /// child, and a parent before its children.
    #[test]
    fn the_link_tree_is_robot_descriptions_joints_parents_first() {
        for robot in Robot::all() {
            let urdf = urdf_rs::read_from_string(&robot_description(robot)).unwrap();
            let model = robot_model(robot);
            let mut ours: Vec<(&str, &str, &str, bool)> = model
                .tree
                .iter()
                .map(|j| {
                    (
                        j.name.as_str(),
                        j.parent.as_str(),
                        j.child.as_str(),
                        j.fixed,
                    )
                })
                .collect();
            let mut theirs: Vec<(&str, &str, &str, bool)> = urdf
                .joints
                .iter()
                .map(|j| {
                    let fixed = matches!(j.joint_type, urdf_rs::JointType::Fixed);
                    (
                        j.name.as_str(),
                        j.parent.link.as_str(),
                        j.child.link.as_str(),
                        fixed,
                    )
                })
                .collect();
            let root = &model.bodies[0].name;
            let mut reached = vec![root.as_str()];
            for j in &model.tree {
                assert!(reached.contains(&j.parent.as_str()), "{robot:?}: {j:?}");
                assert!(!reached.contains(&j.child.as_str()), "{robot:?}: {j:?}");
                reached.push(&j.child);
            }
            assert_eq!(reached.len(), urdf.links.len(), "{robot:?}");
            ours.sort();
            theirs.sort();
            assert_eq!(ours, theirs, "{robot:?}");
        }
    }
}
