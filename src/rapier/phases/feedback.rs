//! After each Rapier step: the balls' velocity jumps give the contact impulses (`m dv`, not the
//! impulses Rapier reports, which are unreliable), the bounces Rapier skipped are restored, the
//! frame receives the opposite of the balls' momentum change, and impacts are attributed to
//! their pair.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::RigidBodyHandle;

use crate::rapier::contacts::{self, resolve_touching, write_velocities, Instant, PairImpact, TOUCHING};
use crate::rapier::resources::{Bodies, DamperScene, FrameState, Recording, StepClock, StepPlan, StepSettings};
use crate::rapier::{ALLOWED_OVERLAP, ENERGY_GAIN_TOLERANCE, WALL_CHORD_ERROR};
use crate::run::Impact;
use crate::scene::{pair_bodies, pair_gap, Body, Scene};

/// Impulses across the pairs from the balls' momentum changes `dp[i] = J[i] - J[i+1]`, where
/// pairs that carried no contact have `J = 0`. A run of active pairs is integrated from its
/// inactive end; a container in contact wall to wall (no inactive pair) takes the least
/// compressive solution.
pub fn pair_impulses(dp: &[f64], active: &[bool], out: &mut [f64]) {
    let n = dp.len();
    out.iter_mut().for_each(|j| *j = 0.0);
    match active.iter().position(|a| !a) {
        Some(k) => {
            for p in (0..k).rev() {
                out[p] = dp[p] + out[p + 1];
            }
            for p in k + 1..=n {
                out[p] = if active[p] { out[p - 1] - dp[p - 1] } else { 0.0 };
            }
        }
        None => {
            // J[p] = J[0] - sum_{i<p} dp[i]; choose J[0] so the smallest impulse is zero.
            let mut partial = 0.0;
            let mut max_partial: f64 = 0.0;
            for &d in dp {
                partial += d;
                max_partial = max_partial.max(partial);
            }
            out[0] = max_partial;
            for p in 1..=n {
                out[p] = out[p - 1] - dp[p - 1];
            }
        }
    }
}

/// Per-step working arrays, kept to avoid allocating in the step.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    handles: Vec<RigidBodyHandle>,
    x: Vec<f64>,
    v: Vec<f64>,
    dp: Vec<f64>,
    active: Vec<bool>,
    j: Vec<f64>,
    shares: Vec<f64>,
    resolved: Vec<PairImpact>,
}

