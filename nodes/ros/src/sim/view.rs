//! What RViz and Foxglove need to draw a run with nothing else running: every URDF link as a
//! `tf` frame (what robot_state_publisher would publish from `robot_description` and
//! `joint_states`; a pip-only Jazzy has no robot_state_publisher) and the scene as
//! `visualization_msgs/MarkerArray`s (the arena latched on `scene_markers`, the object on
//! `object_markers` at every step).
//!
//! Geometry comes from the one source the rest of the suite uses: the arena parts of the
//! `scene` message (composed by the core's arena tables) and the core's object table.

use composuite_core::arena::{Placed, object_parts};
use composuite_core::axes::Object;
use composuite_core::physics::SimWorld;
use composuite_msgs::builtin_interfaces::msg::Time;
use composuite_msgs::geometry_msgs::msg::{TransformStamped, Vector3};
use composuite_msgs::msg;
use composuite_msgs::std_msgs::msg::{ColorRGBA, Header};
use composuite_msgs::visualization_msgs::msg::{Marker, MarkerArray};
use nalgebra::Isometry3;

use crate::shared::convert;
use crate::shared::names::WORLD_FRAME;

/// The part-name prefix (`object/...`) of the object's primitives in a scene.
pub const OBJECT_GROUP: &str = "object";

/// One `tf` transform of the URDF tree: `child`'s frame in `parent`'s.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkTransform {
    /// Parent link.
    pub parent: &'static str,
    /// Child link.
    pub child: &'static str,
    /// Pose of the child link frame in the parent link frame.
    pub transform: Isometry3<f64>,
}

/// Every joint of the arm's URDF (fixed ones included) as parent → child transforms, taken from
/// the simulated link poses: composing them from the root (placed in the world by `tf_static`)
/// gives each link exactly where the physics has it, so the frames agree with `world_state`'s
/// eef pose and the object marker to rounding. (robot_state_publisher would compute them from
/// `joint_states` by forward kinematics; the two agree within the physics' f32 precision, ~1e-6
/// m.) A fixed joint's transform is its URDF origin exactly: both links sit in one rigid body.
pub fn link_transforms(world: &SimWorld) -> Vec<LinkTransform> {
    let model = world.model;
    let pose = |link: &str| {
        world
            .link_world_pose(link)
            .expect("every link of the tree is a link of the model")
    };
    model
        .tree
        .iter()
        .map(|joint| {
            let (parent_body, parent_in_body) = model.links[&joint.parent];
            let (child_body, child_in_body) = model.links[&joint.child];
            let transform = if parent_body == child_body {
                parent_in_body.inverse() * child_in_body
            } else {
                pose(&joint.parent).inverse() * pose(&joint.child)
            };
            LinkTransform {
                parent: &joint.parent,
                child: &joint.child,
                transform,
            }
        })
        .collect()
}

/// A `tf` transform of `child` in `parent` at `stamp`.
pub fn transform_stamped(
    parent: &str,
    child: &str,
    transform: &Isometry3<f64>,
    stamp: Time,
) -> TransformStamped {
    convert::transform_in(parent, child, &convert::pose(transform), stamp)
}

/// The colour a part is drawn in, by its group (the name before `/`).
fn color(group: &str) -> ColorRGBA {
    let (r, g, b, a) = match group {
        "bin1" | "bin2" => (0.55, 0.42, 0.28, 1.0),
        "shelf" => (0.72, 0.58, 0.38, 1.0),
        "trash_can" => (0.32, 0.36, 0.40, 1.0),
        "obstacle" => (0.55, 0.55, 0.60, 1.0),
        // Visual only, as in the reference: see-through so the object inside stays visible.
        "goal" => (0.10, 0.80, 0.25, 0.4),
        OBJECT_GROUP => (0.85, 0.18, 0.12, 1.0),
        _ => (0.6, 0.6, 0.6, 1.0),
    };
    ColorRGBA { r, g, b, a }
}

/// The group of a part name: `bin1` of `bin1/floor`.
pub fn group(name: &str) -> &str {
    name.split('/').next().unwrap_or(name)
}

