//! The contacts of a step and their impacts (docs/MODEL.md §3 along each contact's normal).
//! Rapier solves every contact plastically; after its step, a contact whose approach Rapier
//! stopped in the step, faster than a resting contact's, is an impact: the pair's
//! relative normal velocity is set to `e` times its approach speed by an impulse along the
//! normal, with both bodies' masses (a wall is the frame, of inverse mass `n_x^2 / M` along
//! the normal). Tangential velocities stay Rapier's (friction). Touching pairs that the
//! impacts set approaching are then struck in turn, the fastest first, as in §3.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::cells::Cells;
use crate::scene::{Chamber, Wall};

/// What a ball touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Other {
    /// Another ball, of larger index.
    Ball(usize),
    /// A wall of the frame.
    Wall(Wall),
}

/// A ball touching something at the end of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// The ball (the smaller index of a ball pair).
    pub ball: usize,
    /// What it touches.
    pub other: Other,
    /// Gap between the surfaces, m (negative when they overlap).
    pub gap: f64,
    /// Unit normal from the ball towards the other body.
    pub normal: [f64; 3],
}

/// The balls' state the impacts change: linear velocities, and their masses.
pub struct Balls<'a> {
    /// Velocities, m/s.
    pub v: &'a mut [[f64; 3]],
    /// Masses, kg.
    pub mass: &'a [f64],
}

/// Where each ball's container is: ball `i` is in damper `damper[i]`, whose inside is
/// `chambers[damper[i]]` with its left wall at `xs[damper[i]]`.
#[derive(Clone, Copy)]
pub struct Containers<'a> {
    /// Each damper's inside.
    pub chambers: &'a [Chamber],
    /// Each ball's damper.
    pub damper: &'a [u32],
    /// Each damper's left wall along x, m.
    pub xs: &'a [f64],
}

/// Finds the contacts of a step on a grid of cells over the container, kept between steps and
/// made anew with wider cells when a step asks for a longer reach: every step costs what its
/// balls do, whatever the bed's shape.
#[derive(Default)]
pub struct Finder {
    cells: Option<(Cells, f64)>,
    /// The balls in the cells' order, so that the search around a ball reads them in sequence.
    in_cells: Vec<Nearby>,
}

/// A ball as the search around another reads it.
#[derive(Clone, Copy)]
struct Nearby {
    index: u32,
    damper: u32,
    x: [f64; 3],
    radius: f64,
}

impl Finder {
    /// Finds every pair closer than `touching` (balls and walls) into `out`: each ball's walls,
    /// then the balls of larger index it touches; only balls of one damper touch (the dampers'
    /// insides overlay each other in the cells).
    pub fn find(&mut self, containers: Containers, x: &[[f64; 3]], radius: &[f64], touching: f64, out: &mut Vec<Contact>) {
        let Containers { chambers, damper, xs } = containers;
        out.clear();
        let n = x.len();
        let largest = chambers.iter().map(|c| c.largest_radius).fold(0.0, f64::max);
        let reach = 2.0 * largest + touching;
        if self.cells.as_ref().is_none_or(|(_, width)| *width < reach) {
            // Wider than asked, so that a slowly growing reach does not make the grid anew each step.
            let width = 1.25 * reach;
            let inside = chambers.iter().fold([0.0f64; 3], |m, c| [m[0].max(c.length), m[1].max(c.width), m[2].max(c.height)]);
            self.cells = Some((Cells::new(inside, width, n), width));
        }
        let Some((cells, _)) = self.cells.as_mut() else { return };
        let local = |i: usize| [x[i][0] - xs[damper[i] as usize], x[i][1], x[i][2]];
        cells.rebuild(local);
        self.in_cells.clear();
        self.in_cells.extend(cells.items().iter().map(|&j| {
            let k = j as usize;
            Nearby { index: j, damper: damper[k], x: x[k], radius: radius[k] }
        }));
        for i in 0..n {
            let p = local(i);
            let geometry = &chambers[damper[i] as usize];
            for wall in geometry.walls_near(p) {
                let (gap, normal) = geometry.gap(wall, p, radius[i]);
                if gap <= touching {
                    out.push(Contact { ball: i, other: Other::Wall(wall), gap, normal });
                }
            }
            // Balls farther than the largest radius and `touching` from this ball's surface
            // cannot touch it: the cells beyond are passed over.
            let in_cells = &self.in_cells;
            cells.runs_within(i, p, radius[i] + largest + touching, |run| {
                for other in &in_cells[run] {
                    let j = other.index as usize;
                    if j <= i || other.damper != damper[i] {
                        continue;
                    }
                    let d = [other.x[0] - x[i][0], other.x[1] - x[i][1], other.x[2] - x[i][2]];
                    let squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    // Most balls of the cells around are farther than touching: they are passed
                    // over without a square root, with a margin far above its rounding.
                    let far = radius[i] + other.radius + touching;
                    if squared > far * far * (1.0 + 1e-9) {
                        continue;
                    }
                    let dist = squared.sqrt();
                    let gap = dist - radius[i] - other.radius;
                    if gap <= touching && dist > 0.0 {
                        out.push(Contact { ball: i, other: Other::Ball(j), gap, normal: d.map(|c| c / dist) });
                    }
                }
            });
        }
    }
}

