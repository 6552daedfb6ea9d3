//! Runs one stress scene (by seed, or a TOML file through the reference) and prints its time:
//! `cargo run --release -p lpc-tools --bin stress_one -- SEED [MAX_HORIZON] [MODEL]` (`--toml` prints
//! the scene file instead, `--bed` draws its balls as a bed as `lpc stress --beds` does) or
//! `... -- scene.toml`.
use lpc_damper::model::{Model, RunOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args[1].ends_with(".toml") {
        let scene = lpc_damper::scene::load_scene(&args[1]).unwrap();
        let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
        println!(
            "events {} impacts {} events per simulated second {:.0}",
            run.events,
            run.impacts.len(),
            run.events as f64 / scene.horizon
        );
        return;
    }
    let seed: u64 = args[1].parse().unwrap();
    let max_h: f64 = args.get(2).map_or(100.0, |s| s.parse().unwrap());
    let model: lpc_damper::Model = args.get(3).filter(|s| !s.starts_with("--")).map_or("reference", |s| s).parse().unwrap();
    let mut file = lpc_damper::studies::stress::random_scene_file(seed, max_h, false);
    if args.iter().any(|a| a == "--bed") {
        file = lpc_damper::studies::stress::with_bed(file, seed);
    }
    if args.iter().any(|a| a == "--toml") {
        println!("{}", toml::to_string(&file).unwrap());
        return;
    }
    let scene = lpc_damper::scene::from_file(file, "s", "s").unwrap().scene.unwrap();
    let t = std::time::Instant::now();
    let r = lpc_damper::studies::stress::judge_run(model, &scene, None);
    if let Err(f) = &r {
        println!("{}", f.detail);
    }
    println!(
        "seed {seed}: {:.3} s balls {} horizon {:.2} -> {:?}",
        t.elapsed().as_secs_f64(),
        scene.balls.len(),
        scene.horizon,
        r.map(|p| match p {
            lpc_damper::studies::stress::Passed::Run(r) => Some((r.events, r.impacts.len())),
            lpc_damper::studies::stress::Passed::Refused { .. } | lpc_damper::studies::stress::Passed::Stopped(_) => None,
        })
        .map_err(|f| f.check)
    );
}
