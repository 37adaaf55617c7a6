//! The scene as triangle meshes, built once per task from the tables the physics is built
//! from, and posed each frame from the simulated world.
//!
//! Static solids come from [`arena_parts`] (what `SimWorld::add_arena` turns into colliders)
//! and the goal marker from [`goal_marker_parts`]; the object from [`object_parts`] (what
//! `SimWorld::add_object` collides with), posed by the object body; the arm and gripper from
//! the `<visual>` elements of their URDFs (the files the physics reads its collision shapes
//! and joints from), each posed by the rigid body its link belongs to. Nothing here knows a
//! size.

use nalgebra::{Isometry3, Point3, Vector3};

use super::camera::{Camera, Mount, RenderError, camera_spec};
use super::mesh::Mesh;
use super::raster::{Frame, Paint, SceneClass, View, draw_triangle};
use crate::TaskSpec;
use crate::arena::{
    GROUND_HALF_SIZE, Placed, Primitive, arena_parts, goal_marker_parts, object_parts,
};
use crate::physics::{RobotModel, SimWorld, from_pose, robot_description, urdf_pose};

/// What carries a solid, and so gives its pose each frame.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Carrier {
    /// Fixed in the world (mesh in world coordinates).
    World,
    /// A rigid body of the arm (index into the model's bodies).
    ArmBody(usize),
    /// The manipulated object's body.
    Object,
}

#[derive(Debug, Clone)]
struct Solid {
    /// Vertices in the carrier's frame.
    mesh: Mesh,
    carrier: Carrier,
    paint: Paint,
}

/// Colours (0–1 RGB) of the arena and the object, by part name prefix. The wood tones follow
/// the reference's materials (light wood for bin 1, dark wood for bin 2 and the shelf); the
/// rest are picked to stand apart.
const PART_COLOURS: [(&str, [f32; 3]); 6] = [
    ("bin1/", [0.80, 0.66, 0.46]),
    ("bin2/", [0.45, 0.30, 0.18]),
    ("shelf/", [0.45, 0.30, 0.18]),
    ("trash_can/", [0.35, 0.45, 0.40]),
    ("obstacle/", [0.55, 0.60, 0.70]),
    ("object/", [0.85, 0.15, 0.12]),
];
/// The ground's colour.
const GROUND_COLOUR: [f32; 3] = [0.55, 0.53, 0.50];
/// The goal marker: the reference's rgba (0.8, 0.8, 0.8, 0.3).
const GOAL_COLOUR: [f32; 3] = [0.8, 0.8, 0.8];
const GOAL_ALPHA: f32 = 0.3;
/// A visual whose URDF material gives no colour.
const UNPAINTED: [f32; 3] = [0.62, 0.63, 0.65];
/// Toward the key light (world): the reference's two lights shine along (0, −0.15, −1).
const TOWARD_LIGHT: [f64; 3] = [0.0, 0.15, 1.0];

/// Draws one task's scene; build it once, render many frames.
#[derive(Debug, Clone)]
pub struct SceneRenderer {
    /// Opaque solids first, see-through ones last (they blend over what is drawn).
    solids: Vec<Solid>,
    /// Scratch: one solid's vertices in the optical frame.
    posed: Vec<Point3<f32>>,
}

impl SceneRenderer {
    /// The meshes of `task`'s scene with `model`'s arm.
    pub fn new(task: TaskSpec, model: &RobotModel) -> SceneRenderer {
        let mut solids = vec![Solid {
            mesh: Mesh::floor(GROUND_HALF_SIZE[0], GROUND_HALF_SIZE[1]),
            carrier: Carrier::World,
            paint: Paint {
                colour: GROUND_COLOUR,
                class: SceneClass::Ground,
                alpha: None,
            },
        }];
        let opaque = |class| {
            move |colour| Paint {
                colour,
                class,
                alpha: None,
            }
        };
        solids.extend(placed_solids(
            &arena_parts(task.objective, task.obstacle),
            Carrier::World,
            opaque(SceneClass::Arena),
        ));
        solids.extend(placed_solids(
            &object_parts(task.object),
            Carrier::Object,
            opaque(SceneClass::Object),
        ));
        solids.extend(
            arm_visuals(model)
                .into_iter()
                .map(|(body, mesh, colour)| Solid {
                    mesh,
                    carrier: Carrier::ArmBody(body),
                    paint: opaque(SceneClass::Robot)(colour),
                }),
        );
        // Last, so it tints what is behind it; see-through solids write no class or depth.
        let goal = goal_marker_parts(task.objective, task.object);
        solids.extend(placed_solids(&goal, Carrier::World, |_| Paint {
            colour: GOAL_COLOUR,
            class: SceneClass::Background,
            alpha: Some(GOAL_ALPHA),
        }));
        SceneRenderer {
            solids,
            posed: Vec::new(),
        }
    }

    /// How many triangles a frame draws (before culling).
    pub fn triangle_count(&self) -> usize {
        self.solids.iter().map(|s| s.mesh.triangles.len()).sum()
    }

    /// The scene in `world` as `camera` sees it.
    pub fn render(&mut self, world: &SimWorld, camera: &Camera, width: u32, height: u32) -> Frame {
        let arm_body =
            |body: usize| from_pose(world.physics.bodies[world.arm.bodies[body]].position());
        self.render_posed(arm_body, world.object_pose(), camera, width, height)
    }

