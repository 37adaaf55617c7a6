//! Shelf: the object carried (a planned path) to in front of the shelf's opening, the gripper
//! pointing in, then slid straight in; where no slide keeps clear, a path planned all the way
//! in. Two ways in (heights and depths), tried in turn, then both again a little closer to the
//! arena.

use nalgebra::{Unit, UnitQuaternion, Vector3};

use super::lines::line;
use super::{LEAST_END_CLEARANCE, PlannedExpert, top_of};
use crate::arena::object_geometry;
use crate::axes::{Object, Objective};
use crate::env::Env;
use crate::expert::clearance::Clearance;
use crate::expert::motion::{pad_ik_solutions, pads_at};
use crate::expert::track::{Joints, Leg, joint_distance};
use crate::physics::RobotModel;

/// Where the object's origin waits in front of the shelf (y, m; its front is at 0.14).
const SHELF_FRONT_Y: f64 = 0.07;
/// A way into the shelf: the object's origin's height while it goes in, where it is slid to
/// (y, m), and the lanes (x, m) across the opening (x −0.1…0.3) it may go in along.
struct ShelfWay {
    z: f64,
    inside_y: f64,
    lanes: &'static [f64],
}

/// The ways into the shelf, tried in order. First mid-way in the 0.945…1.095 height band, the
/// gripper's housing clear of the top block (bottom 1.10), slid in to mid-depth of the 0.18…0.33
/// band (short of the back panel at 0.32). Where no first way keeps clear (the IIWA past the
/// goal wall: stretched to the shelf, its forearm crosses the wall's end at the wall's top),
/// higher and only just past the band's front, further out: 3 cm up lifts the forearm over the
/// wall, 5 cm less deep keeps the wrist's housing out from under the top block.
const SHELF_WAYS: [ShelfWay; 2] = [
    ShelfWay {
        z: 1.0,
        inside_y: 0.25,
        lanes: &[0.1, 0.17, 0.03, 0.24],
    },
    ShelfWay {
        z: 1.03,
        inside_y: 0.20,
        lanes: &[0.24, 0.28, 0.17],
    },
];
/// How close (m, a gap) the arm and the held object may come to the arena on the way into the
/// shelf where no way keeps [`LEAST_END_CLEARANCE`]: the held object's covering spheres are
/// rounder than it (the Gen3's dumbbell, held tilted, found its best slides at −6.6 mm). On the
/// 20 shelf tasks with the most failures, seeds 0–9: +3 episodes at −1 cm, +1 at −2 cm (past the
/// goal wall the closer first choices failed).
const SHELF_LAST_CLEARANCE: f64 = -0.01;
/// Turns (rad) of the gripper about the vertical in front of the shelf, tried with each lane.
const SHELF_YAWS: [f64; 3] = [0.0, 0.35, -0.35];
/// How far (rad) the gripper may still point down as it goes into the shelf: each 0.1 rad is
/// 0.1 rad less for the wrist to turn on the way (~13 control steps); the clearance model
/// decides how far its housing clears the top block.
const SHELF_PITCHES: [f64; 4] = [0.6, 0.4, 0.2, 0.0];
/// Turns (rad) of the gripper about the way it points into the shelf, for the dumbbell: held by
/// its bar between the discs, it is held the same way turned half a turn (upside down), and the
/// arm may reach that with less joint travel (from a grasp pointing back past the object wall's
/// end, the shortest turn to pointing into the shelf tips the gripper through the vertical).
/// The 16 dumbbell shelf tasks, seeds 0–9: 110 → 117 of 160 episodes (the Jaco's behind the
/// object wall 5 → 9, the Gen3's 3 → 6); with quarter turns as well 114, with quarter turns
/// instead 110 (the dumbbell lying in the pads); the plate, held by its rim, slips turned so
/// (its 16 tasks 125 → 108).
const DUMBBELL_SHELF_ROLLS: [f64; 2] = [0.0, std::f64::consts::PI];
/// How far (m) the object's bottom stays above the board (top 0.945) as it goes in, whatever
/// the way's height: the upright dumbbell reaches 5.2 cm below its origin.
const SHELF_BOARD_CLEARANCE: f64 = 0.015;

/// Ways into the shelf along one [`ShelfWay`], each nearest to the arm first (the largest joint
/// change to it, rad): the starts in front of the shelf with the straight slides in from them
/// that keep clear, and the poses with the object inside that keep clear (for a planned way in
/// where no slide does).
struct ShelfCandidates {
    slides: Vec<(f64, Joints, Vec<Joints>)>,
    insides: Vec<(f64, Joints)>,
}

