//! Issue 32: a stress draw (`lpc stress --structures`, seed 89) of one storey shaken by random
//! ground motion closed the compliant model's energy balance to only 2.3e-8, past its bound
//! (the steps times the tolerance). Its steps ran across the record's points, where the
//! ground's acceleration kinks, and the error estimate did not see the kink. Steps now end on
//! the points, and a step starting on one differentiates the load on its own side.

use crate::common::scene_from_toml;
use lpc_damper::model::{Model, RunOptions};

const SHAKEN_STOREY: &str = r#"
name = "stress-89"
[structure]
masses = [3.842923165647744]
stiffnesses = [33.834381513416126]
rayleigh = [0.46723306145938165, 0.007592217705119489]
initial_displacements = [-0.011964334590801587]
damper_floor = 1
[balls]
arrangement = "L"
large_mass = 0.11
mass_ratio = 10.0
density = 8000.0
restitution = 0.9
gap = "0.25 Rr"
clearance = "1 Rr"
[run]
horizon = 0.015678709519797336
sample_dt = 0.00001
[forcing]
kind = "random"
ground_frequency = 0.7420783417669327
ground_damping = 0.5684614889610782
intensity = 0.0014778440162335833
duration = 0.06271483807918934
step = 0.0062714838079189344
seed = 89
"#;

#[test]
fn steps_across_a_record_point_keep_the_balance() {
    let scene = scene_from_toml(SHAKEN_STOREY);
    let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    lpc_damper::studies::stress::judge(Model::Compliant, &scene, &run).unwrap();
}
