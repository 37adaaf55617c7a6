//! The planned expert (issue 49, in progress): it acts only with the reference's 8 numbers,
//! solves the tasks it covers so far, and its episodes are demonstrations — replaying the
//! stored actions reproduces them bit for bit.

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::{PLANNED_EXPERT_REVISION, PlannedExpert, Stage, run_planned_episode};

/// The planned expert succeeds in every episode of task `name` on `seeds`.
fn assert_solves(name: &str, seeds: &[u64]) {
    let task: TaskSpec = name.parse().unwrap();
    for &seed in seeds {
        let outcome = run_planned_episode(task, seed);
        assert!(outcome.success, "{name} seed {seed}: {outcome:?}");
    }
}

/// Tasks it solves on every seed tried (measured on seeds 0–9 when pinned): top grasps of the
/// box and the hollow box, every arm, pick_place, trash_can and push, behind each obstacle
/// that it handles so far.
#[test]
fn the_planned_expert_solves_top_grasp_tasks() {
    let tasks = [
        ("IIWA/box/no_obstacle/pick_place", [0, 1]),
        ("Jaco/hollow_box/object_wall/trash_can", [0, 1]),
        ("Gen3/box/object_door/push", [0, 1]),
        ("Panda/hollow_box/goal_wall/pick_place", [0, 1]),
    ];
    for (name, seeds) in tasks {
        assert_solves(name, &seeds);
    }
}

/// Side grasps it failed on every seed before (2026-11-29, seeds 0–1) and solves on all of
/// seeds 0–9 now: the plate through the door into the trash can (its pre-grasp reached with
/// the least largest-joint move, a detour searched again), the dumbbell past the goal wall into
/// the shelf (a path planned all the way in where no straight slide keeps the forearm off the
/// wall).
#[test]
fn the_planned_expert_solves_side_grasp_tasks_behind_obstacles() {
    for name in [
        "IIWA/plate/object_door/trash_can",
        "Jaco/dumbbell/goal_wall/shelf",
    ] {
        assert_solves(name, &[0, 1]);
    }
}

/// The dumbbell behind the door, where no grasp at the usual pitch had a way in (2026-11-29,
/// seeds 0–1: every episode ended at its start): the steeper grasp, the wrist coming down from
/// above the door's posts, takes it to the bin and into the trash can.
#[test]
fn the_planned_expert_takes_the_dumbbell_through_the_door_with_a_steeper_grasp() {
    for (name, seed) in [
        ("IIWA/dumbbell/object_door/pick_place", 0),
        ("Panda/dumbbell/object_door/trash_can", 1),
    ] {
        assert_solves(name, &[seed]);
    }
}

/// The plate pushed from behind the object wall, which failed on seeds 0 and 1 before
/// (2026-11-29; 4 of seeds 0–9, all 10 now): from a grasp pointing towards bin 2 the wrist stood
/// over the wall and the push dragged it along the wall; a grasp is now chosen from which the
/// push's lines keep the arm clear.
#[test]
fn the_planned_expert_pushes_the_plate_from_behind_the_object_wall() {
    assert_solves("IIWA/plate/object_wall/push", &[0, 1]);
}

/// Pushes past the goal wall it failed before (2026-11-30, seeds 0–9: the Jaco's plate 0 of
/// 10, its box 2) and solves now: the plate held by its rim, the gripper turned about the
/// vertical on the way from the wall's end to the goal so that it does not end reaching back
/// across the wall's line; the box taken round the wall's end as high as a push allows, the
/// forearm over the wall's top corner.
#[test]
fn the_planned_expert_pushes_round_the_goal_wall() {
    assert_solves("Jaco/plate/goal_wall/push", &[0, 1]);
    assert_solves("Jaco/box/goal_wall/push", &[0]);
}

/// Pushes out from behind the door it failed before (2026-11-30, seeds 0–9: the Gen3's plate
/// 0 of 10) and solves now: the gripper, which reached in through the opening, turns about the
/// vertical on the way to bin 2 instead of swinging into the door's post.
#[test]
fn the_planned_expert_pushes_the_plate_out_from_behind_the_door() {
    assert_solves("Gen3/plate/object_door/push", &[0, 1]);
}

