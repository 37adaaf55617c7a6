//! Conversions between nalgebra's f64 poses and vectors and rapier's own.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude::*;

pub(super) fn to_vec(v: &Vector3<f64>) -> Vector {
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