    /// The scene with the arm's bodies at `arm_body(i)` (world poses, in the model's body
    /// order) and the object at `object_pose`, as `camera` sees it: what [`render`](Self::render)
    /// draws from the physics, and [`StateRenderer`](super::StateRenderer) from joint positions.
    pub(crate) fn render_posed(
        &mut self,
        arm_body: impl Fn(usize) -> Isometry3<f64>,
        object_pose: Option<Isometry3<f64>>,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Frame {
        let mut frame = Frame::new(width, height);
        // The depth buffer holds 1/z while drawing; 0 is "nothing yet".
        frame.depth.fill(0.0);
        let to_optical = camera.pose.inverse();
        let view = View {
            light: (to_optical.rotation * Vector3::from(TOWARD_LIGHT).normalize()).cast(),
            focal: camera.focal_px(height) as f32,
            centre: (width as f32 / 2.0, height as f32 / 2.0),
        };
        for solid in &self.solids {
            let carrier_pose = match solid.carrier {
                Carrier::World => Isometry3::identity(),
                Carrier::ArmBody(body) => arm_body(body),
                Carrier::Object => match object_pose {
                    Some(pose) => pose,
                    None => continue,
                },
            };
            let pose: Isometry3<f32> = (to_optical * carrier_pose).cast();
            self.posed.clear();
            self.posed
                .extend(solid.mesh.vertices.iter().map(|v| pose * v));
            for triangle in &solid.mesh.triangles {
                let corners = triangle.map(|i| self.posed[i as usize]);
                draw_triangle(&mut frame, &view, corners, &solid.paint);
            }
        }
        for d in &mut frame.depth {
            *d = if *d > 0.0 { 1.0 / *d } else { f32::INFINITY };
        }
        frame
    }
}

/// The camera called `name` where it is in `world` now.
pub fn posed_camera(world: &SimWorld, name: &str) -> Result<Camera, RenderError> {
    posed_camera_with(name, |link| {
        world
            .link_world_pose(link)
            .unwrap_or_else(|| panic!("every arm model has the link `{link}`"))
    })
}

/// The camera called `name`, its mount link (if any) at `link_pose(link)` in the world.
pub(crate) fn posed_camera_with(
    name: &str,
    link_pose: impl Fn(&str) -> Isometry3<f64>,
) -> Result<Camera, RenderError> {
    let spec = camera_spec(name)?;
    let mount = match spec.mount {
        Mount::World => Isometry3::identity(),
        Mount::Link(link) => link_pose(link),
    };
    Ok(Camera {
        pose: mount * spec.optical_in_mount(),
        fovy_deg: spec.fovy_deg,
    })
}

/// One solid per placed primitive, coloured by `paint(colour of its name)`.
fn placed_solids(
    parts: &[Placed],
    carrier: Carrier,
    paint: impl Fn([f32; 3]) -> Paint,
) -> Vec<Solid> {
    parts
        .iter()
        .map(|part| Solid {
            mesh: primitive_mesh(&part.shape).transformed(&part.pose),
            carrier,
            paint: paint(part_colour(part.name)),
        })
        .collect()
}

fn part_colour(name: &str) -> [f32; 3] {
    PART_COLOURS
        .iter()
        .find(|(prefix, _)| name.starts_with(prefix))
        .map_or(UNPAINTED, |(_, colour)| *colour)
}

fn primitive_mesh(shape: &Primitive) -> Mesh {
    match *shape {
        Primitive::Box { half_extents } => Mesh::cuboid(half_extents),
        Primitive::Cylinder {
            radius,
            half_length,
        } => Mesh::cylinder(radius, half_length),
    }
}

/// The arm's and gripper's `<visual>` primitives from its URDF (`robot_description`, the text
/// viewers get), each as (rigid body, mesh in the body's frame, colour).
fn arm_visuals(model: &RobotModel) -> Vec<(usize, Mesh, [f32; 3])> {
    let urdf = urdf_rs::read_from_string(&robot_description(model.robot))
        .expect("the shipped URDFs parse (the physics read them)");
    let named_colour = |name: &str| {
        urdf.materials
            .iter()
            .find(|m| m.name == name)
            .and_then(|m| m.color.as_ref())
    };
    let mut visuals = Vec::new();
    for link in &urdf.links {
        let (body, link_in_body) = model.links[&link.name];
        for visual in &link.visual {
            let colour = visual
                .material
                .as_ref()
                .and_then(|m| m.color.as_ref().or_else(|| named_colour(&m.name)));
            let colour = colour.map_or(UNPAINTED, |c| {
                [c.rgba[0], c.rgba[1], c.rgba[2]].map(|v| v as f32)
            });
            let mesh = visual_mesh(&visual.geometry).unwrap_or_else(|| {
                panic!(
                    "link `{}`: visuals are primitives (box, cylinder, sphere)",
                    link.name
                )
            });
            visuals.push((
                body,
                mesh.transformed(&(link_in_body * urdf_pose(&visual.origin))),
                colour,
            ));
        }
    }
    visuals
}

fn visual_mesh(geometry: &urdf_rs::Geometry) -> Option<Mesh> {
    Some(match *geometry {
        urdf_rs::Geometry::Box { ref size } => {
            Mesh::cuboid(Vector3::new(size[0], size[1], size[2]) / 2.0)
        }
        urdf_rs::Geometry::Cylinder { radius, length } => Mesh::cylinder(radius, length / 2.0),
        urdf_rs::Geometry::Sphere { radius } => Mesh::sphere(radius),
        urdf_rs::Geometry::Capsule { radius, length } => Mesh::capsule(radius, length / 2.0),
        urdf_rs::Geometry::Mesh { .. } => return None,
    })
}
