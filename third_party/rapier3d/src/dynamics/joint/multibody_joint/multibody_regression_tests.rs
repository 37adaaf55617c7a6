//! Regression tests for reported multibody bugs.
//!
//! Each test reproduces a specific issue from the GitHub tracker. The crash
//! tests assert that a known-bad scenario steps (or mutates the joint set)
//! without panicking; the behavior tests assert that the simulation result
//! matches what the multibody solver is supposed to produce.

#[cfg(feature = "dim3")]
use crate::alloc_prelude::*;
use crate::prelude::*;

/// Regression test for <https://github.com/dimforge/rapier/issues/927> (Bug 1).
///
/// Removing a joint that leaves one of its bodies as an isolated single-link
/// multibody must clean up that body's `rb2mb` entry. Otherwise the entry keeps
/// a stale `MultibodyIndex` pointing at a freed arena slot, and the next call
/// to `MultibodyJointSet::iter()` panics with "No element at index".
#[test]
#[cfg(feature = "dim3")]
fn issue_927_remove_isolating_single_link_keeps_iter_valid() {
    let mut world = PhysicsWorld::new();

    let a = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 5.0, 0.0))
            .additional_mass(1.0),
    );
    let b = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(1.0, 5.0, 0.0))
            .additional_mass(1.0),
    );
    let c = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 5.0, 0.0))
            .additional_mass(1.0),
    );

    let joint = || RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0));
    world.insert_multibody_joint(a, b, joint());
    let handle_bc = world.insert_multibody_joint(b, c, joint()).unwrap();

    // Removing B->C isolates C as a single-link multibody.
    world.remove_multibody_joint(handle_bc);

    // Used to panic: "No element at index".
    let count = world.multibody_joints.iter().count();
    assert_eq!(count, 1, "only the A->B joint should remain");
}

/// Regression test for <https://github.com/dimforge/rapier/issues/927> (Bug 2).
///
/// Building multi-link sub-chains separately and then connecting them to a
/// common parent forces `Multibody::append()` to merge subtrees that have more
/// than one link. A bad `internal_id` rebase used to make `fill_jacobians`
/// read `body_jacobians` out of bounds during the velocity solve.
#[test]
#[cfg(feature = "dim3")]
fn issue_927_branching_multibody_tree_steps_without_panic() {
    let mut world = PhysicsWorld::new();

    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.5, 0.0)),
        ColliderBuilder::cuboid(50.0, 0.5, 50.0),
    );

    let make_body = |world: &mut PhysicsWorld, pos: Vector| {
        world
            .insert(
                RigidBodyBuilder::dynamic()
                    .translation(pos)
                    .additional_mass(5.0),
                ColliderBuilder::ball(0.3),
            )
            .0
    };

    let (chassis, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 1.5, 0.0))
            .additional_mass(50.0),
        ColliderBuilder::cuboid(2.0, 0.3, 1.0),
    );

    let joint = || RevoluteJointBuilder::new(Vector::new(1.0, 0.0, 0.0));

    // Two front sub-chains with three links each (so `append()` merges a
    // subtree with more than one link), and two rear sub-chains with two links.
    let axle_fl = make_body(&mut world, Vector::new(-1.5, 1.2, 1.2));
    let mangueta_fl = make_body(&mut world, Vector::new(-1.5, 1.0, 1.5));
    let wheel_fl = make_body(&mut world, Vector::new(-1.5, 0.5, 1.8));
    world.insert_multibody_joint(axle_fl, mangueta_fl, joint());
    world.insert_multibody_joint(mangueta_fl, wheel_fl, joint());

    let axle_fr = make_body(&mut world, Vector::new(1.5, 1.2, 1.2));
    let mangueta_fr = make_body(&mut world, Vector::new(1.5, 1.0, 1.5));
    let wheel_fr = make_body(&mut world, Vector::new(1.5, 0.5, 1.8));
    world.insert_multibody_joint(axle_fr, mangueta_fr, joint());
    world.insert_multibody_joint(mangueta_fr, wheel_fr, joint());

    let axle_rl = make_body(&mut world, Vector::new(-1.5, 1.2, -1.2));
    let wheel_rl = make_body(&mut world, Vector::new(-1.5, 0.5, -1.5));
    world.insert_multibody_joint(axle_rl, wheel_rl, joint());

    let axle_rr = make_body(&mut world, Vector::new(1.5, 1.2, -1.2));
    let wheel_rr = make_body(&mut world, Vector::new(1.5, 0.5, -1.5));
    world.insert_multibody_joint(axle_rr, wheel_rr, joint());

    // Connecting each sub-chain to the chassis triggers `append()` on a
    // multi-link subtree.
    world.insert_multibody_joint(chassis, axle_fl, joint());
    world.insert_multibody_joint(chassis, axle_fr, joint());
    world.insert_multibody_joint(chassis, axle_rl, joint());
    world.insert_multibody_joint(chassis, axle_rr, joint());

    for _ in 0..30 {
        world.step();
    }

    assert!(world.bodies[chassis].translation().y.is_finite());
}

