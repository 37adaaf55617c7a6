//! How far the arm is from the arena for given joint angles, from the arm's kinematic model
//! (its collision primitives) and the arena tables — no physics involved.
//!
//! Each arm primitive is covered by spheres (along a capsule's or cylinder's axis, over a
//! box's faces); each arena solid is a box (a cylinder by its bounding box). The clearance is
//! the smallest gap between any sphere and any solid, negative when they overlap.

use std::ops::Range;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::arena::{Placed, Primitive, arena_parts, object_parts};
use crate::axes::{Object, Objective, Obstacle};
use crate::kinematics::body_poses;
use crate::physics::{ARM_DOF, RobotModel, Shape};

/// Sphere spacing along a primitive, as a fraction of the sphere radius.
const SPACING: f64 = 0.5;

/// A sphere fixed to one body of the arm.
#[derive(Debug, Clone, Copy)]
struct Sphere {
    body: usize,
    centre: Point3<f64>,
    radius: f64,
    /// Whether the body can move with the gripper held still: every link before the last
    /// arm joint (not the hand and the fingers).
    swings: bool,
    /// Whether the body is a finger (which a grasp brings close to the floor on purpose).
    finger: bool,
}

/// An arena solid as an oriented box.
#[derive(Debug, Clone, Copy)]
struct Solid {
    inverse_pose: Isometry3<f64>,
    half: Vector3<f64>,
    /// The box's centre in the world, and the radius of the sphere through its corners: no
    /// point of the box is further from `centre` (see [`surely_beyond`]).
    centre: Point3<f64>,
    circumradius: f64,
}

/// A run of consecutive spheres on one body, and one sphere around all of them: where that
/// sphere keeps clear of a solid (or of a bound), none of the run's spheres can come closer, and
/// their distances to that solid are not computed.
#[derive(Debug, Clone)]
struct Group {
    body: usize,
    /// Centre of the covering sphere, in the body's frame.
    centre: Point3<f64>,
    /// Its radius: no point of the run's spheres is further from `centre`.
    reach: f64,
    spheres: Range<usize>,
}

/// How much a skipped distance is allowed to be below its computed lower bound, for rounding:
/// far below what any decision rests on, far above what rounding does at these sizes.
const BOUND_SLACK: f64 = 1e-9;

/// The most solids an arena has with an object added (checked where they are made): the
/// solids still in question for a group fit a fixed list on the stack.
const MAX_SOLIDS: usize = 64;

/// The spheres of one arm and the solids of one arena.
#[derive(Clone)]
pub(super) struct Clearance {
    spheres: Vec<Sphere>,
    groups: Vec<Group>,
    solids: Vec<Solid>,
}

impl Clearance {
    /// The arm `model` in the arena of `objective` and `obstacle`.
    pub fn new(model: &RobotModel, objective: Objective, obstacle: Obstacle) -> Clearance {
        Clearance::keeping(model, objective, obstacle, |_| true)
    }

    /// [`Clearance::new`] without the bins' floors: what a push must keep clear of, whose
    /// fingers and object ride just off the floor on purpose (the fingers' spheres, rounder
    /// than the fingers, reach centimetres into it and would hide every other gap).
    pub fn above_the_floors(
        model: &RobotModel,
        objective: Objective,
        obstacle: Obstacle,
    ) -> Clearance {
        Clearance::keeping(model, objective, obstacle, |part| {
            !part.name.ends_with("/floor")
        })
    }

