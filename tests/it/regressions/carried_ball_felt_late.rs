//! A frame lost energy to the balls it carried: a ball rolling on the floor of a frame swinging
//! below friction's hold took 14 % of the system's energy in a second at 1 ms, and a settled bed
//! on the particle box's frame took twice the compliant model's energy. Rapier's walls are
//! kinematic: the frame moved by its closed form alone over a step, and what the walls gave the
//! balls reached it as an impulse at the step's end, a step late, which acts as a dashpot of
//! about the carried mass times the step times the frame's rate squared. The frame's closed form
//! now carries the mass its walls drag along (docs/MODEL.md §9, "Carried balls").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// A heavy ball rolls without slipping on the floor of a frame of its own mass: the two swing as
/// one oscillator of mass `ms + 2 m / 7`, keeping their energy.
#[test]
fn a_rolling_ball_rides_the_frame_as_its_share_of_mass() {
    let (ms, m, k, x0) = (1.0f64, 1.0f64, 865.0f64, 0.005f64);
    // The floor's largest acceleration, k x0 / (ms + 2 m / 7) = 3.4 m/s^2, needs a friction
    // force of 2/7 of the ball's weight times that over g: a tenth of it, well inside 0.3.
    let text = format!(
        "[frame]\nmass = {ms}\nstiffness = {k}\ndamping = 0.0\ninitial_displacement = {x0}\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.06\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nfriction = 0.3\nrestitution = 0.6\n\
         [[ball]]\nposition = [0.05, 0.0, -0.02]\nmass = {m}\nradius = 0.01\n\
         [rapier]\ndt = 0.001\n\
         [run]\nhorizon = 1.0\nsample_dt = 0.001\n"
    );
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    assert_eq!(run.impact_count(), 0);
    // The period of the frame's swing, from its zero crossings.
    let (t, xs) = (run.series.t(), run.series.xs());
    let crossings: Vec<f64> = (1..xs.len())
        .filter(|&i| (xs[i - 1] < 0.0) != (xs[i] < 0.0))
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * xs[i - 1] / (xs[i - 1] - xs[i]))
        .collect();
    let period = 2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let rolling = 2.0 * std::f64::consts::PI * ((ms + 2.0 * m / 7.0) / k).sqrt();
    // A sampled crossing is found to a step's share of the sample spacing over the run.
    assert!((period - rolling).abs() <= 1e-3 * rolling, "the frame swings at {period} s, rolling gives {rolling} s");
    // The system keeps its energy but for Rapier's soft contacts and the f32 solve: the lag
    // took 14 % of it in this second; 1 % is left for the rest.
    let lost = run.energy.contact_loss / run.energy.initial;
    assert!(lost.abs() <= 0.01, "the rolling ball took {:.2} % of the energy", 100.0 * lost);
}