/// Regression test for <https://github.com/dimforge/rapier/issues/906>.
///
/// Inserting a multibody joint *after* the pipeline has already stepped at
/// least once used to overflow a subtraction in `Multibody::append()`.
/// Inserting joints only during initialization, or using impulse joints, did
/// not trigger it.
#[test]
#[cfg(feature = "dim3")]
fn issue_906_insert_multibody_joint_between_steps() {
    const SHIFT: Real = 1.15;

    let mut world = PhysicsWorld::new();

    let (root, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );

    let joint = || {
        RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
            .local_anchor1(Vector::new(0.0, -SHIFT, 0.0))
    };

    // Build a short chain before the first step (this path always worked).
    let mut last = root;
    for i in 1..4 {
        let (body, _) = world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.0, -SHIFT * i as Real, 0.0)),
            ColliderBuilder::cuboid(0.5, 0.5, 0.5),
        );
        world.insert_multibody_joint(last, body, joint());
        last = body;
    }

    world.step();

    // Now extend the chain dynamically, between steps. This used to panic with
    // "attempt to subtract with overflow" in `Multibody::append()`.
    for i in 4..10 {
        let (body, _) = world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.0, -SHIFT * i as Real, 0.0)),
            ColliderBuilder::cuboid(0.5, 0.5, 0.5),
        );
        world.insert_multibody_joint(last, body, joint());
        last = body;

        world.step();
    }

    assert!(world.bodies[last].translation().y.is_finite());
}

/// Regression test for <https://github.com/dimforge/rapier/issues/907>.
///
/// A multibody-jointed body and a free rigid body both falling onto the same
/// ground used to crash the velocity solver's warm-start with a nalgebra
/// "Matrix slicing out of bounds" panic in `GenericRhs::apply_impulse`.
#[test]
#[cfg(feature = "dim3")]
fn issue_907_body_colliding_with_multibody() {
    let mut world = PhysicsWorld::new();

    let (ground, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(50.0, 0.5, 50.0),
    );

    // A spinning body attached to the ground with a revolute multibody joint.
    let (attached, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 3.0, 0.0))
            .angvel(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    world.insert_multibody_joint(
        ground,
        attached,
        RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
            .local_anchor1(Vector::new(0.0, 3.0, 0.0)),
    );

    // A free body that falls onto the ground next to the multibody.
    let (free, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(3.0, 3.0, 0.0)),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );

    for _ in 0..400 {
        world.step();
    }

    assert!(world.bodies[free].translation().y.is_finite());
}

/// Regression test for <https://github.com/dimforge/rapier/issues/908>.
///
/// Removing the links of a multibody chain one by one, while a free body rests
/// in contact with the chain's fixed root, used to crash the contact solver
/// with "No element at index" in `GenericContactConstraintBuilder::generate`.
#[test]
#[cfg(feature = "dim3")]
fn issue_908_remove_body_from_multibody_chain() {
    let mut world = PhysicsWorld::new();

    let (root, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );

    // A chain of spherical-jointed bodies hanging from the root.
    let mut chain = vec![root];
    for i in 1..4 {
        let (body, _) = world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.0, -2.0 * i as Real, 0.0)),
            ColliderBuilder::cuboid(0.5, 0.5, 0.5),
        );
        world.insert_multibody_joint(
            *chain.last().unwrap(),
            body,
            SphericalJointBuilder::new().local_anchor1(Vector::new(0.0, -2.0, 0.0)),
        );
        chain.push(body);
    }

    // A free body resting on the root. The crash only happened with it present.
    let (free, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 2.0, 0.0)),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );

    // Let everything settle, then peel the chain off one body at a time,
    // stepping in-between. Removing a link used to panic.
    for _ in 0..32 {
        world.step();
    }

    while chain.len() > 1 {
        let body = chain.pop().unwrap();
        world.remove_body(body);

        for _ in 0..32 {
            world.step();
        }
    }

    assert!(world.bodies[free].translation().y.is_finite());
}