impl PlannedExpert {
    /// Shelf: a free path, the object carried, to in front of the shelf's opening with the
    /// gripper turned to point into the shelf (+y; from a top grasp, which closes along x for
    /// this, a quarter turn about x), then straight in. Of the lanes across the opening and
    /// small turns about the vertical, the first the arm reaches clear of the arena, slide
    /// included; where none does, a path planned all the way in; each of the
    /// [`SHELF_WAYS`] in turn, then each again allowed [`SHELF_LAST_CLEARANCE`].
    pub(super) fn plan_shelf(&mut self, env: &Env, q: Joints) -> Option<Vec<Leg>> {
        let model = env.world().model;
        let carrying = self.carrying(env, &q);
        for (way, least) in SHELF_WAYS
            .iter()
            .map(|way| (way, LEAST_END_CLEARANCE))
            .chain(SHELF_WAYS.iter().map(|way| (way, SHELF_LAST_CLEARANCE)))
        {
            let ShelfCandidates { slides, insides } =
                self.shelf_options(model, &carrying, q, way, least);
            for (_, start, slide) in slides.into_iter().take(3) {
                if let Some(path) = self.plan_path(env, model, &carrying, q, start) {
                    return Some(vec![Leg::new(path), Leg::new(slide)]);
                }
            }
            // No straight way in keeps clear (past the goal wall the forearm would cross
            // it): a path planned all the way in.
            for (_, inside) in insides.into_iter().take(3) {
                if let Some(path) = self.plan_path(env, model, &carrying, q, inside) {
                    return Some(vec![Leg::new(path)]);
                }
            }
        }
        None
    }

    /// [`Self::plan_shelf`]'s candidates along `way` for the arm at `q` (the object carried as
    /// `carrying` says).
    fn shelf_options(
        &self,
        model: &RobotModel,
        carrying: &Clearance,
        q: Joints,
        way: &ShelfWay,
        least: f64,
    ) -> ShelfCandidates {
        let (_, orientation) = pads_at(model, &q);
        let insert_z = way.z.max(
            top_of(Objective::Shelf, "shelf/bottom") + SHELF_BOARD_CLEARANCE
                - object_geometry(self.task.object).bottom_offset,
        );
        let mut options: Vec<(f64, Joints, Vec<Joints>)> = Vec::new();
        let mut insides: Vec<(f64, Joints)> = Vec::new();
        let rolls: &[f64] = if self.task.object == Object::Dumbbell {
            &DUMBBELL_SHELF_ROLLS
        } else {
            &[0.0]
        };
        for (&lane, yaw, pitch, &roll) in way.lanes.iter().flat_map(|lane| {
            SHELF_YAWS.into_iter().flat_map(move |yaw| {
                SHELF_PITCHES
                    .into_iter()
                    .flat_map(move |pitch| rolls.iter().map(move |roll| (lane, yaw, pitch, roll)))
            })
        }) {
            // The gripper turned the shortest way from where it points now to pointing
            // into the shelf (+y turned by `yaw`), still `pitch` below level (for a top
            // grasp a turn about x), then by `roll` about where it points.
            let into_shelf = Vector3::new(
                -yaw.sin() * pitch.cos(),
                yaw.cos() * pitch.cos(),
                -pitch.sin(),
            );
            let Some(shortest) =
                UnitQuaternion::rotation_between(&(orientation * Vector3::z()), &into_shelf)
            else {
                continue;
            };
            let turn =
                UnitQuaternion::from_axis_angle(&Unit::new_normalize(into_shelf), roll) * shortest;
            let front = Vector3::new(lane, SHELF_FRONT_Y, insert_z);
            let inside = Vector3::new(lane, way.inside_y, insert_z);
            let (pad_front, pad_inside) = (front + turn * self.held, inside + turn * self.held);
            // A quarter turn of the wrist is too far for the IK seeded here alone.
            let mut starts = pad_ik_solutions(model, &q, pad_front, turn * orientation);
            starts.truncate(3);
            for start in starts {
                if !carrying.keeps(model, &start, least) {
                    continue;
                }
                let Some(slide) = line(model, start, pad_front, pad_inside, turn * orientation)
                else {
                    continue;
                };
                let end = *slide.last().expect("a point");
                if carrying.keeps(model, &end, least) {
                    insides.push((joint_distance(&q, &end), end));
                }
                if slide.iter().any(|c| !carrying.keeps(model, c, least)) {
                    continue;
                }
                options.push((joint_distance(&q, &start), start, slide));
            }
        }
        options.sort_by(|a, b| a.0.total_cmp(&b.0));
        insides.sort_by(|a, b| a.0.total_cmp(&b.0));
        ShelfCandidates {
            slides: options,
            insides,
        }
    }
}