/// The after-step system, in named phases: read the balls (projecting sunk ones back), find
/// the pairs in contact and their impulses from `m dv`, restore the bounces Rapier skipped,
/// feed the opposite momentum to the frame, book the step's loss and attribute impacts to
/// their pairs, then check the run and roll the state forward.
#[allow(clippy::too_many_arguments)]
pub fn feedback(
    mut clock: ResMut<StepClock>,
    plan: Res<StepPlan>,
    settings: Res<StepSettings>,
    scene: Res<DamperScene>,
    bodies: Option<Res<Bodies>>,
    frame: Option<ResMut<FrameState>>,
    mut rec: ResMut<Recording>,
    mut context: Query<(&RapierContextSimulation, &RapierContextColliders, &mut RapierRigidBodySet)>,
    mut velocities: Query<&mut Velocity>,
    mut scratch: Local<Scratch>,
) {
    let Some(bodies) = bodies else { return };
    let scene = &scene.0;
    let rec: &mut Recording = &mut rec;
    let n = scene.balls.len();
    let t0 = clock.t;
    clock.steps += 1;
    clock.t += plan.h;
    let Ok((sim, colliders, mut set)) = context.single_mut() else { return };
    let Scratch { x: x_new, v: v_new, dp, active, j, handles, shares, resolved } = &mut *scratch;
    if handles.len() != n {
        handles.clear();
        handles.extend(bodies.balls.iter().map(|e| set.entity2body()[e]));
    }
    read_balls(&set, handles, x_new, v_new);
    if let (Some(c), Some(f)) = (scene.container, frame.as_ref()) {
        let deepest = if settings.safeguards { f64::INFINITY } else { RAW_PROJECTION };
        project_sunk_balls(&mut set, handles, x_new, scene, f.before_impulses.0, c.length, deepest);
    }
    mark_pairs_in_contact(sim, colliders, &set, &bodies, n, active);
    let (frame_start, frame_end) = frame.as_ref().map_or(((0.0, 0.0), (0.0, 0.0)), |f| (f.start, f.before_impulses));
    let held = frame.as_ref().map_or([0, 0], |f| f.held);
    let carried = carry_held_balls(n, held, frame_end.1, active, &mut rec.v, v_new);
    if carried != [0, 0] {
        write_velocities(&mut set, handles, &bodies.balls, &mut velocities, v_new);
    }
    step_impulses(scene, v_new, &rec.v, active, dp, j);

    let wall_v = (frame_end.0 - frame_start.0) / plan.h; // the kinematic velocity Rapier used
    let walls_at_start = scene.frame.and(scene.container).map(|c| (frame_start.0, c.length));
    let closed_in_step = |p: usize| pair_gap(&scene.balls, &rec.x, walls_at_start, p).is_some_and(|g| g > TOUCHING);
    let replaced = only_new_contacts(scene, rec, wall_v, j, &closed_in_step);
    if replaced {
        // Rapier only stopped pairs that closed in the step: the balls flew free until then.
        // Discard its simultaneous plastic solve and resolve the impacts one pair at a time.
        v_new.copy_from_slice(&rec.v);
        let mut vs = frame_end.1;
        let walls = scene.frame.zip(scene.container).map(|(f, c)| (frame_end.0, &mut vs, f.mass, c.length));
        let mut now = Instant { x: x_new, v: v_new, frame: walls };
        let floor = contacts::approach_floor(scene);
        resolve_touching(scene, &mut now, |_| floor, resolved);
        write_velocities(&mut set, handles, &bodies.balls, &mut velocities, v_new);
        step_impulses(scene, v_new, &rec.v, active, dp, j);
    } else if restore_bounces(scene, rec, wall_v, frame_end.1, j, dp, v_new, &closed_in_step) {
        write_velocities(&mut set, handles, &bodies.balls, &mut velocities, v_new);
        step_impulses(scene, v_new, &rec.v, active, dp, j);
    }
    if !replaced && hold_loaded_contacts(scene, rec, x_new, v_new, frame_end, j, dp, resolved) {
        write_velocities(&mut set, handles, &bodies.balls, &mut velocities, v_new);
        step_impulses(scene, v_new, &rec.v, active, dp, j);
    }

    if carried != [0, 0] && share_frame_impulse(scene, carried, frame_end.1, dp, v_new) {
        write_velocities(&mut set, handles, &bodies.balls, &mut velocities, v_new);
        step_impulses(scene, v_new, &rec.v, active, dp, j);
    }
    let forcing_work = frame.as_ref().map_or(0.0, |f| f.forcing_work);
    let t1 = t0 + plan.h;
    let (frame_pre, frame_post, frame_energy) = match frame {
        Some(mut f) => {
            let (pre, post) = feed_frame(&mut f, scene, dp);
            let (force, energy) = f.force_and_energy(scene, t1);
            f.held = held_runs(scene, x_new, v_new, f.now, force, plan.h);
            (pre, post, energy)
        }
        None => (0.0, 0.0, 0.0),
    };
    let step = StepVelocities { before: &rec.v, after: v_new, frame_before: frame_pre, frame_after: frame_post };
    rec.impact_loss += step.kinetic_energy_lost(scene);
    let start = StepStart { t: t0, h: plan.h, frame_x: frame_start.0 };
    let ledger = ImpactLedger {
        impacts: &mut rec.impacts,
        last_impact: &mut rec.last_impact,
        last_impulse: &mut rec.last_impulse,
        impulse_floor: rec.impulse_floor,
    };
    if replaced {
        book_resolved(ledger, scene, &start, &rec.x, resolved, &mut rec.struck_at, clock.steps);
    } else {
        attribute_impacts(ledger, scene, &step, &start, &rec.x, active, j, shares);
    }
    if settings.safeguards && rec.failure.is_none() {
        rec.failure = self_check(scene, rec, (x_new, v_new), frame_end.0, frame_energy, forcing_work, t1);
    }
    std::mem::swap(&mut rec.prev_x, &mut rec.x);
    std::mem::swap(&mut rec.prev_v, &mut rec.v);
    rec.x.clone_from(x_new);
    rec.v.clone_from(v_new);
}

