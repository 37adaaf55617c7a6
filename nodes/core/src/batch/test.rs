use super::*;
use crate::env::Step;

fn tasks() -> Vec<TaskSpec> {
    [
        "IIWA/box/no_obstacle/pick_place",
        "Jaco/plate/object_wall/shelf",
        "Gen3/dumbbell/goal_wall/push",
        "Panda/hollow_box/object_door/trash_can",
    ]
    .iter()
    .map(|t| t.parse().unwrap())
    .collect()
}

/// A deterministic action sequence that moves every joint and the gripper.
fn action(env: usize, step: u32) -> Action {
    Action::Reference(std::array::from_fn(|j| {
        (((env * 7 + j * 3) as f64 + f64::from(step) * 0.37).sin()).clamp(-1.0, 1.0)
    }))
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

fn run_batch(threads: usize, steps: u32) -> Vec<BatchResults> {
    let tasks = tasks();
    let mut batch = EnvBatch::new(&tasks, EnvConfig::default().horizon(40), threads).unwrap();
    let mut out = BatchResults::new(&batch);
    let resets: Vec<_> = (0..tasks.len())
        .map(|i| BatchCommand::Reset(i as u64 + 3))
        .collect();
    batch.run(&resets, &mut out.view()).unwrap();
    let mut history = vec![out.clone()];
    for step in 0..steps {
        let commands: Vec<_> = (0..tasks.len())
            .map(|i| match batch.env(i).ended() {
                Some(_) => BatchCommand::Reset(100 + i as u64),
                None => BatchCommand::Step(action(i, step)),
            })
            .collect();
        batch.run(&commands, &mut out.view()).unwrap();
        history.push(out.clone());
    }
    history
}

#[test]
fn a_batch_steps_each_environment_as_env_does_alone() {
    let history = run_batch(2, 50);
    for (i, task) in tasks().into_iter().enumerate() {
        let mut env = Env::new(task, EnvConfig::default().horizon(40));
        let first = env.reset(i as u64 + 3).unwrap();
        let size = first.flat().len();
        let row = |r: &BatchResults| r.observations[i * size..(i + 1) * size].to_vec();
        assert_eq!(
            bits(&first.flat()),
            bits(&row(&history[0])),
            "env {i} reset"
        );
        for (step, results) in history[1..].iter().enumerate() {
            if env.ended().is_some() {
                let obs = env.reset(100 + i as u64).unwrap();
                assert_eq!(bits(&obs.flat()), bits(&row(results)), "env {i} autoreset");
                assert_eq!(results.steps[i], 0);
                continue;
            }
            let Step {
                observation,
                reward,
                terminated,
                truncated,
                info,
            } = env.step(&action(i, step as u32)).unwrap();
            let at = format!("env {i} ({task}) step {step}");
            assert_eq!(bits(&observation.flat()), bits(&row(results)), "{at}");
            assert_eq!(reward.to_bits(), results.rewards[i].to_bits(), "{at}");
            assert_eq!(terminated, results.terminated[i], "{at}");
            assert_eq!(truncated, results.truncated[i], "{at}");
            assert_eq!(info.success, results.success[i], "{at}");
            let stages: Vec<f64> = info.staged.stages.iter().map(|s| s.value).collect();
            let row_stages = &results.stage_values[i * MAX_STAGES..(i + 1) * MAX_STAGES];
            assert_eq!(bits(&stages), bits(&row_stages[..stages.len()]), "{at}");
            assert!(row_stages[stages.len()..].iter().all(|v| *v == 0.0), "{at}");
            assert_eq!(
                info.staged.current_stage().map_or(-1, |c| c as i8),
                results.current_stage[i],
                "{at}"
            );
            assert_eq!(env.steps(), results.steps[i], "{at}");
        }
    }
    // The horizon of 40 ended every episode at least once in 50 steps.
    assert!(history.iter().any(|r| r.truncated.iter().all(|t| *t)));
}

#[test]
fn one_thread_and_three_give_the_same_bits() {
    let one = run_batch(1, 45);
    let three = run_batch(3, 45);
    for (step, (a, b)) in one.iter().zip(&three).enumerate() {
        assert_eq!(bits(&a.observations), bits(&b.observations), "step {step}");
        assert_eq!(bits(&a.rewards), bits(&b.rewards), "step {step}");
        assert_eq!(a, b, "step {step}");
    }
}

#[test]
fn a_refused_command_names_its_environment_and_moves_none() {
    let tasks = tasks();
    let mut batch = EnvBatch::new(&tasks[..2], EnvConfig::default(), 2).unwrap();
    let mut out = BatchResults::new(&batch);
    let err = batch
        .run(
            &[BatchCommand::Step(action(0, 0)), BatchCommand::Idle],
            &mut out.view(),
        )
        .unwrap_err();
    assert_eq!(err.index, 0);
    assert_eq!(err.error, EnvError::NotReset);
    batch
        .run(
            &[BatchCommand::Reset(1), BatchCommand::Reset(2)],
            &mut out.view(),
        )
        .unwrap();
    let mut bad = [0.0; 8];
    bad[3] = f64::NAN;
    let before = out.clone();
    let err = batch
        .run(
            &[
                BatchCommand::Step(action(0, 0)),
                BatchCommand::Step(Action::Reference(bad)),
            ],
            &mut out.view(),
        )
        .unwrap_err();
    assert_eq!(err.index, 1);
    assert!(
        err.to_string().contains("environment 1: action[3] is NaN"),
        "{err}"
    );
    assert_eq!(out, before, "a refused call writes nothing");
    assert_eq!(batch.env(0).steps(), 0, "environment 0 was not stepped");
    let err = batch
        .run(
            &[BatchCommand::Idle, BatchCommand::Reset(u64::MAX)],
            &mut out.view(),
        )
        .unwrap_err();
    assert!(matches!(err.error, EnvError::BadSeed(_)), "{err}");
}

#[test]
fn an_idle_environment_keeps_its_state_and_row() {
    let tasks = tasks();
    let mut batch = EnvBatch::new(&tasks[..2], EnvConfig::default(), 2).unwrap();
    let mut out = BatchResults::new(&batch);
    batch
        .run(
            &[BatchCommand::Reset(1), BatchCommand::Reset(2)],
            &mut out.view(),
        )
        .unwrap();
    let size = batch.observation_size();
    let row1 = out.observations[size..].to_vec();
    batch
        .run(
            &[BatchCommand::Step(action(0, 0)), BatchCommand::Idle],
            &mut out.view(),
        )
        .unwrap();
    assert_eq!(batch.env(1).steps(), 0);
    assert_eq!(bits(&out.observations[size..]), bits(&row1));
    assert_eq!(out.steps, [1, 0]);
}

#[test]
fn max_stages_is_the_widest_objective() {
    use crate::axes::{AxisElement, Objective};
    let widest = Objective::all()
        .into_iter()
        .map(|o| crate::reward::stage_specs(o).len())
        .max()
        .unwrap();
    assert_eq!(MAX_STAGES, widest);
}

#[test]
fn bad_batches_are_refused() {
    assert_eq!(
        EnvBatch::new(&[], EnvConfig::default(), 1).err(),
        Some(BatchBuildError::Empty)
    );
    assert_eq!(
        EnvBatch::new(&tasks(), EnvConfig::default(), 0).err(),
        Some(BatchBuildError::NoThreads)
    );
}

#[test]
fn reset_from_a_generator_seeded_as_numpy_equals_reset_with_the_seed() {
    let tasks = tasks();
    let mut batch = EnvBatch::new(&tasks, EnvConfig::default(), 1).unwrap();
    let mut seeded = BatchResults::new(&batch);
    let resets: Vec<_> = (0..tasks.len()).map(|_| BatchCommand::Reset(17)).collect();
    batch.run(&resets, &mut seeded.view()).unwrap();
    let mut drawn = BatchResults::new(&batch);
    for index in 0..tasks.len() {
        let mut rng = Mt19937::numpy_seed(17);
        batch
            .reset_from(index, &mut rng, &mut drawn.view())
            .unwrap();
        assert_eq!(batch.env(index).seed(), crate::env::UNSEEDED);
        // 7 normals take at least 4 accepted pairs (16 words) and leave the 8th cached; the
        // object's x, y and the goal's two draws take 2 words each.
        let (_, pos, gauss) = rng.numpy_state();
        assert!(pos >= 16 + 4 + 4, "{pos}");
        assert!(gauss.is_some());
    }
    assert_eq!(bits(&seeded.observations), bits(&drawn.observations));
}
