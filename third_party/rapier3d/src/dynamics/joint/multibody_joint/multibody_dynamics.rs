//! CompoSuite-ROS patch: the pieces of a multibody's joint-space dynamics that the
//! composite-rigid-body (CRBA) mass matrix and the recursive Newton–Euler bias share, and a
//! joint-space controller that reuses both.
//!
//! Everything here is in world axes about moving points — each link's centre of mass — rather
//! than about the world origin: a wrist's entries are then computed from lever arms of
//! centimetres, not differences of metre-scale moments, which keeps f32 precise.

use crate::alloc_prelude::*;
use crate::math::{Real, Vector};
use parry::glamx::Mat3;

/// The bodies of a subtree (a link and everything beyond it) as one rigid body, about a point
/// `o` (the link's centre of mass).
#[derive(Copy, Clone, Debug)]
pub(crate) struct Composite {
    pub mass: Real,
    /// Σ m·(c − o).
    pub first_moment: Vector,
    /// Σ (I_c + m·(|c − o|²·1 − (c − o)(c − o)ᵀ)): the inertia about `o`.
    pub inertia: Mat3,
}

impl Default for Composite {
    fn default() -> Self {
        Composite {
            mass: 0.0,
            first_moment: Vector::ZERO,
            inertia: Mat3::ZERO,
        }
    }
}

impl Composite {
    /// A single body about its own centre of mass.
    pub fn body(mass: Real, inertia: Mat3) -> Self {
        Composite {
            mass,
            first_moment: Vector::ZERO,
            inertia,
        }
    }

    /// Adds `other`, taken about a point `d` away from this one's (`d = o_other − o_self`).
    pub fn add_shifted(&mut self, other: &Composite, d: Vector) {
        let (m, h) = (other.mass, other.first_moment);
        // About the new point every body's offset is r + d: expand |r + d|² and (r + d)(r + d)ᵀ.
        let diagonal = 2.0 * h.dot(d) + m * d.length_squared();
        let outer = outer(h, d) + outer(d, h) + outer(d, d * m);
        self.mass += m;
        self.first_moment += h + d * m;
        self.inertia += other.inertia + Mat3::from_diagonal(Vector::splat(diagonal)) - outer;
    }

    /// The momentum (linear, and angular about `o`) of the composite moving with the twist
    /// (`v` the velocity of the point `o`, `w` the angular velocity).
    #[inline]
    pub fn momentum(&self, v: Vector, w: Vector) -> (Vector, Vector) {
        let linear = v * self.mass + w.cross(self.first_moment);
        let angular = self.first_moment.cross(v) + self.inertia * w;
        (linear, angular)
    }
}

/// `a·bᵀ`.
#[inline]
fn outer(a: Vector, b: Vector) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// A force and a torque about a point (a link's centre of mass).
#[derive(Copy, Clone, Debug, Default)]
pub(crate) struct Wrench {
    pub force: Vector,
    pub torque: Vector,
}

impl Wrench {
    /// Adds `other`, which acts about a point `d` away from this one's.
    #[inline]
    pub fn add_shifted(&mut self, other: &Wrench, d: Vector) {
        self.force += other.force;
        self.torque += other.torque + d.cross(other.force);
    }

    /// The power of this wrench on a twist (`v` at the same point, `w`): a generalized force.
    #[inline]
    pub fn power(&self, v: Vector, w: Vector) -> Real {
        self.force.dot(v) + self.torque.dot(w)
    }
}

/// The joint-space controller of robosuite's joint-position controller, run inside the
/// multibody's step where its mass matrix and bias are at hand: on DoFs
/// `first_dof .. first_dof + targets.len()`,
///
/// τ = M·(kp·(target − q) − kd·q̇) + bias,   clamped to ±`effort_limits`,
///
/// with `M` the mass matrix (armature included; no damping or spring terms) restricted to
/// those DoFs, and `bias` the Coriolis, centrifugal and gravity forces (MuJoCo's
/// `qfrc_bias`). The forces are generalized forces on the DoFs, added to the step's free
/// accelerations; `torques` holds the last step's.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug, Default)]
pub struct ComputedTorquePd {
    /// The first controlled DoF (its index in the multibody's generalized coordinates).
    pub first_dof: usize,
    /// Stiffness (1/s²).
    pub kp: Real,
    /// Damping (1/s).
    pub kd: Real,
    /// Target coordinate per controlled DoF.
    pub targets: Vec<Real>,
    /// Largest |τ| per controlled DoF.
    pub effort_limits: Vec<Real>,
    /// The generalized forces exerted in the last step (written by the multibody).
    pub torques: Vec<Real>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shifted_composite_has_the_parallel_axis_inertia() {
        // Two point masses about o: 1 kg at (1, 0, 0), 2 kg at (0, 2, 0), summed one by one about
        // a point d away, against the shift of their composite.
        let bodies = [
            (1.0, Vector::new(1.0, 0.0, 0.0)),
            (2.0, Vector::new(0.0, 2.0, 0.0)),
        ];
        let mut about_o = Composite::default();
        for (m, c) in bodies {
            about_o.add_shifted(&Composite::body(m, Mat3::IDENTITY * 0.1), c);
        }
        let d = Vector::new(0.3, -0.5, 0.7);
        let mut shifted = Composite::default();
        shifted.add_shifted(&about_o, d);
        let mut direct = Composite::default();
        for (m, c) in bodies {
            direct.add_shifted(&Composite::body(m, Mat3::IDENTITY * 0.1), c + d);
        }
        assert!((shifted.mass - direct.mass).abs() < 1e-6);
        assert!((shifted.first_moment - direct.first_moment).length() < 1e-5);
        let diff = shifted.inertia - direct.inertia;
        for c in [diff.x_axis, diff.y_axis, diff.z_axis] {
            assert!(c.length() < 1e-5, "{diff:?}");
        }
    }

    #[test]
    fn momentum_of_a_spinning_offset_mass() {
        // 2 kg at r = (1, 0, 0) from o, spinning about z through o at 3 rad/s: linear momentum
        // m·(w × r) = (0, 6, 0), angular r × p = (0, 0, 6).
        let mut c = Composite::default();
        c.add_shifted(
            &Composite::body(2.0, Mat3::ZERO),
            Vector::new(1.0, 0.0, 0.0),
        );
        let (l, h) = c.momentum(Vector::ZERO, Vector::new(0.0, 0.0, 3.0));
        assert!((l - Vector::new(0.0, 6.0, 0.0)).length() < 1e-6);
        assert!((h - Vector::new(0.0, 0.0, 6.0)).length() < 1e-6);
    }
}
