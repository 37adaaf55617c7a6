//! Starting an episode from the task manager's `scene`: the world rebuilt or reused and reset,
//! the sim time carried on, and the latched robot description, static transform and arena
//! published when the task changes.

use std::collections::BTreeSet;

use composuite_core::TaskSpec;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::physics::{robot_description, robot_model};
use composuite_msgs::msg;
use composuite_msgs::std_msgs::msg::String as StringMsg;
use composuite_msgs::tf2_msgs::msg::TFMessage;
use ros2_client::Gid;

use super::controllers::running::Controllers;
use super::view;
use super::{ActionServers, Running, Sim};
use crate::shared::convert;
use crate::shared::node::Logger;

impl Sim {
    pub(super) fn on_scene(
        &mut self,
        servers: &ActionServers,
        scene: &msg::Scene,
        writer: Gid,
        log: &Logger,
    ) {
        let task: TaskSpec = match convert::task_of(&scene.task) {
            Ok(task) => task,
            Err(err) => {
                log.error(format!("scene refused: {err}"));
                return;
            }
        };
        if let Some(run) = &self.run
            && run.episode == scene.episode
            && run.scene_writer == writer
            && run.env.task() == task
        {
            return; // the latched scene again (e.g. a re-match); nothing new
        }
        self.end_all_goals(servers, &format!("episode {} started", scene.episode), log);
        // The scene carries the latest sim time the task manager has seen: a sim started again
        // (after a crash) goes on from there instead of from 0, so time never runs backwards.
        self.sim_time_ns = self.sim_time_ns.max(convert::nanos_of(&scene.header.stamp));
        let config = EnvConfig::default()
            .horizon(scene.horizon)
            .task_observation(self.task_observation);
        if (config.control_period() - scene.control_period).abs() > 1e-12 {
            log.warn(format!(
                "scene asks for a {} s control period; this sim runs {} s",
                scene.control_period,
                config.control_period()
            ));
        }
        let reuse = self
            .run
            .take()
            .map(|r| r.env)
            .filter(|env| env.task() == task && *env.config() == config);
        let robot_changed = reuse.is_none();
        let started = self.step_pool.run(|| {
            let mut env = reuse.unwrap_or_else(|| Env::new(task, config));
            env.reset(scene.seed).map(|_| env)
        });
        let env = match started {
            Ok(env) => env,
            Err(err) => {
                log.error(format!("cannot start episode {}: {err}", scene.episode));
                return;
            }
        };
        let controllers = Controllers::holding(env.world().arm_positions());
        self.run = Some(Running {
            env,
            episode: scene.episode,
            scene_writer: writer,
            controllers,
            clamp_reported: BTreeSet::new(),
            over_reported: false,
            object_drawn: false,
            started_ns: 0,
        });
        if robot_changed {
            let _ = self.pubs.robot_description.publish(StringMsg {
                data: robot_description(task.robot),
            });
            // The URDF's root link sits at the robot base pose in the world. Only this one
            // transform is static: robot_state_publisher would put the URDF's fixed joints here
            // too, but the task (so the arm) can change during a run, and tf2's and Foxglove's
            // static buffers keep a static transform for good, whichever arm sent it last
            // (IIWA and Jaco both have a `right_hand_mount` from `link_7`, at other offsets). So
            // the fixed joints go out on `tf` with the moving ones at every step, and every link
            // resolves to `world` at every stamp from that step's transforms alone; the root
            // links differ between the four arms, so their static transforms never clash.
            let root = &robot_model(task.robot).bodies[0].name;
            let base = convert::pose(&composuite_core::arena::robot_base_pose());
            let stamp = convert::time_from_nanos(self.sim_time_ns);
            let mut transforms = vec![convert::world_transform(root, &base, stamp.clone())];
            transforms.extend(self.cameras.static_transforms(&stamp));
            let _ = self.pubs.tf_static.publish(TFMessage { transforms });
        }
        log.info(format!(
            "episode {} of {task}, seed {}",
            scene.episode, scene.seed
        ));
        self.advance_clock();
        if let Some(run) = &mut self.run {
            run.started_ns = self.sim_time_ns;
        }
        if robot_changed {
            // The arena is the task's (the goal marker's place too): drawn again when it changes.
            let stamp = convert::time_from_nanos(self.sim_time_ns);
            let _ = self
                .pubs
                .scene_markers
                .publish(view::arena_markers(scene, stamp));
        }
        self.publish_state();
    }
}
