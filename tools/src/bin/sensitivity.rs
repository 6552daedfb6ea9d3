//! How chaotic is a paper scene? Runs the reference with the initial displacement perturbed by
//! a relative `eps` and prints `lpc compare`'s errors of the perturbed run against the
//! unperturbed one: `cargo run --release -p lpc-tools --bin sensitivity -- scenes/lpc-lsl.toml`.
use lpc_damper::model::{Model, RunOptions};

fn main() {
    let path = std::env::args().nth(1).unwrap_or_else(|| "scenes/lpc-lsl.toml".into());
    let scene = lpc_damper::scene::load_scene(&path).unwrap();
    let base = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    println!("{:>8} {:>10} {:>12} {:>12} {:>10} {:>8}", "eps", "rms xs mm", "early xs mm", "settle d s", "loss d %", "impacts");
    for eps in [1e-12, 1e-9, 1e-6, 1e-4, 1e-3] {
        let mut s = scene.clone();
        s.initial_displacement *= 1.0 + eps;
        s.initial_positions.iter_mut().for_each(|x| *x += scene.initial_displacement * eps);
        let run = Model::Reference.simulate(&s, &RunOptions::default()).unwrap();
        let e = lpc_damper::studies::compare::errors(&run, &base);
        println!(
            "{:>8.0e} {:>10.4} {:>12.6} {:>12} {:>10.3} {:>8}",
            eps,
            e.rms_xs * 1e3,
            e.max_xs_early * 1e3,
            e.settling_time_diff.map_or("n/a".into(), |d| format!("{d:+.3}")),
            e.impact_loss_diff * 100.0,
            e.impact_count_diff
        );
    }
}
