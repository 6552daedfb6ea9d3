//! A recorded ground acceleration (docs/MODEL.md §17): read from a two-column text file or a
//! PEER `.AT2` file, scaled, and interpolated linearly between its points, so that the ground's
//! velocity and displacement are its exact integrals (piecewise quadratic and cubic).

use std::sync::atomic::{AtomicUsize, Ordering};

/// Standard gravity, m/s^2: the unit of `.AT2` records.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// A ground acceleration record: `accel[j]` at `times[j]`, linear in between, zero after the
/// last point. A record that starts after `t = 0` is preceded by the point `(0, 0)`.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundRecord {
    /// Strictly increasing, the first 0, s.
    pub times: Vec<f64>,
    /// m/s^2.
    pub accel: Vec<f64>,
    /// The ground's displacement and velocity at each point (it starts at rest at 0), m and m/s.
    pub ground: Vec<(f64, f64)>,
    /// The stretch the last lookup found.
    last: LastStretch,
}

/// The stretch a record's last lookup found: lookups mostly come in time order, so the next is
/// most often in the same stretch. Only a hint: every answer is the one the search gives, and
/// two records with different hints are equal.
#[derive(Debug, Default)]
struct LastStretch(AtomicUsize);

impl Clone for LastStretch {
    fn clone(&self) -> Self {
        LastStretch(AtomicUsize::new(self.0.load(Ordering::Relaxed)))
    }
}

impl PartialEq for LastStretch {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// One stretch of a record on which the acceleration is linear.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretch {
    /// Index of its first point (`times.len() - 1` for the stretch after the record).
    pub index: usize,
    /// Start, s.
    pub start: f64,
    /// End (infinite after the record), s.
    pub end: f64,
    /// Acceleration at `start` and its slope: `ag = g0 + g1 (t - start)`.
    pub g0: f64,
    /// m/s^3.
    pub g1: f64,
    /// The ground's displacement and velocity at `start`.
    pub x0: f64,
    /// m/s.
    pub v0: f64,
}

impl Stretch {
    /// The ground's displacement, velocity and acceleration a time `s` into the stretch.
    #[inline]
    pub fn at(&self, s: f64) -> (f64, f64, f64) {
        let (g0, g1) = (self.g0, self.g1);
        (self.x0 + s * (self.v0 + s * (0.5 * g0 + s * g1 / 6.0)), self.v0 + s * (g0 + 0.5 * g1 * s), g0 + g1 * s)
    }
}

impl GroundRecord {
    /// The record of the points `(times, accel)` (already checked: finite, times strictly
    /// increasing from `>= 0`), each acceleration multiplied by `scale`.
    pub fn new(mut times: Vec<f64>, accel: Vec<f64>, scale: f64) -> Self {
        let mut accel: Vec<f64> = accel.into_iter().map(|a| a * scale).collect();
        if times[0] > 0.0 {
            times.insert(0, 0.0);
            accel.insert(0, 0.0);
        }
        let mut ground = Vec::with_capacity(times.len());
        let (mut x, mut v) = (0.0, 0.0);
        for j in 0..times.len() {
            ground.push((x, v));
            if j + 1 < times.len() {
                let h = times[j + 1] - times[j];
                let g1 = (accel[j + 1] - accel[j]) / h;
                x += h * (v + h * (0.5 * accel[j] + h * g1 / 6.0));
                v += h * (accel[j] + 0.5 * g1 * h);
            }
        }
        GroundRecord { times, accel, ground, last: LastStretch::default() }
    }

    /// The stretch that holds `t` (`t >= 0`); at a point, the stretch that starts there.
    pub fn stretch(&self, t: f64) -> Stretch {
        let n = self.times.len();
        let hint = self.last.0.load(Ordering::Relaxed);
        // The last point at or before `t`: the hint's when `t` lies in its stretch.
        let j = if hint < n && self.times[hint] <= t && (hint + 1 == n || t < self.times[hint + 1]) {
            hint
        } else {
            let j = self.times.partition_point(|&s| s <= t).saturating_sub(1);
            self.last.0.store(j, Ordering::Relaxed);
            j
        };
        self.stretch_at(j)
    }

