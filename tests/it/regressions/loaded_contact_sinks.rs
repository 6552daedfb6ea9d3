//! Issue 6: Rapier's soft contacts let a ball pressed by a fast accelerating wall sink past the
//! allowed error (1.2e-4 m for a small ball carried by a wall at 280 m/s and 1e5 m/s^2), which
//! the stress run reported as a ball outside the container. The plug-in now projects sunk balls
//! back (positions only) and bounds the step by the walls' chord error.

use crate::common;
use lpc_damper::model::RunOptions;
use lpc_damper::Model;

const SCENE: &str = r#"
name = "stress-12"
[frame]
mass = 1.35
stiffness = 243325.7405717183
damping = 0.0
initial_displacement = "-45.17213853470385 Rr"
[balls]
arrangement = "S"
large_mass = 0.11
mass_ratio = 10.0
density = 8000.0
restitution = 0.9
gap = "0.25 Rr"
clearance = "1 Rr"
[run]
horizon = 0.00974313617852078
sample_dt = 0.00001
"#;

#[test]
fn a_ball_carried_by_a_fast_wall_stays_inside() {
    let s = common::scene_from_toml(SCENE);
    let run = Model::Rapier.simulate(&s, &RunOptions::default()).unwrap();
    let c = s.container.unwrap();
    let r = s.balls[0].radius;
    let worst = (0..run.series.len())
        .map(|k| {
            let (x, xs) = (run.series.x(0)[k], run.series.xs()[k]);
            (x - r - xs).min(xs + c.length - x - r)
        })
        .fold(f64::INFINITY, f64::min);
    // Rapier's allowed contact error is 0.005 length units (5e-5 m).
    assert!(worst >= -5e-5, "sank {:e} m into a wall", -worst);
    assert!(run.impacts.len() > 5, "the wall must carry the ball: {} impacts", run.impacts.len());
    lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap();
}
