//! Frames from a state alone, without physics: the arm's joint positions and the object's pose,
//! all an observation carries. This is how a recording is turned into a video (the bag holds
//! every step's `observation`, not the physics) and how an agent on the far side of ROS gets
//! a frame of what it was sent.
//!
//! The arm's bodies are posed by forward kinematics of the same [`RobotModel`] the physics
//! builds its multibody from ([`body_poses`]), so a frame drawn from a step's observation shows
//! what [`Env::render`](crate::env::Env::render) shows at that step, up to rounding (the joint
//! angles come back through their cosine and sine).

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

use super::camera::RenderError;
use super::raster::Frame;
use super::scene::{SceneRenderer, posed_camera_with};
use crate::TaskSpec;
use crate::kinematics::body_poses;
use crate::obs::{
    FLAT_SIZE_WITH_TASK, FLAT_SIZE_WITHOUT_TASK, GRIPPER_QPOS_IN_ROBOT, Observation,
    ROBOT_FACTOR_LEN,
};
use crate::physics::{ARM_DOF, RobotModel, robot_model};
use crate::render::MAX_SIDE;

/// What a frame needs of the world: where the arm's joints are and where the object is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneState {
    /// The arm's joint positions (rad), URDF order.
    pub arm: [f64; ARM_DOF],
    /// The two finger joints' positions (m), as `gripper_qpos` gives them.
    pub fingers: [f64; 2],
    /// The object's body pose in the world.
    pub object: Isometry3<f64>,
}

impl SceneState {
    /// From an observation's factors: joint angles from their cosines and sines, the finger
    /// joints' positions, the object's position and `x y z w` orientation (normalised here).
    pub fn from_factors(
        joint_pos_cos: &[f64; ARM_DOF],
        joint_pos_sin: &[f64; ARM_DOF],
        gripper_qpos: &[f64; 2],
        object_position: &[f64; 3],
        object_xyzw: &[f64; 4],
    ) -> SceneState {
        let [x, y, z, w] = *object_xyzw;
        SceneState {
            arm: std::array::from_fn(|j| joint_pos_sin[j].atan2(joint_pos_cos[j])),
            fingers: *gripper_qpos,
            object: Isometry3::from_parts(
                Translation3::from(Vector3::from(*object_position)),
                UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
            ),
        }
    }

    /// From a core observation.
    pub fn from_observation(obs: &Observation) -> SceneState {
        SceneState::from_factors(
            &obs.robot.joint_pos_cos,
            &obs.robot.joint_pos_sin,
            &obs.robot.gripper_qpos,
            &obs.object.position,
            &obs.object.orientation,
        )
    }

    /// From the flat observation vector (93 values with the task one-hots, 77 without: the
    /// layout of [`Observation::flat`]).
    pub fn from_flat(flat: &[f64]) -> Result<SceneState, String> {
        // The robot factor ends the flat vector, with or without the task one-hots.
        let robot = match flat.len() {
            n @ (FLAT_SIZE_WITHOUT_TASK | FLAT_SIZE_WITH_TASK) => n - ROBOT_FACTOR_LEN,
            n => {
                return Err(format!(
                    "a flat observation has {FLAT_SIZE_WITH_TASK} values (with the task \
                     one-hots) or {FLAT_SIZE_WITHOUT_TASK} (without); this one has {n}"
                ));
            }
        };
        if let Some(i) = flat.iter().position(|v| !v.is_finite()) {
            return Err(format!("observation value {i} is not finite: {}", flat[i]));
        }
        let take = |at: usize| -> [f64; ARM_DOF] { std::array::from_fn(|j| flat[at + j]) };
        let fingers_at = robot + GRIPPER_QPOS_IN_ROBOT;
        Ok(SceneState::from_factors(
            &take(robot),
            &take(robot + ARM_DOF),
            &[flat[fingers_at], flat[fingers_at + 1]],
            &[flat[0], flat[1], flat[2]],
            &[flat[3], flat[4], flat[5], flat[6]],
        ))
    }
}

/// Draws one task's scene from [`SceneState`]s; build it once per task, render many frames.
#[derive(Debug, Clone)]
pub struct StateRenderer {
    task: TaskSpec,
    model: &'static RobotModel,
    scene: SceneRenderer,
}

impl StateRenderer {
    /// The renderer of `task`'s scene (reads the arm's URDF visuals and tessellates once).
    pub fn new(task: TaskSpec) -> StateRenderer {
        let model = robot_model(task.robot);
        StateRenderer {
            task,
            model,
            scene: SceneRenderer::new(task, model),
        }
    }

    /// The task it draws.
    pub fn task(&self) -> TaskSpec {
        self.task
    }

    /// `state` as camera `camera` sees it, `width` × `height` pixels (the same checks and the
    /// same frame layout as [`Env::render`](crate::env::Env::render)).
    pub fn render(
        &mut self,
        state: &SceneState,
        camera: &str,
        width: u32,
        height: u32,
    ) -> Result<Frame, RenderError> {
        let bodies = body_poses(self.model, &state.arm, state.fingers);
        let model = self.model;
        let camera = posed_camera_with(camera, |link| {
            let (body, in_body) = model.links[link];
            bodies[body] * in_body
        })?;
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(RenderError::BadSize { width, height });
        }
        Ok(self.scene.render_posed(
            |body| bodies[body],
            Some(state.object),
            &camera,
            width,
            height,
        ))
    }
}
