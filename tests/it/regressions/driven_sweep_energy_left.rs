//! Issue 32: `lpc sweep` printed `NaN` as the energy left of a driven scene (a ground record
//! starts from rest, so no share of an initial energy is left). It now prints `-`, as for a
//! settling time never reached, and a structure's table adds the building-wide peaks.

use crate::common::lpc_command;

#[test]
fn a_driven_sweep_prints_no_nan() {
    let o = lpc_command().args(["sweep", "scenes/mdof-3storey-record.toml", "--x", "damper_floor=2,3", "--horizon", "1"]).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!stdout.contains("NaN"), "{stdout}");
    assert!(stdout.contains("drift mm") && stdout.contains("roof mm"), "{stdout}");
}
