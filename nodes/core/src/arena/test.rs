//! The arena tables against the reference's scene (its arena, obstacle and object code and its
//! compiled model; `docs/src/reference-sources.md`): every world-frame number is pinned here.

use std::collections::BTreeSet;

use nalgebra::{Isometry3, Vector3};

use super::*;
use crate::axes::AxisElement;

/// Tolerance for numbers docs/src/reference-facts.md gives to the millimetre or better.
const EPS: f64 = 1e-9;

fn find<'a>(parts: &'a [Placed], name: &str) -> &'a Placed {
    parts
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no part {name:?} in {:?}", names(parts)))
}

fn names(parts: &[Placed]) -> Vec<&'static str> {
    parts.iter().map(|p| p.name).collect()
}

/// Asserts a part's world extent along `axis` (0 = x, 1 = y, 2 = z).
#[track_caller]
fn assert_span(part: &Placed, axis: usize, expected: [f64; 2]) {
    let (min, max) = part.aabb();
    let got = [min[axis], max[axis]];
    assert!(
        (got[0] - expected[0]).abs() < EPS && (got[1] - expected[1]).abs() < EPS,
        "{} along {}: got {got:?}, want {expected:?}",
        part.name,
        ["x", "y", "z"][axis],
    );
}

#[track_caller]
fn assert_close(got: f64, want: f64, tolerance: f64, what: &str) {
    assert!(
        (got - want).abs() <= tolerance,
        "{what}: got {got}, want {want} ± {tolerance}"
    );
}

fn centre(part: &Placed) -> Vector3<f64> {
    part.pose.translation.vector
}

const X: usize = 0;
const Y: usize = 1;
const Z: usize = 2;

#[test]
fn rows_belong_to_their_elements() {
    for objective in Objective::all() {
        assert_eq!(objective_arena(objective).objective, objective);
    }
    for obstacle in Obstacle::all() {
        assert_eq!(obstacle_geometry(obstacle).obstacle, obstacle);
    }
    for object in Object::all() {
        assert_eq!(object_geometry(object).object, object);
    }
}

/// docs/src/reference-facts.md §2.1: bin 1 is the same in every arena; Push lacks the rim facing
/// bin 2.
#[test]
fn bin1_floor_and_rims() {
    for objective in Objective::all() {
        let parts = arena_parts(objective, Obstacle::NoObstacle);
        let floor = find(&parts, "bin1/floor");
        assert_span(floor, X, [-0.1, 0.3]);
        assert_span(floor, Y, [-0.51, -0.01]);
        assert_span(floor, Z, [0.78, 0.82]);
        for rim in ["bin1/rim_y-", "bin1/rim_x-", "bin1/rim_x+"] {
            assert_span(find(&parts, rim), Z, [0.82, 0.84]);
        }
        assert_span(find(&parts, "bin1/rim_y-"), Y, [-0.52, -0.50]);
        assert_span(find(&parts, "bin1/rim_y-"), X, [-0.11, 0.31]);
        assert_span(find(&parts, "bin1/rim_x-"), X, [-0.11, -0.09]);
        assert_span(find(&parts, "bin1/rim_x+"), X, [0.29, 0.31]);
        assert_span(find(&parts, "bin1/rim_x+"), Y, [-0.51, -0.01]);
        let facing_bin2 = parts.iter().find(|p| p.name == "bin1/rim_y+");
        if objective == Objective::Push {
            assert!(
                facing_bin2.is_none(),
                "the Push arena has no rim at y = −0.01"
            );
        } else {
            let rim = facing_bin2.expect("bin 1 has its +y rim");
            assert_span(rim, Y, [-0.02, 0.0]);
            assert_span(rim, Z, [0.82, 0.84]);
        }
    }
    assert_eq!(BIN1_POSITION, [0.1, -0.26, 0.8]);
    assert_eq!(BIN1_FLOOR_HALF, [0.2, 0.25, 0.02]);
}

