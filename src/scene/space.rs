//! Where the balls are across the frame's motion and the world they move in: the chains side
//! by side, each ball's place in the container's cross-section, gravity and friction
//! (docs/MODEL.md §13). A one-line scene is the special case with one chain on the container's
//! axis, no gravity and no friction.

use std::ops::Range;

/// The balls' arrangement across the frame's motion, and the world they move in.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Space {
    /// Index of each chain's first ball, in increasing order (`[0]` for one chain, empty
    /// without balls). The balls of a chain follow each other left to right.
    pub chain_starts: Vec<usize>,
    /// Each ball's centre across the motion, `[y, z]`, m, in the container's frame (its axis
    /// at `y = z = 0`); empty when every ball is on the axis.
    pub lateral: Vec<[f64; 2]>,
    /// Each ball's initial velocity across the motion, `[vy, vz]`, m/s; empty when none moves
    /// across.
    pub lateral_velocities: Vec<[f64; 2]>,
    /// The container's inner size across the motion, `[width (y), height (z)]`, m, centred on
    /// its axis; `[0, 0]` for a scene on one line (the container a tube as wide as its balls).
    pub section: [f64; 2],
    /// Channel width of each chain, m (0 for one chain): thin dividers along x separate the
    /// chains, so balls of different chains never touch.
    pub channel: f64,
    /// Gravity, m/s^2, `[gx, gy, gz]` (x along the frame's motion).
    pub gravity: [f64; 3],
    /// Coulomb friction coefficient of every contact.
    pub friction: f64,
}

impl Space {
    /// A scene's balls on one line: one chain of `n` balls on the container's axis.
    pub fn line(n: usize) -> Space {
        Space { chain_starts: if n == 0 { vec![] } else { vec![0] }, ..Space::default() }
    }

    /// Number of chains (0 without balls).
    pub fn chains(&self) -> usize {
        self.chain_starts.len()
    }

    /// The balls of chain `k`, of `n` balls in all.
    pub fn chain(&self, k: usize, n: usize) -> Range<usize> {
        self.chain_starts[k]..self.chain_starts.get(k + 1).copied().unwrap_or(n)
    }

    /// The chain ball `i` belongs to.
    pub fn chain_of(&self, i: usize) -> usize {
        self.chain_starts.partition_point(|&s| s <= i).saturating_sub(1)
    }

    /// Ball `i`'s centre across the motion, `[y, z]`, m.
    pub fn lateral_of(&self, i: usize) -> [f64; 2] {
        self.lateral.get(i).copied().unwrap_or([0.0; 2])
    }

    /// Ball `i`'s initial velocity across the motion, `[vy, vz]`, m/s.
    pub fn lateral_velocity_of(&self, i: usize) -> [f64; 2] {
        self.lateral_velocities.get(i).copied().unwrap_or([0.0; 2])
    }

    /// Why balls at centres `x` along the motion are not a set of chains on lines parallel to
    /// it, each listed left to right (balls off their chain's line or out of order, motion
    /// across it, gravity, friction), or `None` when they are: what a one-dimensional model
    /// can represent exactly.
    pub fn beyond_lines(&self, x: &[f64]) -> Option<String> {
        let n = x.len();
        if self.gravity.iter().any(|&g| g != 0.0) {
            return Some(format!(
                "the scene has gravity {:?} m/s^2; this model moves balls along lines only, without gravity",
                self.gravity
            ));
        }
        if self.friction != 0.0 {
            return Some(format!("the scene has friction {}; this model has no tangential forces", self.friction));
        }
        if let Some(i) = self.lateral_velocities.iter().position(|v| *v != [0.0; 2]) {
            return Some(format!("ball{} moves across the frame's motion; this model moves balls along lines only", i + 1));
        }
        for k in 0..self.chains() {
            let chain = self.chain(k, n);
            let line = self.lateral_of(chain.start);
            if let Some(i) = chain.clone().find(|&i| self.lateral_of(i) != line) {
                return Some(format!(
                    "ball{} is off the line of ball{} (its chain's first ball); this model moves balls along lines only",
                    i + 1,
                    chain.start + 1
                ));
            }
            if let Some(i) = chain.clone().skip(1).find(|&i| x[i] < x[i - 1]) {
                return Some(format!(
                    "ball{} lies left of ball{} on their line; this model needs a line's balls listed left to right",
                    i + 1,
                    i
                ));
            }
        }
        None
    }

    /// Whether the scene has more than one line's worth of geometry to show or write: several
    /// chains, a cross-section, balls off the axis or moving across it, gravity or friction.
    pub fn is_spatial(&self) -> bool {
        self.chains() > 1
            || self.section != [0.0; 2]
            || !self.lateral.is_empty()
            || !self.lateral_velocities.is_empty()
            || self.gravity != [0.0; 3]
            || self.friction != 0.0
    }
}
