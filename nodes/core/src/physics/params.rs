//! Simulation and control settings, as plain structs with documented defaults.

use crate::axes::Robot;

/// Settings of the physics engine.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicsParams {
    /// Physics step (s). The reference steps MuJoCo at 2 ms.
    pub dt: f64,
    /// Physics steps per control step: 25 gives the reference's 20 Hz control.
    pub substeps: usize,
    /// Solver iterations per step (rapier's substeps: cost grows linearly).
    pub solver_iterations: usize,
    /// Inner PGS iterations per solver iteration (cheap; what keeps grasps firm at 1 iteration).
    pub internal_pgs_iterations: usize,
    /// Rapier's length unit (m): scales its tolerances; 0.1 gives 2 mm contact prediction.
    pub length_unit: f64,
    /// Contact stiffness as a natural frequency (Hz); the default lets finger pads sink mm deep.
    pub contact_frequency: f64,
    /// Contact damping ratio.
    pub contact_damping_ratio: f64,
    /// Gravity along −z (m/s²).
    pub gravity: f64,
}

impl Default for PhysicsParams {
    fn default() -> Self {
        PhysicsParams {
            dt: 0.002,
            substeps: 25,
            solver_iterations: 1,
            internal_pgs_iterations: 8,
            length_unit: 0.1,
            contact_frequency: 240.0,
            contact_damping_ratio: 1.0,
            gravity: 9.81,
        }
    }
}

/// Joint-space PD gains of an arm's position servos (per joint, 1..7).
#[derive(Debug, Clone, PartialEq)]
pub struct ArmGains {
    /// Stiffness (N·m/rad).
    pub kp: [f64; 7],
    /// Damping (N·m·s/rad).
    pub kd: [f64; 7],
    /// Rotor inertia added to each joint (kg·m²): robosuite's 5/(i+1) on every arm.
    pub armature: [f64; 7],
    /// Viscous joint damping (N·m·s/rad), as the reference compiles it.
    pub damping: [f64; 7],
    /// Dry joint friction (N·m): the most torque friction can oppose motion with, MuJoCo's
    /// `frictionloss` as the reference compiles it (the same on every joint of an arm).
    pub frictionloss: f64,
}

impl ArmGains {
    /// The gains used for `robot`.
    pub fn for_robot(robot: Robot) -> ArmGains {
        // Reference joint damping (docs/src/reference-facts.md §4.1): 0.1 everywhere on the iiwa,
        // 0.01 on the two wrist joints of the other arms.
        let damping = match robot {
            Robot::Iiwa => [0.1; 7],
            Robot::Jaco | Robot::Gen3 | Robot::Panda => [0.1, 0.1, 0.1, 0.1, 0.1, 0.01, 0.01],
        };
        // Reference frictionloss (docs/src/reference-facts.md §4.1): robosuite's default 0.1,
        // except the Jaco's own 0.01.
        let frictionloss = match robot {
            Robot::Jaco => 0.01,
            Robot::Iiwa | Robot::Gen3 | Robot::Panda => 0.1,
        };
        ArmGains {
            kp: [4000.0, 4000.0, 3000.0, 3000.0, 1500.0, 1000.0, 1000.0],
            // Joint 1 carries the largest armature (5 kg·m²) and turns the whole arm: it needs
            // more damping than joint 2 for the Gen3's torque-limited joint 1 to settle a step
            // without overshoot (nodes/core/tests/arms.rs; the figures: docs/src/physics.md).
            kd: [550.0, 400.0, 300.0, 300.0, 120.0, 80.0, 80.0],
            armature: [5.0, 2.5, 5.0 / 3.0, 1.25, 1.0, 5.0 / 6.0, 5.0 / 7.0],
            damping,
            frictionloss,
        }
    }
}

/// The finger servos.
#[derive(Debug, Clone, PartialEq)]
pub struct GripperParams {
    /// Stiffness per finger (N/m).
    pub kp: f64,
    /// Damping per finger (N·s/m).
    pub kd: f64,
    /// Force limit per finger (N); the reference's actuators are limited to 20 N.
    pub max_force: f64,
    /// How far past a closed-on-nothing position the servo aims when closing (m), so the grip
    /// force saturates at `max_force` instead of depending on where the object stopped the pads.
    pub close_overshoot: f64,
    /// Dry friction of each finger joint (N): the reference's `frictionloss` 1
    /// (docs/src/reference-facts.md §4.4).
    pub frictionloss: f64,
}

impl Default for GripperParams {
    fn default() -> Self {
        GripperParams {
            kp: 2000.0,
            kd: 100.0,
            max_force: 20.0,
            close_overshoot: 0.01,
            frictionloss: 1.0,
        }
    }
}
