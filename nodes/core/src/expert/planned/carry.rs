//! The carry of pick-place and the trash can: a planned path, the object held, from just off
//! the floor to above where it is let go, its bottom clear of the walls it drops over.

use nalgebra::{UnitQuaternion, Vector3};

use super::{LEAST_END_CLEARANCE, PlannedExpert, quicker, top_of};
use crate::arena::{ROBOT_BASE_POSITION, TRASH_CAN, object_geometry};
use crate::axes::{Object, Objective};
use crate::env::Env;
use crate::expert::motion::{level_pointing, pad_ik, pad_ik_solutions, pads_at};
use crate::expert::track::{Joints, joint_distance};

/// How far (m) the object's bottom is above the walls of what it is dropped into.
const DROP_CLEARANCE: f64 = 0.03;
/// How far (m) short of the trash can's centre the dumbbell is let go, back along the way the
/// gripper points (level). Held by its bar, it hangs by its upper disc on the opened fingers
/// and tips off them as they back out: from the centre it was dragged towards the can's near
/// wall and wedged there, above the can's 0.93 m line (the Panda's past the goal wall 4 of 10
/// episodes); from nearer that wall it tips the other way, into the can. The 16 dumbbell
/// trash-can tasks, seeds 0–9, by the distance: 0 145 of 160 episodes, 1 cm 151, 2 cm 152,
/// 3 cm 150, 4 cm 148; past the centre instead, 1.2 cm 138, 2.5 cm 122.
const DUMBBELL_CAN_SHORT: f64 = 0.02;
/// An end of the carry closer to the arena than this (m) counts [`CLOSE_END_COST`] more joint
/// travel (rad): the arm, lagging a few mm behind its path with the object's weight, stalls on
/// a wall it ends on (the Gen3 over the trash can, its forearm on the goal wall's top at 1.10 m,
/// let the dumbbell go short of the can, onto its rim). The 128 pick-place and trash-can tasks
/// on seeds 0–9, by the extra cost: none 1196 episodes, 0.2 rad 1200, 0.4 rad 1207, 0.8 rad
/// 1202, the clear ends always first 1193 (their carries ran 2.4× longer past the goal wall).
const CARRY_END_CLEARANCE: f64 = 0.01;
/// See [`CARRY_END_CLEARANCE`].
const CLOSE_END_COST: f64 = 0.4;
/// Turns (rad) of the gripper about the vertical tried for the carry's end, besides the turn
/// of the arm's base from the object to the goal.
const CARRY_TURNS: [f64; 17] = [
    0.0, -0.3, 0.3, -0.6, 0.6, -0.9, 0.9, -1.2, 1.2, -1.5, 1.5, -1.9, 1.9, -2.4, 2.4, -2.8, 2.8,
];

impl PlannedExpert {
    /// The height (m) of the object's bottom where it is let go: just over bin 2's walls or
    /// the trash can's.
    fn drop_bottom(&self) -> f64 {
        let top = match self.task.objective {
            Objective::TrashCan => top_of(Objective::TrashCan, "trash_can/"),
            _ => top_of(Objective::PickPlace, "bin2/wall"),
        };
        top + DROP_CLEARANCE
    }

    /// How far (a level vector, m) from the goal the object is let go, short of it along the
    /// way a gripper at `orientation` points: the dumbbell over the trash can
    /// ([`DUMBBELL_CAN_SHORT`]); otherwise nothing.
    fn let_go_short(&self, orientation: &UnitQuaternion<f64>) -> Vector3<f64> {
        if self.task.objective != Objective::TrashCan || self.task.object != Object::Dumbbell {
            return Vector3::zeros();
        }
        match level_pointing(orientation).try_normalize(1e-6) {
            Some(level) => level * DUMBBELL_CAN_SHORT,
            None => Vector3::zeros(),
        }
    }

    /// A free path, the object carried, from just off the floor to where it is let go: above
    /// the goal (the dumbbell a little short of the trash can's centre, [`Self::let_go_short`]),
    /// its bottom clear of what it drops into. Of the turns of the gripper about the
    /// vertical, the one moving the joints least, an end close to the arena counted dearer.
    pub(super) fn plan_carry(&mut self, env: &Env, q: Joints) -> Option<Vec<Joints>> {
        let model = env.world().model;
        let carrying = self.carrying(env, &q);
        let (pad, orientation) = pads_at(model, &q);
        let object_now = pad - self.held;
        let origin_z = self.drop_bottom() - object_geometry(self.task.object).bottom_offset;
        let goal = match self.task.objective {
            Objective::TrashCan => {
                let [x, y, _] = TRASH_CAN.position;
                Vector3::new(x, y, origin_z)
            }
            _ => {
                let g = env.goal();
                Vector3::new(g.x, g.y, origin_z)
            }
        };
        // The base's own turn from the object to the goal turns the gripper with it.
        let [bx, by, _] = ROBOT_BASE_POSITION;
        let base_turn =
            (goal.y - by).atan2(goal.x - bx) - (object_now.y - by).atan2(object_now.x - bx);
        let mut ends: Vec<(f64, Joints)> = Vec::new();
        for extra in CARRY_TURNS {
            let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), base_turn + extra);
            let orientation_end = turn * orientation;
            let drop = goal - self.let_go_short(&orientation_end);
            let pad_end = drop + turn * self.held;
            // The quicker variant of `solved`, kept as an end where it keeps clear.
            let mut keep = |solved: Joints| {
                let (solved, gap) = quicker(model, &carrying, &q, solved, pad_end, orientation_end);
                let clear = gap >= LEAST_END_CLEARANCE;
                if clear {
                    let close = if gap < CARRY_END_CLEARANCE {
                        CLOSE_END_COST
                    } else {
                        0.0
                    };
                    ends.push((joint_distance(&q, &solved) + close, solved));
                }
                clear
            };
            let (solved, met) = pad_ik(model, &q, pad_end, orientation_end);
            if met && keep(solved) {
                continue;
            }
            // The IK from here finds one way of holding that pose: where it meets the arena
            // (or nothing), look for the others.
            for solved in pad_ik_solutions(model, &q, pad_end, orientation_end)
                .into_iter()
                .take(3)
            {
                keep(solved);
            }
        }
        ends.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (_, end) in ends.into_iter().take(3) {
            if let Some(path) = self.plan_path(env, model, &carrying, q, end) {
                return Some(path);
            }
        }
        None
    }
}
