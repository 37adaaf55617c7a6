//! A scripted expert: a phase machine that solves tasks through the public [`Env`] interface.
//!
//! The expert reads only what an agent can see — the observation (object pose, joint angles)
//! and the scene description ([`Env::goal`], [`Env::task`], the tables in [`crate::arena`]) —
//! and acts only with [`crate::env::Action::Absolute`] joint targets plus a gripper opening.
//! Gripper poses are turned into joint targets with the crate's own damped-least-squares IK
//! ([`crate::kinematics::solve_ik`]) on the arm's kinematic model, seeded from the previous
//! solution so consecutive targets stay on one IK branch.
//!
//! Every motion is a straight line of the pads' centre (and a slerp of the gripper's
//! orientation) with a smoothstep time law over 1–2 s, sampled once per control step, slowed
//! down (up to 3×) where a joint would move faster than about 1 rad/s — the arms' torque
//! limits cannot follow faster targets, and a lagging joint bends the path into walls.
//! Where the line cannot be followed (joint limits) the joints move straight to a
//! collision-checked IK solution instead, unless that path comes closer to the arena.
//!
//! A grasp counts as usable only if the gripper can rise straight from it (10 cm; Push 3 cm):
//! lifting from a pose at the edge of the arm's reach swings the joints and drags the object
//! over the floor. Where nothing but bin 2's walls has to be cleared, the carry height comes
//! down (1.05 → 0.93 m) until the lift is a straight line.
//!
//! If the object did not rise with the gripper (seen in its observed pose), the gripper
//! opens, backs off, and the next grasp is tried (at most twice).
//!
//! Phases: approach (to the pre-grasp, clear of the object and the obstacles) → descend (the
//! last stretch into the grasp; for a push without a grasp, up to the object, then nudge to
//! the goal) → close → lift → transport → the objective's finish (lower
//! into bin 2 / slide to the goal / over the trash can / into the shelf) → release → retreat
//! → hold.
//!
//! Grasps (`grasp.rs`): the box from the top; the hollow box from the top by one wall (the
//! near one, else the far one); the plate by its rim and the dumbbell by its bar, both from
//! the side, pointing towards bin 2 (+y) where the arm reaches that way without touching the
//! arena, else turned towards +x. Obstacles are passed over (object wall,
//! door) or over / around (goal wall). Pushing around the goal wall, a top-grasped object is
//! carried as high as Push allows and the gripper may lean (wrist towards +y) so the forearm
//! clears the wall's free end. A side-grasped object is turned level in front of the shelf,
//! so the wrist behind the gripper passes under the shelf's top block. The lane in front of
//! the shelf and a turn of the gripper about the vertical (swinging the wrist and forearm
//! away from the walls) are chosen by the arm's clearance along the way in, slide included.
//! Past the goal wall, where every way through the shelf's front runs the arm into the wall
//! by more than 4 cm, the object may instead go in through the shelf's open end nearest the
//! robot (x −0.1, where the goal wall ends too): carried over the wall to beside that end,
//! the gripper level and pointing +x, and slid in along +x, wrist and forearm staying on the
//! robot's side of the end.
//!
//! Pushing a side-grasped object past the goal wall takes two grasps: no single heading
//! keeps the wrist (10–20 cm behind the pads, below the wall's top) clear all the way. The
//! first carries the object to a spot just past the wall's free end and sets it down (pressed
//! into the floor so a plate tilted in the grasp lands level); the second grasps it again,
//! wrist towards the robot and +y (+x−y first), chosen by the clearance of its approach and
//! of the carry to the goal, at a quicker pace. The dumbbell is carried just off the floor
//! (higher, it tilts in the grasp and crosses the 0.9 m line that ends a Push episode). Over
//! the trash can the open fingers slide out level before rising (they still hold the
//! dumbbell's upper disc).
//!
//! From behind the object wall and the door the plate and the dumbbell are pushed without a
//! grasp (`nudge.rs`): no side grasp keeps the low wrist off the wall (checked pose by pose),
//! while a gripper pointing down keeps wrist and forearm above the pads. Its two fingers, held
//! 4 cm apart behind the object, push it along the floor in legs of 5 cm, each aimed again
//! from where the object is then; the object rolls back between the fingers when pushed
//! off-centre, and where it slips out (or past the goal) the fingers are set behind it again.
//! The Panda, whose two-grasp plan does not fit in the episode, pushes them round the goal
//! wall too: first to a point in front of the wall's line from which the way to the goal
//! passes the wall's free end.

mod clearance;
mod grasp;
mod motion;
mod nudge;
mod plan;
mod planned;
mod reach;
mod script;
mod track;

pub use planned::{PLANNED_EXPERT_REVISION, PlannedExpert, Stage, run_planned_episode};
pub use script::{Expert, Phase};

use crate::TaskSpec;
use crate::env::{Action, Env, EnvConfig};

/// What an episode of the expert achieved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeOutcome {
    /// Whether any step succeeded.
    pub success: bool,
    /// Sum of the rewards.
    pub ret: f64,
    /// Control steps run.
    pub length: u32,
    /// Wall-clock seconds the expert spent choosing its actions (planning included): a
    /// measurement, not part of the episode (the trajectory does not depend on it).
    pub expert_seconds: f64,
}

/// Runs one episode of `task` with `seed` (default config) driven by the expert.
pub fn run_episode(task: TaskSpec, seed: u64) -> EpisodeOutcome {
    let mut expert = Expert::new(task);
    run_with(task, seed, |env| expert.act(env))
}

/// Runs one episode of `task` with `seed` (default config), `act` choosing each action.
fn run_with(task: TaskSpec, seed: u64, mut act: impl FnMut(&Env) -> Action) -> EpisodeOutcome {
    let mut env = Env::new(task, EnvConfig::default());
    let mut outcome = EpisodeOutcome {
        success: false,
        ret: 0.0,
        length: 0,
        expert_seconds: 0.0,
    };
    if env.reset(seed).is_err() {
        return outcome;
    }
    while env.ended().is_none() {
        let started = std::time::Instant::now();
        let action = act(&env);
        outcome.expert_seconds += started.elapsed().as_secs_f64();
        match env.step(&action) {
            Ok(step) => outcome.success |= step.info.success,
            Err(_) => break,
        }
    }
    outcome.ret = env.episode_return();
    outcome.length = env.steps();
    outcome
}
