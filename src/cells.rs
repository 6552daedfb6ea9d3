//! A grid of cells over a container's inside, rebuilt by a counting sort, so that finding every
//! close pair of balls costs O(n): balls closer than a cell's width lie in the same or
//! neighbouring cells. The compliant model, the contact model and settled beds find their
//! pairs with it.

/// The cells and which balls lie in each.
pub(crate) struct Cells {
    /// Lower corner of the grid in the container's frame, m.
    low: [f64; 3],
    /// Width of a cell along each axis, m.
    size: [f64; 3],
    /// Cells along each axis.
    dims: [usize; 3],
    /// Where each cell's balls start in `items` (one more entry than cells).
    start: Vec<u32>,
    /// The balls, cell by cell.
    items: Vec<u32>,
    /// Each ball's cell.
    cell_of: Vec<u32>,
}

/// Cells per ball the grid may have at most: a container far larger than its balls gets
/// wider cells rather than a grid that outgrows memory.
const CELLS_PER_BALL: f64 = 16.0;

impl Cells {
    /// A grid over a container's inside, `[length, width, height]` in its frame (x from the
    /// left wall, y and z about the axis), for `n` balls, whose cells are at least `diameter`
    /// wide (the farthest apart a pair may be and still be found).
    pub(crate) fn new(inside: [f64; 3], diameter: f64, n: usize) -> Cells {
        let low = [0.0, -0.5 * inside[1], -0.5 * inside[2]];
        let extent: [f64; 3] = std::array::from_fn(|k| inside[k].max(diameter));
        let most = CELLS_PER_BALL * n as f64 + 64.0;
        let mut width = diameter.max(f64::MIN_POSITIVE);
        let count = |w: f64| extent.iter().map(|e| (e / w).floor().max(1.0)).product::<f64>();
        while count(width) > most {
            width *= 1.25;
        }
        let dims: [usize; 3] = std::array::from_fn(|k| (extent[k] / width).floor().max(1.0) as usize);
        let size: [f64; 3] = std::array::from_fn(|k| extent[k] / dims[k] as f64);
        let cells = dims.iter().product::<usize>();
        Cells { low, size, dims, start: vec![0; cells + 1], items: vec![0; n], cell_of: vec![0; n] }
    }

