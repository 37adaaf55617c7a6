//! Push: the object lifted just off the floor and slid along straight lines to the goal —
//! round the goal wall's free end where the wall stands between them, out from behind the
//! door — the gripper turning about the vertical on the last line where that keeps the arm
//! clear. Grasps whose lines keep clear are tried first.

use nalgebra::{Isometry3, Point3, Vector3};

use super::approach::{ApproachOption, PLANNED_OPTIONS};
use super::lines::{keeps_more, last_line, lines_through, smallest_gap, swinging_line};
use super::{LEAST_END_CLEARANCE, PlannedExpert, object_pose};
use crate::axes::Obstacle;
use crate::env::Env;
use crate::expert::clearance::Clearance;
use crate::expert::motion::pads_at;
use crate::expert::track::{Joints, Leg};

/// How far (m) the pads rise for a push: the object slides just off the floor, far under the
/// 0.9 m line whose crossing ends a Push episode.
pub(super) const PUSH_LIFT: f64 = 0.012;
/// The most (m) the pads rise from a side grasp for a push…
pub(super) const SIDE_PUSH_LIFT: f64 = 0.04;
/// …keeping the object's origin under this height (m; a Push episode ends above 0.9): the
/// dumbbell (origin 0.868 at rest) rises 1.2 cm.
pub(super) const PUSH_SIDE_TOP: f64 = 0.88;
/// The object must rise at least this far (m) with a push's lift for the grasp to count.
pub(super) const PUSH_RISE_CHECK: f64 = 0.006;
/// The goal wall's line (y, m; on the seam between the bins) and points past its free end
/// (which is at x 0.11) that a pushed object may go round by (x, m), in the order tried.
const GOAL_WALL_Y: f64 = -0.01;
const AROUND_GOAL_WALL_X: [f64; 3] = [0.22, 0.17, 0.26];
/// A push past the goal wall may first go along the wall to its lane (when the diagonal to the
/// lane comes closer to the wall) where the object is more than this (m) short of the lane.
const ALONG_THE_WALL_FIRST: f64 = 0.05;
/// The object's origin's height (m) on the way round the goal wall from a top grasp: as high as
/// a Push lets it (its episode ends above 0.9), so the forearm passes over the wall's end
/// higher. (A side grasp keeps its lift: the plate held by its rim tilts in the pads.)
const ROUND_THE_WALL_Z: f64 = 0.885;
/// Where a push round the goal wall may end (x, y offsets from the goal, m; success allows 3 cm):
/// the goal, or a little further from the wall's end, which the gripper of a side grasp then
/// clears more easily.
const GOAL_SHIFTS: [[f64; 2]; 2] = [[0.0, 0.0], [0.015, 0.015]];
/// What each metre by which a grasp's push lines come closer to the arena than
/// [`LEAST_END_CLEARANCE`] adds to its joint travel (rad) when grasps whose lines all come that
/// close are compared: 2 cm weighs as 0.8 rad (~5 s). Past the goal wall the cheapest grasp's
/// lines ran the Panda's hand 4 cm into the wall and the push stalled 6 cm short of the goal;
/// a grasp 0.02 rad dearer came 1.6 cm close. The 64 push tasks, seeds 0–9, by the weight:
/// 0 (the cheapest first) 552 episodes, 10 569, 20 576, 40 578, 80 577, 200 568.
const SHORTFALL_COST: f64 = 40.0;
/// Turns (rad) about the vertical the gripper may make on a push's last line, from past the
/// goal wall's end to the goal (a gripper that held the object from the object's side of the
/// wall otherwise ends reaching back across the wall's line, right by its end) or from behind
/// the door (where the gripper reached in through the opening).
const FINAL_TURNS: [f64; 7] = [0.0, 0.4, -0.4, 0.8, -0.8, 1.2, -1.2];

impl PlannedExpert {
    /// Push: the pads along straight lines that take the object, just off the floor, to the
    /// goal (round the goal wall's free end where the wall stands between them), the gripper
    /// as it is (past the goal wall, out from behind the door, or where the IK loses the line
    /// with the gripper as it is, it may turn about the vertical on the last line), the elbow
    /// swung away from the arena where it comes close.
    pub(super) fn plan_slide(&mut self, env: &Env, q: Joints) -> Option<Vec<Leg>> {
        let carrying = self.carrying(env, &q);
        let top_down = self.grasp.as_ref().is_some_and(|g| g.top_down);
        self.slide_lines(env, &carrying, top_down, q, &object_pose(env))
            .map(|(_, legs)| legs)
    }