/// Phase 1: the balls' positions and velocities as Rapier left them.
fn read_balls(set: &RapierRigidBodySet, handles: &[RigidBodyHandle], x: &mut Vec<f64>, v: &mut Vec<f64>) {
    x.clear();
    v.clear();
    for &h in handles {
        let body = &set.bodies[h];
        x.push(body.translation().x as f64);
        v.push(body.linvel().x as f64);
    }
}

/// Phase 1b: Rapier's contacts are soft, so a ball pressed by an accelerating wall or a loaded
/// chain sinks past the allowed error. Project it back (positions only: no energy changes).
fn project_sunk_balls(
    set: &mut RapierRigidBodySet,
    handles: &[RigidBodyHandle],
    x: &mut [f64],
    scene: &Scene,
    frame_x: f64,
    length: f64,
    deepest: f64,
) {
    if !project_inside(x, &scene.balls, frame_x, length, deepest) {
        return;
    }
    for (i, &h) in handles.iter().enumerate() {
        let body = &mut set.bodies[h];
        let mut p = body.translation();
        if p.x as f64 != x[i] {
            p.x = x[i] as f32;
            body.set_translation(p, false);
            x[i] = p.x as f64;
        }
    }
}

/// Phase 2: which pairs were in contact this step (only whether, not how hard). Pair `p` lies
/// between body `p - 1` and body `p` (body `-1` the left wall, body `n` the right one).
fn mark_pairs_in_contact(
    sim: &RapierContextSimulation,
    colliders: &RapierContextColliders,
    set: &RapierRigidBodySet,
    bodies: &Bodies,
    n: usize,
    active: &mut Vec<bool>,
) {
    let collider = |body: isize| -> Option<Entity> {
        match (body, bodies.walls) {
            (-1, Some((l, _))) => Some(l),
            (b, Some((_, r))) if b == n as isize => Some(r),
            (b, _) if b >= 0 && (b as usize) < n => Some(bodies.balls[b as usize]),
            _ => None,
        }
    };
    active.clear();
    active.extend((0..=n).map(|p| {
        let (Some(a), Some(b)) = (collider(p as isize - 1), collider(p as isize)) else {
            return false;
        };
        sim.contact_pair(colliders, set, a, b).is_some_and(|pair| pair.manifolds().any(|m| m.points().any(|pt| pt.impulse() > 0.0)))
    }));
}

/// Phase 2b: the balls' momentum changes `dp` and the impulse across each pair `j` (m dv, not
/// the impulses Rapier reports).
fn step_impulses(scene: &Scene, v_new: &[f64], v_old: &[f64], active: &[bool], dp: &mut Vec<f64>, j: &mut Vec<f64>) {
    let n = scene.balls.len();
    dp.clear();
    dp.extend((0..n).map(|i| scene.balls[i].mass * (v_new[i] - v_old[i])));
    j.clear();
    j.resize(n + 1, 0.0);
    if n > 0 {
        pair_impulses(dp, active, j);
    }
}

/// Velocity of body `body` (a ball, or a wall moving at `frame_v`).
fn body_velocity(v: &[f64], frame_v: f64, body: isize) -> f64 {
    if body < 0 || body >= v.len() as isize {
        frame_v
    } else {
        v[body as usize]
    }
}

/// Phase 1c: balls held against a wall rode the frame this step (their mass in its
/// oscillator): they were expected to end at the frame's velocity, which stands for their
/// velocity before the step's impulses. Where nothing struck the held run from its open end,
/// they end there too (Rapier left them at the walls' mean velocity over the step); otherwise
/// what Rapier gave them is an impulse like any other. Returns whether a velocity changed.
fn carry_held_balls(n: usize, held: [usize; 2], frame_v: f64, active: &[bool], before: &mut [f64], v_new: &mut [f64]) -> [usize; 2] {
    let [left, right] = [held[0].min(n), held[1].min(n)];
    let mut carried = [0, 0];
    for (side, balls, open_pair) in [(0, 0..left, left), (1, n - right..n, n - right)] {
        if balls.is_empty() {
            continue;
        }
        let struck = open_pair > 0 && open_pair < n && active[open_pair];
        if !struck {
            carried[side] = balls.len();
        }
        for i in balls {
            before[i] = frame_v;
            if !struck {
                v_new[i] = frame_v;
            }
        }
    }
    carried
}

