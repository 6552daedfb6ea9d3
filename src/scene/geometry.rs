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

/// A body that takes part in an impact; in JSON, its name ([`Body::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum Body {
    /// The container's left wall (the frame).
    LeftWall,
    /// Ball `i` (0-based, left to right).
    Ball(usize),
    /// The container's right wall (the frame).
    RightWall,
    /// The container's floor (z = -height / 2): part of the frame, like every wall below, but
    /// its normal has no component along the motion.
    Floor,
    /// The container's ceiling (z = +height / 2).
    Ceiling,
    /// The container's front wall (y = -width / 2).
    FrontWall,
    /// The container's back wall (y = +width / 2).
    BackWall,
    /// The divider between chains `k - 1` and `k` (`k` from 1).
    Divider(usize),
}

impl Body {
    /// The body's name in outputs: `left-wall`, `right-wall`, `floor`, `ceiling`,
    /// `front-wall`, `back-wall`, `divider1`..., `ball1`..`ballN`.
    pub fn name(self) -> String {
        match self {
            Body::LeftWall => "left-wall".into(),
            Body::RightWall => "right-wall".into(),
            Body::Floor => "floor".into(),
            Body::Ceiling => "ceiling".into(),
            Body::FrontWall => "front-wall".into(),
            Body::BackWall => "back-wall".into(),
            Body::Divider(k) => format!("divider{k}"),
            Body::Ball(i) => format!("ball{}", i + 1),
        }
    }

    /// The wall across the motion at the negative (`positive` false) or positive end of
    /// `axis` (1 for y, 2 for z).
    pub fn across(axis: usize, positive: bool) -> Body {
        match (axis, positive) {
            (1, false) => Body::FrontWall,
            (1, true) => Body::BackWall,
            (_, false) => Body::Floor,
            (_, true) => Body::Ceiling,
        }
    }
}

impl From<Body> for String {
    fn from(body: Body) -> String {
        body.name()
    }
}

impl TryFrom<String> for Body {
    type Error = String;