    fn coordinates(&self, p: [f64; 3]) -> [usize; 3] {
        std::array::from_fn(|k| (((p[k] - self.low[k]) / self.size[k]).floor().max(0.0) as usize).min(self.dims[k] - 1))
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]
    }

    /// Sorts the balls at `p(i)` (the container's frame) into their cells.
    pub(crate) fn rebuild(&mut self, p: impl Fn(usize) -> [f64; 3]) {
        self.start.iter_mut().for_each(|s| *s = 0);
        for i in 0..self.cell_of.len() {
            let c = self.index(self.coordinates(p(i)));
            self.cell_of[i] = c as u32;
            self.start[c + 1] += 1;
        }
        for c in 1..self.start.len() {
            self.start[c] += self.start[c - 1];
        }
        let mut next = self.start.clone();
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.items[next[c as usize] as usize] = i as u32;
            next[c as usize] += 1;
        }
    }

    /// Calls `visit(j)` for every ball `j > i` in ball `i`'s cell and the cells around it.
    pub(crate) fn neighbours(&self, i: usize, mut visit: impl FnMut(usize)) {
        self.runs_within(i, [0.0; 3], f64::INFINITY, |run| {
            for &j in &self.items[run] {
                if j as usize > i {
                    visit(j as usize);
                }
            }
        });
    }

    /// The balls in cell order: each cell's, by index, cell after cell.
    pub(crate) fn items(&self) -> &[u32] {
        &self.items
    }

    /// Calls `visit(run)` for where ball `i`'s cell and the cells around it lie in
    /// [`Cells::items`], less the cells farther than `reach` from `p` (ball `i`'s position in the
    /// container's frame; the cells on the grid's faces reach on without end, as they hold the
    /// balls beyond it). A run of neighbouring cells along z is one range, so there are nine
    /// ranges at most, in the cells' order.
    pub(crate) fn runs_within(&self, i: usize, p: [f64; 3], reach: f64, mut visit: impl FnMut(std::ops::Range<usize>)) {
        let c = self.cell_of[i] as usize;
        let at = [c / (self.dims[1] * self.dims[2]), (c / self.dims[2]) % self.dims[1], c % self.dims[2]];
        let low = |k: usize| at[k].saturating_sub(1);
        let high = |k: usize| (at[k] + 1).min(self.dims[k] - 1);
        // The square of how far `p` lies from the cells `a` along axis `k`.
        let off = |k: usize, a: usize| {
            let below = if a == 0 { f64::NEG_INFINITY } else { self.low[k] + a as f64 * self.size[k] };
            let above = if a + 1 == self.dims[k] { f64::INFINITY } else { self.low[k] + (a + 1) as f64 * self.size[k] };
            let d = (below - p[k]).max(p[k] - above).max(0.0);
            d * d
        };
        // A margin far above the rounding of the cells' bounds and of the balls' offsets.
        let limit = reach * reach * (1.0 + 1e-6);
        let (z_low, z_high) = (low(2), high(2));
        let along_z: [f64; 3] = std::array::from_fn(|d| if z_low + d <= z_high { off(2, z_low + d) } else { 0.0 });
        for a in low(0)..=high(0) {
            let along_x = off(0, a);
            for b in low(1)..=high(1) {
                let across = along_x + off(1, b);
                // The cells of a column within reach are a run: `off` grows away from `p`.
                let (mut first, mut last) = (usize::MAX, 0);
                for (d, z) in along_z.iter().enumerate().take(z_high - z_low + 1) {
                    if across + z <= limit {
                        first = first.min(d);
                        last = d;
                    }
                }
                if first <= last {
                    let (first, last) = (self.index([a, b, z_low + first]), self.index([a, b, z_low + last]));
                    visit(self.start[first] as usize..self.start[last + 1] as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair of centres closer than a diameter is visited once, whatever the grid.
    #[test]
    fn finds_every_close_pair_once() {
        let diameter = 0.1;
        let p: Vec<[f64; 3]> = (0..200)
            .map(|k| {
                let s = (k as f64 * 0.618_033_988_75).fract();
                let u = (k as f64 * 0.414_213_562_37).fract();
                let w = (k as f64 * 0.732_050_807_57).fract();
                [s, u - 0.5, 0.3 * (w - 0.5)]
            })
            .collect();
        for n_cells_cap in [1usize, 200] {
            let mut cells = Cells::new([1.0, 1.0, 0.3], diameter, n_cells_cap);
            cells.items = vec![0; p.len()];
            cells.cell_of = vec![0; p.len()];
            cells.rebuild(|i| p[i]);
            let mut found = Vec::new();
            for i in 0..p.len() {
                cells.neighbours(i, |j| {
                    let d: f64 = (0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum::<f64>().sqrt();
                    if d < diameter {
                        found.push((i, j));
                    }
                });
            }
            let mut all = Vec::new();
            for i in 0..p.len() {
                for j in i + 1..p.len() {
                    let d: f64 = (0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum::<f64>().sqrt();
                    if d < diameter {
                        all.push((i, j));
                    }
                }
            }
            found.sort();
            assert_eq!(found, all);
            assert!(!all.is_empty());
        }
    }

    /// The runs within a reach of a ball hold every ball within that reach of it, and only balls
    /// of the cells around it, on grids one or two cells deep along an axis and with balls
    /// beyond the grid's faces.
    #[test]
    fn runs_within_reach_hold_every_ball_within_it() {
        let width = 0.1;
        let point = |k: usize, extent: [f64; 3]| -> [f64; 3] {
            let u = [(k as f64 * 0.618_033_988_75).fract(), (k as f64 * 0.414_213_562_37).fract(), (k as f64 * 0.732_050_807_57).fract()];
            // Some balls lie a little beyond the grid, as a ball sunk into a wall does.
            std::array::from_fn(|a| (1.1 * u[a] - 0.05) * extent[a] - if a == 0 { 0.0 } else { 0.5 * extent[a] })
        };
        for extent in [[1.0, 0.5, 0.3], [0.15, 0.1, 0.25], [0.35, 0.05, 1.0]] {
            let p: Vec<[f64; 3]> = (0..300).map(|k| point(k, extent)).collect();
            let mut cells = Cells::new(extent, width, p.len());
            cells.rebuild(|i| p[i]);
            for reach in [0.03, 0.07, width] {
                for i in 0..p.len() {
                    let mut visited = Vec::new();
                    cells.runs_within(i, p[i], reach, |run| visited.extend(cells.items()[run].iter().map(|&j| j as usize)));
                    let mut around = Vec::new();
                    cells.neighbours(i, |j| around.push(j));
                    for j in (i + 1)..p.len() {
                        let d: f64 = (0..3).map(|a| (p[i][a] - p[j][a]).powi(2)).sum::<f64>().sqrt();
                        if d <= reach {
                            assert!(visited.contains(&j), "{extent:?} {reach}: ball {j} at {d} from {i}");
                        }
                    }
                    assert!(visited.iter().filter(|&&j| j > i).all(|j| around.contains(j)));
                    assert_eq!(visited.len(), visited.iter().collect::<std::collections::HashSet<_>>().len());
                }
            }
        }
    }
}
