//! Disjoint sets with path halving, linking the larger root under the smaller so that
//! every set is named by its smallest member whatever the order of the unions.

/// Disjoint sets over `0..n`.
#[derive(Clone, Debug, Default)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// Every element in a set of its own.
    pub fn new(n: usize) -> Self {
        let mut sets = Self::default();
        sets.reset(n);
        sets
    }

    /// Every element of `0..n` in a set of its own again (keeps the allocation).
    pub fn reset(&mut self, n: usize) {
        self.parent.clear();
        self.parent.extend(0..n as u32);
    }

    /// The set of `x` (its smallest member).
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let grandparent = self.parent[self.parent[x] as usize];
            self.parent[x] = grandparent;
            x = grandparent as usize;
        }
        x
    }

    /// Join the sets of `a` and `b`; returns the surviving and the absorbed root, or
    /// `None` if they were one set already.
    pub fn union(&mut self, a: usize, b: usize) -> Option<(usize, usize)> {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return None;
        }
        let (keep, merged) = (ra.min(rb), ra.max(rb));
        self.parent[merged] = keep as u32;
        Some((keep, merged))
    }

    /// Join every one of `members` to the first (a contact row's members: one set);
    /// returns the first, or `None` when there are none.
    pub fn union_all(&mut self, members: impl IntoIterator<Item = usize>) -> Option<usize> {
        let mut members = members.into_iter();
        let first = members.next()?;
        for other in members {
            self.union(first, other);
        }
        Some(first)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_are_named_by_their_smallest_member() {
        let mut sets = UnionFind::new(6);
        assert_eq!(sets.union(4, 2), Some((2, 4)));
        assert_eq!(sets.union(5, 4), Some((2, 5)));
        assert_eq!(sets.union(2, 5), None);
        assert_eq!(sets.find(5), 2);
        assert_eq!(sets.find(0), 0);
        assert_eq!(sets.union_all([1, 3, 0]), Some(1));
        assert_eq!(sets.find(3), 0);
        assert_eq!(sets.union_all([]), None);
        sets.reset(3);
        assert_eq!(sets.find(2), 2);
    }
}