/// Counts into `near` how many of `found` each ball is in, and into `held` how many of them
/// touch (closer than `touching`).
pub fn count(found: &[Contact], touching: f64, near: &mut [u32], held: &mut [u32]) {
    near.iter_mut().chain(held.iter_mut()).for_each(|count| *count = 0);
    for c in found {
        let touches = u32::from(c.gap <= touching);
        near[c.ball] += 1;
        held[c.ball] += touches;
        if let Other::Ball(j) = c.other {
            near[j] += 1;
            held[j] += touches;
        }
    }
}

/// A contact between balls whose normal has at least this component along gravity leans across
/// it: one ball rests partly on the other (a row lying on the floor has none, to round-off).
pub const PILE_LEANING: f64 = 1e-3;

/// Whether a wall whose normal (from the ball) is `normal` is a floor under gravity of unit
/// direction `down`: gravity presses a ball straight onto it, its normal leaning across
/// gravity by less than [`PILE_LEANING`].
pub fn is_floor(normal: [f64; 3], down: [f64; 3]) -> bool {
    let along = dot(normal, down);
    along > 0.0 && 1.0 - along * along < PILE_LEANING * PILE_LEANING
}

/// Marks in `in_pile` (one flag a ball) the balls of `found` in a pile: those touching (closer
/// than `touching`) a ball along a normal that leans across gravity, of unit direction `down`,
/// by [`PILE_LEANING`] or more. The weight such a contact carries presses the balls' other
/// contacts, whatever their direction.
pub fn mark_piles(found: &[Contact], touching: f64, down: [f64; 3], in_pile: &mut [bool]) {
    in_pile.iter_mut().for_each(|p| *p = false);
    for c in found {
        if let Other::Ball(j) = c.other {
            if c.gap <= touching && dot(c.normal, down).abs() >= PILE_LEANING {
                in_pile[c.ball] = true;
                in_pile[j] = true;
            }
        }
    }
}

/// The dot product of two vectors.
pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The bodies that carry the walls (the frame, or the floors that carry dampers): each one's
/// velocity along x and mass, and which of them carries each ball's walls.
pub struct FrameBody<'a> {
    /// Velocities, m/s.
    pub vs: Vec<f64>,
    /// Masses, kg.
    pub mass: &'a [f64],
    /// The body that carries each ball's walls.
    pub of_ball: &'a [usize],
}

/// Relative normal velocity of contact `c` (the other body's less the ball's, along the
/// normal: negative when they approach) and the pair's inverse masses along the normal.
pub fn relative(c: &Contact, balls: &Balls, frame: &FrameBody) -> (f64, f64, f64) {
    let n = c.normal;
    let inv_a = 1.0 / balls.mass[c.ball];
    match c.other {
        Other::Ball(j) => (dot(balls.v[j], n) - dot(balls.v[c.ball], n), inv_a, 1.0 / balls.mass[j]),
        Other::Wall(_) => {
            let body = frame.of_ball[c.ball];
            (n[0] * frame.vs[body] - dot(balls.v[c.ball], n), inv_a, n[0] * n[0] / frame.mass[body])
        }
    }
}

