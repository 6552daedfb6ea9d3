//! Issue 19: 100 000 balls for 5 s (5001 samples) need 8 GB of series; under a 4 GB limit the
//! reference aborted ("memory allocation of 40008 bytes failed") with a backtrace. A run whose
//! series cannot fit in the memory left is now refused before anything is allocated, with the
//! numbers. Here the series would take 32 TB (2e7 samples x 100 000 balls), beyond any machine.

use crate::common::lpc;

#[test]
fn a_run_too_large_for_memory_is_refused_with_the_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.toml");
    let scene = format!(
        "name = \"huge\"\n[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [balls]\narrangement = \"{}\"\nlarge_mass = 0.11\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.0\nclearance = 0.0\n\
         [run]\nhorizon = 20.0\nsample_dt = 0.000001\n",
        "L".repeat(100_000)
    );
    std::fs::write(&path, scene).unwrap();
    let o = lpc(["run", path.to_str().unwrap(), "--out", dir.path().join("out").to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("32.0 TB") && stderr.contains("100000 balls") && stderr.contains("2e7 samples"), "{stderr}");
    assert!(!dir.path().join("out").exists(), "nothing written");
}
