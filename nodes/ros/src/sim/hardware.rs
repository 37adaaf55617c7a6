//! The hardware seam, in ros2_control's shape: every control period the controllers read the
//! joints' state, compute their commands (`update`), and the commands are written, all on one
//! timestamp. Controllers see only the [`Hardware`] trait:
//!
//! - [`SimHardware`]: the rapier world behind the core's `Env`; `write` also simulates the
//!   period (as a simulator's ros2_control plugin steps its world);
//! - [`MockHardware`]: follows its position commands exactly, as ros2_control's
//!   `mock_components/GenericSystem` does, so the controllers run and are tested without physics;
//! - a real arm's driver would be a third implementation (docs/src/controllers.md, "Real cell").
//!
//! Interfaces, as ros2_control names them: `<joint>/position` and `<joint>/velocity` state
//! interfaces and a `<joint>/position` command interface for the seven arm joints and for the
//! gripper's left finger joint (m; the fingers are coupled, the pad opening is
//! `0.0371 + 2·position`).

use composuite_core::env::{Action, Env, EnvError, Step};
use composuite_core::physics::{ARM_DOF, RobotModel, finger_for_gap, pad_gap};

/// Joints with interfaces: the arm's seven, then the gripper's left finger.
pub const JOINTS: usize = ARM_DOF + 1;

/// Index of the gripper joint in a [`JointSnapshot`].
pub const GRIPPER: usize = ARM_DOF;

/// What `read` gives: every joint's position and velocity at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct JointSnapshot {
    /// Sim (or hardware) time of the reading, ns.
    pub time_ns: u64,
    /// Positions (rad; the gripper joint in m), arm joints then the gripper joint.
    pub positions: [f64; JOINTS],
    /// Velocities (rad/s; m/s), same order.
    pub velocities: [f64; JOINTS],
}

/// What the arm's command interfaces receive for one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArmCommand {
    /// Absolute joint position targets (rad).
    Positions([f64; ARM_DOF]),
    /// The reference benchmark's normalised action (joint deltas from the measured positions,
    /// and the gripper's sign), for `reference_action`: its own gripper command included.
    Reference([f64; ARM_DOF + 1]),
}

/// A gripper position command with its effort limit. It carries the pad opening, the unit the
/// simulated gripper is commanded in (`gripper_command`, the finger joints of `joint_command`), so
/// those paths reach the world bit for bit; a finger joint position converts with
/// [`GripperTarget::finger`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperTarget {
    /// Distance between the finger pads (m): `0.0371 + 2·(left finger joint position)`.
    pub opening: f64,
    /// Effort limit (N); 0 = the default.
    pub max_effort: f64,
}

impl GripperTarget {
    /// The target that puts the left finger joint at `position` (m).
    pub fn finger(position: f64, max_effort: f64) -> Self {
        GripperTarget {
            opening: pad_gap(position),
            max_effort,
        }
    }
}

/// Everything written for one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// The arm's targets.
    pub arm: ArmCommand,
    /// A new gripper target, or `None` to keep the last one.
    pub gripper: Option<GripperTarget>,
}

/// The seam a controller talks to: joint names, a state reading, a command write.
pub trait Hardware {
    /// The robot: joint names and limits (arm joints, then fingers).
    fn model(&self) -> &'static RobotModel;
    /// The joints' state now.
    fn read(&self) -> JointSnapshot;
    /// Apply `command` for the next control period (a simulator also simulates it).
    fn write(&mut self, command: &Command) -> Result<(), String>;
}

/// The simulated arm: the core's `Env`, one control period per `write`.
pub struct SimHardware<'a> {
    env: &'a mut Env,
    time_ns: u64,
    /// The outcome of the last `write` (the step's reward, termination, clamped targets), for
    /// the sim node to report; controllers do not see it.
    pub last_step: Option<Result<Step, EnvError>>,
}

impl<'a> SimHardware<'a> {
    /// The arm of `env`, read at sim time `time_ns`.
    pub fn new(env: &'a mut Env, time_ns: u64) -> Self {
        SimHardware {
            env,
            time_ns,
            last_step: None,
        }
    }
}

impl Hardware for SimHardware<'_> {
    fn model(&self) -> &'static RobotModel {
        self.env.world().model
    }

    fn read(&self) -> JointSnapshot {
        read_env(self.env, self.time_ns)
    }

    fn write(&mut self, command: &Command) -> Result<(), String> {
        let action = match command.arm {
            ArmCommand::Positions(joints) => Action::Absolute {
                joints,
                gripper: command.gripper.map(|g| (g.opening, g.max_effort)),
            },
            ArmCommand::Reference(values) => Action::Reference(values),
        };
        let result = self.env.step(&action);
        let outcome = result.as_ref().map(|_| ()).map_err(|e| e.to_string());
        self.last_step = Some(result);
        outcome
    }
}

/// The joints of `env`'s arm, read at sim time `time_ns` (what [`SimHardware::read`] gives).
pub fn read_env(env: &Env, time_ns: u64) -> JointSnapshot {
    let world = env.world();
    let mut positions = [0.0; JOINTS];
    let mut velocities = [0.0; JOINTS];
    positions[..ARM_DOF].copy_from_slice(&world.arm_positions());
    velocities[..ARM_DOF].copy_from_slice(&world.arm_velocities());
    positions[GRIPPER] = world.joint_position(ARM_DOF);
    velocities[GRIPPER] = world.joint_velocity(ARM_DOF);
    JointSnapshot {
        time_ns,
        positions,
        velocities,
    }
}

/// Hardware that follows its commands exactly: each `write` puts every joint at its target (the
/// gripper within its limits), velocities being the change over the period. No physics.
pub struct MockHardware {
    model: &'static RobotModel,
    period_ns: u64,
    time_ns: u64,
    positions: [f64; JOINTS],
    velocities: [f64; JOINTS],
    /// Every command written, in order (what a test checks).
    pub written: Vec<Command>,
}

impl MockHardware {
    /// `model`'s arm at `positions`, at rest, at time 0, advancing `period_ns` per write.
    pub fn new(model: &'static RobotModel, positions: [f64; JOINTS], period_ns: u64) -> Self {
        MockHardware {
            model,
            period_ns,
            time_ns: 0,
            positions,
            velocities: [0.0; JOINTS],
            written: Vec::new(),
        }
    }
}

impl Hardware for MockHardware {
    fn model(&self) -> &'static RobotModel {
        self.model
    }

    fn read(&self) -> JointSnapshot {
        JointSnapshot {
            time_ns: self.time_ns,
            positions: self.positions,
            velocities: self.velocities,
        }
    }

    fn write(&mut self, command: &Command) -> Result<(), String> {
        let ArmCommand::Positions(arm) = command.arm else {
            return Err("the mock hardware takes position commands only".into());
        };
        let mut next = self.positions;
        next[..ARM_DOF].copy_from_slice(&arm);
        if let Some(gripper) = command.gripper {
            let (lower, upper) = self.model.joints[ARM_DOF]
                .limits
                .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
            next[GRIPPER] = finger_for_gap(gripper.opening).clamp(lower, upper);
        }
        let period = self.period_ns as f64 * 1e-9;
        for (velocity, (new, old)) in self
            .velocities
            .iter_mut()
            .zip(next.iter().zip(&self.positions))
        {
            *velocity = (new - old) / period;
        }
        self.positions = next;
        self.time_ns += self.period_ns;
        self.written.push(*command);
        Ok(())
    }
}