/// Applies the impulse `j` (N s, pushing the pair apart along the normal) to contact `c`.
pub fn push_apart(c: &Contact, j: f64, balls: &mut Balls, frame: &mut FrameBody) {
    let n = c.normal;
    let ma = balls.mass[c.ball];
    for (a, &nk) in n.iter().enumerate() {
        balls.v[c.ball][a] -= j * nk / ma;
    }
    match c.other {
        Other::Ball(b) => {
            let mb = balls.mass[b];
            for (a, &nk) in n.iter().enumerate() {
                balls.v[b][a] += j * nk / mb;
            }
        }
        Other::Wall(_) => {
            let body = frame.of_ball[c.ball];
            frame.vs[body] += j * n[0] / frame.mass[body];
        }
    }
}

/// One impact: the pair's relative normal velocity set to `e` times `approach` (the speed at
/// which it closed), whatever Rapier left it at. Returns the energy Eq. 9-10 take from an
/// impact at that speed, `(1 - e^2)/2 mu approach^2`.
pub fn strike(c: &Contact, approach: f64, e: f64, balls: &mut Balls, frame: &mut FrameBody) -> f64 {
    let (w, inv_a, inv_b) = relative(c, balls, frame);
    let inv = inv_a + inv_b;
    push_apart(c, (e * approach - w) / inv, balls, frame);
    0.5 * (1.0 - e * e) * approach * approach / inv
}

/// The speed at which a contact closes, from its gap `gap0` and relative normal velocity
/// `w0` at the step's start and the relative acceleration `-g_n` along the normal (gravity
/// pulls a ball towards a wall, not towards another ball): the approach speed at the instant
/// the free flight closes the gap (within the step, or just after it when Rapier stopped the
/// pair short of contact; at the step's end when the flight never closes it; at its start
/// when it was closed already).
pub fn closing_speed(gap0: f64, w0: f64, g_n: f64, h: f64) -> f64 {
    closing(gap0, w0, g_n, h).1
}

/// [`closing_speed`] and the time into the step at which the contact closes, s.
pub fn closing(gap0: f64, w0: f64, g_n: f64, h: f64) -> (f64, f64) {
    // gap(t) = gap0 + w0 t - g_n t^2 / 2.
    let tau = if gap0 <= 0.0 {
        0.0
    } else if g_n.abs() < 1e-300 {
        if w0 < 0.0 {
            -gap0 / w0
        } else {
            h
        }
    } else {
        let disc = w0 * w0 + 2.0 * g_n * gap0;
        if disc < 0.0 {
            h
        } else {
            // The roots of g_n t^2 / 2 - w0 t - gap0, in the form that keeps a small g_n's
            // root from cancelling to zero: q t = -gap0 and (g_n / 2) t = q.
            let q = 0.5 * (w0 + w0.signum() * disc.sqrt());
            let roots = [q / (0.5 * g_n), if q != 0.0 { -gap0 / q } else { f64::INFINITY }];
            let first = roots.into_iter().filter(|t| *t >= 0.0).fold(f64::INFINITY, f64::min);
            if first.is_finite() {
                first
            } else {
                h
            }
        }
    };
    (tau, -(w0 - g_n * tau))
}

/// The unit direction from one ball's centre to the other's at the instant free flight brings
/// them to touch, from the offset `d` of their centres and their relative velocity `dv` now and
/// the sum `reach` of their radii: `None` when they touch already, or free flight does not bring
/// them to touch within `within` seconds.
pub fn touching_normal(d: [f64; 3], dv: [f64; 3], reach: f64, within: f64) -> Option<[f64; 3]> {
    // |d + dv t| = reach: a t^2 + 2 b t + c = 0.
    let (a, b, c) = (dot(dv, dv), dot(d, dv), dot(d, d) - reach * reach);
    let disc = b * b - a * c;
    if c <= 0.0 || b >= 0.0 || disc < 0.0 {
        return None;
    }
    // The smaller root, in the form that keeps its digits when `a c` is small.
    let t = c / (-b + disc.sqrt());
    if t > within {
        return None;
    }
    let p: [f64; 3] = std::array::from_fn(|k| d[k] + dv[k] * t);
    let length = dot(p, p).sqrt();
    Some(p.map(|x| x / length))
}