/// Shelf tasks it failed before (2026-11-30, seeds 0–9: the IIWA's box past the goal wall and
/// the Gen3's dumbbell with no obstacle, 0 of 10 each; now 10 and 9) and solves now: where no way in at
/// mid-height keeps clear (the IIWA's forearm crossing the goal wall's end at its top), the
/// object goes in 3 cm higher and 5 cm less deep.
#[test]
fn the_planned_expert_puts_the_object_in_the_shelf_a_higher_way() {
    assert_solves("IIWA/box/goal_wall/shelf", &[0]);
    assert_solves("Gen3/dumbbell/no_obstacle/shelf", &[1]);
}

/// The dumbbell let go over the trash can past the goal wall, which stayed on the open fingers
/// before (2026-11-30, seeds 0–9: the IIWA 3 of 10, the Jaco 3; now 10 and 8): backing straight
/// out ran the wrist into the goal wall and the fingers never slid out from under the upper
/// disc; the way out now turns about the vertical where the straight one comes close.
#[test]
fn the_planned_expert_lets_the_dumbbell_fall_into_the_trash_can_past_the_goal_wall() {
    assert_solves("IIWA/dumbbell/goal_wall/trash_can", &[0]);
    assert_solves("Jaco/dumbbell/goal_wall/trash_can", &[0]);
}

/// Plates pushed from behind the object wall that it lifted and then held still before
/// (2026-11-30, seeds 0–9: the Jaco 1 of 10, the Gen3 3; now 7 and 9): the IK lost the
/// straight line to the goal with the gripper held as it was; the gripper now turns about the
/// vertical on the way, as out from behind the door.
#[test]
fn the_planned_expert_turns_the_gripper_where_the_straight_push_is_lost() {
    assert_solves("Jaco/plate/object_wall/push", &[0]);
    assert_solves("Gen3/plate/object_wall/push", &[0]);
}

/// The plate carried from behind the door by the Panda, which it never managed before
/// (2026-12-01, seeds 0–9: 0 of 10 into the trash can; now 7): the level rim grasp needs the
/// forearm turned 2.5 rad (~340 of the 500 steps), the steep one 0.4 rad of joint travel.
#[test]
fn the_planned_expert_takes_the_plate_from_behind_the_door_with_the_steep_grasp() {
    assert_solves("Panda/plate/object_door/trash_can", &[0]);
}

/// The dumbbell behind the object wall, where the IIWA found no way in on 6 of seeds 0–9
/// before (2026-12-01; now 10 of 10 into bin 2): every pre-grasp solved on its own ran the
/// forearm into the wall on the descent; from the arm's pose at the grasp, with a shorter last
/// stretch, it does not.
#[test]
fn the_planned_expert_finds_a_way_in_from_the_grasp_behind_the_object_wall() {
    assert_solves("IIWA/dumbbell/object_wall/pick_place", &[0]);
}

/// Revision 11: a push whose every grasp's lines come close to the goal wall takes the grasp
/// whose lines come least close (before, the cheapest: its hand ran 4 cm into the wall and the
/// push stalled 6 cm short; 4 of 10 seeds then, 10 of 10 now); a carry ends clear of the goal
/// wall's top where that costs little more (before, the Gen3's forearm stalled on it and the
/// dumbbell fell onto the trash can's rim: 5 of 10 then, 10 of 10 now).
#[test]
fn the_planned_expert_keeps_its_pushes_and_carries_off_the_goal_wall() {
    assert_solves("Panda/dumbbell/goal_wall/push", &[0]);
    assert_solves("Gen3/dumbbell/goal_wall/trash_can", &[0]);
}

/// Revision 12: where no way in keeps the arm's descent clear of the arena, the last search
/// from the grasp takes one that comes no closer than a pre-grasp may (behind the door the
/// IIWA found no way in at all on seed 7: 7 of 10 then, 9 of 10 now); where no way into the
/// shelf keeps the held dumbbell's spheres that clear, both ways again 1 cm closer (past the
/// goal wall the IIWA lifted the dumbbell and held it on seed 1: 9 of 10 then, 10 of 10 now).
#[test]
fn the_planned_expert_comes_closer_where_nothing_else_is_left() {
    assert_solves("IIWA/dumbbell/object_door/trash_can", &[7]);
    assert_solves("IIWA/dumbbell/goal_wall/shelf", &[1]);
}