    /// The arm `model` and the colliding parts of the arena that `keep` keeps.
    fn keeping(
        model: &RobotModel,
        objective: Objective,
        obstacle: Obstacle,
        keep: impl Fn(&Placed) -> bool,
    ) -> Clearance {
        let mut spheres = Vec::new();
        let hand: Vec<usize> = model.joints[ARM_DOF - 1..]
            .iter()
            .map(|j| j.child)
            .collect();
        let fingers: Vec<usize> = model.joints[ARM_DOF..].iter().map(|j| j.child).collect();
        // Body 0 is the fixed base on its pedestal, far from everything.
        for (body, b) in model.bodies.iter().enumerate().skip(1) {
            for c in &b.collisions {
                for (centre, radius) in cover(&c.shape) {
                    spheres.push(Sphere {
                        body,
                        centre: c.pose * centre,
                        radius,
                        swings: !hand.contains(&body),
                        finger: fingers.contains(&body),
                    });
                }
            }
        }
        let solids = arena_parts(objective, obstacle)
            .iter()
            .filter(|p| p.collides && keep(p))
            .map(solid)
            .collect();
        Clearance::of(spheres, solids)
    }

    fn of(spheres: Vec<Sphere>, solids: Vec<Solid>) -> Clearance {
        assert!(
            solids.len() <= MAX_SOLIDS,
            "{} solids: at most {MAX_SOLIDS}",
            solids.len()
        );
        Clearance {
            groups: groups(&spheres),
            spheres,
            solids,
        }
    }

    /// The same arena with the object's solids added at `pose`, as something to keep clear of
    /// on the way to a grasp.
    pub fn with_object(&self, object: Object, pose: &Isometry3<f64>) -> Clearance {
        let mut solids = self.solids.clone();
        solids.extend(object_parts(object).iter().map(|part| {
            solid(&Placed {
                pose: pose * part.pose,
                ..*part
            })
        }));
        Clearance::of(self.spheres.clone(), solids)
    }

    /// The same arena with the arm holding the object: the object (at `object_pose` with the
    /// arm at `q`) moves with the hand from then on, covered by spheres of its own.
    pub fn holding(
        &self,
        model: &RobotModel,
        q: &[f64; ARM_DOF],
        object: Object,
        object_pose: &Isometry3<f64>,
    ) -> Clearance {
        let mut spheres = self.spheres.clone();
        let hand = model.joints[ARM_DOF - 1].child;
        let to_hand = body_poses(model, q, [0.0, 0.0])[hand].inverse() * object_pose;
        for part in object_parts(object) {
            for (centre, radius) in held_cover(&part.shape) {
                spheres.push(Sphere {
                    body: hand,
                    centre: to_hand * part.pose * centre,
                    radius,
                    swings: false,
                    finger: false,
                });
            }
        }
        Clearance::of(spheres, self.solids.clone())
    }

    /// How crowded the links that can swing with the gripper held still are at `q`: the sum over
    /// their spheres of the square of how far each comes within `margin` (m) of the arena (0
    /// when all keep `margin`). Smooth where the smallest gap is not, so its gradient still
    /// points away from several solids close at once.
    pub fn crowding(&self, model: &RobotModel, q: &[f64; ARM_DOF], margin: f64) -> f64 {
        let poses = &body_poses(model, q, [0.0, 0.0]);
        self.groups
            .iter()
            .filter(|group| self.spheres[group.spheres.start].swings)
            .flat_map(|group| {
                // Solids at least `margin` from every sphere of the group add nothing.
                let near = self.near(poses, group, margin);
                self.spheres[group.spheres.clone()]
                    .iter()
                    .map(move |s| (margin - self.sphere_gap(poses, s, &near)).max(0.0).powi(2))
            })
            .sum()
    }

    /// The smallest gap (m) between the arm at `q` (fingers open) and the arena.
    pub fn at(&self, model: &RobotModel, q: &[f64; ARM_DOF]) -> f64 {
        self.smallest_gap(model, q, |_| true)
    }

    /// Whether the arm at `q` keeps at least `least` (m) from the arena: `at(model, q) >=
    /// least`, answered as soon as one sphere comes closer.
    pub fn keeps(&self, model: &RobotModel, q: &[f64; ARM_DOF], least: f64) -> bool {
        let poses = body_poses(model, q, [0.0, 0.0]);
        self.groups.iter().all(|group| {
            let near = self.near(&poses, group, least);
            self.spheres[group.spheres.clone()]
                .iter()
                .all(|s| self.sphere_gap(&poses, s, &near) >= least)
        })
    }

