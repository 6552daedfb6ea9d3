//! # lpc-damper
//!
//! Simulates the Linear Particle Chain (LPC) impact damper of Gharib & Ghani (J. Sound Vib.
//! 2013): a spring-damped frame carrying a container of large and small steel balls that
//! collide with each other and with the walls. Several models of the same system read one
//! scene format and write one output type, so they can be checked against each other.
//!
//! Data flows one way: `scenes/*.toml` → [`scene`] (parse + validate) → a [`model`]
//! ([`reference`](mod@reference), [`rapier`], [`compliant`], each behind [`model::Simulator`]) → [`run::Run`] →
//! [`metrics`], [`studies`], [`output`].
//!
//! ```
//! use lpc_damper::model::{Model, RunOptions};
//! let scene = lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join("lpc-lsl.toml")).unwrap();
//! let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
//! assert!(run.energy.balance_error.abs() < 1e-12);
//! let m = lpc_damper::metrics::metrics(&run);
//! assert!(m.peak_displacement < scene.initial_displacement);
//! ```
#![warn(missing_docs)]
// Numerical loops index several arrays by one body or pair index, which iterators would hide.
#![allow(clippy::needless_range_loop)]
// Comparisons written `!(a > b)` hold for NaN on purpose: a NaN must fail the test they guard.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod cells;
pub mod compliant;
pub mod files;
pub mod floor_motion;
pub mod impact_law;
pub mod metrics;
pub mod model;
pub mod oscillator;
pub mod output;
pub mod rapier;
pub mod reference;
mod registry;
#[cfg(feature = "render")]
pub mod render;
pub mod run;
pub mod scene;
pub mod storeys;
pub mod studies;

pub use model::Model;
