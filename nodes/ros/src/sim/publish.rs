//! Publishing what describes the world after a step or reset: `world_state`, `observation`,
//! `joint_states`, `tf`, `object_markers`, `clock`, and the cameras' images.

use composuite_core::physics::ARM_DOF;
use composuite_msgs::msg;
use composuite_msgs::rosgraph_msgs::msg::Clock;
use composuite_msgs::tf2_msgs::msg::TFMessage;

use super::Sim;
use super::view;
use crate::shared::convert;
use crate::shared::names;

impl Sim {
    /// Publish everything that describes the world now, stamped with the sim time: the
    /// episode's step (`world_state` first — the reward node's input — then `observation`),
    /// then the robot's state for ROS tools.
    pub(super) fn publish_state(&mut self) {
        let Some(run) = &self.run else { return };
        let env = &run.env;
        let stamp = convert::time_from_nanos(self.sim_time_ns);
        let step = env.steps();
        let world_msg = convert::world_state(&env.world_state(), stamp.clone(), run.episode, step);
        // Publishing only fails when DDS is shutting down; the next step tries again.
        let _ = self.pubs.world_state.publish(world_msg.clone());
        let _ = self.pubs.observation.publish(convert::observation(
            &env.observation(),
            stamp.clone(),
            run.episode,
            step,
        ));
        self.publish_robot_state(&world_msg);
        if let Some(run) = &mut self.run {
            self.cameras.publish(&mut run.env, &stamp);
        }
    }

    /// `joint_states`, `tf`, `object_markers` and `clock` (also while a realtime episode is over,
    /// so ROS tools keep seeing a live robot).
    pub(super) fn publish_robot_state(&mut self, world_msg: &msg::WorldState) {
        let Some(run) = &mut self.run else { return };
        let env = &run.env;
        let stamp = convert::time_from_nanos(self.sim_time_ns);
        let w = env.world();
        let mut positions = w.arm_positions().to_vec();
        positions.extend(w.finger_positions());
        let mut velocities = w.arm_velocities().to_vec();
        velocities.extend([w.joint_velocity(ARM_DOF), w.joint_velocity(ARM_DOF + 1)]);
        let _ = self.pubs.joint_states.publish(convert::joint_state(
            w.model,
            &positions,
            &velocities,
            stamp.clone(),
        ));
        let goal = env.goal();
        let goal_pose = convert::pose(&nalgebra::Isometry3::translation(goal.x, goal.y, goal.z));
        let mut transforms = vec![
            convert::world_transform(names::EEF_FRAME, &world_msg.eef_pose, stamp.clone()),
            convert::world_transform(names::OBJECT_FRAME, &world_msg.object_pose, stamp.clone()),
            convert::world_transform(names::GOAL_FRAME, &goal_pose, stamp.clone()),
        ];
        transforms.extend(view::link_transforms(w).iter().map(|link| {
            view::transform_stamped(link.parent, link.child, &link.transform, stamp.clone())
        }));
        let _ = self.pubs.tf.publish(TFMessage { transforms });
        if let Some(object_pose) = w.object_pose() {
            let _ = self.pubs.object_markers.publish(view::object_markers(
                env.task().object,
                &object_pose,
                stamp.clone(),
                !run.object_drawn,
            ));
            run.object_drawn = true;
        }
        let _ = self.pubs.clock.publish(Clock { clock: stamp });
    }
}
