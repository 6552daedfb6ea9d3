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
        let c = self.cell_of[i] as usize;
        let at = [c / (self.dims[1] * self.dims[2]), (c / self.dims[2]) % self.dims[1], c % self.dims[2]];
        let range = |k: usize| at[k].saturating_sub(1)..=(at[k] + 1).min(self.dims[k] - 1);
        for a in range(0) {
            for b in range(1) {
                for d in range(2) {
                    let cell = self.index([a, b, d]);
                    for &j in &self.items[self.start[cell] as usize..self.start[cell + 1] as usize] {
                        if j as usize > i {
                            visit(j as usize);
                        }
                    }
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
}
