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

use super::contacts::{Contact, Other};

/// The step's groups of balls joined by contacts, kept between steps.
#[derive(Default)]
pub struct Flights {
    root: Vec<u32>,
    in_flight: Vec<bool>,
    off_walls: Vec<bool>,
    /// Each group's balls, and what it strikes ([`BALLS`], [`WALL`]).
    size: Vec<u32>,
    struck: Vec<u32>,
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
        for (i, flag) in undone.iter_mut().enumerate() {
            let r = self.find(i);
            let (kinds, size) = (self.struck[r], self.size[r]);
            *flag = (self.in_flight[r] && kinds & BALLS != 0) || (self.off_walls[r] && size >= 2 && kinds & WALL != 0);
            any |= *flag;
        }
        any
    }
}

/// What a group strikes in a step: each other, a wall.
const BALLS: u32 = 1;
const WALL: u32 = 2;

#[cfg(test)]
mod tests {
    use super::*;

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
}
