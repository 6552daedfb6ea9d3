//! The same scene and settings give identical results across runs and thread counts, for every model.

use lpc_damper::metrics::RunSummary;
use lpc_damper::scene::{load, scenes_dir};
use lpc_damper::studies::sweep::{run_sweep, sweep_scenes};
use lpc_damper::Model;

fn sweep_on(threads: usize, model: Model) -> Vec<RunSummary> {
    let loaded = load(scenes_dir().join("sweep-mass-ratio.toml")).unwrap();
    let scenes = sweep_scenes(&loaded).unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| run_sweep("mass_ratio", &scenes, model, lpc_damper::model::Limits::NONE, &|| {}))
        .unwrap()
        .into_iter()
        .map(|p| RunSummary { wall_time_s: 0.0, ..p.summary })
        .collect()
}

#[test]
fn sweeps_are_identical_on_one_and_two_threads() {
    for model in [Model::Reference, Model::Rapier, Model::Compliant] {
        let one = sweep_on(1, model);
        let two = sweep_on(2, model);
        assert_eq!(serde_json::to_string(&one).unwrap(), serde_json::to_string(&two).unwrap(), "{}", model.name());
        assert_eq!(one, sweep_on(2, model), "{}: second run differs", model.name());
    }
}
