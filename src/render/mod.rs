//! 3D pictures of a run (cargo feature `render`): the structure of the paper's Fig. 6 (a frame
//! on two columns with the container on top), a see-through container, balls coloured by
//! size at true proportions, a flash at each impact.
//!
//! Rendering consumes a finished [`Run`]: the physics runs first, headless, exactly as `lpc
//! run` runs it, and the pictures show its samples. So rendering can never change the physics,
//! and a frame rate different from the physics rate shows the state at the frame's simulated
//! time: the run is sampled at a step that divides the frame interval
//! ([`crate::run::frame_sampling`]).

pub mod animation;
pub mod offscreen;
pub mod stage;
pub mod window;

use crate::run::Run;

pub use offscreen::{render_frames, RenderError, RenderOptions};
pub use stage::{Layout, Playback};

/// Frame displacement and ball centres of `run` at sample `k` (clamped to the last sample).
pub fn state_at_sample(run: &Run, k: usize) -> (f64, Vec<f64>) {
    let s = &run.series;
    let k = k.min(s.len().saturating_sub(1));
    (s.xs().get(k).copied().unwrap_or(0.0), (0..s.balls()).map(|i| s.x(i).get(k).copied().unwrap_or(0.0)).collect())
}
