//! The balls: where each is and how fast it flies, the rounding its position has gathered, and
//! which the frame holds (and where on it). The gap of each pair of neighbours follows from them
//! alone, as a function of time ([`Gap`]).

use crate::scene::Scene;

/// Which wall a stuck ball is held by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Hold {
    Free,
    Left,
    Right,
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
    /// The container is packed wall to wall: it moves as one body for good.
    pub(super) packed: bool,
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
        }
    }

    /// Pairs that can touch: `p` lies between body `p - 1` and body `p` (body `-1` is the left
    /// wall, body `n` the right wall).
    pub(super) fn pair_range(&self) -> std::ops::Range<usize> {
        crate::scene::pair_range(self.n, self.walls)
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
        let left_frame = p == 0 || self.hold[p - 1] != Hold::Free;
        let right_frame = p == self.n || self.hold[p] != Hold::Free;
        left_frame != right_frame
    }

    /// The gap of pair `p` as a function of time.
    #[inline(always)]
    pub(super) fn gap(&self, p: usize) -> Gap {
        // The left body's right edge and the right body's left edge: a free ball's, or the
        // frame's (a wall, or a ball the frame holds, at an offset from `xs`).
        let left_free = p >= 1 && self.hold[p - 1] == Hold::Free;
        let right_free = p < self.n && self.hold[p] == Hold::Free;
        match (left_free, right_free) {
            (true, true) => {
                let (i, j) = (p - 1, p);
                Gap::Linear { g: (self.x[j] - self.radius[j]) - (self.x[i] + self.radius[i]), rate: self.v[j] - self.v[i] }
            }
            (false, true) => {
                let c = if p == 0 { 0.0 } else { self.offset[p - 1] + self.radius[p - 1] };
                Gap::Frame { ball: p, s: 1.0, k: -self.radius[p] - c }
            }
            (true, false) => {
                let c = if p == self.n { self.length } else { self.offset[p] - self.radius[p] };
                Gap::Frame { ball: p - 1, s: -1.0, k: c - self.radius[p - 1] }
            }
            (false, false) => Gap::Fixed,
        }
    }

    /// Whether the body left of pair `p` is a free ball.
    pub(super) fn left_body_free(&self, p: usize) -> bool {
        p >= 1 && self.hold[p - 1] == Hold::Free
    }

    /// Whether the body right of pair `p` is a free ball.
    pub(super) fn right_body_free(&self, p: usize) -> bool {
        p < self.n && self.hold[p] == Hold::Free
    }
}