/// A touching contact listed in the knock-on cascade's calendar: its relative normal velocity
/// when listed (negative: approaching), its index among the step's contacts and its stamp then.
#[derive(Debug, Clone, Copy)]
struct Listed {
    w: f64,
    k: usize,
    stamp: u32,
}

impl PartialEq for Listed {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Listed {}

impl PartialOrd for Listed {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Listed {
    /// The heap's greatest is the fastest approach, at a tie the first contact found.
    fn cmp(&self, other: &Self) -> Ordering {
        other.w.total_cmp(&self.w).then(other.k.cmp(&self.k))
    }
}

/// The knock-on cascade (§3 along normals): touching pairs that strikes set approaching strike
/// in turn, the fastest first, at a tie the first found. Its scratch is kept between steps.
///
/// A contact's relative velocity changes only when one of its balls is struck, except against
/// an end wall, whose velocity is the frame's and changes with every end-wall strike. So the
/// contacts between balls and with the side walls wait in a calendar ordered by approach,
/// entered again with a new stamp whenever one of their balls is struck (an entry whose stamp
/// is old, or that does not approach, is dropped as it surfaces), and the few touching an end
/// wall are looked at afresh before each strike. A cascade costs what it reaches, a logarithm
/// per contact, not every listed contact at each strike.
#[derive(Debug, Default)]
pub struct Cascade {
    /// Each ball's touching contacts.
    by_ball: Vec<Vec<usize>>,
    calendar: BinaryHeap<Listed>,
    /// Each contact's stamp: how many times its balls were struck in the cascade.
    stamp: Vec<u32>,
    /// The end-wall contacts of the balls struck so far, and whether each contact is among them.
    end_walls: Vec<usize>,
    listed: Vec<bool>,
}

/// Whether `c` is a contact with a wall that moves along its normal (an end wall).
fn moves_with_frame(c: &Contact) -> bool {
    matches!(c.other, Other::Wall(_)) && c.normal[0] != 0.0
}

impl Cascade {
    /// Strikes, one at a time and the fastest first, the contacts of `found` that `touches`
    /// accepts and that approach faster than `resting(contact)`, beginning with those of the
    /// `kicked` balls and going on to those of each ball struck, until none approaches or after
    /// four strikes a contact on average (a collapse within the step). `strike` applies one
    /// strike, given the contact and its approach speed; struck balls are marked in `kicked`.
    pub fn run(
        &mut self,
        found: &[Contact],
        touches: impl Fn(&Contact) -> bool,
        kicked: &mut [bool],
        resting: impl Fn(&Contact) -> f64,
        bodies: (&mut Balls, &mut FrameBody),
        mut strike: impl FnMut(&Contact, f64, &mut Balls, &mut FrameBody),
    ) {
        let (balls, frame) = bodies;
        let n = kicked.len();
        self.by_ball.resize_with(n, Vec::new);
        self.by_ball.iter_mut().for_each(|list| list.clear());
        for (k, c) in found.iter().enumerate() {
            if touches(c) {
                self.by_ball[c.ball].push(k);
                if let Other::Ball(j) = c.other {
                    self.by_ball[j].push(k);
                }
            }
        }
        self.calendar.clear();
        self.stamp.clear();
        self.stamp.resize(found.len(), 0);
        self.end_walls.clear();
        self.listed.clear();
        self.listed.resize(found.len(), false);
        for i in 0..n {
            if kicked[i] {
                self.list(i, found, &resting, balls, frame);
            }
        }
        let cap = 4 * found.len() + 16;
        for _ in 0..cap {
            // The calendar's fastest valid approach, and the fastest approach on an end wall.
            let mut fastest: Option<(f64, usize)> = None;
            while let Some(top) = self.calendar.peek() {
                let c = &found[top.k];
                if top.stamp == self.stamp[top.k] && top.w < -resting(c) {
                    fastest = Some((top.w, top.k));
                    break;
                }
                self.calendar.pop();
            }
            let from_calendar = fastest.is_some();
            for &k in &self.end_walls {
                let c = &found[k];
                let w = relative(c, balls, frame).0;
                if w < -resting(c) && fastest.is_none_or(|(fw, fk)| w.total_cmp(&fw).then(k.cmp(&fk)).is_lt()) {
                    fastest = Some((w, k));
                }
            }
            let Some((w, k)) = fastest else { break };
            if from_calendar && self.calendar.peek().is_some_and(|top| top.k == k) {
                self.calendar.pop();
            }
            let c = found[k];
            strike(&c, -w, balls, frame);
            kicked[c.ball] = true;
            self.list(c.ball, found, &resting, balls, frame);
            if let Other::Ball(j) = c.other {
                kicked[j] = true;
                self.list(j, found, &resting, balls, frame);
            }
        }
    }