/// A marker in the world frame at `stamp`, every other field at its ROS default (lifetime 0:
/// until replaced or deleted; not frame-locked; no texture, mesh or text).
fn blank(stamp: Time) -> Marker {
    Marker {
        header: Header {
            stamp,
            frame_id: WORLD_FRAME.into(),
        },
        ..Marker::default()
    }
}

/// A DELETEALL marker: everything this topic drew before goes.
fn delete_all(stamp: Time) -> Marker {
    Marker {
        action: Marker::DELETEALL,
        ..blank(stamp)
    }
}

/// One scene part as a CUBE or CYLINDER marker in the world frame, in namespace `group(name)`
/// with `id`. Sizes are full extents: a box's half-sizes doubled; a cylinder's diameter in x and
/// y, its length along its local z.
pub fn part_marker(part: &msg::ScenePart, id: i32, stamp: Time) -> Marker {
    let h = &part.half_size;
    let (kind, scale) = if part.shape == msg::ScenePart::SHAPE_CYLINDER {
        (Marker::CYLINDER, [2.0 * h.x, 2.0 * h.x, 2.0 * h.z])
    } else {
        (Marker::CUBE, [2.0 * h.x, 2.0 * h.y, 2.0 * h.z])
    };
    let group = group(&part.name);
    Marker {
        ns: group.into(),
        id,
        r#type: kind,
        pose: part.pose.clone(),
        scale: Vector3 {
            x: scale[0],
            y: scale[1],
            z: scale[2],
        },
        color: color(group),
        ..blank(stamp)
    }
}

/// The arena of `scene` (bins, obstacle, trash can or shelf, goal marker: every part but the
/// object's), after a DELETEALL so the parts of a previous task vanish. Marker ids are the parts'
/// indices in `scene.parts`.
pub fn arena_markers(scene: &msg::Scene, stamp: Time) -> MarkerArray {
    let mut markers = vec![delete_all(stamp.clone())];
    markers.extend(
        scene
            .parts
            .iter()
            .enumerate()
            .filter(|(_, part)| group(&part.name) != OBJECT_GROUP)
            .map(|(index, part)| part_marker(part, index as i32, stamp.clone())),
    );
    MarkerArray { markers }
}

/// The object's primitives placed at `object_pose` (its body origin in the world), one marker
/// each in namespace `object` with ids 0, 1, ...; `clear` puts a DELETEALL first (the first
/// message of an episode, so a previous object's extra parts vanish).
pub fn object_markers(
    object: Object,
    object_pose: &Isometry3<f64>,
    stamp: Time,
    clear: bool,
) -> MarkerArray {
    let mut markers = Vec::new();
    if clear {
        markers.push(delete_all(stamp.clone()));
    }
    markers.extend(object_parts(object).iter().enumerate().map(|(id, part)| {
        let placed = Placed {
            pose: object_pose * part.pose,
            ..*part
        };
        part_marker(&convert::scene_part(&placed), id as i32, stamp.clone())
    }));
    MarkerArray { markers }
}

#[cfg(test)]
mod test {
    use super::*;
    use composuite_core::TaskSpec;
    use composuite_core::axes::{AxisElement, Robot};
    use composuite_core::env::{Action, Env, EnvConfig};
    use composuite_core::physics::robot_model;
    use std::collections::HashMap;

