//! The cells the balls are sorted into (docs/MODEL.md §14): cubes at least as wide as the
//! largest ball's diameter, so that two touching balls are in the same cell or in neighbouring
//! ones, and a ball is tested only against the balls of the 27 cells around its own. Across the
//! motion the cells tile the container; along it they are numbered in the world's x without
//! bound and folded onto a few more columns than the container spans, so the frame may carry
//! the balls anywhere.

/// No ball: the end of a cell's list.
const NONE: u32 = u32::MAX;

/// The balls in each cell, a list threaded through the balls: a cell holds its first ball and
/// each ball the next and the previous one in its cell, so that the cells around a ball are
/// read from two small arrays rather than from a buffer of their own each. Across the motion
/// a border of cells that stay empty lies beyond the walls, so that the 27 cells around any
/// ball are there to be read, without a bound checked on each.
pub(super) struct Cells {
    /// Width of a cell, m.
    pub(super) size: f64,
    /// Columns along x (the world's column `c` is `c mod nx`).
    nx: i64,
    /// Cells across, `[y, z]`.
    across: [i64; 2],
    /// The container's half width and half height: cells across start at `-half`.
    pub(super) half: [f64; 2],
    /// Each cell's first ball, or `NONE`.
    first: Vec<u32>,
    /// Each ball's next ball in its cell, or `NONE`.
    next: Vec<u32>,
    /// Each ball's previous ball in its cell, or `NONE` for the first.
    previous: Vec<u32>,
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
        let count = (nx * (across[0] + 2) * (across[1] + 2)) as usize;
        Cells {
            size,
            nx,
            across,
            half: [0.5 * section[0], 0.5 * section[1]],
            first: vec![NONE; count],
            next: vec![NONE; balls],
            previous: vec![NONE; balls],
        }
    }

    /// The cell of a ball at `p`: its world column along x and its cells across.
    pub(super) fn cell_of(&self, p: [f64; 3]) -> [i64; 3] {
        let x = (p[0] / self.size).floor() as i64;
        let y = (((p[1] + self.half[0]) / self.size).floor() as i64).clamp(0, self.across[0] - 1);
        let z = (((p[2] + self.half[1]) / self.size).floor() as i64).clamp(0, self.across[1] - 1);
        [x, y, z]
    }

    /// Where cell `c` (or a cell of the border, one beyond the walls across) is kept.
    fn index(&self, c: [i64; 3]) -> usize {
        ((c[0].rem_euclid(self.nx) * (self.across[0] + 2) + c[1] + 1) * (self.across[1] + 2) + c[2] + 1) as usize
    }

    /// Puts `ball` first in cell `c`.
    pub(super) fn insert(&mut self, c: [i64; 3], ball: u32) {
        let k = self.index(c);
        let b = ball as usize;
        let head = self.first[k];
        self.next[b] = head;
        self.previous[b] = NONE;
        if head != NONE {
            self.previous[head as usize] = ball;
        }
        self.first[k] = ball;
    }

    /// Takes `ball` out of cell `c`, which holds it.
    pub(super) fn remove(&mut self, c: [i64; 3], ball: u32) {
        let b = ball as usize;
        let (previous, next) = (self.previous[b], self.next[b]);
        if previous == NONE {
            let k = self.index(c);
            self.first[k] = next;
        } else {
            self.next[previous as usize] = next;
        }
        if next != NONE {
            self.previous[next as usize] = previous;
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
    pub(super) fn around(&self, c: [i64; 3], f: impl FnMut(u32)) {
        self.in_block(Cells::around_block(c), f);
    }

    /// The block of the 27 cells around `c`.
    pub(super) fn around_block(c: [i64; 3]) -> Block {
        Block { lo: [c[0] - 1, c[1] - 1, c[2] - 1], extent: [3, 3, 3] }
    }

    /// Calls `f` with every ball in `block` (cells of the border included, which are empty).
    #[inline]
    fn in_block(&self, block: Block, mut f: impl FnMut(u32)) {
        let (heads, count) = self.heads(block);
        for &head in &heads[..count] {
            let mut b = head;
            loop {
                f(b);
                match self.next(b) {
                    Some(next) => b = next,
                    None => break,
                }
            }
        }
    }

    /// The first balls of the cells of `block` that hold any, in the block's order, and how
    /// many: each cell's list goes on through [`Cells::next`]. Inlined, so that the 27 cells
    /// around a ball are read in loops of known length.
    #[inline(always)]
    pub(super) fn heads(&self, block: Block) -> ([u32; 27], usize) {
        let Block { lo, extent } = block;
        // The empty cells are skipped without a branch on each (whether a cell is empty is as
        // good as random, and a branch on it is mispredicted about every third cell); the
        // lists are then walked, mostly one ball long.
        let mut heads = [NONE; 27];
        let mut count = 0;
        for dx in 0..extent[0] {
            let start = self.index([lo[0] + dx, lo[1], lo[2]]);
            for dy in 0..extent[1] {
                let row = start + (dy * (self.across[1] + 2)) as usize;
                for dz in 0..extent[2] {
                    let b = self.first[row + dz as usize];
                    heads[count] = b;
                    count += usize::from(b != NONE);
                }
            }
        }
        (heads, count)
    }

    /// The ball after `b` in its cell.
    #[inline]
    pub(super) fn next(&self, b: u32) -> Option<u32> {
        let next = self.next[b as usize];
        (next != NONE).then_some(next)
    }

    /// Calls `f` with every ball of [`Cells::slab_block`].
    #[cfg(test)]
    fn slab(&self, c: [i64; 3], axis: usize, dir: i64, f: impl FnMut(u32)) {
        if let Some(block) = self.slab_block(c, axis, dir) {
            self.in_block(block, f);
        }
    }

    /// The block of the nine cells next to `c` across its face along `axis` on side `dir`:
    /// the cells a ball that has just crossed into `c` that way neighbours now and did not
    /// before; `None` past the container's walls across.
    pub(super) fn slab_block(&self, c: [i64; 3], axis: usize, dir: i64) -> Option<Block> {
        if !self.has_neighbour(c, axis, dir) {
            return None;
        }
        let mut block = Cells::around_block(c);
        block.lo[axis] = c[axis] + dir;
        block.extent[axis] = 1;
        Some(block)
    }
}

/// A block of cells: `extent` cells along each axis from `lo`, at most three.
#[derive(Clone, Copy)]
pub(super) struct Block {
    lo: [i64; 3],
    extent: [i64; 3],
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// The slab beyond the face a ball crossed holds exactly the balls around its new cell that
    /// were not around its old one, in every direction, at the walls across and where the
    /// columns along x fold: a ball in every cell of a 4 x 3 x 3 container.
    #[test]
    fn a_slab_holds_the_balls_a_crossing_ball_newly_neighbours() {
        let mut cells = Cells::new(0.5, 4.0, [3.0, 3.0], 200);
        let mut ball = 0;
        for x in -2..6 {
            for y in 0..3 {
                for z in 0..3 {
                    if (0..cells.nx).contains(&x) {
                        cells.insert([x, y, z], ball);
                        ball += 1;
                    }
                }
            }
        }
        // The balls a visit meets, each once.
        fn met(visit: impl FnOnce(&mut dyn FnMut(u32))) -> BTreeSet<u32> {
            let mut s = BTreeSet::new();
            visit(&mut |b| assert!(s.insert(b), "ball {b} met twice"));
            s
        }
        for x in -1..cells.nx + 1 {
            for y in 0..3 {
                for z in 0..3 {
                    let new = [x, y, z];
                    for axis in 0..3 {
                        for dir in [1i64, -1] {
                            if !cells.has_neighbour(new, axis, -dir) {
                                continue;
                            }
                            let mut old = new;
                            old[axis] -= dir;
                            let around_new = met(|f| cells.around(new, f));
                            let around_old = met(|f| cells.around(old, f));
                            let slab = met(|f| cells.slab(new, axis, dir, f));
                            let fresh: BTreeSet<u32> = around_new.difference(&around_old).copied().collect();
                            assert_eq!(slab, fresh, "crossing into {new:?} along {axis} towards {dir}");
                        }
                    }
                }
            }
        }
    }
}
