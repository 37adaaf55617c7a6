//! Frames checked against the geometry they show: where the object projects, how far the table
//! is, which pixels the arm owns, that frames repeat bit for bit, that every camera sees the
//! scene, and that a wrong camera name is refused with the valid ones.

use composuite_core::axes::{AxisElement, Robot};
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::render::{CAMERAS, Frame, SceneClass};
use nalgebra::Point3;

fn env(task: &str, seed: u64) -> Env {
    let mut env = Env::new(task.parse().unwrap(), EnvConfig::default());
    env.reset(seed).unwrap();
    env
}

/// Pixels (x, y) showing `class`.
fn pixels_of(frame: &Frame, class: SceneClass) -> Vec<(u32, u32)> {
    (0..frame.height)
        .flat_map(|y| (0..frame.width).map(move |x| (x, y)))
        .filter(|&(x, y)| frame.class_at(x, y) == class)
        .collect()
}

#[test]
fn the_objects_pixels_centre_on_the_projection_of_its_pose() {
    // Objects whose body origin is their centre of symmetry, so their silhouette centres on it.
    for task in [
        "IIWA/box/no_obstacle/pick_place",
        "Panda/box/no_obstacle/shelf",
        "Jaco/dumbbell/no_obstacle/trash_can",
        "Gen3/dumbbell/goal_wall/push",
    ] {
        for seed in [0, 5, 11] {
            let mut env = env(task, seed);
            let (width, height) = (256, 256);
            let frame = env.render("frontview", width, height).unwrap();
            let object = pixels_of(&frame, SceneClass::Object);
            assert!(
                object.len() >= 20,
                "{task} seed {seed}: {} pixels",
                object.len()
            );
            let n = object.len() as f64;
            let centroid_u = object.iter().map(|p| p.0 as f64 + 0.5).sum::<f64>() / n;
            let centroid_v = object.iter().map(|p| p.1 as f64 + 0.5).sum::<f64>() / n;
            let pose = env.world().object_pose().unwrap();
            let camera = env.camera("frontview").unwrap();
            let (u, v, _) = camera
                .project(&Point3::from(pose.translation.vector), width, height)
                .unwrap();
            let off = (centroid_u - u).hypot(centroid_v - v);
            assert!(
                off <= 2.0,
                "{task} seed {seed}: centroid ({centroid_u:.2}, {centroid_v:.2}) vs ({u:.2}, {v:.2})"
            );
        }
    }
}

#[test]
fn depth_at_a_table_pixel_is_the_tables_distance() {
    // Points on bin 2's floor (top at z = 0.82), clear of the object in bin 1 and of the shadow
    // of bin 2's 8 cm walls; the goal marker there is see-through and leaves depth alone.
    const FLOOR_TOP: f64 = 0.82;
    let mut env = env("IIWA/box/no_obstacle/pick_place", 0);
    let (width, height) = (256, 256);
    for camera_name in ["frontview", "agentview", "birdview"] {
        let frame = env.render(camera_name, width, height).unwrap();
        let camera = env.camera(camera_name).unwrap();
        for point in [[0.0, 0.18], [0.05, 0.28], [-0.05, 0.08]] {
            let world = Point3::new(point[0], point[1], FLOOR_TOP);
            let (u, v, _) = camera.project(&world, width, height).unwrap();
            let (x, y) = (u.floor() as u32, v.floor() as u32);
            assert_eq!(
                frame.class_at(x, y),
                SceneClass::Arena,
                "{camera_name} {point:?}"
            );
            // The depth of the floor plane along the ray through that pixel's centre.
            let (origin, direction) = camera.ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
            let expected = (FLOOR_TOP - origin.z) / direction.z;
            let got = frame.depth_at(x, y) as f64;
            assert!(
                (got - expected).abs() < 0.01,
                "{camera_name} {point:?}: depth {got} vs the floor's {expected}"
            );
        }
    }
}

