//! Issue 19: `stiffness = 1e10` (or 1e12) on lpc-lsl made the contact model panic, exit 101,
//! in `aligned_step`'s `clamp(MIN_STEP, longest)`: a 40th of the frame's period (1.8e-7 s at
//! 1e12 N/m) is shorter than the shortest contact-closing step, so min > max. The period's
//! bound now wins; the run goes on with steps that short.

use crate::common::lpc;

#[test]
fn a_very_stiff_frame_runs_in_the_contact_model() {
    for stiffness in ["1e10", "1e12"] {
        let dir = tempfile::tempdir().unwrap();
        let text = std::fs::read_to_string(lpc_damper::scene::scenes_dir().join("lpc-lsl.toml"))
            .unwrap()
            .replace("stiffness = 865.0", &format!("stiffness = {stiffness}"));
        assert!(text.contains(stiffness), "the scene file sets the stiffness");
        let path = dir.path().join("stiff.toml");
        std::fs::write(&path, text).unwrap();
        let o = lpc(["run", path.to_str().unwrap(), "--model", "rapier", "--horizon", "0.001", "--format", "json"]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(o.status.code(), Some(0), "{stderr}");
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let balance = summary["energy"]["balance_error"].as_f64().unwrap();
        assert!(balance.abs() < 1e-3, "energy balance {balance:e} of E0");
    }
}
