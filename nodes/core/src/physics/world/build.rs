//! Building the world: the ground, the arm (bodies, colliders, multibody joints, the floor
//! filter), the arena's static parts, and a fresh copy of an unstepped world.

use nalgebra::Isometry3;
use rapier3d::prelude::*;

use super::convert::{to_pose, to_vec};
use super::gripper::{FINGER_OPEN, GripperCommand};
use super::servos::ServoMode;
use super::{ArmHandles, SimWorld};
use crate::arena::{Placed, Primitive, merged_solids, robot_base_pose};
use crate::axes::Robot;
use crate::physics::params::{ArmGains, GripperParams, PhysicsParams};
use crate::physics::robot_model::{
    ARM_DOF, CollisionShape, FINGER_JOINTS, GRIP_SITE_LINK, HAND_LINK, JointKind, RobotModel,
    Shape, robot_model,
};
use crate::physics::tags::{ColliderTag, Side};
use crate::physics::torsion::TorsionalFriction;

/// A rapier shape and its pose for an arena primitive (cylinders along the pose's z axis).
pub(super) fn primitive_shape(shape: &Primitive, pose: &Isometry3<f64>) -> (SharedShape, Pose) {
    match *shape {
        Primitive::Box { half_extents: h } => (
            SharedShape::cuboid(h.x as Real, h.y as Real, h.z as Real),
            to_pose(pose),
        ),
        // Parry's cylinders run along y.
        Primitive::Cylinder {
            radius,
            half_length,
        } => (
            SharedShape::cylinder(half_length as Real, radius as Real),
            to_pose(pose) * Pose::rotation(Vector::X * std::f32::consts::FRAC_PI_2),
        ),
    }
}

fn shape_of(c: &CollisionShape) -> (SharedShape, Pose) {
    let pose = to_pose(&c.pose);
    match c.shape {
        Shape::Box(h) => (
            SharedShape::cuboid(h.x as Real, h.y as Real, h.z as Real),
            pose,
        ),
        Shape::Capsule {
            radius,
            half_length,
        } => (
            SharedShape::capsule_z(half_length as Real, radius as Real),
            pose,
        ),
        // Parry's cylinders run along y; URDF's along z.
        Shape::Cylinder {
            radius,
            half_length,
        } => (
            SharedShape::cylinder(half_length as Real, radius as Real),
            pose * Pose::rotation(Vector::X * std::f32::consts::FRAC_PI_2),
        ),
        Shape::Sphere(r) => (SharedShape::ball(r as Real), pose),
    }
}

fn tag_for(collision_name: &str, body: usize) -> ColliderTag {
    match collision_name {
        "l_fingerpad" => ColliderTag::Pad(Side::Left),
        "r_fingerpad" => ColliderTag::Pad(Side::Right),
        n if n.starts_with("l_finger") => ColliderTag::Finger(Side::Left),
        n if n.starts_with("r_finger") => ColliderTag::Finger(Side::Right),
        "gripper_base" => ColliderTag::GripperBase,
        _ => ColliderTag::Arm(body as u32),
    }
}

impl SimWorld {
    /// A world with `robot` on its pedestal at the reference base pose, at its initial joint
    /// positions with the gripper fully open, and a ground plane.
    pub fn new(robot: Robot, params: PhysicsParams) -> SimWorld {
        let model = robot_model(robot);
        let mut physics = PhysicsWorld::new();
        physics.gravity = Vector::new(0.0, 0.0, -params.gravity as Real);
        let ip = &mut physics.integration_parameters;
        ip.dt = params.dt as Real;
        ip.num_solver_iterations = params.solver_iterations;
        ip.num_internal_pgs_iterations = params.internal_pgs_iterations;
        // No continuous collision detection, as in MuJoCo (the reference), whose collisions are
        // all discrete. rapier's default sweeps every dynamic body that moves further than its
        // own size in a step; at the arm's speeds a 2 ms step moves a link or the object a few
        // mm, and deciding that cost ~2 % of every step. Over the 256 tasks × 500 steps of
        // random and scripted-expert episodes (`examples/trajectory_digest`) the sweep acted in
        // 2 of 512 episodes (scripted expert, stiff servos), their returns unchanged.
        ip.max_ccd_substeps = 0;
        ip.length_unit = params.length_unit as Real;
        ip.contact_softness = SpringCoefficients::new(
            params.contact_frequency as Real,
            params.contact_damping_ratio as Real,
        );
        ip.static_contact_softness = SpringCoefficients::new(
            2.0 * params.contact_frequency as Real,
            params.contact_damping_ratio as Real,
        );

        let ground = physics.insert_body(RigidBodyBuilder::fixed());
        physics.insert_collider(
            ColliderBuilder::halfspace(rapier3d::na::Unit::new_unchecked(Vector::Z))
                .collision_groups(InteractionGroups::new(
                    FLOOR_GROUP,
                    Group::ALL,
                    InteractionTestMode::And,
                ))
                .user_data(ColliderTag::Ground.encode()),
            Some(ground),
        );

        let arm = insert_arm(&mut physics, model, &robot_base_pose());
        let gains = ArmGains::for_robot(robot);
        let mut world = SimWorld {
            physics,
            robot,
            model,
            arm,
            gains,
            gripper: GripperParams::default(),
            params,
            arm_targets: robot.init_qpos(),
            setpoints: robot.init_qpos(),
            gripper_command: GripperCommand::Reference { action: 0.0 },
            gripper_c: 0.0,
            servo_mode: ServoMode::Stiff,
            object: None,
            torsion: TorsionalFriction::default(),
            steps: 0,
        };
        world.configure_joints();
        world.reset_arm(&robot.init_qpos(), FINGER_OPEN);
        world
    }

