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

/// `series.csv` is formatted in chunks of rows on every thread: it must not depend on their
/// number, and it must hold every value of the series, each read back to the same `f64`.
#[test]
fn series_csv_is_the_same_on_any_threads_and_reads_back_exactly() {
    let mut scene = load("examples/scenes/small-box-building.toml").unwrap().scene.unwrap();
    scene.horizon = 0.3;
    let run = Model::Rapier.simulate(&scene, &lpc_damper::model::RunOptions::default()).unwrap();
    let s = &run.series;
    assert!(s.has_across() && s.floor_count() == 3 && s.len() > 256, "the run has balls in space, floors and several chunks");
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| lpc_damper::output::series_csv(&run))
    };
    let text = on(1);
    assert_eq!(text, on(3));
    let mut reader = csv::Reader::from_reader(text.as_slice());
    let header = reader.headers().unwrap().clone();
    let rows: Vec<Vec<f64>> = reader.records().map(|r| r.unwrap().iter().map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), s.len());
    let column = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"));
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), header.len());
        let same = |name: &str, value: f64| assert_eq!(row[column(name)].to_bits(), value.to_bits(), "{name} at row {k}");
        same("t", s.t()[k]);
        same("xs", s.xs()[k]);
        for i in 0..s.balls() {
            same(&format!("x{}", i + 1), s.x(i)[k]);
            same(&format!("v{}", i + 1), s.v(i)[k]);
            let [y, z] = s.across(i, k);
            same(&format!("y{}", i + 1), y);
            same(&format!("z{}", i + 1), z);
        }
        for i in 0..3 {
            let (u, v, a) = s.floor(i, k).unwrap();
            same(&format!("xs{}", i + 1), u);
            same(&format!("vs{}", i + 1), v);
            same(&format!("as{}", i + 1), a);
        }
    }
}
