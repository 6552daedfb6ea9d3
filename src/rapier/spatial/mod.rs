//! The contact model beyond one line (docs/MODEL.md §9, "Rapier"): balls free in 3D under the
//! scene's gravity and friction, in a container of six walls (and dividers between chains)
//! carried by the kinematic frame. The frame moves in x only, by the same closed-form
//! oscillator step as the one-line path, and is fed back the x impulse the walls give the
//! balls. Rapier solves every contact plastically; `contacts` gives the bounces by Eq. 9-10
//! along the normal of each contact whose approach Rapier stopped in the step.
//!
//! This path is a lean loop over Rapier's own `PhysicsWorld`, not Bevy systems: one step has
//! four phases (drive the frame, Rapier's step, feedback and impacts, samples) that read and
//! write the same few arrays, and the Bevy schedule would add its ECS synchronisation (a copy
//! of every body per step) and nothing the headless run needs. The one-line path is untouched.

mod balls;
mod carried;
mod carrier;
mod closings;
mod contacts;
mod flights;
mod hooks;
mod records;
mod settings;
mod strikes;
mod world;

use bevy_rapier3d::rapier::prelude::{ActiveHooks, Vector};

pub use contacts::closing_speed;
pub use settings::{
    checks, energy_gain_allowance, needs_spatial, rapier_world, refusal, resting_wall_sink, solver_settings, wall_sink_limit,
    CONTACT_DAMPING_RATIO, CONTACT_FREQUENCY_PER_SUBSTEP_RATE, DEFAULT_SPATIAL_DT, DEFAULT_SPATIAL_ITERATIONS, LEAST_PREDICTION,
    RESTING_SINK_FRACTION, SPATIAL_ENERGY_GAIN, STEP_TRAVEL, TOUCHING_FRACTION,
};
pub use world::{SolverSettings, SpatialWorld};

use crate::model::{Budget, Meter, Model, ModelError, OverBudget, RunOptions};
use crate::run::{EnergyAccount, Impacts, Recorder, Run, MAX_KEPT_IMPACTS};
use crate::scene::Scene;
use balls::BallState;
use carrier::Carrier;
use closings::{Closing, Solved, WallKicks};
use contacts::{dot as contacts_dot, Balls, Contact, Containers, FrameBody, Other};
use records::{impact_record, sample, sunk_too_deep};
use settings::chambers;

/// Steps between two looks at the budgets and the progress: every step, since a step of a deep
/// bed can take a second (a look costs tens of nanoseconds, a step at least microseconds).
const BUDGET_STEPS: u64 = 1;

/// What a spatial run measured besides its [`Run`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpatialReport {
    /// Energy Rapier's steps took beyond the impact law's losses, J (the run's
    /// `contact_loss`): per step, the drop in the balls' kinetic energy (spin included) and
    /// the frame's energy jump, less gravity's work on the balls' displacement and the
    /// impacts' losses of the step. Friction and Rapier's plastic resting contacts end up
    /// here, and so does the step's own energy error (docs/MODEL.md §9).
    pub contact_loss: f64,
    /// The largest energy one step made (the most negative per-step contact loss, as a
    /// positive number), J.
    pub worst_step_gain: f64,
    /// The deepest a ball sank into a wall or another ball at a step's end, m.
    pub deepest_overlap: f64,
    /// Steps taken.
    pub steps: u64,
    /// The deepest a ball sank into a wall at a step's end, before it was put back, m.
    pub deepest_wall_sink: f64,
    /// Steps at whose end a ball sunk into a wall past the resting sink was put back.
    pub sinks_put_back: u64,
    /// Impacts found as new contacts.
    pub new_contact_impacts: u64,
    /// Impacts of touching pairs the new ones set approaching, and of those that touch and
    /// approach at the start.
    pub knock_on_impacts: u64,
}

/// Runs the spatial path on `scene` with its default settings.
pub fn simulate_spatial(scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
    simulate_spatial_with(scene, solver_settings(scene), options).map(|(run, _)| run)
}

