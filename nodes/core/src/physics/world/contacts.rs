//! Contact queries: which parts of the fingers touch the object (the grasp test), and how deep
//! the object penetrates anything.

use rapier3d::prelude::*;

use super::SimWorld;
use crate::axes::Object;
use crate::physics::tags::{ColliderTag, Side};

/// Finger/object contacts at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FingerContacts {
    /// The left pad touches the object.
    pub left_pad: bool,
    /// The right pad touches the object.
    pub right_pad: bool,
    /// Any part of the left finger (pad, tip, blade, knuckle) touches the object.
    pub left_finger: bool,
    /// Any part of the right finger touches the object.
    pub right_finger: bool,
}

impl FingerContacts {
    /// The benchmark's grasp test (docs/src/reference-facts.md §6): both pads touch the object; for
    /// the plate, one pad and any part of the other finger suffice.
    pub fn grasping(&self, object: Object) -> bool {
        match object {
            Object::Plate => {
                (self.right_finger && self.left_pad) || (self.left_finger && self.right_pad)
            }
            Object::Box | Object::HollowBox | Object::Dumbbell => self.left_pad && self.right_pad,
        }
    }
}

impl SimWorld {
    /// The deepest penetration (m, ≥ 0) of any contact involving the object right now.
    pub fn object_penetration(&self) -> f64 {
        let Some(body) = self.object.and_then(|h| self.physics.bodies.get(h)) else {
            return 0.0;
        };
        let mut deepest: f64 = 0.0;
        for &collider in body.colliders() {
            for pair in self.physics.narrow_phase.contact_pairs_with(collider) {
                if let PairContacts::Rigid(rigid) = &pair.contacts {
                    for manifold in &rigid.manifolds {
                        for point in &manifold.points {
                            deepest = deepest.max(-(point.dist as f64));
                        }
                    }
                }
            }
        }
        deepest
    }

    /// Which parts of the fingers touch the object now.
    pub fn finger_contacts(&self) -> FingerContacts {
        FingerContacts {
            left_pad: self.finger_touches_object(Side::Left, true),
            right_pad: self.finger_touches_object(Side::Right, true),
            left_finger: self.finger_touches_object(Side::Left, false),
            right_finger: self.finger_touches_object(Side::Right, false),
        }
    }

    /// Whether any collider of the given finger (only its pad with `pad_only`) touches the
    /// object: the shapes overlap or touch at their current poses (distance ≤ 0), which is what
    /// MuJoCo's contact list holds (geom margins are 0 in the reference). Rapier's own contact
    /// pairs would not do: they include speculative contacts up to the prediction distance
    /// apart (2 mm), and a pair that moves less than its recycling distance keeps last
    /// update's points.
    pub fn finger_touches_object(&self, side: Side, pad_only: bool) -> bool {
        let Some(object) = self.object_collider() else {
            return false;
        };
        let colliders = &self.physics.colliders;
        let object = &colliders[object];
        let object_pose = self.collider_pose(object);
        self.arm.finger_colliders.iter().any(|(handle, tag)| {
            let wanted = if pad_only {
                *tag == ColliderTag::Pad(side)
            } else {
                tag.is_finger(side)
            };
            wanted && {
                let finger = &colliders[*handle];
                rapier3d::parry::query::intersection_test(
                    &self.collider_pose(finger),
                    finger.shape(),
                    &object_pose,
                    object.shape(),
                )
                .expect("parry tests boxes, capsules, cylinders and compounds of them")
                .intersecting
            }
        })
    }

    /// The object's (one, compound) collider.
    fn object_collider(&self) -> Option<ColliderHandle> {
        let body = self.physics.bodies.get(self.object?)?;
        body.colliders().first().copied()
    }

    /// A collider's world pose from its body's current pose (not the pose cached at the last
    /// collision detection).
    pub(super) fn collider_pose(&self, collider: &Collider) -> Pose {
        let local = collider.position_wrt_parent().copied().unwrap_or_default();
        match collider.parent() {
            Some(body) => *self.physics.bodies[body].position() * local,
            None => *collider.position(),
        }
    }
}