    /// Composing the published transforms from the root (at the robot base, as `tf_static`
    /// places it) gives every link where the core has it, on every arm, after the arm moved.
    #[test]
    fn link_transforms_compose_to_the_cores_link_poses() {
        for robot in Robot::all() {
            let task: TaskSpec = format!("{}/box/no_obstacle/pick_place", robot.wire_name())
                .parse()
                .unwrap();
            let mut env = Env::new(task, EnvConfig::default());
            env.reset(3).unwrap();
            for k in 0..5 {
                let a = [
                    0.6,
                    -0.4,
                    0.5,
                    0.7,
                    -0.5,
                    0.4,
                    if k % 2 == 0 { 1.0 } else { -1.0 },
                    1.0,
                ];
                env.step(&Action::Reference(a)).unwrap();
            }
            let world = env.world();
            let model = robot_model(robot);
            let root = model.bodies[0].name.as_str();
            let transforms = link_transforms(world);
            assert_eq!(transforms.len(), model.links.len() - 1, "{robot:?}");
            let mut composed: HashMap<&str, Isometry3<f64>> = HashMap::new();
            composed.insert(root, world.link_world_pose(root).unwrap());
            for t in &transforms {
                let parent = composed[t.parent];
                composed.insert(t.child, parent * t.transform);
            }
            for (link, pose) in &composed {
                let core = world.link_world_pose(link).unwrap();
                let dp = (pose.translation.vector - core.translation.vector).norm();
                let dr = pose.rotation.angle_to(&core.rotation);
                assert!(dp < 1e-9 && dr < 1e-6, "{robot:?} {link}: {dp} m, {dr} rad");
            }
            assert_eq!(composed.len(), model.links.len(), "{robot:?}: every link");
            let grip = composed["grip_site"].translation.vector;
            assert!((grip - world.grip_site_pose().translation.vector).norm() < 1e-9);
        }
    }

    #[test]
    fn markers_carry_the_parts_sizes_and_poses() {
        let part = msg::ScenePart {
            name: "trash_can/wall_x+".into(),
            shape: msg::ScenePart::SHAPE_CYLINDER,
            half_size: Vector3 {
                x: 0.1,
                y: 0.0,
                z: 0.3,
            },
            pose: convert::pose(&Isometry3::translation(1.0, 2.0, 3.0)),
            collides: true,
        };
        let m = part_marker(&part, 7, convert::time_from_nanos(5));
        assert_eq!(
            (m.ns.as_str(), m.id, m.r#type),
            ("trash_can", 7, Marker::CYLINDER)
        );
        assert_eq!((m.scale.x, m.scale.y, m.scale.z), (0.2, 0.2, 0.6));
        assert_eq!(m.pose, part.pose);
        assert_eq!(m.header.frame_id, "world");
    }

    #[test]
    fn the_arena_starts_with_deleteall_and_leaves_the_object_out() {
        let task: TaskSpec = "Jaco/dumbbell/object_door/shelf".parse().unwrap();
        let mut env = Env::new(task, EnvConfig::default());
        env.reset(0).unwrap();
        let layout = env.layout();
        let scene = convert::scene(&layout, env.config(), 1, convert::time_from_nanos(0));
        let arena = arena_markers(&scene, convert::time_from_nanos(0));
        assert_eq!(arena.markers[0].action, Marker::DELETEALL);
        let objects = scene
            .parts
            .iter()
            .filter(|p| p.name.starts_with("object/"))
            .count();
        assert!(objects > 0);
        assert_eq!(arena.markers.len(), 1 + scene.parts.len() - objects);
        for m in &arena.markers[1..] {
            let part = &scene.parts[m.id as usize];
            assert_eq!(m.ns, group(&part.name));
            assert_eq!(m.pose, part.pose);
        }
        assert!(arena.markers.iter().any(|m| m.ns == "shelf"));
        assert!(arena.markers.iter().any(|m| m.ns == "goal"));
        // At the episode start the object's markers are the scene's object parts.
        let start = env.world().object_pose().unwrap();
        let object = object_markers(task.object, &start, convert::time_from_nanos(0), true);
        assert_eq!(object.markers[0].action, Marker::DELETEALL);
        let scene_object: Vec<_> = scene
            .parts
            .iter()
            .filter(|p| p.name.starts_with("object/"))
            .collect();
        assert_eq!(object.markers.len(), 1 + scene_object.len());
        for (m, part) in object.markers[1..].iter().zip(scene_object) {
            let d = (m.pose.position.x - part.pose.position.x).abs()
                + (m.pose.position.y - part.pose.position.y).abs()
                + (m.pose.position.z - part.pose.position.z).abs();
            assert!(d < 1e-6, "{}: {d}", part.name);
        }
    }
}
