//! A rapier world holding one arm with its gripper, static scene parts and (optionally) one
//! object, stepped at the physics period with joint position servos.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude::*;

use super::arm_dynamics::{ArmDynamics, ArmState, arm_dynamics};
use super::params::{ArmGains, GripperParams, PhysicsParams};
use super::robot_model::{
    ARM_DOF, CollisionShape, FINGER_JOINTS, GRIP_SITE_LINK, HAND_LINK, JointKind, MAX_BODIES,
    RobotModel, Shape, robot_model,
};
use super::tags::{ColliderTag, Side};
use super::torsion::TorsionalFriction;
use crate::arena::{Placed, Primitive, merged_solids, object_geometry, robot_base_pose};
use crate::axes::{Object, Robot};

/// How the gripper is being commanded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GripperCommand {
    /// Reach this opening between the pads (m) with at most this force per finger (N).
    Width {
        /// Target pad gap (m); clamped to what the fingers can reach.
        width: f64,
        /// Force limit per finger (N), at most the servo's limit.
        max_effort: f64,
    },
    /// The reference's scheme: an internal command c in [−1, 1] moves by 0.01·sign(action)
    /// every physics step (+ closes, − opens, 0 holds) and maps linearly onto the servo range.
    Reference {
        /// The last action's gripper component; only its sign matters.
        action: f64,
    },
}

/// The pad gap at finger position `q_left` (fingers coupled, q_right = −q_left):
/// 0.0371 m at q = 0 (docs/src/reference-facts.md §4.4).
pub fn pad_gap(q_left: f64) -> f64 {
    PAD_GAP_AT_ZERO + 2.0 * q_left
}

/// The left finger position whose pad gap is `gap` (the inverse of [`pad_gap`]).
pub fn finger_for_gap(gap: f64) -> f64 {
    (gap - PAD_GAP_AT_ZERO) / 2.0
}

/// Pad gap (m) with both fingers at 0.
const PAD_GAP_AT_ZERO: f64 = 0.0371;

/// How the arm's joint servos behave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ServoMode {
    /// Stiff position servos (the `ArmGains`), set points rate-limited by each joint's velocity
    /// limit: how a real arm's driver tracks absolute position commands.
    #[default]
    Stiff,
    /// The reference benchmark's joint controller (docs/src/reference-facts.md §4.2), every physics
    /// step: torques
    /// τ = M(q)·(kp·e − kd·q̇) + bias with kp 50, kd 2√50 (critical damping), the full joint-space
    /// mass matrix M (armature included) and the gravity, Coriolis and centrifugal torques
    /// (`arm_dynamics`), clipped to the effort limits — so each joint settles like an ideal
    /// critically damped spring, and agents trained on the reference see the same soft,
    /// slow-settling response. No set-point rate limit (the reference has none).
    Reference,
}

/// The reference's joint-controller stiffness (1/s²); its damping is 2√kp (ζ = 1).
const REFERENCE_KP: f64 = 50.0;

/// Finger/object contacts at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FingerContacts {
    /// The left pad touches the object.
    pub left_pad: bool,
    /// The right pad touches the object.
    pub right_pad: bool,
    /// Any part of the left finger (pad, tip, blade, knuckle) touches the object.
    pub left_finger: bool,
    /// Any part of the right finger touches the object.
    pub right_finger: bool,
}

impl FingerContacts {
    /// The benchmark's grasp test (docs/src/reference-facts.md §6): both pads touch the object; for
    /// the plate, one pad and any part of the other finger suffice.
    pub fn grasping(&self, object: Object) -> bool {
        match object {
            Object::Plate => {
                (self.right_finger && self.left_pad) || (self.left_finger && self.right_pad)
            }
            Object::Box | Object::HollowBox | Object::Dumbbell => self.left_pad && self.right_pad,
        }
    }
}

/// Handles of one arm in the world.
#[derive(Debug, Clone)]
pub struct ArmHandles {
    /// Rigid body of each model body (index 0: the fixed base).
    pub bodies: Vec<RigidBodyHandle>,
    /// The multibody joint of each model joint (7 arm joints, then left and right finger).
    pub joints: Vec<MultibodyJointHandle>,
    /// Finger colliders: (collider, tag).
    pub finger_colliders: Vec<(ColliderHandle, ColliderTag)>,
    /// Body and in-body pose of the grip site.
    pub grip_site: (usize, Isometry3<f64>),
    /// Body and in-body pose of the hand frame.
    pub hand: (usize, Isometry3<f64>),
    /// For each arm joint, which bodies move with it (for gravity compensation).
    pub downstream: Vec<Vec<usize>>,
    /// The multibody link id of each model joint (stable: links are never removed).
    pub link_ids: Vec<usize>,
}

