//! The compliant model against the reference as the balls stiffen (early xs error against
//! Young's modulus: contact durations scale as E^(-2/5)), and its energy balance against the
//! error tolerance. Figures of docs/BENCHMARKS.md, "Compliant model".
//!
//! `cargo run --release -p lpc-tools --bin compliant_convergence`

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::scene::{load_scene, scenes_dir};
use lpc_damper::studies::compare::errors;

fn main() {
    println!("early xs error (max |xs - xs_ref| over 0.5 s), mm");
    println!("{:>12} {:>10} {:>10} {:>10}", "E factor", "lpc-lsl", "conventional", "chain-lll");
    for factor in [1.0, 1e2, 1e4] {
        let mut row = format!("{factor:>12.0e}");
        for name in ["lpc-lsl", "conventional", "chain-lll"] {
            let mut scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
            scene.horizon = 0.5;
            scene.compliant.youngs_modulus *= factor;
            let reference = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
            let e = errors(&Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap(), &reference);
            row += &format!(" {:>10.4}", e.max_xs_early * 1e3);
        }
        println!("{row}");
    }
    println!("\nlpc-lsl, 5 s: energy balance error against the tolerance");
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    for tolerance in [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11] {
        let mut scene = scene.clone();
        scene.compliant.tolerance = tolerance;
        let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
        println!(
            "tolerance {tolerance:.0e}: balance error {:+.2e}, {} steps, {} impacts, {:.1} ms",
            run.energy.balance_error,
            run.events,
            run.impacts.len(),
            run.wall_time_s * 1e3
        );
    }
}
