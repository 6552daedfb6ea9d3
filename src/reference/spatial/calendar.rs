//! The spatial reference's event calendar (docs/MODEL.md §14): each ball's entries in a short
//! list of its own, and a tournament tree over the balls whose root is the ball with the
//! earliest entry. A ball's list is emptied when it is predicted again (every entry it owns is
//! then stale), so stale entries no longer wait in one large heap until they surface, and the
//! tree a pop walks is as deep as the balls are many, not their entries.

/// An entry's time as an integer in the same order: of two entries of different owners, the
/// one with the smaller key is the earlier, and at equal keys the lower owner's; of two of the
/// same owner, the one with the smaller key, and at equal keys neither.
pub(super) trait Timed {
    fn key(&self) -> u64;
}

/// Entries of type `T`, ordered by their keys ([`Timed`]), each owned by a ball.
pub(super) struct Calendar<T> {
    lists: Vec<Vec<T>>,
    /// Each ball's earliest entry: its key and its place in the ball's list, or [`NO_ENTRY`].
    heads: Vec<(u64, u32)>,
    /// Node `k` holds the key and the leaf of the earliest head below it (at equal keys the
    /// lower leaf); the leaves start at `leaves`, one per ball, `NO_HEAD` for a ball without
    /// entries (and past the balls). A walk up the tree compares the key it carries with each
    /// sibling's, read from the node itself rather than through the leaf it names.
    tree: Vec<Node>,
    leaves: usize,
    len: usize,
    /// The ball whose walks up the tree wait for [`Calendar::release`], or `NOT_HELD`.
    held: usize,
}

/// A node of the tree: the earliest head's key below it, then its leaf. Ordered as a pair, so
/// that at equal keys the lower leaf is the earlier.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Node {
    key: u64,
    leaf: u32,
}

/// The key of a ball without entries: later than any entry's.
const NO_HEAD: u64 = u64::MAX;

/// The head of a ball without entries.
const NO_ENTRY: (u64, u32) = (NO_HEAD, u32::MAX);

/// No ball held.
const NOT_HELD: usize = usize::MAX;

impl<T: Copy + Timed> Calendar<T> {
    /// An empty calendar for `balls` balls.
    pub(super) fn new(balls: usize) -> Self {
        let leaves = balls.max(1).next_power_of_two();
        let mut tree = vec![Node { key: NO_HEAD, leaf: 0 }; 2 * leaves];
        for k in 0..leaves {
            tree[leaves + k].leaf = k as u32;
        }
        for node in (1..leaves).rev() {
            tree[node] = tree[2 * node];
        }
        Calendar { lists: vec![Vec::new(); balls], heads: vec![NO_ENTRY; balls], tree, leaves, len: 0, held: NOT_HELD }
    }

    /// Entries held, stale ones included.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Enters `entry`, owned by ball `owner`.
    pub(super) fn push(&mut self, owner: usize, entry: T) {
        let list = &mut self.lists[owner];
        list.push(entry);
        self.len += 1;
        // Chosen without a branch: whether the new entry is the ball's earliest is as good as
        // random. The tree is walked either way; when the head stands, the walk stops at once.
        let head = self.heads[owner];
        let key = entry.key();
        self.heads[owner] = std::hint::select_unpredictable(key < head.0, (key, (list.len() - 1) as u32), head);
        if owner != self.held {
            self.update(owner);
        }
    }

    /// Holds ball `owner`'s place in the tree until [`Calendar::release`]: its head may change
    /// many times while it is predicted, and the tree is walked once, at the release. Nothing
    /// is taken out meanwhile.
    pub(super) fn hold(&mut self, owner: usize) {
        debug_assert_eq!(self.held, NOT_HELD, "one ball is held at a time");
        self.held = owner;
    }

    /// Walks the tree for the held ball's head as it now is.
    pub(super) fn release(&mut self) {
        let owner = std::mem::replace(&mut self.held, NOT_HELD);
        self.update(owner);
    }

    /// The earliest entry.
    pub(super) fn peek(&self) -> Option<&T> {
        let ball = self.tree[1].leaf as usize;
        let &(_, at) = self.heads.get(ball)?;
        self.lists[ball].get(at as usize)
    }

