//! Groups of balls in flight (docs/MODEL.md §9, "Groups in flight"). Rapier solves all the
//! contacts of a step at once: a ball that meets two others in one step is stopped short of
//! both by one plastic solve, which passes momentum between pairs that never touch. The impact
//! law applied afterwards to each pair then starts from velocities the other pairs' contacts
//! have changed, and a gas loses or gains energy at `e = 1`. A group of balls joined only by
//! each other's contacts, none of which was pressed against anything at the step's start, felt
//! nothing in the step but Rapier's solve of those contacts and gravity: its whole step is
//! undone, and its impacts act one after the other on the velocities free flight gives. So is
//! the step of a touching group off the walls of which a ball strikes a wall ("Touching rows
//! struck into a wall"): Rapier's solve stops such a row as one block.

use super::contacts::{dot, Contact, Other};

/// The step's groups of balls joined by contacts, kept between steps.
#[derive(Default)]
pub struct Flights {
    root: Vec<u32>,
    in_flight: Vec<bool>,
    off_walls: Vec<bool>,
    /// Each group's balls, and what it strikes ([`BALLS`], [`WALL`]).
    size: Vec<u32>,
    struck: Vec<u32>,
    into_wall: Vec<bool>,
}

impl Flights {
    fn find(&mut self, mut i: usize) -> usize {
        while self.root[i] as usize != i {
            let up = self.root[self.root[i] as usize];
            self.root[i] = up;
            i = up as usize;
        }
        i
    }

    /// Marks in `undone` the balls of every group, joined by the ball pairs of `found` (every
    /// pair a step may have closed, at its end) marked in `joined` (those Rapier's solve acted
    /// on), that is in flight: its balls were all free at the step's start (`free`: not pressed
    /// against a ball or a wall) and two of them strike each other (a pair of `struck`), or it
    /// is a group of two or more balls that rested on no wall at the step's start (`off_walls`)
    /// of which one strikes a wall (a ball of `wall_struck`). Returns whether it marked any; a
    /// step without such strikes costs nothing more.
    pub fn mark(
        &mut self,
        found: &[Contact],
        joined: &[bool],
        (free, off_walls): (impl Fn(usize) -> bool, impl Fn(usize) -> bool),
        struck: impl Iterator<Item = (usize, usize)>,
        wall_struck: impl Iterator<Item = usize>,
        undone: &mut [bool],
    ) -> bool {
        let mut struck = struck.peekable();
        let mut wall_struck = wall_struck.peekable();
        if struck.peek().is_none() && wall_struck.peek().is_none() {
            undone.iter_mut().for_each(|flag| *flag = false);
            self.into_wall.iter_mut().for_each(|flag| *flag = false);
            return false;
        }
        let n = undone.len();
        self.root.clear();
        self.root.extend(0..n as u32);
        for (c, _) in found.iter().zip(joined).filter(|(_, &joins)| joins) {
            if let Other::Ball(j) = c.other {
                let (a, b) = (self.find(c.ball), self.find(j));
                if a != b {
                    self.root[a.max(b)] = a.min(b) as u32;
                }
            }
        }
        for flags in [&mut self.in_flight, &mut self.off_walls] {
            flags.clear();
            flags.resize(n, true);
        }
        for counts in [&mut self.size, &mut self.struck] {
            counts.clear();
            counts.resize(n, 0);
        }
        for i in 0..n {
            let r = self.find(i);
            self.in_flight[r] &= free(i);
            self.off_walls[r] &= off_walls(i);
            self.size[r] += 1;
        }
        // A group in flight whose balls strike each other, or a group off the walls that
        // strikes one.
        for (a, _) in struck {
            let r = self.find(a);
            self.struck[r] |= BALLS;
        }
        for a in wall_struck {
            let r = self.find(a);
            self.struck[r] |= WALL;
        }
        let mut any = false;
        self.into_wall.clear();
        self.into_wall.resize(n, false);
        for (i, flag) in undone.iter_mut().enumerate() {
            let r = self.find(i);
            let (kinds, size) = (self.struck[r], self.size[r]);
            self.into_wall[i] = self.off_walls[r] && size >= 2 && kinds & WALL != 0;
            *flag = (self.in_flight[r] && kinds & BALLS != 0) || self.into_wall[i];
            any |= *flag;
        }
        any
    }

