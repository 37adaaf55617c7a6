//! The ROS 2 standard simulation interfaces (`simulation_interfaces`, Jazzy 1.5.1) on the suite:
//! what is offered, by which node, and what it maps to. [`INTERFACES`] is the one table; the
//! features `get_simulator_features` reports are computed from it, and docs/src/
//! simulation-interfaces.md prints the same table for people.
//!
//! The services are split as the suite's own are: the sim owns the world, so simulation state,
//! stepping and entities are the sim's ([`crate::sim`]); the task manager owns tasks, seeds and
//! episodes, so reset and worlds are its ([`crate::task_manager`]). Both sit in the
//! environment's namespace, so a client sees one simulator.
//!
//! - [`entities`]: the robot, the object and the arena's parts as entities;
//! - [`worlds`]: the 256 tasks as worlds.

pub mod entities;
pub mod worlds;

use composuite_msgs::simulation_interfaces::msg::{Result as SimResult, SimulatorFeatures as F};

use crate::shared::names;
use crate::shared::node_kind::NodeKind;

/// One interface of the standard the suite serves.
#[derive(Debug, Clone, Copy)]
pub struct Interface {
    /// Its name, relative to the environment's namespace.
    pub name: &'static str,
    /// Its ROS type.
    pub type_name: &'static str,
    /// The node that serves it.
    pub node: NodeKind,
    /// The `SimulatorFeatures` values it implements; empty for an interface that only answers
    /// "unsupported" (spawning, deleting, unloading: see [`UNSUPPORTED_WHY`]).
    pub features: &'static [u8],
    /// What it does on the suite.
    pub maps_to: &'static str,
}

/// Every interface the suite serves.
pub const INTERFACES: &[Interface] = &[
    Interface {
        name: names::GET_SIMULATOR_FEATURES,
        type_name: "simulation_interfaces/srv/GetSimulatorFeatures",
        node: NodeKind::Sim,
        features: &[],
        maps_to: "this table's features, the suite's name and version",
    },
    Interface {
        name: names::GET_SIMULATION_STATE,
        type_name: "simulation_interfaces/srv/GetSimulationState",
        node: NodeKind::Sim,
        features: &[F::SIMULATION_STATE_GETTING],
        maps_to: "the sim's `mode`: lockstep is PAUSED (it holds between commands), realtime PLAYING",
    },
    Interface {
        name: names::SET_SIMULATION_STATE,
        type_name: "simulation_interfaces/srv/SetSimulationState",
        node: NodeKind::Sim,
        features: &[F::SIMULATION_STATE_SETTING, F::SIMULATION_STATE_PAUSE],
        maps_to: "sets the sim's `mode` parameter: PAUSED = lockstep, PLAYING = realtime",
    },
    Interface {
        name: names::STEP_SIMULATION,
        type_name: "simulation_interfaces/srv/StepSimulation",
        node: NodeKind::Sim,
        features: &[F::STEP_SIMULATION_SINGLE, F::STEP_SIMULATION_MULTIPLE],
        maps_to: "`steps` control periods with the last command held, each published as a \
                  lockstep command's step",
    },
    Interface {
        name: names::SIMULATE_STEPS,
        type_name: "simulation_interfaces/action/SimulateSteps",
        node: NodeKind::Sim,
        features: &[F::STEP_SIMULATION_ACTION],
        maps_to: "the same, one control period per feedback; cancelable",
    },
    Interface {
        name: names::RESET_SIMULATION,
        type_name: "simulation_interfaces/srv/ResetSimulation",
        node: NodeKind::TaskManager,
        features: &[F::SIMULATION_RESET, F::SIMULATION_RESET_STATE],
        maps_to: "`reset` without a seed: a new episode of the current task with the next seed",
    },
    Interface {
        name: names::GET_ENTITIES,
        type_name: "simulation_interfaces/srv/GetEntities",
        node: NodeKind::Sim,
        features: &[F::ENTITY_CATEGORIES, F::ENTITY_TAGS],
        maps_to: "robot, object, bin1, bin2, the fixture and the obstacle, filtered by name \
                  regex, category and tags",
    },
    Interface {
        name: names::GET_ENTITY_INFO,
        type_name: "simulation_interfaces/srv/GetEntityInfo",
        node: NodeKind::Sim,
        features: &[F::ENTITY_INFO_GETTING],
        maps_to: "category (ROBOT, DYNAMIC_OBJECT, STATIC_OBJECT), description, tags",
    },
    Interface {
        name: names::GET_ENTITY_STATE,
        type_name: "simulation_interfaces/srv/GetEntityState",
        node: NodeKind::Sim,
        features: &[F::ENTITY_STATE_GETTING],
        maps_to: "pose and twist in `world`, stamped with the sim time",
    },
    Interface {
        name: names::GET_ENTITIES_STATES,
        type_name: "simulation_interfaces/srv/GetEntitiesStates",
        node: NodeKind::Sim,
        features: &[F::ENTITY_STATE_GETTING],
        maps_to: "the same for every entity the filters keep",
    },
    Interface {
        name: names::SET_ENTITY_STATE,
        type_name: "simulation_interfaces/srv/SetEntityState",
        node: NodeKind::Sim,
        features: &[F::ENTITY_STATE_SETTING],
        maps_to: "teleports the object (pose, twist); the next step's observation and reward \
                  follow",
    },
    Interface {
        name: names::GET_ENTITY_BOUNDS,
        type_name: "simulation_interfaces/srv/GetEntityBounds",
        node: NodeKind::Sim,
        features: &[F::ENTITY_BOUNDS],
        maps_to: "a box in the entity's frame (not the arm: its extent follows its joints)",
    },
    Interface {
        name: names::GET_AVAILABLE_WORLDS,
        type_name: "simulation_interfaces/srv/GetAvailableWorlds",
        node: NodeKind::TaskManager,
        features: &[F::AVAILABLE_WORLDS, F::WORLD_TAGS],
        maps_to: "the 256 tasks, tagged with their four axis elements",
    },
    Interface {
        name: names::LOAD_WORLD,
        type_name: "simulation_interfaces/srv/LoadWorld",
        node: NodeKind::TaskManager,
        features: &[F::WORLD_LOADING],
        maps_to: "`set_task`: the uri names a task, e.g. `IIWA/box/no_obstacle/pick_place`",
    },
    Interface {
        name: names::GET_CURRENT_WORLD,
        type_name: "simulation_interfaces/srv/GetCurrentWorld",
        node: NodeKind::TaskManager,
        features: &[F::WORLD_INFO_GETTING],
        maps_to: "the current episode's task",
    },
    Interface {
        name: names::UNLOAD_WORLD,
        type_name: "simulation_interfaces/srv/UnloadWorld",
        node: NodeKind::TaskManager,
        features: &[],
        maps_to: "unsupported",
    },
    Interface {
        name: names::SPAWN_ENTITY,
        type_name: "simulation_interfaces/srv/SpawnEntity",
        node: NodeKind::Sim,
        features: &[],
        maps_to: "unsupported",
    },
    Interface {
        name: names::DELETE_ENTITY,
        type_name: "simulation_interfaces/srv/DeleteEntity",
        node: NodeKind::Sim,
        features: &[],
        maps_to: "unsupported",
    },
];