/// The simulated world: rapier sets plus the arm's handles and command state.
pub struct SimWorld {
    /// Rapier's world (bodies, colliders, joints, pipeline).
    pub physics: PhysicsWorld,
    /// Which arm.
    pub robot: Robot,
    /// The arm's model.
    pub model: &'static RobotModel,
    /// The arm's handles.
    pub arm: ArmHandles,
    /// Servo gains.
    pub gains: ArmGains,
    /// Finger servo settings.
    pub gripper: GripperParams,
    /// Settings the world was built with.
    pub params: PhysicsParams,
    /// Current joint position targets (rad), as commanded.
    arm_targets: [f64; ARM_DOF],
    /// The servos' set points (rad): they move toward the targets no faster than each joint's
    /// velocity limit, as a real arm's joint-limit layer does with position commands.
    setpoints: [f64; ARM_DOF],
    gripper_command: GripperCommand,
    /// The reference's internal gripper command c in [−1, 1].
    gripper_c: f64,
    /// How the arm servos behave.
    servo_mode: ServoMode,
    /// The object body, if one was added.
    pub object: Option<RigidBodyHandle>,
    /// The object's torsional friction (none until an object with it is added).
    torsion: TorsionalFriction,
    /// Physics steps taken.
    pub steps: u64,
}

fn to_vec(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as Real, v.y as Real, v.z as Real)
}

/// nalgebra pose (f64) to rapier pose.
pub fn to_pose(p: &Isometry3<f64>) -> Pose {
    let q = p.rotation.quaternion();
    Pose::from_parts(
        to_vec(&p.translation.vector),
        Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real),
    )
}

/// rapier pose to nalgebra pose (f64).
pub fn from_pose(p: &Pose) -> Isometry3<f64> {
    let t = p.translation;
    let r = p.rotation;
    Isometry3::from_parts(
        Translation3::new(t.x as f64, t.y as f64, t.z as f64),
        UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
            r.w as f64, r.x as f64, r.y as f64, r.z as f64,
        )),
    )
}