    /// The balls of the groups the last [`Flights::mark`] undid because they strike a wall.
    pub fn struck_into_wall(&self) -> &[bool] {
        &self.into_wall
    }
}

/// What a group strikes in a step: each other, a wall.
const BALLS: u32 = 1;
const WALL: u32 = 2;

/// The most sweeps over an undone group's pairs that part its pressed balls, and the overlap,
/// relative to the pair's distance, below which a pair counts as parted (an `f32` position's
/// rounding).
const PARTING_SWEEPS: usize = 2000;
const PARTED: f64 = 1e-7;

/// A ball parted from another moves into a wall it touches when its move has at least this
/// component along the wall's normal: it stays put for that pair instead.
const INTO_WALL: f64 = 1e-3;

/// Whether balls `a` and `b` of an undone group touched at the step's start (positions `x`,
/// velocities `v`, within `touching` of each other) and their free flight keeps them that close
/// through a step of `h`. Such a pair touches still as hard spheres move, and takes the step's
/// knock-ons, though Rapier's solve, whose positions the group keeps, may have opened it.
pub fn kept_touching((a, b): (usize, usize), (x, v): (&[[f64; 3]], &[[f64; 3]]), radius: &[f64], (touching, h): (f64, f64)) -> bool {
    let d: [f64; 3] = std::array::from_fn(|k| x[b][k] - x[a][k]);
    let dv: [f64; 3] = std::array::from_fn(|k| v[b][k] - v[a][k]);
    let distance = dot(d, d).sqrt();
    let parting = (dot(dv, d) / distance).max(0.0);
    distance - radius[a] - radius[b] + parting * h <= touching
}

