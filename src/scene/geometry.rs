//! Where the bodies are: the balls (mass, radius, size class), the container on the frame, and
//! the pairs of neighbours that can touch, stated once for every model (docs/MODEL.md §1, §3).

use std::f64::consts::PI;

/// Size class of a ball, for reports and colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BallKind {
    /// `L`.
    Large,
    /// `S`.
    Small,
    /// From an explicit list.
    Custom,
}

/// One ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// kg.
    pub mass: f64,
    /// m, from mass and density.
    pub radius: f64,
    /// Size class.
    pub kind: BallKind,
}

/// The container fixed on the frame: inner walls at `xs` and `xs + length`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Container {
    /// `Le`, m.
    pub length: f64,
    /// `Delta`, m.
    pub gap: f64,
    /// `Lc`, m.
    pub clearance: f64,
}

/// Radius of a solid sphere of mass `m` and density `rho`: `(3 m / (4 pi rho))^(1/3)`.
pub fn ball_radius(mass: f64, density: f64) -> f64 {
    (3.0 * mass / (4.0 * PI * density)).cbrt()
}

/// A body that takes part in an impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Body {
    /// The container's left wall (the frame).
    LeftWall,
    /// Ball `i` (0-based, left to right).
    Ball(usize),
    /// The container's right wall (the frame).
    RightWall,
}

impl Body {
    /// The body's name in outputs: `left-wall`, `right-wall`, `ball1`..`ballN`.
    pub fn name(self) -> String {
        match self {
            Body::LeftWall => "left-wall".into(),
            Body::RightWall => "right-wall".into(),
            Body::Ball(i) => format!("ball{}", i + 1),
        }
    }
}

/// The pairs of neighbours of a line of `n` balls that can touch: pair `p` between body `p - 1`
/// and body `p`, the walls included when the balls are in a container (pair 0 the left wall
/// and ball 1, pair `n` ball `n` and the right wall), only ball-ball pairs otherwise.
pub fn pair_range(n: usize, walls: bool) -> std::ops::Range<usize> {
    if walls {
        0..n + 1
    } else {
        1..n.max(1)
    }
}

/// The bodies either side of pair `p` of a line of `n` balls: pair `p` lies between body
/// `p - 1` and body `p`, the left wall being body `-1` and the right wall body `n`.
pub fn pair_bodies(p: usize, n: usize) -> (Body, Body) {
    let left = if p == 0 { Body::LeftWall } else { Body::Ball(p - 1) };
    let right = if p >= n { Body::RightWall } else { Body::Ball(p) };
    (left, right)
}

/// The gap across pair `p` of balls `balls` at centres `x`, with the container's walls at
/// `(left wall, length)` when there are walls, m (`None` for a wall pair without walls).
pub fn pair_gap(balls: &[Ball], x: &[f64], walls: Option<(f64, f64)>, p: usize) -> Option<f64> {
    let n = x.len();
    let r = |i: usize| balls[i].radius;
    match (p, walls) {
        (0, Some((xs, _))) if n > 0 => Some(x[0] - r(0) - xs),
        (p, Some((xs, length))) if p == n && n > 0 => Some(xs + length - x[n - 1] - r(n - 1)),
        (p, _) if p > 0 && p < n => Some(x[p] - r(p) - x[p - 1] - r(p - 1)),
        _ => None,
    }
}
