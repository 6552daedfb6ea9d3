//! Issue 32: `mdof-3storey-random.toml` with most seeds never started. The building stood at
//! rest and the ground's acceleration started from 0, so the carrying floor's acceleration grew
//! as the square of time and was round-off for the first tens of nanoseconds; its round-off took
//! a sign against the parabola's, and the sign-change scan, which proved each piece with bounds
//! far larger than that parabola, split those nanoseconds into some 1e8 pieces. The fix takes
//! no sign change on a piece over which the acceleration is provably round-off (docs/MODEL.md
//! §16).

use lpc_damper::model::{Model, RunOptions};

#[test]
fn a_floor_starting_from_rest_under_a_ground_motion_from_zero_runs() {
    let dir = tempfile::tempdir().unwrap();
    for (k, slope) in [1.0, -1.0].into_iter().enumerate() {
        // The ground's acceleration from 0, either way, then back.
        std::fs::write(dir.path().join(format!("from-zero-{k}.txt")), format!("0 0\n0.01 {}\n0.02 0\n", 0.05 * slope)).unwrap();
        let text = crate::common::LSL_TOML.replace(
            "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0185",
            &format!(
                "[structure]\nmasses = [1.35, 1.35, 1.35]\nstiffnesses = [4364.0, 4364.0, 4364.0]\n\
                 damping_ratios = [0.016, 0.016, 0.016]\n[forcing]\nkind = \"record\"\nfile = \"from-zero-{k}.txt\""
            ),
        );
        let file = dir.path().join("scene.toml");
        std::fs::write(&file, text.replace("horizon = 5.0", "horizon = 0.5")).unwrap();
        let scene = lpc_damper::scene::load_scene(&file).unwrap();
        let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
        assert_eq!(run.horizon, 0.5);
        assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    }
}
