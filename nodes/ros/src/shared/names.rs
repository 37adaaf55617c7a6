//! Topic and service names, relative (no leading `/`) so a launch can put each environment
//! in its own namespace (`/env_00/joint_states`, ...). The node table in docs/src/node-suite.md
//! lists them per node.

/// Arm and finger joint states (sensor_msgs/JointState), sim → agents.
pub const JOINT_STATES: &str = "joint_states";
/// Absolute joint position targets by name (sensor_msgs/JointState), agents → sim; stamped with
/// the observation it answers (a command stamped before the episode began is dropped).
pub const JOINT_COMMAND: &str = "joint_command";
/// The reference benchmark's 8 action values in [−1, 1] (std_msgs/Float64MultiArray): joint
/// deltas of 0.05 rad per unit from the measured positions, then the gripper's sign; agents → sim.
pub const REFERENCE_ACTION: &str = "reference_action";
/// The same action stamped with the observation it answers (`composuite_msgs/ReferenceAction`).
pub const REFERENCE_ACTION_STAMPED: &str = "reference_action_stamped";
/// Gripper opening and effort (control_msgs/GripperCommand), agents → sim.
pub const GRIPPER_COMMAND: &str = "gripper_command";
/// Factored observation (composuite_msgs/Observation), sim → agents.
pub const OBSERVATION: &str = "observation";
/// Privileged truth (composuite_msgs/WorldState), sim → reward.
pub const WORLD_STATE: &str = "world_state";
/// The composed scene, transient local (composuite_msgs/Scene), task_manager → all.
pub const SCENE: &str = "scene";
/// Staged reward (composuite_msgs/StagedReward), reward → agents.
pub const REWARD: &str = "reward";
/// Success flag (std_msgs/Bool), reward → agents.
pub const SUCCESS: &str = "success";
/// Episode progress (composuite_msgs/EpisodeStatus), task_manager → agents.
pub const EPISODE: &str = "episode";
/// Sim time (rosgraph_msgs/Clock), sim → all.
pub const CLOCK: &str = "clock";
/// Service: choose the task.
pub const SET_TASK: &str = "set_task";
/// Service: start an episode.
pub const RESET: &str = "reset";
/// Service: reference-identical task splits.
pub const SAMPLE_TASKS: &str = "sample_tasks";
/// The world frame every pose is expressed in.
pub const WORLD_FRAME: &str = "world";
/// The arm + gripper URDF (std_msgs/String), transient local, sim → RViz/Foxglove.
pub const ROBOT_DESCRIPTION: &str = "robot_description";
/// Transforms (tf2_msgs/TFMessage), every step: every URDF link in its parent link, as
/// robot_state_publisher would publish them, and the `eef`, `object` and `goal` frames in the
/// world.
pub const TF: &str = "tf";
/// The arm's root link in the world (tf2_msgs/TFMessage), transient local like tf2's
/// `/tf_static`: with `tf` it places every link of `robot_description`.
pub const TF_STATIC: &str = "tf_static";
/// The arena as markers (visualization_msgs/MarkerArray), transient local: bins, obstacle,
/// trash can or shelf, goal marker; re-published (after a DELETEALL) when the task changes.
pub const SCENE_MARKERS: &str = "scene_markers";
/// The object as markers (visualization_msgs/MarkerArray), volatile, every step at its pose.
pub const OBJECT_MARKERS: &str = "object_markers";
/// `tf` frame of the grip site (position) with the hand's orientation: the reference's eef.
pub const EEF_FRAME: &str = "eef";
/// `tf` frame of the object's body origin.
pub const OBJECT_FRAME: &str = "object";
/// `tf` frame of the goal marker.
pub const GOAL_FRAME: &str = "goal";

// ros2_control's controller interfaces, named as a driver's controllers name them (each under
// its controller's name; `controller_manager` is the manager's node name).

/// Action `control_msgs/action/FollowJointTrajectory` of the trajectory controller.
pub const TRAJECTORY_ACTION: &str = "joint_trajectory_controller/follow_joint_trajectory";
/// Topic `trajectory_msgs/JointTrajectory` of the trajectory controller (no result, no feedback).
pub const TRAJECTORY_TOPIC: &str = "joint_trajectory_controller/joint_trajectory";
/// Topic `std_msgs/Float64MultiArray` of the forward position controller (7 arm positions).
pub const FORWARD_COMMANDS: &str = "forward_position_controller/commands";
/// Action `control_msgs/action/GripperCommand` of the gripper controller (finger joint, m).
pub const GRIPPER_ACTION: &str = "gripper_action_controller/gripper_cmd";
/// Service `controller_manager_msgs/srv/ListControllers`.
pub const LIST_CONTROLLERS: &str = "controller_manager/list_controllers";
/// Service `controller_manager_msgs/srv/ListHardwareInterfaces`.
pub const LIST_HARDWARE_INTERFACES: &str = "controller_manager/list_hardware_interfaces";

// The ROS 2 standard simulation interfaces (simulation_interfaces, Jazzy), named as Gazebo and
// Isaac Sim name them, without a prefix; the table in crate::simulation_interfaces says which
// node serves each and what it maps to.

/// Service `simulation_interfaces/srv/GetSimulatorFeatures`.
pub const GET_SIMULATOR_FEATURES: &str = "get_simulator_features";
/// Service `simulation_interfaces/srv/GetSimulationState`.
pub const GET_SIMULATION_STATE: &str = "get_simulation_state";
/// Service `simulation_interfaces/srv/SetSimulationState`.
pub const SET_SIMULATION_STATE: &str = "set_simulation_state";
/// Service `simulation_interfaces/srv/StepSimulation`.
pub const STEP_SIMULATION: &str = "step_simulation";
/// Action `simulation_interfaces/action/SimulateSteps`.
pub const SIMULATE_STEPS: &str = "simulate_steps";
/// Service `simulation_interfaces/srv/ResetSimulation`.
pub const RESET_SIMULATION: &str = "reset_simulation";
/// Service `simulation_interfaces/srv/GetEntities`.
pub const GET_ENTITIES: &str = "get_entities";
/// Service `simulation_interfaces/srv/GetEntityInfo`.
pub const GET_ENTITY_INFO: &str = "get_entity_info";
/// Service `simulation_interfaces/srv/GetEntityState`.
pub const GET_ENTITY_STATE: &str = "get_entity_state";
/// Service `simulation_interfaces/srv/GetEntitiesStates`.
pub const GET_ENTITIES_STATES: &str = "get_entities_states";
/// Service `simulation_interfaces/srv/SetEntityState`.
pub const SET_ENTITY_STATE: &str = "set_entity_state";
/// Service `simulation_interfaces/srv/GetEntityBounds`.
pub const GET_ENTITY_BOUNDS: &str = "get_entity_bounds";
/// Service `simulation_interfaces/srv/SpawnEntity` (answered: unsupported).
pub const SPAWN_ENTITY: &str = "spawn_entity";
/// Service `simulation_interfaces/srv/DeleteEntity` (answered: unsupported).
pub const DELETE_ENTITY: &str = "delete_entity";
/// Service `simulation_interfaces/srv/GetAvailableWorlds`.
pub const GET_AVAILABLE_WORLDS: &str = "get_available_worlds";
/// Service `simulation_interfaces/srv/LoadWorld`.
pub const LOAD_WORLD: &str = "load_world";
/// Service `simulation_interfaces/srv/GetCurrentWorld`.
pub const GET_CURRENT_WORLD: &str = "get_current_world";
/// Service `simulation_interfaces/srv/UnloadWorld` (answered: unsupported).
pub const UNLOAD_WORLD: &str = "unload_world";