/// A rapier shape and its pose for an arena primitive (cylinders along the pose's z axis).
fn primitive_shape(shape: &Primitive, pose: &Isometry3<f64>) -> (SharedShape, Pose) {
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

    /// The multibody link id of model joint `j`.
    fn link_id(&self, j: usize) -> usize {
        self.arm.link_ids[j]
    }

    fn multibody(&self) -> &Multibody {
        self.physics
            .multibody_joints
            .get(self.arm.joints[0])
            .expect("arm multibody")
            .0
    }

    /// Position of model joint `j` (rad or m).
    pub fn joint_position(&self, j: usize) -> f64 {
        let link = self.multibody().link(self.link_id(j)).expect("link");
        let axis = coordinate_axis(self.model.joints[j].kind);
        link.joint.coords()[axis] as f64
    }

    /// Velocity of model joint `j` (rad/s or m/s).
    pub fn joint_velocity(&self, j: usize) -> f64 {
        let mb = self.multibody();
        let link = mb.link(self.link_id(j)).expect("link");
        mb.joint_velocity(link)[0] as f64
    }

    /// The seven arm joint positions (rad).
    pub fn arm_positions(&self) -> [f64; ARM_DOF] {
        std::array::from_fn(|j| self.joint_position(j))
    }

    /// The seven arm joint velocities (rad/s).
    pub fn arm_velocities(&self) -> [f64; ARM_DOF] {
        std::array::from_fn(|j| self.joint_velocity(j))
    }

    /// Finger joint positions (left, right) in m.
    pub fn finger_positions(&self) -> [f64; 2] {
        [
            self.joint_position(ARM_DOF),
            self.joint_position(ARM_DOF + 1),
        ]
    }

    /// Put the arm at `q` (rad) and the fingers at `q_left` (m), at rest, with matching targets.
    pub fn reset_arm(&mut self, q: &[f64; ARM_DOF], q_left: f64) {
        let mut wanted: Vec<f64> = q.to_vec();
        wanted.push(q_left);
        wanted.push(-q_left);
        let current: Vec<f64> = (0..wanted.len()).map(|j| self.joint_position(j)).collect();
        let link_ids = &self.arm.link_ids;
        let physics = &mut self.physics;
        let (mb, _) = physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        // Displacements are indexed by generalized coordinate (the root may own some).
        let mut disp: Vec<Real> = vec![0.0; mb.ndofs()];
        for (j, link) in link_ids.iter().enumerate() {
            disp[mb.link(*link).expect("link").assembly_id()] = (wanted[j] - current[j]) as Real;
        }
        mb.apply_displacements(&disp);
        mb.generalized_velocity_mut().fill(0.0);
        mb.forward_kinematics(&physics.bodies, true);
        mb.update_rigid_bodies(&mut physics.bodies, false);
        for &handle in &self.arm.bodies {
            if let Some(body) = physics.bodies.get_mut(handle) {
                body.set_linvel(Vector::ZERO, true);
                body.set_angvel(Vector::ZERO, true);
            }
        }
        self.arm_targets = *q;
        self.setpoints = *q;
        self.gripper_c = 0.0;
        self.gripper_command = GripperCommand::Width {
            width: pad_gap(q_left),
            max_effort: self.gripper.max_force,
        };
    }

    /// Set arm joint targets (rad), used from the next physics step on, as given: absolute
    /// commands are validated and clamped by the caller (`control::limits`), while the
    /// reference's goals (q + 0.05·a) may lie past a limit, as in the reference, where the
    /// joint's limit constraint (here rapier's) stops the joint and the servo pushes into it.
    pub fn set_arm_targets(&mut self, targets: &[f64; ARM_DOF]) {
        self.arm_targets = *targets;
    }

    /// Current arm targets (rad).
    pub fn arm_targets(&self) -> [f64; ARM_DOF] {
        self.arm_targets
    }

    /// Switch the arm servos' behaviour.
    pub fn set_servo_mode(&mut self, mode: ServoMode) {
        self.servo_mode = mode;
    }

    /// The current servo behaviour.
    pub fn servo_mode(&self) -> ServoMode {
        self.servo_mode
    }

    /// Command the gripper.
    pub fn set_gripper(&mut self, command: GripperCommand) {
        self.gripper_command = command;
    }

    /// The reference's internal gripper command c in [−1, 1] (+1 closed).
    pub fn gripper_c(&self) -> f64 {
        self.gripper_c
    }

    /// Gravity torque on each arm joint at the current configuration (N·m): what the servos
    /// must add to hold still.
    pub fn gravity_torques(&self) -> [f64; ARM_DOF] {
        let g = Vector3::new(0.0, 0.0, -self.params.gravity);
        let bodies = &self.physics.bodies;
        let mut tau = [0.0; ARM_DOF];
        for (j, joint) in self.model.joints.iter().enumerate().take(ARM_DOF) {
            let child = &bodies[self.arm.bodies[joint.child]];
            let frame = from_pose(child.position());
            let anchor = frame.translation.vector;
            let axis = frame.rotation * joint.axis;
            for &b in &self.arm.downstream[j] {
                let body = &bodies[self.arm.bodies[b]];
                let com = body.center_of_mass();
                let r = Vector3::new(com.x as f64, com.y as f64, com.z as f64) - anchor;
                tau[j] += r.cross(&(g * body.mass() as f64)).dot(&axis);
            }
        }
        tau
    }

    fn update_servos(&mut self) {
        let gripper_targets = self.finger_targets();
        // The reference controller drives the joints with torques; the stiff servos with
        // rapier's joint motors (implicit springs), gravity fed forward through their set points.
        let (reference_torques, tau_g) = match self.servo_mode {
            ServoMode::Reference => (Some(self.reference_torques()), [0.0; ARM_DOF]),
            ServoMode::Stiff => (None, self.gravity_torques()),
        };
        let (kp, kd) = (self.gains.kp, self.gains.kd);
        let gripper = &self.gripper;
        let link_ids = &self.arm.link_ids;
        let (mb, _) = self
            .physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        let dt = self.params.dt;
        for j in 0..ARM_DOF {
            let joint = &self.model.joints[j];
            let data = &mut mb.link_mut(link_ids[j]).expect("link").joint.data;
            if reference_torques.is_some() {
                self.setpoints[j] = self.arm_targets[j];
                data.set_motor_position(JointAxis::AngX, 0.0, 0.0, 0.0);
                data.set_motor_max_force(JointAxis::AngX, 0.0);
                continue;
            }
            let max_step = joint.velocity * dt;
            let step = (self.arm_targets[j] - self.setpoints[j]).clamp(-max_step, max_step);
            self.setpoints[j] += step;
            // Feed-forward gravity compensation through the servo's set point: at q = set point
            // the spring pushes exactly −τ_g.
            let target = self.setpoints[j] - tau_g[j] / kp[j];
            data.set_motor_position(
                JointAxis::AngX,
                target as Real,
                kp[j] as Real,
                kd[j] as Real,
            );
            data.set_motor_max_force(JointAxis::AngX, joint.effort as Real);
        }
        let (targets, max_force) = gripper_targets;
        for (i, target) in targets.iter().enumerate() {
            let data = &mut mb.link_mut(link_ids[ARM_DOF + i]).expect("link").joint.data;
            data.set_motor_position(
                JointAxis::LinX,
                *target as Real,
                gripper.kp as Real,
                gripper.kd as Real,
            );
            data.set_motor_max_force(JointAxis::LinX, max_force as Real);
        }
        self.apply_joint_torques(&reference_torques.unwrap_or([0.0; ARM_DOF]));
    }

    /// The arm's mass matrix and bias torques now.
    pub fn dynamics(&self) -> ArmDynamics {
        let mut body_poses = [Isometry3::identity(); MAX_BODIES];
        for (pose, &h) in body_poses.iter_mut().zip(&self.arm.bodies) {
            *pose = from_pose(self.physics.bodies[h].position());
        }
        arm_dynamics(&ArmState {
            model: self.model,
            body_poses: &body_poses[..self.arm.bodies.len()],
            downstream: &self.arm.downstream,
            armature: &self.gains.armature,
            velocities: &self.arm_velocities(),
            gravity: self.params.gravity,
        })
    }

    /// The reference controller's joint torques for the current state and targets (N·m):
    /// M(q)·(kp·e − kd·q̇) + bias, clipped to the effort limits as robosuite clips them.
    fn reference_torques(&self) -> [f64; ARM_DOF] {
        let dynamics = self.dynamics();
        let (q, qd) = (self.arm_positions(), self.arm_velocities());
        let kd = 2.0 * REFERENCE_KP.sqrt();
        let acceleration = nalgebra::SVector::<f64, ARM_DOF>::from_fn(|j, _| {
            REFERENCE_KP * (self.arm_targets[j] - q[j]) - kd * qd[j]
        });
        let tau = dynamics.mass_matrix * acceleration;
        std::array::from_fn(|j| {
            let effort = self.model.joints[j].effort;
            (tau[j] + dynamics.bias[j]).clamp(-effort, effort)
        })
    }

    /// Exert `tau` (N·m) at each arm joint: on its child body about the axis, and the reaction
    /// on its parent. Replaces what was exerted the step before.
    fn apply_joint_torques(&mut self, tau: &[f64; ARM_DOF]) {
        for &h in &self.arm.bodies {
            self.physics.bodies[h].reset_torques(false);
        }
        for (j, &t) in tau.iter().enumerate() {
            if t == 0.0 {
                continue;
            }
            let joint = &self.model.joints[j];
            let child = self.arm.bodies[joint.child];
            let axis = from_pose(self.physics.bodies[child].position()).rotation * joint.axis;
            let torque = to_vec(&(axis * t));
            self.physics.bodies[child].add_torque(torque, true);
            self.physics.bodies[self.arm.bodies[joint.parent]].add_torque(-torque, true);
        }
    }

    /// Finger servo targets (left, right) and force limit for the current command; advances
    /// the reference's internal command by one physics step.
    fn finger_targets(&mut self) -> ([f64; 2], f64) {
        let (lo, hi) = self.model.joints[ARM_DOF].limits.expect("finger limits");
        match self.gripper_command {
            GripperCommand::Width { width, max_effort } => {
                let mut q = (width - pad_gap(0.0)) / 2.0;
                if q <= lo {
                    // Closing onto the stop (or an object): aim past it so the force saturates.
                    q = lo - self.gripper.close_overshoot;
                }
                let q = q.min(hi);
                let force = if max_effort > 0.0 {
                    max_effort.min(self.gripper.max_force)
                } else {
                    self.gripper.max_force
                };
                ([q, -q], force)
            }
            GripperCommand::Reference { action } => {
                let step = if action > 0.0 {
                    0.01
                } else if action < 0.0 {
                    -0.01
                } else {
                    0.0
                };
                self.gripper_c = (self.gripper_c + step).clamp(-1.0, 1.0);
                // The reference maps c linearly onto the actuator range: +1 aims the left finger
                // at −0.020833 (past its closed stop), −1 at +0.0115 (its "open").
                let (closed, open) = (-0.020833, 0.0115);
                let q = open + (self.gripper_c + 1.0) / 2.0 * (closed - open);
                ([q, -q], self.gripper.max_force)
            }
        }
    }

    /// One physics step.
    pub fn step(&mut self) {
        self.update_servos();
        if let Some(object) = self.object {
            self.torsion.update(&mut self.physics, object);
        }
        self.physics.step();
        self.steps += 1;
    }

    /// One control period (`substeps` physics steps).
    pub fn step_control(&mut self) {
        for _ in 0..self.params.substeps {
            self.step();
        }
    }

    fn link_pose(&self, (body, in_body): (usize, Isometry3<f64>)) -> Isometry3<f64> {
        from_pose(self.physics.bodies[self.arm.bodies[body]].position()) * in_body
    }

    /// World pose of the grip site (the reference's end-effector point).
    pub fn grip_site_pose(&self) -> Isometry3<f64> {
        self.link_pose(self.arm.grip_site)
    }

    /// World pose of the hand frame (its orientation is the reference's `eef_quat`).
    pub fn hand_pose(&self) -> Isometry3<f64> {
        self.link_pose(self.arm.hand)
    }

    /// World pose of a URDF link by name.
    pub fn link_world_pose(&self, name: &str) -> Option<Isometry3<f64>> {
        self.model.links.get(name).map(|l| self.link_pose(*l))
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

    /// Add the manipulated object at `pose`: one compound collider of its primitives, with the
    /// reference's mass (uniform density, so the primitives give its centre of mass and inertia).
    pub fn add_object(&mut self, object: Object, pose: &Isometry3<f64>) -> RigidBodyHandle {
        let geometry = object_geometry(object);
        let shapes: Vec<(Pose, SharedShape)> = crate::arena::object_parts(object)
            .iter()
            .filter(|p| p.collides)
            .map(|p| {
                let (shape, local) = primitive_shape(&p.shape, &p.pose);
                (local, shape)
            })
            .collect();
        let compound = SharedShape::compound(shapes);
        let unit = compound.mass_properties(1.0);
        let density = (geometry.mass() / unit.mass() as f64) as Real;
        let friction = geometry.parts.first().map_or(1.0, |p| p.friction.slide);
        let body = self.physics.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(to_pose(pose))
                .can_sleep(false),
        );
        self.physics.insert_collider(
            ColliderBuilder::new(compound)
                .density(density)
                .friction(friction as Real)
                .user_data(ColliderTag::Object.encode()),
            Some(body),
        );
        self.object = Some(body);
        self.torsion = TorsionalFriction::new(geometry.torsional_coefficients());
        body
    }

    /// Move the object to `pose`, at rest.
    pub fn place_object(&mut self, pose: &Isometry3<f64>) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.set_position(to_pose(pose), true);
            body.set_linvel(Vector::ZERO, true);
            body.set_angvel(Vector::ZERO, true);
        }
    }

    /// Move the object to `pose` with velocities `linear` (m/s) and `angular` (rad/s), world
    /// frame — a teleport, as a simulator's "set entity state" does.
    pub fn set_object_motion(
        &mut self,
        pose: &Isometry3<f64>,
        linear: &Vector3<f64>,
        angular: &Vector3<f64>,
    ) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.set_position(to_pose(pose), true);
            body.set_linvel(to_vec(linear), true);
            body.set_angvel(to_vec(angular), true);
        }
    }

    /// Hold a torque (N·m, world frame) on the object about its centre of mass until it is
    /// changed — MuJoCo's `xfrc_applied`, for test rigs and disturbance studies.
    pub fn set_object_torque(&mut self, torque: Vector3<f64>) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.reset_torques(false);
            body.add_torque(to_vec(&torque), true);
        }
    }

    /// Pose of the object body.
    pub fn object_pose(&self) -> Option<Isometry3<f64>> {
        self.object
            .map(|h| from_pose(self.physics.bodies[h].position()))
    }

    /// The deepest penetration (m, ≥ 0) of any contact involving the object right now.
    pub fn object_penetration(&self) -> f64 {
        let Some(body) = self.object.and_then(|h| self.physics.bodies.get(h)) else {
            return 0.0;
        };
        let mut deepest: f64 = 0.0;
        for &collider in body.colliders() {
            for pair in self.physics.narrow_phase.contact_pairs_with(collider) {
                if let PairContacts::Rigid(rigid) = &pair.contacts {
                    for manifold in &rigid.manifolds {
                        for point in &manifold.points {
                            deepest = deepest.max(-(point.dist as f64));
                        }
                    }
                }
            }
        }
        deepest
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

    /// Which parts of the fingers touch the object now.
    pub fn finger_contacts(&self) -> FingerContacts {
        FingerContacts {
            left_pad: self.finger_touches_object(Side::Left, true),
            right_pad: self.finger_touches_object(Side::Right, true),
            left_finger: self.finger_touches_object(Side::Left, false),
            right_finger: self.finger_touches_object(Side::Right, false),
        }
    }

    /// Whether any collider of the given finger (only its pad with `pad_only`) touches the
    /// object: the shapes overlap or touch at their current poses (distance ≤ 0), which is what
    /// MuJoCo's contact list holds (geom margins are 0 in the reference). Rapier's own contact
    /// pairs would not do: they include speculative contacts up to the prediction distance
    /// apart (2 mm), and a pair that moves less than its recycling distance keeps last
    /// update's points.
    pub fn finger_touches_object(&self, side: Side, pad_only: bool) -> bool {
        let Some(object) = self.object_collider() else {
            return false;
        };
        let colliders = &self.physics.colliders;
        let object = &colliders[object];
        let object_pose = self.collider_pose(object);
        self.arm.finger_colliders.iter().any(|(handle, tag)| {
            let wanted = if pad_only {
                *tag == ColliderTag::Pad(side)
            } else {
                tag.is_finger(side)
            };
            wanted && {
                let finger = &colliders[*handle];
                rapier3d::parry::query::intersection_test(
                    &self.collider_pose(finger),
                    finger.shape(),
                    &object_pose,
                    object.shape(),
                )
                .expect("parry tests boxes, capsules, cylinders and compounds of them")
                .intersecting
            }
        })
    }

    /// The object's (one, compound) collider.
    fn object_collider(&self) -> Option<ColliderHandle> {
        let body = self.physics.bodies.get(self.object?)?;
        body.colliders().first().copied()
    }

    /// A collider's world pose from its body's current pose (not the pose cached at the last
    /// collision detection).
    fn collider_pose(&self, collider: &Collider) -> Pose {
        let local = collider.position_wrt_parent().copied().unwrap_or_default();
        match collider.parent() {
            Some(body) => *self.physics.bodies[body].position() * local,
            None => *collider.position(),
        }
    }
}

