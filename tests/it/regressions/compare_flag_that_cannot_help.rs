//! `lpc compare` on a scene with friction that the reference refuses for another reason too
//! (several dampers whose balls, once frictionless, stay on their lines) told the user that
//! `--frictionless-reference` would compare the models, which it could not: the frictionless
//! copy is refused as well. The flag is suggested only where friction is all the reference
//! refuses.

use crate::common::lpc;

/// Two boxes on floors 2 and 3 of a building, each with two balls on its axis, with friction:
/// without friction the balls stay on their lines, where the reference holds one container.
const TWO_DAMPERS_ON_LINES: &str = "[structure]\nmasses = [1.35, 1.35, 1.35]\nstiffnesses = [4364.0, 4364.0, 4364.0]\n\
     damping_ratios = [0.016, 0.016, 0.016]\ninitial_displacements = [0.005, 0.01, 0.015]\n\
     [[damper]]\nfloor = 2\n[damper.container]\nlength = 0.06\nwidth = 0.04\nheight = 0.04\n\
     [[damper.ball]]\nposition = [0.01, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n\
     [[damper.ball]]\nposition = [0.03, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n\
     [[damper]]\nfloor = 3\n[damper.container]\nlength = 0.06\nwidth = 0.04\nheight = 0.04\n\
     [[damper.ball]]\nposition = [0.01, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n\
     [[damper.ball]]\nposition = [0.03, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n\
     [world]\nrestitution = 0.6\nfriction = 0.1\n[run]\nhorizon = 0.1\nsample_dt = 0.001\n";

#[test]
fn compare_names_the_reason_without_a_flag_that_cannot_help() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two-dampers-on-lines.toml");
    std::fs::write(&path, TWO_DAMPERS_ON_LINES).unwrap();
    let o = lpc(["compare", path.to_str().unwrap(), "--horizon", "0.01"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(stderr.contains("2 dampers"), "{stderr}");
    assert!(!stderr.contains("--frictionless-reference"), "{stderr}");
}
