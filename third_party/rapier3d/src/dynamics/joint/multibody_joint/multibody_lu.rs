//! CompoSuite-ROS patch: the LU factorisation of a multibody's mass matrix, kept in the
//! multibody and refactorised in place every step.
//!
//! The release built a fresh `nalgebra::LU` twice per step (a copy of the matrix and a new
//! permutation sequence each: four heap allocations per step). This one keeps its storage and
//! allocates only when the number of DoFs changes. It runs nalgebra 0.35's algorithm operation
//! for operation — partial pivoting on the first largest |entry| of the column, the column
//! below the pivot scaled by the pivot's inverse, then each later column updated by
//! `y = a·x + y` — so factors and solutions are the same bit for bit.

use crate::alloc_prelude::*;
use crate::math::Real;
use na::{DMatrix, Dyn, Matrix, StorageMut, U1};

/// `P·M = L·U` of a square matrix, with `L` unit lower-triangular; both factors share one
/// matrix, as nalgebra's `LU` keeps them.
#[derive(Clone, Debug)]
pub struct MultibodyLu {
    lu: DMatrix<Real>,
    /// Row swaps `(i, pivot)` in the order they were made.
    swaps: Vec<(usize, usize)>,
}

impl Default for MultibodyLu {
    fn default() -> Self {
        MultibodyLu {
            lu: DMatrix::zeros(0, 0),
            swaps: Vec::new(),
        }
    }
}

/// Systems up to this size are solved in a stack copy of the right-hand side (a 9-DoF arm and
/// gripper is 9), larger ones in a heap copy (allocated per solve).
const STACK_DIM: usize = 32;

impl MultibodyLu {
    /// Factorises the leading `dim × dim` block of `m`, reusing this factorisation's storage.
    pub fn factorise(&mut self, m: &DMatrix<Real>, dim: usize) {
        if self.lu.shape() != (dim, dim) {
            self.lu = DMatrix::zeros(dim, dim);
            self.swaps = Vec::with_capacity(dim);
        }
        if dim == m.nrows() {
            // One `memcpy` (nalgebra's `copy_from` copies entry by entry).
            self.lu.as_mut_slice().copy_from_slice(m.as_slice());
        } else {
            self.lu.copy_from(&m.view((0, 0), (dim, dim)));
        }
        self.swaps.clear();

        // Column-major: entry (r, c) is `data[c * dim + r]`, a column is one slice.
        let data = self.lu.as_mut_slice();
        for i in 0..dim {
            // The first row holding the column's largest |entry| (nalgebra's `icamax`).
            let column = &data[i * dim..(i + 1) * dim];
            let mut pivot = i;
            let mut largest = column[i].abs();
            for (r, value) in column.iter().enumerate().skip(i + 1) {
                // Selects, not a branch: which entry wins is data, and mispredicted.
                let magnitude = value.abs();
                let larger = magnitude > largest;
                largest = if larger { magnitude } else { largest };
                pivot = if larger { r } else { pivot };
            }
            let diag = column[pivot];
            if diag == 0.0 {
                continue; // No non-zero entry in this column.
            }
            if pivot != i {
                self.swaps.push((i, pivot));
                for c in 0..dim {
                    data.swap(c * dim + i, c * dim + pivot);
                }
            }
            let inv_diag = 1.0 / diag;
            for value in &mut data[i * dim + i + 1..(i + 1) * dim] {
                *value *= inv_diag;
            }
            // Column i's multipliers, then each later column k (in order) updated by them; the
            // split tells the compiler the two do not overlap, so it updates four rows at a time
            // (each row's own multiply and add, as before).
            let (done, later) = data.split_at_mut((i + 1) * dim);
            let multipliers = &done[i * dim + i + 1..];
            for column in later.chunks_exact_mut(dim) {
                let a = -column[i];
                for (value, l) in column[i + 1..].iter_mut().zip(multipliers) {
                    *value = a * l + *value;
                }
            }
        }
    }

    /// Solves `M·x = b` in place (`b` becomes `x`), as `nalgebra::LU::solve_mut`.
    pub fn solve_mut<S: StorageMut<Real, Dyn, U1>>(&self, b: &mut Matrix<Real, Dyn, U1, S>) {
        self.solve_from(b, 0);
    }