/// docs/src/reference-facts.md §2.1: bin 2 at y 0.18 (PickPlace included, despite its class
/// default) or 0.13 for Push, whose wall facing bin 1 is absent and whose floor overlaps bin 1's by
/// 3.5 cm.
#[test]
fn bin2_floor_and_walls() {
    for objective in Objective::all() {
        let parts = arena_parts(objective, Obstacle::NoObstacle);
        let floor = find(&parts, "bin2/floor");
        let y = if objective == Objective::Push {
            0.13
        } else {
            0.18
        };
        assert_eq!(bin2_position(objective).coords, Vector3::new(0.1, y, 0.8));
        assert_span(floor, X, [-0.1, 0.3]);
        assert_span(floor, Y, [y - 0.175, y + 0.175]);
        assert_span(floor, Z, [0.78, 0.82]);
        for wall in ["bin2/wall_y+", "bin2/wall_x-", "bin2/wall_x+"] {
            assert_span(find(&parts, wall), Z, [0.80, 0.90]);
        }
        assert_span(find(&parts, "bin2/wall_y+"), Y, [y + 0.165, y + 0.185]);
        assert_span(find(&parts, "bin2/wall_x-"), X, [-0.11, -0.09]);
        assert_span(find(&parts, "bin2/wall_x+"), Y, [y - 0.175, y + 0.175]);
        let facing_bin1 = parts.iter().find(|p| p.name == "bin2/wall_y-");
        if objective == Objective::Push {
            assert!(
                facing_bin1.is_none(),
                "the Push arena has no wall between the bins"
            );
            assert_span(floor, Y, [-0.045, 0.305]);
            let overlap = find(&parts, "bin1/floor").aabb().1.y - floor.aabb().0.y;
            assert_close(overlap, 0.035, EPS, "Push floor overlap");
        } else {
            assert_span(floor, Y, [0.005, 0.355]);
            let wall = facing_bin1.expect("bin 2 has its −y wall");
            assert_span(wall, X, [-0.11, 0.31]);
            assert_span(wall, Z, [0.80, 0.90]);
        }
    }
    assert_eq!(BIN2_FLOOR_HALF, [0.2, 0.175, 0.02]);
}

/// docs/src/reference-facts.md §2.3, ObjectWall: 0.20 m along y, 1 cm thick, z 0.82…1.07, across
/// bin 1.
#[test]
fn object_wall() {
    let row = obstacle_geometry(Obstacle::ObjectWall);
    let x = 0.1 - 0.2 / 2.2;
    assert_close(x, 0.00909, 1e-5, "the reference's rounded body x");
    let body = row.body_pose();
    assert_close(
        (body.translation.vector - Vector3::new(x, -0.26, 0.925)).norm(),
        0.0,
        EPS,
        "body",
    );
    let q = body.rotation.coords; // x, y, z, w
    assert_close(
        (q - nalgebra::Vector4::new(0.0, 0.0, 0.5f64.sqrt(), 0.5f64.sqrt())).norm(),
        0.0,
        EPS,
        "quat",
    );

    let parts = arena_parts(Objective::PickPlace, Obstacle::ObjectWall);
    let wall = find(&parts, "obstacle/wall");
    assert_close(
        (centre(wall) - Vector3::new(x, -0.26, 0.945)).norm(),
        0.0,
        EPS,
        "centre",
    );
    assert_span(wall, X, [x - 0.005, x + 0.005]);
    assert_span(wall, Y, [-0.36, -0.16]);
    assert_span(wall, Z, [0.82, 1.07]);
    assert_eq!((row.bottom_offset, row.top_offset), (-0.125, 0.125));
}

/// docs/src/reference-facts.md §2.3, ObjectDoor: two posts with an 0.18 m opening centred on
/// y = −0.26, open top.
#[test]
fn object_door() {
    let parts = arena_parts(Objective::Shelf, Obstacle::ObjectDoor);
    let x = 0.1 - 0.2 / 2.2;
    let low = find(&parts, "obstacle/post_y-");
    let high = find(&parts, "obstacle/post_y+");
    assert_close(
        (centre(low) - Vector3::new(x, -0.42, 0.945)).norm(),
        0.0,
        EPS,
        "low post",
    );
    assert_close(
        (centre(high) - Vector3::new(x, -0.10, 0.945)).norm(),
        0.0,
        EPS,
        "high post",
    );
    assert_span(low, Y, [-0.49, -0.35]);
    assert_span(high, Y, [-0.17, -0.03]);
    for post in [low, high] {
        assert_span(post, Z, [0.82, 1.07]);
        assert_span(post, X, [x - 0.005, x + 0.005]);
    }
    let opening = [low.aabb().1.y, high.aabb().0.y];
    assert_close(opening[1] - opening[0], 0.18, EPS, "opening width");
    assert_close(
        (opening[0] + opening[1]) / 2.0,
        -0.26,
        EPS,
        "opening centre",
    );
    assert_eq!(
        obstacle_geometry(Obstacle::ObjectDoor).body_position,
        obstacle_geometry(Obstacle::ObjectWall).body_position
    );
}

