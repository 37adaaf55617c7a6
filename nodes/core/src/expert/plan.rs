//! Collision-free joint-space paths: a straight line where it is free, else RRT-Connect (two
//! trees grown towards random configurations and towards each other), then shortened by
//! cutting corners wherever the straight line between two of its points is free.
//!
//! Distances are the largest joint difference ([`joint_distance`]): under the reference's
//! controller every joint moves at the same top speed, so that is what a move costs in time.
//! The sampler is seeded by the caller, so the same request gives the same path.

use super::track::{Joints, joint_distance};
use crate::physics::ARM_DOF;
use crate::rng::Mt19937;

/// How far (rad, largest joint) a tree grows towards a sample in one extension.
const EXTEND: f64 = 0.15;
/// The spacing (rad, largest joint) at which a straight move is checked for collisions.
const CHECK_SPACING: f64 = 0.02;
/// Random corner cuts tried on a found path.
const SHORTCUTS: usize = 150;

/// A planning request's world: the joint limits and a test of whether a configuration is free.
pub(crate) struct Space<'a> {
    /// Lower and upper limit per joint (rad).
    pub limits: [(f64, f64); ARM_DOF],
    /// Whether the arm (and what it carries) at a configuration keeps clear of the arena.
    pub free: &'a dyn Fn(&Joints) -> bool,
}

impl Space<'_> {
    /// Whether every configuration on the straight line from `a` to `b` is free (`a` is taken
    /// as checked).
    pub fn line_free(&self, a: &Joints, b: &Joints) -> bool {
        let n = (joint_distance(a, b) / CHECK_SPACING).ceil().max(1.0) as usize;
        (1..=n).all(|k| (self.free)(&lerp(a, b, k as f64 / n as f64)))
    }

    fn sample(&self, rng: &mut Mt19937) -> Joints {
        std::array::from_fn(|j| {
            let (lo, hi) = self.limits[j];
            lo + (hi - lo) * rng.random_sample()
        })
    }
}

/// `a + f·(b − a)`.
pub(crate) fn lerp(a: &Joints, b: &Joints, f: f64) -> Joints {
    std::array::from_fn(|j| a[j] + f * (b[j] - a[j]))
}

/// A tree of configurations, each with its parent's index.
struct Tree {
    nodes: Vec<(Joints, usize)>,
}

impl Tree {
    fn new(root: Joints) -> Tree {
        Tree {
            nodes: vec![(root, 0)],
        }
    }

    fn nearest(&self, q: &Joints) -> usize {
        (0..self.nodes.len())
            .min_by(|&a, &b| {
                joint_distance(&self.nodes[a].0, q).total_cmp(&joint_distance(&self.nodes[b].0, q))
            })
            .expect("a tree has its root")
    }

    /// One step from the node nearest `target` towards it, if free: the new node's index and
    /// whether it reached `target`.
    fn extend(&mut self, space: &Space, target: &Joints) -> Option<(usize, bool)> {
        let near = self.nearest(target);
        let from = self.nodes[near].0;
        let d = joint_distance(&from, target);
        let (to, reached) = if d <= EXTEND {
            (*target, true)
        } else {
            (lerp(&from, target, EXTEND / d), false)
        };
        if !space.line_free(&from, &to) {
            return None;
        }
        self.nodes.push((to, near));
        Some((self.nodes.len() - 1, reached))
    }

    /// Extensions towards `target` until it is reached or blocked: whether it was reached, and
    /// the last node added.
    fn connect(&mut self, space: &Space, target: &Joints) -> (bool, Option<usize>) {
        let mut last = None;
        loop {
            match self.extend(space, target) {
                Some((i, true)) => return (true, Some(i)),
                Some((i, false)) => last = Some(i),
                None => return (false, last),
            }
        }
    }

    /// The configurations from the root to node `i`.
    fn path_to(&self, mut i: usize) -> Vec<Joints> {
        let mut path = vec![self.nodes[i].0];
        while i != 0 {
            i = self.nodes[i].1;
            path.push(self.nodes[i].0);
        }
        path.reverse();
        path
    }
}

/// A free path from `start` to `goal` (both ends included), or `None` when `goal` is not free
/// or no path was found within `max_nodes` tree nodes.
pub(crate) fn plan(
    space: &Space,
    start: &Joints,
    goal: &Joints,
    seed: u32,
    max_nodes: usize,
) -> Option<Vec<Joints>> {
    if !(space.free)(goal) {
        return None;
    }
    if space.line_free(start, goal) {
        return Some(vec![*start, *goal]);
    }
    let mut rng = Mt19937::init_genrand(seed);
    let mut trees = [Tree::new(*start), Tree::new(*goal)];
    // Which tree is `trees[0]`: they swap after every round so both grow.
    let mut swapped = false;
    while trees[0].nodes.len() + trees[1].nodes.len() < max_nodes {
        let sample = space.sample(&mut rng);
        if let Some((i, _)) = trees[0].extend(space, &sample) {
            let new = trees[0].nodes[i].0;
            if let (true, Some(k)) = trees[1].connect(space, &new) {
                let mut a = trees[0].path_to(i);
                let mut b = trees[1].path_to(k);
                if swapped {
                    std::mem::swap(&mut a, &mut b);
                }
                // `a` runs from the start, `b` from the goal; both end at the meeting point.
                b.pop();
                b.reverse();
                a.extend(b);
                return Some(shortcut(space, a, &mut rng));
            }
        }
        trees.swap(0, 1);
        swapped = !swapped;
    }
    None
}