/// Regression test for <https://github.com/dimforge/rapier/issues/400>.
///
/// A dynamic body attached to a *fixed* parent through a `MultibodyJoint`,
/// plus a free dynamic body colliding with that fixed parent, used to crash
/// the moment the free body touched the parent.
#[test]
#[cfg(feature = "dim3")]
fn issue_400_multibody_joint_fixed_parent_dynamic_collision() {
    let mut world = PhysicsWorld::new();

    // The fixed "table".
    let (table, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(1.0, 0.1, 1.0),
    );

    // A "flipper": dynamic body attached to the fixed table by a multibody
    // revolute joint, with a velocity motor.
    let (flipper, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(-0.5, 0.3, -0.5)),
        ColliderBuilder::cuboid(0.1, 0.1, 0.1),
    );
    world.insert_multibody_joint(
        table,
        flipper,
        RevoluteJointBuilder::new(Vector::new(0.0, 1.0, 0.0))
            .local_anchor1(Vector::new(-0.5, 0.3, -0.5))
            .motor_velocity(-1.0, 1.0),
    );

    // The "ball" that falls onto the table.
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::ball(0.01).friction(0.0),
    );

    for _ in 0..200 {
        world.step();
    }

    assert!(world.bodies[ball].translation().y.is_finite());
}

/// Regression test for <https://github.com/dimforge/rapier/issues/656>.
///
/// A free-floating multibody whose root collides off-center with a ledge must
/// pick up angular velocity, just like the same setup built with an impulse
/// joint does. The bug left the multibody root unable to react to the
/// collision torque.
#[test]
#[cfg(feature = "dim2")]
fn issue_656_multibody_root_reacts_to_collision_torque() {
    let impulse_angvel = run_issue_656_scenario(false);
    let multibody_angvel = run_issue_656_scenario(true);

    // Sanity check: the off-center landing must spin the body in the
    // (known-good) impulse-joint case.
    assert!(
        impulse_angvel > 0.1,
        "scenario should induce rotation; impulse-joint baseline = {impulse_angvel}"
    );

    // Regression check: the multibody root must react to the collision torque
    // comparably. With the bug its angular velocity stays near zero.
    assert!(
        multibody_angvel > impulse_angvel * 0.25,
        "multibody root barely rotated: multibody = {multibody_angvel}, impulse = {impulse_angvel}"
    );
}

/// Builds the issue-656 scenario (two co-located dynamic bodies joined at their
/// center, free-falling onto a ledge they only partly overlap) and returns the
/// largest angular velocity magnitude the root body reaches.
#[cfg(feature = "dim2")]
fn run_issue_656_scenario(use_multibody: bool) -> Real {
    let mut world = PhysicsWorld::new();

    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -2.0)),
        ColliderBuilder::cuboid(0.5, 0.5),
    );

    // Both bodies start at the same place; the joint pins them at that point.
    let start = Vector::new(0.70, 0.0);
    let (root, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(start),
        ColliderBuilder::cuboid(0.3, 0.1).mass(0.1),
    );
    let (child, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(start),
        ColliderBuilder::cuboid(0.05, 0.05).mass(0.1),
    );

    let joint = RevoluteJointBuilder::new()
        .local_anchor1(Vector::new(0.0, 0.0))
        .local_anchor2(Vector::new(0.0, 0.0))
        .contacts_enabled(false);
    if use_multibody {
        world.insert_multibody_joint(root, child, joint);
    } else {
        world.insert_impulse_joint(root, child, joint);
    }

    let mut max_angvel: Real = 0.0;
    for _ in 0..600 {
        world.step();
        max_angvel = max_angvel.max(world.bodies[root].angvel().abs());
    }
    max_angvel
}

