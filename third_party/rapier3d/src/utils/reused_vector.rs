//! CompoSuite-ROS patch: per-step vectors refilled in their own storage (allocated only when
//! their length changes), so a physics step allocates nothing.

use crate::alloc_prelude::*;
use crate::math::DVector;

/// Below this many bytes, glibc's `memset` on a CPU with AVX-512 writes with one masked vector
/// store, which stalls on AMD Zen 4: on the machine this was measured on, the ~15 such calls
/// of a physics step (9-entry vectors, empty-table clears, short masks) cost ~3 % of it.
const MASKED_MEMSET_BYTES: usize = 64;

/// CompoSuite-ROS patch: every entry of `slice` set to `value`; a slice shorter than
/// [`MASKED_MEMSET_BYTES`] entry by entry with volatile stores (which the compiler cannot merge
/// back into a `memset` call), a longer one by `fill` (a `memset` for zeros).
#[inline]
pub fn fill_entries<T: Copy>(slice: &mut [T], value: T) {
    if is_short(slice) {
        for entry in slice {
            // SAFETY: `entry` is a valid, aligned, exclusive reference.
            unsafe { core::ptr::write_volatile(entry, value) };
        }
    } else {
        slice.fill(value);
    }
}

/// Whether `memset` would clear `slice` with a masked store (see [`MASKED_MEMSET_BYTES`]).
fn is_short<T>(slice: &[T]) -> bool {
    core::mem::size_of_val(slice) < MASKED_MEMSET_BYTES
}

/// CompoSuite-ROS patch: `Vec::resize(len, value)` with the added entries written as
/// [`fill_entries`] writes (`resize` fills them with a `memset`).
pub fn resize_entries<T: Copy>(vector: &mut Vec<T>, len: usize, value: T) {
    let old_len = vector.len();
    if len <= old_len {
        vector.truncate(len);
        return;
    }
    vector.reserve(len - old_len);
    let added = &mut vector.spare_capacity_mut()[..len - old_len];
    // Written through `MaybeUninit` (no reference to an uninitialised `T` is made).
    if is_short(added) {
        for slot in added {
            // SAFETY: `slot` is a valid, aligned, exclusive place for a `T`.
            unsafe { core::ptr::write_volatile(slot.as_mut_ptr(), value) };
        }
    } else {
        for slot in added {
            slot.write(value);
        }
    }
    // SAFETY: the entries up to `len` are initialised (above) and within the capacity.
    unsafe { vector.set_len(len) };
}

/// `vector` as `len` zeros.
pub(crate) fn zero_in_place(vector: &mut DVector, len: usize) {
    if vector.len() == len {
        fill_entries(vector.as_mut_slice(), 0.0); // not nalgebra's entry-by-entry fill
    } else {
        *vector = DVector::zeros(len);
    }
}