    /// [`Self::plan_slide`]'s lines from the arm at `q` holding the object at `pose` (held from
    /// above where `top_down`; the elbow swung clear of the arena as `carrying` says), with the
    /// smallest gap kept on them: straight to the goal, the arm's own (the held object rides
    /// just off the floor on purpose); round the goal wall, out from behind the door, or
    /// turning, the arm's and the object's from the arena above its floors.
    fn slide_lines(
        &self,
        env: &Env,
        carrying: &Clearance,
        top_down: bool,
        q: Joints,
        pose: &Isometry3<f64>,
    ) -> Option<(f64, Vec<Leg>)> {
        let model = env.world().model;
        let object = Point3::from(pose.translation.vector);
        let goal = env.goal();
        let (pad, orientation) = pads_at(model, &q);
        let offset = pad - object.coords;
        let round_the_wall = self.task.obstacle == Obstacle::GoalWall
            && goal.y > GOAL_WALL_Y
            && object.y < GOAL_WALL_Y;
        if !round_the_wall && self.task.obstacle != Obstacle::ObjectDoor {
            let to = Vector3::new(goal.x, goal.y, object.z) + offset;
            if let Some(points) = swinging_line(model, carrying, q, pad, to, orientation) {
                let gap = smallest_gap(model, &self.clearance, &points);
                return Some((gap, vec![Leg::new(points)]));
            }
            // The IK loses the straight line with the gripper held as it is: the same line,
            // the gripper turning on the way, below.
        }
        let walls = &self
            .above_the_floors
            .holding(model, &q, self.task.object, pose);
        // Routes to where the last line to the goal starts, that line's ends, and the object's
        // height on the way. Past the goal wall, round its free end: diagonally to one of the
        // lanes past the end, else first along the wall (at the object's distance from it) to
        // the lane and then across the wall's line; a top-grasped object as high as a push
        // allows; the last line ends at the goal or a little beyond it. Out from behind the
        // door (the gripper reached in through the opening), or where the straight line with
        // the gripper as it is was lost, straight there.
        let (z, routes, ends) = if round_the_wall {
            let z = if top_down {
                object.z.max(ROUND_THE_WALL_Z)
            } else {
                object.z
            };
            let routes = [false, true]
                .into_iter()
                .flat_map(|along| AROUND_GOAL_WALL_X.map(|x| (x, along)))
                .filter(|&(x, along)| !along || object.x < x - ALONG_THE_WALL_FIRST)
                .map(|(x, along)| {
                    let mut stops = Vec::new();
                    if along {
                        stops.push(Vector3::new(x, object.y, z));
                    }
                    stops.push(Vector3::new(x, GOAL_WALL_Y, z));
                    stops
                })
                .collect::<Vec<_>>();
            (z, routes, &GOAL_SHIFTS[..])
        } else {
            (object.z, vec![Vec::new()], &[[0.0, 0.0]][..])
        };
        // On the last line the gripper may turn about the vertical so that it ends clear of the
        // wall's end (it held the object from the object's side of the wall) or of the door's
        // post. The first lines that keep clear, else those that come least close (the model's
        // spheres are rounder than the links: a few mm in is often no contact).
        let mut best: Option<(f64, Vec<Leg>)> = None;
        for stops in routes {
            let Some((on_the_way, legs)) =
                lines_through(model, carrying, walls, q, pad, offset, orientation, &stops)
            else {
                continue;
            };
            let from = legs.last().map_or(q, Leg::end);
            let from_object = stops.last().copied().unwrap_or(object.coords);
            for (&[dx, dy], &turn) in ends
                .iter()
                .flat_map(|shift| FINAL_TURNS.iter().map(move |turn| (shift, turn)))
            {
                let to = Vector3::new(goal.x + dx, goal.y + dy, z);
                let line = (from_object, to);
                let Some(points) =
                    last_line(model, carrying, from, line, offset, orientation, turn)
                else {
                    continue;
                };
                let gap = on_the_way.min(smallest_gap(model, walls, &points));
                let mut all = legs.clone();
                all.push(Leg::new(points));
                if gap >= LEAST_END_CLEARANCE {
                    return Some((gap, all));
                }
                if keeps_more(&best, gap, turn == 0.0 && dx == 0.0 && dy == 0.0) {
                    best = Some((gap, all));
                }
            }
        }
        best
    }

    /// `options` as [`Self::clear_slides_first`] orders them where the objective is Push (it
    /// goes on from the grasp in straight lines), else as they are.
    pub(super) fn pushes_clear_first(
        &self,
        env: &Env,
        options: Vec<ApproachOption>,
    ) -> Vec<ApproachOption> {
        if self.pushing() {
            self.clear_slides_first(env, options, PLANNED_OPTIONS).0
        } else {
            options
        }
    }

    /// The first `looked_at` of `options` (cheapest first), those from whose grasp the push's
    /// straight lines keep the arm clear first (behind the object wall a gripper pointing
    /// towards bin 2 can leave the wrist over the wall, and the push then drags it along the
    /// wall), cheapest first; then the others by their cost with how close their lines come
    /// added ([`SHORTFALL_COST`]), those with no lines last; and whether any keeps clear.
    pub(super) fn clear_slides_first(
        &self,
        env: &Env,
        options: Vec<ApproachOption>,
        looked_at: usize,
    ) -> (Vec<ApproachOption>, bool) {
        let model = env.world().model;
        let pose = object_pose(env);
        let mut ranked: Vec<(bool, f64, ApproachOption)> = options
            .into_iter()
            .take(looked_at)
            .map(|option| {
                let grasped = *option.descent.last().expect("a point");
                let carrying = self
                    .clearance
                    .holding(model, &grasped, self.task.object, &pose);
                let gap = self
                    .slide_lines(env, &carrying, option.grasp.top_down, grasped, &pose)
                    .map_or(f64::NEG_INFINITY, |(gap, _)| gap);
                let clear = gap >= LEAST_END_CLEARANCE;
                // No lines at all count as a metre short.
                let shortfall = (LEAST_END_CLEARANCE - gap).clamp(0.0, 1.0);
                (clear, option.cost + SHORTFALL_COST * shortfall, option)
            })
            .collect();
        ranked.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)));
        let any = ranked.first().is_some_and(|(clear, _, _)| *clear);
        (
            ranked.into_iter().map(|(_, _, option)| option).collect(),
            any,
        )
    }
}