/// Phase 3d: the balls carried this step are part of the frame: an impulse the frame takes from
/// the other balls moves them too, `dv = -sum(dp) / (ms + carried mass)`. Sets their
/// velocities so that the frame's feedback (`-sum(dp) / ms`, theirs included) gives the same
/// `dv`. Returns whether a velocity changed.
fn share_frame_impulse(scene: &Scene, carried: [usize; 2], frame_v: f64, dp: &[f64], v_new: &mut [f64]) -> bool {
    let Some(f) = scene.frame else { return false };
    let n = v_new.len();
    let is_carried = |i: usize| i < carried[0] || i >= n - carried[1];
    let (mut free_dp, mut carried_mass) = (0.0, 0.0);
    for i in 0..n {
        if is_carried(i) {
            carried_mass += scene.balls[i].mass;
        } else {
            free_dp += dp[i];
        }
    }
    if free_dp == 0.0 {
        return false;
    }
    let dv = -free_dp / (f.mass + carried_mass);
    for (i, v) in v_new.iter_mut().enumerate() {
        if is_carried(i) {
            *v = frame_v + dv;
        }
    }
    true
}

/// Phase 6: the balls the walls hold next step: from each wall, the touching run of balls that
/// moves with the frame (within what its acceleration builds in a step) while the frame's
/// smooth force `force` pushes the wall into it (docs/MODEL.md §4).
fn held_runs(scene: &Scene, x: &[f64], v: &[f64], (xs, vs): (f64, f64), force: f64, h: f64) -> [usize; 2] {
    let (Some(f), Some(c)) = (scene.frame, scene.container) else { return [0, 0] };
    let n = x.len();
    let stick = contacts::sticking_speed(scene, force / f.mass, h);
    let walls = Some((xs, c.length));
    let holds =
        |ball: usize, pair: usize| pair_gap(&scene.balls, x, walls, pair).is_some_and(|g| g <= TOUCHING) && (v[ball] - vs).abs() <= stick;
    let mut held = [0, 0];
    if force > 0.0 {
        held[0] = (0..n).take_while(|&b| holds(b, b)).count();
    } else if force < 0.0 {
        held[1] = (0..n).rev().take_while(|&b| holds(b, b + 1)).count();
    }
    held
}

/// Phase 3a: whether Rapier's solve did nothing but stop pairs that closed in the step: no pair
/// it loaded carried an impulse the step before, and at least one it loaded was apart at the
/// step's start and approaching (the others touched at rest, loaded through the chain). Then
/// the plug-in may replace its solve.
fn only_new_contacts(scene: &Scene, rec: &Recording, wall_v: f64, j: &[f64], closed_in_step: &dyn Fn(usize) -> bool) -> bool {
    let n = scene.balls.len();
    let mut any = false;
    for p in 0..=n {
        if j[p] <= rec.impulse_floor {
            continue;
        }
        let (a, b) = (p as isize - 1, p as isize);
        let u = body_velocity(&rec.v, wall_v, a) - body_velocity(&rec.v, wall_v, b);
        if rec.last_impulse[p] > rec.impulse_floor {
            return false;
        }
        any |= u > 0.0 && closed_in_step(p);
    }
    any
}

/// Phase 5 of a replaced solve: the impacts the plug-in resolved, each timed where its gap at
/// the step's start closes at its approach speed.
fn book_resolved(
    ledger: ImpactLedger<'_>,
    scene: &Scene,
    start: &StepStart,
    x_before: &[f64],
    resolved: &[PairImpact],
    struck_at: &mut [Option<u64>],
    step: u64,
) {
    let n = scene.balls.len();
    let walls = scene.frame.and(scene.container).map(|c| (start.frame_x, c.length));
    let ImpactLedger { impacts, last_impact, last_impulse, .. } = ledger;
    // The pairs are separating now: none carries a contact into the next step.
    last_impulse.iter_mut().for_each(|j| *j = 0.0);
    for hit in resolved {
        let gap = pair_gap(&scene.balls, x_before, walls, hit.pair).unwrap_or(0.0);
        let t = start.t + (gap / hit.approach_speed).clamp(0.0, start.h);
        contacts::book(contacts::Ledger { impacts, last_impact, struck_at }, n, hit, t, step);
    }
}

