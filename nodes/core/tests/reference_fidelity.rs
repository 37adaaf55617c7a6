//! The port against the reference benchmark running: episodes recorded from CompoSuite 1fa36f6
//! on robosuite 1.4.0 / MuJoCo 2.3.7 (`tests/reference/`, how they were made and how to make
//! them again). The bounds below are the documented ones of
//! `docs/src/differences-from-reference.md` ("Measured against the reference").

mod reference;

use composuite_core::axes::AxisElement;
use composuite_core::env::EnvConfig;
use composuite_core::reward::staged_reward;
use reference::{divergence, layout};

/// Every value of every step-0 observation, quaternions included: all 256 tasks × seeds 0–4.
#[test]
fn step0_observations_equal_the_references_for_every_task_and_seed() {
    let cases = reference::step0();
    assert_eq!(cases.len(), 256 * 5, "every task, seeds 0-4");
    let mut differences = Vec::new();
    for case in &cases {
        let ours = case.ours();
        for (i, (a, b)) in ours.iter().zip(&case.observation).enumerate() {
            if (a - b).abs() > 1e-4 {
                differences.push(format!(
                    "{} seed {}: [{i}] {} ours {a:.7} reference {b:.7}",
                    case.task,
                    case.seed,
                    layout::field(i)
                ));
            }
        }
    }
    assert!(
        differences.is_empty(),
        "{} values differ by more than 1e-4, e.g.\n{}",
        differences.len(),
        differences[..differences.len().min(12)].join("\n")
    );
}

