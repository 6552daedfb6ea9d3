//! The invariants checked at every event: no ball inside a wall or inside another beyond the
//! contact tolerance.

use super::*;
use crate::model::ModelError;

impl Solver<'_> {
    /// The contact tolerance of balls `i` and `j` approaching at `rate`: the length tolerance,
    /// the rounding in their positions and two ulps of time at the faster of `rate` and the
    /// run's fastest speed.
    pub(super) fn pair_tolerance(&self, i: usize, j: usize, rate: f64) -> f64 {
        let (a, b) = (&self.balls[i], &self.balls[j]);
        let eps = f64::EPSILON;
        let size = a.p.iter().chain(&b.p).fold(0.0, |m: f64, c| m.max(c.abs())) + a.radius + b.radius;
        self.limits.tol + a.drift + b.drift + 8.0 * eps * size + 2.0 * eps * self.t.abs() * rate.abs().max(self.limits.fastest)
    }

    /// The postcondition for ball `k` (brought to now) against the walls: it overlaps none
    /// beyond the contact tolerance (docs/MODEL.md §14).
    pub(super) fn check_walls(&self, k: usize) -> Result<(), ModelError> {
        let b = self.balls[k];
        let (ends, half) = (self.walls[b.damper as usize], self.cells[b.damper as usize].half);
        let (xs, _) = self.frame.state_of(ends.floor, self.t);
        let tol = self.pair_tolerance(k, k, 0.0) + self.frame.position_roundoff_of(ends.floor, self.t);
        let walls = [
            ("left-wall", b.p[0] - b.radius - xs),
            ("right-wall", xs + ends.length - b.p[0] - b.radius),
            ("front wall", b.p[1] + half[0] - b.radius),
            ("back wall", half[0] - b.p[1] - b.radius),
            ("floor", b.p[2] + half[1] - b.radius),
            ("ceiling", half[1] - b.p[2] - b.radius),
        ];
        for (name, gap) in walls {
            if gap < -tol {
                return Err(self.broken(format!(
                    "its contact invariant at t = {} s: ball{} overlaps the {name} by {:.3e} m (tolerance {:.3e} m)",
                    crate::scene::human(self.t),
                    k + 1,
                    -gap,
                    tol
                )));
            }
        }
        Ok(())
    }

    /// The postcondition for ball `k` (brought to now) against the balls of the cells around
    /// it; the first violation found.
    pub(super) fn check_neighbours(&self, k: usize) -> Result<(), ModelError> {
        let p = self.balls[k].p;
        let mut checked = Ok(());
        self.cells[self.balls[k].damper as usize].around(self.balls[k].cell, |o| {
            let o = o as usize;
            if checked.is_ok() && o != k {
                let (po, _) = self.balls[o].at(self.t, self.gravity);
                checked = self.check_pair(k, o, std::array::from_fn(|c| po[c] - p[c]));
            }
        });
        checked
    }

    /// The postcondition for balls `k` and `o`, their centres `d` apart now: they overlap by
    /// no more than the contact tolerance (docs/MODEL.md §14).
    #[inline]
    pub(super) fn check_pair(&self, k: usize, o: usize, d: [f64; 3]) -> Result<(), ModelError> {
        let reach = self.balls[k].radius + self.balls[o].radius;
        if dot(d, d) >= reach * reach {
            // Apart, or touching: no overlap to weigh against the tolerance.
            return Ok(());
        }
        self.check_overlap(k, o, dot(d, d).sqrt() - reach)
    }

    /// [`Solver::check_pair`] for a pair closer than touching, `gap` (negative) apart.
    #[cold]
    pub(super) fn check_overlap(&self, k: usize, o: usize, gap: f64) -> Result<(), ModelError> {
        let tol = self.pair_tolerance(k, o, 0.0);
        if gap < -tol {
            return Err(self.broken(format!(
                "its contact invariant at t = {} s: ball{} / ball{} overlap by {:.3e} m (tolerance {:.3e} m)",
                crate::scene::human(self.t),
                k + 1,
                o + 1,
                -gap,
                tol
            )));
        }
        Ok(())
    }
}
