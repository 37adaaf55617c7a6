//! The entities of a task's scene, as `simulation_interfaces` sees a scene: the arm (`robot`,
//! category ROBOT), the object (`object`, DYNAMIC_OBJECT) and the arena's rigid parts (`bin1`,
//! `bin2`, the objective's fixture `trash_can` or `shelf`, and `obstacle`: STATIC_OBJECT). Every
//! entity is tagged with its axis and its axis element (`robot` + `IIWA`, `object` + `box`,
//! `obstacle` + `object_wall`, `objective` + `pick_place` for the bins and the fixture), so
//! tag filters select by task element. Geometry comes from the core's arena tables; poses of
//! the moving entities from the running [`Env`].

use composuite_core::TaskSpec;
use composuite_core::arena::{
    BIN1_POSITION, Part, Placed, object_geometry, objective_arena, obstacle_geometry,
    robot_base_pose,
};
use composuite_core::axes::{AxisElement, Obstacle};
use composuite_core::env::Env;
use composuite_msgs::simulation_interfaces::msg::EntityCategory;
use nalgebra::{Isometry3, Point3, Translation3, Vector3};

/// The arm's entity name.
pub const ROBOT: &str = "robot";
/// The object's entity name.
pub const OBJECT: &str = "object";

/// What an entity is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The arm: its base is fixed in the world; its links move with its joints.
    Robot,
    /// The object: a free body.
    Object,
    /// A rigid arena part that never moves.
    Static,
}

/// One entity of a task's scene.
#[derive(Debug, Clone)]
pub struct Entity {
    /// Unique name in the scene.
    pub name: &'static str,
    /// Robot, object or static part.
    pub kind: Kind,
    /// For people.
    pub description: String,
    /// The axis and the axis element it belongs to.
    pub tags: Vec<String>,
    /// The body's pose in the world when it cannot move (`None` for the object).
    fixed_pose: Option<Isometry3<f64>>,
    /// Its solids in its body frame (empty for the arm).
    parts: Vec<Placed>,
}

impl Entity {
    /// The `EntityCategory` value.
    pub fn category(&self) -> u8 {
        match self.kind {
            Kind::Robot => EntityCategory::CATEGORY_ROBOT,
            Kind::Object => EntityCategory::CATEGORY_DYNAMIC_OBJECT,
            Kind::Static => EntityCategory::CATEGORY_STATIC_OBJECT,
        }
    }

    /// Pose (world), linear (m/s) and angular (rad/s) velocity (world) now.
    pub fn motion(&self, env: &Env) -> (Isometry3<f64>, Vector3<f64>, Vector3<f64>) {
        match self.fixed_pose {
            Some(pose) => (pose, Vector3::zeros(), Vector3::zeros()),
            None => {
                let w = env.world_state();
                (
                    w.object_pose,
                    w.object_linear_velocity,
                    w.object_angular_velocity,
                )
            }
        }
    }

    /// The axis-aligned box (min, max corner) around its solids in its own body frame, or
    /// `None` for the arm, whose extent changes with its joints.
    pub fn bounds(&self) -> Option<(Point3<f64>, Point3<f64>)> {
        self.parts
            .iter()
            .map(Placed::aabb)
            .reduce(|(lo, hi), (l, h)| {
                (
                    Point3::from(lo.coords.inf(&l.coords)),
                    Point3::from(hi.coords.sup(&h.coords)),
                )
            })
    }
}

/// A body's parts in its own frame.
fn in_body_frame(parts: &[Part]) -> Vec<Placed> {
    parts
        .iter()
        .map(|p| Placed {
            name: p.name,
            shape: p.shape,
            pose: Isometry3::from_parts(
                Translation3::from(Vector3::from(p.offset)),
                Default::default(),
            ),
            collides: p.collides,
            friction: p.friction,
        })
        .collect()
}

fn at(position: [f64; 3]) -> Isometry3<f64> {
    Isometry3::translation(position[0], position[1], position[2])
}

fn tags<E: AxisElement>(element: E) -> Vec<String> {
    vec![E::AXIS.name().to_string(), element.wire_name().to_string()]
}

/// Every entity of `task`'s scene, in a fixed order: robot, object, bin1, bin2, the fixture
/// (trash_can, shelf) if the objective has one, the obstacle if there is one.
pub fn entities(task: TaskSpec) -> Vec<Entity> {
    let arena = objective_arena(task.objective);
    let objective = task.objective.wire_name();
    let mut list = vec![
        Entity {
            name: ROBOT,
            kind: Kind::Robot,
            description: format!(
                "the {} arm with its two-finger gripper; its base is fixed, its joints move it",
                task.robot.wire_name()
            ),
            tags: tags(task.robot),
            fixed_pose: Some(robot_base_pose()),
            parts: Vec::new(),
        },
        Entity {
            name: OBJECT,
            kind: Kind::Object,
            description: format!(
                "the {} to {objective}; set_entity_state teleports it",
                task.object.wire_name()
            ),
            tags: tags(task.object),
            fixed_pose: None,
            parts: in_body_frame(object_geometry(task.object).parts),
        },
        Entity {
            name: "bin1",
            kind: Kind::Static,
            description: "bin 1, where the object starts".into(),
            tags: tags(task.objective),
            fixed_pose: Some(at(BIN1_POSITION)),
            parts: in_body_frame(arena.bin1_parts),
        },
        Entity {
            name: "bin2",
            kind: Kind::Static,
            description: "bin 2, beside bin 1".into(),
            tags: tags(task.objective),
            fixed_pose: Some(at(arena.bin2_position)),
            parts: in_body_frame(arena.bin2_parts),
        },
    ];
    if let Some(first) = arena.fixture_parts.first() {
        // The fixture's parts are named `trash_can/...` or `shelf/...`.
        let name = first.name.split('/').next().unwrap_or(first.name);
        list.push(Entity {
            name,
            kind: Kind::Static,
            description: format!("the {objective} objective's {name}, the goal's place"),
            tags: tags(task.objective),
            fixed_pose: Some(at(arena.fixture_position)),
            parts: in_body_frame(arena.fixture_parts),
        });
    }
    if task.obstacle != Obstacle::NoObstacle {
        let geometry = obstacle_geometry(task.obstacle);
        list.push(Entity {
            name: "obstacle",
            kind: Kind::Static,
            description: format!("the {} obstacle", task.obstacle.wire_name()),
            tags: tags(task.obstacle),
            fixed_pose: Some(geometry.body_pose()),
            parts: in_body_frame(geometry.parts),
        });
    }
    list
}

/// The entity named `name`, or an error naming the valid ones.
pub fn find(list: &[Entity], name: &str) -> Result<usize, String> {
    list.iter().position(|e| e.name == name).ok_or_else(|| {
        format!(
            "no entity `{name}` in this scene; its entities are: {}",
            list.iter().map(|e| e.name).collect::<Vec<_>>().join(", ")
        )
    })
}
