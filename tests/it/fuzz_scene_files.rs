//! Fuzzed scene files: arbitrary bytes and arbitrary TOML never panic the parser; every
//! rejection is an error that names the file and says what is wrong.

use lpc_damper::scene::{parse, SceneError};
use proptest::prelude::*;

fn check(text: &str) {
    match parse(text, "fuzz.toml", "fuzz") {
        Ok(_) => {}
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("fuzz.toml: "), "error does not name the file: {msg}");
            if let SceneError::Invalid { field, rule, .. } = &e {
                assert!(!field.is_empty() && !rule.is_empty(), "{msg}");
            }
        }
    }
}

/// TOML values, including the awkward ones (NaN, infinities, huge and negative numbers).
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|x| if x.is_nan() {
            "nan".into()
        } else if x.is_infinite() {
            if x > 0.0 {
                "inf".into()
            } else {
                "-inf".into()
            }
        } else {
            format!("{x:e}")
        }),
        any::<i64>().prop_map(|i| i.to_string()),
        "[LS]{0,60}".prop_map(|s| format!("\"{s}\"")),
        "[-0-9.]{1,8} ?Rr".prop_map(|s| format!("\"{s}\"")),
        Just("true".to_string()),
        Just("[]".to_string()),
        Just("[1, 2, 3]".to_string()),
        Just("{ mass = 0.1 }".to_string()),
        Just("[{ mass = -1.0 }, { mass = 0.011, density = 0.0 }]".to_string()),
    ]
}

const KEYS: &[(&str, &[&str])] = &[
    ("frame", &["mass", "stiffness", "damping", "initial_displacement", "bogus"]),
    ("balls", &["arrangement", "large_mass", "mass_ratio", "density", "restitution", "gap", "clearance", "container_length"]),
    ("run", &["horizon", "sample_dt"]),
    ("rapier", &["dt", "solver_iterations", "stepping"]),
    ("sweep", &["parameter", "values"]),
    ("chain", &["large_counts", "small_balls", "large_mass", "mass_ratio", "density", "restitution", "gap", "incident_speed"]),
];

fn document() -> impl Strategy<Value = String> {
    prop::collection::vec((0..KEYS.len(), prop::collection::vec((0usize..8, value()), 0..9)), 0..6).prop_map(|tables| {
        let mut out = String::new();
        let mut seen = std::collections::HashSet::new();
        for (t, entries) in tables {
            let (name, keys) = KEYS[t];
            if !seen.insert(name) {
                continue;
            }
            out.push_str(&format!("[{name}]\n"));
            let mut used = std::collections::HashSet::new();
            for (k, v) in entries {
                let key = keys[k % keys.len()];
                if used.insert(key) {
                    out.push_str(&format!("{key} = {v}\n"));
                }
            }
        }
        out
    })
}

proptest! {
    #![proptest_config(crate::common::proptest_config(3000))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn arbitrary_toml_never_panics(doc in document()) {
        check(&doc);
    }

    #[test]
    fn mutated_paper_scene_never_panics(cut in 0usize..2000, insert in "[\\x20-\\x7e\\n]{0,12}") {
        let base = include_str!("../../scenes/lpc-lsl.toml");
        let cut = cut.min(base.len());
        let cut = (0..=cut).rev().find(|&i| base.is_char_boundary(i)).unwrap_or(0);
        check(&format!("{}{}{}", &base[..cut], insert, &base[cut..]));
    }
}