    /// Stretch `j` (`j < times.len()`).
    pub fn stretch_at(&self, j: usize) -> Stretch {
        let last = self.times.len() - 1;
        let (x0, v0) = self.ground[j];
        if j >= last {
            // After the record the ground coasts at its last velocity, its acceleration zero.
            return Stretch { index: last, start: self.times[last], end: f64::INFINITY, g0: 0.0, g1: 0.0, x0, v0 };
        }
        let h = self.times[j + 1] - self.times[j];
        Stretch {
            index: j,
            start: self.times[j],
            end: self.times[j + 1],
            g0: self.accel[j],
            g1: (self.accel[j + 1] - self.accel[j]) / h,
            x0,
            v0,
        }
    }

    /// Largest `|ag|`, m/s^2.
    pub fn peak(&self) -> f64 {
        self.accel.iter().fold(0.0, |m, a| m.max(a.abs()))
    }

    /// Duration of the record, s.
    pub fn duration(&self) -> f64 {
        *self.times.last().expect("a record has points")
    }
}

/// A Kanai-Tajimi random ground motion (docs/MODEL.md §17): white noise of two-sided spectral
/// density `intensity` filtered by a soil layer of frequency `ground_frequency` and damping
/// `ground_damping`, times an envelope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KanaiTajimi {
    /// `fg`, Hz.
    pub ground_frequency: f64,
    /// `zeta_g`.
    pub ground_damping: f64,
    /// `S0`, m^2/s^3.
    pub intensity: f64,
    /// s.
    pub duration: f64,
    /// s.
    pub step: f64,
    /// `[rise, strong, decay]`, or none.
    pub envelope: Option<[f64; 3]>,
}

impl KanaiTajimi {
    /// The envelope at `t`.
    pub fn envelope_at(&self, t: f64) -> f64 {
        let Some([rise, strong, decay]) = self.envelope else { return 1.0 };
        if t < rise {
            (t / rise).powi(2)
        } else if t <= strong {
            1.0
        } else {
            (-decay * (t - strong)).exp()
        }
    }

    /// The stationary standard deviation of the filtered acceleration (no envelope),
    /// `sqrt(pi S0 wg (1 + 4 zeta_g^2) / (2 zeta_g))`, m/s^2.
    pub fn standard_deviation(&self) -> f64 {
        let (wg, zg) = (2.0 * std::f64::consts::PI * self.ground_frequency, self.ground_damping);
        (std::f64::consts::PI * self.intensity * wg * (1.0 + 4.0 * zg * zg) / (2.0 * zg)).sqrt()
    }

    /// The record drawn from `seed`: the noise held over each step (variance `2 pi S0 / step`),
    /// the filter `x'' + 2 zeta_g wg x' + wg^2 x = -n` stepped exactly (its transition matrix),
    /// the ground's acceleration `-(2 zeta_g wg x' + wg^2 x)` read at each step, from rest.
    pub fn record(&self, seed: u64) -> GroundRecord {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let noise =
            rand_distr::Normal::new(0.0, (2.0 * std::f64::consts::PI * self.intensity / self.step).sqrt()).expect("a finite spread");
        let wg = 2.0 * std::f64::consts::PI * self.ground_frequency;
        let filter = crate::oscillator::Oscillator::new(1.0, 2.0 * self.ground_damping * wg, wg * wg);
        let [[a, b], [c, d]] = filter.transition(self.step);
        let steps = (self.duration / self.step).ceil() as usize;
        let (mut x, mut v) = (0.0, 0.0);
        let (mut times, mut accel) = (Vec::with_capacity(steps + 1), Vec::with_capacity(steps + 1));
        for k in 0..=steps {
            let t = k as f64 * self.step;
            times.push(t);
            accel.push(-(2.0 * self.ground_damping * wg * v + wg * wg * x) * self.envelope_at(t));
            // Over the step the noise is a constant `n`: the filter moves about its static
            // deflection `-n / wg^2`.
            let n = noise.sample(&mut rng);
            let rest = -n / (wg * wg);
            let (dx, dv) = (x - rest, v);
            (x, v) = (rest + a * dx + b * dv, c * dx + d * dv);
        }
        GroundRecord::new(times, accel, 1.0)
    }
}

