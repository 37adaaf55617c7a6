//! Trash can: the object carried (`carry.rs`) to above the can and let go; a side grasp backs
//! out level before it rises, turning where the straight way out meets the arena.

use nalgebra::{UnitQuaternion, Vector3};

use super::lines::{keeps_more, line, smallest_gap};
use super::{LEAST_END_CLEARANCE, PlannedExpert, RETREAT};
use crate::expert::track::Joints;
use crate::physics::RobotModel;

/// Turns (rad) about the vertical of a side grasp's way out over the trash can, tried in this
/// order where backing straight out comes close to the arena ([`PlannedExpert::back_out`]).
const BACK_OUT_TURNS: [f64; 5] = [0.0, 0.5, -0.5, 1.0, -1.0];

impl PlannedExpert {
    /// A side grasp's way out over the trash can, the pads from `pad` along `away` (level,
    /// back along the gripper): a dumbbell hangs on the open fingers by its upper disc until
    /// they back out from under it. Where that line comes closer to the arena above its floors
    /// than [`LEAST_END_CLEARANCE`] (past the goal wall the wrist backs into the wall), the way
    /// out turns about the vertical ([`BACK_OUT_TURNS`]): the first line that keeps clear, else
    /// the one that comes least close (a turned one by [`TURN_GAIN`] more than the straight).
    pub(super) fn back_out(
        &self,
        model: &RobotModel,
        q: Joints,
        pad: Vector3<f64>,
        away: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Option<Vec<Joints>> {
        let mut best: Option<(f64, Vec<Joints>)> = None;
        for turn in BACK_OUT_TURNS {
            let way = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn) * away;
            let Some(points) = line(model, q, pad, pad + way * RETREAT, orientation) else {
                continue;
            };
            let gap = smallest_gap(model, &self.above_the_floors, &points[1..]);
            if gap >= LEAST_END_CLEARANCE {
                return Some(points);
            }
            if keeps_more(&best, gap, turn == 0.0) {
                best = Some((gap, points));
            }
        }
        best.map(|(_, points)| points)
    }
}
