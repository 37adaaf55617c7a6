//! Following joint-space paths with the reference's 8 numbers.
//!
//! The reference's controller sets each joint's goal to its measured position plus 0.05·a at
//! the start of a control step and pulls the joint towards it as an ideal critically damped
//! spring (q̈ = kp·(goal − q) − kd·q̇, kp 50, the mass matrix and the bias torques cancelled).
//! Over one control step that is a linear map of the joint's state and of the goal offset
//! ([`StepResponse`]), the same for every joint of every arm. Held at a = +1 a joint creeps
//! towards about 0.16 rad/s, so a path is run at most at [`MAX_SPEED`] (the rest is the
//! feedback's room) and its time law is a trapezoid from rest to rest ([`Leg`]).
//!
//! [`Tracker`] turns the path's position and speed one step ahead into the goal offset that
//! the linear map says lands there, with feedback on the position error and an estimate of
//! what the map does not know (a held object's weight, joint friction, a contact), learnt from
//! how far each step's speed ended from the prediction.

use crate::env::REFERENCE_DELTA_SCALE;
use crate::physics::{ARM_DOF, PhysicsParams, REFERENCE_KP};

/// Joint configuration (rad, URDF order).
pub(crate) type Joints = [f64; ARM_DOF];

/// The fastest a path is run (rad/s, the fastest joint). A joint held at a = +1 settles at
/// ≈ 0.16 rad/s; the difference is what the feedback has left to correct with (in free
/// space the arm then stays within about 1 mrad of the path).
pub(crate) const MAX_SPEED: f64 = 0.15;
/// The largest path acceleration (rad/s²): from rest, a = +1 gives a joint ≈ 1.8 rad/s² over
/// the first step and less after, down to nothing at the top speed.
pub(crate) const MAX_ACCELERATION: f64 = 0.8;
/// Position feedback (1/s): each step removes about `T·POSITION_GAIN` of the position error
/// (0.3 at 50 ms).
const POSITION_GAIN: f64 = 6.0;
/// How much of each step's unexplained speed change the estimate of the unmodelled torque
/// takes in (per step).
const DISTURBANCE_RATE: f64 = 0.3;
/// A leg counts as arrived when every joint is this close to its end (rad)…
const ARRIVED_POSITION: f64 = 0.004;
/// …and slower than this (rad/s).
const ARRIVED_SPEED: f64 = 0.02;
/// Steps after a leg's planned end at which it counts as over even if not arrived.
const SETTLE_STEPS: u32 = 40;
/// After its planned end, a leg is also over once no joint has moved more than this (rad/s)
/// for [`STALL_STEPS`] steps: a contact holds the arm back.
const STALL_SPEED: f64 = 0.01;
/// See [`STALL_SPEED`].
const STALL_STEPS: u32 = 3;

/// One joint under the reference's controller over one control step, the goal offset `g`
/// (rad, 0.05·a) held: q' = q + alpha·g + beta·q̇ and q̇' = gamma·q̇ + delta·g.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StepResponse {
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    pub delta: f64,
    /// The control period (s).
    pub period: f64,
}

impl StepResponse {
    /// The ideal law integrated over the control step's physics steps the way the engine
    /// integrates (the speed first, then the position with the new speed).
    pub fn of(params: &PhysicsParams) -> StepResponse {
        let kd = 2.0 * REFERENCE_KP.sqrt();
        let run = |v0: f64, goal: f64| {
            let (mut q, mut v) = (0.0, v0);
            for _ in 0..params.substeps {
                v += params.dt * (REFERENCE_KP * (goal - q) - kd * v);
                q += params.dt * v;
            }
            (q, v)
        };
        let (alpha, delta) = run(0.0, 1.0);
        let (beta, gamma) = run(1.0, 0.0);
        StepResponse {
            alpha,
            beta,
            gamma,
            delta,
            period: params.dt * params.substeps as f64,
        }
    }

    /// The speed (rad/s) a joint held at a = ±1 settles at.
    #[cfg(test)]
    pub fn top_speed(&self) -> f64 {
        self.delta * REFERENCE_DELTA_SCALE / (1.0 - self.gamma)
    }
}