/// Phase 3c: Rapier held its loaded contacts against the walls' mean velocity over the step,
/// but the frame ends the step at its own velocity: a ball pressed by an accelerating wall is
/// left behind it (and one sandwiched in a container it fits gained energy from the lag).
/// Hold each loaded pair that still approaches, measured with the frame's velocity at the
/// step's end after its feedback, plastically (`e = 0`). Returns whether any velocity changed.
#[allow(clippy::too_many_arguments)]
fn hold_loaded_contacts(
    scene: &Scene,
    rec: &Recording,
    x: &[f64],
    v_new: &mut [f64],
    frame_end: (f64, f64),
    j: &[f64],
    dp: &[f64],
    held: &mut Vec<PairImpact>,
) -> bool {
    let (Some(f), Some(c)) = (scene.frame, scene.container) else { return false };
    let mut vs = frame_end.1 - dp.iter().sum::<f64>() / f.mass;
    let floor = contacts::approach_floor(scene);
    let mut now = Instant { x, v: v_new, frame: Some((frame_end.0, &mut vs, f.mass, c.length)) };
    let threshold = |p: usize| if j[p] > rec.impulse_floor { floor } else { f64::INFINITY };
    contacts::resolve_touching_with(scene, 0.0, &mut now, threshold, held);
    !held.is_empty()
}

/// Phase 3: contacts that closed inside the step. Rapier holds every contact plastically (the
/// plug-in resolves the impacts that land on a step's boundary before the step, `super::impacts`);
/// a pair that carried no impulse last step, approached at the step's start and was loaded in
/// it closed inside the step (fixed stepping, or an approach the planner could not end a step
/// on). Give it the bounce of Eq. 9-10: the impulse that leaves it separating at `e` times its
/// approach once the frame has taken the opposite of the balls' momentum change. Returns
/// whether any velocity changed.
#[allow(clippy::too_many_arguments)]
fn restore_bounces(
    scene: &Scene,
    rec: &Recording,
    wall_v: f64,
    frame_v: f64,
    j: &[f64],
    dp: &[f64],
    v_new: &mut [f64],
    closed_in_step: &dyn Fn(usize) -> bool,
) -> bool {
    let n = scene.balls.len();
    let mass = |i: usize| scene.balls[i].mass;
    let inv_frame = scene.frame.map_or(0.0, |f| 1.0 / f.mass);
    // The frame's velocity once it has taken the step's impulses (and the bounces added here).
    let mut frame_after = frame_v - dp.iter().sum::<f64>() * inv_frame;
    let mut corrected = false;
    for p in 0..=n {
        let (a, b) = (p as isize - 1, p as isize);
        let u = body_velocity(&rec.v, wall_v, a) - body_velocity(&rec.v, wall_v, b);
        if !(j[p] > rec.impulse_floor && rec.last_impulse[p] <= rec.impulse_floor && u > 0.0 && closed_in_step(p)) {
            continue;
        }
        let u_after = body_velocity(v_new, frame_after, a) - body_velocity(v_new, frame_after, b);
        let inv = |body: isize| if body < 0 || body >= n as isize { inv_frame } else { 1.0 / mass(body as usize) };
        let dj = (scene.restitution * u + u_after) / (inv(a) + inv(b));
        if dj <= 0.0 {
            continue;
        }
        // dj pushes `a` back and `b` on; a wall's share reaches the frame through `dp`.
        for (body, sign) in [(a, -1.0), (b, 1.0)] {
            if body >= 0 && body < n as isize {
                v_new[body as usize] += sign * dj * inv(body);
                frame_after -= sign * dj * inv_frame;
            }
        }
        corrected = true;
    }
    corrected
}

/// Phase 4: the frame takes the opposite of the balls' total momentum change. Returns its
/// velocity before and after.
fn feed_frame(frame: &mut FrameState, scene: &Scene, dp: &[f64]) -> (f64, f64) {
    let (x, v) = frame.before_impulses;
    let dv = -dp.iter().sum::<f64>() / scene.frame.expect("frame").mass;
    frame.now = (x, v + dv);
    (v, v + dv)
}

/// The velocities of the balls and the frame before and after one step's contacts.
struct StepVelocities<'a> {
    before: &'a [f64],
    after: &'a [f64],
    frame_before: f64,
    frame_after: f64,
}

