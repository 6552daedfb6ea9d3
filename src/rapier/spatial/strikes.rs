//! Strikes on touching groups (docs/MODEL.md §9, "Rapier"). Rapier solves a step's new contact
//! together with the touching contacts of the ball it strikes, so its solve passes part of the
//! strike through them at once, and the impact law applied afterwards cannot undo that. A ball
//! in flight (touching no other ball and no end wall) that will close, within two steps, on
//! exactly one ball that touches something (a row, a pile, the floor) is therefore kept out of
//! Rapier's solve of that one pair: the pair's solver contacts are removed for the step. After
//! the step the striker, which flew into the other ball, is set back along its path among the
//! walls to contact; the impact law and its knock-ons then give the sequence of §3 from
//! velocities that Rapier's solve of the pair never touched.

use bevy_rapier3d::rapier::prelude::{ColliderHandle, ContactModificationContext, PhysicsHooks};

use super::contacts::{dot, is_floor, Contact, Other};

/// A striker kept out of Rapier's solve of its pair for one step, and the ball it strikes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Strike {
    /// The ball that touches no other ball.
    pub striker: usize,
    /// The ball it closes on, which touches something.
    pub target: usize,
}

/// Finds a step's strikes from the contacts at its start, kept between steps.
#[derive(Default)]
pub struct Strikes {
    touches_ball: Vec<bool>,
    touches_any: Vec<bool>,
    touches_end_wall: Vec<bool>,
    pressed: Vec<bool>,
    held_by_wall: Vec<bool>,
    on_floor: Vec<bool>,
    closings: Vec<u32>,
    /// Each ball's partner in a strike of the step, if it is in one.
    partner: Vec<Option<usize>>,
    /// The step's strikes.
    pub list: Vec<Strike>,
}

impl Strikes {
    /// Lists the strikes of a step of length `h` from `found` (every pair closer than
    /// `touching` and those a step may close, at the step's start) and the balls' velocities
    /// `v` (ball `k`'s walls moving along x at `walls_v(k)`): pairs of balls apart by more than `touching` whose free flight closes them within
    /// two steps, approaching faster than `resting(contact)`, of which one ball (the striker)
    /// touches no other ball and no end wall (one that the frame drives is not in flight),
    /// closes on nothing else and carries half the approach or more relative to the walls, and
    /// the other touches something. A ball is in one strike at most.
    pub fn predict(
        &mut self,
        found: &[Contact],
        v: &[[f64; 3]],
        walls_v: impl Fn(usize) -> f64,
        (touching, down): (f64, [f64; 3]),
        h: f64,
        resting: impl Fn(&Contact) -> f64,
    ) {
        let n = v.len();
        self.list.clear();
        let flags = [
            &mut self.touches_ball,
            &mut self.touches_any,
            &mut self.touches_end_wall,
            &mut self.pressed,
            &mut self.held_by_wall,
            &mut self.on_floor,
        ];
        for flags in flags {
            flags.clear();
            flags.resize(n, false);
        }
        self.partner.clear();
        self.partner.resize(n, None);
        self.closings.clear();
        self.closings.resize(n, 0);
        // Within two steps of closing: the step's impacts are looked for among pairs that far
        // apart, so a pair left to Rapier's solve there could be taken for an impact early.
        let closes = |c: &Contact, j: usize| {
            let w = dot(v[j], c.normal) - dot(v[c.ball], c.normal);
            c.gap > touching && w < -resting(c) && c.gap + 2.0 * w * h <= touching
        };
        for c in found {
            match c.other {
                Other::Ball(j) if c.gap <= touching => {
                    let parting = dot(v[j], c.normal) - dot(v[c.ball], c.normal) > resting(c);
                    for k in [c.ball, j] {
                        self.touches_ball[k] = true;
                        self.touches_any[k] = true;
                        self.pressed[k] |= !parting;
                    }
                }
                Other::Ball(j) if closes(c, j) => {
                    self.closings[c.ball] += 1;
                    self.closings[j] += 1;
                }
                Other::Wall(_) if c.gap <= touching => {
                    let (w, rest) = (walls_v(c.ball) * c.normal[0] - dot(v[c.ball], c.normal), resting(c));
                    let parting = w > rest;
                    self.pressed[c.ball] |= !parting;
                    // A ball that closes on the wall faster than a resting contact strikes it.
                    let held = !parting && w >= -rest;
                    if is_floor(c.normal, down) {
                        self.on_floor[c.ball] |= held;
                    } else {
                        self.held_by_wall[c.ball] |= held;
                    }
                    self.touches_any[c.ball] = true;
                    self.touches_end_wall[c.ball] |= c.normal[0] != 0.0;
                }
                _ => {}
            }
        }
        for c in found {
            let Other::Ball(j) = c.other else { continue };
            if !closes(c, j) {
                continue;
            }
            // A striker carries at least half the pair's approach along the normal relative to
            // the walls, so that it touches the other ball no further back along its path
            // among them than two steps.
            let approach = dot(v[c.ball], c.normal) - dot(v[j], c.normal);
            let free = |k: usize| {
                let among_walls = dot(v[k], c.normal) - walls_v(k) * c.normal[0];
                let own = if k == c.ball { among_walls } else { -among_walls };
                !self.touches_ball[k] && !self.touches_end_wall[k] && self.closings[k] == 1 && own >= 0.5 * approach
            };
            // The striker is the ball that touches nothing at all when both could strike.
            let (striker, target) = match (free(c.ball), free(j)) {
                (true, true) if self.touches_any[c.ball] && !self.touches_any[j] => (j, c.ball),
                (true, _) => (c.ball, j),
                (false, true) => (j, c.ball),
                (false, false) => continue,
            };
            // Two free balls meet exactly in Rapier's solve of their pair alone.
            if !self.touches_any[target] || self.partner[striker].is_some() || self.partner[target].is_some() {
                continue;
            }
            self.partner[striker] = Some(target);
            self.partner[target] = Some(striker);
            self.list.push(Strike { striker, target });
        }
    }

