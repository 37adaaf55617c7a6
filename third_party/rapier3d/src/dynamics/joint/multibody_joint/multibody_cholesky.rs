//! CompoSuite-ROS patch: the Cholesky factorisation `M = L·Lᵀ` of a multibody's (symmetric,
//! positive definite) mass matrix, kept in the multibody and refactorised in place every step.
//!
//! The release factorised two matrices per step with LU (the plain mass matrix for the
//! constraints, and a second one with semi-implicit Coriolis and gyroscopic blocks for the free
//! accelerations). With the Coriolis forces explicit (MuJoCo's `implicitfast` treatment, see
//! `Multibody::update_acceleration`) one symmetric matrix serves both, and Cholesky needs
//! half LU's work and no pivoting. The storage is kept between steps: nothing is allocated
//! unless the number of DoFs changes.

use crate::alloc_prelude::*;
use crate::math::Real;
use na::{DMatrix, Dyn, Matrix, StorageMut, U1};

/// `M = L·Lᵀ`, `L` lower-triangular with a positive diagonal (the upper triangle of the
/// storage is not read).
#[derive(Clone, Debug)]
pub struct MultibodyCholesky {
    l: DMatrix<Real>,
    /// `1 / L[i, i]`, so the substitutions multiply instead of divide.
    inv_diagonal: Vec<Real>,
    /// `M⁻¹ = L⁻ᵀ·L⁻¹`, formed once per factorisation: each solve is then one product by it
    /// (a 9-DoF arm's ~20 solves a step — free accelerations, motor, limit and friction rows,
    /// contact rows on links — share it), and its columns are the unit rows' `M⁻¹·e_k`.
    inverse: DMatrix<Real>,
    /// `L⁻¹` (lower-triangular), the step between the two.
    l_inv: DMatrix<Real>,
}

impl Default for MultibodyCholesky {
    fn default() -> Self {
        MultibodyCholesky {
            l: DMatrix::zeros(0, 0),
            inv_diagonal: Vec::new(),
            inverse: DMatrix::zeros(0, 0),
            l_inv: DMatrix::zeros(0, 0),
        }
    }
}

/// Systems up to this size are solved in a stack copy of the right-hand side (a 9-DoF arm and
/// gripper is 9), larger ones in a heap copy.
const STACK_DIM: usize = 32;

/// The size the factorisation and the solves are specialised for: a 7-DoF arm and the two
/// fingers of its gripper.
const ARM_DIM: usize = crate::utils::ARM_DOFS;

/// The smallest pivot the factorisation accepts, relative to the matrix's largest diagonal
/// entry: a DoF with no inertia at all (a massless link without armature) would otherwise
/// divide by zero; it gets this much instead (MuJoCo clamps its pivots the same way).
const MIN_RELATIVE_PIVOT: Real = 1.0e-10;

impl MultibodyCholesky {
    /// The size of the factorised system.
    pub fn dim(&self) -> usize {
        self.l.nrows()
    }

    /// Factorises the leading `dim × dim` block of `m` (its lower triangle is read), reusing
    /// this factorisation's storage.
    pub fn factorise(&mut self, m: &DMatrix<Real>, dim: usize) {
        if self.l.shape() != (dim, dim) {
            self.l = DMatrix::zeros(dim, dim);
            self.inv_diagonal = vec![0.0; dim];
            self.inverse = DMatrix::zeros(dim, dim);
            self.l_inv = DMatrix::zeros(dim, dim);
        }
        // An arm with a two-finger gripper has 9 DoFs: with the size a constant the loops below
        // unroll and lose their bounds checks. The same operations in the same order either way.
        if dim == ARM_DIM {
            self.factorise_sized(m, ARM_DIM);
            self.form_inverse_sized(ARM_DIM);
        } else {
            self.factorise_sized(m, dim);
            self.form_inverse_sized(dim);
        }
    }

    /// [`Self::factorise`]'s work for `n = dim`, inlined into each of its calls so that a
    /// constant `n` specialises it.
    #[inline(always)]
    fn factorise_sized(&mut self, m: &DMatrix<Real>, n: usize) {
        let m_rows = m.nrows();
        let m = &m.as_slice()[..m_rows * n];
        let largest = (0..n).fold(0.0, |acc: Real, i| acc.max(m[i * m_rows + i].abs()));
        let min_pivot = (largest * MIN_RELATIVE_PIVOT).max(Real::MIN_POSITIVE);
        // Column-major: entry (r, c) is `l[c * n + r]`; column j is one slice.
        let l = &mut self.l.as_mut_slice()[..n * n];
        let inv_diagonal = &mut self.inv_diagonal[..n];
        for j in 0..n {
            // Columns before j, and column j from its diagonal down.
            let (before, rest) = l.split_at_mut(j * n);
            let column = &mut rest[j..n];
            column.copy_from_slice(&m[j * m_rows + j..j * m_rows + n]);
            // Subtract the columns before j: L[r, j] -= L[r, k]·L[j, k].
            for k in 0..j {
                let earlier = &before[k * n + j..(k + 1) * n];
                let ljk = earlier[0];
                if ljk == 0.0 {
                    continue; // A tree's mass matrix has zero blocks between branches.
                }
                for (entry, lrk) in column.iter_mut().zip(earlier) {
                    *entry -= lrk * ljk;
                }
            }
            let pivot = column[0].max(min_pivot);
            let diagonal = pivot.sqrt();
            let inv = 1.0 / diagonal;
            inv_diagonal[j] = inv;
            column[0] = diagonal;
            for entry in &mut column[1..] {
                *entry *= inv;
            }
        }
    }

