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

use composuite_msgs::geometry_msgs::msg::{Twist, Vector3};
use composuite_msgs::simulation_interfaces::action::{
    SimulateStepsFeedback, SimulateStepsGoal, SimulateStepsResult,
};
use composuite_msgs::simulation_interfaces::msg::{
    Bounds, EntityInfo, EntityState, Result as SimResult, SimulationState,
};
use composuite_msgs::simulation_interfaces::srv;
use futures::stream::FusedStream;
use ros2_client::action::{GetResultRequest, GoalId, GoalStatusEnum, SendGoalRequest};
use ros2_client::action_msgs::CancelGoalRequest;
use ros2_client::dds::{ActionServer, Server};
use ros2_client::{ParameterValue, RmwRequestId};

use super::{ActionServers, Advance, Mode, Sim};
use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::{Logger, RosNode, StartError};
use crate::simulation_interfaces::entities::{self, Entity, Kind};
use crate::simulation_interfaces::{self as si, failed, ok, unsupported};

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

/// The `simulate_steps` goal being executed.
pub(super) struct StepsGoal {
    id: GoalId,
    /// The episode it steps: a new episode ends it.
    episode: u32,
    total: u64,
    done: u64,
}

fn vector(v: &nalgebra::Vector3<f64>) -> Vector3 {
    Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// Why a step cannot be taken now, as the standard's result.
enum NoStep {
    /// Not paused (realtime), or no episode, or the episode is over.
    Refused(SimResult),
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

    /// The standard's state: no world before the first scene; PAUSED in lockstep, PLAYING in
    /// realtime.
    fn simulation_state(&self) -> u8 {
        match (&self.run, self.mode) {
            (None, _) => SimulationState::STATE_NO_WORLD,
            (Some(_), Mode::Lockstep) => SimulationState::STATE_PAUSED,
            (Some(_), Mode::Realtime) => SimulationState::STATE_PLAYING,
        }
    }

    fn set_simulation_state(
        &mut self,
        target: u8,
        si_servers: &Servers,
        log: &Logger,
    ) -> SimResult {
        use srv::SetSimulationStateResponse as R;
        let mode = match target {
            SimulationState::STATE_PLAYING => Mode::Realtime,
            SimulationState::STATE_PAUSED => Mode::Lockstep,
            SimulationState::STATE_STOPPED => {
                return failed(
                    SimResult::RESULT_FEATURE_UNSUPPORTED,
                    "STATE_STOPPED (paused and reset) is not offered: reset_simulation starts a \
                     new episode, and STATE_PAUSED holds it",
                );
            }
            SimulationState::STATE_QUITTING => {
                return failed(
                    SimResult::RESULT_FEATURE_UNSUPPORTED,
                    "STATE_QUITTING is not offered: the suite stops on SIGINT/SIGTERM, as \
                     `ros2 launch` stops it",
                );
            }
            other => {
                return failed(
                    R::INCORRECT_TRANSITION,
                    format!(
                        "state {other} is not a state to set; valid targets: STATE_PLAYING (1), \
                         STATE_PAUSED (2)"
                    ),
                );
            }
        };
        if mode == self.mode {
            return failed(
                R::ALREADY_IN_TARGET_STATE,
                format!("already {}", state_name(target)),
            );
        }
        if mode == Mode::Realtime
            && let Some(goal) = self.steps_running.take()
        {
            let message = format!(
                "the simulation was set to PLAYING after {} of {} steps",
                goal.done, goal.total
            );
            self.end_steps_goal(
                &si_servers.steps,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_INCORRECT_STATE,
                message,
                log,
            );
        }
        // Through the parameter, so `ros2 param get` agrees; its change (handled next, before any
        // other request) sets the realtime timer.
        let value = match mode {
            Mode::Lockstep => "lockstep",
            Mode::Realtime => "realtime",
        };
        if let Err(err) = self
            .parameters
            .set("mode", ParameterValue::String(value.into()))
        {
            return failed(R::STATE_TRANSITION_ERROR, err);
        }
        self.mode = mode;
        log.info(format!(
            "{}: now {}",
            names::SET_SIMULATION_STATE,
            state_name(target)
        ));
        ok()
    }

    /// Whether one step may be taken now, or the standard's result saying why not.
    fn may_step(&self) -> Result<(), NoStep> {
        if self.mode != Mode::Lockstep {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_OPERATION_FAILED,
                "the simulation is PLAYING (realtime): steps are taken only when it is PAUSED; \
                 set_simulation_state to STATE_PAUSED first",
            )));
        }
        let Some(run) = &self.run else {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_INCORRECT_STATE,
                "no episode yet (the task manager publishes the scene)",
            )));
        };
        if run.env.ended().is_some() {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_INCORRECT_STATE,
                format!(
                    "episode {} is over after {} steps; reset_simulation starts the next",
                    run.episode,
                    run.env.steps()
                ),
            )));
        }
        Ok(())
    }

    /// `steps` control periods with the last command held, each published as a lockstep
    /// command's step is; stops early if the episode ends.
    fn step_simulation(&mut self, servers: &ActionServers, steps: u64, log: &Logger) -> SimResult {
        if steps == 0 {
            return failed(
                SimResult::RESULT_OPERATION_FAILED,
                "steps is 0; a step is one control period, and at least 1 is needed",
            );
        }
        for done in 0..steps {
            if let Err(NoStep::Refused(mut result)) = self.may_step() {
                if done > 0 {
                    result.error_message =
                        format!("{} of {steps} steps done: {}", done, result.error_message);
                }
                return result;
            }
            if !self.advance(servers, Advance::Command, log) {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "{done} of {steps} steps done: the sim refused the held command (see its log)"
                    ),
                );
            }
        }
        ok()
    }

    fn on_steps_goal(
        &mut self,
        server: &StepsServer,
        request_id: RmwRequestId,
        request: SendGoalRequest<SimulateStepsGoal>,
        log: &Logger,
    ) {
        let now = convert::time_from_nanos(self.sim_time_ns);
        if let Err(err) = self
            .steps_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        // Accepted, then ended at once when it cannot run: the result says why (a rejection
        // could not).
        let refused = if request.goal.steps == 0 {
            Some(failed(
                SimResult::RESULT_OPERATION_FAILED,
                "steps is 0; a step is one control period, and at least 1 is needed",
            ))
        } else if let Some(running) = &self.steps_running {
            Some(failed(
                SimResult::RESULT_INCORRECT_STATE,
                format!(
                    "another simulate_steps goal is running ({} of {} steps done); cancel it or \
                     wait for it",
                    running.done, running.total
                ),
            ))
        } else {
            self.may_step().err().map(|NoStep::Refused(result)| result)
        };
        match refused {
            Some(result) => {
                let message = result.error_message.clone();
                self.end_steps_goal(
                    server,
                    request.goal_id,
                    GoalStatusEnum::Aborted,
                    result.result,
                    message,
                    log,
                );
            }
            None => {
                self.steps_running = Some(StepsGoal {
                    id: request.goal_id,
                    episode: self.run.as_ref().map_or(0, |r| r.episode),
                    total: request.goal.steps,
                    done: 0,
                })
            }
        }
    }

    /// Whether a `simulate_steps` goal wants the next step (the loop calls
    /// [`Sim::simulate_step`] then).
    pub(super) fn steps_goal_running(&self) -> bool {
        self.steps_running.is_some()
    }

    /// One step of the running `simulate_steps` goal, its feedback, and its end when done.
    pub(super) fn simulate_step(
        &mut self,
        servers: &ActionServers,
        si_servers: &Servers,
        log: &Logger,
    ) {
        let Some(mut goal) = self.steps_running.take() else {
            return;
        };
        let server = &si_servers.steps;
        if self.run.as_ref().is_some_and(|r| r.episode != goal.episode) {
            let message = format!(
                "{} of {} steps done: a new episode started",
                goal.done, goal.total
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_INCORRECT_STATE,
                message,
                log,
            );
            return;
        }
        if let Err(NoStep::Refused(result)) = self.may_step() {
            let message = format!(
                "{} of {} steps done: {}",
                goal.done, goal.total, result.error_message
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                result.result,
                message,
                log,
            );
            return;
        }
        if !self.advance(servers, Advance::Command, log) {
            let message = format!(
                "{} of {} steps done: the sim refused the held command (see its log)",
                goal.done, goal.total
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_OPERATION_FAILED,
                message,
                log,
            );
            return;
        }
        goal.done += 1;
        let feedback = SimulateStepsFeedback {
            completed_steps: goal.done,
            remaining_steps: goal.total - goal.done,
        };
        if let Err(err) = server.send_feedback(goal.id, feedback) {
            log.warn(format!(
                "{} feedback not sent: {err:?}",
                names::SIMULATE_STEPS
            ));
        }
        if goal.done == goal.total {
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Succeeded,
                SimResult::RESULT_OK,
                String::new(),
                log,
            );
        } else {
            self.steps_running = Some(goal);
        }
    }

    fn on_steps_cancel(
        &mut self,
        server: &StepsServer,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let running = &mut self.steps_running;
        let (ended, replied) = self.steps_goals.cancel(server, request_id, request, |id| {
            running.take_if(|g| g.id == id)
        });
        if let Err(err) = replied {
            log.warn(err);
        }
        for goal in ended {
            let message = format!("canceled after {} of {} steps", goal.done, goal.total);
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Canceled,
                SimResult::RESULT_OK,
                message,
                log,
            );
        }
    }

    fn end_steps_goal(
        &mut self,
        server: &StepsServer,
        id: GoalId,
        status: GoalStatusEnum,
        code: u8,
        message: String,
        log: &Logger,
    ) {
        match status {
            GoalStatusEnum::Succeeded => {
                log.debug(format!("{} goal succeeded", names::SIMULATE_STEPS))
            }
            _ => log.info(format!(
                "{} goal {status:?}: {message}",
                names::SIMULATE_STEPS
            )),
        }
        let result = SimulateStepsResult {
            result: failed(code, message),
        };
        if let Err(err) = self.steps_goals.end(server, id, status, result) {
            log.warn(err);
        }
    }

    /// The current scene's entities (none before the first scene).
    fn entity_list(&self) -> Vec<Entity> {
        self.run
            .as_ref()
            .map(|run| entities::entities(run.env.task()))
            .unwrap_or_default()
    }

    /// The entity named `name`, or RESULT_NOT_FOUND naming the valid ones.
    fn entity(&self, name: &str) -> Result<Entity, SimResult> {
        if self.run.is_none() {
            return Err(failed(
                SimResult::RESULT_INCORRECT_STATE,
                "no world yet (the task manager publishes the scene)",
            ));
        }
        let mut list = self.entity_list();
        entities::find(&list, name)
            .map(|i| list.swap_remove(i))
            .map_err(|why| failed(SimResult::RESULT_NOT_FOUND, why))
    }

    /// The entities passing `filters` (name regex, categories, tags); bounds filters are not
    /// offered.
    fn filtered(
        &self,
        filters: &composuite_msgs::simulation_interfaces::msg::EntityFilters,
    ) -> Result<Vec<Entity>, SimResult> {
        if filters.bounds.r#type != Bounds::TYPE_EMPTY {
            return Err(failed(
                SimResult::RESULT_FEATURE_UNSUPPORTED,
                "filtering by bounds is not offered; leave `bounds` empty (TYPE_EMPTY) and \
                 filter by name, category or tags",
            ));
        }
        let regex = if filters.filter.is_empty() {
            None
        } else {
            Some(regex::Regex::new(&filters.filter).map_err(|e| {
                failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "filter `{}` is not a valid regular expression: {e}",
                        filters.filter
                    ),
                )
            })?)
        };
        Ok(self
            .entity_list()
            .into_iter()
            .filter(|e| regex.as_ref().is_none_or(|r| r.is_match(e.name)))
            .filter(|e| {
                filters.categories.is_empty()
                    || filters
                        .categories
                        .iter()
                        .any(|c| c.category == e.category())
            })
            .filter(|e| si::tags_match(&filters.tags, &e.tags))
            .collect())
    }

    /// An entity's pose and twist in `world`, stamped with the sim time. The acceleration is
    /// not measured: zero.
    fn entity_state(&self, entity: &Entity) -> EntityState {
        let run = self.run.as_ref().expect("entities exist only with a run");
        let (pose, linear, angular) = entity.motion(&run.env);
        let mut header = convert::header(convert::time_from_nanos(self.sim_time_ns));
        header.frame_id = names::WORLD_FRAME.into();
        EntityState {
            header,
            pose: convert::pose(&pose),
            twist: Twist {
                linear: vector(&linear),
                angular: vector(&angular),
            },
            acceleration: Default::default(),
        }
    }

    fn set_entity_state(&mut self, req: &srv::SetEntityStateRequest, log: &Logger) -> SimResult {
        use srv::SetEntityStateResponse as R;
        let entity = match self.entity(&req.entity) {
            Ok(e) => e,
            Err(result) => return result,
        };
        match entity.kind {
            Kind::Object => {}
            Kind::Robot => {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    "the robot's base is fixed and its joints move it (joint_command, \
                     reference_action, the controllers); only `object` can be set",
                );
            }
            Kind::Static => {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "`{}` is a static part of the task's arena; only `object` can be set",
                        entity.name
                    ),
                );
            }
        }
        let frame = req.state.header.frame_id.as_str();
        if !frame.is_empty() && frame != names::WORLD_FRAME {
            return failed(
                R::INVALID_POSE,
                format!(
                    "frame `{frame}` is not known here; give the state in `world` (or leave frame_id empty)"
                ),
            );
        }
        let p = &req.state.pose;
        let q = &p.orientation;
        let norm = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
        if !norm.is_finite() || (norm - 1.0).abs() > 1e-3 {
            return failed(
                R::INVALID_POSE,
                format!(
                    "the orientation ({}, {}, {}, {}) has length {norm}; a rotation quaternion has length 1",
                    q.x, q.y, q.z, q.w
                ),
            );
        }
        let pose = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(p.position.x, p.position.y, p.position.z),
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q.w, q.x, q.y, q.z,
            )),
        );
        let v = |v: &Vector3| nalgebra::Vector3::new(v.x, v.y, v.z);
        let run = self.run.as_mut().expect("checked by entity()");
        match run.env.set_object_state(
            &pose,
            &v(&req.state.twist.linear),
            &v(&req.state.twist.angular),
        ) {
            Ok(()) => {
                log.info(format!(
                    "{}: object at ({:.3}, {:.3}, {:.3}) m; the next step's observation and reward follow",
                    names::SET_ENTITY_STATE,
                    p.position.x,
                    p.position.y,
                    p.position.z
                ));
                let a = &req.state.acceleration;
                if [
                    a.linear.x,
                    a.linear.y,
                    a.linear.z,
                    a.angular.x,
                    a.angular.y,
                    a.angular.z,
                ]
                .iter()
                .any(|x| *x != 0.0)
                {
                    return failed(
                        SimResult::RESULT_OK,
                        "pose and twist set; the acceleration is not settable (the physics \
                         integrates forces) and was ignored",
                    );
                }
                ok()
            }
            Err(why) => failed(R::INVALID_POSE, why),
        }
    }
}

/// An entity's bounds as a `TYPE_BOX` (two opposite corners in its body frame), or why none.
fn entity_bounds(entity: &Entity) -> Result<Bounds, SimResult> {
    let Some((lo, hi)) = entity.bounds() else {
        return Err(failed(
            SimResult::RESULT_OPERATION_FAILED,
            format!(
                "`{}` has no fixed bounds: the arm's extent changes with its joints (its links \
                 are on `tf`)",
                entity.name
            ),
        ));
    };
    Ok(Bounds {
        r#type: Bounds::TYPE_BOX,
        points: vec![vector(&lo.coords), vector(&hi.coords)],
    })
}

fn state_name(state: u8) -> &'static str {
    match state {
        SimulationState::STATE_PLAYING => "PLAYING",
        SimulationState::STATE_PAUSED => "PAUSED",
        _ => "in that state",
    }
}