    /// The smallest gap (m) between the arm at `q` and the arena, the fingers left out.
    pub fn without_fingers(&self, model: &RobotModel, q: &[f64; ARM_DOF]) -> f64 {
        self.smallest_gap(model, q, |s| !s.finger)
    }

    /// The smallest gap (m) between the arena and the spheres `counts` keeps, the arm at `q`.
    fn smallest_gap(
        &self,
        model: &RobotModel,
        q: &[f64; ARM_DOF],
        counts: impl Fn(&Sphere) -> bool,
    ) -> f64 {
        let poses = body_poses(model, q, [0.0, 0.0]);
        let mut smallest = f64::INFINITY;
        for group in &self.groups {
            // Solids no closer to the group than the smallest gap so far cannot lower it.
            let near = self.near(&poses, group, smallest);
            for s in self.spheres[group.spheres.clone()]
                .iter()
                .filter(|s| counts(s))
            {
                smallest = smallest.min(self.sphere_gap(&poses, s, &near));
            }
        }
        smallest
    }

    /// The solids that may come closer than `bound` (m) to a sphere of `group`, its body at
    /// `poses`: those whose distance from the group's covering sphere is below it.
    fn near(&self, poses: &[Isometry3<f64>], group: &Group, bound: f64) -> Near {
        let centre = poses[group.body] * group.centre;
        let mut near = Near {
            solids: [0; MAX_SOLIDS],
            len: 0,
        };
        for (i, solid) in self.solids.iter().enumerate() {
            if surely_beyond(solid, &centre, bound + group.reach + BOUND_SLACK) {
                continue;
            }
            if box_distance(solid, &centre) - group.reach - BOUND_SLACK < bound {
                near.solids[near.len] = i as u8;
                near.len += 1;
            }
        }
        near
    }

    /// The gap (m) between one sphere, its body at `poses`, and the nearest of the `near`
    /// solids (infinite when there are none).
    fn sphere_gap(&self, poses: &[Isometry3<f64>], s: &Sphere, near: &Near) -> f64 {
        if near.len == 0 {
            return f64::INFINITY;
        }
        let c = poses[s.body] * s.centre;
        near.solids[..near.len]
            .iter()
            .map(|&i| box_distance(&self.solids[i as usize], &c) - s.radius)
            .fold(f64::INFINITY, f64::min)
    }
}

/// Indices of the solids still in question for one group.
struct Near {
    solids: [u8; MAX_SOLIDS],
    len: usize,
}

/// The runs of consecutive spheres on one body, each with a sphere covering it.
fn groups(spheres: &[Sphere]) -> Vec<Group> {
    let mut groups: Vec<Group> = Vec::new();
    let mut start = 0;
    for end in 1..=spheres.len() {
        if end < spheres.len() && spheres[end].body == spheres[start].body {
            continue;
        }
        let run = &spheres[start..end];
        // The centre of the run's bounding box, and the furthest sphere surface from it.
        let (mut lo, mut hi) = (run[0].centre, run[0].centre);
        for s in run {
            lo = lo.inf(&s.centre);
            hi = hi.sup(&s.centre);
        }
        let centre = nalgebra::center(&lo, &hi);
        let reach = run
            .iter()
            .map(|s| (s.centre - centre).norm() + s.radius)
            .fold(0.0, f64::max);
        groups.push(Group {
            body: run[0].body,
            centre,
            reach,
            spheres: start..end,
        });
        start = end;
    }
    groups
}