/// docs/src/reference-facts.md §2.3, GoalWall: on the seam between the bins, robot-near half only,
/// 28 cm tall.
#[test]
fn goal_wall() {
    let row = obstacle_geometry(Obstacle::GoalWall);
    assert_close(
        (row.body_pose().translation.vector - Vector3::new(0.1, -0.01, 0.94)).norm(),
        0.0,
        EPS,
        "body",
    );
    assert_eq!(row.yaw, 0.0);
    let parts = arena_parts(Objective::Push, Obstacle::GoalWall);
    let wall = find(&parts, "obstacle/wall");
    assert_close(
        (centre(wall) - Vector3::new(0.005, -0.01, 0.96)).norm(),
        0.0,
        EPS,
        "centre",
    );
    assert_span(wall, X, [-0.10, 0.11]);
    assert_span(wall, Y, [-0.015, -0.005]);
    assert_span(wall, Z, [0.82, 1.10]);
    assert_eq!((row.bottom_offset, row.top_offset), (-0.14, 0.14));
}

/// docs/src/reference-facts.md §2.3 and STYLE D6: "no obstacle" is a row with nothing in it,
/// reported at the origin.
#[test]
fn no_obstacle_is_an_empty_row() {
    let row = obstacle_geometry(Obstacle::NoObstacle);
    assert!(row.parts.is_empty() && row.footprint.is_empty());
    assert_eq!(row.body_position, [0.0; 3]);
    for objective in Objective::all() {
        let base = arena_parts(objective, Obstacle::NoObstacle).len();
        for (obstacle, extra) in [
            (Obstacle::ObjectWall, 1),
            (Obstacle::ObjectDoor, 2),
            (Obstacle::GoalWall, 1),
        ] {
            assert_eq!(arena_parts(objective, obstacle).len(), base + extra);
        }
    }
    let counts: Vec<usize> = Objective::all()
        .into_iter()
        .map(|o| arena_parts(o, Obstacle::NoObstacle).len())
        .collect();
    // Bins 5 + 5 (Push 4 + 4), trash can 5 parts, shelf 3.
    assert_eq!(counts, [10, 8, 15, 13]);
}

/// docs/src/reference-facts.md §2.5: the trash can stands on bin 2's floor inside bin 2.
#[test]
fn trash_can() {
    assert_eq!(TRASH_CAN.position, [0.1, 0.18, 0.825]);
    assert_eq!(
        (TRASH_CAN.half_size, TRASH_CAN.z_offset, TRASH_CAN.height),
        (0.08, 0.005, 0.08)
    );
    let parts = arena_parts(Objective::TrashCan, Obstacle::NoObstacle);
    let floor = find(&parts, "trash_can/floor");
    assert_span(floor, X, [0.02, 0.18]);
    assert_span(floor, Y, [0.10, 0.26]);
    assert_span(floor, Z, [0.82, 0.83]);
    assert_close(
        floor.aabb().0.z,
        find(&parts, "bin2/floor").aabb().1.z,
        EPS,
        "on the floor",
    );
    for wall in [
        "trash_can/wall_y+",
        "trash_can/wall_y-",
        "trash_can/wall_x+",
        "trash_can/wall_x-",
    ] {
        assert_span(find(&parts, wall), Z, [0.8255, 0.9855]);
    }
    assert_span(find(&parts, "trash_can/wall_y+"), Y, [0.255, 0.265]);
    assert_span(find(&parts, "trash_can/wall_x-"), X, [0.015, 0.025]);
    let cavity_x =
        find(&parts, "trash_can/wall_x+").aabb().0.x - find(&parts, "trash_can/wall_x-").aabb().1.x;
    let cavity_y =
        find(&parts, "trash_can/wall_y+").aabb().0.y - find(&parts, "trash_can/wall_y-").aabb().1.y;
    assert_close(cavity_x, 0.15, EPS, "cavity x");
    assert_close(cavity_y, 0.15, EPS, "cavity y");
    for objective in [Objective::PickPlace, Objective::Push, Objective::Shelf] {
        assert!(
            !names(&arena_parts(objective, Obstacle::NoObstacle))
                .iter()
                .any(|n| n.starts_with("trash_can/"))
        );
    }
}

