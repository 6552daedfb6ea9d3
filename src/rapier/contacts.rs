//! The plug-in's own contact resolution, which the impact and feedback phases share: the
//! two-body law of docs/MODEL.md §3 (Eq. 9-10) applied one pair at a time, the fastest approach
//! first, until no touching pair approaches (the sequential reading of simultaneous impacts, as
//! in the reference); the booking of impacts; and the velocities written back into Rapier.
//!
//! Rapier itself is left only what it does well, keeping bodies apart: every contact it solves
//! is plastic (restitution 0). Three things it cannot do, and why the plug-in does them:
//! - a chain of touching balls struck at one end: Rapier's solve is simultaneous, so the pairs
//!   that touched at rest keep a relative velocity of zero and the chain moves off as one block
//!   instead of passing the momentum along as Newton's cradle does;
//! - a contact that persists: Rapier bounces a contact only in the step it is new, so a ball
//!   that stays within its prediction distance of a wall is struck plastically ever after;
//! - a wall impact with the frame's finite mass: the frame is kinematic in Rapier, infinitely
//!   heavy, and no restitution against it gives Eq. 9-10 for a ball heavier than `e` times the
//!   frame, or for `e = 0`; here the frame's mass enters the law itself.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::RigidBodyHandle;

use crate::impact_law::impact_law;
use crate::run::Impact;
use crate::scene::{pair_bodies, pair_gap, Scene};

/// Pairs closer than this are touching, m (the same tolerance the step planner aims at).
pub const TOUCHING: f64 = super::phases::plan::TOUCHING as f64;
/// Pair impacts resolved at one instant at most, per pair of the chain: a light ball squeezed
/// between heavy bodies bounces ever faster (inelastic collapse); past this the rest of the
/// approach is left to Rapier's plastic solve.
pub const MAX_SEQUENTIAL_PER_PAIR: usize = 64;

/// One impact resolved before a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairImpact {
    /// Pair index: between body `pair - 1` and body `pair` (body `-1` the left wall, `n` the right).
    pub pair: usize,
    /// Relative speed of approach before, m/s.
    pub approach_speed: f64,
    /// Kinetic energy lost, J.
    pub energy_lost: f64,
    /// Gap across the pair when resolved (at most [`TOUCHING`]; negative if overlapping), m.
    pub gap: f64,
}

/// The bodies at one instant: the balls' positions and velocities, and the frame's
/// displacement, velocity and mass when there are walls.
pub struct Instant<'a> {
    /// Ball positions, m.
    pub x: &'a [f64],
    /// Ball velocities, m/s (changed in place).
    pub v: &'a mut [f64],
    /// `(xs, vs, ms, container length)` when the balls are in a container on a frame.
    pub frame: Option<(f64, &'a mut f64, f64, f64)>,
}

impl Instant<'_> {
    fn n(&self) -> usize {
        self.x.len()
    }

    /// Gap across `pair`, m (`None` for a wall pair without walls).
    fn gap(&self, scene: &Scene, pair: usize) -> Option<f64> {
        pair_gap(&scene.balls, self.x, self.frame.as_ref().map(|(xs, _, _, length)| (*xs, *length)), pair)
    }

    /// Mass and velocity of body `body` (-1 and n are the frame).
    fn body(&self, scene: &Scene, body: isize) -> (f64, f64) {
        if body < 0 || body as usize >= self.n() {
            let (_, vs, ms, _) = self.frame.as_ref().expect("a wall pair has a frame");
            (*ms, **vs)
        } else {
            (scene.balls[body as usize].mass, self.v[body as usize])
        }
    }

    fn set_velocity(&mut self, body: isize, v: f64) {
        if body < 0 || body as usize >= self.n() {
            if let Some((_, vs, ..)) = self.frame.as_mut() {
                **vs = v;
            }
        } else {
            self.v[body as usize] = v;
        }
    }
}

/// Resolves the impacts of the touching pairs of `now` that approach faster than
/// `threshold(pair)`, fastest first, each with Eq. 9-10; returns them in the order resolved.
pub fn resolve_touching(scene: &Scene, now: &mut Instant<'_>, threshold: impl Fn(usize) -> f64, out: &mut Vec<PairImpact>) {
    resolve_touching_with(scene, scene.restitution, now, threshold, out)
}

