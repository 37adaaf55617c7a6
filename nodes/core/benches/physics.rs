//! Physics speed per arm: arm + gripper + the pick-place bins + the box resting in bin 1,
//! driven by random joint targets (validated and clamped, as commands arrive), 2 ms steps.
//!
//! ```text
//! cargo bench -p composuite_core --bench physics
//! ```
//! Prints, per arm: µs per physics step, control steps/s (25 steps each), scene build time,
//! reset time, and the heap bytes a scene holds. Wall-clock times on one thread; the machine
//! may be shared, so each figure is the best of several repeats.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::Instant;

use composuite_core::arena::{BIN1_POSITION, arena_parts, object_geometry};
use composuite_core::axes::{AxisElement, Object, Objective, Obstacle, Robot};
use composuite_core::control::validate_arm_targets;
use composuite_core::physics::{FINGER_OPEN, PhysicsParams, SimWorld};
use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};

/// Counts live heap bytes so a scene's footprint can be read off.
struct Counting;
static LIVE: AtomicIsize = AtomicIsize::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_add(
            new_size as isize - layout.size() as isize,
            Ordering::Relaxed,
        );
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}
#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn box_start() -> Isometry3<f64> {
    Isometry3::translation(
        BIN1_POSITION[0],
        BIN1_POSITION[1],
        object_geometry(Object::Box).spawn_z(),
    )
}

fn build(robot: Robot) -> SimWorld {
    let mut world = SimWorld::new(robot, PhysicsParams::default());
    world.add_arena(&arena_parts(Objective::PickPlace, Obstacle::NoObstacle));
    world.add_object(Object::Box, &box_start());
    world
}

fn best<T>(repeats: usize, mut f: impl FnMut() -> (f64, T)) -> f64 {
    (0..repeats).map(|_| f().0).fold(f64::INFINITY, f64::min)
}

fn main() {
    let params = PhysicsParams::default();
    println!(
        "physics: dt {} s, {} steps per control step, {} solver iteration(s) + {} PGS, length unit {}",
        params.dt,
        params.substeps,
        params.solver_iterations,
        params.internal_pgs_iterations,
        params.length_unit
    );
    println!(
        "{:<6} {:>12} {:>16} {:>12} {:>10} {:>12} {:>16}",
        "arm", "us/step", "control steps/s", "build ms", "reset us", "scene kB", "+workspace kB"
    );
    for robot in Robot::all() {
        let build_ms = best(5, || {
            let t = Instant::now();
            let world = build(robot);
            (t.elapsed().as_secs_f64() * 1e3, world)
        });
        let before = LIVE.load(Ordering::Relaxed);
        let mut world = build(robot);
        let scene_bytes = LIVE.load(Ordering::Relaxed) - before;
        world.step();
        let with_workspace = LIVE.load(Ordering::Relaxed) - before;

        let control_steps = 400;
        let us_per_step = best(3, || {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
            let mut world = build(robot);
            let init = robot.init_qpos();
            let t = Instant::now();
            for _ in 0..control_steps {
                // Random targets near the start pose keep the arm moving over the bins.
                let raw: Vec<f64> = init
                    .iter()
                    .map(|q| q + rng.random_range(-0.3..0.3))
                    .collect();
                let (targets, _) = validate_arm_targets(world.model, &raw).unwrap();
                world.set_arm_targets(&targets);
                world.step_control();
            }
            (
                t.elapsed().as_secs_f64() * 1e6 / (control_steps * params.substeps) as f64,
                world,
            )
        });
        let reset_us = best(5, || {
            let t = Instant::now();
            for _ in 0..1000 {
                world.reset_arm(&robot.init_qpos(), FINGER_OPEN);
                world.place_object(&box_start());
            }
            (t.elapsed().as_secs_f64() * 1e3, ())
        });
        println!(
            "{:<6} {:>12.1} {:>16.0} {:>12.2} {:>10.1} {:>12.1} {:>16.1}",
            robot.wire_name(),
            us_per_step,
            1e6 / (us_per_step * params.substeps as f64),
            build_ms,
            reset_us,
            scene_bytes as f64 / 1024.0,
            (with_workspace - scene_bytes) as f64 / 1024.0
        );
    }
}
