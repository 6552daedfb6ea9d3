//! The cells the balls are sorted into (docs/MODEL.md §14): cubes at least as wide as the
//! largest ball's diameter, so that two touching balls are in the same cell or in neighbouring
//! ones, and a ball is tested only against the balls of the 27 cells around its own. Across the
//! motion the cells tile the container; along it they are numbered in the world's x without
//! bound and folded onto a few more columns than the container spans, so the frame may carry
//! the balls anywhere.

/// The balls in each cell.
pub(super) struct Cells {
    /// Width of a cell, m.
    pub(super) size: f64,
    /// Columns along x (the world's column `c` is `c mod nx`).
    nx: i64,
    /// Cells across, `[y, z]`.
    across: [i64; 2],
    /// The container's half width and half height: cells across start at `-half`.
    pub(super) half: [f64; 2],
    members: Vec<Vec<u32>>,
}

impl Cells {
    /// Cells for balls no larger than `largest_radius` in a container `length` long with
    /// cross-section `section`.
    pub(super) fn new(largest_radius: f64, length: f64, section: [f64; 2], balls: usize) -> Cells {
        // A little wider than a diameter: a ball's cell is followed by its crossings, which
        // round-off can place a hair late.
        let mut size = 2.0 * largest_radius * (1.0 + 1e-9);
        // No more cells than about four per ball: a sparse bed gets larger cells.
        let volume = (length + 2.0 * size) * section[0].max(size) * section[1].max(size);
        let most = (4 * balls.max(1)) as f64;
        if volume / size.powi(3) > most {
            size = (volume / most).cbrt();
        }
        let nx = (length / size).ceil() as i64 + 3;
        let across = [((section[0] / size).ceil() as i64).max(1), ((section[1] / size).ceil() as i64).max(1)];
        let count = (nx * across[0] * across[1]) as usize;
        Cells { size, nx, across, half: [0.5 * section[0], 0.5 * section[1]], members: vec![Vec::new(); count] }
    }

    /// The cell of a ball at `p`: its world column along x and its cells across.
    pub(super) fn cell_of(&self, p: [f64; 3]) -> [i64; 3] {
        let x = (p[0] / self.size).floor() as i64;
        let y = (((p[1] + self.half[0]) / self.size).floor() as i64).clamp(0, self.across[0] - 1);
        let z = (((p[2] + self.half[1]) / self.size).floor() as i64).clamp(0, self.across[1] - 1);
        [x, y, z]
    }

    fn index(&self, c: [i64; 3]) -> usize {
        ((c[0].rem_euclid(self.nx) * self.across[0] + c[1]) * self.across[1] + c[2]) as usize
    }

    pub(super) fn insert(&mut self, c: [i64; 3], ball: u32) {
        let k = self.index(c);
        self.members[k].push(ball);
    }

    pub(super) fn remove(&mut self, c: [i64; 3], ball: u32) {
        let k = self.index(c);
        let list = &mut self.members[k];
        if let Some(at) = list.iter().position(|&b| b == ball) {
            list.swap_remove(at);
        }
    }

    /// Whether cell `c` has a neighbour across axis `axis` (1 or 2) on side `dir`: the cells
    /// across end at the container's walls, which no ball crosses.
    pub(super) fn has_neighbour(&self, c: [i64; 3], axis: usize, dir: i64) -> bool {
        axis == 0 || (0..self.across[axis - 1]).contains(&(c[axis] + dir))
    }

    /// The lower face of cell `c` along `axis`, m (world x, container y and z).
    pub(super) fn face(&self, c: [i64; 3], axis: usize) -> f64 {
        let origin = if axis == 0 { 0.0 } else { -self.half[axis - 1] };
        origin + c[axis] as f64 * self.size
    }

    /// Calls `f` with every ball in the 27 cells around `c` (each once: there are at
    /// least three columns, so three neighbouring ones never fold onto one another).
    pub(super) fn around(&self, c: [i64; 3], mut f: impl FnMut(u32)) {
        let ys = (c[1] - 1).max(0)..=(c[1] + 1).min(self.across[0] - 1);
        let zs = (c[2] - 1).max(0)..=(c[2] + 1).min(self.across[1] - 1);
        for dx in -1..=1 {
            let column = (c[0] + dx).rem_euclid(self.nx) * self.across[0];
            for y in ys.clone() {
                let row = (column + y) * self.across[1];
                for z in zs.clone() {
                    for &b in &self.members[(row + z) as usize] {
                        f(b);
                    }
                }
            }
        }
    }
}