/// The largest joint difference (rad): how long a straight joint-space move takes is set by
/// the joint that moves furthest.
pub(crate) fn joint_distance(a: &Joints, b: &Joints) -> f64 {
    (0..ARM_DOF)
        .map(|j| (a[j] - b[j]).abs())
        .fold(0.0, f64::max)
}

/// A stretch of path run from rest to rest: a polyline through joint configurations, timed by
/// a trapezoid over its length in [`joint_distance`].
#[derive(Debug, Clone)]
pub(crate) struct Leg {
    points: Vec<Joints>,
    /// Path length at each point (rad).
    at_point: Vec<f64>,
    /// The trapezoid's top speed (rad/s) and acceleration (rad/s²).
    speed: f64,
    acceleration: f64,
}

impl Leg {
    /// A leg through `points` (at least one) at the top pace.
    pub fn new(points: Vec<Joints>) -> Leg {
        assert!(!points.is_empty(), "a leg needs a point");
        let mut at_point = vec![0.0];
        for pair in points.windows(2) {
            let last = *at_point.last().expect("one at least");
            at_point.push(last + joint_distance(&pair[0], &pair[1]));
        }
        Leg {
            points,
            at_point,
            speed: MAX_SPEED,
            acceleration: MAX_ACCELERATION,
        }
    }

    /// The path's length (rad).
    pub fn length(&self) -> f64 {
        *self.at_point.last().expect("one at least")
    }

    /// Where the leg ends.
    pub fn end(&self) -> Joints {
        *self.points.last().expect("one at least")
    }

    /// The time (s) the trapezoid takes.
    pub fn duration(&self) -> f64 {
        let (ramp, top) = self.ramp();
        2.0 * ramp + top
    }

    /// The ramp's duration and the time at top speed (s).
    fn ramp(&self) -> (f64, f64) {
        let length = self.length();
        let full_ramp = self.speed / self.acceleration;
        if self.acceleration * full_ramp * full_ramp >= length {
            // A triangle: never reaches the top speed.
            ((length / self.acceleration).sqrt(), 0.0)
        } else {
            (
                full_ramp,
                (length - self.acceleration * full_ramp * full_ramp) / self.speed,
            )
        }
    }

    /// Path length travelled and path speed at time `t` (s).
    fn progress(&self, t: f64) -> (f64, f64) {
        let (ramp, top) = self.ramp();
        let peak = self.acceleration * ramp;
        let length = self.length();
        if t <= 0.0 {
            (0.0, 0.0)
        } else if t < ramp {
            (0.5 * self.acceleration * t * t, self.acceleration * t)
        } else if t < ramp + top {
            (0.5 * peak * ramp + peak * (t - ramp), peak)
        } else if t < 2.0 * ramp + top {
            let left = 2.0 * ramp + top - t;
            (
                length - 0.5 * self.acceleration * left * left,
                self.acceleration * left,
            )
        } else {
            (length, 0.0)
        }
    }

    /// The path's joints and joint speeds (rad/s) at time `t` (s).
    pub fn at(&self, t: f64) -> (Joints, Joints) {
        if self.points.len() == 1 {
            return (self.points[0], [0.0; ARM_DOF]);
        }
        let (s, speed) = self.progress(t);
        let i = self
            .at_point
            .partition_point(|&a| a <= s)
            .clamp(1, self.points.len() - 1);
        let (a, b) = (&self.points[i - 1], &self.points[i]);
        let span = self.at_point[i] - self.at_point[i - 1];
        if span <= 0.0 {
            return (*b, [0.0; ARM_DOF]);
        }
        let f = ((s - self.at_point[i - 1]) / span).clamp(0.0, 1.0);
        let q = std::array::from_fn(|j| a[j] + f * (b[j] - a[j]));
        let v = std::array::from_fn(|j| speed * (b[j] - a[j]) / span);
        (q, v)
    }
}