    /// Solves `M·x = e_k` into `out`: the same solution as [`Self::solve_mut`] of the unit
    /// vector. The permuted unit vector is built directly (its 1 where the row swaps take row
    /// `k`), and the forward substitution starts at that row — the rows before it stay exact
    /// zeros, so skipping them changes no bit.
    pub fn solve_unit<S: StorageMut<Real, Dyn, U1>>(
        &self,
        k: usize,
        out: &mut Matrix<Real, Dyn, U1, S>,
    ) {
        let dim = self.lu.nrows();
        assert_eq!(dim, out.nrows(), "LU solve dimension mismatch.");
        let first = self.unit_row(k);
        if dim > STACK_DIM {
            out.fill(0.0);
            out[k] = 1.0;
            self.solve_from(out, first);
            return;
        }
        let mut x = [0.0; STACK_DIM];
        x[first] = 1.0;
        self.substitute(&mut x[..dim], first);
        for (r, value) in x[..dim].iter().enumerate() {
            out[r] = *value;
        }
    }

    /// The row the row swaps move `e_k`'s 1 to.
    fn unit_row(&self, k: usize) -> usize {
        let mut row = k;
        for &(i, pivot) in &self.swaps {
            if row == i {
                row = pivot;
            } else if row == pivot {
                row = i;
            }
        }
        row
    }

    /// Every column of `M⁻¹` into `out` (dim × dim): column k is what [`Self::solve_unit`]
    /// gives for k, bit for bit. Four columns are solved side by side in the lanes of an
    /// `f32x4`, each lane running its column's substitutions in their order. A lane whose 1
    /// sits lower than its neighbours' runs the forward steps above it too, but there its
    /// entries are still `+0` or its 1, and adding `±0` to them changes nothing.
    pub fn solve_all_units(&self, out: &mut DMatrix<Real>) {
        use wide::f32x4;
        let dim = self.lu.nrows();
        assert_eq!(out.shape(), (dim, dim), "LU solve dimension mismatch.");
        if dim > STACK_DIM {
            for k in 0..dim {
                self.solve_unit(k, &mut out.column_mut(k));
            }
            return;
        }
        let data = self.lu.as_slice();
        for k0 in (0..dim).step_by(4) {
            let lanes = 4.min(dim - k0);
            let mut x = [[0.0 as Real; 4]; STACK_DIM];
            let mut start = dim;
            for lane in 0..lanes {
                let row = self.unit_row(k0 + lane);
                x[row][lane] = 1.0;
                start = start.min(row);
            }
            let mut x: [f32x4; STACK_DIM] = x.map(f32x4::from);
            let x = &mut x[..dim];
            for i in start..dim.saturating_sub(1) {
                let a = -x[i];
                let column = &data[i * dim..(i + 1) * dim];
                for r in i + 1..dim {
                    x[r] = a * f32x4::splat(column[r]) + x[r];
                }
            }
            for i in (0..dim).rev() {
                let diag = data[i * dim + i];
                if diag == 0.0 {
                    break; // Singular: `substitute` stops here too.
                }
                let coeff = x[i] / f32x4::splat(diag);
                x[i] = coeff;
                let a = -coeff;
                let column = &data[i * dim..i * dim + i];
                for r in 0..i {
                    x[r] = a * f32x4::splat(column[r]) + x[r];
                }
            }
            for (r, value) in x.iter().enumerate() {
                let value = value.to_array();
                for lane in 0..lanes {
                    out[(r, k0 + lane)] = value[lane];
                }
            }
        }
    }

    /// Solves in a copy of `b` (on the stack up to [`STACK_DIM`]) with contiguous slices, the
    /// forward substitution from row `first` of the permuted vector.
    fn solve_from<S: StorageMut<Real, Dyn, U1>>(
        &self,
        b: &mut Matrix<Real, Dyn, U1, S>,
        first: usize,
    ) {
        let dim = self.lu.nrows();
        assert_eq!(dim, b.nrows(), "LU solve dimension mismatch.");
        let mut stack = [0.0; STACK_DIM];
        let mut heap = Vec::new();
        let x = if dim <= STACK_DIM {
            &mut stack[..dim]
        } else {
            heap.resize(dim, 0.0);
            &mut heap[..]
        };
        for (r, value) in x.iter_mut().enumerate() {
            *value = b[r];
        }
        self.permute_and_substitute(x, first);
        for (r, value) in x.iter().enumerate() {
            b[r] = *value;
        }
    }

