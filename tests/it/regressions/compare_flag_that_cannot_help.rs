//! `lpc compare` on a scene with friction that the reference refuses for another reason too
//! (several dampers) told the user that `--frictionless-reference` would compare the models,
//! which it could not: the frictionless copy is refused as well. The flag is suggested only
//! where friction is all the reference refuses.

use crate::common::lpc;

#[test]
fn compare_names_the_reason_without_a_flag_that_cannot_help() {
    let o = lpc(["compare", "examples/scenes/dampers-two-floors.toml", "--horizon", "0.01"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(stderr.contains("2 dampers"), "{stderr}");
    assert!(!stderr.contains("--frictionless-reference"), "{stderr}");
}