/// Turns a leg into the reference's joint actions, one control step at a time.
#[derive(Debug, Clone)]
pub(crate) struct Tracker {
    response: StepResponse,
    leg: Leg,
    /// Control steps taken on the current leg.
    steps: u32,
    /// The estimated speed change per step (rad/s) the linear map does not predict.
    disturbance: Joints,
    /// The state and goal offsets of the last step, to learn the disturbance from.
    last: Option<(Joints, Joints)>,
    /// Steps in a row, after the leg's planned end, with every joint slower than
    /// [`STALL_SPEED`].
    stalled: u32,
}

impl Tracker {
    /// A tracker holding the arm at `q`.
    pub fn new(params: &PhysicsParams, q: Joints) -> Tracker {
        Tracker {
            response: StepResponse::of(params),
            leg: Leg::new(vec![q]),
            steps: 0,
            disturbance: [0.0; ARM_DOF],
            last: None,
            stalled: 0,
        }
    }

    /// Run `leg` from the next step on (the estimate of the disturbance is kept: a held
    /// object weighs the same on the next leg).
    pub fn start(&mut self, leg: Leg) {
        self.leg = leg;
        self.steps = 0;
        self.stalled = 0;
    }

    /// The leg being run.
    #[cfg(test)]
    pub fn leg(&self) -> &Leg {
        &self.leg
    }

    /// Control steps taken on the current leg.
    #[cfg(test)]
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Control steps the leg's time law takes.
    fn planned_steps(&self) -> u32 {
        (self.leg.duration() / self.response.period).ceil() as u32
    }

    /// Whether the leg is over: its time has run and the arm has arrived (or has had
    /// [`SETTLE_STEPS`] to, or has stalled short of it).
    pub fn arrived(&self, q: &Joints, v: &Joints) -> bool {
        let planned = self.planned_steps();
        if self.steps < planned {
            return false;
        }
        let end = self.leg.end();
        let close = joint_distance(q, &end) <= ARRIVED_POSITION
            && v.iter().all(|s| s.abs() <= ARRIVED_SPEED);
        close || self.stalled >= STALL_STEPS || self.steps >= planned + SETTLE_STEPS
    }