/// The reward arithmetic on the reference's own states: every stage of every record of the 32
/// episodes, fed the positions, hand axis, grasp flag and gripper action the reference used.
#[test]
fn staged_rewards_equal_the_references_on_its_own_states() {
    let mut checked = 0;
    for trajectory in reference::trajectories() {
        let task = trajectory.task;
        for r in 0..trajectory.observations.len() {
            let ours = staged_reward(task.objective, task.object, &trajectory.snapshot(r));
            let names: Vec<&str> = ours.stages.iter().map(|s| s.name).collect();
            assert_eq!(names, trajectory.stage_names, "{task}: stage names");
            for (stage, theirs) in ours.stages.iter().zip(&trajectory.staged[r]) {
                assert!(
                    (stage.value - theirs).abs() <= 1e-6,
                    "{task} seed {} record {r}: stage {} ours {} reference {theirs}",
                    trajectory.seed,
                    stage.name,
                    stage.value
                );
            }
            assert_eq!(ours.success, trajectory.success[r], "{task} record {r}");
            if let Some(reward) = trajectory.rewards[r] {
                assert!(
                    (ours.total - reward).abs() <= 1e-6,
                    "{task} seed {} record {r}: reward ours {} reference {reward}",
                    trajectory.seed,
                    ours.total
                );
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 32 * 101);
}

/// The same seed and the same 100 actions in the port and in the reference: how far the arm, the
/// grip site and the object drift apart, and how far the rewards then differ.
#[test]
fn replayed_reference_episodes_stay_within_the_documented_bounds() {
    // (step, joints mean |Δ| rad, grip site m, object m), each for the worst single episode.
    const BOUNDS: [(usize, f64, f64, f64); 3] = [
        (10, 0.006, 0.0075, 0.001),
        (30, 0.006, 0.0075, 0.001),
        (100, 0.006, 0.0075, 0.001),
    ];
    const REWARD_BOUND: f64 = 0.005;
    let mut report = Vec::new();
    let mut worst = [0.0f64; 3];
    let mut worst_reward_all: f64 = 0.0;
    for trajectory in reference::trajectories() {
        let ours = trajectory.replay(EnvConfig::default());
        assert_eq!(
            ours.observations.len(),
            trajectory.observations.len(),
            "{} seed {}: the port ended the episode early",
            trajectory.task,
            trajectory.seed
        );
        let worst_reward = ours.rewards[1..]
            .iter()
            .zip(&trajectory.rewards[1..])
            .map(|(a, b)| (a.expect("a reward") - b.expect("a reward")).abs())
            .fold(0.0, f64::max);
        worst_reward_all = worst_reward_all.max(worst_reward);
        assert!(
            worst_reward <= REWARD_BOUND,
            "{} seed {}: rewards differ by {worst_reward:.4}",
            trajectory.task,
            trajectory.seed
        );
        for (step, joints, eef, object) in BOUNDS {
            let d = divergence(&ours.observations[step], &trajectory.observations[step]);
            worst[0] = worst[0].max(d.joints);
            worst[1] = worst[1].max(d.eef);
            worst[2] = worst[2].max(d.object);
            if d.joints > joints || d.eef > eef || d.object > object {
                report.push(format!(
                    "{} seed {} after {step} steps: joints {:.4} rad, grip site {:.4} m, object {:.4} m",
                    trajectory.task, trajectory.seed, d.joints, d.eef, d.object
                ));
            }
        }
    }
    eprintln!(
        "worst episode: joints {:.4} rad, grip site {:.4} m, object {:.5} m, reward {:.4}",
        worst[0], worst[1], worst[2], worst_reward_all
    );
    assert!(report.is_empty(), "over the bounds:\n{}", report.join("\n"));
}

#[test]
fn the_random_policys_actions_are_the_references_bit_for_bit() {
    let tasks = reference::random_returns();
    assert_eq!(tasks.len(), 16);
    for t in &tasks {
        assert_eq!(t.episodes.len(), 10, "{}", t.task);
        for e in &t.episodes {
            let first = reference::numpy_random::DefaultRng::new(e.action_seed()).action();
            assert_eq!(
                first.map(f64::to_bits),
                e.first_action.map(f64::to_bits),
                "{} episode {}: default_rng({}) gave {first:?}, the reference {:?}",
                t.task,
                e.seed,
                e.action_seed(),
                e.first_action
            );
        }
    }
}

/// The uniform random policy's mean return per objective, ours against the reference's, with
/// the same seeds and actions: within 10 % (the documented target). The first 3 of the 10
/// recorded episodes of each task keep this test short; `--example reference_random_returns`
/// runs all of them (measured: every objective within 2.7 %).
#[test]
fn random_policy_returns_per_objective_within_10_percent_of_the_references() {
    let mut sums: std::collections::BTreeMap<String, (f64, f64)> = Default::default();
    for t in reference::random_returns() {
        for e in t.episodes.iter().take(3) {
            let (ours, _, length) = reference::random_episode(t.task, e);
            assert_eq!(length, e.length, "{} episode {}: length", t.task, e.seed);
            let sum = sums
                .entry(t.task.objective.wire_name().to_string())
                .or_default();
            sum.0 += ours;
            sum.1 += e.episode_return;
        }
    }
    assert_eq!(sums.len(), 4, "every objective");
    for (objective, (ours, reference)) in sums {
        let difference = (ours - reference) / reference;
        assert!(
            difference.abs() < 0.10,
            "{objective}: summed random-policy return {ours:.3}, reference {reference:.3} ({:+.1} %)",
            100.0 * difference
        );
    }
}

/// Torsional friction: each object on bin 1's floor turned by a torque about the vertical for
/// 1 s, on a ladder of torques (`spin.json`). The break-away torque — the smallest on the ladder
/// that turns the object more than 1 rad — is within a factor of 2 of the reference's, and below
/// both the object holds (under 0.1 rad). Measured: box 0.05 and hollow box 0.2 N·m in both,
/// plate 0.05 in both (it stands on its stem, whose torsional coefficient is 0.005), dumbbell
/// 1.5 in the reference and 2.5 here (without torsional friction: 0.1). The dumbbell's cap here
/// is its coefficient times its weight, 2.01 N·m; the reference's is lower because MuJoCo 2.3.7
/// touches a cylinder to a box at one point, on the disc's rim, where ~1 N of sliding friction
/// already holds it at rest and shares the elliptic friction cone with the spin.
#[test]
fn objects_resist_spinning_on_the_floor_as_the_references_do() {
    let spins = reference::spins();
    let mut by_task: std::collections::BTreeMap<String, Vec<(f64, f64, f64)>> = Default::default();
    for spin in &spins {
        let (ours, _) = spin.ours();
        let turned = |yaw: &[f64]| reference::Spin::turned(yaw, spin.torque_steps).abs();
        by_task.entry(spin.task.to_string()).or_default().push((
            spin.torque,
            turned(&spin.yaw),
            turned(&ours),
        ));
    }
    assert_eq!(by_task.len(), 4, "every object");
    for (task, ladder) in by_task {
        let table: Vec<String> = ladder
            .iter()
            .map(|(t, r, o)| format!("{t} N·m: reference {r:.3} rad, ours {o:.3} rad"))
            .collect();
        let table = table.join("\n");
        let rung = |pick: fn(&(f64, f64, f64)) -> f64| {
            ladder
                .iter()
                .position(|r| pick(r) > 1.0)
                .unwrap_or_else(|| panic!("{task}: never turns on the ladder\n{table}"))
        };
        let (reference_rung, our_rung) = (rung(|r| r.1), rung(|r| r.2));
        let ratio = ladder[our_rung].0 / ladder[reference_rung].0;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "{task}: break-away at {} N·m, the reference's at {} N·m\n{table}",
            ladder[our_rung].0,
            ladder[reference_rung].0,
        );
        for (torque, reference, ours) in &ladder[..reference_rung.min(our_rung)] {
            assert!(
                *reference < 0.1 && *ours < 0.1,
                "{task}: {torque} N·m, below break-away, turns the reference {reference:.3} rad, ours {ours:.3} rad"
            );
        }
    }
}

/// Contact-rich episodes: the port's scripted plans for 12 tasks × 2 seeds (every element at
/// least twice: grasps from the top and the side, carries, pushes, placing in a bin, a shelf and
/// a trash can) played in both engines through the reference's controller, each closing the loop
/// on its own observation. Measured: 23 of 24 episodes end alike (21 succeed in both, 2 fail in
/// both; the odd one is a dumbbell released over the trash can that stays lodged on the can's
/// rim in the reference and falls in here), first successes within 47 control steps of the
/// reference's (20 of 21 within 9), the grasp flag equal at 98.9 % of the samples, the object's
/// median distance from the reference's at most 39 mm in an episode that ends alike.
#[test]
fn scripted_grasps_succeed_in_both_engines_alike() {
    let plans = reference::grasp_plans();
    let runs = reference::grasp_runs();
    assert_eq!(plans.len(), 24, "12 tasks × 2 seeds");
    assert_eq!(runs.len(), plans.len());
    let (mut flags, mut flags_equal, mut both_succeed) = (0, 0, 0);
    let mut differently = Vec::new();
    for (plan, (task, seed, theirs)) in plans.iter().zip(&runs) {
        assert_eq!(
            (plan.task, plan.seed),
            (*task, *seed),
            "plans and runs in one order"
        );
        let ours = plan.ours();
        let episode = format!("{task} seed {seed}");
        let (n, equal) = ours.grasp_flags_equal(theirs);
        flags += n;
        flags_equal += equal;
        if ours.first_success.is_some() != theirs.first_success.is_some() {
            differently.push(format!(
                "{episode}: success at step {:?} here, {:?} in the reference",
                ours.first_success, theirs.first_success
            ));
            continue;
        }
        if let (Some(o), Some(t)) = (ours.first_success, theirs.first_success) {
            both_succeed += 1;
            assert!(
                o.abs_diff(t) <= GRASP_SUCCESS_STEPS,
                "{episode}: first success at step {o} here, {t} in the reference"
            );
        }
        let gaps = ours.sorted_object_gaps(theirs);
        let median = gaps[gaps.len() / 2];
        assert!(
            median <= GRASP_OBJECT_MEDIAN_M,
            "{episode}: the object {:.1} mm from the reference's (median over the episode)",
            1e3 * median
        );
    }
    assert!(
        differently.len() <= GRASP_EPISODES_ENDING_DIFFERENTLY,
        "episodes that end differently:\n{}",
        differently.join("\n")
    );
    let agreement = flags_equal as f64 / flags as f64;
    assert!(
        agreement >= GRASP_FLAG_AGREEMENT,
        "grasp flags equal at {:.1} % of the samples",
        100.0 * agreement
    );
    assert!(
        both_succeed >= 18,
        "the comparison covers successes: {both_succeed}"
    );
}

/// Bounds of [`scripted_grasps_succeed_in_both_engines_alike`] (measured: see its comment and
/// `docs/src/differences-from-reference.md`).
const GRASP_EPISODES_ENDING_DIFFERENTLY: usize = 2;
const GRASP_SUCCESS_STEPS: usize = 60;
const GRASP_FLAG_AGREEMENT: f64 = 0.97;
const GRASP_OBJECT_MEDIAN_M: f64 = 0.05;
