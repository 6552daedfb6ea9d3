//! One module per command, each with its arguments (`Args`) beside the function that runs it
//! (`run`), which returns how the command ended.

pub mod bench;
pub mod chain;
pub mod check;
pub mod compare;
pub mod frf;
pub mod merge;
pub mod optimize;
pub mod plot;
pub mod render;
pub mod run;
pub mod stability;
pub mod stress;
pub mod sweep;
pub mod view;
