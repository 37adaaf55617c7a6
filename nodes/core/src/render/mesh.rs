//! Triangle meshes of the primitives the scene is made of, built once per scene.
//!
//! Every mesh is closed and convex, wound so that each triangle's normal
//! `(b − a) × (c − a)` points out of the solid: the rasteriser culls triangles facing away from
//! the camera by that sign. Round shapes are lathes (a profile turned about the local z axis);
//! [`SEGMENTS`] around and [`BANDS`] per quarter circle are plenty at 640×480 for parts a few
//! centimetres across and keep an arm near 3 000 triangles.

use nalgebra::{Isometry3, Point3, Vector3};

/// Facets around a round shape's axis.
pub const SEGMENTS: usize = 16;
/// Latitude bands per quarter circle of a sphere or a capsule's cap.
pub const BANDS: usize = 3;

/// Triangles over a shared vertex list, in the frame of whatever carries the mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions (m).
    pub vertices: Vec<Point3<f32>>,
    /// Vertex indices, three per triangle, wound outward.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// A box of the given half-extents, centred on the origin.
    pub fn cuboid(half: Vector3<f64>) -> Mesh {
        let mut mesh = Mesh::default();
        for axis in 0..3 {
            // (u, v, n) right-handed, so corners taken counter-clockwise in (u, v) face +n.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for sign in [1.0, -1.0] {
                let corner = |su: f64, sv: f64| {
                    let mut p = Vector3::zeros();
                    p[axis] = sign * half[axis];
                    p[u] = su * half[u];
                    p[v] = sv * half[v];
                    Point3::from(p)
                };
                let mut quad = [
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ];
                if sign < 0.0 {
                    quad.reverse();
                }
                mesh.push_quad(quad);
            }
        }
        mesh
    }

    /// A cylinder along local z: radius and half-length (m).
    pub fn cylinder(radius: f64, half_length: f64) -> Mesh {
        Mesh::lathe(&[
            (0.0, -half_length),
            (radius, -half_length),
            (radius, half_length),
            (0.0, half_length),
        ])
    }

    /// A sphere of the given radius (m).
    pub fn sphere(radius: f64) -> Mesh {
        Mesh::capsule(radius, 0.0)
    }

    /// A capsule along local z: radius and half the distance between the cap centres (m).
    pub fn capsule(radius: f64, half_length: f64) -> Mesh {
        let quarter = std::f64::consts::FRAC_PI_2;
        let mut profile = Vec::with_capacity(4 * BANDS + 2);
        // Bottom cap from its pole to the equator, then the top cap from the equator up.
        for band in 0..=BANDS {
            let angle = -quarter + quarter * band as f64 / BANDS as f64;
            profile.push((radius * angle.cos(), -half_length + radius * angle.sin()));
        }
        for band in 0..=BANDS {
            let angle = quarter * band as f64 / BANDS as f64;
            profile.push((radius * angle.cos(), half_length + radius * angle.sin()));
        }
        Mesh::lathe(&profile)
    }

    /// A flat rectangle in the local xy plane facing +z: the ground.
    pub fn floor(half_x: f64, half_y: f64) -> Mesh {
        let corner = |x: f64, y: f64| Point3::new(x * half_x, y * half_y, 0.0);
        let mut mesh = Mesh::default();
        mesh.push_quad([
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ]);
        mesh
    }

    /// The mesh moved by `pose`.
    pub fn transformed(mut self, pose: &Isometry3<f64>) -> Mesh {
        let pose: Isometry3<f32> = pose.cast();
        for v in &mut self.vertices {
            *v = pose * *v;
        }
        self
    }

    /// Appends `other`'s triangles.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// A profile of (radius, z) points from bottom to top, turned about the z axis. Points on
    /// the axis (radius 0) close the ends; the triangles they would make degenerate are left out.
    fn lathe(profile: &[(f64, f64)]) -> Mesh {
        let mut mesh = Mesh::default();
        for &(r, z) in profile {
            for s in 0..SEGMENTS {
                let angle = std::f64::consts::TAU * s as f64 / SEGMENTS as f64;
                mesh.vertices
                    .push(Point3::new(r * angle.cos(), r * angle.sin(), z).cast::<f32>());
            }
        }
        let index = |ring: usize, s: usize| (ring * SEGMENTS + s % SEGMENTS) as u32;
        // Radii this small are the poles (cos(±π/2) is not exactly 0).
        let on_axis = |r: f64| r < 1e-12;
        for ring in 0..profile.len() - 1 {
            if profile[ring] == profile[ring + 1] {
                continue; // a sphere's two equators: nothing between them
            }
            let (lower_on_axis, upper_on_axis) =
                (on_axis(profile[ring].0), on_axis(profile[ring + 1].0));
            for s in 0..SEGMENTS {
                let (a, b) = (index(ring, s), index(ring, s + 1));
                let (c, d) = (index(ring + 1, s + 1), index(ring + 1, s));
                // Counter-clockwise about +z going up the profile: the normal points outward.
                if !lower_on_axis {
                    mesh.triangles.push([a, b, c]);
                }
                if !upper_on_axis {
                    mesh.triangles.push([a, c, d]);
                }
            }
        }
        mesh
    }

    fn push_quad(&mut self, corners: [Point3<f64>; 4]) {
        let base = self.vertices.len() as u32;
        self.vertices
            .extend(corners.iter().map(|c| c.cast::<f32>()));
        self.triangles.push([base, base + 1, base + 2]);
        self.triangles.push([base, base + 2, base + 3]);
    }
}