/// Regression test for <https://github.com/dimforge/rapier/issues/379>.
///
/// Angular limits set on a ball (spherical) joint must be enforced by the
/// multibody constraint solver. The bug ignored them entirely, so the child
/// swung freely as if no limit had been set.
#[test]
#[cfg(feature = "dim3")]
fn issue_379_multibody_ball_joint_respects_angular_limits() {
    const LIMIT: Real = 0.3;

    let mut world = PhysicsWorld::new();

    // Fixed root at the origin.
    let root = world.insert_body(RigidBodyBuilder::fixed());

    // A child whose left end is pinned to the origin, extending along +X. Under
    // gravity it tries to swing down (rotating about the Z axis).
    let (child, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(1.0, 0.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::cuboid(1.0, 0.1, 0.1),
    );

    world.insert_multibody_joint(
        root,
        child,
        SphericalJointBuilder::new()
            .local_anchor1(Vector::new(0.0, 0.0, 0.0))
            .local_anchor2(Vector::new(-1.0, 0.0, 0.0))
            .limits(JointAxis::AngZ, [-LIMIT, LIMIT]),
    );

    let mut lowest: Real = 0.0;
    for _ in 0..600 {
        world.step();
        lowest = lowest.min(world.bodies[child].translation().y);
    }

    // Gravity pulls the child down until the `AngZ` limit stops it, so the
    // child center settles at about `y = -sin(LIMIT)` (~ -0.30):
    //  * if the limit is ignored, it keeps swinging down towards y = -1.0;
    //  * if the child somehow never swings, it stays at y = 0.
    // Bracketing `lowest` around the expected stop rejects both failure modes.
    let max_drop = -LIMIT.sin();
    assert!(
        lowest > max_drop - 0.15,
        "ball joint ignored its angular limit: child dropped to y = {lowest}, \
         but the {LIMIT} rad limit should keep it above {max_drop}"
    );
    assert!(
        lowest < max_drop + 0.1,
        "child never reached the joint limit (y = {lowest}); the test is not \
         exercising the limit"
    );
}

/// Companion to [`issue_906_insert_multibody_joint_between_steps`], covering the
/// variant that motivated the question in issue #906's discussion: attaching a
/// body with a **fixed** multibody joint (`joint.ndofs() == 0`) to the
/// **non-dynamic root** of an existing multibody, between steps.
///
/// This is the same `Multibody::append()` underflow as #906 — the old
/// `self.velocities.len() - rhs_root_ndofs` subtraction underflows whenever
/// `self` has a fixed (small-`ndofs`) root, regardless of the connecting
/// joint's dof count. The fix's per-link arithmetic is underflow-free for any
/// `joint.ndofs()`, including 0.
#[test]
#[cfg(feature = "dim3")]
fn issue_906_append_fixed_joint_to_fixed_multibody_root() {
    let mut world = PhysicsWorld::new();

    // A multibody with a fixed (non-dynamic) root and one revolute child.
    let (root, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    let (child, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, -2.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    world.insert_multibody_joint(
        root,
        child,
        RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
            .local_anchor1(Vector::new(0.0, -2.0, 0.0)),
    );

    // Step once so `update_root_type` recognizes the root as non-dynamic.
    world.step();

    // Attach a new body to the (now non-dynamic) root with a *fixed* joint.
    let (attached, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 0.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    let handle = world.insert_multibody_joint(
        root,
        attached,
        FixedJointBuilder::new().local_anchor1(Vector::new(2.0, 0.0, 0.0)),
    );
    assert!(
        handle.is_some(),
        "attaching a fixed joint to a fixed multibody root should be allowed"
    );

    let start = world.bodies[attached].translation();
    for _ in 0..60 {
        world.step();
    }
    let end = world.bodies[attached].translation();

    // A fixed joint to a fixed root contributes zero dofs: the attached body
    // must stay rigidly in place despite gravity.
    let drift = (end.x - start.x).abs() + (end.y - start.y).abs() + (end.z - start.z).abs();
    assert!(
        drift < 1.0e-3,
        "body fixed-jointed to a fixed root should not move, but drifted by {drift}"
    );
    // The pre-existing revolute branch must still simulate.
    assert!(world.bodies[child].translation().y.is_finite());
    assert_eq!(world.multibody_joints.iter().count(), 2);
}

/// Regression test for an issue #907 variant uncovered while reviewing that
/// fix. The #907 contact-side fix only treats a multibody's *fixed root* as a
/// plain fixed body — but a body attached to that root (here with a fixed
/// joint) is a *non-root link*, so it is still handled as a multibody link.
///
/// Such a link sits in a branch joined to the rest of the multibody only
/// *through* the fixed root. Island traversals never cross fixed bodies, so the
/// branch used to land in a separate island from the multibody's solver
/// representative — and a contact against it hit the same empty
/// `generic_solver_vels` out-of-bounds as #907. The fix keeps every link of a
/// multibody in a single island (island-merge anchoring in `do_insert` +
/// whole-multibody island traversal in `push_linked_bodies`).
#[test]
#[cfg(feature = "dim3")]
fn issue_907_contact_with_branch_off_fixed_root() {
    let mut world = PhysicsWorld::new();

    // A multibody with a fixed root and a revolute child.
    let (root, _) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    let (child, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, -3.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::ball(0.5),
    );
    world.insert_multibody_joint(
        root,
        child,
        RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
            .local_anchor1(Vector::new(0.0, -3.0, 0.0)),
    );

    // Step once so the root is recognized as non-dynamic.
    world.step();

    // A second branch off the (non-dynamic) root, far from `child` — it lands
    // in a different island unless the whole multibody is kept together.
    let (branch, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(5.0, 0.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    world.insert_multibody_joint(
        root,
        branch,
        FixedJointBuilder::new().local_anchor1(Vector::new(5.0, 0.0, 0.0)),
    );

    // A free body that falls onto `branch`: the contact used to crash the
    // velocity solver's warm-start with an out-of-bounds matrix slice.
    let (free, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(5.0, 3.0, 0.0))
            .additional_mass(1.0),
        ColliderBuilder::cuboid(0.3, 0.3, 0.3),
    );

    for _ in 0..200 {
        world.step();
    }

    // The free body must come to rest on top of `branch` (`branch` top at
    // y = 0.5, free half-height 0.3 → free center settles around y = 0.8).
    let free_y = world.bodies[free].translation().y;
    assert!(
        (free_y - 0.8).abs() < 0.15,
        "free body should rest on the fixed-jointed branch, but settled at y = {free_y}"
    );
    assert!(world.bodies[child].translation().y.is_finite());
}

/// Builds a one-link pendulum hinged at the origin, its rod along +X so gravity
/// torques the hinge, steps it through the start of its descent, and returns
/// how far the link's centre fell.
///
/// The horizon is deliberately short: a free pendulum reaches the bottom in
/// roughly half a second and swings back up, so drop-at-a-fixed-time only
/// decreases with friction while every case is still descending.
#[cfg(feature = "dim3")]
fn friction_pendulum_drop(friction: Real) -> Real {
    const LINK_LEN: Real = 1.0;
    let mut world = PhysicsWorld::new();

    let root = world.insert_body(RigidBodyBuilder::fixed());
    let link = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(LINK_LEN, 0.0, 0.0))
            .additional_mass(1.0),
    );

    let handle = world
        .insert_multibody_joint(
            root,
            link,
            RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
                .local_anchor1(Vector::ZERO)
                .local_anchor2(Vector::new(-LINK_LEN, 0.0, 0.0)),
        )
        .unwrap();

    if friction > 0.0 {
        let (multibody, _) = world.multibody_joints.get_mut(handle).unwrap();
        multibody.frictions_mut().fill(friction);
    }

    for _ in 0..15 {
        world.step();
    }
    -world.bodies[link].translation().y
}

/// Joint dry friction (MuJoCo `frictionloss`).
#[test]
#[cfg(feature = "dim3")]
fn joint_friction_bounds_the_joint_force() {
    // Gravity torque about the hinge for a 1 kg rod of length 1 m.
    let gravity_torque = 1.0 * 9.81 * 1.0;

    let free = friction_pendulum_drop(0.0);
    let weak = friction_pendulum_drop(0.25 * gravity_torque);
    let locked = friction_pendulum_drop(4.0 * gravity_torque);
    let extreme = friction_pendulum_drop(1000.0 * gravity_torque);

    assert!(free > 0.05, "frictionless pendulum should fall: {free}");
    assert!(
        weak < free * 0.9,
        "sub-gravity friction should slow the fall: {weak} vs {free}"
    );
    assert!(
        locked.abs() < 1.0e-4,
        "friction above the gravity torque should hold the joint at rest: {locked}"
    );
    assert!(
        extreme.abs() < 1.0e-4,
        "an oversized friction bound must stay inert, not chatter: {extreme}"
    );
}

/// CompoSuite-ROS patch: the narrow phase skips a pair it found on two links of one multibody
/// without self-contacts (`ContactPair::self_contact_filter`). The skip must end when the
/// verdict's grounds change: self-contacts turned on, or a joint removed so that the two bodies
/// are no longer links of one multibody.
#[test]
#[cfg(feature = "dim3")]
fn self_contact_filter_follows_the_multibody() {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    let root = world.insert_body(RigidBodyBuilder::fixed());
    // Two links whose boxes overlap, each on its own joint to the root.
    let (link1, collider1) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    let (link2, collider2) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.4, 1.0, 0.0)),
        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
    );
    let joint = || RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0));
    let joint1 = world.insert_multibody_joint(root, link1, joint()).unwrap();
    let joint2 = world.insert_multibody_joint(root, link2, joint()).unwrap();
    let set_self_contacts = |world: &mut PhysicsWorld, enabled: bool| {
        let (multibody, _) = world.multibody_joints.get_mut(joint1).unwrap();
        multibody.set_self_contacts_enabled(enabled);
    };
    let touching = |world: &PhysicsWorld| {
        world
            .narrow_phase
            .contact_pair(collider1, collider2)
            .is_some_and(|pair| pair.has_any_active_contact())
    };

    set_self_contacts(&mut world, false);
    for _ in 0..3 {
        world.step();
        assert!(!touching(&world), "self-contacts are off");
    }
    set_self_contacts(&mut world, true);
    world.step();
    assert!(
        touching(&world),
        "self-contacts turned on: the pair is updated again"
    );
    set_self_contacts(&mut world, false);
    for _ in 0..3 {
        world.step();
        assert!(!touching(&world), "self-contacts off again");
    }
    // Removing link 2's joint makes it a body of its own: a pair the filter no longer covers,
    // even though the multibody left with link 1 has its self-contacts off too.
    world.remove_multibody_joint(joint2);
    set_self_contacts(&mut world, false);
    world.step();
    assert!(
        touching(&world),
        "two multibodies now: the pair is updated again"
    );
}