/// Revision 13: where the IK loses the line down into bin 2 past the goal wall, the dumbbell
/// is lowered only to just under the bin's line, or part of the way, before it is let go
/// (before, it was let go 9 cm above and bounced out; the Gen3 solved 1 of 10 seeds then, 3
/// now).
#[test]
fn the_planned_expert_lowers_what_it_can_into_bin_2() {
    assert_solves("Gen3/dumbbell/goal_wall/pick_place", &[0]);
}

/// Revision 14: the dumbbell may go into the shelf turned half a turn about the gripper's axis
/// (held the same way, upside down), where the arm reaches that with less joint travel: behind
/// the object wall the Jaco solved 5 of 10 seeds before, 9 now; the Gen3 3, now 6.
#[test]
fn the_planned_expert_turns_the_dumbbell_over_into_the_shelf() {
    assert_solves("Jaco/dumbbell/object_wall/shelf", &[1]);
    assert_solves("Gen3/dumbbell/object_wall/shelf", &[4]);
}

/// Revision 15: into the shelf past the goal wall the plate is taken with its steep rim grasp,
/// as from behind the door (the Panda's level approach took ~245 of the 500 steps: 2 of 10
/// seeds before, 8 now).
#[test]
fn the_planned_expert_takes_the_plate_steeply_past_the_goal_wall() {
    assert_solves("Panda/plate/goal_wall/shelf", &[2]);
}

/// Revision 16: the dumbbell is let go 2 cm short of the trash can's centre, back along the way
/// the gripper points. Hanging by its upper disc on the opened fingers, from the centre it was
/// dragged towards the can's near wall as they backed out and wedged there (the Panda's past
/// the goal wall: 4 of 10 seeds before, 10 now).
#[test]
fn the_planned_expert_lets_the_dumbbell_go_short_of_the_trash_cans_centre() {
    assert_solves("Panda/dumbbell/goal_wall/trash_can", &[3]);
}

/// Revision 17: where the object lies in bin 2 but the gripper, after letting go and backing
/// away, is out of the 7.75 cm that pick-place's success asks, the pads go back over it (the
/// Gen3's plate past the goal wall slipped out of the steep grasp on the way down, seed 2).
#[test]
fn the_planned_expert_goes_back_over_the_object_it_left_in_bin_2() {
    assert_solves("Gen3/plate/goal_wall/pick_place", &[2]);
}

/// Revision 18: out from behind the door, the plate and the dumbbell are taken from the goal's
/// side where the arm reaches that side round the door's y+ post (the gripper pointing away
/// from the goal), before any grasp through the opening, which drags the wrist into the post
/// (the IIWA's plate: 2 of 10 seeds before, 6 now; the Jaco's 4, now 6).
#[test]
fn the_planned_expert_pushes_from_the_goals_side_out_from_behind_the_door() {
    assert_solves("IIWA/plate/object_door/push", &[0]);
    assert_solves("Jaco/plate/object_door/push", &[2]);
}

/// Revision 19: the plate goes into the shelf from a grasp whose gripper points no further back
/// towards bin 1 than 15° where there is one: from further back the hand turns ~2 rad on the
/// carry and the plate slips out (the Panda's past the goal wall: 8 of 10 seeds before, 10 now;
/// the Gen3's behind the door 3, now 5).
#[test]
fn the_planned_expert_takes_the_plate_into_the_shelf_from_its_side() {
    assert_solves("Panda/plate/goal_wall/shelf", &[4]);
    assert_solves("Gen3/plate/object_door/shelf", &[1]);
}

