//! Issue 30: `series.csv` of a scene whose balls move across the motion has `y1, z1, ...`
//! after the balls' `x` and `v`, and reading it back (`lpc plot` on a run's directory, the
//! render tests) took those columns for twice as many balls. They are now read as the balls'
//! places across the motion, and the series comes back as it was written.

use crate::common::lpc_command;
use lpc_damper::model::{Model, RunOptions};
use lpc_damper::output::figures::read_series_csv;

#[test]
fn a_spatial_series_reads_back_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let o = lpc_command()
        .args(["run", "scenes/planar-bed.toml", "--model", "rapier", "--horizon", "0.01", "--out", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut scene = lpc_damper::scene::load_scene("scenes/planar-bed.toml").unwrap();
    scene.horizon = 0.01;
    let run = Model::Rapier.simulate(&scene, &RunOptions::default()).unwrap();
    let read = read_series_csv(&dir.path().join("series.csv")).unwrap();
    assert_eq!(read.balls(), scene.balls.len());
    assert!(read.has_across());
    assert!(read == run.series, "the series read back differs from the run's");
}
