use nalgebra::{Isometry3, Point3, Vector3};

use super::raster::{Paint, View, draw_triangle};
use super::*;

fn outward(mesh: &Mesh) -> bool {
    let n = mesh.vertices.len() as f32;
    let centre = mesh
        .vertices
        .iter()
        .fold(Vector3::zeros(), |a, v| a + v.coords)
        / n;
    mesh.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        let normal = (b - a).cross(&(c - a));
        normal.norm() > 0.0 && normal.dot(&(a.coords - centre)) > 0.0
    })
}

#[test]
fn every_mesh_is_wound_outward_and_has_no_degenerate_triangle() {
    let meshes = [
        Mesh::cuboid(Vector3::new(0.1, 0.2, 0.3)),
        Mesh::cylinder(0.05, 0.2),
        Mesh::sphere(0.07),
        Mesh::capsule(0.04, 0.1),
    ];
    for mesh in &meshes {
        assert!(outward(mesh), "{mesh:?}");
    }
    assert_eq!(meshes[0].triangles.len(), 12);
}

#[test]
fn a_capsule_reaches_its_radius_beyond_the_cap_centres() {
    let mesh = Mesh::capsule(0.04, 0.1);
    let top = mesh.vertices.iter().map(|v| v.z).fold(f32::MIN, f32::max);
    let widest = mesh
        .vertices
        .iter()
        .map(|v| v.x.hypot(v.y))
        .fold(0.0, f32::max);
    assert!((top - 0.14).abs() < 1e-6, "{top}");
    assert!((widest - 0.04).abs() < 1e-6, "{widest}");
}

#[test]
fn intrinsics_follow_the_reference_formula() {
    let camera = Camera {
        pose: Isometry3::identity(),
        fovy_deg: 45.0,
    };
    // robosuite: f = 0.5 H / tan(fovy / 2); 256 px tall at 45° → 309.019 px.
    let k = camera.intrinsics(256, 256);
    assert!((k[0] - 309.019).abs() < 1e-3, "{k:?}");
    assert_eq!((k[2], k[5]), (128.0, 128.0));
    let k = camera.intrinsics(640, 480);
    assert!((k[4] - 579.411).abs() < 1e-3 && k[2] == 320.0 && k[5] == 240.0);
}

#[test]
fn a_ray_through_a_projected_point_passes_through_it() {
    let spec = camera_spec("frontview").unwrap();
    let camera = Camera {
        pose: spec.optical_in_mount(),
        fovy_deg: spec.fovy_deg,
    };
    let point = Point3::new(0.1, -0.26, 0.82);
    let (u, v, depth) = camera.project(&point, 640, 480).unwrap();
    let (origin, direction) = camera.ray(u, v, 640, 480);
    assert!((origin + direction * depth - point).norm() < 1e-9);
}

#[test]
fn the_arena_cameras_look_at_the_table() {
    // Bin 1's centre, on the robot's right, is in view of every arena camera.
    let bin1 = Point3::new(0.1, -0.26, 0.82);
    for spec in CAMERAS.iter().filter(|c| c.mount == Mount::World) {
        let camera = Camera {
            pose: spec.optical_in_mount(),
            fovy_deg: spec.fovy_deg,
        };
        let (u, v, depth) = camera.project(&bin1, 256, 256).expect(spec.name);
        assert!(
            (0.0..256.0).contains(&u) && (0.0..256.0).contains(&v),
            "{}: ({u}, {v})",
            spec.name
        );
        assert!((0.3..3.5).contains(&depth), "{}: {depth}", spec.name);
    }
    // frontview faces the robot (looks along −x) from above the far side of the table.
    let front = camera_spec("frontview").unwrap().optical_in_mount();
    let forward = front.rotation * Vector3::z();
    assert!(forward.x < -0.7 && forward.z < -0.2, "{forward}");
}

#[test]
fn an_unknown_camera_is_refused_with_the_valid_names() {
    let message = camera_spec("front_view").unwrap_err().to_string();
    for spec in &CAMERAS {
        assert!(message.contains(spec.name), "{message}");
    }
    assert!(message.contains("front_view"));
}

/// A square at depth 2 facing the camera fills exactly the pixels its corners bound, at the
/// depth it is, and a second square behind it does not show through.
#[test]
fn the_rasteriser_fills_a_facing_square_with_its_depth() {
    let mut frame = Frame::new(64, 48);
    frame.depth.fill(0.0);
    let view = View {
        light: Vector3::new(0.0, 0.0, -1.0),
        focal: 32.0,
        centre: (32.0, 24.0),
    };
    let paint = |class| Paint {
        colour: [1.0, 0.5, 0.0],
        class,
        alpha: None,
    };
    // Corners at x, y = ±0.5 m, z = 2 m project to u ∈ [24, 40], v ∈ [16, 32].
    let square = |z: f32, half: f32| {
        let p = |x: f32, y: f32| Point3::new(x * half, y * half, z);
        // Wound to face the camera (normal toward −z).
        [
            [p(-1.0, -1.0), p(1.0, 1.0), p(1.0, -1.0)],
            [p(-1.0, -1.0), p(-1.0, 1.0), p(1.0, 1.0)],
        ]
    };
    for t in square(2.0, 0.5) {
        draw_triangle(&mut frame, &view, t, &paint(SceneClass::Object));
    }
    for t in square(3.0, 2.0) {
        draw_triangle(&mut frame, &view, t, &paint(SceneClass::Arena));
    }
    let mut filled = 0;
    for y in 0..48 {
        for x in 0..64 {
            let inside = (24..40).contains(&x) && (16..32).contains(&y);
            let class = frame.class_at(x, y);
            assert_eq!(class == SceneClass::Object, inside, "({x}, {y})");
            if inside {
                filled += 1;
                assert!((1.0 / frame.depth_at(x, y) - 2.0).abs() < 1e-5);
            }
        }
    }
    assert_eq!(filled, 16 * 16);
}

#[test]
fn triangles_facing_away_or_behind_the_near_plane_draw_nothing() {
    let mut frame = Frame::new(16, 16);
    frame.depth.fill(0.0);
    let view = View {
        light: Vector3::z(),
        focal: 8.0,
        centre: (8.0, 8.0),
    };
    let paint = Paint {
        colour: [1.0; 3],
        class: SceneClass::Robot,
        alpha: None,
    };
    let p = |x: f32, y: f32, z: f32| Point3::new(x, y, z);
    // Facing away from the camera.
    draw_triangle(
        &mut frame,
        &view,
        [p(-1.0, -1.0, 2.0), p(1.0, -1.0, 2.0), p(1.0, 1.0, 2.0)],
        &paint,
    );
    // Wholly closer than the near plane.
    draw_triangle(
        &mut frame,
        &view,
        [
            p(-1.0, -1.0, NEAR / 2.0),
            p(1.0, 1.0, NEAR / 2.0),
            p(1.0, -1.0, NEAR / 2.0),
        ],
        &paint,
    );
    assert!(frame.classes.iter().all(|&c| c == SceneClass::Background));
}