    /// `M⁻¹` from the factor: each column of `L⁻¹` by a forward substitution of a unit vector
    /// (updates along `L`'s contiguous columns), then `M⁻¹ = L⁻ᵀ·L⁻¹`, whose entry (i, j),
    /// i ≤ j, is the dot product of `L⁻¹`'s columns i and j over rows j.. (each entry once,
    /// mirrored). Inlined like [`Self::factorise_sized`].
    #[inline(always)]
    fn form_inverse_sized(&mut self, n: usize) {
        let l = &self.l.as_slice()[..n * n];
        let inv_diagonal = &self.inv_diagonal[..n];
        let l_inv = &mut self.l_inv.as_mut_slice()[..n * n];
        for c in 0..n {
            let x = &mut l_inv[c * n..(c + 1) * n];
            x.fill(0.0);
            x[c] = 1.0;
            for k in c..n {
                let xk = x[k] * inv_diagonal[k];
                x[k] = xk;
                let (_, below) = x.split_at_mut(k + 1);
                for (xr, lrk) in below.iter_mut().zip(&l[k * n + k + 1..(k + 1) * n]) {
                    *xr -= lrk * xk;
                }
            }
        }
        let inverse = &mut self.inverse.as_mut_slice()[..n * n];
        for i in 0..n {
            let column_i = &l_inv[i * n..(i + 1) * n];
            for j in i..n {
                let column_j = &l_inv[j * n..(j + 1) * n];
                let sum: Real = column_i[j..]
                    .iter()
                    .zip(&column_j[j..])
                    .map(|(a, b)| a * b)
                    .sum();
                inverse[j * n + i] = sum;
                inverse[i * n + j] = sum;
            }
        }
    }

    /// `M⁻¹` (dim × dim, symmetric).
    pub fn inverse(&self) -> &DMatrix<Real> {
        &self.inverse
    }

    /// Solves `M·x = b` in place: `x = M⁻¹·b`. `b` may be a strided view: it is solved in a
    /// contiguous copy (on the stack up to `STACK_DIM`) by [`Self::solve_slice_mut`].
    pub fn solve_mut<S: StorageMut<Real, Dyn, U1>>(&self, b: &mut Matrix<Real, Dyn, U1, S>) {
        let n = self.dim();
        assert_eq!(n, b.nrows(), "Cholesky solve dimension mismatch.");
        let mut stack = [0.0; STACK_DIM];
        let mut heap = Vec::new();
        let x = if n <= STACK_DIM {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap[..]
        };
        for (value, entry) in x.iter_mut().zip(b.iter()) {
            *value = *entry;
        }
        self.solve_slice_mut(x);
        for (r, value) in x.iter().enumerate() {
            b[r] = *value;
        }
    }

    /// Solves `M·x = b` in place on a contiguous slice: `x = M⁻¹·b`, the product by `M⁻¹` from
    /// a copy of `b` (on the stack up to `STACK_DIM`), column by column, skipping zero entries.
    pub fn solve_slice_mut(&self, b: &mut [Real]) {
        let n = self.dim();
        assert_eq!(n, b.len(), "Cholesky solve dimension mismatch.");
        // Specialised for the common size, as in `factorise`.
        if n == ARM_DIM {
            self.solve_sized(b, ARM_DIM);
        } else {
            self.solve_sized(b, n);
        }
    }

    /// [`Self::solve_slice_mut`]'s work for `n = b.len()`, inlined into each of its calls.
    #[inline(always)]
    fn solve_sized(&self, b: &mut [Real], n: usize) {
        let b = &mut b[..n];
        let mut stack = [0.0; STACK_DIM];
        let mut heap = Vec::new();
        let rhs = if n <= STACK_DIM {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap[..]
        };
        rhs.copy_from_slice(b);
        b.fill(0.0);
        // Column by column of the (column-major) inverse: x += M⁻¹[:, c]·b[c].
        let inverse = &self.inverse.as_slice()[..n * n];
        for (c, bc) in rhs.iter().enumerate() {
            if *bc != 0.0 {
                for (xr, mrc) in b.iter_mut().zip(&inverse[c * n..(c + 1) * n]) {
                    *xr += mrc * bc;
                }
            }
        }
    }