/// Reads the points of a record: a PEER `.AT2` file (by its header, accelerations in g at
/// `k DT`) or two columns of time (s) and acceleration (m/s^2) separated by a comma or spaces,
/// `#` starting a comment and a first line of words taken as a header. `named_at2` says that
/// the file's name ends in `.AT2` (any case), which makes it a PEER file even when its header
/// lacks `NPTS`. Returns the times and accelerations, or the rule the text breaks.
pub fn read_points(text: &str, named_at2: bool) -> Result<(Vec<f64>, Vec<f64>), String> {
    let lines: Vec<&str> = text.lines().collect();
    if let Some(k) = at2_header(&lines) {
        return read_at2(&lines, k);
    }
    if named_at2 || is_peer_banner(&lines) {
        return Err(format!(
            "is a PEER .AT2 record, but none of its first {AT2_HEADER_LINES} lines gives NPTS (the number of points) and DT (their \
             step, s), as `NPTS=  4000, DT=   .0050 SEC`"
        ));
    }
    let (mut times, mut accel) = (Vec::new(), Vec::new());
    for (n, line) in lines.iter().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(|c: char| c == ',' || c.is_whitespace()).filter(|f| !f.is_empty()).collect();
        let numbers: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
        match numbers {
            Err(_) if times.is_empty() && accel.is_empty() => continue, // a header
            Err(_) => return Err(format!("line {}: `{line}` is not two numbers", n + 1)),
            Ok(v) if v.len() != 2 => return Err(format!("line {}: has {} columns, a record has two (time, acceleration)", n + 1, v.len())),
            Ok(v) => {
                times.push(v[0]);
                accel.push(v[1]);
            }
        }
    }
    check_points(&times, &accel)?;
    Ok((times, accel))
}

/// The lines of a PEER `.AT2` file's header searched for `NPTS`.
const AT2_HEADER_LINES: usize = 8;

/// The line of a PEER `.AT2` header that gives `NPTS`, when `lines` are one.
fn at2_header(lines: &[&str]) -> Option<usize> {
    lines.iter().take(AT2_HEADER_LINES).position(|l| l.to_ascii_uppercase().contains("NPTS"))
}

/// Whether `lines` open with the PEER database's banner (its first line names PEER).
fn is_peer_banner(lines: &[&str]) -> bool {
    lines.first().is_some_and(|l| l.trim_start().to_ascii_uppercase().starts_with("PEER"))
}

/// Whether `text` is a PEER `.AT2` record (ground accelerations in g), `named_at2` as in
/// [`read_points`].
pub fn is_at2(text: &str, named_at2: bool) -> bool {
    let lines: Vec<&str> = text.lines().collect();
    named_at2 || at2_header(&lines).is_some() || is_peer_banner(&lines)
}

/// Whether a record file's `path` ends in `.AT2`, any case.
pub fn named_at2(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("at2"))
}

/// The PEER format: a header whose line `k` gives `NPTS` and `DT`, then the accelerations in g.
fn read_at2(lines: &[&str], k: usize) -> Result<(Vec<f64>, Vec<f64>), String> {
    let header = lines[k].to_ascii_uppercase();
    let number_after = |key: &str| -> Option<f64> {
        let rest = &header[header.find(key)? + key.len()..];
        let rest = rest.trim_start_matches(|c: char| c == '=' || c.is_whitespace());
        let end = rest.find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+' || c == 'E')).unwrap_or(rest.len());
        rest[..end].parse().ok()
    };
    let (npts, dt) = match (number_after("NPTS"), number_after("DT")) {
        (Some(n), Some(d)) => (n, d),
        _ => {
            // The older header: `4000 .0050 NPTS, DT`.
            let nums: Vec<f64> = header.split(|c: char| c == ',' || c.is_whitespace()).filter_map(|f| f.parse().ok()).collect();
            match nums[..] {
                [n, d, ..] => (n, d),
                _ => return Err(format!("line {}: the AT2 header gives no NPTS and DT", k + 1)),
            }
        }
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(format!("line {}: DT must be a positive time step (got {dt})", k + 1));
    }
    let mut accel = Vec::new();
    for (n, line) in lines.iter().enumerate().skip(k + 1) {
        for field in line.split_whitespace() {
            accel.push(field.parse::<f64>().map_err(|_| format!("line {}: `{field}` is not a number", n + 1))? * STANDARD_GRAVITY);
        }
    }
    if accel.len() as f64 != npts {
        return Err(format!("the AT2 header announces {npts} points but the file has {}", accel.len()));
    }
    let times: Vec<f64> = (0..accel.len()).map(|j| j as f64 * dt).collect();
    check_points(&times, &accel)?;
    Ok((times, accel))
}