    fn configure_joints(&mut self) {
        let link_ids = self.arm.link_ids.clone();
        let (mb, _) = self
            .physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        // Settle the multibody's degrees of freedom first: until its fixed root is noticed, the
        // root counts 6 free DoFs that are dropped later, and per-DoF values written before
        // would shift onto the wrong joints.
        mb.forward_kinematics(&self.physics.bodies, false);
        mb.set_self_contacts_enabled(false);
        for (j, &link) in link_ids.iter().enumerate() {
            let dof = mb.link(link).expect("link").assembly_id();
            // The finger joints get no armature or damping (their servos set how they move),
            // only the reference's dry friction.
            let (armature, damping, friction) = if j < ARM_DOF {
                let g = &self.gains;
                (g.armature[j], g.damping[j], g.frictionloss)
            } else {
                (0.0, 0.0, self.gripper.frictionloss)
            };
            mb.armature_mut()[dof] = armature as Real;
            mb.damping_mut()[dof] = damping as Real;
            mb.frictions_mut()[dof] = friction as Real;
        }
        // The fingers move as one: q_right = −q_left (a mimic joint).
        let left = self.link_id(ARM_DOF);
        let right = self.link_id(ARM_DOF + 1);
        let (mb, _) = self
            .physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        mb.add_dof_coupling(MultibodyDofCoupling {
            link1: left,
            dof1: 0,
            axis1: 0,
            link2: right,
            dof2: 0,
            axis2: 0,
            coeff: -1.0,
            offset: 0.0,
        });
    }

    /// Add the static parts of an arena (bins, fixture, obstacle); visual-only parts are skipped,
    /// boxes lying flush in one solid collide as that one box ([`merged_solids`]). Each
    /// collider is tagged with its (first) index in `parts`.
    pub fn add_arena(&mut self, parts: &[Placed]) {
        let body = self.physics.insert_body(RigidBodyBuilder::fixed());
        for (index, part) in merged_solids(parts) {
            let (shape, pose) = primitive_shape(&part.shape, &part.pose);
            self.physics.insert_collider(
                ColliderBuilder::new(shape)
                    .position(pose)
                    .friction(part.friction.slide as Real)
                    .user_data(ColliderTag::Arena(index as u32).encode()),
                Some(body),
            );
        }
    }

    /// A copy of a world that has not been stepped yet, as if built afresh: the rapier sets are
    /// cloned, the pipeline and solver workspaces start empty. Much cheaper than building
    /// (no URDF merging, no shape or mass computations), and just as history-free.
    pub fn fresh_copy(&self) -> SimWorld {
        assert_eq!(
            self.steps, 0,
            "fresh_copy is for worlds that have not been stepped"
        );
        let p = &self.physics;
        let mut physics = PhysicsWorld::new();
        physics.gravity = p.gravity;
        physics.integration_parameters = p.integration_parameters;
        physics.islands = p.islands.clone();
        physics.broad_phase = p.broad_phase.clone();
        physics.narrow_phase = p.narrow_phase.clone();
        physics.bodies = p.bodies.clone();
        physics.colliders = p.colliders.clone();
        physics.impulse_joints = p.impulse_joints.clone();
        physics.multibody_joints = p.multibody_joints.clone();
        SimWorld {
            physics,
            robot: self.robot,
            model: self.model,
            arm: self.arm.clone(),
            gains: self.gains.clone(),
            gripper: self.gripper.clone(),
            params: self.params.clone(),
            arm_targets: self.arm_targets,
            setpoints: self.setpoints,
            gripper_command: self.gripper_command,
            gripper_c: self.gripper_c,
            servo_mode: self.servo_mode,
            object: self.object,
            torsion: self.torsion.clone(),
            steps: 0,
        }
    }
}