/// An episode's stored actions are the reference's 8 numbers, each in [−1, 1]; played again
/// into a fresh environment they give the same observations, rewards and success, bit for bit.
#[test]
fn an_expert_episode_replays_from_its_stored_actions() {
    let task: TaskSpec = "Gen3/hollow_box/no_obstacle/pick_place".parse().unwrap();
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(3).unwrap();
    let mut expert = PlannedExpert::new(task);
    let mut recorded = Vec::new();
    while env.ended().is_none() {
        let action = expert.act(&env);
        let Action::Reference(a) = action else {
            panic!("the planned expert acted with {action:?}");
        };
        assert!(a.iter().all(|x| x.is_finite() && x.abs() <= 1.0), "{a:?}");
        let step = env.step(&action).unwrap();
        recorded.push((a, step.observation.flat(), step.reward, step.info.success));
    }
    assert_eq!(expert.stage(), Stage::Done);
    assert!(recorded.iter().any(|r| r.3), "the episode succeeded");

    let mut replay = Env::new(task, EnvConfig::default());
    replay.reset(3).unwrap();
    for (i, (a, observation, reward, success)) in recorded.iter().enumerate() {
        let step = replay.step(&Action::Reference(*a)).unwrap();
        assert_eq!(&step.observation.flat(), observation, "step {i}");
        assert_eq!(step.reward.to_bits(), reward.to_bits(), "step {i}");
        assert_eq!(step.info.success, *success, "step {i}");
    }
    assert!(replay.ended().is_some());
}

/// The digest of the actions [`PLANNED_EXPERT_REVISION`] stands for: one episode of each
/// objective and object, a push out from behind the door (300 steps each) and a dumbbell let go
/// over the trash can past the goal wall (400), and a push that turns the gripper where the
/// straight line is lost (300), a dumbbell behind the object wall reached only from the arm's
/// pose at the grasp (300), every action's 8 numbers hashed by their bits.
const REVISION_DIGEST: (u32, u64) = (19, 0x9783c7d7392a98c9);

/// FNV-1a over the actions' bits of the first `steps` steps of `name` from `seed`.
fn action_digest(name: &str, seed: u64, steps: usize, digest: &mut u64) {
    let task: TaskSpec = name.parse().unwrap();
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).unwrap();
    let mut expert = PlannedExpert::new(task);
    for _ in 0..steps {
        let action = expert.act(&env);
        let Action::Reference(a) = action else {
            panic!("the planned expert acted with {action:?}");
        };
        for byte in a.iter().flat_map(|x| x.to_bits().to_le_bytes()) {
            *digest = (*digest ^ byte as u64).wrapping_mul(0x100_0000_01b3);
        }
        env.step(&action).unwrap();
    }
}

/// A change that moves any of the expert's actions must raise [`PLANNED_EXPERT_REVISION`]:
/// the offline datasets' noise table was measured with the actions of one revision, and
/// calibrates again where an entry's revision is not the expert's.
#[test]
fn the_expert_revision_names_its_actions() {
    let mut digest = 0xcbf2_9ce4_8422_2325u64;
    for (name, seed, steps) in [
        ("IIWA/box/no_obstacle/pick_place", 0, 300),
        ("Jaco/plate/object_wall/trash_can", 1, 300),
        ("Gen3/dumbbell/no_obstacle/shelf", 2, 300),
        ("Panda/hollow_box/goal_wall/push", 3, 300),
        ("Gen3/plate/object_door/push", 0, 300),
        // Past its release over the trash can (step 318).
        ("Jaco/dumbbell/goal_wall/trash_can", 0, 400),
        // A push whose straight line the IK loses (from step 194).
        ("Jaco/plate/object_wall/push", 0, 300),
        // A way in found only from the arm's pose at the grasp, with a short last stretch.
        ("IIWA/dumbbell/object_wall/pick_place", 0, 300),
    ] {
        action_digest(name, seed, steps, &mut digest);
    }
    assert_eq!(
        (PLANNED_EXPERT_REVISION, digest),
        REVISION_DIGEST,
        "the planned expert's actions are not those of revision {}: if that is meant, raise \
         PLANNED_EXPERT_REVISION (expert/planned/mod.rs), pin (revision, digest) here, and \
         calibrate the noise table's test tasks again (docs/src/offline-datasets.md)",
        REVISION_DIGEST.0
    );
}
