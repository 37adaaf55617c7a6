//! Physics speed per arm: arm + gripper + the pick-place bins + the box resting in bin 1,
//! driven by random joint targets (validated and clamped, as commands arrive), 2 ms steps.
//!
//! ```text
//! cargo bench -p composuite_core --bench physics
//! ```
//! Prints, per arm: µs per physics step, control steps/s (25 steps each), scene build time,
//! reset time, the heap bytes a scene holds, and how many heap allocations a physics step
//! makes with the stiff servos and with the reference controller law. Wall-clock times on one thread; the machine
//! may be shared, so each figure is the best of several repeats.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::Instant;

use composuite_core::arena::{BIN1_POSITION, arena_parts, object_geometry};
use composuite_core::axes::{AxisElement, Object, Objective, Obstacle, Robot};
use composuite_core::control::validate_arm_targets;
use composuite_core::physics::{FINGER_OPEN, PhysicsParams, ServoMode, SimWorld};
use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};

/// Counts live heap bytes so a scene's footprint can be read off, and allocations (`alloc`
/// and `realloc` calls) so a step's can.
struct Counting;
static LIVE: AtomicIsize = AtomicIsize::new(0);
static ALLOCATIONS: AtomicIsize = AtomicIsize::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
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

/// Heap allocations per physics step over `steps` steps after a warm-up, in `mode`.
fn allocations_per_step(robot: Robot, mode: ServoMode, steps: usize) -> f64 {
    let mut world = build(robot);
    world.set_servo_mode(mode);
    let mut targets = robot.init_qpos();
    targets[1] += 0.2; // keep the arm moving
    world.set_arm_targets(&targets);
    for _ in 0..50 {
        world.step(); // warm-up: workspaces reach their size
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..steps {
        world.step();
    }
    (ALLOCATIONS.load(Ordering::Relaxed) - before) as f64 / steps as f64
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
        "{:<6} {:>12} {:>16} {:>12} {:>10} {:>12} {:>16} {:>22}",
        "arm",
        "us/step",
        "control steps/s",
        "build ms",
        "reset us",
        "scene kB",
        "+workspace kB",
        "allocs/step stiff/ref"
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
        let allocations = format!(
            "{:.1} / {:.1}",
            allocations_per_step(robot, ServoMode::Stiff, 500),
            allocations_per_step(robot, ServoMode::Reference, 500)
        );
        println!(
            "{:<6} {:>12.1} {:>16.0} {:>12.2} {:>10.1} {:>12.1} {:>16.1} {:>22}",
            robot.wire_name(),
            us_per_step,
            1e6 / (us_per_step * params.substeps as f64),
            build_ms,
            reset_us,
            scene_bytes as f64 / 1024.0,
            (with_workspace - scene_bytes) as f64 / 1024.0,
            allocations
        );
    }
}