    /// The body that [`Body::name`] names `name`.
    fn try_from(name: String) -> Result<Body, String> {
        // A numbered body: `prefix` then a number from 1 written without sign or leading zero.
        let numbered = |prefix: &str| {
            name.strip_prefix(prefix)
                .filter(|k| !k.starts_with('0') && !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|k| k.parse::<usize>().ok())
        };
        match name.as_str() {
            "left-wall" => Ok(Body::LeftWall),
            "right-wall" => Ok(Body::RightWall),
            "floor" => Ok(Body::Floor),
            "ceiling" => Ok(Body::Ceiling),
            "front-wall" => Ok(Body::FrontWall),
            "back-wall" => Ok(Body::BackWall),
            _ => numbered("ball").map(|k| Body::Ball(k - 1)).or_else(|| numbered("divider").map(Body::Divider)).ok_or_else(|| {
                format!(
                    "no body is named `{name}`: a body is `left-wall`, `right-wall`, `floor`, `ceiling`, `front-wall`, `back-wall`, `divider1`, ... or `ball1`, `ball2`, ..."
                )
            }),
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

/// The pairs of neighbours that can touch on a scene's chains, each chain in its own channel
/// between the container's walls: chain `k`, whose balls are `s_k .. s_k + n_k`, has the pairs
/// `s_k + k ..= s_k + k + n_k` (its left wall and first ball, its neighbours, its last ball
/// and its right wall), so ball `i` of chain `k` has pair `i + k` on its left and `i + k + 1`
/// on its right. On one chain this is [`pair_range`] and [`pair_bodies`]. Chains are coupled
/// only through the walls, which are all the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Pairs {
    /// The ball left of each pair, `None` for a wall.
    left: Vec<Option<usize>>,
    /// The ball right of each pair, `None` for a wall.
    right: Vec<Option<usize>>,
    /// The pair left of each ball.
    left_of_ball: Vec<usize>,
    /// The pairs that can touch.
    range: std::ops::Range<usize>,
}

impl Pairs {
    /// The pairs of `n` balls on the chains starting at `chain_starts`, with or without walls
    /// (balls without walls are on one chain).
    pub fn new(n: usize, chain_starts: &[usize], walls: bool) -> Pairs {
        let chains = chain_starts.len().max(1);
        let count = n + chains;
        let (mut left, mut right) = (vec![None; count], vec![None; count]);
        let mut left_of_ball = vec![0; n];
        for i in 0..n {
            let k = chain_starts.partition_point(|&s| s <= i).saturating_sub(1);
            let first = chain_starts.get(k).is_none_or(|&s| s == i);
            let last = chain_starts.get(k + 1).map_or(i + 1 == n, |&s| s == i + 1);
            let p = i + k;
            left_of_ball[i] = p;
            right[p] = Some(i);
            left[p + 1] = Some(i);
            debug_assert!(!first || left[p].is_none());
            debug_assert!(!last || right[p + 1].is_none());
        }
        let range = if walls { 0..count } else { 1..n.max(1) };
        Pairs { left, right, left_of_ball, range }
    }

    /// The pairs that can touch.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.range.clone()
    }

    /// How many pair slots there are (the walls' included, touchable or not).
    pub fn count(&self) -> usize {
        self.left.len()
    }

    /// The balls either side of pair `p`, `None` for a wall.
    #[inline(always)]
    pub fn balls(&self, p: usize) -> (Option<usize>, Option<usize>) {
        (self.left[p], self.right[p])
    }

    /// The pair left of ball `i`; the pair right of it is the next.
    #[inline(always)]
    pub fn left_of(&self, i: usize) -> usize {
        self.left_of_ball[i]
    }

    /// The bodies either side of pair `p`.
    pub fn bodies(&self, p: usize) -> (Body, Body) {
        (self.left[p].map_or(Body::LeftWall, Body::Ball), self.right[p].map_or(Body::RightWall, Body::Ball))
    }

    /// The gap across pair `p` of balls `balls` at centres `x`, with the container's walls at
    /// `(left wall, length)` when there are walls, m (`None` for a wall pair without walls).
    pub fn gap(&self, balls: &[Ball], x: &[f64], walls: Option<(f64, f64)>, p: usize) -> Option<f64> {
        match (self.balls(p), walls) {
            ((Some(i), Some(j)), _) => Some(x[j] - balls[j].radius - x[i] - balls[i].radius),
            ((None, Some(j)), Some((xs, _))) => Some(x[j] - balls[j].radius - xs),
            ((Some(i), None), Some((xs, length))) => Some(xs + length - x[i] - balls[i].radius),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body is written by its name and read back from it; a name no body has is refused.
    #[test]
    fn bodies_are_read_back_from_their_names() {
        for body in [
            Body::LeftWall,
            Body::RightWall,
            Body::Floor,
            Body::Ceiling,
            Body::FrontWall,
            Body::BackWall,
            Body::Divider(2),
            Body::Ball(0),
            Body::Ball(11),
        ] {
            let json = serde_json::to_string(&body).unwrap();
            assert_eq!(json, format!("\"{}\"", body.name()));
            assert_eq!(serde_json::from_str::<Body>(&json).unwrap(), body);
        }
        for name in ["ball0", "ball", "ball+1", "ball1x", "wall", "Ball1", "side-wall", "divider0", "divider01"] {
            assert!(Body::try_from(name.to_string()).unwrap_err().contains(name), "{name}");
        }
    }

    #[test]
    fn one_chain_pairs_are_the_line_pairs() {
        let balls = vec![Ball { mass: 1.0, radius: 0.1, kind: BallKind::Large }; 4];
        let x = [0.2, 0.5, 0.8, 1.1];
        for walls in [true, false] {
            let pairs = Pairs::new(4, &[0], walls);
            assert_eq!(pairs.range(), pair_range(4, walls));
            for p in pairs.range() {
                assert_eq!(pairs.bodies(p), pair_bodies(p, 4));
                let w = walls.then_some((0.0, 1.3));
                assert_eq!(pairs.gap(&balls, &x, w, p), pair_gap(&balls, &x, w, p));
            }
        }
    }

    #[test]
    fn chains_touch_only_their_own_walls_and_neighbours() {
        // Chains of 2, 1 and 3 balls: pairs 0-2, 3-4 and 5-8.
        let pairs = Pairs::new(6, &[0, 2, 3], true);
        assert_eq!(pairs.range(), 0..9);
        let expect = [
            (None, Some(0)),
            (Some(0), Some(1)),
            (Some(1), None),
            (None, Some(2)),
            (Some(2), None),
            (None, Some(3)),
            (Some(3), Some(4)),
            (Some(4), Some(5)),
            (Some(5), None),
        ];
        for (p, e) in expect.iter().enumerate() {
            assert_eq!(pairs.balls(p), *e, "pair {p}");
        }
        for i in 0..6 {
            assert_eq!(pairs.balls(pairs.left_of(i)).1, Some(i));
            assert_eq!(pairs.balls(pairs.left_of(i) + 1).0, Some(i));
        }
    }
}