    /// The normalised joint actions (in [−1, 1]) for the arm measured at `q`, `v`.
    pub fn act(&mut self, q: &Joints, v: &Joints) -> Joints {
        let r = self.response;
        let limit = REFERENCE_DELTA_SCALE;
        if let Some((v0, g0)) = self.last {
            for j in 0..ARM_DOF {
                let surprise = v[j] - (r.gamma * v0[j] + r.delta * g0[j]);
                let d = &mut self.disturbance[j];
                *d += DISTURBANCE_RATE * (surprise - *d);
                // A joint against a limit or a wall: no more than the goal offset can undo.
                *d = d.clamp(-r.delta * limit, r.delta * limit);
            }
        }
        if self.steps >= self.planned_steps() && v.iter().all(|s| s.abs() < STALL_SPEED) {
            self.stalled += 1;
        } else {
            self.stalled = 0;
        }
        self.steps += 1;
        let (q_ref, v_ref) = self.leg.at(self.steps as f64 * r.period);
        let k = POSITION_GAIN;
        let mut g = [0.0; ARM_DOF];
        for j in 0..ARM_DOF {
            // Speed one step ahead = the path's plus a pull towards its position, both as the
            // linear map predicts them with this step's offset g.
            let wanted = v_ref[j] + k * (q_ref[j] - q[j] - r.beta * v[j])
                - r.gamma * v[j]
                - self.disturbance[j];
            g[j] = (wanted / (r.delta + k * r.alpha)).clamp(-limit, limit);
        }
        self.last = Some((*v, g));
        g.map(|x| x / limit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TaskSpec;
    use crate::env::{Action, Env, EnvConfig};

    /// The linear map reproduces the reference's measured first steps at a = +1 from rest
    /// (docs/src/reference-facts.md §4.2: 0.0026 rad, then 0.0056, 0.0069 per step).
    #[test]
    fn the_step_response_matches_the_references_creep() {
        let r = StepResponse::of(&PhysicsParams::default());
        let (mut q, mut v) = (0.0, 0.0);
        let mut moved = Vec::new();
        for _ in 0..3 {
            let (q1, v1) = (
                q + r.alpha * 0.05 + r.beta * v,
                r.gamma * v + r.delta * 0.05,
            );
            moved.push(q1 - q);
            (q, v) = (q1, v1);
        }
        for (got, want) in moved.iter().zip([0.0026, 0.0056, 0.0069]) {
            assert!((got - want).abs() < 3e-4, "moved {moved:?}");
        }
        assert!((r.top_speed() - 0.16).abs() < 0.01, "{}", r.top_speed());
    }

    /// A trapezoid ends where it should, at rest, within its duration, never above its pace.
    #[test]
    fn a_leg_is_a_trapezoid_along_its_polyline() {
        let a = [0.0; ARM_DOF];
        let mut b = a;
        b[0] = 0.5;
        let mut c = b;
        c[3] = -0.3;
        let leg = Leg::new(vec![a, b, c]);
        assert!((leg.length() - 0.8).abs() < 1e-12);
        let t_end = leg.duration();
        assert!((t_end - (0.8 / MAX_SPEED + MAX_SPEED / MAX_ACCELERATION)).abs() < 1e-9);
        let (end, v_end) = leg.at(t_end + 1.0);
        assert_eq!(end, c);
        assert_eq!(v_end, [0.0; ARM_DOF]);
        let mut t = 0.0;
        while t < t_end {
            let (_, v) = leg.at(t);
            assert!(v.iter().all(|s| s.abs() <= MAX_SPEED + 1e-12));
            t += 0.01;
        }
        let (mid, _) = leg.at(t_end / 2.0);
        assert!((mid[0] - 0.4).abs() < 1e-9 && mid[3] == 0.0, "{mid:?}");
    }

    /// In the environment, the arm follows a leg through six joints with the reference's
    /// actions alone: within 3 mrad of the path on the way (1 mrad measured), within 4 mrad at
    /// the end, in the leg's time plus two steps.
    #[test]
    fn the_arm_follows_a_leg_in_the_reference_action_space() {
        for robot in ["IIWA", "Jaco", "Gen3", "Panda"] {
            let task: TaskSpec = format!("{robot}/box/no_obstacle/pick_place")
                .parse()
                .unwrap();
            let mut env = Env::new(task, EnvConfig::default());
            env.reset(0).unwrap();
            let start = env.world().arm_positions();
            let mut end = start;
            for (j, d) in [0.3, -0.2, 0.25, 0.3, -0.4, 0.2, 0.6].iter().enumerate() {
                end[j] += d;
            }
            let mut tracker = Tracker::new(&env.config().physics, start);
            tracker.start(Leg::new(vec![start, end]));
            let planned = (tracker.leg().duration() / 0.05).ceil() as u32;
            let mut worst: f64 = 0.0;
            loop {
                let (q, v) = (env.world().arm_positions(), env.world().arm_velocities());
                if tracker.arrived(&q, &v) {
                    break;
                }
                let a = tracker.act(&q, &v);
                assert!(a.iter().all(|x| x.abs() <= 1.0));
                let mut action = [0.0; 8];
                action[..ARM_DOF].copy_from_slice(&a);
                action[7] = -1.0;
                env.step(&Action::Reference(action)).unwrap();
                let (q_ref, _) = tracker.leg().at(tracker.steps() as f64 * 0.05);
                worst = worst.max(joint_distance(&env.world().arm_positions(), &q_ref));
            }
            let q = env.world().arm_positions();
            eprintln!(
                "{robot}: worst {worst:.4} steps {} planned {planned} end {:.4}",
                tracker.steps(),
                joint_distance(&q, &end)
            );
            assert!(
                joint_distance(&q, &end) <= ARRIVED_POSITION,
                "{robot}: {q:?}"
            );
            assert!(worst < 0.003, "{robot}: {worst} rad off the path");
            assert!(
                tracker.steps() <= planned + 2,
                "{robot}: {} steps for a {planned}-step leg",
                tracker.steps()
            );
        }
    }
}
