//! The phases of one physics step, a module each, in the order [`super::DamperSet`] runs them:
//! the impacts of touching pairs, the step's length, the frame driven to the step's end,
//! Rapier's step, the feedback of the balls' impulses into the frame, and the samples.

pub mod drive;
pub mod feedback;
pub mod impacts;
pub mod plan;
pub mod record;
