//! Frames drawn from an observation alone (`StateRenderer`, what bag videos and the ROS
//! Gymnasium env use) against frames of the simulated world (`Env::render`) at the same step.

use composuite_core::axes::{AxisElement, Robot};
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::render::{CAMERAS, Frame, SceneState, StateRenderer};

/// An environment of `task` after `steps` steps of a fixed action sequence that moves every
/// joint and the gripper.
fn moved(task: &str, steps: u32) -> Env {
    let mut env = Env::new(task.parse().unwrap(), EnvConfig::default());
    env.reset(3).unwrap();
    for i in 0..steps {
        let phase = i as f64 * 0.15;
        let mut values = [0.0; 8];
        for (j, v) in values.iter_mut().enumerate() {
            *v = (phase + j as f64).sin();
        }
        env.step(&Action::Reference(values)).unwrap();
    }
    env
}

/// Share of pixels whose colour differs by more than `tolerance` in any channel.
fn differing(a: &Frame, b: &Frame, tolerance: u8) -> f64 {
    let differ = a
        .rgb
        .chunks(3)
        .zip(b.rgb.chunks(3))
        .filter(|(p, q)| {
            p.iter()
                .zip(q.iter())
                .any(|(x, y)| x.abs_diff(*y) > tolerance)
        })
        .count();
    differ as f64 / (a.width * a.height) as f64
}

#[test]
fn a_frame_from_the_observation_matches_the_worlds_frame() {
    for robot in Robot::all() {
        let task = format!("{}/box/no_obstacle/pick_place", robot.wire_name());
        let mut env = moved(&task, 40);
        let state = SceneState::from_observation(&env.observation());
        let mut renderer = StateRenderer::new(env.task());
        for camera in CAMERAS.iter().map(|c| c.name) {
            let world = env.render(camera, 128, 128).unwrap();
            let observed = renderer.render(&state, camera, 128, 128).unwrap();
            // The same solids at poses equal up to rounding: only edge pixels may differ.
            let share = differing(&world, &observed, 2);
            assert!(
                share < 0.01,
                "{task} {camera}: {:.2} % differ",
                share * 100.0
            );
        }
    }
}

#[test]
fn the_state_follows_the_arm_it_is_read_from() {
    let env = moved("Panda/box/no_obstacle/pick_place", 0);
    let start = SceneState::from_observation(&env.observation());
    let mut renderer = StateRenderer::new(env.task());
    let before = renderer.render(&start, "frontview", 96, 96).unwrap();
    let mut env = moved("Panda/box/no_obstacle/pick_place", 30);
    let later = SceneState::from_observation(&env.observation());
    let after = renderer.render(&later, "frontview", 96, 96).unwrap();
    assert!(
        differing(&before, &after, 2) > 0.005,
        "the arm moved; the frame must change"
    );
    // The joint angles read back through cos/sin are the world's, to rounding.
    for (got, want) in later.arm.iter().zip(env.world().arm_positions()) {
        let wrapped = (got - want + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        assert!(wrapped.abs() < 1e-12, "{got} vs {want}");
    }
    assert_eq!(later.fingers, env.world().finger_positions());
    let frame = env.render("frontview", 96, 96).unwrap();
    assert!(differing(&frame, &after, 2) < 0.01);
}

#[test]
fn the_same_state_gives_the_same_frame_bit_for_bit() {
    let env = moved("Jaco/dumbbell/object_wall/shelf", 25);
    let state = SceneState::from_observation(&env.observation());
    let a = StateRenderer::new(env.task())
        .render(&state, "sideview", 80, 60)
        .unwrap();
    let mut renderer = StateRenderer::new(env.task());
    renderer.render(&state, "frontview", 80, 60).unwrap();
    let b = renderer.render(&state, "sideview", 80, 60).unwrap();
    assert_eq!(a.rgb, b.rgb);
    assert_eq!(
        a.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
        b.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>()
    );
}

#[test]
fn the_flat_vector_gives_the_factored_observations_state() {
    for with_task in [true, false] {
        let mut env = Env::new(
            "Gen3/plate/goal_wall/trash_can".parse().unwrap(),
            EnvConfig::default().task_observation(with_task),
        );
        env.reset(9).unwrap();
        env.step(&Action::Reference([
            0.3, -0.2, 0.1, 0.5, -0.4, 0.2, 0.1, 1.0,
        ]))
        .unwrap();
        let obs = env.observation();
        assert_eq!(
            SceneState::from_flat(&obs.flat()).unwrap(),
            SceneState::from_observation(&obs)
        );
    }
}

#[test]
fn bad_input_is_refused_with_what_is_valid() {
    let err = SceneState::from_flat(&[0.0; 50]).unwrap_err();
    assert!(
        err.contains("93") && err.contains("77") && err.contains("50"),
        "{err}"
    );
    let mut flat = vec![0.0; 93];
    flat[70] = f64::NAN;
    assert!(SceneState::from_flat(&flat).unwrap_err().contains("70"));
    let env = moved("IIWA/box/no_obstacle/push", 0);
    let state = SceneState::from_observation(&env.observation());
    let mut renderer = StateRenderer::new(env.task());
    let err = renderer.render(&state, "front", 64, 64).unwrap_err();
    assert!(err.to_string().contains("frontview, agentview"), "{err}");
    let err = renderer.render(&state, "frontview", 0, 64).unwrap_err();
    assert!(err.to_string().contains("4096"), "{err}");
}