/// docs/src/reference-facts.md §2.6: the shelf opens towards bin 1; free opening z 0.945…1.10,
/// y 0.14…0.32.
#[test]
fn shelf() {
    let bin2 = bin2_position(Objective::Shelf);
    let expected = [bin2.x, bin2.y + (SHELF.y_size + SHELF.thickness), bin2.z];
    assert_eq!(SHELF.position, expected);
    assert_close(
        (Vector3::from(SHELF.position) - Vector3::new(0.1, 0.33, 0.8)).norm(),
        0.0,
        EPS,
        "body",
    );
    assert_eq!(
        (
            SHELF.x_size,
            SHELF.y_size,
            SHELF.thickness,
            SHELF.z_offset,
            SHELF.z_height
        ),
        (0.2, 0.1, 0.05, 0.145, 0.15)
    );
    let parts = arena_parts(Objective::Shelf, Obstacle::NoObstacle);
    let back = find(&parts, "shelf/back");
    let bottom = find(&parts, "shelf/bottom");
    let top = find(&parts, "shelf/top");
    assert_span(back, X, [-0.1, 0.3]);
    assert_span(back, Y, [0.32, 0.34]);
    assert_span(back, Z, [0.80, 1.10]);
    assert_span(bottom, Y, [0.14, 0.34]);
    assert_span(bottom, Z, [0.80, 0.945]);
    assert_span(top, Y, [0.14, 0.34]);
    assert_span(top, Z, [1.10, 1.20]);
    for part in [bottom, top] {
        assert_span(part, X, [-0.1, 0.3]);
    }
    // The free opening between the blocks and in front of the back panel.
    assert_close(bottom.aabb().1.z, 0.945, EPS, "opening bottom");
    assert_close(top.aabb().0.z, 1.10, EPS, "opening top");
    assert_close(back.aabb().0.y, 0.32, EPS, "opening depth end");
    // Bin 2 is still there under the shelf.
    assert!(names(&parts).contains(&"bin2/wall_y+"));
}

/// docs/src/reference-facts.md §2.4: the goal marker's xy per objective and its z for all 16
/// objective × object pairs (reference height + offset − the object's bottom offset).
#[test]
fn goal_positions() {
    let objects = [
        Object::Box,
        Object::Dumbbell,
        Object::Plate,
        Object::HollowBox,
    ];
    let table: [(Objective, [f64; 2], [f64; 4]); 4] = [
        (
            Objective::PickPlace,
            [0.1, 0.18],
            [0.830, 0.852, 0.820, 0.808],
        ),
        (Objective::Push, [0.1, 0.13], [0.830, 0.852, 0.820, 0.808]),
        (Objective::Shelf, [0.1, 0.23], [0.975, 0.997, 0.965, 0.953]),
        (
            Objective::TrashCan,
            [0.1, 0.18],
            [0.860, 0.882, 0.850, 0.838],
        ),
    ];
    for (objective, xy, zs) in table {
        for (object, z) in objects.into_iter().zip(zs) {
            let goal = goal_position(objective, object);
            let what = format!("{objective:?}/{object:?} goal");
            assert_close(goal.x, xy[0], EPS, &what);
            assert_close(goal.y, xy[1], EPS, &what);
            assert_close(goal.z, z, EPS, &what);
            // The marker is visual only and sits at the goal.
            let marker = goal_marker_parts(objective, object);
            assert!(!marker.is_empty() && marker.iter().all(|p| !p.collides));
            assert!(marker.iter().all(|p| p.name.starts_with("goal/")));
            assert_eq!(marker[0].pose.translation.vector, goal.coords);
        }
    }
    // PickPlace and Push markers sit 2 cm below a resting object.
    for object in Object::all() {
        let rest = object_geometry(object).spawn_z();
        assert_close(
            rest - goal_position(Objective::PickPlace, object).z,
            0.02,
            EPS,
            "2 cm low",
        );
    }
}

