//! The sim's part of the ROS 2 standard simulation interfaces (the table and the task manager's
//! part: [`crate::simulation_interfaces`]): features, simulation state, stepping (the
//! `step_simulation` service and the `simulate_steps` action), entities, and the spawn/delete
//! services that answer "unsupported".
//!
//! The simulation state is the sim's `mode`: lockstep holds the world between commands, which
//! is the standard's PAUSED; realtime runs it on the wall clock, PLAYING. Setting the state sets
//! the `mode` parameter, so `ros2 param get` and the state agree. A step is one control period
//! with the last command held, done by [`Sim::advance`] exactly as a lockstep command's step:
//! the same messages, in the same order, with the same stamps.

mod scene_entities;
mod state;
mod steps;

use composuite_msgs::simulation_interfaces::action::{
    SimulateStepsFeedback, SimulateStepsGoal, SimulateStepsResult,
};
use composuite_msgs::simulation_interfaces::msg::{EntityInfo, SimulationState};
use composuite_msgs::simulation_interfaces::srv;
use futures::stream::FusedStream;
use ros2_client::RmwRequestId;
use ros2_client::action::{GetResultRequest, SendGoalRequest};
use ros2_client::action_msgs::CancelGoalRequest;
use ros2_client::dds::{ActionServer, Server};

use super::{ActionServers, Sim};
use crate::shared::names;
use crate::shared::node::{Logger, RosNode, StartError};
use crate::simulation_interfaces::{self as si, ok, unsupported};

use scene_entities::entity_bounds;
pub(super) use steps::StepsGoal;

type StepsServer = ActionServer<SimulateStepsGoal, SimulateStepsResult, SimulateStepsFeedback>;

/// A server of the standard's service `S`.
type ServerOf<S> = Server<
    <S as composuite_msgs::RosService>::Request,
    <S as composuite_msgs::RosService>::Response,
>;

/// The sim's servers of the standard.
pub(super) struct Servers {
    features: ServerOf<srv::GetSimulatorFeatures>,
    get_state: ServerOf<srv::GetSimulationState>,
    set_state: ServerOf<srv::SetSimulationState>,
    step: ServerOf<srv::StepSimulation>,
    entities: ServerOf<srv::GetEntities>,
    entity_info: ServerOf<srv::GetEntityInfo>,
    entity_state: ServerOf<srv::GetEntityState>,
    entities_states: ServerOf<srv::GetEntitiesStates>,
    set_entity_state: ServerOf<srv::SetEntityState>,
    entity_bounds: ServerOf<srv::GetEntityBounds>,
    spawn: ServerOf<srv::SpawnEntity>,
    delete: ServerOf<srv::DeleteEntity>,
    steps: StepsServer,
}

impl Servers {
    /// Create every server on `node`.
    pub(super) fn new(node: &mut RosNode) -> Result<Servers, StartError> {
        Ok(Servers {
            features: node.server::<srv::GetSimulatorFeatures>(names::GET_SIMULATOR_FEATURES)?,
            get_state: node.server::<srv::GetSimulationState>(names::GET_SIMULATION_STATE)?,
            set_state: node.server::<srv::SetSimulationState>(names::SET_SIMULATION_STATE)?,
            step: node.server::<srv::StepSimulation>(names::STEP_SIMULATION)?,
            entities: node.server::<srv::GetEntities>(names::GET_ENTITIES)?,
            entity_info: node.server::<srv::GetEntityInfo>(names::GET_ENTITY_INFO)?,
            entity_state: node.server::<srv::GetEntityState>(names::GET_ENTITY_STATE)?,
            entities_states: node.server::<srv::GetEntitiesStates>(names::GET_ENTITIES_STATES)?,
            set_entity_state: node.server::<srv::SetEntityState>(names::SET_ENTITY_STATE)?,
            entity_bounds: node.server::<srv::GetEntityBounds>(names::GET_ENTITY_BOUNDS)?,
            spawn: node.server::<srv::SpawnEntity>(names::SPAWN_ENTITY)?,
            delete: node.server::<srv::DeleteEntity>(names::DELETE_ENTITY)?,
            steps: node.action_server(
                names::SIMULATE_STEPS,
                "simulation_interfaces",
                "SimulateSteps",
            )?,
        })
    }

