//! Pick-place: the object carried (`carry.rs`) to above bin 2 and lowered into it before it is
//! let go — success needs it below the bin's wall tops with the gripper near it.

use nalgebra::{Point3, Vector3};

use super::lines::line;
use super::{PlannedExpert, top_of};
use crate::arena::object_geometry;
use crate::axes::Objective;
use crate::expert::motion::pads_at;
use crate::expert::track::{Joints, Leg};
use crate::physics::RobotModel;

/// Where the object's origin is lowered to in bin 2 (m): 3 cm under the 0.9 m line below which
/// it counts as in the bin.
const IN_BIN_Z: f64 = 0.87;

impl PlannedExpert {
    /// Down into bin 2 from above it, the object (origin at `object`) still held: to
    /// [`IN_BIN_Z`], no lower than 1 cm above the bin's floor.
    pub(super) fn lower_into_bin2(&mut self, model: &RobotModel, q: Joints, object: Point3<f64>) {
        // Success needs the object below bin 2's wall tops with the gripper near it:
        // lowered there, not dropped.
        let bottom = object_geometry(self.task.object).bottom_offset;
        let (pad, orientation) = pads_at(model, &q);
        let floor = top_of(Objective::PickPlace, "bin2/floor");
        let floor_gap = object.z + bottom - (floor + 0.01);
        let depth = (object.z - IN_BIN_Z).clamp(0.0, floor_gap.max(0.0));
        match line(model, q, pad, pad - Vector3::z() * depth, orientation) {
            Some(points) => self.start(Leg::new(points)),
            None => self.hold(q),
        }
    }
}
