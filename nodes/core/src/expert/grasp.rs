//! Object-specific grasps: where the pads go, how the gripper is turned, and from which side
//! the pads come in.
//!
//! The gripper frame (`gripper_base`): +z is the approach axis (from the wrist towards the
//! fingertips), the fingers slide along ±y. [`gripper_orientation`] turns an approach and a
//! closing axis into the grip site's orientation, which the IK tracks.

use nalgebra::{Point3, Unit, UnitQuaternion, Vector3};

use crate::arena::object_geometry;
use crate::axes::{Object, Objective, Obstacle};
use crate::kinematics::{frame_from_axes, link_pose};
use crate::physics::{ARM_DOF, FINGER_OPEN, RobotModel, pad_gap};

use super::motion::reach_cost;

/// Gripper opening (m) while approaching and releasing: fully open, the pads' gap with the
/// fingers at their limit (0.0788; a larger command is clamped by the environment).
pub(super) fn open() -> f64 {
    pad_gap(FINGER_OPEN)
}
/// Gripper opening (m) commanded to grasp: the pads' gap with the fingers at their closed
/// limit (0.0141; the finger servos then squeeze the object with their force limit).
pub(super) fn closed(model: &RobotModel) -> f64 {
    let (closed, _) = model.joints[ARM_DOF]
        .limits
        .expect("finger joints are limited");
    pad_gap(closed)
}

/// The dumbbell's side grasp: the approach axis leans this far below horizontal (rad), so the
/// wrist behind the gripper stays above bin 1's floor and rims while the gripper base still
/// fits between the discs (gap 8.3 cm, base Ø 5.8 cm).
const DUMBBELL_PITCH: f64 = 0.5;
/// Pads' centre below the dumbbell's origin (m): the middle of the bar between the discs is
/// the origin; a little lower keeps the pitched gripper base clear of the upper disc.
const DUMBBELL_PAD_BELOW_ORIGIN: f64 = 0.02;
/// The dumbbell's steeper side grasp ([`Headings::AroundSteep`], the last choice: behind the
/// object wall or the door the wrist must come down from above it): pitch (rad) and pads'
/// centre below the origin (m). With the pads 2.5 cm down the gripper base (Ø 5.8 cm, 6 cm
/// behind the pads) keeps ~4 mm under the upper disc at 0.6 rad. On the dumbbell behind the
/// object wall and the door (seeds 0-1) 0.6 and 0.65 rad did best: 35 of 64 episodes against
/// 31 without this choice (0.7 rad: 33; 0.8 with the pads 3.5 cm down: 31).
const DUMBBELL_STEEP_PITCH: f64 = 0.6;
const DUMBBELL_STEEP_PAD_BELOW_ORIGIN: f64 = 0.025;

/// The plate's rim grasp: the approach axis leans this far below horizontal (rad) so the
/// gripper base (a Ø 5.8 cm × 10 cm cylinder along the closing axis, 6 cm behind the pads)
/// clears bin 1's floor while the pads sit at the disc's height.
const PLATE_PITCH: f64 = 0.38;
/// The plate's steeper rim grasp ([`PlatePitch::Steep`]): the approach axis this far below
/// horizontal (rad). The wrist turns less from pointing down to reach it, and behind the door
/// the Panda reaches it without turning its forearm half round (0.4 rad of joint travel
/// against 2.5). The pads then grip the disc by its edges only, and the plate slips when the
/// gripper turns a lot with it held (into the shelf) — see `PlannedExpert::plate_pitch`.
/// Beyond ~0.62 rad the lower fingertip, lower by sin(pitch) × its length, meets the floor
/// unless the pads aim higher (`PLATE_STEEP_GRASP_RAISE` in `planned/approach.rs`).
const PLATE_STEEP_PITCH: f64 = 0.65;
/// The plate's rim grasp: roll about the approach axis (rad). The disc is 1.40 cm thick and
/// the pads close to 1.41 cm at most, so square-on pads never squeeze it; rolled, the pads'
/// edges bite the disc's faces across a wider span ((t + w·sin β)/cos β ≈ 1.5 cm).
const PLATE_ROLL: f64 = 0.14;
/// How far inside the plate's rim the pads' centre goes (m); the pads are 3.3 cm long.
const PLATE_PAD_INSIDE_RIM: f64 = 0.012;
/// Height of the plate's disc centre above the plate's origin (m, docs/src/reference-facts.md §3).
const PLATE_DISC_Z: f64 = 0.02;
/// Opening (m) while the pads slide over and under the plate's rim: the lower finger must stay
/// above bin 1's floor, 3.3 cm below the disc.
const PLATE_OPEN: f64 = 0.044;