/// CompoSuite-ROS patch: the narrow phase leaves a pair alone while its one manifold is empty
/// and the dispatcher knows the shapes apart (`pair_update::stays_idle`, for the floor's pairs).
/// Bodies falling onto, sliding on and bouncing off a half-space must move exactly as with a
/// dispatcher that never claims that (the default dispatcher chained to itself), and the claim
/// must have been made, or the test shows nothing: the skipping world's idle manifolds keep the
/// normals of their last full update while the other world's follow the tumbling bodies.
#[test]
#[cfg(feature = "dim3")]
fn idle_floor_pairs_move_as_fully_updated_ones() {
    use crate::geometry::PairContacts;
    use parry::query::{DefaultQueryDispatcher, QueryDispatcher};

    let build = |narrow_phase: NarrowPhase| {
        let mut world = PhysicsWorld::new();
        world.narrow_phase = narrow_phase;
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        world.insert_collider(
            ColliderBuilder::halfspace(crate::na::Unit::new_unchecked(Vector::Y)),
            Some(ground),
        );
        let mut colliders = Vec::new();
        let shapes = [
            ColliderBuilder::cuboid(0.2, 0.1, 0.3),
            ColliderBuilder::capsule_y(0.2, 0.1),
            ColliderBuilder::cylinder(0.1, 0.2),
        ];
        for (i, shape) in shapes.into_iter().enumerate() {
            let body = RigidBodyBuilder::dynamic()
                .translation(Vector::new(i as Real, 0.5 + 0.4 * i as Real, 0.0))
                .linvel(Vector::new(0.3, 1.0, -0.2))
                .angvel(Vector::new(2.0, -1.0, 3.0));
            let (_, collider) = world.insert(body, shape.restitution(0.5));
            colliders.push(collider);
        }
        (world, colliders)
    };
    let (mut skipping, colliders) = build(NarrowPhase::new());
    let (mut full, _) = build(NarrowPhase::with_query_dispatcher(
        DefaultQueryDispatcher.chain(DefaultQueryDispatcher),
    ));
    let floor_normal = |world: &PhysicsWorld, collider| {
        let pair = world
            .narrow_phase
            .contact_pairs()
            .find(|pair| pair.collider1 == collider || pair.collider2 == collider)
            .expect("the floor's pair");
        match &pair.contacts {
            PairContacts::Rigid(rigid) => rigid.manifolds.first().map(|m| (m.local_n1, m.local_n2)),
            PairContacts::Soft { .. } => None,
        }
    };
    let mut touched = false;
    let mut stale_normals = 0;
    for step in 0..400 {
        skipping.step();
        full.step();
        for &collider in &colliders {
            let (a, b) = (&skipping.colliders[collider], &full.colliders[collider]);
            assert_eq!(
                a.position(),
                b.position(),
                "collider {collider:?} diverged at step {step}"
            );
            touched |= skipping
                .narrow_phase
                .contact_pairs()
                .any(|pair| pair.has_any_active_contact());
            if floor_normal(&skipping, collider) != floor_normal(&full, collider) {
                stale_normals += 1;
            }
        }
    }
    assert!(touched, "the bodies reach the floor");
    assert!(
        stale_normals > 0,
        "no pair was left idle: the shortcut never ran"
    );
}