/// Why spawning, deleting and unloading are answered "unsupported" (said in each reply).
pub const UNSUPPORTED_WHY: &str = "a CompoSuite task fixes its scene (one arm, one object, its \
    obstacle and arena); load_world changes the task, set_entity_state moves the object";

/// The suite's name and version, for `custom_info`.
pub fn custom_info() -> String {
    format!(
        "CompoSuite-ROS {} (simulation_interfaces 1.5.1, Jazzy): the 256 CompoSuite tasks; one \
         step is one control period",
        env!("CARGO_PKG_VERSION")
    )
}

/// The features of every interface in [`INTERFACES`], sorted, each once.
pub fn features() -> F {
    let mut features: Vec<u16> = INTERFACES
        .iter()
        .flat_map(|i| i.features.iter().map(|&f| u16::from(f)))
        .collect();
    features.sort_unstable();
    features.dedup();
    F {
        features,
        spawn_formats: Vec::new(),
        custom_info: custom_info(),
    }
}

/// `RESULT_OK`.
pub fn ok() -> SimResult {
    SimResult {
        result: SimResult::RESULT_OK,
        error_message: String::new(),
    }
}

/// A result with `code` and a message saying what was wrong and what is valid.
pub fn failed(code: u8, message: impl Into<String>) -> SimResult {
    SimResult {
        result: code,
        error_message: message.into(),
    }
}

/// `RESULT_FEATURE_UNSUPPORTED` for `what`, with [`UNSUPPORTED_WHY`].
pub fn unsupported(what: &str) -> SimResult {
    failed(
        SimResult::RESULT_FEATURE_UNSUPPORTED,
        format!("{what} is not supported: {UNSUPPORTED_WHY}"),
    )
}

/// Whether a tag list passes a `TagsFilter` (`tags` empty: every list passes).
pub fn tags_match(
    filter: &composuite_msgs::simulation_interfaces::msg::TagsFilter,
    tags: &[String],
) -> bool {
    use composuite_msgs::simulation_interfaces::msg::TagsFilter;
    let has = |t: &String| tags.iter().any(|own| own.eq_ignore_ascii_case(t));
    match filter.filter_mode {
        _ if filter.tags.is_empty() => true,
        TagsFilter::FILTER_MODE_ALL => filter.tags.iter().all(has),
        _ => filter.tags.iter().any(has),
    }
}

/// A server's requests as a stream of `T` (`wrap` for a request, `unreadable` for one that did
/// not decode), so a node's loop can merge all its servers of the standard into one arm.
pub fn request_stream<'a, Req, Resp, T: 'a>(
    server: &'a ros2_client::dds::Server<Req, Resp>,
    name: &'static str,
    wrap: fn(ros2_client::RmwRequestId, Req) -> T,
    unreadable: fn(&'static str, String) -> T,
) -> futures::stream::LocalBoxStream<'a, T>
where
    Req: ros2_client::Message + 'static,
    Resp: ros2_client::Message + 'static,
{
    use futures::StreamExt;
    server
        .receive_request_stream()
        .map(move |r| match r {
            Ok((id, req)) => wrap(id, req),
            Err(e) => unreadable(name, format!("{e:?}")),
        })
        .boxed_local()
}

/// Send a reply, or log why it was not sent.
pub fn reply<Req, Resp>(
    server: &ros2_client::dds::Server<Req, Resp>,
    id: ros2_client::RmwRequestId,
    response: Resp,
    what: &str,
    log: &crate::shared::node::Logger,
) where
    Req: ros2_client::Message + 'static,
    Resp: ros2_client::Message + 'static,
{
    if let Err(err) = server.send_response(id, response) {
        log.warn(format!("{what} reply not sent: {err:?}"));
    }
}

#[cfg(test)]
mod test;