/// [`resolve_touching`] with restitution `e` (0 holds the pairs together).
pub fn resolve_touching_with(scene: &Scene, e: f64, now: &mut Instant<'_>, threshold: impl Fn(usize) -> f64, out: &mut Vec<PairImpact>) {
    out.clear();
    let n = now.n();
    let touching = |p: &usize| now.gap(scene, *p).is_some_and(|g| g <= TOUCHING);
    let count = (0..=n).filter(touching).count();
    let budget = MAX_SEQUENTIAL_PER_PAIR * count;
    for _ in 0..budget {
        let fastest = (0..=n)
            .filter(|p| now.gap(scene, *p).is_some_and(|g| g <= TOUCHING))
            .map(|p| {
                let ((_, va), (_, vb)) = (now.body(scene, p as isize - 1), now.body(scene, p as isize));
                (p, va - vb)
            })
            .filter(|&(p, u)| u > threshold(p))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((p, u)) = fastest else { return };
        let gap = now.gap(scene, p).unwrap_or(0.0);
        let (a, b) = (p as isize - 1, p as isize);
        let ((ma, va), (mb, vb)) = (now.body(scene, a), now.body(scene, b));
        let (va2, vb2, lost) = impact_law(ma, va, mb, vb, e);
        now.set_velocity(a, va2);
        now.set_velocity(b, vb2);
        out.push(PairImpact { pair: p, approach_speed: u, energy_lost: lost, gap });
    }
}

/// Where resolved impacts are booked.
pub struct Ledger<'a> {
    /// The run's impacts.
    pub impacts: &'a mut Vec<Impact>,
    /// Each pair's latest impact.
    pub last_impact: &'a mut [Option<usize>],
    /// The step in which each pair was last struck.
    pub struck_at: &'a mut [Option<u64>],
}

/// Books `hit`, at time `t`, in step `step`: a pair struck again in the same step or the next
/// (a sequence at one instant, a squeeze) adds to its latest impact, as one persistent
/// contact; otherwise it is a new impact.
pub fn book(ledger: Ledger<'_>, n: usize, hit: &PairImpact, t: f64, step: u64) {
    let Ledger { impacts, last_impact, struck_at } = ledger;
    let p = hit.pair;
    let persists = struck_at[p].is_some_and(|s| s + 1 >= step);
    struck_at[p] = Some(step);
    if let (true, Some(k)) = (persists, last_impact[p]) {
        impacts[k].energy_lost += hit.energy_lost;
        impacts[k].impulses += 1;
        return;
    }
    let (a, b) = pair_bodies(p, n);
    last_impact[p] = Some(impacts.len());
    impacts.push(Impact {
        t: after_the_last(impacts, t),
        a,
        b,
        approach_speed: hit.approach_speed,
        energy_lost: hit.energy_lost,
        impulses: 1,
        peak_force: None,
        contact_duration: None,
    });
}

/// `t`, or the time of the last impact booked when `t` is earlier: an impact is booked after
/// the impacts that led to it (resolved before it at the same instant, each stamped where its
/// own gap closes), so it never precedes them, and the list stays in time order.
pub fn after_the_last(impacts: &[Impact], t: f64) -> f64 {
    impacts.last().map_or(t, |last| t.max(last.t))
}

/// Persistent contacts approach slower than this many times what the frame's acceleration
/// builds over the last step.
pub const PERSISTENT_APPROACH: f64 = 2.0;
/// Approaches slower than this fraction of the scene's speed scale are round-off (f32
/// velocities in Rapier).
pub const APPROACH_FLOOR: f64 = 1e-6;

/// Approaches slower than this are round-off, m/s.
pub fn approach_floor(scene: &Scene) -> f64 {
    APPROACH_FLOOR * super::resources::speed_scale(scene)
}

/// The sticking speed over a step of `h` while the frame accelerates at `acceleration`:
/// [`PERSISTENT_APPROACH`] times what it builds in the step, at least the round-off floor.
pub fn sticking_speed(scene: &Scene, acceleration: f64, h: f64) -> f64 {
    approach_floor(scene).max(PERSISTENT_APPROACH * acceleration.abs() * h)
}