fn check_points(times: &[f64], accel: &[f64]) -> Result<(), String> {
    if times.len() < 2 {
        return Err("a record needs at least two points".into());
    }
    if let Some(j) = (0..times.len()).find(|&j| !times[j].is_finite() || !accel[j].is_finite()) {
        return Err(format!("point {} is not finite ({}, {})", j + 1, times[j], accel[j]));
    }
    if times[0] < 0.0 {
        return Err(format!("starts at a negative time ({} s)", times[0]));
    }
    if let Some(j) = (1..times.len()).find(|&j| times[j] <= times[j - 1]) {
        return Err(format!("times must increase: point {} ({} s) is not after point {j} ({} s)", j + 1, times[j], times[j - 1]));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_at2_records_read_alike() {
        let text = "time, accel\n0, 0\n0.01, 0.4903325\n# comment\n0.02 -0.980665\n";
        let (t, a) = read_points(text, false).unwrap();
        assert_eq!(t, vec![0.0, 0.01, 0.02]);
        let at2 = "PEER NGA STRONG MOTION DATABASE RECORD\nSYNTHETIC\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=    3, DT=   .0100 SEC\n  0.0  .05  -.1\n";
        let (t2, a2) = read_points(at2, false).unwrap();
        assert_eq!(t2, t);
        for (x, y) in a.iter().zip(&a2) {
            assert!((x - y).abs() < 1e-15);
        }
        assert!(read_points("0 1\n0 2\n", false).unwrap_err().contains("must increase"));
        assert!(read_points("0 1 2\n", false).unwrap_err().contains("columns"));
    }

    /// The filtered noise has the Kanai-Tajimi process's stationary variance: over 2000 s
    /// (about 20 000 correlation times of the filter) the sample variance's standard error is
    /// about 1 %, and the noise held over each step cuts the filter's slowly decaying
    /// high-frequency tail (`4 zeta_g^2 wg^2 S0 / w^2`) above about `2 / step`, some 2 % of the
    /// variance: 6 % is three times their sum.
    #[test]
    fn kanai_tajimi_noise_has_its_stationary_variance() {
        let kt = KanaiTajimi { ground_frequency: 2.5, ground_damping: 0.6, intensity: 0.02, duration: 2000.0, step: 0.01, envelope: None };
        let r = kt.record(7);
        let tail = &r.accel[1000..];
        let variance = tail.iter().map(|a| a * a).sum::<f64>() / tail.len() as f64;
        let expected = kt.standard_deviation().powi(2);
        assert!((variance / expected - 1.0).abs() < 0.06, "{variance} vs {expected}");
        // Another seed draws another record; the same seed the same one.
        assert_ne!(kt.record(8).accel, r.accel);
        assert_eq!(kt.record(7), r);
    }

    #[test]
    fn the_ground_motion_integrates_the_record_exactly() {
        // A ramp then a constant: the ground's velocity and displacement in closed form.
        let r = GroundRecord::new(vec![0.0, 1.0, 3.0], vec![0.0, 2.0, 2.0], 1.0);
        let s = r.stretch(2.0);
        let (x, v, a) = s.at(1.0);
        // v(t) = t^2 on [0, 1], then 1 + 2 (t - 1); x = t^3/3, then 1/3 + (t-1) + (t-1)^2.
        assert!((v - 3.0).abs() < 1e-15 && (x - (1.0 / 3.0 + 1.0 + 1.0)).abs() < 1e-15 && a == 2.0);
        let after = r.stretch(10.0);
        assert_eq!((after.g0, after.g1, after.end), (0.0, 0.0, f64::INFINITY));
        assert!((after.v0 - 5.0).abs() < 1e-15);
    }
}