/// Horizontal distance (m) from the hollow box's origin to the middle of a wall
/// (docs/src/reference-facts.md §3: walls 1.6 cm thick centred at ±0.03).
const HOLLOW_BOX_WALL_OFFSET: f64 = 0.03;
/// Height (m) of the pads' centre above the hollow box's origin: the pads (3.3 cm long)
/// cover the wall's upper part (walls reach z 0.06), the fingertips stay above the base.
const HOLLOW_BOX_PAD_Z: f64 = 0.035;
/// How far above its centre (m) the pads take the box where walls pass under the wrist
/// ([`walls_under_the_wrist`]): the pads (3.3 cm long) stay within the box's 6 cm height and the
/// wrist and forearm ride 1 cm higher. Pushed past the goal wall, the Jaco's forearm otherwise
/// runs 1.9 cm into the wall's free end on every lane. Only there: into the shelf past the goal
/// wall the higher grasp does worse (docs/src/expert.md, "How the expert's settings were
/// chosen").
const BOX_RAISED_GRASP: f64 = 0.01;

/// Where the pads go and how they get there.
#[derive(Debug, Clone, Copy)]
pub(super) struct Grasp {
    /// Grip-site orientation at the grasp.
    pub orientation: UnitQuaternion<f64>,
    /// Pads' centre at the grasp (world, m).
    pub pad: Vector3<f64>,
    /// Unit direction the pads move along over the last stretch into the grasp.
    pub approach: Vector3<f64>,
    /// Length of that last stretch (m): the pre-grasp is this far back along `approach`.
    pub backoff: f64,
    /// Gripper opening (m) during the approach.
    pub open: f64,
    /// Whether the gripper points down (top grasp) rather than sideways.
    pub top_down: bool,
}

impl Grasp {
    /// The pre-grasp pads' centre.
    pub fn pre(&self) -> Vector3<f64> {
        self.pad - self.approach * self.backoff
    }
}

/// What the grasp planner may look at.
pub(super) struct GraspInput<'a> {
    pub model: &'a RobotModel,
    pub q: [f64; ARM_DOF],
    pub object: Object,
    pub objective: Objective,
    pub obstacle: Obstacle,
    pub position: Point3<f64>,
    pub rotation: UnitQuaternion<f64>,
    /// Lean of a top-down approach towards the robot (rad; 0 = vertical).
    pub tilt: f64,
    /// Which way side grasps should point.
    pub headings: Headings,
    /// How steeply the plate's rim grasp points down.
    pub plate_pitch: PlatePitch,
}

/// The grasps of the object in `input`, the planner's preferred one first.
pub(super) fn grasp_candidates(input: &GraspInput) -> Vec<Grasp> {
    match input.object {
        Object::Box => vec![top_grasp(input)],
        Object::HollowBox => {
            // By the wall on the robot's side, else by the opposite one.
            let near = top_grasp(input);
            let far = Grasp {
                pad: near.pad + 2.0 * (input.position.coords - near.pad).xy().push(0.0),
                ..near
            };
            vec![near, far]
        }
        Object::Dumbbell => side_grasps(input.headings, |h| {
            let steep = input.headings == Headings::AroundSteep;
            dumbbell_grasps_towards(input.position, h, steep)
        }),
        Object::Plate => side_grasps(input.headings, |h| {
            plate_grasps_towards(input.position, h, input.plate_pitch)
        }),
    }
}

/// How far below horizontal the plate's rim grasp points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PlatePitch {
    /// [`PLATE_PITCH`]: the scripted expert's, and the planned expert's where the held plate
    /// turns in the hand.
    Level,
    /// [`PLATE_STEEP_PITCH`].
    Steep,
}

impl PlatePitch {
    /// The approach axis's angle below horizontal (rad).
    pub(super) fn angle(self) -> f64 {
        match self {
            PlatePitch::Level => PLATE_PITCH,
            PlatePitch::Steep => PLATE_STEEP_PITCH,
        }
    }
}