/// The floor's collision group: colliders whose filter leaves it out are never paired with
/// the floor, so the broad phase does not hand such pairs to the narrow phase at all.
const FLOOR_GROUP: Group = Group::GROUP_1;

/// Clearance (m) kept between the floor and the lowest point a body could reach before its
/// floor pair is dropped: far more than rapier's contact prediction distance (2 mm).
const FLOOR_CLEARANCE: f64 = 0.05;

/// For each body of the arm, whether no joint configuration brings any of its collision shapes
/// to the floor. The floor is an infinite half-space, so the broad phase pairs it with every
/// collider, and its narrow-phase tests were ~5 % of a physics step; but the arm stands on a
/// pedestal, and its inner links cannot swing that low.
fn bodies_that_cannot_reach_floor(model: &RobotModel, poses: &[Isometry3<f64>]) -> Vec<bool> {
    lowest_reach(model, poses)
        .iter()
        .map(|lowest| lowest.is_some_and(|z| z > FLOOR_CLEARANCE))
        .collect()
}

/// For each moving body, a height (m) that none of its collision shapes can get below in any
/// joint configuration (`None` for the fixed base), judged from the model alone: the first
/// joint's child frame sits on its axis, so it stays put; every point of a body lies within
/// the sum of the joint offsets (and prismatic travels) from there, plus the body's own
/// farthest collision point.
fn lowest_reach(model: &RobotModel, poses: &[Isometry3<f64>]) -> Vec<Option<f64>> {
    let shoulder = poses[model.joints[0].child].translation.vector;
    // Farthest distance from the shoulder a body's frame origin can get.
    let mut frame_reach = vec![0.0; model.bodies.len()];
    for (j, joint) in model.joints.iter().enumerate() {
        frame_reach[joint.child] = if j == 0 {
            0.0
        } else {
            let travel = match (joint.kind, joint.limits) {
                (JointKind::Prismatic, Some((lo, hi))) => lo.abs().max(hi.abs()),
                _ => 0.0,
            };
            frame_reach[joint.parent] + joint.origin.translation.vector.norm() + travel
        };
    }
    model
        .bodies
        .iter()
        .enumerate()
        .map(|(b, body)| {
            if !model.joints.iter().any(|j| j.child == b) {
                // The fixed base: static colliders are never paired with the (static) floor.
                return None;
            }
            let shape_reach = body
                .collisions
                .iter()
                .map(|c| c.pose.translation.vector.norm() + bounding_radius(&c.shape))
                .fold(0.0, f64::max);
            Some(shoulder.z - (frame_reach[b] + shape_reach))
        })
        .collect()
}

/// The radius of a sphere about a shape's own origin that holds the whole shape.
fn bounding_radius(shape: &Shape) -> f64 {
    match *shape {
        Shape::Box(h) => h.norm(),
        Shape::Capsule {
            radius,
            half_length,
        } => half_length + radius,
        Shape::Cylinder {
            radius,
            half_length,
        } => radius.hypot(half_length),
        Shape::Sphere(r) => r,
    }
}

/// Each body's world pose with every joint at 0, the base at `base`: the joint origins chained.
fn rest_poses(model: &RobotModel, base: &Isometry3<f64>) -> Vec<Isometry3<f64>> {
    let mut poses: Vec<Isometry3<f64>> = vec![*base; model.bodies.len()];
    for joint in &model.joints {
        poses[joint.child] = poses[joint.parent] * joint.origin;
    }
    poses
}

