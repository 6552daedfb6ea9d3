//! Several dampers on one carrier: each a container with its own balls, on a floor of its
//! choice (docs/MODEL.md §18). A scene with one damper describes it with its own `container`,
//! `space` and structure's floor, as every scene did before there could be several.

use super::{Container, Scene};
use std::ops::Range;

/// One damper of a scene: its container, its balls among the scene's, and the floor that
/// carries it.
#[derive(Debug, Clone, PartialEq)]
pub struct Damper {
    /// The floor that carries it, 0 at the bottom (0 on a frame).
    pub floor: usize,
    /// Its balls, a run of the scene's.
    pub balls: Range<usize>,
    /// Its container along the motion.
    pub container: Container,
    /// Its container's inner size across the motion, `[width, height]`, m (`[0, 0]` for a
    /// line).
    pub section: [f64; 2],
    /// The channel width of each of its chains, m (0 for one chain).
    pub channel: f64,
}

impl Scene {
    /// Whether the scene carries more than one damper: then only a model that hands each
    /// damper's impulses to its own floor can run it.
    pub fn has_several_dampers(&self) -> bool {
        self.dampers.len() > 1
    }

    /// Every damper of the scene, in the order the file gives them (none without a container).
    pub fn damper_list(&self) -> Vec<Damper> {
        if !self.dampers.is_empty() {
            return self.dampers.clone();
        }
        let Some(container) = self.container else { return Vec::new() };
        vec![Damper {
            floor: self.structure.as_ref().map_or(0, |s| s.floor),
            balls: 0..self.balls.len(),
            container,
            section: self.space.section,
            channel: self.space.channel,
        }]
    }

    /// Where damper `d`'s container starts along the motion: its floor's initial displacement
    /// (the frame's on a frame), m.
    pub fn damper_start(&self, d: &Damper) -> f64 {
        match &self.structure {
            Some(s) if self.has_several_dampers() => s.initial_displacements[d.floor],
            _ => self.initial_displacement,
        }
    }

    /// The length of the longest container, m (`None` without one).
    pub fn longest_container(&self) -> Option<f64> {
        let first = self.container?.length;
        Some(self.dampers.iter().fold(first, |m, d| m.max(d.container.length)))
    }

    /// The damper ball `i` is in (0 for a scene of one damper).
    pub fn damper_of(&self, i: usize) -> usize {
        self.dampers.iter().position(|d| d.balls.contains(&i)).unwrap_or(0)
    }

    /// The cross-section of the container ball `i` is in, `[width, height]`, m.
    pub fn section_of(&self, i: usize) -> [f64; 2] {
        self.dampers.get(self.damper_of(i)).map_or(self.space.section, |d| d.section)
    }
}
