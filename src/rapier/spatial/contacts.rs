//! The contacts of a step and their impacts (docs/MODEL.md §3 along each contact's normal).
//! Rapier solves every contact plastically; after its step, a contact whose approach Rapier
//! stopped in the step, faster than a resting contact's, is an impact: the pair's
//! relative normal velocity is set to `e` times its approach speed by an impulse along the
//! normal, with both bodies' masses (a wall is the frame, of inverse mass `n_x^2 / M` along
//! the normal). Tangential velocities stay Rapier's (friction). Touching pairs that the
//! impacts set approaching are then struck in turn, the fastest first, as in §3.

use crate::scene::{Chamber, Wall};

/// What a ball touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Other {
    /// Another ball, of larger index.
    Ball(usize),
    /// A wall of the frame.
    Wall(Wall),
}

/// A ball touching something at the end of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// The ball (the smaller index of a ball pair).
    pub ball: usize,
    /// What it touches.
    pub other: Other,
    /// Gap between the surfaces, m (negative when they overlap).
    pub gap: f64,
    /// Unit normal from the ball towards the other body.
    pub normal: [f64; 3],
}

/// The balls' state the impacts change: linear velocities, and their masses.
pub struct Balls<'a> {
    /// Velocities, m/s.
    pub v: &'a mut [[f64; 3]],
    /// Masses, kg.
    pub mass: &'a [f64],
}

/// Finds every pair closer than `touching` (balls and walls), sweeping along x in `order`
/// (kept between steps: nearly sorted already, so the insertion sort is linear).
pub fn find(geometry: &Chamber, x: &[[f64; 3]], radius: &[f64], xs: f64, touching: f64, order: &mut Vec<usize>, out: &mut Vec<Contact>) {
    out.clear();
    let n = x.len();
    if order.len() != n {
        *order = (0..n).collect();
    }
    for k in 1..n {
        let mut j = k;
        while j > 0 && x[order[j - 1]][0] > x[order[j]][0] {
            order.swap(j - 1, j);
            j -= 1;
        }
    }
    let reach = geometry.largest_radius + touching;
    for (k, &i) in order.iter().enumerate() {
        let local = [x[i][0] - xs, x[i][1], x[i][2]];
        for wall in geometry.walls_near(local) {
            let (gap, normal) = geometry.gap(wall, local, radius[i]);
            if gap <= touching {
                out.push(Contact { ball: i, other: Other::Wall(wall), gap, normal });
            }
        }
        for &j in &order[k + 1..] {
            if x[j][0] - x[i][0] > radius[i] + reach {
                break;
            }
            let d = [x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]];
            let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let gap = dist - radius[i] - radius[j];
            if gap <= touching && dist > 0.0 {
                let (a, b, s) = if i < j { (i, j, 1.0) } else { (j, i, -1.0) };
                out.push(Contact { ball: a, other: Other::Ball(b), gap, normal: d.map(|c| s * c / dist) });
            }
        }
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The frame as the walls' body: its velocity along x and its mass.
pub struct FrameBody {
    /// Velocity, m/s.
    pub vs: f64,
    /// Mass, kg.
    pub mass: f64,
}

/// Relative normal velocity of contact `c` (the other body's less the ball's, along the
/// normal: negative when they approach) and the pair's inverse masses along the normal.
pub fn relative(c: &Contact, balls: &Balls, frame: &FrameBody) -> (f64, f64, f64) {
    let n = c.normal;
    let inv_a = 1.0 / balls.mass[c.ball];
    match c.other {
        Other::Ball(j) => (dot(balls.v[j], n) - dot(balls.v[c.ball], n), inv_a, 1.0 / balls.mass[j]),
        Other::Wall(_) => (n[0] * frame.vs - dot(balls.v[c.ball], n), inv_a, n[0] * n[0] / frame.mass),
    }
}

/// Applies the impulse `j` (N s, pushing the pair apart along the normal) to contact `c`.
pub fn push_apart(c: &Contact, j: f64, balls: &mut Balls, frame: &mut FrameBody) {
    let n = c.normal;
    let ma = balls.mass[c.ball];
    for (a, &nk) in n.iter().enumerate() {
        balls.v[c.ball][a] -= j * nk / ma;
    }
    match c.other {
        Other::Ball(b) => {
            let mb = balls.mass[b];
            for (a, &nk) in n.iter().enumerate() {
                balls.v[b][a] += j * nk / mb;
            }
        }
        Other::Wall(_) => frame.vs += j * n[0] / frame.mass,
    }
}

/// One impact: the pair's relative normal velocity set to `e` times `approach` (the speed at
/// which it closed), whatever Rapier left it at. Returns the energy Eq. 9-10 take from an
/// impact at that speed, `(1 - e^2)/2 mu approach^2`.
pub fn strike(c: &Contact, approach: f64, e: f64, balls: &mut Balls, frame: &mut FrameBody) -> f64 {
    let (w, inv_a, inv_b) = relative(c, balls, frame);
    let inv = inv_a + inv_b;
    push_apart(c, (e * approach - w) / inv, balls, frame);
    0.5 * (1.0 - e * e) * approach * approach / inv
}

/// The speed at which a contact closes, from its gap `gap0` and relative normal velocity
/// `w0` at the step's start and the relative acceleration `-g_n` along the normal (gravity
/// pulls a ball towards a wall, not towards another ball): the approach speed at the instant
/// the free flight closes the gap (within the step, or just after it when Rapier stopped the
/// pair short of contact; at the step's end when the flight never closes it; at its start
/// when it was closed already).
pub fn closing_speed(gap0: f64, w0: f64, g_n: f64, h: f64) -> f64 {
    // gap(t) = gap0 + w0 t - g_n t^2 / 2.
    let tau = if gap0 <= 0.0 {
        0.0
    } else if g_n.abs() < 1e-300 {
        if w0 < 0.0 {
            -gap0 / w0
        } else {
            h
        }
    } else {
        let disc = w0 * w0 + 2.0 * g_n * gap0;
        if disc < 0.0 {
            h
        } else {
            let roots = [(w0 - disc.sqrt()) / g_n, (w0 + disc.sqrt()) / g_n];
            let first = roots.into_iter().filter(|t| *t >= 0.0).fold(f64::INFINITY, f64::min);
            if first.is_finite() {
                first
            } else {
                h
            }
        }
    };
    -(w0 - g_n * tau)
}
