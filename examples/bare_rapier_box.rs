//! The yardstick of the contact model's cost in space: a bare Rapier pipeline stepping a
//! scene's box of balls with Rapier's own restitution. The world is the contact model's (the
//! same walls on the kinematic frame and the same spheres under the same gravity and
//! friction), but every collider bounces with the scene's `e` (Rapier's average rule) and
//! Rapier keeps its default contact settings, with no impact law, strikes or checks. The frame
//! moves by its exact oscillator step and takes the opposite of the x momentum its walls give
//! the balls, as in the contact model. Prints the steps, the computing time and its cost per
//! simulated second; docs/BENCHMARKS.md 3.9 times it against `lpc run`:
//!
//! ```sh
//! cargo run --release --example bare_rapier_box -- SCENE [DT] [HORIZON]
//! ```
//!
//! (default: steps of 0.1 ms over the scene's horizon). A scene under an excitation or on a
//! structure is refused: the frame here vibrates freely.

use std::time::Instant;

use anyhow::{bail, Context};
use bevy_rapier3d::rapier::prelude::*;
use lpc_damper::oscillator::Oscillator;
use lpc_damper::rapier::spatial::rapier_world;
use lpc_damper::scene::load_scene;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else { bail!("usage: bare_rapier_box SCENE [DT] [HORIZON]") };
    let scene = load_scene(path)?;
    let dt: f64 = args.get(1).map_or(Ok(1e-4), |a| a.parse()).context("DT")?;
    let horizon: f64 = args.get(2).map_or(Ok(scene.horizon), |a| a.parse()).context("HORIZON")?;
    if !(dt > 0.0 && horizon > 0.0) {
        bail!("DT and HORIZON must be positive");
    }
    if scene.is_driven() || scene.structure.is_some() || scene.has_several_dampers() {
        bail!("{path}: the bare pipeline drives one damper on a frame in free vibration only");
    }
    let frame = scene.frame.context("the scene has no frame")?;
    let built = rapier_world(&scene).map_err(anyhow::Error::msg)?;
    let balls: Vec<RigidBodyHandle> = built.balls.iter().map(|b| b.body).collect();
    let mut world = built.dampers.into_iter().next().context("the scene has no damper")?;
    // Rapier's own: its contact settings and restitution, at the step asked for.
    let length_unit = world.physics.integration_parameters.length_unit;
    world.physics.integration_parameters = IntegrationParameters { dt: dt as f32, length_unit, ..IntegrationParameters::default() };
    for (_, collider) in world.physics.colliders.iter_mut() {
        collider.set_restitution(scene.restitution as f32);
        collider.set_restitution_combine_rule(CoefficientCombineRule::Average);
    }
    let masses: Vec<f64> = scene.balls.iter().map(|b| b.mass).collect();
    let oscillator = Oscillator::new(frame.mass, frame.damping, frame.stiffness);
    let (mut xs, mut vs) = (scene.initial_displacement, 0.0);
    let mut vx: Vec<f64> = balls.iter().map(|h| world.physics.bodies[*h].linvel().x as f64).collect();
    let steps = (horizon / dt).round().max(1.0) as u64;
    let started = Instant::now();
    for _ in 0..steps {
        let (x1, v1) = oscillator.state(xs, vs, dt);
        world.physics.bodies[world.frame].set_next_kinematic_translation(Vector::new(x1 as f32, 0.0, 0.0));
        world.physics.step();
        let mut momentum = 0.0;
        for (i, h) in balls.iter().enumerate() {
            let v = world.physics.bodies[*h].linvel().x as f64;
            momentum += masses[i] * (v - vx[i]);
            vx[i] = v;
        }
        (xs, vs) = (x1, v1 - momentum / frame.mass);
    }
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "{}: {} balls, {steps} steps of {dt} s, computed in {seconds:.3} s, {:.3} s per simulated second; xs {:.4} mm at the end",
        scene.name,
        scene.balls.len(),
        seconds / (steps as f64 * dt),
        xs * 1e3
    );
    Ok(())
}
