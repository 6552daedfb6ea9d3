//! `lpc run --format json` printed every impact on standard output (445 MB for a box of 3000
//! balls). It now prints the summary with the impacts' count and noise proxy; `--out` writes
//! them to `impacts.csv`, and `--print-impacts` adds them to what is printed.

use crate::common::lpc;

#[test]
fn the_printed_summary_leaves_the_impacts_out_unless_asked() {
    let args = ["run", "scenes/planar-bed.toml", "--horizon", "0.05", "--format", "json"];
    let plain = lpc(args);
    assert_eq!(plain.status.code(), Some(0), "{}", String::from_utf8_lossy(&plain.stderr));
    let plain: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert!(plain.get("impacts").is_none(), "no impact list by default");
    let count = plain["impact_count"].as_u64().unwrap();
    assert!(count > 10 && plain["noise"]["energy_lost"]["p95"].is_number());
    let asked = lpc(args.iter().chain(&["--print-impacts"]));
    assert_eq!(asked.status.code(), Some(0), "{}", String::from_utf8_lossy(&asked.stderr));
    let asked: serde_json::Value = serde_json::from_slice(&asked.stdout).unwrap();
    assert_eq!(asked["impacts"].as_array().unwrap().len() as u64, count);
    assert_eq!(asked["energy"], plain["energy"]);
}
