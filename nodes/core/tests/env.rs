//! The environment: observation layout, reference-exact starts, episodes, all 256 tasks.

mod common;

use composuite_core::arena::object_start_region;
use composuite_core::axes::{AxisElement, Object, Objective, Obstacle, Robot};
use composuite_core::env::{Action, Env, EnvConfig, EnvError, sample_object_start};
use composuite_core::obs::{FLAT_SIZE_WITH_TASK, FLAT_SIZE_WITHOUT_TASK};
use composuite_core::{TaskSpec, all_tasks};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};

fn env(task: &str) -> Env {
    Env::new(task.parse().unwrap(), EnvConfig::default())
}

/// Object starts computed with numpy's own generator, following docs/src/reference-facts.md §7.3's
/// draw order (7 normals; 2 obstacle uniforms if any; x, y per attempt with rejection).
#[test]
fn starts_match_numpy_for_the_same_seed() {
    let pinned = [
        (
            Obstacle::NoObstacle,
            Object::Box,
            0,
            0.17418604168016472,
            -0.2844772810465867,
        ),
        (
            Obstacle::NoObstacle,
            Object::Box,
            42,
            0.023293519087328393,
            -0.16131893104598122,
        ),
        (
            Obstacle::ObjectWall,
            Object::Dumbbell,
            7,
            0.1488094113314854,
            -0.3294501844950552,
        ),
        (
            Obstacle::ObjectDoor,
            Object::Plate,
            123,
            0.15122855510640754,
            -0.3172418734407561,
        ),
        (
            Obstacle::GoalWall,
            Object::HollowBox,
            2024,
            0.11270361883700769,
            -0.17965070189637503,
        ),
        (
            Obstacle::ObjectWall,
            Object::Plate,
            5,
            0.1588035672649073,
            -0.19955043676485681,
        ),
    ];
    for (obstacle, object, seed, x, y) in pinned {
        let p = sample_object_start(obstacle, object, seed).unwrap();
        assert_eq!((p.x, p.y), (x, y), "{obstacle:?} {object:?} seed {seed}");
    }
    assert_eq!(
        sample_object_start(Obstacle::NoObstacle, Object::Box, 1 << 32),
        Err(EnvError::BadSeed(1 << 32))
    );
}

#[test]
fn starts_stay_in_the_region_and_repeat_for_a_seed() {
    for obstacle in Obstacle::all() {
        for object in Object::all() {
            let region = object_start_region(obstacle, object);
            for seed in 0..200 {
                let p = sample_object_start(obstacle, object, seed).unwrap();
                let [x0, x1] = region.world_x();
                let [y0, y1] = region.world_y();
                assert!(
                    (x0..=x1).contains(&p.x) && (y0..=y1).contains(&p.y),
                    "{obstacle:?} {object:?} {seed}: {p}"
                );
                assert!(region.is_clear(p.x, p.y));
                assert_eq!(p, sample_object_start(obstacle, object, seed).unwrap());
            }
        }
    }
}

