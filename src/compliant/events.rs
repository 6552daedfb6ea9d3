//! Contacts as events of the integration: onsets located on the dense output, contacts opened
//! and closed (with their impact recorded), and each open contact's peak force and largest
//! overlap rate tracked over a step.

use super::contact;
use super::driver::{Contact, Driver};
use super::integrator::bracketed_root;
use super::stepper::{Active, Stepper};
use super::SCAN_POINTS;
use crate::run::Impact;

impl Driver<'_, '_> {
    /// Opens contacts of pairs that overlap, or touch and approach, and closes those that no
    /// longer overlap, at the current time; pair `event` (whose crossing was just located, its
    /// overlap now zero to round-off) changes state whatever the sign of that round-off.
    /// Returns whether anything changed.
    pub(super) fn update_contacts(&mut self, event: Option<usize>) -> bool {
        let sys = self.sys;
        let mut changed = false;
        for (q, pair) in sys.pairs.iter().enumerate() {
            let (d, rate) = sys.overlap(pair, |i| self.y[i]);
            let toggle = event == Some(q);
            match self.contacts[q] {
                None if toggle || d > 0.0 || (d == 0.0 && rate > 0.0) => {
                    self.contacts[q] = Some(Contact {
                        onset: self.t,
                        v_max: rate.max(0.0),
                        dissipated_before: self.y[sys.dissipation(pair.p)],
                        exit: None,
                        peak_force: 0.0,
                    });
                    self.v_max[q] = rate.max(0.0);
                    changed = true;
                }
                Some(c) if d <= -pair.rest_band => {
                    self.close(q, c);
                    changed = true;
                }
                Some(ref mut c) if rate > c.v_max => {
                    c.v_max = rate;
                    self.v_max[q] = rate;
                    changed = true;
                }
                _ => {}
            }
        }
        changed
    }

    /// Closes pair `q`'s contact `c` and records it as an impact at its onset.
    pub(super) fn close(&mut self, q: usize, c: Contact) {
        let sys = self.sys;
        let pair = &sys.pairs[q];
        let (a, b) = sys.bodies(pair);
        self.impacts.push(Impact {
            t: c.onset,
            a,
            b,
            approach_speed: c.v_max,
            energy_lost: self.y[sys.dissipation(pair.p)] - c.dissipated_before,
            impulses: 1,
            peak_force: Some(c.peak_force),
            contact_duration: Some(c.exit.unwrap_or(self.t) - c.onset),
        });
        self.contacts[q] = None;
        self.v_max[q] = 0.0;
    }

    /// The earliest point of the last step where a pair's contact state changes: the first
    /// scan point where an open pair's overlap is no longer positive, or a closed pair's is,
    /// refined to the crossing.
    pub(super) fn first_event(&self) -> Option<(f64, usize)> {
        let sys = self.sys;
        let mut earliest: Option<(f64, usize)> = None;
        for (q, pair) in sys.pairs.iter().enumerate() {
            if self.contacts[q].is_some() {
                continue;
            }
            let overlap = |th: f64| sys.overlap(pair, |i| self.dense_component(i, th)).0;
            let crossed = |d: f64| d > 0.0;
            let limit = earliest.map_or(1.0, |e| e.0);
            let mut prev = 0.0;
            for j in 1..=SCAN_POINTS {
                let th = (j as f64 / SCAN_POINTS as f64).min(limit);
                if crossed(overlap(th)) {
                    let root = if crossed(overlap(prev)) {
                        prev
                    } else {
                        // Sign of g follows "crossed": the root returned lies on the crossed side.
                        bracketed_root(
                            |x| if crossed(overlap(x)) { 1.0 } else { -1.0 } * overlap(x).abs().max(f64::MIN_POSITIVE),
                            prev,
                            th,
                            1e-15,
                        )
                    };
                    if earliest.is_none_or(|e| root < e.0) {
                        earliest = Some((root, q));
                    }
                    break;
                }
                if th >= limit {
                    break;
                }
                prev = th;
            }
        }
        earliest
    }

    /// Tracks each open contact's peak force and largest overlap rate over the last step (on
    /// the dense output, refined around a new peak). Returns whether a contact's largest rate,
    /// and so its damping, changed.
    pub(super) fn track_contacts(&mut self, t0: f64, h: f64) -> bool {
        let sys = self.sys;
        let mut changed = false;
        let stepper = if self.stiff { Active::Implicit(&self.rodas) } else { Active::Explicit(&self.rk) };
        let dense = |i: usize, th: f64| stepper.dense_component(i, th);
        for (q, pair) in sys.pairs.iter().enumerate() {
            let Some(c) = self.contacts[q].as_mut() else { continue };
            let v_max0 = c.v_max;
            // Force, overlap rate and overlap at `th`.
            let at = |th: f64| -> (f64, f64, f64) {
                let (d, rate) = sys.overlap(pair, |i| dense(i, th));
                (contact::force(pair.k, sys.alpha(v_max0, rate), d, rate), rate, d)
            };
            let mut best = (f64::NEG_INFINITY, 0usize);
            let mut rates = 0.0f64;
            let mut d_prev = 0.0;
            for j in 0..=SCAN_POINTS {
                let th = j as f64 / SCAN_POINTS as f64;
                let (f, rate, d) = at(th);
                // The contact's last exit: where the overlap last fell to zero in this step.
                if j > 0 && d_prev > 0.0 && d <= 0.0 {
                    let lo = (j - 1) as f64 / SCAN_POINTS as f64;
                    c.exit = Some(t0 + h * bracketed_root(|x| -at(x).2, lo, th, 1e-15));
                } else if d > 0.0 {
                    c.exit = None;
                }
                d_prev = d;
                rates = rates.max(rate);
                if f > best.0 {
                    best = (f, j);
                }
            }
            if best.0 > c.peak_force {
                c.peak_force = best.0;
                let j = best.1;
                if j > 0 && j < SCAN_POINTS {
                    // Golden-section search for the maximum between the neighbouring points.
                    let step = 1.0 / SCAN_POINTS as f64;
                    let (mut a, mut b) = ((j - 1) as f64 * step, (j + 1) as f64 * step);
                    let r = 0.5 * (5f64.sqrt() - 1.0);
                    let (mut x1, mut x2) = (b - r * (b - a), a + r * (b - a));
                    let (mut f1, mut f2) = (at(x1).0, at(x2).0);
                    for _ in 0..60 {
                        if f1 < f2 {
                            a = x1;
                            x1 = x2;
                            f1 = f2;
                            x2 = a + r * (b - a);
                            f2 = at(x2).0;
                        } else {
                            b = x2;
                            x2 = x1;
                            f2 = f1;
                            x1 = b - r * (b - a);
                            f1 = at(x1).0;
                        }
                        if b - a <= 1e-13 {
                            break;
                        }
                    }
                    c.peak_force = c.peak_force.max(f1).max(f2);
                }
            }
            // The rate may peak inside the step (a pair squeezed by a neighbour).
            if rates > c.v_max {
                c.v_max = rates;
                self.v_max[q] = rates;
                changed = true;
            }
        }
        changed
    }
}
