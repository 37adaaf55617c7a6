//! CompoSuite-ROS patch: per-step vectors refilled in their own storage (allocated only when
//! their length changes), so a physics step allocates nothing.

use crate::math::DVector;

/// `vector` as `len` zeros.
pub(crate) fn zero_in_place(vector: &mut DVector, len: usize) {
    if vector.len() == len {
        vector.as_mut_slice().fill(0.0); // a memset, not nalgebra's entry-by-entry fill
    } else {
        *vector = DVector::zeros(len);
    }
}

/// `to` as a copy of `from`.
pub(crate) fn copy_in_place(to: &mut DVector, from: &DVector) {
    if to.len() == from.len() {
        to.as_mut_slice().copy_from_slice(from.as_slice()); // a memcpy
    } else {
        *to = from.clone();
    }
}
