//! The impact law of the impulse models (docs/MODEL.md §3, Eq. 9-10): kinematic coefficient of
//! restitution, momentum conserved, `(1 - e^2)/2 * mu * (v1 - v2)^2` of kinetic energy lost.

/// Velocities after an impact of body 1 (mass `m1`, velocity `v1`) with body 2, and the energy
/// lost. Either mass may be infinite (a rigid wall). `e` is the coefficient of restitution.
#[inline]
pub fn impact_law(m1: f64, v1: f64, m2: f64, v2: f64, e: f64) -> (f64, f64, f64) {
    let rel = v1 - v2;
    let (v1p, v2p) = separate(m1, v1, m2, v2, e * rel);
    (v1p, v2p, 0.5 * (1.0 - e * e) * reduced_mass(m1, m2) * rel * rel)
}

/// The reduced mass `m1 m2 / (m1 + m2)` of two bodies, either of which may be infinite.
#[inline]
pub fn reduced_mass(m1: f64, m2: f64) -> f64 {
    if m2.is_infinite() {
        m1
    } else if m1.is_infinite() {
        m2
    } else {
        m1 * m2 / (m1 + m2)
    }
}

/// Velocities of body 1 (mass `m1`, velocity `v1`) and body 2 after an impulse between them
/// that leaves them separating at `separation` (`v2 - v1`), momentum kept. Eq. 9-10 are the
/// case `separation = e (v1 - v2)`; the spatial reference's collapse rule sets it otherwise.
/// Either mass may be infinite (a rigid wall), not both.
#[inline]
pub fn separate(m1: f64, v1: f64, m2: f64, v2: f64, separation: f64) -> (f64, f64) {
    if m2.is_infinite() {
        return (v2 - separation, v2);
    }
    if m1.is_infinite() {
        return (v1, v1 + separation);
    }
    let total = m1 + m2;
    // Written as the centre-of-mass velocity minus each body's share of the separation: the
    // same as Eq. 9-10, with one rounding less.
    let vcm = (m1 * v1 + m2 * v2) / total;
    (vcm - separation * m2 / total, vcm + separation * m1 / total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn equal_masses_elastic_exchange_velocities() {
        let (a, b, lost) = impact_law(1.0, 2.0, 1.0, 0.0, 1.0);
        assert_relative_eq!(a, 0.0, epsilon = 1e-15);
        assert_relative_eq!(b, 2.0);
        assert_eq!(lost, 0.0);
    }

    #[test]
    fn matches_eq_9_10_as_printed() {
        let (m1, v1, m2, v2, e) = (0.11, 0.7, 1.35, -0.2, 0.9);
        let (a, b, _) = impact_law(m1, v1, m2, v2, e);
        let eq9 = ((m1 - e * m2) * v1 + (1.0 + e) * m2 * v2) / (m1 + m2);
        let eq10 = ((m2 - e * m1) * v2 + (1.0 + e) * m1 * v1) / (m1 + m2);
        assert_relative_eq!(a, eq9, max_relative = 1e-14);
        assert_relative_eq!(b, eq10, max_relative = 1e-14);
    }

    #[test]
    fn rigid_wall_reverses_with_e() {
        let (a, b, lost) = impact_law(2.0, 3.0, f64::INFINITY, 0.0, 0.5);
        assert_eq!((a, b), (-1.5, 0.0));
        assert_relative_eq!(lost, 0.5 * 0.75 * 2.0 * 9.0);
    }
}
