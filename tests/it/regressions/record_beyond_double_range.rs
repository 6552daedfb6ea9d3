//! Issue 32: a ground or force record reaching 1e308 (finite, so it was read) hung the
//! reference: the energy it put in left the range of double precision, and the sign-change
//! scan of the floors' acceleration never finished on the resulting infinities. At 1e160 the
//! run ended with a balance of NaN. A record beyond 1e100 is now refused with the reason.

use crate::common::lpc_command;

#[test]
fn a_record_beyond_the_range_of_double_precision_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("huge.txt"), "0 0\n0.5 1e308\n1 -1e308\n").unwrap();
    let scene = std::fs::read_to_string(lpc_damper::scene::scenes_dir().join("lpc-lsl.toml")).unwrap();
    for kind in ["record", "force_record"] {
        let file = dir.path().join(format!("{kind}.toml"));
        std::fs::write(&file, format!("{scene}\n[forcing]\nkind = \"{kind}\"\nfile = \"huge.txt\"\n")).unwrap();
        let out = dir.path().join("out");
        let o = lpc_command().arg("run").arg(&file).arg("--out").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{kind}: {stderr}");
        assert!(stderr.contains("forcing.scale") && stderr.contains("double precision"), "{kind}: {stderr}");
        assert!(!out.exists());
    }
}