    /// Takes the earliest entry out.
    pub(super) fn pop(&mut self) -> Option<T> {
        debug_assert_eq!(self.held, NOT_HELD, "nothing is taken out while a ball is held");
        let owner = self.tree[1].leaf as usize;
        let &(key, at) = self.heads.get(owner)?;
        if key == NO_HEAD {
            return None;
        }
        let entry = self.lists[owner].swap_remove(at as usize);
        self.len -= 1;
        self.find_head(owner);
        Some(entry)
    }

    /// Drops every entry owned by ball `owner`.
    pub(super) fn clear(&mut self, owner: usize) {
        self.len -= self.lists[owner].len();
        self.lists[owner].clear();
        let had = std::mem::replace(&mut self.heads[owner], NO_ENTRY) != NO_ENTRY;
        if had && owner != self.held {
            self.update(owner);
        }
    }

    /// Keeps only the entries for which `keep` holds.
    pub(super) fn retain(&mut self, mut keep: impl FnMut(&T) -> bool) {
        for owner in 0..self.lists.len() {
            let before = self.lists[owner].len();
            self.lists[owner].retain(&mut keep);
            self.len -= before - self.lists[owner].len();
            self.find_head(owner);
        }
    }

    /// Finds ball `owner`'s earliest entry again (the first of equals in its list).
    fn find_head(&mut self, owner: usize) {
        let list = &self.lists[owner];
        let (mut key, mut at) = (NO_HEAD, u32::MAX);
        for (k, e) in list.iter().enumerate() {
            // Chosen without a branch: whether an entry is earlier is as good as random.
            let earlier = e.key() < key;
            (key, at) = std::hint::select_unpredictable(earlier, (e.key(), k as u32), (key, at));
        }
        self.heads[owner] = (key, at);
        self.update(owner);
    }

    /// Walks from ball `owner`'s leaf to the root, each node taking its earlier child.
    fn update(&mut self, owner: usize) {
        let key = self.heads[owner].0;
        let mut node = self.leaves + owner;
        let mut earliest = Node { key, leaf: owner as u32 };
        self.tree[node] = earliest;
        while node > 1 {
            let sibling = self.tree[node ^ 1];
            // The earlier of the two, chosen without a branch: which one it is, is as good as
            // random.
            let sibling_earlier = (sibling.key, sibling.leaf) < (earliest.key, earliest.leaf);
            earliest = std::hint::select_unpredictable(sibling_earlier, sibling, earliest);
            node /= 2;
            if self.tree[node] == earliest {
                // Nothing above changes: every node there was taken from this one as it is.
                break;
            }
            self.tree[node] = earliest;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    impl Timed for Reverse<(u64, usize)> {
        fn key(&self) -> u64 {
            self.0 .0
        }
    }

    /// The calendar gives its entries in the order a binary heap gives them, through pushes,
    /// pops, clears of a ball's entries and predictions of a held ball, on 20 000 random
    /// operations.
    #[test]
    fn the_calendar_pops_in_a_heaps_order() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let balls = 37;
        let mut calendar = Calendar::new(balls);
        let mut heap = BinaryHeap::new();
        for _ in 0..20_000 {
            match rng.random_range(0..11) {
                0..6 => {
                    // Ties in time go by owner; entries of one owner at one time are equal,
                    // as the solver's are.
                    let e = Reverse((rng.random_range(0..1_000_000u64), rng.random_range(0..balls)));
                    calendar.push(e.0 .1, e);
                    heap.push(e);
                }
                6..9 => assert_eq!(calendar.pop(), heap.pop()),
                9 => {
                    // A ball predicted again: held, cleared and given new entries (some
                    // owned by other balls), then released.
                    let owner = rng.random_range(0..balls);
                    calendar.hold(owner);
                    calendar.clear(owner);
                    heap.retain(|e: &Reverse<(u64, usize)>| e.0 .1 != owner);
                    for _ in 0..rng.random_range(0..8) {
                        let by = if rng.random_bool(0.5) { owner } else { rng.random_range(0..balls) };
                        let e = Reverse((rng.random_range(0..1_000_000u64), by));
                        calendar.push(by, e);
                        heap.push(e);
                    }
                    calendar.release();
                }
                _ => {
                    let owner = rng.random_range(0..balls);
                    calendar.clear(owner);
                    heap.retain(|e: &Reverse<(u64, usize)>| e.0 .1 != owner);
                }
            }
            assert_eq!(calendar.len(), heap.len());
            assert_eq!(calendar.peek(), heap.peek());
        }
    }
}