/// docs/src/reference-facts.md §3 notes: the goal markers' cosmetic differences.
#[test]
fn goal_marker_shapes() {
    let dumbbell = goal_marker_parts(Objective::Push, Object::Dumbbell);
    assert_eq!(
        find(&dumbbell, "goal/disc_z+").shape,
        Primitive::cylinder(0.05, 0.0035)
    );
    let plate = goal_marker_parts(Objective::Push, Object::Plate);
    let goal = goal_position(Objective::Push, Object::Plate);
    assert_eq!(
        find(&plate, "goal/stem").shape,
        Primitive::cuboid(0.01, 0.01, 0.016)
    );
    assert_eq!(
        find(&plate, "goal/disc").shape,
        Primitive::cylinder(0.06, 0.005)
    );
    assert_close(
        centre(find(&plate, "goal/disc")).z - goal.z,
        0.016,
        EPS,
        "plate marker disc",
    );
    let boxed = goal_marker_parts(Objective::Push, Object::Box);
    assert_eq!(boxed[0].shape, object_parts(Object::Box)[0].shape);
}

/// docs/src/reference-facts.md §3: shapes, masses (1000 kg/m³ × collision volume + 0.001 kg per
/// material copy, within 1 g of the runtime masses), friction, sampler offsets and spawn heights.
#[test]
fn objects() {
    // (object, runtime mass, collision-volume mass, bottom, top, radius, spawn z)
    let table = [
        (Object::Box, 0.097, 0.096, -0.03, 0.03, 0.02, 0.85),
        (Object::HollowBox, 0.292, 0.288, -0.008, 0.068, 0.038, 0.828),
        (Object::Plate, 0.176, 0.1743, -0.02, 0.034, 0.06, 0.84),
        (Object::Dumbbell, 0.205, 0.2022, -0.052, 0.052, 0.045, 0.872),
    ];
    for (object, mass, volume_mass, bottom, top, radius, spawn_z) in table {
        let row = object_geometry(object);
        let what = format!("{object:?}");
        assert_close(row.mass(), mass, 0.001, &format!("{what} mass"));
        let volume: f64 = row.parts.iter().map(|p| p.shape.volume()).sum();
        assert_close(
            OBJECT_DENSITY * volume,
            volume_mass,
            0.00005,
            &format!("{what} volume mass"),
        );
        assert_eq!(
            (row.bottom_offset, row.top_offset, row.horizontal_radius),
            (bottom, top, radius)
        );
        assert_close(row.spawn_z(), spawn_z, EPS, &format!("{what} spawn z"));
        assert!(
            object_parts(object)
                .iter()
                .all(|p| p.collides && p.name.starts_with("object/"))
        );
    }

    let extent = |object: Object| {
        let parts = object_parts(object);
        let min = parts
            .iter()
            .map(|p| p.aabb().0)
            .fold(Vector3::repeat(f64::MAX), |a, b| a.inf(&b.coords));
        let max = parts
            .iter()
            .map(|p| p.aabb().1)
            .fold(Vector3::repeat(f64::MIN), |a, b| a.sup(&b.coords));
        (min, max)
    };
    let (min, max) = extent(Object::Box);
    assert_close(
        (max - min - Vector3::new(0.04, 0.04, 0.06)).norm(),
        0.0,
        EPS,
        "box size",
    );
    let (min, max) = extent(Object::HollowBox);
    assert_close(max.x - min.x, 0.076, EPS, "hollow box outer x");
    assert_close(max.y - min.y, 0.076, EPS, "hollow box outer y");
    assert_close(min.z, -0.008, EPS, "hollow box bottom");
    assert_close(max.z, 0.06, EPS, "hollow box top");
    let (min, max) = extent(Object::Plate);
    assert_close(min.z, -0.02, EPS, "plate bottom");
    assert_close(max.z, 0.027, EPS, "plate top");
    assert_close(max.x - min.x, 0.12, EPS, "plate diameter");
    let (min, max) = extent(Object::Dumbbell);
    assert_close(max.z - min.z, 0.097, EPS, "dumbbell height");
    assert_close(max.x - min.x, 0.09, EPS, "dumbbell disc diameter");

    let plate = object_parts(Object::Plate);
    assert_eq!(find(&plate, "object/stem").friction, Friction::TABLE);
    assert_eq!(find(&plate, "object/disc").friction, Friction::OBJECT);
    for object in [Object::Box, Object::HollowBox, Object::Dumbbell] {
        assert!(
            object_parts(object)
                .iter()
                .all(|p| p.friction == Friction::OBJECT)
        );
    }
    assert_eq!(
        Friction::OBJECT,
        Friction {
            slide: 1.0,
            torsion: 1.0,
            roll: 1.0
        }
    );
    assert_eq!(
        Friction::TABLE,
        Friction {
            slide: 1.0,
            torsion: 0.005,
            roll: 0.0001
        }
    );
}

