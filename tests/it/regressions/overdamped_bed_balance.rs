//! Issue 31 (the compliant model in space), found by `lpc stress --beds --models compliant`
//! (seed 31, shrunk): a bed of 106 balls with restitution 0 missed its energy balance by 3 % of
//! the energy put in. Its contacts are overdamped (`e` raised to 1e-3), and the steps were up to
//! half a contact's damping time, where velocity Verlet's damping errs by a few percent. The
//! step now keeps to a fifth of it (`DAMPING_STEP`), an error of about `0.2^2 / 12`.

use crate::common::scene_from_toml;
use lpc_damper::compliant::spatial::STEPS_PER_CONTACT;
use lpc_damper::model::RunOptions;
use lpc_damper::studies::stress::judge;
use lpc_damper::Model;

#[test]
fn an_overdamped_bed_closes_its_energy_balance() {
    let scene = scene_from_toml(
        r#"
[frame]
mass = 1.35
stiffness = 1.9601755355565684
damping = 0.08343156255231088
initial_displacement = 0.01169597699620907
[container]
length = 0.05016071340115164
width = 0.04395446327595777
height = 0.04395446327595777
[world]
gravity = [0.0, 0.0, -9.81]
friction = 0.16305889915000793
restitution = 0.0
[bed]
count = 106
radii = [0.0031085193264468016, 0.0014643884968338627]
density = 7800.0
placement = "lattice"
seed = 31
[run]
horizon = 0.028766108828942268
sample_dt = 0.000014383054414471135
"#,
    );
    let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    judge(Model::Compliant, &scene, &run).unwrap();
    // The contacts' stiffness bound, independent of the damping step: `(pi / 50)^2` of what
    // flows through the contacts (the energy put in and, once more, what they take).
    let a = &run.energy;
    let residual = a.initial + a.forcing_work - a.final_ - a.damping_loss - a.impact_loss;
    let bound = (std::f64::consts::PI / STEPS_PER_CONTACT).powi(2) * (a.initial + 2.0 * a.impact_loss);
    assert!(residual.abs() <= bound, "balance off by {residual:e} J, more than {bound:e} J");
}