    /// Every request to these servers, as one stream (the sim's loop has one arm for them).
    pub(super) fn requests(&self) -> impl FusedStream<Item = Request> + '_ {
        let u = Request::Unreadable;
        futures::stream::select_all([
            si::request_stream(
                &self.features,
                names::GET_SIMULATOR_FEATURES,
                |id, _| Request::Features(id),
                u,
            ),
            si::request_stream(
                &self.get_state,
                names::GET_SIMULATION_STATE,
                |id, _| Request::GetState(id),
                u,
            ),
            si::request_stream(
                &self.set_state,
                names::SET_SIMULATION_STATE,
                Request::SetState,
                u,
            ),
            si::request_stream(&self.step, names::STEP_SIMULATION, Request::Step, u),
            si::request_stream(&self.entities, names::GET_ENTITIES, Request::Entities, u),
            si::request_stream(
                &self.entity_info,
                names::GET_ENTITY_INFO,
                Request::EntityInfo,
                u,
            ),
            si::request_stream(
                &self.entity_state,
                names::GET_ENTITY_STATE,
                Request::EntityState,
                u,
            ),
            si::request_stream(
                &self.entities_states,
                names::GET_ENTITIES_STATES,
                Request::EntitiesStates,
                u,
            ),
            si::request_stream(
                &self.set_entity_state,
                names::SET_ENTITY_STATE,
                Request::SetEntityState,
                u,
            ),
            si::request_stream(
                &self.entity_bounds,
                names::GET_ENTITY_BOUNDS,
                Request::EntityBounds,
                u,
            ),
            si::request_stream(
                &self.spawn,
                names::SPAWN_ENTITY,
                |id, _| Request::Spawn(id),
                u,
            ),
            si::request_stream(
                &self.delete,
                names::DELETE_ENTITY,
                |id, _| Request::Delete(id),
                u,
            ),
            si::request_stream(
                self.steps.goal_service(),
                names::SIMULATE_STEPS,
                Request::StepsGoal,
                u,
            ),
            si::request_stream(
                self.steps.cancel_service(),
                names::SIMULATE_STEPS,
                Request::StepsCancel,
                u,
            ),
            si::request_stream(
                self.steps.result_service(),
                names::SIMULATE_STEPS,
                Request::StepsResult,
                u,
            ),
        ])
    }
}