/// docs/src/reference-facts.md §2.2: the start ranges in world coordinates, the spawn height and
/// the rejection discs, for every obstacle × object.
#[test]
fn start_regions() {
    for obstacle in Obstacle::all() {
        for object in Object::all() {
            let region = object_start_region(obstacle, object);
            let row = object_geometry(object);
            let r = row.horizontal_radius;
            let what = format!("{obstacle:?}/{object:?}");
            let behind_wall = matches!(obstacle, Obstacle::ObjectWall | Obstacle::ObjectDoor);
            let x_low = if behind_wall { 0.1 + r } else { r };
            let [x0, x1] = region.world_x();
            assert_close(x0, x_low.min(0.2 - r), EPS, &what);
            assert_close(x1, x_low.max(0.2 - r), EPS, &what);
            let [y0, y1] = region.world_y();
            assert_close(y0, -0.385 + r, EPS, &what);
            assert_close(y1, -0.135 - r, EPS, &what);
            // The draws themselves, in the reference's (low, high) order.
            assert_close(
                region.x_range[0],
                if behind_wall { r } else { -0.1 + r },
                EPS,
                &what,
            );
            assert_close(region.x_range[1], 0.1 - r, EPS, &what);
            assert_eq!(region.reference, BIN1_POSITION);
            assert_eq!(region.z, row.spawn_z());
            assert_eq!(
                region.position(0.0, 0.0).coords,
                Vector3::new(0.1, -0.26, region.z)
            );

            let obstacle_radius = match obstacle {
                Obstacle::NoObstacle => None,
                Obstacle::ObjectWall => Some(0.1),
                Obstacle::ObjectDoor => Some(0.07),
                Obstacle::GoalWall => Some(0.08),
            };
            let radii: Vec<f64> = region.keep_out.iter().map(|k| k.radius).collect();
            assert_eq!(
                radii,
                obstacle_radius
                    .map(|o| o + r)
                    .into_iter()
                    .collect::<Vec<_>>()
            );
            if let Some(disc) = region.keep_out.first() {
                let body = obstacle_geometry(obstacle).body_position;
                assert_eq!(disc.centre, [body[0], body[1]]);
            }
            // GoalWall can never reject: its disc cannot reach the region's nearest point.
            if obstacle == Obstacle::GoalWall {
                assert!(region.is_clear(x0, y1) && region.is_clear(0.1, y1));
            }
        }
    }
    // The plate's band behind an object wall is reversed (low 0.06 > high 0.04), 2 cm wide.
    let plate = object_start_region(Obstacle::ObjectWall, Object::Plate);
    assert!(plate.x_range[0] > plate.x_range[1]);
    assert_eq!(
        plate.world_x().map(|v| (v * 1e9).round() / 1e9),
        [0.14, 0.16]
    );
    // ObjectWall removes the corner next to the wall; the far edge stays clear.
    let boxed = object_start_region(Obstacle::ObjectWall, Object::Box);
    assert!(!boxed.is_clear(0.12, -0.26));
    assert!(boxed.is_clear(0.18, -0.26));
    // The rejection is inclusive: at exactly the disc's radius the sample is rejected.
    let disc = boxed.keep_out[0];
    assert!(!boxed.is_clear(disc.centre[0] + disc.radius, disc.centre[1]));
    assert!(object_start_region(Obstacle::NoObstacle, Object::Plate).is_clear(0.0, -0.26));
    assert_eq!(PLACEMENT_ATTEMPTS, 5000);
}

