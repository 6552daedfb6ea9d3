//! A PEER `.AT2` file whose header lacks `NPTS` was read as two columns of numbers and reported
//! as "a line with five columns", which says nothing of what is wrong. A file named `.AT2`, or
//! opening with the PEER banner, is now read as one, and its missing `NPTS` is named.

use crate::common::lpc;

#[test]
fn an_at2_record_without_npts_is_named_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let record = "PEER NGA STRONG MOTION DATABASE RECORD\nSYNTHETIC, 1/1/2000, STATION, 0\n\
                  ACCELERATION TIME SERIES IN UNITS OF G\nDT=   .0100 SEC\n\
                  0.0 .01 .02 -.01 -.02\n0.0 .01 .02 -.01 -.02\n";
    let scene = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/mdof-3storey-record.toml")).unwrap();
    let scene = scene.replace("records/synthetic-kt.csv", "record.AT2");
    assert!(scene.contains("record.AT2"), "the shipped scene names its record as this test expects");
    // Named .AT2, and the same text under another name: the banner says what it is.
    for name in ["record.AT2", "record.txt"] {
        std::fs::write(dir.path().join(name), record).unwrap();
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, scene.replace("record.AT2", name)).unwrap();
        let out = dir.path().join("out");
        let o = lpc(["run".as_ref(), path.as_os_str(), "--out".as_ref(), out.as_os_str()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains("forcing.file") && stderr.contains("NPTS") && !stderr.contains("columns"), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: nothing is written");
    }
}
