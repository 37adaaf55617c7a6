//! URDF as the physics reads it: poses, capsules joined back, and the error a file that does
//! not fit gives.
//!
//! Capsules are written in standard URDF and joined back into capsules for the physics.
//! URDF has no capsule, and parsers that keep to the standard (urdfdom under RViz, Foxglove,
//! yourdfpy) refuse one, so the URDFs write each capsule as what it is made of: a `<cylinder>`
//! collision named `N` and two `<sphere>` collisions `N_end1`, `N_end2` of the same radius,
//! centred on the cylinder's end faces. The loader turns each such trio back into one capsule,
//! which rapier handles better than the three pieces, and refuses a trio that does not fit.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// A URDF that does not describe what the loader needs.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelError(pub String);

impl std::fmt::Display for ModelError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ModelError {}

/// A URDF `origin` as an isometry (xyz, then roll-pitch-yaw as URDF defines them).
pub(crate) fn urdf_pose(pose: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = *pose.xyz;
    let [roll, pitch, yaw] = *pose.rpy;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

/// How far (m) a sphere's centre may be from its end face's centre: the files give 6 decimals.
const END_TOLERANCE: f64 = 1e-5;

/// Replaces every cylinder-and-two-spheres trio of `robot`'s collisions with one capsule of
/// the cylinder's name and pose.
pub(crate) fn join_capsules(robot: &mut urdf_rs::Robot) -> Result<(), ModelError> {
    for link in &mut robot.links {
        let collisions = std::mem::take(&mut link.collision);
        let name_of = |c: &urdf_rs::Collision| c.name.clone().unwrap_or_default();
        let mut joined = Vec::with_capacity(collisions.len());
        let mut ends_used: Vec<String> = Vec::new();
        for collision in &collisions {
            let urdf_rs::Geometry::Cylinder { radius, length } = collision.geometry else {
                continue;
            };
            let name = name_of(collision);
            let ends: Vec<&urdf_rs::Collision> = ["_end1", "_end2"]
                .iter()
                .filter_map(|suffix| {
                    let end = format!("{name}{suffix}");
                    collisions.iter().find(|c| name_of(c) == end)
                })
                .collect();
            match ends.as_slice() {
                [] => {}
                [first, second] => {
                    let pose = urdf_pose(&collision.origin);
                    let axis = pose.rotation * Vector3::z() * (length / 2.0);
                    let centre = Point3::from(pose.translation.vector);
                    for (end, expected) in [(first, centre + axis), (second, centre - axis)] {
                        let at = Point3::from(urdf_pose(&end.origin).translation.vector);
                        let fits = matches!(end.geometry,
                            urdf_rs::Geometry::Sphere { radius: r } if (r - radius).abs() < 1e-12);
                        if !fits || (at - expected).norm() > END_TOLERANCE {
                            return Err(ModelError(format!(
                                "link `{}`: `{}` is not a sphere of radius {radius} centred on \
                                 an end of cylinder `{name}` (at {:?})",
                                link.name,
                                name_of(end),
                                expected.coords.as_slice()
                            )));
                        }
                        ends_used.push(name_of(end));
                    }
                }
                _ => {
                    return Err(ModelError(format!(
                        "link `{}`: cylinder `{name}` has one end sphere; a capsule needs \
                         `{name}_end1` and `{name}_end2`",
                        link.name
                    )));
                }
            }
        }
        for collision in collisions {
            let name = name_of(&collision);
            if ends_used.contains(&name) {
                continue;
            }
            let capsule = match collision.geometry {
                urdf_rs::Geometry::Cylinder { radius, length }
                    if ends_used.contains(&format!("{name}_end1")) =>
                {
                    urdf_rs::Geometry::Capsule { radius, length }
                }
                ref other => other.clone(),
            };
            joined.push(urdf_rs::Collision {
                geometry: capsule,
                ..collision
            });
        }
        link.collision = joined;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link_with(collisions: &str) -> String {
        format!(r#"<robot name="r"><link name="l">{collisions}</link></robot>"#)
    }

    const CYLINDER: &str = r#"<collision name="c"><origin xyz="0 0 1" rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.1" length="0.4"/></geometry></collision>"#;

    fn end(name: &str, xyz: &str, radius: f64) -> String {
        format!(
            r#"<collision name="{name}"><origin xyz="{xyz}" rpy="0 0 0"/><geometry><sphere radius="{radius}"/></geometry></collision>"#
        )
    }

    fn joined(text: &str) -> Result<Vec<urdf_rs::Collision>, ModelError> {
        let mut robot = urdf_rs::read_from_string(text).unwrap();
        join_capsules(&mut robot)?;
        Ok(robot.links[0].collision.clone())
    }

    #[test]
    fn a_cylinder_with_its_two_end_spheres_is_one_capsule() {
        // Turned +90° about x, the cylinder's axis is −y: its ends are at y = ∓0.2.
        let text = link_with(&format!(
            "{CYLINDER}{}{}",
            end("c_end1", "0 -0.2 1", 0.1),
            end("c_end2", "0 0.2 1", 0.1)
        ));
        let collisions = joined(&text).unwrap();
        assert_eq!(collisions.len(), 1);
        assert_eq!(collisions[0].name.as_deref(), Some("c"));
        assert!(matches!(
            collisions[0].geometry,
            urdf_rs::Geometry::Capsule { radius, length } if radius == 0.1 && length == 0.4
        ));
    }

    #[test]
    fn a_lone_cylinder_stays_a_cylinder() {
        let collisions = joined(&link_with(CYLINDER)).unwrap();
        assert!(matches!(
            collisions[0].geometry,
            urdf_rs::Geometry::Cylinder { .. }
        ));
    }

    #[test]
    fn end_spheres_that_do_not_fit_are_refused() {
        for (ends, what) in [
            (end("c_end1", "0 -0.2 1", 0.1), "c_end2"),
            (
                end("c_end1", "0 -0.2 1", 0.1) + &end("c_end2", "0 0.25 1", 0.1),
                "c_end2",
            ),
            (
                end("c_end1", "0 -0.2 1", 0.12) + &end("c_end2", "0 0.2 1", 0.1),
                "c_end1",
            ),
        ] {
            let error = joined(&link_with(&format!("{CYLINDER}{ends}"))).unwrap_err();
            assert!(error.0.contains(what), "{error}");
        }
    }
}
