//! A run driven by an excitation reported `energy remaining` as a share of its initial energy:
//! a building shaken from rest by a record printed `not reached`, and a box of balls on it
//! (whose lattice starts with height energy) a share far above 100 %. An excitation puts
//! energy in as it goes, so what is left at the end says nothing of the damper. A driven run
//! now has no remaining share, and its summary gives what the damper took of the energy
//! dissipated instead.

use lpc_damper::metrics::metrics;
use lpc_damper::model::{Model, RunOptions};
use lpc_damper::scene::load_scene;

use crate::common::lpc_command;

#[test]
fn a_driven_run_has_no_energy_remaining() {
    for file in ["scenes/mdof-3storey-record.toml", "scenes/forced-lsl.toml"] {
        let scene = load_scene(file).unwrap();
        let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
        let m = metrics(&run);
        assert_eq!(m.energy_remaining, None, "{file}");
        // The damper's share of the energy dissipated is what the summary gives instead.
        let e = &run.energy;
        let share = (e.impact_loss + e.contact_loss) / (e.damping_loss + e.impact_loss + e.contact_loss);
        let o = lpc_command().args(["run", file]).output().unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let expected = format!("the damper took {:.1} % of the energy dissipated", 100.0 * share);
        assert!(stdout.contains(&expected), "{file}: expected `{expected}` in\n{stdout}");
    }
    // A free run keeps its share of the initial energy.
    let scene = load_scene("scenes/lpc-lsl.toml").unwrap();
    let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    let left = metrics(&run).energy_remaining.expect("a free run with energy has a remaining share");
    assert_eq!(left, run.energy.final_ / run.energy.initial);
}
