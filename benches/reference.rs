//! Criterion benchmarks of the reference model: one per paper scene (5 s horizon, 1 ms
//! samples), the forced LSL damper (4 s, where the frame's motion is not a free oscillation and
//! contacts are found by the forced root search), plus the chain experiment.
//! `cargo bench --bench reference`.

use criterion::{criterion_group, criterion_main, Criterion};
use lpc_damper::model::{Model, RunOptions};
use lpc_damper::scene::{load, load_scene, scenes_dir};

fn paper_scenes(c: &mut Criterion) {
    let mut group = c.benchmark_group("reference");
    for name in ["no-damper", "conventional", "lpc-lsl", "lpc-lslsl", "chain-lll", "forced-lsl"] {
        let scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
        group.bench_function(name, |b| b.iter(|| Model::Reference.simulate(std::hint::black_box(&scene), &RunOptions::default()).unwrap()));
    }
    let cases = load(scenes_dir().join("chain-ker.toml")).unwrap().chain.unwrap();
    group.bench_function("chain-ker (10 chains)", |b| {
        b.iter(|| {
            for c in &cases {
                Model::Reference.simulate(&c.scene, &RunOptions::default()).unwrap();
            }
        })
    });
    group.finish();
}

criterion_group!(benches, paper_scenes);
criterion_main!(benches);
