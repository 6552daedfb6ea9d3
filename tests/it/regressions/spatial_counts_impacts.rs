//! The contact model's spatial path kept every impact in memory until the run's end even when
//! asked only to count them (`--impacts count`): a resting pile at 0.1 ms steps books some 16
//! million knock-on impacts a simulated second, 4 GB, so a run of ten seconds would have been
//! killed for memory. It now counts them as they come, and a run that keeps them stops past the
//! most memory holds.

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;
use lpc_damper::run::ImpactRecord;
use lpc_damper::scene::{load_scene, scenes_dir};

#[test]
fn a_spatial_run_that_counts_its_impacts_keeps_none() {
    let mut scene = load_scene(scenes_dir().join("particle-box.toml")).unwrap();
    scene.horizon = 0.05;
    let kept = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    let counted = simulate_spatial(&scene, &RunOptions { impacts: ImpactRecord::Count, ..RunOptions::default() }).unwrap();
    assert!(counted.impacts.is_empty());
    assert!(kept.impacts.len() > 100);
    assert_eq!(counted.impact_count(), kept.impacts.len());
    assert_eq!(counted.energy, kept.energy);
}
