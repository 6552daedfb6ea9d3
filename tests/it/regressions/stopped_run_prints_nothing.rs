//! A run that stopped (exit 1) with `--format json` printed nothing on standard output, while
//! `summary.json` of the run so far was written with `--out`: a script reading standard output
//! had no result and no reason. It now prints the run so far with its `stop` reason, and the
//! written summary carries the same reason.

use crate::common::lpc;

#[test]
fn a_stopped_run_prints_the_run_so_far_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = lpc([
        "run".as_ref(),
        "scenes/planar-bed.toml".as_ref(),
        "--max-steps".as_ref(),
        "200".as_ref(),
        "--format".as_ref(),
        "json".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let printed: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the run so far, as JSON");
    let stop = printed["stop"].as_str().expect("the reason it stopped");
    assert!(stop.contains("200"), "{stop}");
    let horizon = printed["horizon"].as_f64().unwrap();
    assert!(horizon > 0.0 && horizon < 5.0, "stopped before the horizon: {horizon}");
    let written: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(written["stop"], printed["stop"]);
    assert_eq!(written["impact_count"], printed["impact_count"]);
}