/// Which way side grasps should point, in the planner's order of preference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Headings {
    /// +y first (towards bin 2, so the object goes into the shelf without turning), then
    /// turning towards +x (away from the robot), which arms with a shorter reach need for
    /// objects on bin 1's far side.
    TowardsBin2,
    /// For grasping a set-down object again (just past the goal wall's free end): the wrist
    /// towards the robot and +y (+x−y first), so carrying the
    /// object on to the goal keeps the wrist off the wall. The carry's clearance decides
    /// among them.
    Regrasp,
    /// Every [`AROUND_HEADINGS`]th of a turn from +x, those of [`Headings::TowardsBin2`]
    /// left out: the planned expert's second choice where none of those has a free path
    /// (behind the object wall the gripper may point back past the wall's end).
    Around,
    /// Every heading of [`Headings::Around`] and [`Headings::TowardsBin2`], the dumbbell's
    /// approach pitched steeper: the planned expert's last choice for the dumbbell.
    AroundSteep,
}

/// The headings [`Headings::Around`] tries (every 15°).
const AROUND_HEADINGS: usize = 24;

impl Headings {
    /// The horizontal directions a side grasp may point in, best first.
    fn directions(self) -> Vec<Vector3<f64>> {
        let d = std::f64::consts::FRAC_1_SQRT_2;
        match self {
            Headings::TowardsBin2 => vec![
                Vector3::y(),
                Vector3::new(d, d, 0.0),
                Vector3::x(),
                Vector3::new(d, -d, 0.0),
            ],
            Headings::Around => {
                let first = Headings::TowardsBin2.directions();
                (0..AROUND_HEADINGS)
                    .map(|k| {
                        let a = k as f64 * std::f64::consts::TAU / AROUND_HEADINGS as f64;
                        Vector3::new(a.cos(), a.sin(), 0.0)
                    })
                    .filter(|h| first.iter().all(|f| (f - h).norm() > 1e-6))
                    .collect()
            }
            Headings::AroundSteep => {
                let mut all = Headings::TowardsBin2.directions();
                all.extend(Headings::Around.directions());
                all
            }
            Headings::Regrasp => vec![
                Vector3::new(d, -d, 0.0),
                -Vector3::y(),
                Vector3::x(),
                Vector3::new(d, d, 0.0),
            ],
        }
    }
}

/// The grasps each heading allows, best heading first.
fn side_grasps(headings: Headings, grasps_at: impl Fn(Vector3<f64>) -> Vec<Grasp>) -> Vec<Grasp> {
    headings
        .directions()
        .into_iter()
        .flat_map(grasps_at)
        .collect()
}

/// The dumbbell by its bar, from the side: the approach axis leaning down, the fingers
/// closing horizontally across the bar between the discs; pointing along `h`, both ways round.
fn dumbbell_grasps_towards(position: Point3<f64>, h: Vector3<f64>, steep: bool) -> Vec<Grasp> {
    let (pitch, below) = if steep {
        (DUMBBELL_STEEP_PITCH, DUMBBELL_STEEP_PAD_BELOW_ORIGIN)
    } else {
        (DUMBBELL_PITCH, DUMBBELL_PAD_BELOW_ORIGIN)
    };
    let approach = (h * pitch.cos() - Vector3::z() * pitch.sin()).normalize();
    let across = h.cross(&Vector3::z()).normalize();
    let pad = position.coords - Vector3::z() * below;
    [across, -across]
        .map(|closing| Grasp {
            orientation: gripper_orientation(approach, closing),
            pad,
            // Slide in level, between the discs.
            approach: h,
            backoff: 0.08,
            open: open(),
            top_down: false,
        })
        .to_vec()
}

/// The plate by its rim, from the side: the fingers close (nearly) vertically on the disc;
/// pointing along `h` and leaning down by `pitch`, both ways round, rolled either way.
fn plate_grasps_towards(position: Point3<f64>, h: Vector3<f64>, pitch: PlatePitch) -> Vec<Grasp> {
    let (pitch, roll) = (pitch.angle(), PLATE_ROLL);
    let approach = (h * pitch.cos() - Vector3::z() * pitch.sin()).normalize();
    let up = (h * pitch.sin() + Vector3::z() * pitch.cos()).normalize();
    let axis = Unit::new_normalize(approach);
    let radius = object_geometry(Object::Plate).horizontal_radius;
    let pad = position.coords - h * (radius - PLATE_PAD_INSIDE_RIM) + Vector3::z() * PLATE_DISC_Z;
    [roll, -roll]
        .into_iter()
        .flat_map(|roll| {
            let c = UnitQuaternion::from_axis_angle(&axis, roll) * up;
            [c, -c]
        })
        .map(|closing| Grasp {
            orientation: gripper_orientation(approach, closing),
            pad,
            // Slide in level: the lower finger stays between the floor and the disc.
            approach: h,
            backoff: 0.07,
            open: PLATE_OPEN,
            top_down: false,
        })
        .collect()
}