    /// Every column of `M⁻¹` into `out` (dim × dim).
    pub fn solve_all_units(&self, out: &mut DMatrix<Real>) {
        assert_eq!(
            out.shape(),
            self.inverse.shape(),
            "Cholesky solve dimension mismatch."
        );
        out.as_mut_slice().copy_from_slice(self.inverse.as_slice());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use na::DVector;

    /// A random symmetric positive definite matrix: `A·Aᵀ + n·1`.
    fn spd(n: usize, seed: u32) -> DMatrix<Real> {
        let mut state = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let a = DMatrix::<Real>::from_fn(n, n, |_, _| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state % 2000) as Real / 1000.0 - 1.0
        });
        &a * a.transpose() + DMatrix::identity(n, n) * n as Real
    }

    #[test]
    fn solves_and_inverse_columns_agree_with_nalgebra() {
        for n in [1, 2, 5, 9, 14] {
            let m = spd(n, n as u32);
            let mut chol = MultibodyCholesky::default();
            chol.factorise(&m, n);
            let reference = m.clone().cholesky().expect("SPD");
            let b = DVector::<Real>::from_fn(n, |i, _| (i as Real * 0.7).sin());
            let mut ours = b.clone();
            chol.solve_mut(&mut ours);
            let theirs = reference.solve(&b);
            assert!((ours - &theirs).amax() <= 1e-5 * theirs.amax().max(1.0));

            let mut inverse = DMatrix::zeros(n, n);
            chol.solve_all_units(&mut inverse);
            let identity = &m * &inverse;
            assert!((identity - DMatrix::<Real>::identity(n, n)).amax() <= 1e-4);
        }
    }

    #[test]
    fn the_slice_solve_equals_the_view_solve_bit_for_bit() {
        for n in [1, 4, 9, 14] {
            let mut chol = MultibodyCholesky::default();
            chol.factorise(&spd(n, 7 + n as u32), n);
            for zeros in [0, 1, 3] {
                // Zero entries take the skip; a -0 one too.
                let b = DVector::<Real>::from_fn(n, |i, _| match i % 4 {
                    _ if i < zeros => if i == 1 { -0.0 } else { 0.0 },
                    k => (k as Real * 0.37 + i as Real).sin(),
                });
                let mut view = b.clone();
                chol.solve_mut(&mut view);
                let mut slice = b.clone();
                chol.solve_slice_mut(slice.as_mut_slice());
                let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&slice), bits(&view), "n {n}, {zeros} zeros");
            }
        }
    }

    #[test]
    fn the_arm_sized_path_equals_the_general_one_bit_for_bit() {
        // `black_box` hides the size from the optimiser: the general loops, against the ones
        // specialised for ARM_DIM that `factorise` and `solve_slice_mut` take.
        let n = ARM_DIM;
        let m = spd(n, 11);
        let mut specialised = MultibodyCholesky::default();
        specialised.factorise(&m, n);
        let mut general = MultibodyCholesky::default();
        general.factorise(&m, n);
        general.factorise_sized(&m, core::hint::black_box(n));
        general.form_inverse_sized(core::hint::black_box(n));
        let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(specialised.l.as_slice()), bits(general.l.as_slice()));
        assert_eq!(
            bits(specialised.inverse.as_slice()),
            bits(general.inverse.as_slice())
        );
        let b: Vec<Real> = (0..n).map(|i| (i as Real * 0.61).cos()).collect();
        let mut x = b.clone();
        specialised.solve_slice_mut(&mut x);
        let mut y = b.clone();
        general.solve_sized(&mut y, core::hint::black_box(n));
        assert_eq!(bits(&x), bits(&y));
    }

    #[test]
    fn a_leading_block_is_factorised_when_dofs_are_removed() {
        let m = spd(9, 3);
        let mut chol = MultibodyCholesky::default();
        chol.factorise(&m, 6);
        let block = m.view((0, 0), (6, 6)).into_owned();
        let b = DVector::<Real>::from_fn(6, |i, _| i as Real - 2.0);
        let mut x = b.clone();
        chol.solve_mut(&mut x);
        assert!((&block * x - b).amax() <= 1e-4);
    }

    #[test]
    fn a_dof_without_inertia_gets_a_finite_solution() {
        let mut m = spd(4, 9);
        for k in 0..4 {
            m[(2, k)] = 0.0;
            m[(k, 2)] = 0.0;
        }
        let mut chol = MultibodyCholesky::default();
        chol.factorise(&m, 4);
        let mut x = DVector::<Real>::from_element(4, 1.0);
        chol.solve_mut(&mut x);
        assert!(x.iter().all(|v| v.is_finite()));
    }
}
