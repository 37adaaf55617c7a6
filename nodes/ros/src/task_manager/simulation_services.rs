//! The task manager's part of the ROS 2 standard simulation interfaces (the table and the sim's
//! part: [`crate::simulation_interfaces`]): `reset_simulation`, the worlds (the 256 tasks), and
//! `unload_world`, answered "unsupported".
//!
//! `reset_simulation` is `reset` without a seed and `load_world` is `set_task`: both start an
//! episode the usual way (the next seed, the scene published), and both answer once the sim has
//! published that episode's first observation, so a client's next call already sees the new
//! episode.

use composuite_core::TaskSpec;
use composuite_msgs::simulation_interfaces::msg::Result as SimResult;
use composuite_msgs::simulation_interfaces::srv;
use futures::stream::FusedStream;
use ros2_client::RmwRequestId;
use ros2_client::dds::Server;

use super::{TaskManager, Waiting};
use crate::shared::names;
use crate::shared::node::{Logger, RosNode, StartError};
use crate::simulation_interfaces::{self as si, failed, ok, unsupported, worlds};

type ServerOf<S> = Server<
    <S as composuite_msgs::RosService>::Request,
    <S as composuite_msgs::RosService>::Response,
>;

/// The task manager's servers of the standard.
pub(super) struct Servers {
    pub(super) reset: ServerOf<srv::ResetSimulation>,
    available: ServerOf<srv::GetAvailableWorlds>,
    pub(super) load: ServerOf<srv::LoadWorld>,
    current: ServerOf<srv::GetCurrentWorld>,
    unload: ServerOf<srv::UnloadWorld>,
}

/// A request to one of them.
pub(super) enum Request {
    Reset(RmwRequestId, srv::ResetSimulationRequest),
    Available(RmwRequestId, srv::GetAvailableWorldsRequest),
    Load(RmwRequestId, srv::LoadWorldRequest),
    Current(RmwRequestId),
    Unload(RmwRequestId),
    /// A request that did not decode: which server, and why.
    Unreadable(&'static str, String),
}

impl Servers {
    /// Create every server on `node`.
    pub(super) fn new(node: &mut RosNode) -> Result<Servers, StartError> {
        Ok(Servers {
            reset: node.server::<srv::ResetSimulation>(names::RESET_SIMULATION)?,
            available: node.server::<srv::GetAvailableWorlds>(names::GET_AVAILABLE_WORLDS)?,
            load: node.server::<srv::LoadWorld>(names::LOAD_WORLD)?,
            current: node.server::<srv::GetCurrentWorld>(names::GET_CURRENT_WORLD)?,
            unload: node.server::<srv::UnloadWorld>(names::UNLOAD_WORLD)?,
        })
    }

    /// Every request to these servers, as one stream.
    pub(super) fn requests(&self) -> impl FusedStream<Item = Request> + '_ {
        let u = Request::Unreadable;
        futures::stream::select_all([
            si::request_stream(&self.reset, names::RESET_SIMULATION, Request::Reset, u),
            si::request_stream(
                &self.available,
                names::GET_AVAILABLE_WORLDS,
                Request::Available,
                u,
            ),
            si::request_stream(&self.load, names::LOAD_WORLD, Request::Load, u),
            si::request_stream(
                &self.current,
                names::GET_CURRENT_WORLD,
                |id, _| Request::Current(id),
                u,
            ),
            si::request_stream(
                &self.unload,
                names::UNLOAD_WORLD,
                |id, _| Request::Unload(id),
                u,
            ),
        ])
    }
}

impl TaskManager {
    /// Handle one request; `reset_simulation` and `load_world` are answered later, when their
    /// episode's first observation arrives (see [`TaskManager::on_observation`]).
    pub(super) fn on_simulation_request(&mut self, s: &Servers, request: Request, log: &Logger) {
        match request {
            Request::Reset(id, req) => {
                if let Err(result) = self.reset_simulation(id, req.scope, log) {
                    si::reply(
                        &s.reset,
                        id,
                        srv::ResetSimulationResponse { result },
                        names::RESET_SIMULATION,
                        log,
                    );
                }
            }
            Request::Available(id, req) => {
                let response = available_worlds(&req);
                si::reply(&s.available, id, response, names::GET_AVAILABLE_WORLDS, log);
            }
            Request::Load(id, req) => {
                if let Err(result) = self.load_world(id, &req, log) {
                    let response = srv::LoadWorldResponse {
                        result,
                        ..Default::default()
                    };
                    si::reply(&s.load, id, response, names::LOAD_WORLD, log);
                }
            }
            Request::Current(id) => {
                let response = match &self.current {
                    Some(ep) => srv::GetCurrentWorldResponse {
                        result: ok(),
                        world: worlds::world(ep.task),
                    },
                    None => srv::GetCurrentWorldResponse {
                        result: failed(
                            srv::GetCurrentWorldResponse::NO_WORLD_LOADED,
                            "no episode has started yet; load_world starts one",
                        ),
                        ..Default::default()
                    },
                };
                si::reply(&s.current, id, response, names::GET_CURRENT_WORLD, log);
            }
            Request::Unload(id) => {
                let response = srv::UnloadWorldResponse {
                    result: unsupported("unloading the world"),
                };
                si::reply(&s.unload, id, response, names::UNLOAD_WORLD, log);
            }
            Request::Unreadable(name, err) => log.warn(format!("unreadable {name} request: {err}")),
        }
    }

