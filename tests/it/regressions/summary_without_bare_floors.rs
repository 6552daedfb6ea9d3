//! Issue 32: `lpc run --out` on a structure printed each floor's response without the damper but
//! left it out of `summary.json`: the run's directory was written from the run alone, not from
//! the summary the command had completed with the bare building's floors. It is now written
//! from that summary.

use crate::common::lpc_command;

#[test]
fn a_structures_summary_keeps_its_floors_without_the_damper() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = lpc_command().args(["run", "scenes/mdof-3storey.toml", "--horizon", "1", "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    for key in ["floors", "floors_without_damper"] {
        assert_eq!(summary[key].as_array().map(|f| f.len()), Some(3), "{key}");
    }
}
