//! The container's inside in the frame's coordinates (origin at the left wall's inner face on
//! the container's axis): its walls and the dividers between chains, and the gap and normal
//! from a ball to each of them, stated once for every model that moves balls off their lines.

use super::{Body, Damper, Scene};

/// A wall of the container, or a divider between chains `k - 1` and `k`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Wall {
    /// The inner face at x = 0.
    Left,
    /// The inner face at x = length.
    Right,
    /// y = -width / 2.
    Front,
    /// y = +width / 2.
    Back,
    /// z = -height / 2.
    Floor,
    /// z = +height / 2.
    Ceiling,
    /// The divider at y = -width / 2 + k channel.
    Divider(usize),
}

impl Wall {
    /// How impacts name the wall.
    pub fn body(self) -> Body {
        match self {
            Wall::Left => Body::LeftWall,
            Wall::Right => Body::RightWall,
            Wall::Front => Body::FrontWall,
            Wall::Back => Body::BackWall,
            Wall::Floor => Body::Floor,
            Wall::Ceiling => Body::Ceiling,
            Wall::Divider(k) => Body::Divider(k),
        }
    }
}

/// The container's inside: its size, its chains' channels and the dividers between them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chamber {
    /// Inner length along x, m.
    pub length: f64,
    /// Inner width along y, m.
    pub width: f64,
    /// Inner height along z, m.
    pub height: f64,
    /// Number of chains (a divider between each two).
    pub chains: usize,
    /// Width of each chain's channel, m (the width for one chain).
    pub channel: f64,
    /// Half the thickness of a divider, m.
    pub divider_half_thickness: f64,
    /// Largest ball radius, m.
    pub largest_radius: f64,
}

/// Dividers take this fraction of a channel at most: they are thin.
const DIVIDER_FRACTION: f64 = 0.01;

impl Chamber {
    /// The inside of `scene`'s container (its first damper's), or why it has none beyond a
    /// line.
    pub fn new(scene: &Scene) -> Result<Chamber, String> {
        match scene.damper_list().first() {
            Some(d) => Chamber::of_damper(scene, d),
            None => Err("the scene has no container".into()),
        }
    }

    /// The inside of damper `d`'s container, or why it has none beyond a line.
    pub fn of_damper(scene: &Scene, d: &Damper) -> Result<Chamber, String> {
        let [width, height] = d.section;
        if !(width > 0.0 && height > 0.0) {
            return Err("the scene gives the container no cross-section (width and height)".into());
        }
        let starts = &scene.space.chain_starts;
        let chains = starts.iter().filter(|&&s| d.balls.contains(&s)).count().max(1);
        let channel = if chains > 1 { d.channel } else { width };
        let largest_radius = scene.balls[d.balls.clone()].iter().map(|b| b.radius).fold(0.0, f64::max);
        // A divider fits in what the balls leave of their channels, each side half of it.
        let divider_half_thickness = (DIVIDER_FRACTION * channel).min(0.25 * (channel - 2.0 * largest_radius));
        if chains > 1 && divider_half_thickness <= 1e-6 * channel {
            return Err(format!(
                "its channels ({} m) are as narrow as its largest ball: no room for the dividers between the chains; widen the container",
                super::human(channel)
            ));
        }
        Ok(Chamber { length: d.container.length, width, height, chains, channel, divider_half_thickness, largest_radius })
    }

    /// The length of the inside's diagonal, m: the farthest a ball can fall or be thrown in it.
    pub fn diagonal(&self) -> f64 {
        (self.length * self.length + self.width * self.width + self.height * self.height).sqrt()
    }

    /// Every wall and divider.
    pub fn walls(&self) -> impl Iterator<Item = Wall> + use<> {
        [Wall::Left, Wall::Right, Wall::Front, Wall::Back, Wall::Floor, Wall::Ceiling]
            .into_iter()
            .chain((1..self.chains).map(Wall::Divider))
    }

    /// The centre of divider `k` along y, m.
    pub fn divider_y(&self, k: usize) -> f64 {
        -0.5 * self.width + k as f64 * self.channel
    }

    /// The walls a ball at `p` (frame coordinates) may touch: the six walls and the dividers
    /// either side of its channel.
    pub fn walls_near(&self, p: [f64; 3]) -> impl Iterator<Item = Wall> + use<> {
        let channel = ((p[1] + 0.5 * self.width) / self.channel).floor().clamp(0.0, (self.chains - 1) as f64) as usize;
        let chains = self.chains;
        let dividers = [channel, channel + 1].into_iter().filter(move |&k| k >= 1 && k < chains).map(Wall::Divider);
        [Wall::Left, Wall::Right, Wall::Front, Wall::Back, Wall::Floor, Wall::Ceiling].into_iter().chain(dividers)
    }

    /// The gap between a ball of radius `r` centred at `p` (frame coordinates) and `wall`, m,
    /// and the unit normal pointing from the ball to the wall.
    pub fn gap(&self, wall: Wall, p: [f64; 3], r: f64) -> (f64, [f64; 3]) {
        let (hw, hh) = (0.5 * self.width, 0.5 * self.height);
        match wall {
            Wall::Left => (p[0] - r, [-1.0, 0.0, 0.0]),
            Wall::Right => (self.length - p[0] - r, [1.0, 0.0, 0.0]),
            Wall::Front => (p[1] + hw - r, [0.0, -1.0, 0.0]),
            Wall::Back => (hw - p[1] - r, [0.0, 1.0, 0.0]),
            Wall::Floor => (p[2] + hh - r, [0.0, 0.0, -1.0]),
            Wall::Ceiling => (hh - p[2] - r, [0.0, 0.0, 1.0]),
            Wall::Divider(k) => {
                let y = self.divider_y(k);
                if p[1] < y {
                    (y - self.divider_half_thickness - p[1] - r, [0.0, 1.0, 0.0])
                } else {
                    (p[1] - y - self.divider_half_thickness - r, [0.0, -1.0, 0.0])
                }
            }
        }
    }
}