    /// Lists ball `i`'s touching contacts as they stand now: the end-wall ones once, the
    /// others in the calendar with a new stamp when they approach.
    fn list(&mut self, i: usize, found: &[Contact], resting: &impl Fn(&Contact) -> f64, balls: &Balls, frame: &FrameBody) {
        for &k in &self.by_ball[i] {
            let c = &found[k];
            if moves_with_frame(c) {
                if !self.listed[k] {
                    self.listed[k] = true;
                    self.end_walls.push(k);
                }
                continue;
            }
            self.stamp[k] += 1;
            let w = relative(c, balls, frame).0;
            if w < -resting(c) {
                self.calendar.push(Listed { w, k, stamp: self.stamp[k] });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// A contact under a tiny acceleration along its normal (a heavy frame's, 1e-12 m/s^2)
    /// closes when its free flight does: the quadratic's root cancelled to zero, so a wall a
    /// step away was struck at the step's start, as the walls moved then.
    #[test]
    fn a_contact_under_a_tiny_acceleration_closes_when_its_flight_does() {
        for g_n in [1e-12, -1e-12, 1e-3] {
            let (tau, approach) = closing(1.216e-3, -1.0, g_n, 1e-3);
            let flight = 1.216e-3 * (1.0 - 0.5 * g_n * 1.216e-3);
            assert!((tau - flight).abs() <= 1e-9 * flight, "g_n {g_n}: closes at {tau} s, not {flight} s");
            assert!((approach - (1.0 + g_n * tau)).abs() <= 1e-12, "g_n {g_n}: approach {approach} m/s");
        }
    }

    /// A lattice of touching balls, `nx` by `ny` by `nz`, with its contacts: neighbours along
    /// each axis, the left and right end walls at the first and last columns, the floor under
    /// the first layer. Random masses, and random velocities, some approaching.
    fn pile(rng: &mut Pcg64, nx: usize, ny: usize, nz: usize) -> (Vec<Contact>, Vec<[f64; 3]>, Vec<f64>) {
        let index = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        let n = nx * ny * nz;
        let mut found = Vec::new();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = index(x, y, z);
                    if x == 0 {
                        found.push(Contact { ball: i, other: Other::Wall(Wall::Left), gap: 0.0, normal: [-1.0, 0.0, 0.0] });
                    }
                    if x + 1 == nx {
                        found.push(Contact { ball: i, other: Other::Wall(Wall::Right), gap: 0.0, normal: [1.0, 0.0, 0.0] });
                    }
                    if z == 0 {
                        found.push(Contact { ball: i, other: Other::Wall(Wall::Floor), gap: 0.0, normal: [0.0, 0.0, -1.0] });
                    }
                    let mut neighbour = |j: usize, normal: [f64; 3]| {
                        // A few pairs stand a little apart: not touching, never struck.
                        let gap = if rng.random::<f64>() < 0.1 { 1e-3 } else { 0.0 };
                        found.push(Contact { ball: i, other: Other::Ball(j), gap, normal });
                    };
                    if x + 1 < nx {
                        neighbour(index(x + 1, y, z), [1.0, 0.0, 0.0]);
                    }
                    if y + 1 < ny {
                        neighbour(index(x, y + 1, z), [0.0, 1.0, 0.0]);
                    }
                    if z + 1 < nz {
                        neighbour(index(x, y, z + 1), [0.0, 0.0, 1.0]);
                    }
                }
            }
        }
        let v = (0..n).map(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0))).collect();
        let mass = (0..n).map(|_| rng.random_range(0.5..2.0)).collect();
        (found, v, mass)
    }

