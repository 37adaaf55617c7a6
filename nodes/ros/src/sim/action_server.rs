//! An action server's goal bookkeeping, as rclcpp keeps it, over ros2-client's `ActionServer`
//! services: goals are accepted or rejected at once, a result is answered whenever it is asked
//! for (before or after the goal ends), cancel requests are answered at once, and the status
//! array (every goal still known) is published on each change. What a goal does is the
//! controller's business ([`crate::sim::controllers::running`]); this module only talks to
//! clients.

use composuite_msgs::builtin_interfaces::msg::Time as TimeMsg;
use ros2_client::RmwRequestId;
use ros2_client::action::{GetResultResponse, GoalId, GoalInfo, GoalStatusEnum, SendGoalResponse};
use ros2_client::action_msgs::{
    CancelGoalRequest, CancelGoalResponse, CancelGoalResponseEnum, GoalStatus, GoalStatusArray,
};
use ros2_client::builtin_interfaces::Time;
use ros2_client::dds::ActionServer;
use ros2_client::{Message, WriteError};

/// How many ended goals keep their results (and status entries). rclcpp keeps them for its
/// `result_timeout` (15 min of wall time); a count bounds memory the same way over a week-long
/// run, and a client asks for a result right after its goal is accepted.
const ENDED_KEPT: usize = 32;

struct Goal<R> {
    id: GoalId,
    accepted: Time,
    status: GoalStatusEnum,
    result: Option<R>,
    /// Result requests waiting for the goal to end.
    waiting: Vec<RmwRequestId>,
}

/// One action's goals. The server itself stays with the node's event loop (its request streams
/// borrow it); each reply takes it as an argument.
#[derive(Default)]
pub struct Goals<R> {
    /// In acceptance order.
    goals: Vec<Goal<R>>,
}

/// A reply could not be written (DDS is shutting down); said by the caller.
pub type ReplyError = String;

fn reply_error<T: std::fmt::Debug>(what: &str, e: WriteError<T>) -> ReplyError {
    format!("{what} not sent: {e:?}")
}

/// The server of an action with result type `R` (any goal and feedback type).
pub trait Server<R> {
    /// Reply to a goal request.
    fn goal_reply(&self, request: RmwRequestId, reply: SendGoalResponse) -> Result<(), ReplyError>;
    /// Reply to a cancel request.
    fn cancel_reply(
        &self,
        request: RmwRequestId,
        reply: CancelGoalResponse,
    ) -> Result<(), ReplyError>;
    /// Reply to a result request.
    fn result_reply(
        &self,
        request: RmwRequestId,
        reply: GetResultResponse<R>,
    ) -> Result<(), ReplyError>;
    /// Publish the goals' status.
    fn status(&self, status: GoalStatusArray) -> Result<(), ReplyError>;
}

impl<G, R, F> Server<R> for ActionServer<G, R, F>
where
    G: Message + Clone + 'static,
    R: Message + Clone + 'static,
    F: Message + 'static,
{
    fn goal_reply(&self, request: RmwRequestId, reply: SendGoalResponse) -> Result<(), ReplyError> {
        self.goal_service()
            .send_response(request, reply)
            .map_err(|e| reply_error("goal response", e))
    }
    fn cancel_reply(
        &self,
        request: RmwRequestId,
        reply: CancelGoalResponse,
    ) -> Result<(), ReplyError> {
        self.cancel_service()
            .send_response(request, reply)
            .map_err(|e| reply_error("cancel response", e))
    }
    fn result_reply(
        &self,
        request: RmwRequestId,
        reply: GetResultResponse<R>,
    ) -> Result<(), ReplyError> {
        self.result_service()
            .send_response(request, reply)
            .map_err(|e| reply_error("result", e))
    }
    fn status(&self, status: GoalStatusArray) -> Result<(), ReplyError> {
        self.send_goal_statuses(status)
            .map(|_| ())
            .map_err(|e| reply_error("goal status", e))
    }
}

impl<R: Clone + Default> Goals<R> {
    /// Accept goal `id` (it starts executing at once), stamped `now` (sim time).
    pub fn accept(
        &mut self,
        server: &impl Server<R>,
        request: RmwRequestId,
        id: GoalId,
        now: &TimeMsg,
    ) -> Result<(), ReplyError> {
        let accepted = ros_time(now);
        self.goals.push(Goal {
            id,
            accepted,
            status: GoalStatusEnum::Executing,
            result: None,
            waiting: Vec::new(),
        });
        server.goal_reply(
            request,
            SendGoalResponse {
                accepted: true,
                stamp: accepted,
            },
        )?;
        self.publish_status(server)
    }

    /// Reject a goal request (the reason goes to the log: the response cannot carry it).
    pub fn reject(
        server: &impl Server<R>,
        request: RmwRequestId,
        now: &TimeMsg,
    ) -> Result<(), ReplyError> {
        server.goal_reply(
            request,
            SendGoalResponse {
                accepted: false,
                stamp: ros_time(now),
            },
        )
    }