/// docs/src/reference-facts.md §2.7.
#[test]
fn robot_base() {
    assert_eq!(robot_base_pose(), Isometry3::translation(-0.5, -0.1, 0.912));
    assert_eq!(GROUND_HALF_SIZE, [3.0, 3.0]);
}

/// STYLE Nm4: part names never collide within a composed scene, and every solid is real.
#[test]
fn every_scene_has_unique_names_and_sound_parts() {
    for objective in Objective::all() {
        for obstacle in Obstacle::all() {
            for object in Object::all() {
                let mut scene = arena_parts(objective, obstacle);
                assert!(scene.iter().all(|p| p.collides));
                scene.extend(goal_marker_parts(objective, object));
                scene.extend(object_parts(object));
                let unique: BTreeSet<&str> = scene.iter().map(|p| p.name).collect();
                assert_eq!(
                    unique.len(),
                    scene.len(),
                    "{objective:?}/{obstacle:?}/{object:?}"
                );
                for part in &scene {
                    let (min, max) = part.aabb();
                    assert!((max - min).iter().all(|&d| d > 0.0), "{}", part.name);
                    assert!(part.shape.volume() > 0.0);
                }
            }
        }
    }
}

/// The bounds of a cylinder laid along y: its radius spans x and z, its length y.
#[test]
fn aabb_of_a_turned_cylinder() {
    let lying = Placed {
        name: "test/cylinder",
        shape: Primitive::cylinder(0.05, 0.2),
        pose: Isometry3::new(
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::x() * std::f64::consts::FRAC_PI_2,
        ),
        collides: true,
        friction: Friction::TABLE,
    };
    assert_span(&lying, X, [0.95, 1.05]);
    assert_span(&lying, Y, [1.8, 2.2]);
    assert_span(&lying, Z, [2.95, 3.05]);
    assert_close(
        lying.shape.volume(),
        std::f64::consts::PI * 0.05 * 0.05 * 0.4,
        1e-15,
        "volume",
    );
}

/// In Push the two bin floors fill one box (docs/src/reference-facts.md §2.1: they overlap by 3.5
/// cm); they collide as that one box, so nothing sliding from bin 1 to bin 2 catches on bin 2's
/// buried edge. Elsewhere the floors are apart and every solid collides as it is.
#[test]
fn flush_floors_collide_as_one_box() {
    for objective in Objective::all() {
        let parts = arena_parts(objective, Obstacle::NoObstacle);
        let colliding = parts.iter().filter(|p| p.collides).count();
        let solids = merged_solids(&parts);
        if objective != Objective::Push {
            assert_eq!(solids.len(), colliding, "{objective:?}");
            continue;
        }
        assert_eq!(solids.len(), colliding - 1);
        let (index, floor) = solids
            .iter()
            .find(|(_, s)| s.name == "bin1/floor")
            .expect("the merged floor keeps bin 1's name");
        assert_eq!(parts[*index].name, "bin1/floor");
        assert!(solids.iter().all(|(_, s)| s.name != "bin2/floor"));
        assert_span(floor, 0, [-0.1, 0.3]);
        assert_span(floor, 1, [-0.51, 0.305]);
        assert_span(floor, 2, [0.78, 0.82]);
    }
    // Boxes apart, or matching in only one extent, stay apart.
    let floor = *find(
        &arena_parts(Objective::Push, Obstacle::NoObstacle),
        "bin1/floor",
    );
    let moved = |dy: f64| Placed {
        pose: Isometry3::translation(0.0, dy, 0.0) * floor.pose,
        ..floor
    };
    assert_eq!(merged_solids(&[floor, moved(0.5 + 1e-6)]).len(), 2);
    assert_eq!(merged_solids(&[floor, moved(0.5)]).len(), 1);
    let taller = Placed {
        shape: Primitive::Box {
            half_extents: Vector3::new(0.2, 0.25, 0.03),
        },
        ..moved(0.3)
    };
    assert_eq!(merged_solids(&[floor, taller]).len(), 2);
}