/// Spheres (centre in the shape's frame, radius) covering a primitive.
fn cover(shape: &Shape) -> Vec<(Point3<f64>, f64)> {
    let along_z = |radius: f64, half: f64| -> Vec<(Point3<f64>, f64)> {
        let n = ((2.0 * half) / (SPACING * radius)).ceil().max(1.0) as usize;
        (0..=n)
            .map(|k| {
                let z = -half + 2.0 * half * k as f64 / n as f64;
                (Point3::new(0.0, 0.0, z), radius)
            })
            .collect()
    };
    match *shape {
        Shape::Sphere(r) => vec![(Point3::origin(), r)],
        Shape::Capsule {
            radius,
            half_length,
        } => along_z(radius, half_length),
        // Spheres inside the flat ends; the rims are covered within a few mm.
        Shape::Cylinder {
            radius,
            half_length,
        } => along_z(radius, (half_length - 0.5 * radius).max(0.0)),
        Shape::Box(h) => {
            // Spheres of the smallest half-extent on a grid over the other two.
            let (axis, r) = (0..3)
                .map(|i| (i, h[i]))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("three axes");
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let steps = |half: f64| ((2.0 * (half - r).max(0.0)) / (SPACING * r)).ceil() as usize;
            let (nu, nv) = (steps(h[u]), steps(h[v]));
            let mut out = Vec::new();
            for i in 0..=nu {
                for j in 0..=nv {
                    let mut p = Vector3::zeros();
                    let span = |half: f64, k: usize, n: usize| {
                        let half = (half - r).max(0.0);
                        if n == 0 {
                            0.0
                        } else {
                            -half + 2.0 * half * k as f64 / n as f64
                        }
                    };
                    p[u] = span(h[u], i, nu);
                    p[v] = span(h[v], j, nv);
                    out.push((Point3::from(p), r));
                }
            }
            out
        }
    }
}

/// The smallest sphere (m) covering a held object's thin parts: one sphere per 1.5 cm of a
/// plate's disc instead of one per 3 mm.
const HELD_SPHERE: f64 = 0.015;

/// Spheres (centre in the primitive's frame, radius) covering an object's primitive within a
/// few mm: over its two larger extents, each at least [`HELD_SPHERE`].
fn held_cover(shape: &Primitive) -> Vec<(Point3<f64>, f64)> {
    let (half, round) = match *shape {
        Primitive::Box { half_extents } => (half_extents, false),
        Primitive::Cylinder {
            radius,
            half_length,
        } => (Vector3::new(radius, radius, half_length), true),
    };
    let (axis, thin) = (0..3)
        .map(|i| (i, half[i]))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("three axes");
    let r = thin.max(HELD_SPHERE);
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let ticks = |h: f64| {
        let n = ((2.0 * (h - 0.5 * r).max(0.0)) / r).ceil() as usize;
        (0..=n).map(move |k| {
            if n == 0 {
                0.0
            } else {
                -(h - 0.5 * r) + 2.0 * (h - 0.5 * r) * k as f64 / n as f64
            }
        })
    };
    let mut out = Vec::new();
    for a in ticks(half[u]) {
        for b in ticks(half[v]) {
            // A disc's corners are empty.
            if round && (a * a + b * b).sqrt() > half[u] {
                continue;
            }
            let mut p = Vector3::zeros();
            p[u] = a;
            p[v] = b;
            out.push((Point3::from(p), r));
        }
    }
    out
}

/// An arena part as an oriented box (a cylinder by its bounding box).
fn solid(part: &Placed) -> Solid {
    let half = match part.shape {
        Primitive::Box { half_extents } => half_extents,
        Primitive::Cylinder {
            radius,
            half_length,
        } => Vector3::new(radius, radius, half_length),
    };
    Solid {
        inverse_pose: part.pose.inverse(),
        half,
        centre: Point3::from(part.pose.translation.vector),
        circumradius: half.norm(),
    }
}

/// Whether `box_distance(solid, p)` is surely at least `least` (m), from the sphere through the
/// box's corners alone: the box lies inside that sphere, so no point of it is nearer to `p` than
/// `|p − centre| − circumradius` (and inside the box that is at most the box's own negative
/// distance, whose magnitude is at most the smallest half-extent). Squared, without a root;
/// `BOUND_SLACK` covers the rounding of both sides, so a `true` never hides a distance that
/// `box_distance` would compute below `least`. [`Clearance::near`] skips the solids it rules out
/// — most of an arena, for any one run of spheres — with the same answers bit for bit, for a
/// few multiplications instead of a rotation. (Among the near solids the test rarely rules one
/// out, and costs more than it saves there.)
fn surely_beyond(solid: &Solid, p: &Point3<f64>, least: f64) -> bool {
    let reach = least + solid.circumradius + BOUND_SLACK;
    reach < 0.0 || (p - solid.centre).norm_squared() > reach * reach
}