fn insert_arm(physics: &mut PhysicsWorld, model: &RobotModel, base: &Isometry3<f64>) -> ArmHandles {
    let poses = rest_poses(model, base);
    let above_floor = bodies_that_cannot_reach_floor(model, &poses);
    // Bodies out of the floor's reach: no floor pair for the broad phase to make.
    let arm_groups = |body: usize| {
        let filter = if above_floor[body] {
            Group::ALL.difference(FLOOR_GROUP)
        } else {
            Group::ALL
        };
        InteractionGroups::new(Group::ALL, filter, InteractionTestMode::And)
    };
    let mut bodies = Vec::with_capacity(model.bodies.len());
    let mut finger_colliders = Vec::new();
    for (index, body) in model.bodies.iter().enumerate() {
        let builder = if index == 0 {
            RigidBodyBuilder::fixed()
        } else {
            RigidBodyBuilder::dynamic()
        };
        let inertia = nalgebra::Matrix3::<Real>::from_fn(|r, c| body.inertia[(r, c)] as Real);
        let mut builder = builder.pose(to_pose(&poses[index])).can_sleep(false);
        if index > 0 {
            builder = builder.additional_mass_properties(MassProperties::with_inertia_matrix(
                to_vec(&body.com),
                body.mass as Real,
                inertia.into(),
            ));
        }
        let handle = physics.insert_body(builder);
        for collision in &body.collisions {
            let (shape, pose) = shape_of(collision);
            let tag = tag_for(&collision.name, index);
            let collider = ColliderBuilder::new(shape)
                .position(pose)
                .collision_groups(arm_groups(index))
                .density(0.0)
                .friction(if matches!(tag, ColliderTag::Arm(_)) {
                    0.5
                } else {
                    1.0
                })
                .user_data(tag.encode());
            let ch = physics.insert_collider(collider, Some(handle));
            if matches!(tag, ColliderTag::Pad(_) | ColliderTag::Finger(_)) {
                finger_colliders.push((ch, tag));
            }
        }
        bodies.push(handle);
    }
    let mut joints = Vec::with_capacity(model.joints.len());
    for joint in &model.joints {
        let basis = Pose::from_rotation(GenericJoint::complete_ang_frame(to_vec(&joint.axis)));
        let locked = match joint.kind {
            JointKind::Revolute => JointAxesMask::LOCKED_REVOLUTE_AXES,
            JointKind::Prismatic => JointAxesMask::LOCKED_PRISMATIC_AXES,
        };
        let axis = match joint.kind {
            JointKind::Revolute => JointAxis::AngX,
            JointKind::Prismatic => JointAxis::LinX,
        };
        let mut builder = GenericJointBuilder::new(locked)
            .local_frame1(to_pose(&joint.origin) * basis)
            .local_frame2(basis)
            .motor_model(axis, MotorModel::ForceBased)
            .contacts_enabled(false);
        if let Some((lo, hi)) = joint.limits {
            builder = builder.limits(axis, [lo as Real, hi as Real]);
        }
        let handle = physics
            .insert_multibody_joint(bodies[joint.parent], bodies[joint.child], builder.build())
            .unwrap_or_else(|| panic!("joint {} closes a loop", joint.name));
        joints.push(handle);
    }
    assert_eq!(model.joints[ARM_DOF].name, FINGER_JOINTS[0]);
    assert_eq!(model.joints[ARM_DOF + 1].name, FINGER_JOINTS[1]);
    // Bodies moved by each arm joint: the child and everything below it.
    let downstream = (0..ARM_DOF)
        .map(|j| {
            (0..model.bodies.len())
                .filter(|&b| {
                    let mut cur = b;
                    loop {
                        if cur == model.joints[j].child {
                            return true;
                        }
                        match model.joints.iter().find(|jm| jm.child == cur) {
                            Some(parent_joint) => cur = parent_joint.parent,
                            None => return false,
                        }
                    }
                })
                .collect()
        })
        .collect();
    let link_ids = joints
        .iter()
        .map(|h| physics.multibody_joints.get(*h).expect("inserted joint").1)
        .collect();
    ArmHandles {
        bodies,
        joints,
        link_ids,
        finger_colliders,
        grip_site: model.links[GRIP_SITE_LINK],
        hand: model.links[HAND_LINK],
        downstream,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axes::AxisElement;
    use rand::{Rng, SeedableRng};

    /// The floor filter rests on a bound, which must hold in every configuration: no collision
    /// shape of a body comes below its `lowest_reach`, over random joint positions within the
    /// limits (continuous joints anywhere), for every arm.
    #[test]
    fn bodies_kept_from_the_floor_never_reach_it() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(31);
        for robot in Robot::all() {
            let mut world = SimWorld::new(robot, PhysicsParams::default());
            let poses = rest_poses(world.model, &robot_base_pose());
            let above = bodies_that_cannot_reach_floor(world.model, &poses);
            assert!(
                above.iter().filter(|&&a| a).count() >= 4,
                "{robot:?}: the filter should spare at least the four inner links: {above:?}"
            );
            let bound = lowest_reach(world.model, &poses);
            for _ in 0..2000 {
                let q: [f64; ARM_DOF] = std::array::from_fn(|j| {
                    let (lo, hi) = world.model.joints[j]
                        .limits
                        .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI));
                    rng.random_range(lo..=hi)
                });
                world.reset_arm(&q, FINGER_OPEN);
                for (b, &handle) in world.arm.bodies.iter().enumerate() {
                    let Some(bound) = bound[b] else { continue };
                    for &c in world.physics.bodies[handle].colliders() {
                        let collider = &world.physics.colliders[c];
                        let aabb = collider
                            .shape()
                            .compute_aabb(&world.collider_pose(collider));
                        // AABBs of rotated shapes overshoot the shape; the bound holds for them too.
                        assert!(
                            aabb.mins.z as f64 >= bound - 1e-4,
                            "{robot:?} body {b} at q = {q:?}: z = {} below its bound {bound}",
                            aabb.mins.z
                        );
                    }
                }
            }
        }
    }
}
