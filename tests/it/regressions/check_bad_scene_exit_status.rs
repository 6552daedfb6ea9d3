//! Issue 12: the exit status was found by searching the error chain for a `SceneError`, which
//! `#[error(transparent)]` wrappers hide: `lpc check DIR` on a directory holding a malformed
//! scene exited 1 (a failed run) instead of 2 (bad input). The class is now decided by the
//! error's type where it is made.

use crate::common::lpc_command;

#[test]
fn check_on_a_malformed_scene_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.toml"), "name = \"broken\"\n[frame]\nmass = -1.0\n").unwrap();
    let o = lpc_command().arg("check").arg(dir.path()).args(["--models", "reference"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("broken.toml"), "{stderr}");
}
