//! The chain experiment's rules (`[chain]`): the KER cases it runs.

use super::damper::arrangement_balls;
use crate::scene::format::{self, Arrangement};
use crate::scene::geometry::ball_radius;
use crate::scene::settings::{CompliantSettings, RapierSettings, ReferenceSettings};
use crate::scene::space::Space;
use crate::scene::validator::Validator;
use crate::scene::{ChainCase, Scene, SceneError, CHAIN_HORIZON};

pub(in crate::scene) fn build_chain(
    c: &format::ChainFile,
    run: &format::RunFile,
    reference: ReferenceSettings,
    name: &str,
    v: &Validator,
) -> Result<Vec<ChainCase>, SceneError> {
    let large_mass = v.positive("chain.large_mass", c.large_mass)?;
    let mass_ratio = v.positive("chain.mass_ratio", c.mass_ratio)?;
    let density = v.positive("chain.density", c.density)?;
    let restitution = v.restitution("chain.restitution", c.restitution)?;
    let speed = v.positive("chain.incident_speed", c.incident_speed)?;
    let rr = ball_radius(large_mass, density);
    let gap = v.non_negative("chain.gap", c.gap.metres(rr))?;
    let (horizon, sample_dt) = v.run(run, CHAIN_HORIZON)?;
    if c.large_counts.is_empty() {
        return Err(v.err("chain.large_counts", "is empty"));
    }
    if c.small_balls.is_empty() {
        return Err(v.err("chain.small_balls", "is empty: give [false], [true] or both"));
    }
    let mut cases = Vec::new();
    for &small in &c.small_balls {
        for &nl in &c.large_counts {
            if !(1..=1000).contains(&nl) {
                return Err(v.err("chain.large_counts", &format!("must lie in 1..=1000 (got {nl})")));
            }
            let mut letters = String::from("L");
            for i in 0..nl {
                if i > 0 && small {
                    letters.push('S');
                }
                letters.push('L');
            }
            let balls = arrangement_balls(&Arrangement::Letters(letters), large_mass, mass_ratio, density, "chain", v)?;
            let mut positions = Vec::with_capacity(balls.len());
            let mut x = 0.0;
            for (i, b) in balls.iter().enumerate() {
                if i > 0 {
                    x += gap + b.radius;
                }
                positions.push(x);
                x += b.radius;
            }
            let mut velocities = vec![0.0; balls.len()];
            velocities[0] = speed;
            let balls_len = balls.len();
            cases.push(ChainCase {
                large: nl,
                small,
                scene: Scene {
                    name: format!("{name}-{nl}L{}", if small { format!("-{}S", nl - 1) } else { String::new() }),
                    frame: None,
                    container: None,
                    balls,
                    restitution,
                    initial_displacement: 0.0,
                    initial_positions: positions,
                    initial_velocities: velocities,
                    horizon,
                    sample_dt,
                    reference,
                    rapier: RapierSettings::default(),
                    compliant: CompliantSettings::default(),
                    forcing: None,
                    reference_radius: rr,
                    space: Space::line(balls_len),
                    structure: None,
                    dampers: vec![],
                },
            });
        }
    }
    Ok(cases)
}