/// CompoSuite-ROS patch: parry's `halfspace_pfm_surely_apart` (the test behind the floor pairs'
/// shortcuts) must never call a shape apart that `contact_manifold_halfspace_pfm`'s loop would
/// give a point within the prediction distance — checked against that loop's own computation,
/// over tumbling boxes, capsules and cylinders at heights around the prediction distance — and
/// must call apart every shape clearly beyond it (or the shortcuts never run).
#[test]
#[cfg(feature = "dim3")]
fn halfspace_apart_test_agrees_with_the_contact_loop() {
    use parry::query::details::halfspace_pfm_surely_apart;
    use parry::shape::{HalfSpace, PolygonalFeature, SharedShape};

    let halfspace = HalfSpace::new(Vector::Y);
    let prediction = 0.002;
    let shapes = [
        SharedShape::cuboid(0.2, 0.05, 0.3),
        SharedShape::capsule_z(0.15, 0.04),
        SharedShape::cylinder(0.1, 0.06),
    ];
    // A small deterministic generator: the cases are the same every run.
    let mut state = 0x2545_f491_u32;
    let mut unit = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as Real / u32::MAX as Real
    };
    let (mut apart, mut clearly_beyond) = (0, 0);
    for shape in &shapes {
        let (pfm, border_radius) = shape.as_polygonal_feature_map().unwrap();
        for _ in 0..4000 {
            let axis =
                Vector::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize_or(Vector::X);
            let rotation = Rotation::from_scaled_axis(axis * (unit() * 6.3));
            let position = Vector::new(unit() - 0.5, 0.0, unit() - 0.5);
            let pose = Pose::from_parts(position, rotation);
            // Place the shape's lowest point at a height within ±1 cm of the prediction.
            let lowest = |pose: &Pose| {
                let n = pose.rotation.inverse() * halfspace.normal;
                let mut feature = PolygonalFeature::default();
                pfm.local_support_feature(-n, &mut feature);
                (0..feature.num_vertices)
                    .map(|i| (pose * feature.vertices[i]).dot(halfspace.normal) - border_radius)
                    .fold(Real::INFINITY, Real::min)
            };
            let lift = prediction + (unit() - 0.5) * 0.02 - lowest(&pose);
            let pose = Pose::from_parts(position + Vector::Y * lift, rotation);
            let nearest = lowest(&pose);
            let surely_apart =
                halfspace_pfm_surely_apart(&pose, &halfspace, pfm, border_radius, prediction);
            if surely_apart {
                apart += 1;
                assert!(
                    nearest > prediction,
                    "called apart at {nearest} (prediction {prediction})"
                );
            }
            if nearest > prediction + 1.0e-3 {
                clearly_beyond += 1;
                assert!(surely_apart, "not called apart at {nearest}");
            }
        }
    }
    assert!(
        apart > 1000 && clearly_beyond > 1000,
        "{apart} apart, {clearly_beyond} beyond"
    );
}