#[test]
fn the_arms_pixels_change_when_the_arm_moves_and_not_otherwise() {
    let task = "Panda/box/no_obstacle/pick_place";
    for camera in ["frontview", "sideview", "birdview"] {
        let mut first = env(task, 0);
        let before = first.render(camera, 128, 128).unwrap();
        // Another episode: the object starts elsewhere, the arm is where it was.
        let mut other = env(task, 3);
        let elsewhere = other.render(camera, 128, 128).unwrap();
        let object_moved =
            pixels_of(&before, SceneClass::Object) != pixels_of(&elsewhere, SceneClass::Object);
        assert!(
            object_moved,
            "{camera}: the object should show in another place"
        );
        let mut arm_pixels = 0;
        for i in 0..before.classes.len() {
            let near_object = [&before, &elsewhere]
                .iter()
                .any(|f| f.classes[i] == SceneClass::Object);
            if near_object {
                continue;
            }
            assert_eq!(
                before.classes[i], elsewhere.classes[i],
                "{camera} pixel {i}"
            );
            if before.classes[i] == SceneClass::Robot {
                arm_pixels += 1;
                assert_eq!(
                    before.rgb[3 * i..3 * i + 3],
                    elsewhere.rgb[3 * i..3 * i + 3]
                );
                assert_eq!(before.depth[i].to_bits(), elsewhere.depth[i].to_bits());
            }
        }
        assert!(arm_pixels > 100, "{camera}: {arm_pixels} arm pixels");

        // Turn the base joint for a few steps: the arm's pixels move.
        for _ in 0..5 {
            first
                .step(&Action::Reference([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
                .unwrap();
        }
        let after = first.render(camera, 128, 128).unwrap();
        let changed = (0..after.classes.len())
            .filter(|&i| {
                (before.classes[i] == SceneClass::Robot || after.classes[i] == SceneClass::Robot)
                    && before.rgb[3 * i..3 * i + 3] != after.rgb[3 * i..3 * i + 3]
            })
            .count();
        assert!(changed > 20, "{camera}: only {changed} arm pixels changed");
    }
}

#[test]
fn the_same_state_gives_the_same_frame_bit_for_bit() {
    let task = "Gen3/plate/object_door/shelf";
    let mut a = env(task, 4);
    let mut b = env(task, 4);
    for env in [&mut a, &mut b] {
        for _ in 0..3 {
            env.step(&Action::Reference([
                0.3, -0.2, 0.1, 0.5, 0.0, -0.4, 0.2, 1.0,
            ]))
            .unwrap();
        }
    }
    for camera in &CAMERAS {
        let first = a.render(camera.name, 96, 72).unwrap();
        let again = a.render(camera.name, 96, 72).unwrap();
        let twin = b.render(camera.name, 96, 72).unwrap();
        for other in [&again, &twin] {
            assert_eq!(first.rgb, other.rgb, "{}", camera.name);
            assert_eq!(first.classes, other.classes, "{}", camera.name);
            let bits = |f: &Frame| f.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&first), bits(other), "{}", camera.name);
        }
    }
}

#[test]
fn every_camera_sees_the_arm_and_the_scene() {
    for robot in Robot::all() {
        let task = format!("{}/hollow_box/object_wall/trash_can", robot.wire_name());
        let mut env = env(&task, 2);
        for camera in &CAMERAS {
            let frame = env.render(camera.name, 84, 84).unwrap();
            let n = frame.classes.len();
            let background = pixels_of(&frame, SceneClass::Background).len();
            assert!(
                background < n / 2,
                "{task} {}: {background} of {n} sky",
                camera.name
            );
            let robot_pixels = pixels_of(&frame, SceneClass::Robot).len();
            assert!(robot_pixels > 0, "{task} {}: no arm in view", camera.name);
            let drawn: std::collections::BTreeSet<SceneClass> =
                frame.classes.iter().copied().collect();
            assert!(drawn.len() >= 3, "{task} {}: only {drawn:?}", camera.name);
            // Flat shading still gives many shades, not one colour per class.
            let colours: std::collections::BTreeSet<&[u8]> = frame.rgb.chunks(3).collect();
            assert!(
                colours.len() >= 10,
                "{task} {}: {} colours",
                camera.name,
                colours.len()
            );
        }
    }
}

#[test]
fn the_wrist_camera_moves_with_the_hand() {
    let mut env = env("IIWA/box/no_obstacle/pick_place", 0);
    let before = env.camera("eye_in_hand").unwrap().pose;
    for _ in 0..5 {
        env.step(&Action::Reference([0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
            .unwrap();
    }
    let after = env.camera("eye_in_hand").unwrap().pose;
    assert!((after.translation.vector - before.translation.vector).norm() > 0.005);
    // The arena cameras stay put.
    let front = env.camera("frontview").unwrap().pose;
    assert_eq!(
        front,
        composuite_core::render::camera_spec("frontview")
            .unwrap()
            .optical_in_mount()
    );
}

#[test]
fn an_unknown_camera_or_size_is_refused_with_what_is_valid() {
    let mut env = env("Jaco/box/no_obstacle/push", 0);
    let message = env.render("topview", 64, 64).unwrap_err().to_string();
    assert!(message.contains("topview"), "{message}");
    for camera in &CAMERAS {
        assert!(message.contains(camera.name), "{message}");
    }
    let message = env.render("frontview", 0, 64).unwrap_err().to_string();
    assert!(message.contains("0×64"), "{message}");
    assert!(env.render("frontview", 64, 100_000).is_err());
}