    /// Whether ball `i` was pressed at the step's start: it touched a ball or a wall and did
    /// not part from it faster than a resting contact.
    pub fn pressed(&self, i: usize) -> bool {
        self.pressed[i]
    }

    /// Whether ball `i` rested on a wall other than a floor at the step's start: it touched
    /// the wall and neither parted from it nor closed on it faster than a resting contact.
    pub fn held_by_wall(&self, i: usize) -> bool {
        self.held_by_wall[i]
    }

    /// Whether ball `i` rested so on a floor (a wall gravity presses it straight onto) at the
    /// step's start.
    pub fn on_floor(&self, i: usize) -> bool {
        self.on_floor[i]
    }

    /// Whether contact `c` is between the balls of one of the step's strikes.
    pub fn holds(&self, c: &Contact) -> bool {
        let Other::Ball(j) = c.other else { return false };
        self.partner.get(c.ball) == Some(&Some(j))
    }
}

/// Sets the striker of `s` back along its path among the walls (its velocity `v` at the step's
/// end, less the walls' `walls_v` along x) to where it touches the target at the step's end
/// positions `x`, no further back than two steps of `h`: a striker that slides on a wall stays
/// on it. Returns whether it moved (the pair overlapped).
pub fn bring_back(s: Strike, x: &mut [[f64; 3]], v: &[[f64; 3]], walls_v: f64, radius: &[f64], h: f64) -> bool {
    let (a, b) = (s.striker, s.target);
    let d: [f64; 3] = std::array::from_fn(|k| x[b][k] - x[a][k]);
    let u = [v[a][0] - walls_v, v[a][1], v[a][2]];
    let reach = radius[a] + radius[b];
    let (dd, du, uu) = (dot(d, d), dot(d, u), dot(u, u));
    if dd >= reach * reach || uu <= 0.0 {
        return false;
    }
    // |d + u s|^2 = reach^2 with the striker set back by `u s`.
    let back = ((-du + (du * du + uu * (reach * reach - dd)).sqrt()) / uu).clamp(0.0, 2.0 * h);
    for (k, uk) in u.iter().enumerate() {
        x[a][k] -= uk * back;
    }
    true
}

/// Rapier's hooks for a step: the solver contacts of the listed collider pairs are removed.
pub struct Unsolved<'a> {
    /// The pairs, in either order.
    pub pairs: &'a [(ColliderHandle, ColliderHandle)],
}

impl PhysicsHooks for Unsolved<'_> {
    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        let pair = (context.collider1, context.collider2);
        if self.pairs.iter().any(|&(a, b)| pair == (a, b) || pair == (b, a)) {
            context.solver_contacts.clear();
        }
    }
}