    /// A new episode of the current task with the next seed, for a scope that includes
    /// SCOPE_STATE (SCOPE_DEFAULT and SCOPE_ALL do). Sim time is not reset: every stamp of a
    /// run is unique (recordings, tf buffers and the restart check rely on it); the episode's
    /// step count starts again at 0.
    fn reset_simulation(
        &mut self,
        id: RmwRequestId,
        scope: u8,
        log: &Logger,
    ) -> Result<(), SimResult> {
        use srv::ResetSimulationRequest as R;
        let resets_state = scope == R::SCOPE_DEFAULT || scope & R::SCOPE_STATE != 0;
        if !resets_state {
            return Err(failed(
                SimResult::RESULT_FEATURE_UNSUPPORTED,
                format!(
                    "scope {scope} is not offered: the suite resets the state (SCOPE_STATE = 2, \
                     also within SCOPE_DEFAULT = 0 and SCOPE_ALL = 255) as a new episode; sim \
                     time never goes back (SCOPE_TIME), and nothing is ever spawned \
                     (SCOPE_SPAWNED)"
                ),
            ));
        }
        match self.start_episode(None) {
            Ok((episode, seed)) => {
                log.info(format!(
                    "{}: episode {episode}, seed {seed}",
                    names::RESET_SIMULATION
                ));
                self.wait_for_start(id, episode, seed, Waiting::ResetSimulation);
                Ok(())
            }
            Err(err) => Err(failed(SimResult::RESULT_OPERATION_FAILED, err)),
        }
    }

    /// `set_task` of the task the uri names; answered when its first observation arrives.
    fn load_world(
        &mut self,
        id: RmwRequestId,
        req: &srv::LoadWorldRequest,
        log: &Logger,
    ) -> Result<(), SimResult> {
        use srv::LoadWorldResponse as R;
        if req.uri.is_empty() {
            return Err(if req.resource_string.is_empty() {
                failed(
                    R::NO_RESOURCE,
                    "no uri given; the uri names a task, robot/object/obstacle/objective, e.g. \
                     IIWA/box/no_obstacle/pick_place (get_available_worlds lists all 256)",
                )
            } else {
                failed(
                    SimResult::RESULT_FEATURE_UNSUPPORTED,
                    "worlds are not loaded from a resource_string; give the task as the uri, \
                     e.g. IIWA/box/no_obstacle/pick_place",
                )
            });
        }
        let task: TaskSpec = req.uri.parse().map_err(|e: composuite_core::TaskParseError| {
            failed(
                SimResult::RESULT_NOT_FOUND,
                format!(
                    "no world `{}`: {e}; a world is a task robot/object/obstacle/objective, e.g. \
                     IIWA/box/no_obstacle/pick_place (get_available_worlds lists all 256)",
                    req.uri
                ),
            )
        })?;
        let previous = self.task;
        self.task = task;
        match self.start_episode(None) {
            Ok((episode, seed)) => {
                log.info(format!(
                    "{}: {task} (episode {episode}, seed {seed})",
                    names::LOAD_WORLD
                ));
                self.wait_for_start(id, episode, seed, Waiting::LoadWorld(task));
                Ok(())
            }
            Err(err) => {
                self.task = previous;
                Err(failed(SimResult::RESULT_OPERATION_FAILED, err))
            }
        }
    }
}

fn available_worlds(req: &srv::GetAvailableWorldsRequest) -> srv::GetAvailableWorldsResponse {
    if !req.additional_sources.is_empty() && !req.continue_on_error {
        return srv::GetAvailableWorldsResponse {
            result: failed(
                SimResult::RESULT_OPERATION_FAILED,
                format!(
                    "the worlds are the 256 built-in tasks; additional sources {:?} cannot be \
                     searched (leave them out, or set continue_on_error to skip them)",
                    req.additional_sources
                ),
            ),
            ..Default::default()
        };
    }
    match worlds::available(&req.filter) {
        Ok(worlds) => srv::GetAvailableWorldsResponse {
            result: ok(),
            worlds,
        },
        Err(why) => srv::GetAvailableWorldsResponse {
            result: failed(SimResult::RESULT_OPERATION_FAILED, why),
            ..Default::default()
        },
    }
}
