//! `lpc bench` reports, for each setting, exactly the errors `lpc compare` reports for it.

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::Stepping;
use lpc_damper::scene::{load_scene, scenes_dir};
use lpc_damper::studies::bench::{bench_scene, Plan};
use lpc_damper::studies::compare::errors;
use lpc_damper::Model;

#[test]
fn bench_errors_equal_compare_errors() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let plan = Plan {
        models: vec![Model::Reference, Model::Rapier],
        steppings: vec![Stepping::Fixed, Stepping::Aligned],
        dts: vec![5e-4],
        solver_iterations: vec![4],
        tolerances: vec![],
        repeat: 1,
    };
    let rows = bench_scene(&scene, &plan, &|| {}).unwrap();
    assert_eq!(rows.len(), 3);
    let reference = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    assert_eq!(rows[0].errors.max_xs_early, 0.0);
    for (row, stepping) in rows[1..].iter().zip([Stepping::Fixed, Stepping::Aligned]) {
        let mut s = scene.clone();
        s.rapier.stepping = Some(stepping);
        s.rapier.dt = Some(5e-4);
        s.rapier.solver_iterations = Some(4);
        let expected = errors(&Model::Rapier.simulate(&s, &RunOptions::default()).unwrap(), &reference);
        assert_eq!(row.errors, expected, "{stepping:?}");
        assert_eq!(row.settings.stepping, stepping.name());
    }
    // The reference row is the only one of its model, so it is on its front.
    assert!(rows[0].pareto);
}