/// The spatial path with given solver settings: the run and what it measured.
pub fn simulate_spatial_with(scene: &Scene, solver: SolverSettings, options: &RunOptions) -> Result<(Run, SpatialReport), ModelError> {
    if let Some(reason) = refusal(scene) {
        return Err(ModelError::Refused(reason));
    }
    let geometry = chambers(scene).map_err(ModelError::Refused)?;
    let speed = crate::rapier::resources::speed_scale(scene);
    let Some(f) = scene.frame else { return Err(ModelError::Refused("the scene has no frame".into())) };
    let meter = Meter::new(options, BUDGET_STEPS);
    let mut world = world::build(scene, &geometry, solver);
    let n = scene.balls.len();
    // The bodies that carry the walls: the frame, or each floor that carries a damper. Each
    // ball's walls are its damper's, on its damper's body.
    let dampers = scene.damper_list();
    let body_floors = carrier::carrying_floors(scene);
    let body_of_damper: Vec<usize> = dampers.iter().map(|d| body_floors.iter().position(|&j| j == d.floor).unwrap_or(0)).collect();
    let damper_of: Vec<u32> = (0..n).map(|i| scene.damper_of(i) as u32).collect();
    let body_of: Vec<usize> = damper_of.iter().map(|&d| body_of_damper[d as usize]).collect();
    let body_mass: Vec<f64> = match (&scene.structure, body_floors.len()) {
        (Some(s), 2..) => body_floors.iter().map(|&j| s.building.masses[j]).collect(),
        _ => vec![f.mass],
    };
    let bodies = body_mass.len();
    let xs_of_damper = |xs: &[f64]| -> Vec<f64> { body_of_damper.iter().map(|&b| xs[b]).collect() };
    let mass: Vec<f64> = scene.balls.iter().map(|b| b.mass).collect();
    let radius: Vec<f64> = scene.balls.iter().map(|b| b.radius).collect();
    let inertia: Vec<f64> = scene.balls.iter().map(|b| 0.4 * b.mass * b.radius * b.radius).collect();
    let g = scene.space.gravity;
    let e = scene.restitution;
    let mut carrier = Carrier::new(scene).map_err(ModelError::Refused)?;
    let mut now = BallState { x: vec![[0.0; 3]; n], v: vec![[0.0; 3]; n], w: vec![[0.0; 3]; n] };
    now.read(&world);
    let start_positions = now.x.clone();
    let mut before = BallState { x: now.x.clone(), v: now.v.clone(), w: now.w.clone() };
    let (mut xs, mut vs): (Vec<f64>, Vec<f64>) = carrier.starts().into_iter().unzip();
    let (mut damping_loss, mut forcing_work, mut impact_loss, mut contact_loss) = (0.0, 0.0, 0.0, 0.0);
    let mut report = SpatialReport::default();
    let mut impacts = Impacts::new(options.impacts);
    let mut recorder = Recorder::new(scene, options.record);
    let sample_count = scene.sample_count();
    sample(&mut recorder, scene, &carrier, 0.0, (xs[0], vs[0]), |i| {
        let ([y, z], [vy, vz]) = (scene.space.lateral_of(i), scene.space.lateral_velocity_of(i));
        ([scene.initial_positions[i], y, z], [scene.initial_velocities[i], vy, vz])
    });
    let mut next_sample = 1;
    let touching = TOUCHING_FRACTION * solver.length_unit;
    // Closings slower than gravity and the frame's acceleration over the step (`walls_a`)
    // build along a contact's normal in two steps are resting contacts, left to Rapier's
    // plastic solve. A ball in a pile (touching a ball across gravity) carries weight along
    // every one of its contacts, so there gravity counts whole, whatever the normal.
    let speed_floor = 1e-9 * speed;
    let g_norm = contacts_dot(g, g).sqrt();
    let down = if g_norm > 0.0 { g.map(|c| c / g_norm) } else { [0.0; 3] };
    let mut in_pile = vec![false; n];
    let piled = |c: &Contact, in_pile: &[bool]| in_pile[c.ball] || matches!(c.other, Other::Ball(j) if in_pile[j]);
    let resting_speed = |c: &Contact, in_pile: &[bool], walls_a: &[f64]| {
        let pressing = if piled(c, in_pile) { g_norm } else { contacts_dot(g, c.normal).abs() };
        2.0 * (pressing + c.normal[0].abs() * walls_a[body_of[c.ball]]) * solver.dt + speed_floor
    };
    let lu = solver.length_unit as f32;
    // How deep a ball may sink into a wall, and the resting sink a deeper one is put back to.
    // (Balls may sink deeper into each other: Rapier's solve holds a pile by the overlaps of
    // its balls, which nothing outside the run sees.)
    let sink_limit = wall_sink_limit(scene);
    let resting_sink = resting_wall_sink(scene);
    let mut finder = contacts::Finder::default();
    // How fast pairs may close, m/s: twice the fastest expected speed.
    let reach = 2.0 * speed;
    let mut found: Vec<Contact> = Vec::new();
    let (mut near, mut held) = (vec![0u32; n], vec![0u32; n]);
    let mut kicked = vec![false; n];
    let mut cascade = contacts::Cascade::default();
    let mut strikes = strikes::Strikes::default();
    let mut flights = flights::Flights::default();
    let mut undone = vec![false; n];
    let mut parted = vec![false; n];
    let mut joined: Vec<bool> = Vec::new();
    let mut unsolved = vec![Vec::new(); dampers.len()];
    // The pairs the impact law struck in a step, whose impulses Rapier forgets at the next.
    let mut struck_last_step = hooks::Struck::default();
    let mut fastest = vec![0.0f64; dampers.len()];
    // How far ahead each damper's broad-phase boxes reach, in Rapier's length unit: the first
    // step makes them.
    let mut boxed_for = vec![f32::INFINITY; dampers.len()];
    // The mass of balls each body's walls drag along (`carried`), which its closed form
    // carries, and the x momentum Rapier's step gave each ball.
    let mut carried = carried::CarriedMass::new((0..bodies).map(|b| (0..n).filter(|&i| body_of[i] == b).map(|i| mass[i]).sum()).collect());
    let mut pushed = vec![0.0; n];
    let height_at_start = scene.height_energy_at_start();
    let energy_of = |carrier: &Carrier, state: &BallState, t: f64, xs: &[f64], vs: &[f64]| -> f64 {
        let mut e = carrier.energy(t, xs[0], vs[0]) + height_at_start;
        for i in 0..n {
            let (v, w, x, x0) = (state.v[i], state.w[i], state.x[i], start_positions[i]);
            e += 0.5 * mass[i] * contacts_dot(v, v) + 0.5 * inertia[i] * contacts_dot(w, w);
            // Gravity's potential energy, from the start: m g . (r0 - r).
            e += mass[i] * contacts_dot(g, std::array::from_fn(|a| x0[a] - x[a]));
        }
        e
    };
    let initial_energy = scene.initial_energy();
    // Pairs that touch at the start and approach strike before the first step, the fastest
    // first with their knock-ons (§3 along normals), as a step's impacts do at its end: left
    // to Rapier's plastic solve, a ball touching a row would move the whole row as one block.
    {
        // As far as the first step may close a pair, for its strikes.
        let walls = Containers { chambers: &geometry, damper: &damper_of, xs: &xs_of_damper(&xs) };
        finder.find(walls, &now.x, &radius, touching + reach * solver.dt, &mut found);
        contacts::mark_piles(&found, touching, down, &mut in_pile);
        contacts::count(&found, touching, &mut near, &mut held);
        kicked.iter_mut().for_each(|k| *k = true);
        let mut struck = vec![false; n];
        let mut balls = Balls { v: &mut now.v, mass: &mass };
        let mut frame = FrameBody { vs: vs.clone(), mass: &body_mass, of_ball: &body_of };
        // The walls' mean acceleration over the first step.
        let walls_a: Vec<f64> = carrier.states(solver.dt).iter().zip(&vs).map(|((_, v1), v0)| ((v1 - v0) / solver.dt).abs()).collect();
        let resting = |c: &Contact| resting_speed(c, &in_pile, &walls_a);
        let touches = |c: &Contact| c.gap <= touching;
        cascade.run(&found, touches, &mut kicked, resting, (&mut balls, &mut frame), |c, approach, balls, frame| {
            let lost = contacts::strike(c, approach, e, balls, frame);
            impact_loss += lost;
            impacts.push(impact_record(0.0, c, approach, lost));
            report.knock_on_impacts += 1;
            struck[c.ball] = true;
            if let Other::Ball(j) = c.other {
                struck[j] = true;
            }
        });
        let starts: Vec<(f64, f64)> = xs.iter().copied().zip(vs.iter().copied()).collect();
        carrier.restart_bodies(0.0, &starts, &frame.vs, &carried.mass, &vec![0.0; bodies]).map_err(ModelError::Refused)?;
        vs = frame.vs;
        now.write_velocities(&mut world, &struck);
    }
    let mut t = 0.0;
    let mut steps: u64 = 0;
    let finish = |carrier: &Carrier,
                  t: f64,
                  xs: &[f64],
                  vs: &[f64],
                  state: &BallState,
                  recorder: Recorder,
                  impacts: Impacts,
                  damping_loss: f64,
                  impact_loss: f64,
                  contact_loss: f64,
                  forcing_work: f64,
                  steps: u64| {
        let final_ = energy_of(carrier, state, t, xs, vs);
        let (series, motion) = recorder.finish();
        Run {
            scene: scene.name.clone(),
            model: Model::Rapier,
            horizon: t,
            sample_dt: scene.sample_dt,
            initial_displacement: scene.initial_displacement,
            damped_period: f.damped_period(),
            series,
            motion,
            impacts: impacts.kept,
            counted_impacts: impacts.counted,
            energy: EnergyAccount::forced(initial_energy, final_, damping_loss, impact_loss, forcing_work).with_contact_loss(contact_loss),
            events: steps,
            final_velocities: state.v.iter().map(|v| v[0]).collect(),
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    };
    while !scene.reached_horizon(t) {
        // A run that keeps its impacts stops past the most memory holds (a long run of a bed
        // thrown about makes millions); one that counts them goes on.
        let beyond_memory = impacts.beyond_memory().then_some(Budget::Memory);
        if let Some(budget) = beyond_memory.or_else(|| meter.look(t, steps)) {
            let wall_s = meter.elapsed();
            let mut cost = format!("{} impacts so far; {} balls in 3D at steps of {} s", impacts.len(), n, crate::scene::human(solver.dt));
            if budget == Budget::Memory {
                cost += "; a run that counts its impacts instead of keeping them (`--impacts count`) is not bounded by memory";
            }
            let mut partial =
                finish(&carrier, t, &xs, &vs, &now, recorder, impacts, damping_loss, impact_loss, contact_loss, forcing_work, steps);
            partial.wall_time_s = wall_s;
            return Err(ModelError::OverBudget(Box::new(OverBudget {
                scene: scene.name.clone(),
                model: Model::Rapier,
                t,
                horizon: scene.horizon,
                steps,
                wall_s,
                budget,
                limit: if budget == Budget::Memory { MAX_KEPT_IMPACTS as f64 } else { meter.limit(budget) },
                cost,
                partial,
            })));
        }
        // The last step ends on the horizon, unless it is a whole step to within the clock's
        // round-off: then the step is the same as in a longer run.
        let left = scene.horizon - t;
        let h = if left >= solver.dt * (1.0 - 1e-6) { solver.dt } else { left };
        for damper in &mut world.dampers {
            damper.physics.integration_parameters.dt = h as f32;
        }
        // The frame to where its closed form is at the step's end; Rapier moves the walls
        // there in a straight line.
        let (t0, t1) = (t, t + h);
        let (x1, v1): (Vec<f64>, Vec<f64>) = carrier.states(t1).into_iter().unzip();
        let (damping, work) = carrier.energy_flows(t0, h);
        damping_loss += damping;
        forcing_work += work;
        for (d, damper) in world.dampers.iter_mut().enumerate() {
            let x = x1[body_of_damper[d]];
            damper.physics.bodies[damper.frame].set_next_kinematic_translation(Vector::new(x as f32, 0.0, 0.0));
        }
        // The walls' mean velocity over the step: Rapier moves them there in a straight line.
        let mean_vs: Vec<f64> = (0..bodies).map(|b| (x1[b] - xs[b]) / h).collect();
        // Rapier stops a pair at contact only when it predicts it: in each damper, as far ahead
        // as any of its pairs can close in the step (twice its fastest ball's speed relative to
        // its walls, and gravity's pull), and never nearer than [`LEAST_PREDICTION`]. A contact
        // predicted further ahead than that cannot act in the step and only adds to Rapier's
        // solve.
        fastest.iter_mut().for_each(|f| *f = 0.0);
        for (i, v) in now.v.iter().enumerate() {
            let relative = ((v[0] - mean_vs[body_of[i]]).powi(2) + v[1] * v[1] + v[2] * v[2]).sqrt();
            let d = damper_of[i] as usize;
            fastest[d] = fastest[d].max(relative);
        }
        for ((damper, fastest), boxed) in world.dampers.iter_mut().zip(&fastest).zip(&mut boxed_for) {
            let closing = (2.0 * fastest * h + g_norm * h * h) as f32 / lu;
            let prediction = closing.max(LEAST_PREDICTION);
            damper.physics.integration_parameters.normalized_prediction_distance = prediction;
            // Rapier boxes its colliders for the broad phase at a step's end, as far ahead as
            // that step predicted: boxes made for a slower step would hide pairs this one can
            // close, so they are made anew when the prediction grows.
            if prediction > *boxed {
                let physics = &mut damper.physics;
                for (handle, collider) in physics.colliders.iter() {
                    let aabb = collider.compute_broad_phase_aabb(&physics.integration_parameters, &physics.bodies);
                    physics.broad_phase.set_aabb(&physics.integration_parameters, handle, aabb);
                }
            }
            *boxed = prediction;
        }
        // Strikes on touching groups are kept out of Rapier's solve of their pair (`strikes`).
        // The walls' mean acceleration over the step, as its closed form moves them.
        let walls_a: Vec<f64> = (0..bodies).map(|b| ((v1[b] - vs[b]) / h).abs()).collect();
        strikes.predict(&found, &now.v, |k| vs[body_of[k]], (touching, down), h, |c| resting_speed(c, &in_pile, &walls_a));
        // Each damper's strikes, as pairs of its world's colliders.
        unsolved.iter_mut().for_each(Vec::clear);
        for s in &strikes.list {
            let (striker, target) = (world.balls[s.striker], world.balls[s.target]);
            unsolved[striker.damper].push((striker.collider, target.collider));
            world.collider_mut(s.striker).set_active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS);
        }
        struck_last_step.forget(&mut world);
        let walls_v = carried::WallsVelocity { start: &vs, mean: &mean_vs, end: &v1 };
        // The balls that touch something step in their walls' reference (`carried`); those in
        // flight, in the ground's.
        let resting: Vec<bool> = held.iter().map(|&count| count > 0).collect();
        carried::enter_walls_reference(&mut world, &now.v, (&body_of, &resting), walls_v, &mass, h);
        std::mem::swap(&mut before, &mut now);
        for (damper, pairs) in world.dampers.iter_mut().zip(&unsolved) {
            damper.physics.step_with_events(&strikes::Unsolved { pairs }, &());
        }
        now.read(&world);
        carried::leave_walls_reference(&mut world, &mut now.v, (&body_of, &resting), walls_v);
        for s in &strikes.list {
            world.collider_mut(s.striker).set_active_hooks(ActiveHooks::empty());
            if strikes::bring_back(*s, &mut now.x, &now.v, v1[body_of[s.striker]], &radius, h) {
                let p = now.x[s.striker].map(|c| c as f32);
                world.ball_mut(s.striker).set_translation(Vector::new(p[0], p[1], p[2]), true);
                now.x[s.striker] = p.map(f64::from);
            }
        }
        // Rapier's walls are infinitely heavy: the frame takes the opposite of the x momentum
        // they gave the balls (ball-ball impulses cancel in the sum; gravity's is not theirs),
        // less what its closed form gave the mass it carried through the step.
        let carrying = carrier.carried();
        let mut dpx: Vec<f64> = (0..bodies).map(|b| -carrying[b] * (v1[b] - vs[b])).collect();
        for i in 0..n {
            pushed[i] = mass[i] * (now.v[i][0] - before.v[i][0] - g[0] * h);
            dpx[body_of[i]] += pushed[i];
        }
        let mut frame = FrameBody { vs: (0..bodies).map(|b| v1[b] - dpx[b] / body_mass[b]).collect(), mass: &body_mass, of_ball: &body_of };
        // Pairs Rapier may have stopped: its speculative contacts slow a pair a little before
        // it touches, within what it closes in a step or two.
        let walls = Containers { chambers: &geometry, damper: &damper_of, xs: &xs_of_damper(&x1) };
        finder.find(walls, &now.x, &radius, touching + reach * h, &mut found);
        contacts::mark_piles(&found, touching, down, &mut in_pile);
        // A ball Rapier's soft contacts let sink into a wall past the resting sink (struck hard
        // in a crowd, or pressed by walls at thousands of g) is put back to that sink; one
        // whose centre has crossed the wall stops the run.
        for c in &found {
            report.deepest_overlap = report.deepest_overlap.max(-c.gap);
            if let Other::Wall(_) = c.other {
                report.deepest_wall_sink = report.deepest_wall_sink.max(-c.gap);
            }
        }
        match now.put_back_sunk(&mut world, &found, &radius, (sink_limit, resting_sink)) {
            Ok(true) => {
                report.sinks_put_back += 1;
                finder.find(walls, &now.x, &radius, touching + reach * h, &mut found);
                contacts::mark_piles(&found, touching, down, &mut in_pile);
            }
            Ok(false) => {}
            Err(sunk) => {
                let b = body_of[sunk.0];
                return Err(sunk_too_deep(scene, t1, sunk, radius[sunk.0], (v1[b] - vs[b]) / h));
            }
        }
        // Contacts whose approach Rapier stopped, and strikes kept out of its solve.
        let mut new: Vec<Closing> = Vec::new();
        contacts::count(&found, touching, &mut near, &mut held);
        joined.clear();
        joined.resize(found.len(), false);
        for (k, c) in found.iter().enumerate() {
            if strikes.holds(c) {
                // Rapier did not solve the pair: it strikes at the speed it touches with.
                let balls = Balls { v: &mut now.v, mass: &mass };
                let approach = -contacts::relative(c, &balls, &frame).0;
                if c.gap <= touching && approach > 0.0 {
                    // It strikes at the speed it approaches with when its turn comes.
                    let solved = Some(Solved { undo: None, normal: c.normal });
                    new.push(Closing { approach, tau: 0.0, k, gap0: 0.0, w0: -approach, g_n: 0.0, solved });
                }
                continue;
            }
            let (gap0, w0, w_end, g_n, solved) = match c.other {
                Other::Ball(j) => {
                    let (d, dv, dv_end) = (between(&before.x, c.ball, j), between(&before.v, c.ball, j), between(&now.v, c.ball, j));
                    let distance = contacts_dot(d, d).sqrt();
                    // Two balls that meet in flight touch along the line of their centres at
                    // that instant, and their impact acts along it; Rapier solved the pair
                    // along a line of its own, near that of their centres at the step's start.
                    // When nothing else is near either ball, all the step did to the pair is
                    // that solve, undone whole; when they touch nothing else, it is undone
                    // along the centres' line at the step's start. A ball that touches others
                    // (a pile holding it up) keeps Rapier's solve.
                    let sum = radius[c.ball] + radius[j];
                    let (alone, free) = (near[c.ball] == 1 && near[j] == 1, held[c.ball] <= 1 && held[j] <= 1);
                    let touched = if free { contacts::touching_normal(d, dv, sum, 2.0 * h) } else { None };
                    let solved = touched.map(|normal| {
                        let change: [f64; 3] = std::array::from_fn(|a| dv_end[a] - dv[a]);
                        let size = contacts_dot(change, change).sqrt();
                        let undo = if alone && size > 0.0 {
                            (change.map(|x| x / size), size)
                        } else {
                            let along = d.map(|c| c / distance);
                            (along, contacts_dot(dv_end, along) - contacts_dot(dv, along))
                        };
                        Solved { undo: Some(undo), normal }
                    });
                    let normal = solved.map_or(c.normal, |s| s.normal);
                    (distance - sum, contacts_dot(dv, normal), contacts_dot(dv_end, normal), 0.0, solved)
                }
                Other::Wall(wall) => {
                    let p = before.x[c.ball];
                    let b = body_of[c.ball];
                    let (gap0, _) = geometry[damper_of[c.ball] as usize].gap(wall, [p[0] - xs[b], p[1], p[2]], radius[c.ball]);
                    // The walls accelerate from their velocity at the step's start to that at
                    // its end (Rapier steps the balls in their reference).
                    let n_x = c.normal[0];
                    (
                        gap0,
                        n_x * vs[b] - contacts_dot(before.v[c.ball], c.normal),
                        n_x * v1[b] - contacts_dot(now.v[c.ball], c.normal),
                        contacts_dot(g, c.normal) - n_x * (v1[b] - vs[b]) / h,
                        None,
                    )
                }
            };
            // An impact is a contact Rapier's plastic solve stopped in this step: it was
            // approaching faster than a resting contact, and the step took its approach.
            let resting = resting_speed(c, &in_pile, &walls_a);
            let (tau, approach) = contacts::closing(gap0, w0, g_n, h);
            let stopped = w_end - (w0 - g_n * h) > resting;
            // Rapier's solve joins the balls of a pair only where it acted on it: they touch,
            // or their approach changed by more than a resting contact's.
            joined[k] = c.gap <= touching || (w_end - (w0 - g_n * h)).abs() > resting;
            if approach > resting && stopped && c.gap <= touching + 2.0 * (-w0).max(0.0) * h {
                new.push(Closing { approach, tau, k, gap0, w0, g_n, solved });
            }
        }
        // The impacts act the fastest first, and strikes kept out of Rapier's solve after every
        // impact Rapier stopped: their targets lie in piles whose stops the impact law has to
        // turn into bounces before a strike meets them.
        let held_back = |c: &Closing| strikes.holds(&found[c.k]);
        new.sort_by(|a, b| held_back(a).cmp(&held_back(b)).then(b.approach.total_cmp(&a.approach)));
        // Groups of balls in flight that strike each other: Rapier's whole step of them is
        // undone (`flights`), and each of their impacts acts along the line its balls touch
        // along in free flight, at the speed they approach with when its turn comes.
        // (A strike on a touching group has its own rule, and its target was pressed.)
        let struck_pairs = new.iter().map(|closing| &found[closing.k]).filter(|c| !strikes.holds(c)).filter_map(|c| match c.other {
            Other::Ball(j) => Some((c.ball, j)),
            Other::Wall(_) => None,
        });
        // So are touching groups that rested on no wall of which a ball strikes a wall: Rapier's
        // solve stops the whole group at once, where the impact law passes the strike along it.
        let struck_walls = new.iter().map(|closing| &found[closing.k]).filter(|c| matches!(c.other, Other::Wall(_))).map(|c| c.ball);
        // A ball lying on the floor outside a pile is off the walls too: such a group has only
        // its motion along the floor undone, and keeps Rapier's hold across it and its spin.
        let lies_on_floor = |i: usize| strikes.on_floor(i) && !in_pile[i];
        let free_or_off_walls = (|i| !strikes.pressed(i), |i| !strikes.held_by_wall(i) && (!strikes.on_floor(i) || lies_on_floor(i)));
        let any_undone = flights.mark(&found, &joined, free_or_off_walls, struck_pairs, struck_walls, &mut undone);
        if any_undone {
            // The frame takes back the x momentum the undone solve gave the balls.
            now.undo_step(&before, (&undone, lies_on_floor), (g, down, h), |i, undone_vx| {
                frame.vs[body_of[i]] += mass[i] * undone_vx / body_mass[body_of[i]];
            });
            for closing in new.iter_mut() {
                let c = found[closing.k];
                let Other::Ball(j) = c.other else { continue };
                if undone[c.ball] && undone[j] && !strikes.holds(&c) {
                    let (d, dv) = (between(&before.x, c.ball, j), between(&before.v, c.ball, j));
                    let normal = contacts::touching_normal(d, dv, radius[c.ball] + radius[j], 2.0 * h).unwrap_or(c.normal);
                    // The group's whole step is undone already.
                    closing.solved = Some(Solved { undo: None, normal });
                }
            }
        }
        kicked.iter_mut().for_each(|k| *k = false);
        let mut step_impact_loss = 0.0;
        let mut kicks = WallKicks::new(bodies);
        {
            let mut balls = Balls { v: &mut now.v, mass: &mass };
            // The balls' velocities before the step's impacts: what the impacts ahead of a wall
            // impact changed in its ball shifts that impact's approach.
            let unstruck = if new.is_empty() { Vec::new() } else { balls.v.to_vec() };
            let change = |v: &[[f64; 3]], i: usize, normal: [f64; 3]| -> f64 {
                contacts_dot(std::array::from_fn(|a| v[i][a] - unstruck[i][a]), normal)
            };
            for closing in &new {
                let c = found[closing.k];
                let (approach, lost) = match c.other {
                    Other::Ball(_) => {
                        let (mut c, mut approach) = (c, closing.approach);
                        if let Some(solved) = closing.solved {
                            // Rapier's plastic solve of the pair is undone, and the impact acts
                            // along the line the balls touch along: mixing the two lines lost
                            // energy at e = 1.
                            if let Some((along, change)) = solved.undo {
                                let along = Contact { normal: along, ..c };
                                let (_, inv_a, inv_b) = contacts::relative(&along, &balls, &frame);
                                contacts::push_apart(&along, -change / (inv_a + inv_b), &mut balls, &mut frame);
                            }
                            c.normal = solved.normal;
                            // It strikes at the speed it approaches with now, after the
                            // step's impacts before it.
                            approach = -contacts::relative(&c, &balls, &frame).0;
                            if approach <= 0.0 {
                                continue;
                            }
                        }
                        (approach, contacts::strike(&c, approach, e, &mut balls, &mut frame))
                    }
                    Other::Wall(_) if undone[c.ball] => {
                        // A ball of a group in flight strikes the walls at the speed it
                        // approaches them with when its turn comes, as they move then: the
                        // frame's closed form and the step's wall impacts before this one.
                        let (n, b) = (c.normal, body_of[c.ball]);
                        let walls_then = kicks.walls_then(b, (vs[b], v1[b]), closing.tau, h);
                        let approach = contacts_dot(balls.v[c.ball], n) - n[0] * walls_then;
                        if approach <= 0.0 {
                            continue;
                        }
                        let (impulse, lost) = kicks.strike(b, (mass[c.ball], body_mass[b]), n[0], approach, e, (closing.tau, h));
                        contacts::push_apart(&c, impulse, &mut balls, &mut frame);
                        (approach, lost)
                    }
                    Other::Wall(_) => {
                        let n = c.normal;
                        let b = body_of[c.ball];
                        // Rapier stopped the ball at its own approach: what the impacts before
                        // this one did to it and to the walls shifts that approach.
                        let w0 = closing.w0 + n[0] * kicks.change[b] - change(balls.v, c.ball, n);
                        let (tau, approach) = contacts::closing(closing.gap0, w0, closing.g_n, h);
                        if approach <= 0.0 {
                            continue;
                        }
                        // Eq. 9-10 with the frame as it is at this impact's turn and instant:
                        // the ball leaves at the walls' normal velocity then, less `e` times the
                        // approach, less the frame's share of the recoil.
                        let m = mass[c.ball];
                        let walls_then = kicks.walls_then(b, (vs[b], v1[b]), tau, h);
                        let (impulse, lost) = kicks.strike(b, (m, body_mass[b]), n[0], approach, e, (tau, h));
                        let ball_after = n[0] * walls_then + approach - impulse / m;
                        let ball_now = contacts_dot(balls.v[c.ball], n);
                        contacts::push_apart(&c, m * (ball_now - ball_after), &mut balls, &mut frame);
                        (approach, lost)
                    }
                };
                step_impact_loss += lost;
                impacts.push(impact_record(t1, &c, approach, lost));
                if !piled(&c, &in_pile) {
                    struck_last_step.push(c.ball, c.other);
                }
                report.new_contact_impacts += 1;
                kicked[c.ball] = true;
                if let Other::Ball(j) = c.other {
                    kicked[j] = true;
                }
            }
            // Touching pairs the impacts set approaching strike in turn, the fastest first.
            if !new.is_empty() {
                let resting = |c: &Contact| resting_speed(c, &in_pile, &walls_a);
                let touches = |c: &Contact| {
                    c.gap <= touching
                        || matches!(c.other, Other::Ball(j) if any_undone && undone[c.ball] && undone[j]
                            && flights::kept_touching((c.ball, j), (&before.x, &before.v), &radius, (touching, h)))
                };
                cascade.run(&found, touches, &mut kicked, resting, (&mut balls, &mut frame), |c, approach, balls, frame| {
                    let lost = contacts::strike(c, approach, e, balls, frame);
                    step_impact_loss += lost;
                    impacts.push(impact_record(t1, c, approach, lost));
                    if !piled(c, &in_pile) {
                        struck_last_step.push(c.ball, c.other);
                    }
                    report.knock_on_impacts += 1;
                });
            }
        }
        if any_undone {
            kicked.iter_mut().zip(&undone).for_each(|(k, u)| *k |= u);
            now.write_spins(&mut world, &undone);
            parted.iter_mut().for_each(|p| *p = false);
            if flights::part_pressed(&found, (flights.struck_into_wall(), touching), (&before.x, &mut now.x), (&radius, &mass), &mut parted)
            {
                now.write_positions(&mut world, &parted);
            }
        }
        now.write_velocities(&mut world, &kicked);
        impact_loss += step_impact_loss;
        // What Rapier's step took beyond the impact law's losses (see
        // `SpatialReport::contact_loss`): the balls' and the frame's energy change, less
        // gravity's work on the balls' displacement, less the impacts' losses.
        let kinetic = |s: &BallState| -> f64 {
            (0..n).map(|i| 0.5 * mass[i] * contacts_dot(s.v[i], s.v[i]) + 0.5 * inertia[i] * contacts_dot(s.w[i], s.w[i])).sum()
        };
        let gravity_work: f64 = (0..n).map(|i| mass[i] * contacts_dot(g, std::array::from_fn(|a| now.x[i][a] - before.x[i][a]))).sum();
        let moved = kicks.travel.iter().any(|&d| d != 0.0);
        let frame_jump: f64 = (0..bodies).map(|b| 0.5 * body_mass[b] * (frame.vs[b] * frame.vs[b] - v1[b] * v1[b])).sum::<f64>()
            + if moved { carrier.travel_energy(t1, &kicks.travel) } else { 0.0 };
        // The carrier's closed form did work on the mass it carried: its own energy changed by
        // the excitation's work, less its dampers' loss, less that work.
        let carried_work: f64 = (0..bodies).map(|b| 0.5 * carrying[b] * (v1[b] * v1[b] - vs[b] * vs[b])).sum();
        let step_loss = -(kinetic(&now) - kinetic(&before) - gravity_work + frame_jump - carried_work) - step_impact_loss;
        contact_loss += step_loss;
        report.worst_step_gain = report.worst_step_gain.max(-step_loss);
        // Samples in the step: the carrier in closed form (impulses land at the step's end),
        // the balls along their straight path with their old velocity; then the carrier goes
        // on from the impulses, and the samples at the step's end see it so.
        while next_sample < sample_count {
            let ts = next_sample as f64 * scene.sample_dt;
            if ts > t1 || scene.sample_at_step_end(ts, t1, h) {
                break;
            }
            let wgt = ((ts - t0) / h).clamp(0.0, 1.0);
            let b = &before;
            let a = &now;
            sample(&mut recorder, scene, &carrier, ts, carrier.states(ts.max(t0))[0], |i| {
                (std::array::from_fn(|k| b.x[i][k] + wgt * (a.x[i][k] - b.x[i][k])), b.v[i])
            });
            next_sample += 1;
        }
        // What the walls dragged along in the step, from the balls no impact struck.
        let mut response = vec![0.0; bodies];
        for i in (0..n).filter(|&i| !kicked[i]) {
            response[body_of[i]] += pushed[i];
        }
        let change: Vec<f64> = (0..bodies).map(|b| v1[b] - vs[b]).collect();
        carried.update(&response, &change);
        let ends: Vec<(f64, f64)> = x1.iter().copied().zip(v1.iter().copied()).collect();
        carrier.restart_bodies(t1, &ends, &frame.vs, &carried.mass, &kicks.travel).map_err(ModelError::Refused)?;
        // Rapier's walls go where the impulses took them.
        let x1: Vec<f64> = if moved { x1.iter().zip(&kicks.travel).map(|(x, d)| x + d).collect() } else { x1 };
        if moved {
            for (d, damper) in world.dampers.iter_mut().enumerate() {
                let x = x1[body_of_damper[d]];
                damper.physics.bodies[damper.frame].set_translation(Vector::new(x as f32, 0.0, 0.0), false);
            }
        }
        while next_sample < sample_count && scene.sample_at_step_end(next_sample as f64 * scene.sample_dt, t1, h) {
            let a = &now;
            sample(&mut recorder, scene, &carrier, next_sample as f64 * scene.sample_dt, (x1[0], frame.vs[0]), |i| (a.x[i], a.v[i]));
            next_sample += 1;
        }
        xs = x1;
        vs = frame.vs;
        t = t1;
        steps += 1;
        let energy = energy_of(&carrier, &now, t, &xs, &vs);
        let energy_in = initial_energy + forcing_work;
        if energy > energy_in + energy_gain_allowance(scene, energy_in) {
            return Err(ModelError::Unstable {
                scene: scene.name.clone(),
                model: Model::Rapier,
                t,
                reason: format!(
                    "at t = {t:.6e} s the system holds {energy:.6e} J, more than the {energy_in:.6e} J put in and what Rapier's resting contacts may lift"
                ),
            });
        }
    }
    meter.finish(scene.horizon, steps);
    report.steps = steps;
    report.contact_loss = contact_loss;
    let mut run = finish(&carrier, t, &xs, &vs, &now, recorder, impacts, damping_loss, impact_loss, contact_loss, forcing_work, steps);
    // The steps' sum ends within a relative 1e-12 of the horizon; the run covered it.
    run.horizon = scene.horizon;
    run.wall_time_s = meter.elapsed();
    Ok((run, report))
}

/// Ball `b`'s vector less ball `a`'s, of `v` (positions or velocities).
fn between(v: &[[f64; 3]], a: usize, b: usize) -> [f64; 3] {
    std::array::from_fn(|k| v[b][k] - v[a][k])
}