/// A request to one of the sim's servers of the standard.
pub(super) enum Request {
    Features(RmwRequestId),
    GetState(RmwRequestId),
    SetState(RmwRequestId, srv::SetSimulationStateRequest),
    Step(RmwRequestId, srv::StepSimulationRequest),
    Entities(RmwRequestId, srv::GetEntitiesRequest),
    EntityInfo(RmwRequestId, srv::GetEntityInfoRequest),
    EntityState(RmwRequestId, srv::GetEntityStateRequest),
    EntitiesStates(RmwRequestId, srv::GetEntitiesStatesRequest),
    SetEntityState(RmwRequestId, srv::SetEntityStateRequest),
    EntityBounds(RmwRequestId, srv::GetEntityBoundsRequest),
    Spawn(RmwRequestId),
    Delete(RmwRequestId),
    StepsGoal(RmwRequestId, SendGoalRequest<SimulateStepsGoal>),
    StepsCancel(RmwRequestId, CancelGoalRequest),
    StepsResult(RmwRequestId, GetResultRequest),
    /// A request that did not decode: which server, and why.
    Unreadable(&'static str, String),
}

impl Sim {
    /// Handle one request to the sim's servers of the standard.
    pub(super) fn on_simulation_request(
        &mut self,
        servers: &ActionServers,
        si_servers: &Servers,
        request: Request,
        log: &Logger,
    ) {
        let s = si_servers;
        match request {
            Request::Features(id) => {
                let response = srv::GetSimulatorFeaturesResponse {
                    features: si::features(),
                };
                si::reply(
                    &s.features,
                    id,
                    response,
                    names::GET_SIMULATOR_FEATURES,
                    log,
                );
            }
            Request::GetState(id) => {
                let response = srv::GetSimulationStateResponse {
                    state: SimulationState {
                        state: self.simulation_state(),
                    },
                    result: ok(),
                };
                si::reply(&s.get_state, id, response, names::GET_SIMULATION_STATE, log);
            }
            Request::SetState(id, req) => {
                let result = self.set_simulation_state(req.state.state, si_servers, log);
                let response = srv::SetSimulationStateResponse { result };
                si::reply(&s.set_state, id, response, names::SET_SIMULATION_STATE, log);
            }
            Request::Step(id, req) => {
                let result = self.step_simulation(servers, req.steps, log);
                si::reply(
                    &s.step,
                    id,
                    srv::StepSimulationResponse { result },
                    names::STEP_SIMULATION,
                    log,
                );
            }
            Request::Entities(id, req) => {
                let response = match self.filtered(&req.filters) {
                    Ok(list) => srv::GetEntitiesResponse {
                        result: ok(),
                        entities: list.iter().map(|e| e.name.to_string()).collect(),
                    },
                    Err(result) => srv::GetEntitiesResponse {
                        result,
                        entities: Vec::new(),
                    },
                };
                si::reply(&s.entities, id, response, names::GET_ENTITIES, log);
            }
            Request::EntityInfo(id, req) => {
                let response = match self.entity(&req.entity) {
                    Ok(e) => srv::GetEntityInfoResponse {
                        result: ok(),
                        info: EntityInfo {
                            category: composuite_msgs::simulation_interfaces::msg::EntityCategory {
                                category: e.category(),
                            },
                            description: e.description.clone(),
                            tags: e.tags.clone(),
                        },
                    },
                    Err(result) => srv::GetEntityInfoResponse {
                        result,
                        ..Default::default()
                    },
                };
                si::reply(&s.entity_info, id, response, names::GET_ENTITY_INFO, log);
            }
            Request::EntityState(id, req) => {
                let response = match self.entity(&req.entity) {
                    Ok(e) => srv::GetEntityStateResponse {
                        result: ok(),
                        state: self.entity_state(&e),
                    },
                    Err(result) => srv::GetEntityStateResponse {
                        result,
                        ..Default::default()
                    },
                };
                si::reply(&s.entity_state, id, response, names::GET_ENTITY_STATE, log);
            }
            Request::EntitiesStates(id, req) => {
                let response = match self.filtered(&req.filters) {
                    Ok(list) => srv::GetEntitiesStatesResponse {
                        result: ok(),
                        entities: list.iter().map(|e| e.name.to_string()).collect(),
                        states: list.iter().map(|e| self.entity_state(e)).collect(),
                    },
                    Err(result) => srv::GetEntitiesStatesResponse {
                        result,
                        ..Default::default()
                    },
                };
                si::reply(
                    &s.entities_states,
                    id,
                    response,
                    names::GET_ENTITIES_STATES,
                    log,
                );
            }
            Request::SetEntityState(id, req) => {
                let result = self.set_entity_state(&req, log);
                let response = srv::SetEntityStateResponse { result };
                si::reply(
                    &s.set_entity_state,
                    id,
                    response,
                    names::SET_ENTITY_STATE,
                    log,
                );
            }
            Request::EntityBounds(id, req) => {
                let response = match self.entity(&req.entity).and_then(|e| entity_bounds(&e)) {
                    Ok(bounds) => srv::GetEntityBoundsResponse {
                        result: ok(),
                        bounds,
                    },
                    Err(result) => srv::GetEntityBoundsResponse {
                        result,
                        ..Default::default()
                    },
                };
                si::reply(
                    &s.entity_bounds,
                    id,
                    response,
                    names::GET_ENTITY_BOUNDS,
                    log,
                );
            }
            Request::Spawn(id) => {
                let response = srv::SpawnEntityResponse {
                    result: unsupported("spawning entities"),
                    ..Default::default()
                };
                si::reply(&s.spawn, id, response, names::SPAWN_ENTITY, log);
            }
            Request::Delete(id) => {
                let response = srv::DeleteEntityResponse {
                    result: unsupported("deleting entities"),
                };
                si::reply(&s.delete, id, response, names::DELETE_ENTITY, log);
            }
            Request::StepsGoal(id, req) => self.on_steps_goal(&s.steps, id, req, log),
            Request::StepsCancel(id, req) => self.on_steps_cancel(&s.steps, id, &req, log),
            Request::StepsResult(id, req) => {
                if let Err(err) = self.steps_goals.result_request(&s.steps, id, req.goal_id) {
                    log.warn(err);
                }
            }
            Request::Unreadable(name, err) => log.warn(format!("unreadable {name} request: {err}")),
        }
    }
}
