//! The contacts Rapier's plastic solve stopped in a step, which the impact law then strikes,
//! and the wall impacts' kicks on the carrying bodies (docs/MODEL.md §3 and §9).

/// A contact Rapier stopped in the step: its closing speed and what it was computed from.
pub(super) struct Closing {
    /// Approach speed at closing, m/s.
    pub approach: f64,
    /// When in the step free flight closes it, s after the step's start (0 for a strike kept
    /// out of Rapier's solve, a pair of balls, whose turn no instant sets).
    pub tau: f64,
    /// Index of the contact.
    pub k: usize,
    /// Gap at the step's start, m.
    pub gap0: f64,
    /// Relative normal velocity at the step's start, m/s.
    pub w0: f64,
    /// Gravity along the normal (towards a wall), m/s^2.
    pub g_n: f64,
    /// For two balls that met in flight or a strike kept out of Rapier's solve, what of
    /// Rapier's solve is undone and where they touch: such a pair strikes at the speed it
    /// approaches with when its turn comes.
    pub solved: Option<Solved>,
}

/// How Rapier's plastic solve changed a pair of balls that met in flight in a step.
#[derive(Clone, Copy)]
pub(super) struct Solved {
    /// The line along which the step's change of the pair's relative velocity is undone, and
    /// that change along it, m/s (none when the pair's group had its whole step undone, or
    /// Rapier did not solve the pair).
    pub undo: Option<([f64; 3], f64)>,
    /// The line of the centres where free flight brings them to touch: the impact's normal.
    pub normal: [f64; 3],
}

/// What the step's wall impacts so far did to each carrying body: the velocity they gave it,
/// which each later wall impact of the step meets, and how far that moved it beyond its closed
/// form by the step's end (an impulse lands at its instant; the closed form takes it at the
/// step's end, so the body is moved on by what the impulse would have carried it since).
pub(super) struct WallKicks {
    /// Velocity given to each body, m/s.
    pub change: Vec<f64>,
    /// How far each body moves beyond its closed form by the step's end, m.
    pub travel: Vec<f64>,
}

impl WallKicks {
    /// No kicks yet on `bodies` carrying bodies.
    pub fn new(bodies: usize) -> Self {
        WallKicks { change: vec![0.0; bodies], travel: vec![0.0; bodies] }
    }

    /// The velocity of body `b`'s walls at `tau` into a step of `h` over which its closed form
    /// goes from `vs` to `v1`, with the kicks so far, m/s.
    pub fn walls_then(&self, b: usize, (vs, v1): (f64, f64), tau: f64, h: f64) -> f64 {
        vs + (v1 - vs) * tau / h + self.change[b]
    }

    /// An impact of Eq. 9-10 at `tau` into a step of `h` between a ball of mass `m` and the
    /// walls of body `b` of mass `body_mass`, whose normal's x component is `n_x`, at
    /// `approach` with restitution `e`: books the kick and returns the impulse (N s, pushing
    /// them apart) and the energy the impact takes, J.
    pub fn strike(&mut self, b: usize, (m, body_mass): (f64, f64), n_x: f64, approach: f64, e: f64, (tau, h): (f64, f64)) -> (f64, f64) {
        let mu = 1.0 / (1.0 / m + n_x * n_x / body_mass);
        let impulse = (1.0 + e) * approach * mu;
        let kick = impulse * n_x / body_mass;
        self.change[b] += kick;
        self.travel[b] += kick * (h - tau);
        (impulse, 0.5 * (1.0 - e * e) * mu * approach * approach)
    }
}
