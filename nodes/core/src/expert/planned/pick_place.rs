//! Pick-place: the object carried (`carry.rs`) to above bin 2 and lowered into it before it is
//! let go — success needs it below the bin's wall tops with the gripper near it.

use nalgebra::{Point3, UnitQuaternion, Vector3};

use super::lines::line;
use super::{PlannedExpert, top_of};
use crate::arena::object_geometry;
use crate::axes::Objective;
use crate::env::Env;
use crate::expert::motion::{pad_ik_solutions, pads_at};
use crate::expert::track::{Joints, Leg};
use crate::physics::RobotModel;

/// Where the object's origin is lowered to in bin 2 (m): 3 cm under the 0.9 m line below which
/// it counts as in the bin.
const IN_BIN_Z: f64 = 0.87;
/// Where it is lowered to where the IK loses the line to [`IN_BIN_Z`] (m): just under the line.
const SHALLOW_IN_BIN_Z: f64 = 0.893;
/// Where the IK loses that line too, the parts of it tried in turn: let go lower, the object
/// bounces less. Past the goal wall the Gen3's and the Panda's side-grasped dumbbells ended
/// their carry ~9 cm above the line with no IK down to it and, let go there, bounced out (the
/// 64 pick-place tasks, seeds 0–9: 593 of 640 episodes without any of this, 595 with the
/// shallow line alone, 600 with these parts; with 0.8, 0.6, 0.4 and 0.2 of it, 598).
const SHALLOW_PARTS: [f64; 3] = [1.0, 0.66, 0.33];

/// How high (m) above the object's origin the pads go back to where the object lies in bin 2
/// but out of the gripper's reach (success needs the gripper within 7.75 cm of it).
const BACK_OVER_IT: f64 = 0.045;

impl PlannedExpert {
    /// The pads to just over the object (origin at `object`) where it fell into bin 2 before it
    /// was let go, or rolled away after, and the retreat left the gripper out of its reach: a
    /// straight line with the gripper as it is, else a planned path with the gripper as it is
    /// or pointing straight down. Whether a way was found (and started).
    pub(super) fn back_over_the_object(
        &mut self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
    ) -> bool {
        let model = env.world().model;
        let (pad, orientation) = pads_at(model, &q);
        let over = object.coords + Vector3::z() * BACK_OVER_IT;
        if let Some(points) = line(model, q, pad, over, orientation) {
            self.start(Leg::new(points));
            return true;
        }
        // No straight line (the arm stretched, or a joint at its limit): a path to the pose,
        // the gripper as it is or pointing straight down.
        let down = UnitQuaternion::rotation_between(&(orientation * Vector3::z()), &-Vector3::z())
            .map(|turn| turn * orientation);
        let clearance = self.clearance.clone();
        for turned in std::iter::once(orientation).chain(down) {
            for end in pad_ik_solutions(model, &q, over, turned)
                .into_iter()
                .take(3)
            {
                if let Some(path) = self.plan_path(env, model, &clearance, q, end) {
                    self.start(Leg::new(path));
                    return true;
                }
            }
        }
        false
    }

    /// Down into bin 2 from above it, the object (origin at `object`) still held: to
    /// [`IN_BIN_Z`], no lower than 1 cm above the bin's floor; where the IK loses that line,
    /// to [`SHALLOW_IN_BIN_Z`] or part of the way there ([`SHALLOW_PARTS`]); else held.
    pub(super) fn lower_into_bin2(&mut self, model: &RobotModel, q: Joints, object: Point3<f64>) {
        // Success needs the object below bin 2's wall tops with the gripper near it:
        // lowered there, not dropped.
        let bottom = object_geometry(self.task.object).bottom_offset;
        let (pad, orientation) = pads_at(model, &q);
        let floor = top_of(Objective::PickPlace, "bin2/floor");
        let floor_gap = object.z + bottom - (floor + 0.01);
        let depth = (object.z - IN_BIN_Z).clamp(0.0, floor_gap.max(0.0));
        let shallow = (object.z - SHALLOW_IN_BIN_Z).clamp(0.0, depth);
        let depths = std::iter::once(depth).chain(SHALLOW_PARTS.map(|part| part * shallow));
        for depth in depths {
            if let Some(points) = line(model, q, pad, pad - Vector3::z() * depth, orientation) {
                self.start(Leg::new(points));
                return;
            }
        }
        self.hold(q);
    }
}
