//! The integration tests, one binary: one link against
//! the library and Bevy instead of one per file. Each module is a property of the product;
//! `regressions/` holds one test per fixed bug, on the scene that showed it; `common/` holds
//! the known-solution problems and the one way to run the `lpc` binary.

mod common;
mod regressions;

mod bad_scenes;
mod beds_on_structures;
mod bench_matches_compare;
mod beyond_one_line;
mod budgets;
mod check_goldens;
mod closed_form;
mod compliant_model;
mod compliant_space;
mod design_maps;
mod determinism;
mod energy_balance;
mod ensembles;
mod figures;
mod forcing;
mod fuzz_scene_files;
mod impact_properties;
mod masri_caughey;
mod rapier_model;
mod rapier_space;
mod render;
mod settled_beds;
mod several_dampers;
mod spatial_reference;
mod stability_map;
mod sticking;
mod stress;
mod struck_groups;
mod structures;