/// Signed distance from `p` to the box (negative inside).
fn box_distance(solid: &Solid, p: &Point3<f64>) -> f64 {
    let local = solid.inverse_pose * p;
    let d = local.coords.abs() - solid.half;
    let outside = d.map(|x| x.max(0.0)).norm();
    let inside = d.max().min(0.0);
    outside + inside
}

/// The gap (m) the expert keeps between the arm and the arena where it has a choice.
pub(super) const MIN_CLEARANCE: f64 = 0.01;

/// Of `solutions` (best first), the first whose clearance is at least [`MIN_CLEARANCE`], else
/// the one with the most; with its clearance.
pub(super) fn best_clear(
    clearance: &Clearance,
    model: &RobotModel,
    solutions: Vec<[f64; ARM_DOF]>,
) -> Option<([f64; ARM_DOF], f64)> {
    let mut best: Option<([f64; ARM_DOF], f64)> = None;
    for q in solutions {
        let gap = clearance.at(model, &q);
        if gap >= MIN_CLEARANCE {
            return Some((q, gap));
        }
        if best.is_none_or(|(_, g)| gap > g) {
            best = Some((q, gap));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axes::{AxisElement, Robot};
    use crate::physics::robot_model;
    use crate::rng::Mt19937;

    /// Every sphere against every solid, as the clearance was computed before its groups
    /// skipped solids: the answers the pruned ones must equal bit for bit.
    fn exhaustive(c: &Clearance, model: &RobotModel, q: &[f64; ARM_DOF]) -> Vec<f64> {
        let poses = body_poses(model, q, [0.0, 0.0]);
        c.spheres
            .iter()
            .map(|s| {
                let centre = poses[s.body] * s.centre;
                c.solids
                    .iter()
                    .map(|solid| box_distance(solid, &centre) - s.radius)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    /// Random arm poses (within the joint limits, many close to the arena or in it) in every
    /// arena, bare, with the object placed and with it held: the smallest gap, the gap without
    /// the fingers, the crowding and `keeps` are what the exhaustive computation gives.
    #[test]
    fn the_corner_sphere_never_rules_out_a_nearer_box() {
        let mut rng = Mt19937::init_genrand(11);
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.random_sample();
        let (mut ruled_out, mut inside) = (0, 0);
        for _ in 0..20_000 {
            let half = Vector3::new(u(0.003, 0.4), u(0.003, 0.4), u(0.003, 0.4));
            let axis = Vector3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            let pose = Isometry3::new(Vector3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(0.0, 1.5)), axis);
            let solid = solid(&Placed {
                pose,
                shape: Primitive::Box { half_extents: half },
                ..arena_parts(Objective::PickPlace, Obstacle::NoObstacle)[0]
            });
            // Points near and inside the box as often as far from it.
            let local = Point3::new(
                u(-1.5, 1.5) * half.x,
                u(-1.5, 1.5) * half.y,
                u(-1.5, 1.5) * half.z,
            );
            let p = if u(0.0, 1.0) < 0.5 {
                pose * local
            } else {
                pose * local + axis * u(0.0, 2.0)
            };
            let distance = box_distance(&solid, &p);
            inside += usize::from(distance < 0.0);
            for least in [
                distance - 0.3,
                distance - 1e-6,
                distance - 1e-12,
                distance,
                distance + 1e-6,
            ] {
                if surely_beyond(&solid, &p, least) {
                    ruled_out += 1;
                    assert!(distance >= least, "{distance} ruled out below {least}");
                }
            }
        }
        // The test means something: many boxes ruled out, points inside boxes among them.
        assert!(
            ruled_out > 10_000 && inside > 2_000,
            "{ruled_out} ruled out, {inside} inside"
        );
    }

    #[test]
    fn skipping_far_solids_changes_no_answer() {
        let mut rng = Mt19937::init_genrand(7);
        let mut touching = 0;
        for robot in Robot::all() {
            let model = robot_model(robot);
            for objective in Objective::all() {
                for obstacle in Obstacle::all() {
                    let bare = Clearance::new(model, objective, obstacle);
                    let object = Isometry3::translation(-0.05, -0.25, 0.85);
                    let q0: [f64; ARM_DOF] = std::array::from_fn(|j| 0.3 * j as f64 - 0.6);
                    let variants = [
                        bare.with_object(Object::Dumbbell, &object),
                        bare.holding(model, &q0, Object::Plate, &object),
                        bare,
                    ];
                    for c in &variants {
                        for _ in 0..12 {
                            let q: [f64; ARM_DOF] = std::array::from_fn(|j| {
                                let (lo, hi) = model.joints[j].limits.unwrap_or((-3.0, 3.0));
                                lo + (hi - lo) * rng.random_sample()
                            });
                            let gaps = exhaustive(c, model, &q);
                            let smallest = gaps.iter().copied().fold(f64::INFINITY, f64::min);
                            touching += usize::from(smallest < 0.0);
                            assert_eq!(c.at(model, &q).to_bits(), smallest.to_bits());
                            let arm = gaps
                                .iter()
                                .zip(&c.spheres)
                                .filter(|(_, s)| !s.finger)
                                .map(|(g, _)| *g)
                                .fold(f64::INFINITY, f64::min);
                            assert_eq!(c.without_fingers(model, &q).to_bits(), arm.to_bits());
                            for margin in [0.02, 0.1] {
                                let crowding: f64 = gaps
                                    .iter()
                                    .zip(&c.spheres)
                                    .filter(|(_, s)| s.swings)
                                    .map(|(g, _)| (margin - g).max(0.0).powi(2))
                                    .sum();
                                let pruned = c.crowding(model, &q, margin);
                                assert_eq!(pruned.to_bits(), crowding.to_bits());
                            }
                            for least in [-0.02, 0.0, smallest, 0.01, 0.08] {
                                assert_eq!(c.keeps(model, &q, least), smallest >= least);
                            }
                        }
                    }
                }
            }
        }
        // Both sides of the answers were exercised.
        assert!(
            touching > 50 && touching < 1400,
            "{touching} of 1536 poses touch"
        );
    }

    /// Above the floors, the model keeps every solid but the bins' floors: a sphere sunk in bin
    /// 1's floor, with nothing else near, comes close only with the floors in; one on the goal
    /// wall's top comes just as close either way.
    #[test]
    fn above_the_floors_leaves_out_the_floors_and_only_them() {
        let (objective, obstacle) = (Objective::Push, Obstacle::GoalWall);
        let with = Clearance::new(robot_model(Robot::Iiwa), objective, obstacle);
        let above = Clearance::above_the_floors(robot_model(Robot::Iiwa), objective, obstacle);
        let floors = arena_parts(objective, obstacle)
            .iter()
            .filter(|p| p.collides && p.name.ends_with("/floor"))
            .count();
        assert_eq!(floors, 2, "bin 1's and bin 2's");
        assert_eq!(above.solids.len() + floors, with.solids.len());
        // A 1 cm sphere on the floor of bin 1, and one on the goal wall's top.
        let on_the_floor = Point3::new(0.1, -0.3, 0.825);
        let on_the_wall = Point3::new(0.0, -0.01, 1.105);
        let gap = |c: &Clearance, p: Point3<f64>| {
            c.solids
                .iter()
                .map(|solid| box_distance(solid, &p) - 0.01)
                .fold(f64::INFINITY, f64::min)
        };
        assert!(gap(&with, on_the_floor) < 0.0);
        assert!(gap(&above, on_the_floor) > 0.01);
        assert_eq!(gap(&with, on_the_wall), gap(&above, on_the_wall));
        assert!(gap(&above, on_the_wall) < 0.0);
    }
}
