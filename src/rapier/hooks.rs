//! Per-contact restitution. Rapier sees the frame as a kinematic (infinitely heavy) body, so a
//! ball-wall contact gets the restitution `e'` that, followed by the impulse fed back into the
//! frame, yields the two-body result of Eq. 9-10 for the frame's finite mass; ball-ball
//! contacts get exactly `e`, whatever the colliders' combine rules say.

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

/// What a collider is, for the restitution hook.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub enum ContactRole {
    /// Ball `index` (left to right), of mass `mass`.
    Ball {
        /// Position in the chain.
        index: usize,
        /// kg.
        mass: f64,
    },
    /// A container wall (part of the frame).
    Wall,
}

/// The numbers the hook needs.
#[derive(Resource, Debug, Clone, Copy)]
pub struct RestitutionConfig {
    /// The scene's `e`.
    pub restitution: f64,
    /// `ms`, kg.
    pub frame_mass: f64,
}

/// Restitution against a rigid wall that, once the frame receives the opposite impulse, gives
/// Eq. 9-10 for a ball of mass `m` and a frame of mass `big_m`:
///
/// Rapier leaves the ball with `v_w - e' u` (u the approach speed), so `dv_b = -(1 + e') u`,
/// and the frame then gets `dv_w = (m / M)(1 + e') u`. The final relative velocity is
/// `-u (e' + (m/M)(1 + e'))`, which equals `-e u` exactly when `e' = (e M - m) / (M + m)`.
/// Returns `None` when that is negative (a ball heavier than `e` times the frame).
pub fn wall_restitution(e: f64, big_m: f64, m: f64) -> Option<f64> {
    let ep = (e * big_m - m) / (big_m + m);
    (ep >= 0.0).then_some(ep)
}

/// The physics hook that sets each contact's restitution.
#[derive(SystemParam)]
pub struct RestitutionHooks<'w, 's> {
    roles: Query<'w, 's, &'static ContactRole>,
    config: Res<'w, RestitutionConfig>,
}

impl BevyPhysicsHooks for RestitutionHooks<'_, '_> {
    fn modify_solver_contacts(&self, ctx: ContactModificationContextView) {
        let a = self.roles.get(ctx.collider1()).ok();
        let b = self.roles.get(ctx.collider2()).ok();
        let e = self.config.restitution;
        let restitution = match (a, b) {
            (Some(ContactRole::Ball { mass, .. }), Some(ContactRole::Wall))
            | (Some(ContactRole::Wall), Some(ContactRole::Ball { mass, .. })) => {
                // Refused scenes never get here; clamp for safety.
                wall_restitution(e, self.config.frame_mass, *mass).unwrap_or(0.0)
            }
            _ => e,
        };
        *ctx.raw.restitution = restitution as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::impact_law;
    use approx::assert_relative_eq;

    #[test]
    fn rigid_bounce_plus_feedback_equals_eq_9_10() {
        let (e, big_m, m, vb, vw) = (0.9, 1.35, 0.11, 0.4, -0.3);
        let ep = wall_restitution(e, big_m, m).unwrap();
        let u = vb - vw;
        let vb_rigid = vw - ep * u;
        let vw_after = vw - m * (vb_rigid - vb) / big_m;
        let (vb_exact, vw_exact, _) = impact_law(m, vb, big_m, vw, e);
        assert_relative_eq!(vb_rigid, vb_exact, max_relative = 1e-14);
        assert_relative_eq!(vw_after, vw_exact, max_relative = 1e-14);
    }

    #[test]
    fn heavy_ball_is_refused() {
        assert!(wall_restitution(0.9, 1.0, 0.95).is_none());
        assert!(wall_restitution(0.9, 1.0, 0.85).is_some());
    }
}