/// CompoSuite-ROS patch: `place_rigid_bodies_where_moved` leaves a link's body alone when it
/// is at its link pose with no mass-property change pending (a marker put in its world centre
/// of mass survives), and otherwise puts it there with the world mass properties of that pose:
/// when moved away without the pipeline's knowledge, and when a mass change is pending.
#[test]
#[cfg(feature = "dim3")]
fn links_are_placed_only_where_moved() {
    let mut world = PhysicsWorld::new();
    let root = world.insert_body(RigidBodyBuilder::fixed());
    let (link, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::cuboid(0.1, 0.4, 0.2),
    );
    let joint = RevoluteJointBuilder::new(Vector::new(0.0, 0.0, 1.0))
        .local_anchor2(Vector::new(0.0, -0.5, 0.0));
    let handle = world.insert_multibody_joint(root, link, joint).unwrap();
    for _ in 0..10 {
        world.step();
    }
    let marker = Vector::new(7.0, 7.0, 7.0);
    let place = |world: &mut PhysicsWorld| {
        let (multibody, _) = world.multibody_joints.get(handle).unwrap();
        multibody.place_rigid_bodies_where_moved(&mut world.bodies);
    };
    let fresh_com = |world: &PhysicsWorld| {
        let rb = &world.bodies[link];
        let mut fresh = rb.mprops.clone();
        fresh.update_world_mass_properties(rb.body_type, &rb.pos.position);
        fresh.world_com
    };

    world
        .bodies
        .get_mut_internal(link)
        .unwrap()
        .mprops
        .world_com = marker;
    place(&mut world);
    assert_eq!(
        world.bodies[link].mprops.world_com, marker,
        "in place: left alone"
    );

    let placed = world.bodies[link].pos.position;
    let body = world.bodies.get_mut_internal(link).unwrap();
    body.pos.position = Pose::from_translation(Vector::new(0.3, 2.0, 0.1));
    place(&mut world);
    assert_eq!(
        world.bodies[link].pos.position, placed,
        "moved away: put back"
    );
    assert_eq!(world.bodies[link].mprops.world_com, fresh_com(&world));

    world
        .bodies
        .get_mut_internal(link)
        .unwrap()
        .mprops
        .world_com = marker;
    world.bodies[link].set_additional_mass(2.0, true);
    place(&mut world);
    assert_eq!(
        world.bodies[link].mprops.world_com,
        fresh_com(&world),
        "a mass change pending: updated"
    );
}

