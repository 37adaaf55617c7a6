//! Interpolation between two trajectory points, as joint_trajectory_controller's "splines"
//! method does it: linear when either point has positions only, cubic when both have
//! velocities, quintic when both also have accelerations. Times are integer nanoseconds, so a
//! sample at a point's own time returns that point's values exactly (bit for bit).

/// One joint's state at one time: position, and optionally velocity and acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knot {
    /// Time, ns from the trajectory's start.
    pub time_ns: i64,
    /// Position (rad or m).
    pub position: f64,
    /// Velocity, if given.
    pub velocity: Option<f64>,
    /// Acceleration, if given.
    pub acceleration: Option<f64>,
}

/// Position, velocity and acceleration of one joint at one time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointSample {
    /// Position.
    pub position: f64,
    /// Velocity.
    pub velocity: f64,
    /// Acceleration.
    pub acceleration: f64,
}

/// The state at `t_ns` between knots `a` and `b` (`a.time_ns <= t_ns <= b.time_ns`).
pub fn interpolate(a: &Knot, b: &Knot, t_ns: i64) -> JointSample {
    if t_ns >= b.time_ns {
        return at_knot(b);
    }
    if t_ns <= a.time_ns {
        return at_knot(a);
    }
    let duration = (b.time_ns - a.time_ns) as f64 * 1e-9;
    let t = (t_ns - a.time_ns) as f64 * 1e-9;
    match (
        a.velocity.zip(b.velocity),
        a.acceleration.zip(b.acceleration),
    ) {
        (Some((v0, v1)), Some((a0, a1))) => {
            quintic(a.position, v0, a0, b.position, v1, a1, duration, t)
        }
        (Some((v0, v1)), None) => cubic(a.position, v0, b.position, v1, duration, t),
        _ => {
            let rate = (b.position - a.position) / duration;
            JointSample {
                position: a.position + rate * t,
                velocity: rate,
                acceleration: 0.0,
            }
        }
    }
}

fn at_knot(k: &Knot) -> JointSample {
    JointSample {
        position: k.position,
        velocity: k.velocity.unwrap_or(0.0),
        acceleration: k.acceleration.unwrap_or(0.0),
    }
}

/// The cubic with the given end positions and velocities over `duration`, at `t`.
fn cubic(p0: f64, v0: f64, p1: f64, v1: f64, duration: f64, t: f64) -> JointSample {
    let d = duration;
    let c2 = (3.0 * (p1 - p0) - (2.0 * v0 + v1) * d) / (d * d);
    let c3 = (2.0 * (p0 - p1) + (v0 + v1) * d) / (d * d * d);
    JointSample {
        position: p0 + v0 * t + c2 * t * t + c3 * t * t * t,
        velocity: v0 + 2.0 * c2 * t + 3.0 * c3 * t * t,
        acceleration: 2.0 * c2 + 6.0 * c3 * t,
    }
}

/// The quintic with the given end positions, velocities and accelerations over `duration`,
/// at `t`.
#[allow(clippy::too_many_arguments)] // two full end states and the time: the formula's inputs
fn quintic(
    p0: f64,
    v0: f64,
    a0: f64,
    p1: f64,
    v1: f64,
    a1: f64,
    duration: f64,
    t: f64,
) -> JointSample {
    let d = duration;
    let (d2, d3) = (d * d, d * d * d);
    let (d4, d5) = (d3 * d, d3 * d2);
    let c3 = (20.0 * (p1 - p0) - (8.0 * v1 + 12.0 * v0) * d - (3.0 * a0 - a1) * d2) / (2.0 * d3);
    let c4 =
        (30.0 * (p0 - p1) + (14.0 * v1 + 16.0 * v0) * d + (3.0 * a0 - 2.0 * a1) * d2) / (2.0 * d4);
    let c5 = (12.0 * (p1 - p0) - 6.0 * (v1 + v0) * d - (a0 - a1) * d2) / (2.0 * d5);
    let (t2, t3) = (t * t, t * t * t);
    JointSample {
        position: p0 + v0 * t + 0.5 * a0 * t2 + c3 * t3 + c4 * t3 * t + c5 * t3 * t2,
        velocity: v0 + a0 * t + 3.0 * c3 * t2 + 4.0 * c4 * t3 + 5.0 * c5 * t3 * t,
        acceleration: a0 + 6.0 * c3 * t + 12.0 * c4 * t2 + 20.0 * c5 * t3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knot(time_ns: i64, position: f64, velocity: Option<f64>, acceleration: Option<f64>) -> Knot {
        Knot {
            time_ns,
            position,
            velocity,
            acceleration,
        }
    }

    #[test]
    fn linear_without_velocities_and_exact_at_knots() {
        let a = knot(0, 0.1, None, None);
        let b = knot(50_000_000, 0.3, Some(1.0), None);
        let mid = interpolate(&a, &b, 25_000_000);
        assert!((mid.position - 0.2).abs() < 1e-15);
        assert!((mid.velocity - 4.0).abs() < 1e-12);
        // At a knot: the knot's own value, bit for bit (0.1 + (0.3 − 0.1) would round).
        assert_eq!(
            interpolate(&a, &b, 50_000_000).position.to_bits(),
            0.3f64.to_bits()
        );
        assert_eq!(interpolate(&a, &b, 0).position.to_bits(), 0.1f64.to_bits());
    }

    #[test]
    fn cubic_and_quintic_meet_their_end_conditions() {
        let a = knot(0, -0.2, Some(0.5), Some(1.0));
        let b = knot(2_000_000_000, 0.7, Some(-0.3), Some(-2.0));
        let eps = 1e-9;
        for (a, b, check_acceleration) in [
            (
                knot(0, -0.2, Some(0.5), None),
                knot(2_000_000_000, 0.7, Some(-0.3), None),
                false,
            ),
            (a, b, true),
        ] {
            let near_start = interpolate(&a, &b, 1);
            let near_end = interpolate(&a, &b, b.time_ns - 1);
            assert!((near_start.position - a.position).abs() < eps);
            assert!((near_start.velocity - a.velocity.unwrap()).abs() < 1e-6);
            assert!((near_end.position - b.position).abs() < eps);
            assert!((near_end.velocity - b.velocity.unwrap()).abs() < 1e-6);
            if check_acceleration {
                assert!((near_start.acceleration - 1.0).abs() < 1e-6);
                assert!((near_end.acceleration + 2.0).abs() < 1e-6);
            }
            // Velocity is the derivative of position (central difference at 0.7 s).
            let (t, h) = (700_000_000, 1_000_000);
            let slope = (interpolate(&a, &b, t + h).position - interpolate(&a, &b, t - h).position)
                / (2.0 * h as f64 * 1e-9);
            assert!((slope - interpolate(&a, &b, t).velocity).abs() < 1e-5);
        }
    }
}
