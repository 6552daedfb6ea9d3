//! An ensemble of a scene without `[tolerances]` panicked (the draw blamed its failures on
//! the first toleranced parameter, of which there was none). Every member is the nominal scene.

use lpc_damper::metrics::Headline;
use lpc_damper::model::{Limits, RunOptions};
use lpc_damper::studies::ensemble;
use lpc_damper::Model;

#[test]
fn an_ensemble_without_tolerances_is_the_nominal_scene_repeated() {
    let l = lpc_damper::scene::parse(crate::common::LSL_TOML, "test.toml", "test").unwrap();
    assert!(l.tolerances.is_none());
    let nominal = l.scene.as_ref().unwrap();
    let members = ensemble::draw(&l.file, &l.path, nominal, None, 3, None).unwrap();
    let single = Headline::of_run(&Model::Reference.simulate(nominal, &RunOptions::default()).unwrap()).values();
    let runs = ensemble::run_members(&members, Model::Reference, Limits::NONE, false, &|| {}).unwrap();
    assert!(members.columns.is_empty());
    assert_eq!(runs.metrics, vec![single; 3]);
}