    /// The row swaps, then [`Self::substitute`].
    fn permute_and_substitute(&self, x: &mut [Real], first: usize) {
        for &(i, pivot) in &self.swaps {
            x.swap(i, pivot);
        }
        self.substitute(x, first);
    }

    /// Forward substitution with `L` (from row `first`), then back substitution with `U`, each
    /// update `y = a·x + y` as nalgebra's `axpy` takes it.
    fn substitute(&self, x: &mut [Real], first: usize) {
        let dim = x.len();
        let data = self.lu.as_slice();
        assert!(data.len() == dim * dim);
        // SAFETY (both loops): i, r < dim, so indices into `data` are < dim * dim and into `x`
        // < dim.
        for i in first..dim.saturating_sub(1) {
            unsafe {
                let a = -*x.get_unchecked(i);
                for r in i + 1..dim {
                    let l = *data.get_unchecked(i * dim + r);
                    let value = x.get_unchecked_mut(r);
                    *value = a * l + *value;
                }
            }
        }
        for i in (0..dim).rev() {
            let diag = data[i * dim + i];
            if diag == 0.0 {
                return; // Singular: nalgebra stops here too.
            }
            let coeff = x[i] / diag;
            x[i] = coeff;
            let a = -coeff;
            unsafe {
                for r in 0..i {
                    let u = *data.get_unchecked(i * dim + r);
                    let value = x.get_unchecked_mut(r);
                    *value = a * u + *value;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MultibodyLu;
    use crate::alloc_prelude::*;
    use crate::math::Real;
    use crate::utils::test_values as values;
    use na::{DMatrix, DVector};

    /// A fixed pseudo-random stream, so the test needs no dependency.
    #[test]
    fn factors_and_solutions_equal_nalgebras_bit_for_bit() {
        let mut lu = MultibodyLu::default();
        for (seed, dim) in [(1, 9), (2, 9), (3, 7), (4, 1), (5, 12), (6, 9), (7, 40)] {
            let m = DMatrix::from_vec(dim, dim, values(seed, dim * dim));
            // Symmetric positive definite, as a mass matrix is, and a general one.
            let spd = &m * m.transpose() + DMatrix::identity(dim, dim) * 0.1;
            for matrix in [m, spd] {
                lu.factorise(&matrix, dim);
                let theirs = na::LU::new(matrix.clone());
                let b = DVector::from_vec(values(seed + 100, dim));
                let (mut ours_x, mut theirs_x) = (b.clone(), b.clone());
                lu.solve_mut(&mut ours_x);
                assert!(theirs.solve_mut(&mut theirs_x));
                assert_eq!(ours_x.as_slice(), theirs_x.as_slice(), "dim {dim}");
                let mut all = DMatrix::zeros(dim, dim);
                lu.solve_all_units(&mut all);
                for k in 0..dim {
                    let mut ours_e = DVector::zeros(dim);
                    lu.solve_unit(k, &mut ours_e);
                    let mut theirs_e = DVector::zeros(dim);
                    theirs_e[k] = 1.0;
                    assert!(theirs.solve_mut(&mut theirs_e));
                    let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&ours_e), bits(&theirs_e), "dim {dim}, column {k}");
                    let column: DVector<Real> = all.column(k).into_owned();
                    assert_eq!(
                        bits(&column),
                        bits(&theirs_e),
                        "all units: dim {dim}, column {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_leading_block_is_factorised_when_dofs_are_removed() {
        let m = DMatrix::from_vec(4, 4, values(9, 16));
        let mut lu = MultibodyLu::default();
        lu.factorise(&m, 3);
        let theirs = na::LU::new(m.view((0, 0), (3, 3)).into_owned());
        let mut ours_x = DVector::from_row_slice(&[1.0, -2.0, 0.5]);
        let mut theirs_x = ours_x.clone();
        lu.solve_mut(&mut ours_x);
        theirs.solve_mut(&mut theirs_x);
        assert_eq!(ours_x, theirs_x);
    }
}
