use crate::math::{Pose, Real, Vector};
use crate::query::{ContactManifold, TrackedContact};
use crate::shape::{HalfSpace, PackedFeatureId, PolygonalFeature, PolygonalFeatureMap, Shape};

/// Computes the contact manifold between a convex shape and a ball, both represented as a `Shape` trait-object.
pub fn contact_manifold_halfspace_pfm_shapes<ManifoldData, ContactData>(
    pos12: &Pose,
    shape1: &dyn Shape,
    shape2: &dyn Shape,
    prediction: Real,
    manifold: &mut ContactManifold<ManifoldData, ContactData>,
) where
    ContactData: Default + Copy,
{
    if let (Some(halfspace1), Some((pfm2, border_radius2))) =
        (shape1.as_halfspace(), shape2.as_polygonal_feature_map())
    {
        contact_manifold_halfspace_pfm(
            pos12,
            halfspace1,
            pfm2,
            border_radius2,
            prediction,
            manifold,
            false,
        );
    } else if let (Some((pfm1, border_radius1)), Some(halfspace2)) =
        (shape1.as_polygonal_feature_map(), shape2.as_halfspace())
    {
        contact_manifold_halfspace_pfm(
            &pos12.inverse(),
            halfspace2,
            pfm1,
            border_radius1,
            prediction,
            manifold,
            true,
        );
    }
}

/// Computes the contact manifold between a convex shape and a ball.
pub fn contact_manifold_halfspace_pfm<'a, ManifoldData, ContactData, S2>(
    pos12: &Pose,
    halfspace1: &'a HalfSpace,
    pfm2: &'a S2,
    border_radius2: Real,
    prediction: Real,
    manifold: &mut ContactManifold<ManifoldData, ContactData>,
    flipped: bool,
) where
    S2: ?Sized + PolygonalFeatureMap,
    ContactData: Default + Copy,
{
    let normal1_2 = pos12.rotation.inverse() * halfspace1.normal;

    // CompoSuite-ROS patch: a shape far above the plane answers without its support feature.
    if surely_apart_along(pos12, halfspace1, normal1_2, pfm2, border_radius2, prediction) {
        manifold.points.clear();
        set_halfspace_normals(manifold, halfspace1, normal1_2, flipped);
        return;
    }

    let mut feature2 = PolygonalFeature::default();
    pfm2.local_support_feature(-normal1_2, &mut feature2);

    // We do this clone to perform contact tracking and transfer impulses.
    // TODO: find a more efficient way of doing this.
    let old_manifold_points = core::mem::take(&mut manifold.points);

    for i in 0..feature2.num_vertices {
        let vtx2 = feature2.vertices[i];
        let vtx2_1 = pos12 * vtx2;
        let dist_to_plane = vtx2_1.dot(halfspace1.normal);

        if dist_to_plane - border_radius2 <= prediction {
            // Keep this contact point.
            manifold.points.push(TrackedContact::flipped(
                vtx2_1 - halfspace1.normal * dist_to_plane,
                vtx2 - normal1_2 * border_radius2,
                PackedFeatureId::face(0),
                feature2.vids[i],
                dist_to_plane - border_radius2,
                flipped,
            ));
        }
    }

    set_halfspace_normals(manifold, halfspace1, normal1_2, flipped);

    // println!("Found contacts: {}", manifold.points.len());

    // Transfer impulses.
    manifold.match_contacts(&old_manifold_points);
}

/// CompoSuite-ROS patch: whether [`contact_manifold_halfspace_pfm`] would surely keep no contact
/// point, told from one support point of the shape instead of its support feature. Every
/// vertex of that feature lies on the shape, so none is nearer the plane than the shape's
/// support point towards it; when that point is beyond `prediction` by more than any rounding
/// of the distances there, the function's loop keeps no point. The margin is ~1000× the f32
/// rounding of a distance at these coordinates.
pub fn halfspace_pfm_surely_apart<S2: ?Sized + PolygonalFeatureMap>(
    pos12: &Pose,
    halfspace1: &HalfSpace,
    pfm2: &S2,
    border_radius2: Real,
    prediction: Real,
) -> bool {
    let normal1_2 = pos12.rotation.inverse() * halfspace1.normal;
    surely_apart_along(pos12, halfspace1, normal1_2, pfm2, border_radius2, prediction)
}

/// [`halfspace_pfm_surely_apart`] with the plane's normal in the shape's frame at hand.
fn surely_apart_along<S2: ?Sized + PolygonalFeatureMap>(
    pos12: &Pose,
    halfspace1: &HalfSpace,
    normal1_2: Vector,
    pfm2: &S2,
    border_radius2: Real,
    prediction: Real,
) -> bool {
    let deepest = pos12 * pfm2.local_support_point(-normal1_2);
    let rounding_margin = 1.0e-4 * (1.0 + pos12.translation.length() + deepest.length());
    deepest.dot(halfspace1.normal) - border_radius2 > prediction + rounding_margin
}

fn set_halfspace_normals<ManifoldData, ContactData>(
    manifold: &mut ContactManifold<ManifoldData, ContactData>,
    halfspace1: &HalfSpace,
    normal1_2: Vector,
    flipped: bool,
) {
    if flipped {
        manifold.local_n1 = -normal1_2;
        manifold.local_n2 = halfspace1.normal;
    } else {
        manifold.local_n1 = halfspace1.normal;
        manifold.local_n2 = -normal1_2;
    }
}