/// Takes out of the undone groups (`undone`) the overlaps Rapier's plastic stop pressed into
/// them ("Touching rows struck into a wall"): the step's velocities are the impact law's, but
/// the positions are Rapier's, and a row it stopped as one block is left pressed into itself,
/// which Rapier's next step would push apart with speeds the impacts never gave. Every pair of
/// `found` (at the step's end) of two undone balls is parted along its centres' line until it
/// overlaps no deeper than at the step's start (`start`), the lighter ball moving more; a ball
/// does not move into a wall it touches at the step's end (a gap within `touching`). Marks the
/// balls it moved in `moved` and returns whether it moved any.
pub fn part_pressed(
    found: &[Contact],
    (undone, touching): (&[bool], f64),
    (start, end): (&[[f64; 3]], &mut [[f64; 3]]),
    (radius, mass): (&[f64], &[f64]),
    moved: &mut [bool],
) -> bool {
    let between = |x: &[[f64; 3]], i: usize, j: usize| -> [f64; 3] { std::array::from_fn(|a| x[j][a] - x[i][a]) };
    let length = |d: [f64; 3]| dot(d, d).sqrt();
    let walls: Vec<(usize, [f64; 3])> = found
        .iter()
        .filter(|c| undone[c.ball] && matches!(c.other, Other::Wall(_)) && c.gap <= touching)
        .map(|c| (c.ball, c.normal))
        .collect();
    // Whether ball `k` may move along `d`: no wall it touches lies that way.
    let may_move = |k: usize, d: [f64; 3]| walls.iter().filter(|(ball, _)| *ball == k).all(|(_, n)| dot(*n, d) < INTO_WALL * length(d));
    // Each pair with the distance it is parted to and its balls' shares of a correction.
    let mut pairs: Vec<(usize, usize, f64, f64, f64)> = Vec::new();
    for c in found.iter().filter(|c| undone[c.ball]) {
        let Other::Ball(j) = c.other else { continue };
        if !undone[j] {
            continue;
        }
        let i = c.ball;
        let d = between(end, i, j);
        let least = (radius[i] + radius[j]).min(length(between(start, i, j)));
        let free_i = if may_move(i, d.map(|x| -x)) { 1.0 / mass[i] } else { 0.0 };
        let free_j = if may_move(j, d) { 1.0 / mass[j] } else { 0.0 };
        if free_i + free_j > 0.0 {
            pairs.push((i, j, least, free_i / (free_i + free_j), free_j / (free_i + free_j)));
        }
    }
    let mut any = false;
    for sweep in 0..PARTING_SWEEPS {
        let mut deepest = 0.0f64;
        // Sweeps alternate in direction, so a correction runs along a row both ways.
        for k in 0..pairs.len() {
            let (i, j, least, share_i, share_j) = pairs[if sweep % 2 == 0 { k } else { pairs.len() - 1 - k }];
            let d = between(end, i, j);
            let apart = length(d);
            if apart >= least || apart == 0.0 {
                continue;
            }
            let short = least - apart;
            for a in 0..3 {
                end[i][a] -= d[a] / apart * short * share_i;
                end[j][a] += d[a] / apart * short * share_j;
            }
            (moved[i], moved[j]) = (moved[i] || share_i > 0.0, moved[j] || share_j > 0.0);
            any = true;
            deepest = deepest.max(short / least);
        }
        if deepest <= PARTED {
            break;
        }
    }
    any
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Wall;

    fn pair(a: usize, b: usize) -> Contact {
        Contact { ball: a, other: Other::Ball(b), gap: 0.0, normal: [1.0, 0.0, 0.0] }
    }

    /// A group is undone only when every ball in it was free and two of them strike; a wall
    /// contact joins nothing.
    #[test]
    fn undoes_only_free_groups_that_strike() {
        let found = [
            pair(0, 1),
            pair(1, 2),
            pair(3, 4),
            pair(5, 6),
            Contact { ball: 7, other: Other::Wall(crate::scene::Wall::Left), gap: 0.0, normal: [-1.0, 0.0, 0.0] },
        ];
        let mut undone = vec![false; 8];
        // Ball 4 touched something at the step's start; 5 and 6 do not strike.
        let any = Flights::default().mark(
            &found,
            &[true; 5],
            (|i| i != 4, |_| false),
            [(1, 2), (3, 4)].into_iter(),
            std::iter::empty(),
            &mut undone,
        );
        assert_eq!(undone, [true, true, true, false, false, false, false, false]);
        assert!(any);
    }

    /// A group off the walls is undone when one of its balls strikes a wall and it has two
    /// balls or more; a group with a ball resting on a wall, or a lone ball, is not.
    #[test]
    fn undoes_groups_off_the_walls_that_strike_one() {
        let found = [pair(0, 1), pair(2, 3), pair(3, 4)];
        let mut undone = vec![false; 6];
        // Ball 4 rested on a wall; ball 5 is alone; none was free of the others.
        let any =
            Flights::default().mark(&found, &[true; 3], (|_| false, |i| i != 4), std::iter::empty(), [1, 2, 5].into_iter(), &mut undone);
        assert_eq!(undone, [true, true, false, false, false, false]);
        assert!(any);
    }

    /// A row lying on the floor, pressed into itself against an end wall, is parted to
    /// touching along the floor, the ball on the end wall staying; a pair that overlapped at
    /// the step's start is parted only to that overlap.
    #[test]
    fn parts_a_pressed_row_from_the_ball_on_its_wall() {
        let r = 0.005;
        let wall = |ball, wall, normal| Contact { ball, other: Other::Wall(wall), gap: -1e-6, normal };
        let mut found = vec![wall(0, Wall::Left, [-1.0, 0.0, 0.0]), pair(0, 1), pair(1, 2), pair(2, 3)];
        found.extend((0..4).map(|k| wall(k, Wall::Floor, [0.0, 0.0, -1.0])));
        // At the start the row touches, but the last two balls overlap by 1 um; Rapier's stop
        // pressed every pair by 30 um more.
        let start = [[r, 0.0, 0.0], [3.0 * r, 0.0, 0.0], [5.0 * r, 0.0, 0.0], [7.0 * r - 1e-6, 0.0, 0.0]];
        let mut end = start;
        for (k, x) in end.iter_mut().enumerate() {
            x[0] -= 3e-5 * k as f64;
        }
        let mut moved = [false; 4];
        let parted = part_pressed(&found, (&[true; 4], 1e-7), (&start, &mut end), (&[r; 4], &[0.01; 4]), &mut moved);
        assert!(parted);
        assert_eq!(moved, [false, true, true, true]);
        assert_eq!(end[0], [r, 0.0, 0.0]);
        for (k, least) in [(0, 2.0 * r), (1, 2.0 * r), (2, 2.0 * r - 1e-6)] {
            let apart = end[k + 1][0] - end[k][0];
            assert!((apart - least).abs() <= PARTED * least, "pair {k}: {apart} m apart, not {least}");
        }
    }
}
