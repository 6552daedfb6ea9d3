//! `lpc check` passes on the committed goldens and catches a regression (exit status 3).

use crate::common::lpc_command;

fn lpc_check(golden: &std::path::Path) -> (Option<i32>, String) {
    let o = lpc_command().args(["check", "scenes", "--golden"]).arg(golden).output().unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into_owned())
}

#[test]
fn committed_goldens_pass() {
    let (code, out) = lpc_check(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden"));
    assert_eq!(code, Some(0), "{out}");
}

#[test]
fn a_changed_metric_is_a_regression() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, dir.path().join(p.file_name().unwrap())).unwrap();
    }
    // Move the reference's LSL peak displacement by 1e-6 relative: far beyond round-off.
    let file = dir.path().join("lpc-lsl.reference.json");
    let mut g: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    let peak = g["metrics"]["peak_displacement"].as_f64().unwrap();
    g["metrics"]["peak_displacement"] = serde_json::json!(peak * (1.0 + 1e-6));
    std::fs::write(&file, serde_json::to_vec(&g).unwrap()).unwrap();
    let (code, out) = lpc_check(dir.path());
    assert_eq!(code, Some(3), "{out}");
    assert!(out.contains("lpc-lsl") && out.contains("peak_displacement") && out.contains("FAIL"), "{out}");
}