#[test]
fn observation_layout_matches_the_reference() {
    let mut e = env("Gen3/plate/no_obstacle/shelf");
    let obs = e.reset(3).unwrap();
    let flat = obs.flat();
    assert_eq!(flat.len(), FLAT_SIZE_WITH_TASK);
    // Index ranges (docs/src/reference-facts.md §5): object 0-13, obstacle 14-27, goal 28-44,
    // one-hots 45-60 (object, robot, obstacle, objective), proprio 61-92.
    assert_eq!(&flat[0..3], &obs.object.position);
    assert_eq!(&flat[14..17], &[0.0; 3], "no obstacle: position 0");
    assert_eq!(&flat[17..21], &[0.0; 4], "no obstacle: zero quaternion");
    assert_ne!(
        &flat[21..24],
        &[0.0; 3],
        "no obstacle: world origin seen from the eef"
    );
    assert_eq!(
        &flat[31..35],
        &[0.0, 0.0, 0.0, 1.0],
        "goal orientation is identity"
    );
    assert_eq!(
        &flat[45..49],
        &[0.0, 0.0, 1.0, 0.0],
        "object one-hot: Box, Dumbbell, Plate, Hollowbox"
    );
    assert_eq!(
        &flat[49..53],
        &[0.0, 0.0, 0.0, 1.0],
        "robot one-hot: IIWA, Jaco, Panda, Kinova3"
    );
    assert_eq!(
        &flat[53..57],
        &[1.0, 0.0, 0.0, 0.0],
        "obstacle one-hot: None first"
    );
    assert_eq!(
        &flat[57..61],
        &[0.0, 0.0, 1.0, 0.0],
        "objective one-hot: PickPlace, Push, Shelf, Trashcan"
    );
    let q = e.world().arm_positions();
    assert_eq!(flat[61], q[0].cos());
    assert_eq!(flat[68], q[0].sin());
    assert_eq!(&flat[82..85], &obs.robot.eef_position);
    // obj_to_goal = goal − object
    for i in 0..3 {
        assert_eq!(
            flat[42 + i],
            obs.goal.pose.position[i] - obs.object.position[i]
        );
    }
    // The grip site is the eef point: the eef-relative position of the object is R^T (p - p_eef).
    let mut e2 = Env::new(e.task(), EnvConfig::default().task_observation(false));
    assert_eq!(e2.reset(3).unwrap().flat().len(), FLAT_SIZE_WITHOUT_TASK);

    let mut walled = env("IIWA/box/object_wall/pick_place");
    let flat = walled.reset(0).unwrap().flat();
    assert!(
        (flat[14] - 0.00909).abs() < 1e-4 && flat[15] == -0.26 && flat[16] == 0.925,
        "{:?}",
        &flat[14..17]
    );
    assert!(
        (flat[19] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12
            && (flat[20] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12
    );
}

#[test]
fn episodes_end_and_refuse_further_steps() {
    let mut e = Env::new(
        "Panda/box/no_obstacle/pick_place".parse().unwrap(),
        EnvConfig::default().horizon(3),
    );
    assert_eq!(
        e.step(&Action::Reference([0.0; 8])).unwrap_err(),
        EnvError::NotReset
    );
    e.reset(1).unwrap();
    for i in 1..=3 {
        let step = e.step(&Action::Reference([0.0; 8])).unwrap();
        assert_eq!(step.truncated, i == 3);
        assert!(!step.terminated);
    }
    let err = e.step(&Action::Reference([0.0; 8])).unwrap_err();
    assert_eq!(
        err,
        EnvError::EpisodeOver {
            episode: 1,
            steps: 3
        }
    );
    assert!(err.to_string().contains("reset"), "{err}");
    e.reset(2).unwrap();
    assert_eq!(e.episode(), 2);
    assert!(e.step(&Action::Reference([0.0; 8])).is_ok());
    // Bad actions are refused and change nothing.
    let mut bad = [0.0; 8];
    bad[3] = f64::NAN;
    assert!(
        e.step(&Action::Reference(bad))
            .unwrap_err()
            .to_string()
            .contains("action[3] is NaN")
    );
    assert_eq!(e.steps(), 1);
}

/// Push ends as soon as the object is more than 10 cm above the bin top
/// (docs/src/reference-facts.md §1): grasp the box through the environment's own actions (absolute
/// targets from IK) and lift it.
#[test]
fn push_terminates_when_the_object_is_lifted() {
    let mut e = env("Panda/box/no_obstacle/push");
    e.reset(0).unwrap();
    let start = e.object_start().coords;
    let down = common::pointing_down(e.world());
    let above = common::pads_at(
        e.world(),
        start + Vector3::new(0.0, 0.0, 0.12),
        down,
        &e.world().arm_positions(),
    );
    let at = common::pads_at(e.world(), start, down, &above);
    let lifted = common::pads_at(e.world(), start + Vector3::new(0.0, 0.0, 0.2), down, &at);
    let open = Some((0.08, 0.0));
    let mut last = e.world().arm_positions();
    for (target, seconds, gripper) in [
        (above, 2.0, open),
        (at, 1.5, open),
        (at, 0.5, Some((0.0, 0.0))),
        (lifted, 2.0, None),
    ] {
        for q in common::path(&last, &target, seconds) {
            let step = e.step(&Action::Absolute { joints: q, gripper }).unwrap();
            if step.terminated {
                let z = step.observation.object.position[2];
                assert!(z - 0.8 > 0.1, "terminated with the object at z {z}");
                assert_eq!(
                    step.info.termination,
                    Some(composuite_core::reward::Termination::ObjectLifted)
                );
                assert!(
                    step.info.staged.stage("grasp").unwrap().value > 0.0,
                    "the box was grasped"
                );
                let err = e
                    .step(&Action::Absolute { joints: q, gripper })
                    .unwrap_err();
                assert!(matches!(err, EnvError::EpisodeOver { .. }));
                return;
            }
        }
        last = target;
    }
    panic!(
        "lifting the box 20 cm did not end the push episode; object at {:?}",
        e.world().object_pose()
    );
}

#[test]
fn same_seed_and_actions_give_bit_identical_trajectories() {
    let run = |task: &str| {
        let mut e = env(task);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut bits = Vec::new();
        // A previous episode must not influence the next one.
        e.reset(3).unwrap();
        for _ in 0..5 {
            let _ = e.step(&Action::Reference([1.0; 8]));
        }
        bits.extend(e.reset(11).unwrap().flat().iter().map(|v| v.to_bits()));
        for _ in 0..60 {
            let a: [f64; 8] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let step = e.step(&Action::Reference(a)).unwrap();
            bits.extend(step.observation.flat().iter().map(|v| v.to_bits()));
            bits.push(step.reward.to_bits());
        }
        bits
    };
    for task in [
        "Jaco/dumbbell/object_door/shelf",
        "Panda/plate/goal_wall/trash_can",
    ] {
        let a = run(task);
        assert_eq!(a, run(task), "{task}");
        let mut fresh = env(task);
        let first: Vec<u64> = fresh
            .reset(11)
            .unwrap()
            .flat()
            .iter()
            .map(|v| v.to_bits())
            .collect();
        assert_eq!(
            first,
            a[..first.len()],
            "{task}: history leaked into the reset"
        );
    }
}

/// docs/src/reference-facts.md §4.3: the reference's gripper command c starts at 0 with the fingers
/// open, so with a[7] = 0 the fingers drift half closed; +1 closes them in 4 steps.
#[test]
fn reference_gripper_follows_the_sign_of_the_action() {
    let mut e = env("IIWA/box/no_obstacle/pick_place");
    e.reset(0).unwrap();
    let open = e.world().finger_positions()[0];
    e.step(&Action::Reference([0.0; 8])).unwrap();
    let half = e.world().finger_positions()[0];
    assert!(
        half < open - 0.003,
        "fingers should drift toward mid-range: {open} -> {half}"
    );
    let mut close = [0.0; 8];
    close[7] = 1.0;
    for _ in 0..4 {
        e.step(&Action::Reference(close)).unwrap();
    }
    assert!((e.world_state().gripper_target - 1.0).abs() < 1e-12);
    assert!(e.world().finger_positions()[0] < -0.005);
}

/// Every one of the 256 tasks builds, resets with 3 seeds and survives 500 random reference
/// actions: no NaN, the object never falls through anything, reward in [0, 1], reward = 1
/// exactly on success.
#[test]
fn all_256_tasks_run_random_episodes() {
    let tasks: Vec<TaskSpec> = all_tasks();
    assert_eq!(tasks.len(), 256);
    let threads = 2;
    std::thread::scope(|scope| {
        for part in 0..threads {
            let tasks = &tasks;
            scope.spawn(move || {
                for (i, task) in tasks
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| i % threads == part)
                {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(i as u64);
                    let mut e = Env::new(*task, EnvConfig::default());
                    for seed in [0, 1, 2] {
                        let obs = e.reset(seed).unwrap();
                        assert!(
                            obs.flat().iter().all(|v| v.is_finite()),
                            "{task} seed {seed}: reset"
                        );
                        loop {
                            let a: [f64; 8] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
                            let step = e.step(&Action::Reference(a)).unwrap();
                            let flat = step.observation.flat();
                            assert!(
                                flat.iter().all(|v| v.is_finite()),
                                "{task} seed {seed} step {}: NaN",
                                e.steps()
                            );
                            assert!(
                                flat[2] > 0.5,
                                "{task} seed {seed} step {}: object at z {}",
                                e.steps(),
                                flat[2]
                            );
                            assert!(
                                (0.0..=1.0).contains(&step.reward),
                                "{task}: reward {}",
                                step.reward
                            );
                            assert_eq!(step.reward == 1.0, step.info.success, "{task}");
                            if step.terminated || step.truncated {
                                break;
                            }
                        }
                        assert!(
                            e.steps() == 500 || task.objective == Objective::Push,
                            "{task}: ended at {}",
                            e.steps()
                        );
                    }
                }
            });
        }
    });
    let _ = Robot::all();
}

/// The reference's `reward_shaping=False` and `reward_scale`: sparse rewards are 0 until
/// success, a scale multiplies every reward, and the stages are reported either way. The
/// scripted expert reaches success, so both sides of the sparse rule are exercised.
#[test]
fn sparse_and_scaled_rewards_follow_the_staged_ones() {
    let task: TaskSpec = "IIWA/box/no_obstacle/pick_place".parse().unwrap();
    let run = |config: EnvConfig| {
        let mut env = Env::new(task, config);
        env.reset(0).unwrap();
        let mut expert = composuite_core::expert::Expert::new(task);
        let mut steps = Vec::new();
        while env.ended().is_none() {
            let step = env.step(&expert.act(&env)).unwrap();
            steps.push((step.reward, step.info.staged.total, step.info.success));
        }
        steps
    };
    let shaped = run(EnvConfig::default());
    let sparse = run(EnvConfig::default().reward_shaping(false));
    let scaled = run(EnvConfig::default().reward_scale(2.5));
    assert!(shaped.iter().any(|s| s.2), "the expert succeeds");
    assert!(shaped.iter().any(|s| !s.2 && s.0 > 0.0));
    for ((a, b), c) in shaped.iter().zip(&sparse).zip(&scaled) {
        assert_eq!(b.0, if a.2 { 1.0 } else { 0.0 }, "sparse");
        assert_eq!(b.1, a.1, "stages unchanged");
        assert_eq!(c.0, 2.5 * a.0, "scaled");
    }
}

/// `Env::set_object_state` teleports the object: the next step starts from there, and bad
/// states are refused before anything moves.
#[test]
fn set_object_state_moves_the_object_and_refuses_bad_states() {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    let mut env = env("IIWA/box/no_obstacle/pick_place");
    let at = Isometry3::from_parts(
        Translation3::new(0.05, 0.2, 0.95),
        UnitQuaternion::identity(),
    );
    let zero = Vector3::zeros();
    assert!(
        env.set_object_state(&at, &zero, &zero)
            .unwrap_err()
            .contains("reset")
    );
    env.reset(1).unwrap();
    let start = env.world_state().object_pose;
    let far = Isometry3::translation(10.0, 0.0, 1.0);
    assert!(
        env.set_object_state(&far, &zero, &zero)
            .unwrap_err()
            .contains("outside")
    );
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    assert!(
        env.set_object_state(&at, &nan, &zero)
            .unwrap_err()
            .contains("non-finite")
    );
    assert_eq!(
        env.world_state().object_pose,
        start,
        "a refused state moves nothing"
    );

    env.set_object_state(&at, &Vector3::new(0.0, 0.0, 0.5), &zero)
        .unwrap();
    let now = env.world_state();
    assert!((now.object_pose.translation.vector - at.translation.vector).norm() < 1e-6);
    assert!((now.object_linear_velocity.z - 0.5).abs() < 1e-6);
    let before = env.observation().flat();
    env.step(&Action::Reference([0.0; 8])).unwrap();
    let after = env.world_state().object_pose.translation.vector;
    // Thrown up at 0.5 m/s from 0.95 m: higher after one 50 ms period, far from its start.
    assert!(after.z > 0.95, "{after:?}");
    assert!((after - start.translation.vector).norm() > 0.1);
    assert_ne!(before, env.observation().flat());
}
