//! Forgetting the stored impulses of struck pairs (docs/MODEL.md §9, "Stored impulses after the
//! impact law"). Rapier starts each step's solve from the impulses its last solve found at each
//! contact (its warm start). Where the impact law then replaced what that solve did, those
//! impulses belong to a plastic stop that never happened, and applied again they push the pair
//! apart a second time. Rapier keeps them with its contact pairs and drops them only when a pair
//! is filtered out of a contact update. So between two steps, one contact update without a solve
//! filters the struck pairs out: they lose their stored impulses, every other pair keeps its own,
//! and the next step finds the struck pairs again, new, and solves them from no impulse.

use bevy_rapier3d::rapier::prelude::{
    ActiveHooks, BroadPhaseBvh, ColliderHandle, CollisionPipeline, PairFilterContext, PhysicsHooks, PhysicsWorld, SolverFlags,
};

use super::contacts::Other;
use super::world::SpatialWorld;

/// A pair of colliders, in either order.
pub type Pair = (ColliderHandle, ColliderHandle);

fn listed(pairs: &[Pair], (a, b): Pair) -> bool {
    pairs.iter().any(|&p| p == (a, b) || p == (b, a))
}

/// A contact update's filter that drops the listed pairs.
struct Dropped<'a> {
    pairs: &'a [Pair],
}

impl PhysicsHooks for Dropped<'_> {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        if listed(self.pairs, (context.collider1, context.collider2)) {
            None
        } else {
            Some(SolverFlags::COMPUTE_IMPULSES)
        }
    }
}

/// The pairs the impact law struck in a step, whose impulses Rapier must forget before the next.
#[derive(Default)]
pub struct Struck {
    pairs: Vec<(usize, Other)>,
    /// Each damper's struck pairs, as colliders of its world.
    by_damper: Vec<Vec<Pair>>,
}

impl Struck {
    /// Keeps that ball `ball` struck `other`.
    pub fn push(&mut self, ball: usize, other: Other) {
        self.pairs.push((ball, other));
    }

    /// Makes each damper's world forget the stored impulses of the pairs kept since the last
    /// call, with one contact update that filters them out, and forgets them too.
    pub fn forget(&mut self, world: &mut SpatialWorld) {
        if self.pairs.is_empty() {
            return;
        }
        self.by_damper.resize(world.dampers.len(), Vec::new());
        self.by_damper.iter_mut().for_each(Vec::clear);
        for (ball, other) in self.pairs.drain(..) {
            let handles = world.balls[ball];
            let damper = &world.dampers[handles.damper];
            let partner = match other {
                Other::Ball(j) => world.balls[j].collider,
                Other::Wall(wall) => match damper.walls.iter().find(|(w, _)| *w == wall) {
                    Some(&(_, collider)) => collider,
                    None => continue,
                },
            };
            let pair = (handles.collider, partner);
            let list = &mut self.by_damper[handles.damper];
            if !listed(list, pair) {
                list.push(pair);
            }
        }
        for (damper, pairs) in world.dampers.iter_mut().zip(&self.by_damper) {
            if !pairs.is_empty() {
                drop_pairs(&mut damper.physics, pairs);
            }
        }
    }
}

/// Runs one contact update of `physics` without a solve, in which `pairs` are filtered out.
fn drop_pairs(physics: &mut PhysicsWorld, pairs: &[Pair]) {
    let set_filter = |physics: &mut PhysicsWorld, on: bool| {
        for &(a, _) in pairs {
            let collider = &mut physics.colliders[a];
            let mut hooks = collider.active_hooks();
            hooks.set(ActiveHooks::FILTER_CONTACT_PAIRS, on);
            collider.set_active_hooks(hooks);
        }
    };
    set_filter(physics, true);
    // The update runs its own broad phase, empty: the world's keeps the pairs it found and those
    // it has still to report to the step, whose removal the update could not book in Rapier's
    // islands.
    let mut unused = BroadPhaseBvh::new();
    // Rapier reuses a pair's contacts while the pair has moved less than its recycling distance
    // since its last full update. This update replaces the contacts but not the pose they are
    // reused from, so it keeps every contact the next steps may reuse: those within twice the
    // step's prediction (any approach a step can close) and twice the recycling distance.
    let params = &physics.integration_parameters;
    let prediction = 2.0 * params.prediction_distance() + 2.0 * params.contact_recycle_distance();
    CollisionPipeline::new().step(
        prediction,
        &mut physics.islands,
        &mut unused,
        &mut physics.narrow_phase,
        &mut physics.bodies,
        &mut physics.colliders,
        &Dropped { pairs },
        &(),
    );
    set_filter(physics, false);
    // The update took the bodies changed since the last step (the velocities the impact law
    // wrote) off Rapier's list of modified bodies without booking them in its islands, so the
    // step kept its graph of solver contacts and missed the changes the update made to it (in
    // debug builds an assertion of Rapier's, in release an index out of bounds). Marked
    // modified again (Rapier's mutable iteration marks each body it yields), every body is
    // booked by the step, which then rebuilds that graph.
    physics.bodies.iter_mut().for_each(drop);
    // The update took the changes made to the world since the last step, which the step's
    // broad phase no longer sees: every collider is boxed for it anew.
    for (handle, collider) in physics.colliders.iter() {
        let aabb = collider.compute_broad_phase_aabb(&physics.integration_parameters, &physics.bodies);
        physics.broad_phase.set_aabb(&physics.integration_parameters, handle, aabb);
    }
}