    /// The running goals a cancel request names. A zero id and zero stamp name every goal; a stamp names the goals
    /// accepted at or before it; an id names that goal.
    fn cancel_targets(&self, request: &CancelGoalRequest) -> Vec<GoalId> {
        let GoalInfo { goal_id, stamp } = &request.goal_info;
        let by_stamp = stamp.to_nanos() != 0;
        self.goals
            .iter()
            .filter(|g| is_running(g.status))
            .filter(|g| {
                (*goal_id == GoalId::ZERO && !by_stamp)
                    || g.id == *goal_id
                    || (by_stamp && g.accepted.to_nanos() <= stamp.to_nanos())
            })
            .map(|g| g.id)
            .collect()
    }

    /// Handle a cancel request: `end` ends each running goal it names (giving what to report,
    /// or `None` if that goal was not running after all), then the reply lists the ended goals.
    pub fn cancel<E>(
        &self,
        server: &impl Server<R>,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        mut end: impl FnMut(GoalId) -> Option<E>,
    ) -> (Vec<E>, Result<(), ReplyError>) {
        let mut ended = Vec::new();
        let mut canceling = Vec::new();
        for goal in self.cancel_targets(request) {
            if let Some(event) = end(goal) {
                ended.push(event);
                canceling.push(goal);
            }
        }
        let replied = self.answer_cancel(server, request_id, request, &canceling);
        (ended, replied)
    }

    /// Answer a cancel request: `canceling` are the goals it ended (empty: say why not).
    fn answer_cancel(
        &self,
        server: &impl Server<R>,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        canceling: &[GoalId],
    ) -> Result<(), ReplyError> {
        let goals_canceling: Vec<GoalInfo> = self
            .goals
            .iter()
            .filter(|g| canceling.contains(&g.id))
            .map(|g| GoalInfo {
                goal_id: g.id,
                stamp: g.accepted,
            })
            .collect();
        let named = request.goal_info.goal_id;
        let return_code = if !goals_canceling.is_empty() {
            CancelGoalResponseEnum::None
        } else if named != GoalId::ZERO && !self.goals.iter().any(|g| g.id == named) {
            CancelGoalResponseEnum::UnknownGoal
        } else if named != GoalId::ZERO {
            CancelGoalResponseEnum::GoalTerminated
        } else {
            CancelGoalResponseEnum::Rejected
        };
        server.cancel_reply(
            request_id,
            CancelGoalResponse {
                return_code,
                goals_canceling,
            },
        )
    }

    /// Goal `id` ended with `status` and `result`: answer the result requests waiting for it.
    pub fn end(
        &mut self,
        server: &impl Server<R>,
        id: GoalId,
        status: GoalStatusEnum,
        result: R,
    ) -> Result<(), ReplyError> {
        let Some(goal) = self.goals.iter_mut().find(|g| g.id == id) else {
            return Ok(());
        };
        goal.status = status;
        goal.result = Some(result.clone());
        let waiting = std::mem::take(&mut goal.waiting);
        for request in waiting {
            server.result_reply(
                request,
                GetResultResponse {
                    status,
                    result: result.clone(),
                },
            )?;
        }
        self.forget_old();
        self.publish_status(server)
    }

    /// A client asks for goal `id`'s result: answered now if the goal has ended (or is unknown:
    /// status UNKNOWN, as rclcpp answers), else when it ends.
    pub fn result_request(
        &mut self,
        server: &impl Server<R>,
        request: RmwRequestId,
        id: GoalId,
    ) -> Result<(), ReplyError> {
        let (status, result) = match self.goals.iter_mut().find(|g| g.id == id) {
            Some(goal) => match &goal.result {
                Some(result) => (goal.status, result.clone()),
                None => {
                    goal.waiting.push(request);
                    return Ok(());
                }
            },
            None => (GoalStatusEnum::Unknown, R::default()),
        };
        server.result_reply(request, GetResultResponse { status, result })
    }

    /// Drop the oldest ended goals beyond [`ENDED_KEPT`].
    fn forget_old(&mut self) {
        let ended = self.goals.iter().filter(|g| !is_running(g.status)).count();
        let mut excess = ended.saturating_sub(ENDED_KEPT);
        self.goals.retain(|g| {
            let drop = excess > 0 && !is_running(g.status);
            excess -= usize::from(drop);
            !drop
        });
    }

    fn publish_status(&self, server: &impl Server<R>) -> Result<(), ReplyError> {
        let status_list = self
            .goals
            .iter()
            .map(|g| GoalStatus {
                goal_info: GoalInfo {
                    goal_id: g.id,
                    stamp: g.accepted,
                },
                status: g.status,
            })
            .collect();
        server.status(GoalStatusArray { status_list })
    }
}

fn is_running(status: GoalStatusEnum) -> bool {
    matches!(
        status,
        GoalStatusEnum::Accepted | GoalStatusEnum::Executing | GoalStatusEnum::Canceling
    )
}

fn ros_time(t: &TimeMsg) -> Time {
    Time::new(t.sec, t.nanosec)
}