impl StepVelocities<'_> {
    /// Kinetic energy the step's contacts took, J.
    fn kinetic_energy_lost(&self, scene: &Scene) -> f64 {
        let frame_mass = scene.frame.map_or(0.0, |f| f.mass);
        let ke =
            |v: &[f64], vf: f64| 0.5 * frame_mass * vf * vf + scene.balls.iter().zip(v).map(|(b, v)| 0.5 * b.mass * v * v).sum::<f64>();
        ke(self.before, self.frame_before) - ke(self.after, self.frame_after)
    }

    /// Approach speed of pair `p` before and after the step.
    fn approach(&self, p: usize) -> (f64, f64) {
        let (a, b) = (p as isize - 1, p as isize);
        (
            body_velocity(self.before, self.frame_before, a) - body_velocity(self.before, self.frame_before, b),
            body_velocity(self.after, self.frame_after, a) - body_velocity(self.after, self.frame_after, b),
        )
    }
}

/// Where a step started: its time, length and the frame's displacement.
struct StepStart {
    t: f64,
    h: f64,
    frame_x: f64,
}

/// The part of the recording that impacts are booked in.
struct ImpactLedger<'a> {
    impacts: &'a mut Vec<Impact>,
    last_impact: &'a mut [Option<usize>],
    last_impulse: &'a mut [f64],
    impulse_floor: f64,
}

/// Phase 5: attribute the step's loss to its pairs. A pair whose impulse starts this step
/// while approaching is a new impact, timed where the gap at the step's start closes at the
/// approach speed; a pair that keeps pushing adds to its latest impact.
#[allow(clippy::too_many_arguments)]
fn attribute_impacts(
    ledger: ImpactLedger<'_>,
    scene: &Scene,
    step: &StepVelocities<'_>,
    start: &StepStart,
    x_before: &[f64],
    active: &[bool],
    j: &[f64],
    shares: &mut Vec<f64>,
) {
    let n = scene.balls.len();
    let walls = scene.frame.and(scene.container).map(|c| (start.frame_x, c.length));
    // Each pair's share of the step's loss, `j (u + u') / 2`; the shares sum to the step's
    // loss. Rapier solves touching contacts together, and the split of one simultaneous solve
    // among its pairs is not physical (a pair can appear to gain while the step loses): when
    // the step loses energy, it is shared among the pairs that lost, in proportion.
    shares.clear();
    shares.extend((0..=n).map(|p| {
        let (u, u_after) = step.approach(p);
        j[p] * 0.5 * (u + u_after)
    }));
    let total: f64 = shares.iter().sum();
    let gross: f64 = shares.iter().filter(|x| **x > 0.0).sum();
    let split = total >= 0.0 && gross > 0.0 && shares.iter().any(|x| *x < 0.0);
    let ImpactLedger { impacts, last_impact, last_impulse, impulse_floor } = ledger;
    for p in 0..=n {
        if !active[p] && j[p] == 0.0 {
            last_impulse[p] = 0.0;
            continue;
        }
        let (u, _) = step.approach(p);
        let lost = if split { shares[p].max(0.0) * total / gross } else { shares[p] };
        let starts = j[p] > impulse_floor && last_impulse[p] <= impulse_floor && u > 0.0;
        if starts {
            let gap = pair_gap(&scene.balls, x_before, walls, p).unwrap_or(0.0);
            last_impact[p] = Some(impacts.len());
            impacts.push(Impact {
                t: contacts::after_the_last(impacts, start.t + (gap / u).clamp(0.0, start.h)),
                a: pair_bodies(p, n).0,
                b: pair_bodies(p, n).1,
                approach_speed: u,
                energy_lost: lost,
                impulses: 1,
                peak_force: None,
                contact_duration: None,
            });
        } else if let Some(k) = last_impact[p] {
            impacts[k].energy_lost += lost;
            if j[p] > impulse_floor {
                impacts[k].impulses += 1;
            }
        }
        last_impulse[p] = j[p];
    }
}