/// CompoSuite-ROS patch: `fill_jacobians` on slices (the contact rows' `J`, `M⁻¹·J` and the two
/// dots) gives what nalgebra's `tr_mul_to`, the Cholesky solve of a view and `dot` gave, bit for
/// bit, on a swinging chain of nine hinges (an arm and gripper's nine DoFs: nalgebra's `dot`
/// sums blocks of eight apart), for every link (the fixed root too) and three force directions.
#[test]
#[cfg(feature = "dim3")]
fn contact_jacobians_on_slices_equal_nalgebras() {
    let mut world = PhysicsWorld::new();
    let mut parent = world.insert_body(RigidBodyBuilder::fixed());
    let mut handle = None;
    for k in 0..9 {
        let (link, _) = world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.3 * k as Real, 1.0, 0.0)),
            ColliderBuilder::cuboid(0.1, 0.3, 0.05 + 0.02 * k as Real),
        );
        let axis = [Vector::Z, Vector::X, Vector::Y][k % 3];
        let joint = RevoluteJointBuilder::new(axis).local_anchor2(Vector::new(-0.15, 0.0, 0.0));
        handle = world.insert_multibody_joint(parent, link, joint);
        parent = link;
    }
    let handle = handle.unwrap();
    let mut checked = 0;
    for _ in 0..30 {
        world.step();
        let (multibody, _) = world.multibody_joints.get(handle).unwrap();
        let n = multibody.ndofs();
        assert_eq!((multibody.num_links(), n), (10, 9), "the fixed root and nine hinges");
        for link_id in 0..multibody.num_links() {
            for s in 0..3 {
                let force = Vector::new(0.3 - 0.2 * s as Real, 0.7, -0.4 + 0.5 * s as Real);
                let torque = Vector::new(-0.1 * s as Real, 0.25, 0.6);
                let mut jacobians = DVector::zeros(2 * n + 3);
                let mut j_id = 1;
                let (gain, vel) =
                    multibody.fill_jacobians(link_id, force, torque, &mut j_id, &mut jacobians);
                assert_eq!(j_id, 1 + 2 * n);

                let spatial = na::Vector6::new(force.x, force.y, force.z, torque.x, torque.y, torque.z);
                let mut j = DVector::zeros(n);
                multibody
                    .body_jacobian(multibody.link(link_id).unwrap().internal_id)
                    .tr_mul_to(&spatial, &mut j);
                let mut invm_j = j.clone();
                multibody.inv_augmented_mass().solve_mut(&mut invm_j);
                let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&jacobians.as_slice()[1..1 + n]), bits(j.as_slice()));
                assert_eq!(bits(&jacobians.as_slice()[1 + n..1 + 2 * n]), bits(invm_j.as_slice()));
                assert_eq!(gain.to_bits(), j.dot(&invm_j).to_bits());
                assert_eq!(vel.to_bits(), j.dot(&multibody.generalized_velocity()).to_bits());
                if link_id > 0 {
                    assert!(gain > 0.0, "a force on a moving link has a positive gain");
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 30 * 10 * 3);
}