/// The box (and, for now, the hollow box) from the top, centred on the object.
fn top_grasp(input: &GraspInput) -> Grasp {
    let GraspInput { model, q, .. } = input;
    let o = input.position;
    let orientation = if input.objective == Objective::Shelf {
        // Close along x (the box later turns about it); of the two signs take the one the IK
        // reaches over the object, moving the joints least.
        let over = Vector3::new(o.x, o.y, o.z + 0.12);
        [Vector3::x(), -Vector3::x()]
            .map(|axis| top_orientation(model, q, &input.rotation, input.tilt, Some(axis)))
            .into_iter()
            .map(|r| (r, reach_cost(model, q, over, r)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(r, _)| r)
            .expect("two candidates")
    } else {
        top_orientation(model, q, &input.rotation, input.tilt, None)
    };
    let pad = match input.object {
        Object::HollowBox => hollow_box_edge(o, &orientation),
        _ if walls_under_the_wrist(input.obstacle, input.objective) => {
            o.coords + Vector3::z() * BOX_RAISED_GRASP
        }
        _ => o.coords,
    };
    Grasp {
        orientation,
        pad,
        approach: -Vector3::z(),
        backoff: 0.12,
        open: open(),
        top_down: true,
    }
}

/// Whether the wrist and forearm of a top grasp pass just over a wall's top on the way: the
/// object wall or door between the robot and the object, or the goal wall's free end on a push
/// past it (carried at most 5 cm off the floor). Not into the shelf past the goal wall, where
/// the box is lifted well over the wall and a higher grasp did worse.
fn walls_under_the_wrist(obstacle: Obstacle, objective: Objective) -> bool {
    match obstacle {
        Obstacle::ObjectWall | Obstacle::ObjectDoor => true,
        Obstacle::GoalWall => objective == Objective::Push,
        Obstacle::NoObstacle => false,
    }
}

/// The hollow box by one wall, from the top: the pads straddle the middle of the wall that
/// crosses the closing axis (the inner finger in the cavity), on the robot's side.
fn hollow_box_edge(o: Point3<f64>, orientation: &UnitQuaternion<f64>) -> Vector3<f64> {
    // The grip site's y axis is the gripper frame's x; the fingers close along the gripper
    // frame's y, which is the grip site's −x turned back: take the horizontal closing axis.
    let closing = gripper_closing_axis(orientation);
    let towards_robot = if closing.x > 1e-6 || (closing.x.abs() <= 1e-6 && closing.y > 0.0) {
        -closing
    } else {
        closing
    };
    o.coords + towards_robot * HOLLOW_BOX_WALL_OFFSET + Vector3::z() * HOLLOW_BOX_PAD_Z
}

/// The horizontal axis the fingers close along for the grip-site `orientation` (unit, z 0).
pub(super) fn gripper_closing_axis(orientation: &UnitQuaternion<f64>) -> Vector3<f64> {
    let gripper =
        orientation * UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
    let mut c = gripper * Vector3::y();
    c.z = 0.0;
    c.normalize()
}

/// The grip site's orientation for a gripper whose approach axis is `approach` and whose
/// fingers close along `closing` (the grip site is the gripper frame turned −90° about z).
pub(super) fn gripper_orientation(
    approach: Vector3<f64>,
    closing: Vector3<f64>,
) -> UnitQuaternion<f64> {
    frame_from_axes(approach, closing)
        * UnitQuaternion::from_euler_angles(0.0, 0.0, -std::f64::consts::FRAC_PI_2)
}

/// The grip-site orientation that points the gripper straight down with the fingers closing
/// along whichever horizontal axis of the object is nearest their current closing direction.
///
/// With `tilt` ≠ 0 (rad) the fingers close along the object axis nearest world y and the
/// approach axis leans towards the robot (−x) by `tilt`, so the wrist and forearm stay high
/// and far from walls standing between the robot and the grasp.
fn top_orientation(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    object_rotation: &UnitQuaternion<f64>,
    tilt: f64,
    close_along: Option<Vector3<f64>>,
) -> UnitQuaternion<f64> {
    let gripper = link_pose(model, q, "gripper_base").expect("gripper base link");
    let mut heading = gripper.rotation * Vector3::y();
    heading.z = 0.0;
    if let Some(axis) = close_along {
        heading = axis;
    } else if tilt != 0.0 {
        heading = Vector3::y() * heading.y.signum();
    }
    let candidates = [
        object_rotation * Vector3::x(),
        object_rotation * Vector3::y(),
    ];
    let mut best = heading;
    let mut best_dot = -1.0;
    for c in candidates {
        let mut c = c;
        c.z = 0.0;
        if c.norm() < 1e-6 {
            continue;
        }
        let c = c.normalize();
        for c in [c, -c] {
            let d = c.dot(&heading);
            if d > best_dot {
                best_dot = d;
                best = c;
            }
        }
    }
    let approach = if tilt != 0.0 {
        // Perpendicular to the closing axis, leaning towards −x.
        let along = best.cross(&Vector3::z()).normalize();
        let along = if along.x > 0.0 { -along } else { along };
        (along * tilt.sin() - Vector3::z() * tilt.cos()).normalize()
    } else {
        -Vector3::z()
    };
    gripper_orientation(approach, best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::Primitive;
    use crate::axes::Robot;
    use crate::physics::robot_model;

    /// The box is taken 1 cm above its centre where a wall passes under the wrist, at its
    /// centre elsewhere; the pads (3.3 cm long) stay within its 6 cm height either way.
    #[test]
    fn the_box_is_taken_higher_where_walls_pass_under_the_wrist() {
        let robot = Robot::Jaco;
        let position = Point3::new(0.15, -0.25, 0.85);
        let pad_z = |obstacle, objective| {
            let input = GraspInput {
                model: robot_model(robot),
                q: robot.init_qpos(),
                object: Object::Box,
                objective,
                obstacle,
                position,
                rotation: UnitQuaternion::identity(),
                tilt: 0.0,
                headings: Headings::TowardsBin2,
                plate_pitch: PlatePitch::Level,
            };
            let grasps = grasp_candidates(&input);
            assert_eq!(grasps.len(), 1);
            assert!(grasps[0].top_down);
            grasps[0].pad.z - position.z
        };
        let raised = [
            (Obstacle::GoalWall, Objective::Push),
            (Obstacle::ObjectWall, Objective::PickPlace),
            (Obstacle::ObjectDoor, Objective::Shelf),
        ];
        for (obstacle, objective) in raised {
            let dz = pad_z(obstacle, objective);
            assert!(
                (dz - BOX_RAISED_GRASP).abs() < 1e-12,
                "{obstacle:?} {objective:?}: {dz}"
            );
        }
        for (obstacle, objective) in [
            (Obstacle::NoObstacle, Objective::Push),
            (Obstacle::GoalWall, Objective::Shelf),
            (Obstacle::GoalWall, Objective::PickPlace),
        ] {
            assert_eq!(
                pad_z(obstacle, objective),
                0.0,
                "{obstacle:?} {objective:?}"
            );
        }
        // The pads' 3.3 cm span around the raised centre stays inside the box's 6 cm height.
        let half_height = -object_geometry(Object::Box).bottom_offset;
        assert!(BOX_RAISED_GRASP + 0.033 / 2.0 <= half_height);
    }

    /// Both dumbbell side grasps fit between the discs on every heading: the gripper base (a
    /// Ø 5.8 cm cylinder along the closing axis, 6 cm behind the pads) keeps under the upper
    /// disc and the pads' centre over the lower one; the steeper grasp comes down steeper.
    #[test]
    fn the_dumbbell_grasps_fit_between_the_discs() {
        let (base_radius, base_behind) = (0.029, 0.06);
        let parts = object_geometry(Object::Dumbbell).parts;
        let disc = |name: &str| {
            let part = parts.iter().find(|p| p.name == name).expect(name);
            let Primitive::Cylinder {
                radius,
                half_length,
            } = part.shape
            else {
                panic!("{name} is a cylinder");
            };
            (radius, part.offset[2], half_length)
        };
        let (radius, upper_z, half) = disc("object/disc_z+");
        let (_, lower_z, _) = disc("object/disc_z-");
        let position = Point3::new(0.15, -0.25, 0.87);
        let mut pitches = Vec::new();
        for steep in [false, true] {
            for h in Headings::AroundSteep.directions() {
                for grasp in dumbbell_grasps_towards(position, h, steep) {
                    let approach = grasp.orientation * Vector3::z();
                    pitches.push((steep, -approach.z.asin()));
                    // The base's centre relative to the dumbbell's axis: out along -h, and up.
                    let base = grasp.pad - approach * base_behind - position.coords;
                    let out = base.xy().norm();
                    // The base's cross-section (a circle in the vertical plane of the approach)
                    // against the upper disc's underside, where the two overlap in reach.
                    if out < radius + base_radius {
                        let dx = (out - radius).max(0.0);
                        let dz = (upper_z - half - base.z).max(0.0);
                        assert!(
                            (dx * dx + dz * dz).sqrt() > base_radius + 0.003,
                            "steep {steep}, heading {h:?}: base at {base:?}"
                        );
                    }
                    let pad_z = grasp.pad.z - position.z;
                    assert!(
                        pad_z > lower_z + half + 0.01,
                        "steep {steep}: pads at {pad_z}"
                    );
                }
            }
        }
        let steepest = |steep: bool| {
            pitches
                .iter()
                .filter(|p| p.0 == steep)
                .map(|p| p.1)
                .fold(f64::NAN, f64::max)
        };
        assert!(steepest(true) > steepest(false) + 0.05);
    }

    /// The plate's rim grasps at either pitch: the gripper points along the heading, leaning
    /// down by the pitch, the pads 1.2 cm inside the rim at the disc's height, the fingers
    /// closing across the disc — square to the approach, within the roll of the approach's
    /// vertical plane — both ways round and rolled either way.
    #[test]
    fn the_plate_rim_grasps_lean_by_their_pitch() {
        let position = Point3::new(0.15, -0.25, 0.84);
        let radius = object_geometry(Object::Plate).horizontal_radius;
        for pitch in [PlatePitch::Level, PlatePitch::Steep] {
            for h in Headings::AroundSteep.directions() {
                let grasps = plate_grasps_towards(position, h, pitch);
                assert_eq!(grasps.len(), 4);
                for grasp in &grasps {
                    let approach = grasp.orientation * Vector3::z();
                    // The grip site's frame is the gripper's turned a quarter about z.
                    let closing = grasp.orientation
                        * UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2)
                        * Vector3::y();
                    assert!(
                        (-approach.z.asin() - pitch.angle()).abs() < 1e-9,
                        "{pitch:?}"
                    );
                    assert!((approach.xy().normalize() - h.xy()).norm() < 1e-9);
                    assert!(approach.dot(&closing).abs() < 1e-9);
                    // Out of the approach's vertical plane by the roll, no more.
                    let out_of_plane = closing.dot(&h.cross(&Vector3::z())).abs();
                    assert!(
                        (out_of_plane - PLATE_ROLL.sin()).abs() < 1e-9,
                        "{out_of_plane}"
                    );
                    let inside = (position.coords - grasp.pad).xy().dot(&h.xy());
                    assert!((inside - (radius - PLATE_PAD_INSIDE_RIM)).abs() < 1e-9);
                    assert!((grasp.pad.z - position.z - PLATE_DISC_Z).abs() < 1e-12);
                    assert_eq!(grasp.approach, h);
                }
            }
        }
        assert!(PlatePitch::Steep.angle() > PlatePitch::Level.angle() + 0.2);
    }

    /// The second choice of headings goes all round, every 15°, without the first choice's.
    #[test]
    fn the_headings_all_round_leave_out_the_first_choice() {
        let first = Headings::TowardsBin2.directions();
        let around = Headings::Around.directions();
        assert_eq!(around.len(), AROUND_HEADINGS - first.len());
        for h in &around {
            assert!((h.norm() - 1.0).abs() < 1e-12 && h.z == 0.0);
            assert!(first.iter().all(|f| (f - h).norm() > 1e-6), "{h:?}");
            let degrees = h.y.atan2(h.x).to_degrees();
            assert!((degrees / 15.0 - (degrees / 15.0).round()).abs() < 1e-9);
        }
    }
}
