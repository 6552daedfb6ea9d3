//! The balls: where each is and how fast it flies, the rounding its position has gathered, and
//! which the frame holds (and where on it). The gap of each pair of neighbours follows from them
//! alone, as a function of time ([`Gap`]).

use crate::scene::{Pairs, Scene};

/// Which wall a stuck ball is held by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Hold {
    Free,
    Left,
    Right,
    /// Its chain is packed wall to wall: it moves with the frame for good.
    Packed,
}

/// The gap of a pair as a function of time.
#[derive(Debug, Clone, Copy)]
pub(super) enum Gap {
    /// Both sides move with the frame: the gap never changes.
    Fixed,
    /// Two free balls: `g(t) = g + rate (t - t_now)`.
    Linear { g: f64, rate: f64 },
    /// A free ball `ball` against the frame: `g(t) = s (x_ball(t) - xs(t)) + k`.
    Frame { ball: usize, s: f64, k: f64 },
}

/// The balls of a run.
pub(super) struct Balls {
    pub(super) n: usize,
    /// Whether the balls are in a container (a chain without a frame has no walls).
    pub(super) walls: bool,
    /// The container's length, m.
    pub(super) length: f64,
    pub(super) mass: Vec<f64>,
    pub(super) radius: Vec<f64>,
    /// Centres of free balls now (a held ball's is `xs + offset`), m.
    pub(super) x: Vec<f64>,
    /// Velocities of free balls, m/s.
    pub(super) v: Vec<f64>,
    /// A bound on the rounding that advancing has added to each ball's position `x` so far.
    pub(super) drift: Vec<f64>,
    pub(super) hold: Vec<Hold>,
    /// A held ball's centre less the frame's position.
    pub(super) offset: Vec<f64>,
    /// No held ball can be released: every held ball's chain is packed wall to wall.
    pub(super) packed: bool,
    /// The balls of each chain.
    pub(super) chains: Vec<std::ops::Range<usize>>,
    /// The pairs of neighbours on the scene's chains.
    pub(super) pairs: Pairs,
}

impl Balls {
    pub(super) fn new(scene: &Scene) -> Self {
        let n = scene.balls.len();
        Balls {
            n,
            walls: scene.container.is_some(),
            length: scene.container.map_or(0.0, |c| c.length),
            mass: scene.balls.iter().map(|b| b.mass).collect(),
            radius: scene.balls.iter().map(|b| b.radius).collect(),
            x: scene.initial_positions.clone(),
            v: scene.initial_velocities.clone(),
            drift: vec![0.0; n],
            hold: vec![Hold::Free; n],
            offset: vec![0.0; n],
            packed: false,
            chains: (0..scene.space.chains()).map(|k| scene.space.chain(k, n)).collect(),
            pairs: Pairs::new(n, &scene.space.chain_starts, scene.container.is_some()),
        }
    }

    /// Pairs that can touch (see [`Pairs`]).
    pub(super) fn pair_range(&self) -> std::ops::Range<usize> {
        self.pairs.range()
    }

    /// Moves the free balls on by `dt`, counting the rounding each step adds to their positions.
    pub(super) fn advance(&mut self, dt: f64) {
        for i in 0..self.n {
            if self.hold[i] == Hold::Free {
                let step = self.v[i] * dt;
                self.x[i] += step;
                // Every ball moves at every event, so a pair that moves as one (equal
                // velocities, no event of its own) sees its gap wander by this rounding.
                self.drift[i] += f64::EPSILON * (self.x[i].abs() + step.abs());
            }
        }
    }

    /// Whether pair `p` is a free ball against the frame (a wall, or a ball the frame holds):
    /// [`Balls::gap`]'s kind without its arithmetic.
    #[inline]
    pub(super) fn is_frame_pair(&self, p: usize) -> bool {
        let (left, right) = self.pairs.balls(p);
        let left_frame = left.is_none_or(|i| self.hold[i] != Hold::Free);
        let right_frame = right.is_none_or(|j| self.hold[j] != Hold::Free);
        left_frame != right_frame
    }

    /// The gap of pair `p` as a function of time.
    #[inline(always)]
    pub(super) fn gap(&self, p: usize) -> Gap {
        // The left body's right edge and the right body's left edge: a free ball's, or the
        // frame's (a wall, or a ball the frame holds, at an offset from `xs`).
        let (left, right) = self.pairs.balls(p);
        let left_free = left.filter(|&i| self.hold[i] == Hold::Free);
        let right_free = right.filter(|&j| self.hold[j] == Hold::Free);
        match (left_free, right_free) {
            (Some(i), Some(j)) => {
                Gap::Linear { g: (self.x[j] - self.radius[j]) - (self.x[i] + self.radius[i]), rate: self.v[j] - self.v[i] }
            }
            (None, Some(j)) => {
                let c = left.map_or(0.0, |i| self.offset[i] + self.radius[i]);
                Gap::Frame { ball: j, s: 1.0, k: -self.radius[j] - c }
            }
            (Some(i), None) => {
                let c = right.map_or(self.length, |j| self.offset[j] - self.radius[j]);
                Gap::Frame { ball: i, s: -1.0, k: c - self.radius[i] }
            }
            (None, None) => Gap::Fixed,
        }
    }

    /// The free ball left of pair `p`, if the body there is one.
    #[inline]
    pub(super) fn left_free_ball(&self, p: usize) -> Option<usize> {
        self.pairs.balls(p).0.filter(|&i| self.hold[i] == Hold::Free)
    }

    /// The free ball right of pair `p`, if the body there is one.
    #[inline]
    pub(super) fn right_free_ball(&self, p: usize) -> Option<usize> {
        self.pairs.balls(p).1.filter(|&j| self.hold[j] == Hold::Free)
    }
}
