//! Criterion benchmarks of ensembles (issue 13's speed targets): lpc-lsl (5 s) with a gap
//! tolerance of 0.02 Rr, every member metrics-only.
//! - `reference/1000 members (2 threads)`: the wall time of a 1000-member ensemble on the
//!   global pool (two threads on the CI machine), and the same on one thread (the cost per
//!   member on one core), against one full run with its series.
//! - `rapier` and `compliant`: a 200-member ensemble on one thread against one full run of the
//!   nominal scene: the cost per member against a single run.
//!
//! `cargo bench --bench ensemble`.

use criterion::{criterion_group, criterion_main, Criterion};
use lpc_damper::model::{Limits, Model, RunOptions};
use lpc_damper::scene::{load, scenes_dir};
use lpc_damper::studies::ensemble::{draw, run_members, Ensemble};

fn lsl_with_tolerance() -> (lpc_damper::scene::Scene, Ensemble, Ensemble) {
    // The scene's own [tolerances]: gap 0.02 Rr.
    let l = load(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let nominal = l.scene.clone().unwrap();
    let big = draw(&l.file, &l.path, &nominal, l.tolerances.as_ref(), 1000, None).unwrap();
    let small = draw(&l.file, &l.path, &nominal, l.tolerances.as_ref(), 200, None).unwrap();
    (nominal, big, small)
}

fn ensembles(c: &mut Criterion) {
    let (nominal, big, small) = lsl_with_tolerance();
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut group = c.benchmark_group("reference");
    group.sample_size(20);
    group.bench_function("single run with series", |b| b.iter(|| Model::Reference.simulate(&nominal, &RunOptions::default()).unwrap()));
    group.bench_function("1000 members (global pool)", |b| {
        b.iter(|| run_members(&big, Model::Reference, Limits::NONE, false, &|| {}).unwrap())
    });
    group.bench_function("1000 members (1 thread)", |b| {
        b.iter(|| one_thread.install(|| run_members(&big, Model::Reference, Limits::NONE, false, &|| {}).unwrap()))
    });
    group.finish();
    for model in [Model::Rapier, Model::Compliant] {
        let mut group = c.benchmark_group(model.name());
        group.sample_size(10);
        group.bench_function("single run with series", |b| b.iter(|| model.simulate(&nominal, &RunOptions::default()).unwrap()));
        group.bench_function("200 members (1 thread)", |b| {
            b.iter(|| one_thread.install(|| run_members(&small, model, Limits::NONE, false, &|| {}).unwrap()))
        });
        group.finish();
    }
}

criterion_group!(benches, ensembles);
criterion_main!(benches);
