use super::multibody_dynamics::{Composite, Wrench};
use crate::alloc_prelude::*;
use crate::dynamics::RigidBodyVelocity;
use crate::math::{DVector, Real, Vector};

/// A temporary workspace for various updates of the multibody.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
pub(crate) struct MultibodyWorkspace {
    pub accs: Vec<RigidBodyVelocity<Real>>,
    pub ndofs_vec: DVector,
    /// CompoSuite-ROS patch: per link, its subtree as one body (the CRBA's pass).
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub composites: Vec<Composite>,
    /// CompoSuite-ROS patch: per link, the world centre of mass its quantities are taken about.
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub centers: Vec<Vector>,
    /// CompoSuite-ROS patch: per link, its centre less its parent's (the lever both passes
    /// carry momenta and wrenches across; the root's is unused).
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub shifts: Vec<Vector>,
    /// CompoSuite-ROS patch: per DoF, its column of its own link's Jacobian as a twist (the
    /// velocity of the link's centre and its angular velocity for a unit rate), read once.
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub twists: Vec<(Vector, Vector)>,
    /// CompoSuite-ROS patch: per link, the wrench of its subtree (the Newton–Euler pass), all
    /// forces, and the user's alone.
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub wrenches: Vec<Wrench>,
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    pub user_wrenches: Vec<Wrench>,
    /// CompoSuite-ROS patch: the user's generalized forces, the generalized coordinates, and
    /// the controller's desired accelerations (`ComputedTorquePd`).
    pub user_forces: DVector,
    pub positions: DVector,
    pub desired: DVector,
}

impl MultibodyWorkspace {
    /// Create an empty workspace.
    pub fn new() -> Self {
        MultibodyWorkspace {
            accs: Vec::new(),
            ndofs_vec: DVector::zeros(0),
            composites: Vec::new(),
            centers: Vec::new(),
            shifts: Vec::new(),
            twists: Vec::new(),
            wrenches: Vec::new(),
            user_wrenches: Vec::new(),
            user_forces: DVector::zeros(0),
            positions: DVector::zeros(0),
            desired: DVector::zeros(0),
        }
    }

    /// Resize the workspace so it is enough for `nlinks` links.
    pub fn resize(&mut self, nlinks: usize, ndofs: usize) {
        self.accs.resize(nlinks, RigidBodyVelocity::zero());
        self.ndofs_vec = DVector::zeros(ndofs);
        self.composites.resize(nlinks, Composite::default());
        self.centers.resize(nlinks, Vector::ZERO);
        self.shifts.resize(nlinks, Vector::ZERO);
        self.twists.resize(ndofs, (Vector::ZERO, Vector::ZERO));
        self.wrenches.resize(nlinks, Wrench::default());
        self.user_wrenches.resize(nlinks, Wrench::default());
        self.user_forces = DVector::zeros(ndofs);
        self.positions = DVector::zeros(ndofs);
        self.desired = DVector::zeros(ndofs);
    }
}
