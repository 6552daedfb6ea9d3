//! The contact forces of a step: the candidate pairs from the cells, each open contact's Hertz
//! spring with Hunt-Crossley damping along its normal and its tangential force capped by
//! Coulomb friction, and the impact a contact makes when it closes.

use super::*;

impl Solver<'_> {
    /// Every force and torque at the current positions and (predicted) velocities; contacts
    /// that ended are written as impacts. `h` is the step just taken (for the losses' sums).
    pub(super) fn forces(&mut self, h: f64) {
        let n = self.n;
        for i in 0..n {
            self.force[i] = std::array::from_fn(|k| self.mass[i] * self.gravity[k]);
            self.torque[i] = [0.0; 3];
            self.open[i].iter_mut().for_each(|c| c.seen = false);
        }
        // On a structure the floors' own forces act in their step; here the walls' alone.
        self.wall_forces.fill(0.0);
        if self.floors.is_none() {
            self.wall_forces[0] = self.scene.frame_force(self.t, self.xs, self.vs);
        }
        self.stiffness_rate = 0.0;
        self.damping_rate = 0.0;
        let moved = (0..n).any(|i| {
            let d: [f64; 3] = std::array::from_fn(|k| self.x[i][k] - self.listed_at[i][k]);
            let damper = self.damper[i] as usize;
            let floor_moved = self.carried[damper].0 - self.listed_carried[damper];
            (d[0] - floor_moved).powi(2) + d[1] * d[1] + d[2] * d[2] > 0.25 * self.skin * self.skin
        });
        if moved || self.steps == 0 {
            self.list_candidates();
        }
        for k in 0..self.ball_candidates.len() {
            let (i, j) = self.ball_candidates[k];
            let (i, j) = (i as usize, j as usize);
            let d: [f64; 3] = std::array::from_fn(|a| self.x[j][a] - self.x[i][a]);
            let reach = self.radius[i] + self.radius[j];
            if dot(d, d) < reach * reach {
                self.ball_contact(i, j, h);
            }
        }
        for k in 0..self.wall_candidates.len() {
            let (i, wall) = self.wall_candidates[k];
            let i = i as usize;
            let damper = self.damper[i] as usize;
            let local = [self.x[i][0] - self.carried[damper].0, self.x[i][1], self.x[i][2]];
            let (gap, normal) = self.chambers[damper].gap(wall, local, self.radius[i]);
            if gap < 0.0 {
                self.wall_contact(i, wall, -gap, normal, h);
            }
        }
        for i in 0..n {
            let mut k = 0;
            while k < self.open[i].len() {
                if self.open[i][k].seen {
                    k += 1;
                } else {
                    let c = self.open[i].swap_remove(k);
                    self.close(i, c, h);
                }
            }
        }
    }

    /// Lists the pairs and walls that may touch before some ball moves half the skin from
    /// where it is now (relative to the container): those closer than the skin now.
    pub(super) fn list_candidates(&mut self) {
        let skin = self.skin;
        let (x, damper, carried, offsets) = (&self.x, &self.damper, &self.carried, &self.offsets);
        self.cells.rebuild(|i| {
            let d = damper[i] as usize;
            [x[i][0] - carried[d].0 + offsets[d], x[i][1], x[i][2]]
        });
        self.ball_candidates.clear();
        self.wall_candidates.clear();
        for i in 0..self.n {
            let (xi, ri, di) = (self.x[i], self.radius[i], self.damper[i]);
            let (x, radius, list) = (&self.x, &self.radius, &mut self.ball_candidates);
            self.cells.neighbours(i, |j| {
                let d: [f64; 3] = std::array::from_fn(|k| x[j][k] - xi[k]);
                let reach = ri + radius[j] + skin;
                // Balls of two dampers are in two containers, on floors that move apart.
                if dot(d, d) < reach * reach && damper[j] == di {
                    list.push((i as u32, j as u32));
                }
            });
            let chamber = &self.chambers[di as usize];
            let local = [xi[0] - self.carried[di as usize].0, xi[1], xi[2]];
            for wall in chamber.walls_near(local) {
                if chamber.gap(wall, local, ri).0 < skin {
                    self.wall_candidates.push((i as u32, wall));
                }
            }
        }
        self.listed_at.copy_from_slice(&self.x);
        for (listed, (x, _)) in self.listed_carried.iter_mut().zip(&self.carried) {
            *listed = *x;
        }
    }

    /// The contact of balls `i < j` whose centres are closer than their radii's sum.
    pub(super) fn ball_contact(&mut self, i: usize, j: usize, h: f64) {
        let d: [f64; 3] = std::array::from_fn(|k| self.x[j][k] - self.x[i][k]);
        let dist = dot(d, d).sqrt();
        if dist <= 0.0 {
            return;
        }
        let normal: [f64; 3] = std::array::from_fn(|k| d[k] / dist);
        let overlap = self.radius[i] + self.radius[j] - dist;
        let (ri, rj) = (self.radius[i], self.radius[j]);
        let dv: [f64; 3] = std::array::from_fn(|k| self.v[i][k] - self.v[j][k]);
        let spin: [f64; 3] = std::array::from_fn(|k| ri * self.w[i][k] + rj * self.w[j][k]);
        let slip_all: [f64; 3] = {
            let s = cross(spin, normal);
            std::array::from_fn(|k| dv[k] + s[k])
        };
        let m_star = self.mass[i] * self.mass[j] / (self.mass[i] + self.mass[j]);
        let r_star = contact::effective_radius(ri, Some(rj));
        let (f_n, f_t) = self.contact_force(i, j as u32, None, r_star, m_star, overlap, dot(dv, normal), slip_all, normal, h);
        for k in 0..3 {
            let f = -f_n * normal[k] + f_t[k];
            self.force[i][k] += f;
            self.force[j][k] -= f;
        }
        let ti = cross(std::array::from_fn(|k| ri * normal[k]), f_t);
        let tj = cross(std::array::from_fn(|k| rj * normal[k]), f_t);
        for k in 0..3 {
            self.torque[i][k] += ti[k];
            self.torque[j][k] += tj[k];
        }
    }

    /// The contact of ball `i` with `wall`, overlapping it by `overlap` along `normal` (from
    /// the ball towards the wall).
    pub(super) fn wall_contact(&mut self, i: usize, wall: Wall, overlap: f64, normal: [f64; 3], h: f64) {
        let (ri, damper) = (self.radius[i], self.damper[i] as usize);
        let u = self.wall_velocity(damper);
        let dv: [f64; 3] = std::array::from_fn(|k| self.v[i][k] - u[k]);
        let s = cross(std::array::from_fn(|k| ri * self.w[i][k]), normal);
        let slip_all: [f64; 3] = std::array::from_fn(|k| dv[k] + s[k]);
        let m = self.mass[i];
        let floor_mass = self.floor_mass[damper];
        let m_star = if floor_mass.is_finite() { m * floor_mass / (m + floor_mass) } else { m };
        let r_star = contact::effective_radius(ri, None);
        let other = wall_index(self.n, wall);
        let (f_n, f_t) = self.contact_force(i, other, Some(wall), r_star, m_star, overlap, dot(dv, normal), slip_all, normal, h);
        for k in 0..3 {
            self.force[i][k] += -f_n * normal[k] + f_t[k];
        }
        self.wall_forces[self.carrier_floor[damper]] -= -f_n * normal[0] + f_t[0];
        let ti = cross(std::array::from_fn(|k| ri * normal[k]), f_t);
        for k in 0..3 {
            self.torque[i][k] += ti[k];
        }
    }

    /// The normal force (pushing the pair apart) and the tangential force on the first body of
    /// an open contact with overlap `overlap` growing at `rate`, slipping at `slip_all` (the
    /// contact point's relative velocity, normal part included); updates its record.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn contact_force(
        &mut self,
        i: usize,
        other: u32,
        wall: Option<Wall>,
        r_star: f64,
        m_star: f64,
        overlap: f64,
        rate: f64,
        slip_all: [f64; 3],
        normal: [f64; 3],
        h: f64,
    ) -> (f64, [f64; 3]) {
        let t = self.t;
        let slot = match self.open[i].iter().position(|c| c.other == other) {
            Some(k) => k,
            None => {
                let approach = rate.max(0.0);
                self.open[i].push(Open {
                    other,
                    wall,
                    k: contact::stiffness(self.e_star, r_star),
                    // Back along the approach to zero overlap.
                    onset: if approach > 0.0 { (t - overlap / approach).max(t - h) } else { t },
                    approach,
                    peak_force: 0.0,
                    loss: 0.0,
                    power: 0.0,
                    friction_power: 0.0,
                    overlap,
                    rate,
                    seen: true,
                });
                self.open[i].len() - 1
            }
        };
        let c = &mut self.open[i][slot];
        c.approach = c.approach.max(rate);
        let root = overlap.sqrt();
        let elastic = c.k * overlap * root;
        // The speed whose kinetic energy (at the reduced mass) is the contact's elastic energy:
        // never above the approach speed in an isolated impact, so `e` is kept, but it grows
        // with the load of a contact that neighbours squeeze, which keeps its damping rate
        // within `c` times its stiffness rate.
        let loaded = (0.8 * elastic * overlap / m_star).sqrt();
        let alpha = self.c / c.approach.max(loaded).max(self.v_floor);
        let f_n = contact::force(c.k, alpha, overlap, rate);
        // The next step must follow this contact: its linearised stiffness and its damping rate.
        self.stiffness_rate = self.stiffness_rate.max(1.5 * c.k * root / m_star);
        self.damping_rate = self.damping_rate.max(elastic * alpha / m_star);
        // What the normal force does beyond the elastic spring's work is lost.
        let power = (elastic - f_n) * -rate;
        let mut friction_power = 0.0;
        let along = dot(slip_all, normal);
        let slip: [f64; 3] = std::array::from_fn(|k| slip_all[k] - along * normal[k]);
        let speed = dot(slip, slip).sqrt();
        let mut f_t = [0.0; 3];
        if self.friction > 0.0 && speed > 0.0 {
            // A sphere's contact point slips against a tangential force with the mass 2/7 m*.
            let viscous = (2.0 / 7.0) * m_star / (SLIP_RELAXATION_STEPS * h.max(f64::MIN_POSITIVE)) * speed;
            let f = viscous.min(self.friction * f_n);
            f_t = std::array::from_fn(|k| -f * slip[k] / speed);
            friction_power = f * speed;
        }
        c.loss += 0.5 * (c.power + power) * h;
        self.impact_loss += 0.5 * (c.power + power) * h;
        self.friction_loss += 0.5 * (c.friction_power + friction_power) * h;
        c.power = power;
        c.friction_power = friction_power;
        c.peak_force = c.peak_force.max(f_n);
        c.overlap = overlap;
        c.rate = rate;
        c.seen = true;
        (f_n, f_t)
    }

    /// Contact `c` of ball `i` ended in the last step: its record becomes an impact.
    pub(super) fn close(&mut self, i: usize, c: Open, h: f64) {
        let tail = 0.5 * c.power * h;
        self.impact_loss += tail;
        self.friction_loss += 0.5 * c.friction_power * h;
        // Forward along the separation to zero overlap.
        let end = if c.rate < 0.0 { (self.t - h - c.overlap / c.rate).min(self.t) } else { self.t };
        if c.approach <= self.v_floor {
            return;
        }
        let (a, b) = match c.wall {
            None => (Body::Ball(i), Body::Ball(c.other as usize)),
            Some(Wall::Left) => (Body::LeftWall, Body::Ball(i)),
            Some(wall) => (Body::Ball(i), wall.body()),
        };
        self.impacts.push(Impact {
            t: c.onset,
            a,
            b,
            approach_speed: c.approach,
            energy_lost: c.loss + tail,
            impulses: 1,
            peak_force: Some(c.peak_force),
            contact_duration: Some(end - c.onset),
        });
    }
}
