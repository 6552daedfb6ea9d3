//! Found by `lpc stress --beds --models compliant` (seed 97): one ball set on the floor of a
//! free frame at rest, so that next to nothing is put in.
//! The ball settles into its contact, trading 1e-8 J between gravity and the contact, and the
//! integration error of that (1e-11 J) was judged against the picojoule the stress checks take
//! for "nothing put in". The balance's tolerance now counts gravity's work on the balls (their
//! weight times the span of their heights) among the energies that flow.

use crate::common::scene_from_toml;
use lpc_damper::model::RunOptions;
use lpc_damper::studies::stress::judge;
use lpc_damper::Model;

#[test]
fn a_ball_settling_on_a_frame_at_rest_passes_the_balance() {
    let scene = scene_from_toml(
        r#"
[frame]
mass = 1.35
stiffness = 0.0
damping = 0.0
initial_displacement = -0.03892524153752126
[container]
length = 0.05100271475087894
width = 0.043545864886434985
height = 0.043545864886434985
[world]
gravity = [0.0, 0.0, -9.81]
friction = 0.08217754706581715
restitution = 1.0
[bed]
count = 1
radii = [0.007185786284890262]
density = 7800.0
placement = "lattice"
seed = 97
[run]
horizon = 0.00753453591165742
sample_dt = 0.00001
"#,
    );
    // The lattice leaves the ball a thousandth of its radius above the floor: that height is
    // all the energy it holds (docs/MODEL.md §6), under a microjoule.
    let (m, r) = (scene.balls[0].mass, scene.balls[0].radius);
    let above = m * 9.81 * 1e-3 * r;
    assert!((scene.initial_energy() - above).abs() <= 1e-9 * above, "{} J, expected {above} J", scene.initial_energy());
    let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    judge(Model::Compliant, &scene, &run).unwrap();
}
