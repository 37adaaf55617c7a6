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

impl MultibodyLu {
    /// Factorises the leading `dim × dim` block of `m`, reusing this factorisation's storage.
    pub fn factorise(&mut self, m: &DMatrix<Real>, dim: usize) {
        if self.lu.shape() != (dim, dim) {
            self.lu = DMatrix::zeros(dim, dim);
            self.swaps = Vec::with_capacity(dim);
        }
        if dim == m.nrows() {
            self.lu.copy_from(m);
        } else {
            self.lu.copy_from(&m.view((0, 0), (dim, dim)));
        }
        self.swaps.clear();

        let lu = &mut self.lu;
        for i in 0..dim {
            // The first row holding the column's largest |entry| (nalgebra's `icamax`).
            let mut pivot = i;
            let mut largest = lu[(i, i)].abs();
            for r in i + 1..dim {
                let value = lu[(r, i)].abs();
                if value > largest {
                    largest = value;
                    pivot = r;
                }
            }
            let diag = lu[(pivot, i)];
            if diag == 0.0 {
                continue; // No non-zero entry in this column.
            }
            if pivot != i {
                self.swaps.push((i, pivot));
                lu.swap_rows(i, pivot);
            }
            let inv_diag = 1.0 / diag;
            for r in i + 1..dim {
                lu[(r, i)] *= inv_diag;
            }
            for k in i + 1..dim {
                let a = -lu[(i, k)];
                for r in i + 1..dim {
                    lu[(r, k)] = a * lu[(r, i)] + lu[(r, k)];
                }
            }
        }
    }

    /// Solves `M·x = b` in place (`b` becomes `x`), as `nalgebra::LU::solve_mut`.
    pub fn solve_mut<S: StorageMut<Real, Dyn, U1>>(&self, b: &mut Matrix<Real, Dyn, U1, S>) {
        self.solve_from(b, 0);
    }

    /// Solves `M·x = e_k` into `out`: the same solution as [`Self::solve_mut`] of the unit
    /// vector, with the forward substitution started at the row its 1 lands on — the rows
    /// before it stay exact zeros, so skipping them changes no bit.
    pub fn solve_unit<S: StorageMut<Real, Dyn, U1>>(
        &self,
        k: usize,
        out: &mut Matrix<Real, Dyn, U1, S>,
    ) {
        out.fill(0.0);
        out[k] = 1.0;
        for &(i, pivot) in &self.swaps {
            out.swap_rows(i, pivot);
        }
        let first = (0..out.nrows()).find(|&r| out[r] != 0.0).unwrap_or(0);
        self.substitute(out, first);
    }

    fn solve_from<S: StorageMut<Real, Dyn, U1>>(
        &self,
        b: &mut Matrix<Real, Dyn, U1, S>,
        first: usize,
    ) {
        assert_eq!(self.lu.nrows(), b.nrows(), "LU solve dimension mismatch.");
        for &(i, pivot) in &self.swaps {
            b.swap_rows(i, pivot);
        }
        self.substitute(b, first);
    }

    /// Forward substitution with `L` (from row `first`), then back substitution with `U`.
    fn substitute<S: StorageMut<Real, Dyn, U1>>(
        &self,
        b: &mut Matrix<Real, Dyn, U1, S>,
        first: usize,
    ) {
        let lu = &self.lu;
        let dim = lu.nrows();
        for i in first..dim.saturating_sub(1) {
            let a = -b[i];
            for r in i + 1..dim {
                b[r] = a * lu[(r, i)] + b[r];
            }
        }
        for i in (0..dim).rev() {
            let diag = lu[(i, i)];
            if diag == 0.0 {
                return; // Singular: nalgebra stops here too.
            }
            let coeff = b[i] / diag;
            b[i] = coeff;
            let a = -coeff;
            for r in 0..i {
                b[r] = a * lu[(r, i)] + b[r];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MultibodyLu;
    use crate::alloc_prelude::*;
    use crate::math::Real;
    use na::{DMatrix, DVector};

    /// A fixed pseudo-random stream, so the test needs no dependency.
    fn values(seed: u64, n: usize) -> Vec<Real> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0) as Real
            })
            .collect()
    }

    #[test]
    fn factors_and_solutions_equal_nalgebras_bit_for_bit() {
        let mut lu = MultibodyLu::default();
        for (seed, dim) in [(1, 9), (2, 9), (3, 7), (4, 1), (5, 12), (6, 9)] {
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
                for k in 0..dim {
                    let mut ours_e = DVector::zeros(dim);
                    lu.solve_unit(k, &mut ours_e);
                    let mut theirs_e = DVector::zeros(dim);
                    theirs_e[k] = 1.0;
                    assert!(theirs.solve_mut(&mut theirs_e));
                    let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&ours_e), bits(&theirs_e), "dim {dim}, column {k}");
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