/// The corrected velocities into Rapier's bodies (rounded to what Rapier carries on with) and
/// into the balls' `Velocity` components.
pub fn write_velocities(
    set: &mut RapierRigidBodySet,
    handles: &[RigidBodyHandle],
    balls: &[Entity],
    velocities: &mut Query<&mut Velocity>,
    v_new: &mut [f64],
) {
    for (i, &h) in handles.iter().enumerate() {
        let body = &mut set.bodies[h];
        let mut lin = body.linvel();
        lin.x = v_new[i] as f32;
        body.set_linvel(lin, true);
        v_new[i] = lin.x as f64; // what Rapier will carry on with
                                 // bevy_rapier wrote the step's velocity into the ball's `Velocity` before this system
                                 // ran, and in an app driven by `app.update()` it copies a changed `Velocity` back into
                                 // the body at the next step: it must hold the corrected one.
        if let Ok(mut velocity) = velocities.get_mut(balls[i]) {
            if velocity.linear != lin {
                velocity.linear = lin;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Ball, BallKind, Container, Frame, Scene};
    use approx::assert_relative_eq;

    /// Three steel balls of `mass`, touching, in a container on a frame of `frame_mass`.
    fn touching_balls(masses: &[f64], e: f64, frame_mass: f64) -> Scene {
        let balls: Vec<Ball> =
            masses.iter().map(|&m| Ball { mass: m, radius: crate::scene::ball_radius(m, 8000.0), kind: BallKind::Custom }).collect();
        let mut x = 0.0;
        let positions = balls
            .iter()
            .map(|b| {
                x += 2.0 * b.radius;
                x - b.radius
            })
            .collect();
        Scene {
            name: "touching".into(),
            frame: Some(Frame { mass: frame_mass, stiffness: 100.0, damping: 0.0 }),
            container: Some(Container { length: x + 0.01, gap: 0.0, clearance: 0.01 }),
            initial_velocities: vec![0.0; balls.len()],
            reference_radius: balls[0].radius,
            space: crate::scene::Space::line(balls.len()),
            balls,
            restitution: e,
            initial_displacement: 0.0,
            initial_positions: positions,
            horizon: 1.0,
            sample_dt: 1e-3,
            reference: Default::default(),
            rapier: Default::default(),
            compliant: Default::default(),
            forcing: None,
            structure: None,
            dampers: vec![],
        }
    }

    /// A ball strikes two equal balls touching at rest at e = 1: the momentum passes along
    /// (Newton's cradle), where a simultaneous solve would move the two off as one block.
    #[test]
    fn touching_chain_passes_the_momentum_along() {
        let s = touching_balls(&[0.11, 0.11, 0.11], 1.0, 1.35);
        let (x, mut v) = (s.initial_positions.clone(), vec![0.5, 0.0, 0.0]);
        let mut out = Vec::new();
        resolve_touching(&s, &mut Instant { x: &x, v: &mut v, frame: None }, |_| 0.0, &mut out);
        assert_eq!(out.iter().map(|i| i.pair).collect::<Vec<_>>(), vec![1, 2]);
        assert_eq!(v, vec![0.0, 0.0, 0.5]);
        assert_eq!(out.iter().map(|i| i.energy_lost).sum::<f64>(), 0.0);
    }

    /// A wall impact uses the frame's mass: a ball heavier than `e` times the frame (which no
    /// restitution against a kinematic wall can give) gets Eq. 9-10, momentum conserved.
    #[test]
    fn wall_impact_uses_the_frame_mass() {
        let s = touching_balls(&[0.11], 0.5, 0.05);
        let length = s.container.unwrap().length;
        let (x, mut v, mut vs) = (s.initial_positions.clone(), vec![-0.3], 0.2);
        let mut out = Vec::new();
        resolve_touching(&s, &mut Instant { x: &x, v: &mut v, frame: Some((0.0, &mut vs, 0.05, length)) }, |_| 0.0, &mut out);
        let (vf, vb, lost) = impact_law(0.05, 0.2, 0.11, -0.3, 0.5);
        assert_eq!(out, vec![PairImpact { pair: 0, approach_speed: 0.5, energy_lost: lost, gap: 0.0 }]);
        assert_eq!((v[0], vs), (vb, vf));
        assert_relative_eq!(0.11 * v[0] + 0.05 * vs, 0.11 * -0.3 + 0.05 * 0.2, max_relative = 1e-15);
    }

    /// A plastic (e = 0) ball squeezed between another and the wall: the sequence ends with
    /// nothing approaching, all three at one velocity, momentum kept. (Each cycle of the
    /// sequence leaves `m2 / (m1 + m2)` of the approach: 1/2 here, so the budget of 64 cycles
    /// converges to round-off; a ball 10 times lighter would leave 0.91^64 = 2e-3 of it to
    /// Rapier's plastic solve.)
    #[test]
    fn plastic_squeeze_ends_at_a_common_velocity() {
        let s = touching_balls(&[0.11, 0.11], 0.0, 1.35);
        let length = s.container.unwrap().length;
        let (x, mut v, mut vs) = (s.initial_positions.clone(), vec![0.0, -0.4], 0.0);
        let mut out = Vec::new();
        resolve_touching(&s, &mut Instant { x: &x, v: &mut v, frame: Some((0.0, &mut vs, 1.35, length)) }, |_| 0.0, &mut out);
        let common = 0.11 * -0.4 / (0.11 + 0.11 + 1.35);
        assert_relative_eq!(v[0], common, max_relative = 1e-12);
        assert_relative_eq!(v[1], common, max_relative = 1e-12);
        assert_relative_eq!(vs, common, max_relative = 1e-12);
        let lost: f64 = out.iter().map(|i| i.energy_lost).sum();
        let ke = |m: f64, v: f64| 0.5 * m * v * v;
        assert_relative_eq!(lost, ke(0.11, -0.4) - ke(0.11 + 0.11 + 1.35, common), max_relative = 1e-12);
    }
}
