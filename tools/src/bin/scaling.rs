//! How cost grows with the number of balls, the horizon and the sweep size, for both models.
//! `cargo run --release -p lpc-tools --bin scaling` prints the tables quoted in docs/BENCHMARKS.md.

use std::time::Instant;

use lpc_damper::model::{Limits, Model, RunOptions};
use lpc_damper::scene::{load, load_scene, scenes_dir, Arrangement, Length};
use lpc_damper::studies::sweep::{run_sweep, sweep_scenes};

fn main() {
    let lsl = scenes_dir().join("lpc-lsl.toml");
    println!("## Balls (alternating L and S, gap 0.25 Rr, clearance 2 Rr, 5 s)\n");
    println!("| balls | model | wall s per sim s | steps or events per sim s | impacts |");
    println!("|---|---|---|---|---|");
    for n in [1usize, 3, 11, 31, 101] {
        let mut loaded = load(&lsl).unwrap();
        let letters: String = (0..n).map(|i| if i % 2 == 0 { 'L' } else { 'S' }).collect();
        loaded.file.balls.as_mut().unwrap().arrangement = Arrangement::Letters(letters);
        let scene = lpc_damper::scene::from_file(loaded.file, "scaling", "scaling").unwrap().scene.unwrap();
        for model in [Model::Reference, Model::Rapier] {
            let run = model.simulate(&scene, &RunOptions::default()).unwrap();
            println!(
                "| {n} | {} | {:.2e} | {:.0} | {} |",
                model.name(),
                run.wall_time_s / scene.horizon,
                run.events as f64 / scene.horizon,
                run.impacts.len()
            );
        }
    }
    println!("\n## Horizon (lpc-lsl)\n");
    println!("| horizon s | model | wall s | wall s per sim s | impacts |");
    println!("|---|---|---|---|---|");
    for horizon in [5.0, 50.0, 500.0] {
        let mut scene = load_scene(&lsl).unwrap();
        scene.horizon = horizon;
        for model in [Model::Reference, Model::Rapier] {
            let run = model.simulate(&scene, &RunOptions::default()).unwrap();
            println!(
                "| {horizon} | {} | {:.3e} | {:.2e} | {} |",
                model.name(),
                run.wall_time_s,
                run.wall_time_s / horizon,
                run.impacts.len()
            );
        }
    }
    println!("\n## Sweep size (gap of lpc-lsl from 0.1 to 1 Rr, 5 s each, rayon on {} threads)\n", rayon::current_num_threads());
    println!("| values | model | wall s | scene-runs per second |");
    println!("|---|---|---|---|");
    for (values, models) in
        [(4usize, &[Model::Reference, Model::Rapier][..]), (16, &[Model::Reference, Model::Rapier]), (256, &[Model::Reference])]
    {
        let mut loaded = load(scenes_dir().join("sweep-gap.toml")).unwrap();
        loaded.file.sweep.as_mut().unwrap().values = (0..values).map(|k| Length::Rr(0.1 + 0.9 * k as f64 / (values - 1) as f64)).collect();
        let scenes = sweep_scenes(&loaded).unwrap();
        for &model in models {
            let start = Instant::now();
            run_sweep("gap", &scenes, model, Limits::NONE, &|| {}).unwrap();
            let wall = start.elapsed().as_secs_f64();
            println!("| {values} | {} | {wall:.3} | {:.1} |", model.name(), values as f64 / wall);
        }
    }
}