/// What the contact model cannot have done, checked after every step: a ball deeper in a wall
/// than Rapier's allowed overlap (pushed through: projection only lifts shallow overlaps), an
/// impact that gained energy, or more energy in the system than was put in. Returns the reason.
fn self_check(
    scene: &Scene,
    rec: &Recording,
    (x, v): (&[f64], &[f64]),
    xs: f64,
    frame_energy: f64,
    forcing_work: f64,
    t: f64,
) -> Option<String> {
    if let Some(c) = scene.container {
        for (i, b) in scene.balls.iter().enumerate() {
            let (left, right) = (x[i] - b.radius - xs, xs + c.length - x[i] - b.radius);
            let depth = -left.min(right);
            if depth > ALLOWED_OVERLAP + 1e-6 {
                let ratio = crate::rapier::neighbour_mass_ratio(scene);
                return Some(format!(
                    "at t = {t:.6e} s {} is {depth:.3e} m into the {} wall, past Rapier's allowed overlap ({ALLOWED_OVERLAP:.1e} m): \
                     Rapier's iterative solver did not hold it (largest neighbouring mass ratio {ratio:.0})",
                    Body::Ball(i).name(),
                    if left < right { "left" } else { "right" },
                ));
            }
        }
    }
    let energy_in = rec.initial_energy.abs() + forcing_work.abs();
    let scale = energy_in.max(rec.energy_floor / ENERGY_GAIN_TOLERANCE);
    // Free chains (the KER experiment, no frame) are judged on their total energy only: there
    // Rapier solves a touching chain at once and moves energy between the pairs of one step
    // (one impact of chain-ker-4L appears to gain 0.3 % of E0 while the chain loses).
    if scene.frame.is_some() {
        for k in rec.last_impact.iter().flatten() {
            let imp = &rec.impacts[*k];
            if imp.energy_lost < -ENERGY_GAIN_TOLERANCE * scale {
                return Some(format!(
                    "the impact of {} and {} at t = {:.6e} s gained {:.3e} J ({:.1e} of the energy put in): \
                     Rapier's simultaneous contact solve added energy",
                    imp.a.name(),
                    imp.b.name(),
                    imp.t,
                    -imp.energy_lost,
                    -imp.energy_lost / scale
                ));
            }
        }
    }
    let now = frame_energy + scene.balls.iter().zip(v).map(|(b, v)| 0.5 * b.mass * v * v).sum::<f64>();
    if now > energy_in * (1.0 + ENERGY_GAIN_TOLERANCE) + rec.energy_floor {
        return Some(format!("at t = {t:.6e} s the system holds {now:.6e} J, more than the {energy_in:.6e} J put in"));
    }
    None
}

/// Overlap a projected contact keeps: Rapier's allowed error (`0.005 length_unit`), less the
/// walls' chord error within a step, so that samples inside a step stay within the allowed error.
pub const PROJECTED_OVERLAP: f64 = ALLOWED_OVERLAP - WALL_CHORD_ERROR;
/// Deepest overlap put back without the plug-in's safeguards, as a fraction of the ball's
/// radius: Rapier's soft contacts sink a pressed ball this far; deeper, its solver has pushed
/// the ball through, which the raw behaviour shows and the safeguards resolve.
pub const RAW_PROJECTION: f64 = 0.25;

/// Moves balls that overlap a wall (at `left` and `left + length`) or a neighbour by more than
/// [`PROJECTED_OVERLAP`] (and at most `deepest` times the radius) back to that overlap: a
/// sweep from the left wall, then one from the right. Returns whether any ball moved. The
/// velocities are left to the impact phase before the next step, which resolves a ball that
/// now touches a wall and approaches it as any impact (`super::impacts`).
pub fn project_inside(x: &mut [f64], balls: &[crate::scene::Ball], left: f64, length: f64, deepest: f64) -> bool {
    let mut moved = false;
    let mut edge = left;
    for (i, b) in balls.iter().enumerate() {
        let lowest = edge + b.radius - PROJECTED_OVERLAP;
        let depth = lowest - x[i];
        if depth > 0.0 && depth <= deepest * b.radius {
            x[i] = lowest;
            moved = true;
        }
        edge = x[i] + b.radius;
    }
    let mut edge = left + length;
    for (i, b) in balls.iter().enumerate().rev() {
        let highest = edge - b.radius + PROJECTED_OVERLAP;
        let depth = x[i] - highest;
        if depth > 0.0 && depth <= deepest * b.radius {
            x[i] = highest;
            moved = true;
        }
        edge = x[i] - b.radius;
    }
    moved
}