/// The fully open finger position (m), where every episode starts
/// (docs/src/reference-facts.md §4.4).
pub const FINGER_OPEN: f64 = 0.020833;

fn coordinate_axis(kind: JointKind) -> usize {
    match kind {
        JointKind::Prismatic => 0, // LinX
        JointKind::Revolute => 3,  // AngX
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

    /// `arm_dynamics` sums over composite bodies (a link and all beyond it); here M(q) and the
    /// bias torques are summed body by body from their definitions — each joint's velocity
    /// Jacobian column at each body, each body's wrench about each joint's axis — in random
    /// configurations and joint velocities of every arm. Measured: they agree to ~1e-15 of
    /// the largest entry.
    #[test]
    fn composite_body_dynamics_equal_the_body_by_body_sums() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for robot in Robot::all() {
            let mut world = SimWorld::new(robot, PhysicsParams::default());
            let model = world.model;
            for _ in 0..50 {
                let q: [f64; ARM_DOF] = std::array::from_fn(|j| {
                    let (lo, hi) = model.joints[j]
                        .limits
                        .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI));
                    rng.random_range(lo..=hi)
                });
                let qd: [f64; ARM_DOF] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
                world.reset_arm(&q, FINGER_OPEN);
                let poses: Vec<Isometry3<f64>> = world
                    .arm
                    .bodies
                    .iter()
                    .map(|&h| from_pose(world.physics.bodies[h].position()))
                    .collect();
                let fast = arm_dynamics(&ArmState {
                    model,
                    body_poses: &poses,
                    downstream: &world.arm.downstream,
                    armature: &world.gains.armature,
                    velocities: &qd,
                    gravity: world.params.gravity,
                });

                // Each joint's axis and anchor; each moving body's link, mass, com, inertia.
                let axis: Vec<Vector3<f64>> = (0..ARM_DOF)
                    .map(|j| poses[model.joints[j].child].rotation * model.joints[j].axis)
                    .collect();
                let anchor: Vec<Vector3<f64>> = (0..ARM_DOF)
                    .map(|j| poses[model.joints[j].child].translation.vector)
                    .collect();
                let link_of = |b: usize| {
                    (0..ARM_DOF)
                        .rev()
                        .find(|&j| world.arm.downstream[j].contains(&b))
                };
                let mut mass_matrix = nalgebra::SMatrix::<f64, ARM_DOF, ARM_DOF>::zeros();
                let mut bias = [0.0; ARM_DOF];
                // Link motion with zero joint accelerations, outward.
                let mut omega = [Vector3::zeros(); ARM_DOF];
                let mut alpha = [Vector3::zeros(); ARM_DOF];
                let mut anchor_acc = [Vector3::zeros(); ARM_DOF];
                for j in 0..ARM_DOF {
                    let spin = axis[j] * qd[j];
                    if j > 0 {
                        let d = anchor[j] - anchor[j - 1];
                        let (w, a) = (omega[j - 1], alpha[j - 1]);
                        omega[j] = w + spin;
                        alpha[j] = a + w.cross(&spin);
                        anchor_acc[j] = anchor_acc[j - 1] + a.cross(&d) + w.cross(&w.cross(&d));
                    } else {
                        omega[0] = spin;
                    }
                }
                let g = Vector3::new(0.0, 0.0, -world.params.gravity);
                for (b, pose) in poses.iter().enumerate() {
                    let Some(link) = link_of(b) else { continue };
                    let body = &model.bodies[b];
                    let r = pose.rotation.to_rotation_matrix();
                    let inertia = r.matrix() * body.inertia * r.matrix().transpose();
                    let com = (pose * nalgebra::Point3::from(body.com)).coords;
                    for j in 0..=link {
                        for i in 0..=link {
                            let v_i = axis[i].cross(&(com - anchor[i]));
                            let v_j = axis[j].cross(&(com - anchor[j]));
                            mass_matrix[(i, j)] +=
                                body.mass * v_i.dot(&v_j) + axis[i].dot(&(inertia * axis[j]));
                        }
                    }
                    let (w, a) = (omega[link], alpha[link]);
                    let rc = com - anchor[link];
                    let com_acc = anchor_acc[link] + a.cross(&rc) + w.cross(&w.cross(&rc));
                    let force = body.mass * (com_acc - g);
                    let moment = inertia * a + w.cross(&(inertia * w));
                    for j in 0..=link {
                        bias[j] += axis[j].dot(&(moment + (com - anchor[j]).cross(&force)));
                    }
                }
                for j in 0..ARM_DOF {
                    mass_matrix[(j, j)] += world.gains.armature[j];
                }
                let m_scale = mass_matrix.amax();
                let m_error = (fast.mass_matrix - mass_matrix).amax();
                assert!(
                    m_error <= 1e-12 * m_scale,
                    "{robot:?} q = {q:?}: M differs by {m_error:e} (largest entry {m_scale})"
                );
                let b_scale = bias.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (j, (ours, summed)) in fast.bias.iter().zip(&bias).enumerate() {
                    assert!(
                        (ours - summed).abs() <= 1e-12 * b_scale,
                        "{robot:?} q = {q:?}, q̇ = {qd:?}: bias {j} is {ours} here, {summed} summed body by body"
                    );
                }
            }
        }
    }
}