    /// The cascade's rule, stated plainly: before each strike, every listed contact is looked
    /// at afresh and the fastest approach strikes, at a tie the first found; a contact is
    /// listed once one of its balls is kicked or struck.
    fn cascade_by_scan(
        found: &[Contact],
        touching: f64,
        kicked: &mut [bool],
        resting: impl Fn(&Contact) -> f64,
        balls: &mut Balls,
        frame: &mut FrameBody,
        e: f64,
    ) -> Vec<(usize, f64)> {
        let mut listed = vec![false; found.len()];
        let list = |i: usize, listed: &mut Vec<bool>| {
            for (k, c) in found.iter().enumerate() {
                if c.gap <= touching && (c.ball == i || c.other == Other::Ball(i)) {
                    listed[k] = true;
                }
            }
        };
        for i in 0..kicked.len() {
            if kicked[i] {
                list(i, &mut listed);
            }
        }
        let mut strikes = Vec::new();
        for _ in 0..4 * found.len() + 16 {
            let mut fastest: Option<(f64, usize)> = None;
            for (k, c) in found.iter().enumerate() {
                let w = relative(c, balls, frame).0;
                if listed[k] && w < -resting(c) && fastest.is_none_or(|(fw, fk)| w.total_cmp(&fw).then(k.cmp(&fk)).is_lt()) {
                    fastest = Some((w, k));
                }
            }
            let Some((w, k)) = fastest else { break };
            let c = found[k];
            strike(&c, -w, e, balls, frame);
            strikes.push((k, -w));
            kicked[c.ball] = true;
            list(c.ball, &mut listed);
            if let Other::Ball(j) = c.other {
                kicked[j] = true;
                list(j, &mut listed);
            }
        }
        strikes
    }

    /// The calendar strikes the same contacts in the same order, at the same speeds, as the
    /// plain statement of the rule, on piles of every shape with end walls and a floor.
    #[test]
    fn the_calendar_strikes_as_the_rule_states() {
        let mut rng = Pcg64::seed_from_u64(30);
        let resting = |c: &Contact| 0.05 * c.normal[2].abs() + 0.1 * c.normal[0].abs() + 1e-9;
        for _ in 0..300 {
            let (nx, ny, nz) = (rng.random_range(1..6), rng.random_range(1..4), rng.random_range(1..5));
            let (found, v, mass) = pile(&mut rng, nx, ny, nz);
            let n = v.len();
            let e = [0.0, 0.6, 1.0][rng.random_range(0..3)];
            let kicked: Vec<bool> = (0..n).map(|_| rng.random::<f64>() < 0.3).collect();
            let frame_vs = rng.random_range(-1.0..1.0);
            let frame_mass = [1e-3, 1.0, 1e6][rng.random_range(0..3)];

            let (mut v_scan, mut kicked_scan) = (v.clone(), kicked.clone());
            let on_frame = vec![0; n];
            let mut frame_scan = FrameBody { vs: vec![frame_vs], mass: &[frame_mass], of_ball: &on_frame };
            let mut balls = Balls { v: &mut v_scan, mass: &mass };
            let expected = cascade_by_scan(&found, 0.0, &mut kicked_scan, resting, &mut balls, &mut frame_scan, e);

            let (mut v_cal, mut kicked_cal) = (v.clone(), kicked.clone());
            let mut frame_cal = FrameBody { vs: vec![frame_vs], mass: &[frame_mass], of_ball: &on_frame };
            let mut balls = Balls { v: &mut v_cal, mass: &mass };
            let mut strikes = Vec::new();
            let mut cascade = Cascade::default();
            let touches = |c: &Contact| c.gap <= 0.0;
            cascade.run(&found, touches, &mut kicked_cal, resting, (&mut balls, &mut frame_cal), |c, approach, balls, frame| {
                let k = found.iter().position(|f| f == c).unwrap();
                strikes.push((k, approach));
                strike(c, approach, e, balls, frame);
            });
            assert_eq!(strikes, expected, "{nx} x {ny} x {nz}");
            assert_eq!(v_cal, v_scan);
            assert_eq!(kicked_cal, kicked_scan);
            assert_eq!(frame_cal.vs[0].to_bits(), frame_scan.vs[0].to_bits());
        }
    }
}
