//! `lpc check` passes on the committed goldens and catches a regression (exit status 3).

use crate::common::lpc_command;

fn lpc_check(scenes: &std::path::Path, golden: &std::path::Path, models: &str) -> (Option<i32>, String) {
    let o = lpc_command().arg("check").arg(scenes).arg("--golden").arg(golden).args(["--models", models]).output().unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into_owned())
}

#[test]
fn committed_goldens_pass() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (code, out) = lpc_check(&root.join("scenes"), &root.join("tests/golden"), "reference,rapier,compliant");
    assert_eq!(code, Some(0), "{out}");
}

/// One scene's golden with one metric moved fails the check: the rest of the goldens are the
/// test above's.
#[test]
fn a_changed_metric_is_a_regression() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (scenes, golden) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    std::fs::copy(root.join("scenes/lpc-lsl.toml"), scenes.path().join("lpc-lsl.toml")).unwrap();
    let file = golden.path().join("lpc-lsl.reference.json");
    std::fs::copy(root.join("tests/golden/lpc-lsl.reference.json"), &file).unwrap();
    let (code, out) = lpc_check(scenes.path(), golden.path(), "reference");
    assert_eq!(code, Some(0), "the copied golden passes: {out}");
    // Move the reference's LSL peak displacement by 1e-6 relative: far beyond round-off.
    let mut g: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    let peak = g["metrics"]["peak_displacement"].as_f64().unwrap();
    g["metrics"]["peak_displacement"] = serde_json::json!(peak * (1.0 + 1e-6));
    std::fs::write(&file, serde_json::to_vec(&g).unwrap()).unwrap();
    let (code, out) = lpc_check(scenes.path(), golden.path(), "reference");
    assert_eq!(code, Some(3), "{out}");
    assert!(out.contains("lpc-lsl") && out.contains("peak_displacement") && out.contains("FAIL"), "{out}");
}

/// `--update` keeps a spread only for the values that a few ulps of restitution move beyond
/// the exact tolerance: none for the Fig. 16 sweep's e = 0.85, the late-time values of its
/// e = 0.95, where the balls' impacts amplify it (as in the committed goldens), and a check
/// against those goldens passes.
#[test]
fn update_keeps_a_spread_where_round_off_moves_a_value() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (scenes, golden) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    std::fs::copy(root.join("scenes/sweep-cor.toml"), scenes.path().join("sweep-cor.toml")).unwrap();
    let o = lpc_command()
        .arg("check")
        .arg(scenes.path())
        .arg("--golden")
        .arg(golden.path())
        .args(["--models", "reference", "--update"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stdout));
    let read = |dir: &std::path::Path, e: &str| -> serde_json::Value {
        let file = dir.join(format!("sweep-cor_restitution_{e}_.reference.json"));
        serde_json::from_slice(&std::fs::read(file).unwrap()).unwrap()
    };
    let low = read(golden.path(), "0.85");
    assert!(low.get("spread").is_none(), "{low}");
    let names = |g: &serde_json::Value| -> Vec<String> { g["spread"].as_object().expect("a spread").keys().cloned().collect() };
    let high = read(golden.path(), "0.95");
    assert!(names(&high).contains(&"settling_time".to_string()) && !names(&high).contains(&"peak_displacement".to_string()), "{high}");
    assert_eq!(names(&high), names(&read(&root.join("tests/golden"), "0.95")));
    let (code, out) = lpc_check(scenes.path(), golden.path(), "reference");
    assert_eq!(code, Some(0), "{out}");
}