/// `path` shortened: lines between random points along it (not only its corners) replace
/// the stretch between them where they are free and shorter, then a greedy pass keeps, from
/// each point, the furthest one reachable in a straight line.
fn shortcut(space: &Space, mut path: Vec<Joints>, rng: &mut Mt19937) -> Vec<Joints> {
    for _ in 0..SHORTCUTS {
        if path.len() < 3 {
            break;
        }
        let total = path_length(&path);
        let (s1, s2) = (rng.random_sample() * total, rng.random_sample() * total);
        let (s1, s2) = (s1.min(s2), s1.max(s2));
        let (i, a) = point_at(&path, s1);
        let (j, b) = point_at(&path, s2);
        // `a` lies on the segment from path[i], `b` on the one from path[j]. The pieces of
        // those segments are checked again: a check samples a line at fixed spacing from its
        // start, so a piece is sampled at other points than the whole was.
        if i == j
            || joint_distance(&a, &b) >= s2 - s1 - 1e-6
            || !space.line_free(&a, &b)
            || !space.line_free(&path[i], &a)
            || !space.line_free(&b, &path[j + 1])
        {
            continue;
        }
        let mut shorter = path[..=i].to_vec();
        shorter.push(a);
        shorter.push(b);
        shorter.extend_from_slice(&path[j + 1..]);
        path = shorter;
    }
    // A final greedy pass: from each kept point, straight to the furthest point reachable.
    let mut out = vec![path[0]];
    let mut i = 0;
    while i + 1 < path.len() {
        let mut j = path.len() - 1;
        while j > i + 1 && !space.line_free(&path[i], &path[j]) {
            j -= 1;
        }
        out.push(path[j]);
        i = j;
    }
    out
}

/// The point `s` (rad, along the path's length) along `path`, and the index of the segment it
/// lies on (from `path[i]` towards `path[i + 1]`).
fn point_at(path: &[Joints], s: f64) -> (usize, Joints) {
    let mut left = s;
    for i in 0..path.len() - 1 {
        let d = joint_distance(&path[i], &path[i + 1]);
        if left <= d || i + 2 == path.len() {
            let f = if d > 0.0 {
                (left / d).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return (i, lerp(&path[i], &path[i + 1], f));
        }
        left -= d;
    }
    (0, path[0])
}

/// The time-relevant length of a path (rad, summed largest joint differences).
pub(crate) fn path_length(path: &[Joints]) -> f64 {
    path.windows(2).map(|w| joint_distance(&w[0], &w[1])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> [(f64, f64); ARM_DOF] {
        [(-3.0, 3.0); ARM_DOF]
    }

    /// Around a slab that blocks the straight line in joints 0 and 1 (only a gap near
    /// joint 1 = 2 passes), every point free, the same path for the same seed, and shorter
    /// than the tree's own wandering.
    #[test]
    fn the_path_goes_round_a_wall_and_is_repeatable() {
        // A wall at joint 0 ∈ [−0.2, 0.2] except where joint 1 > 1.5.
        let free = |q: &Joints| !(q[0].abs() < 0.2 && q[1] < 1.5);
        let space = Space {
            limits: limits(),
            free: &free,
        };
        let start = [-1.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0];
        let goal = [1.0, 0.0, -0.3, 0.0, 0.0, 0.0, 0.0];
        assert!(!space.line_free(&start, &goal));
        let path = plan(&space, &start, &goal, 7, 20_000).expect("a path");
        assert_eq!(path[0], start);
        assert_eq!(*path.last().unwrap(), goal);
        for w in path.windows(2) {
            assert!(space.line_free(&w[0], &w[1]));
        }
        assert!(path.iter().any(|q| q[1] >= 1.5));
        // The shortest way: up to joint 1 = 1.5 at joint 0 = ±0.2, about 1.5 + 0.4 + 1.5 in
        // the largest joint (joint 1 up and down, joint 0 across).
        let length = path_length(&path);
        assert!(length < 4.5, "{length} rad: {path:?}");
        assert_eq!(plan(&space, &start, &goal, 7, 20_000), Some(path));
    }

    /// A clear line is taken as it is; a goal inside the wall is refused at once.
    #[test]
    fn clear_lines_are_kept_and_blocked_goals_refused() {
        let free = |q: &Joints| q[0] < 2.0;
        let space = Space {
            limits: limits(),
            free: &free,
        };
        let a = [0.0; ARM_DOF];
        let mut b = a;
        b[0] = 1.0;
        assert_eq!(plan(&space, &a, &b, 1, 100), Some(vec![a, b]));
        b[0] = 2.5;
        assert_eq!(plan(&space, &a, &b, 1, 100), None);
    }
}
