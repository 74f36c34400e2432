//! Reachability over a DAG as one bitset per node.
//!
//! Used to test "is there an order between these two passes" in O(1) after an
//! O(V·E/64) build; compiling a 1,000-pass graph needs 1,000 × 16 words.

/// `reaches(a, b)`: there is a path of at least one edge from `a` to `b`.
#[derive(Debug, Clone)]
pub struct Reach {
    words: usize,
    bits: Vec<u64>,
}

impl Reach {
    /// `order` must be a topological order of the nodes that `edges` connect.
    pub fn new(n: usize, order: &[usize], edges: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let words = n.div_ceil(64).max(1);
        let mut succ = vec![Vec::new(); n];
        for (a, b) in edges {
            succ[a].push(b);
        }
        let mut bits = vec![0u64; n * words];
        for &a in order.iter().rev() {
            for &b in &succ[a] {
                // Rows of `a` and `b` are disjoint slices of one vector.
                let (row_a, row_b) = if a < b {
                    let (lo, hi) = bits.split_at_mut(b * words);
                    (&mut lo[a * words..(a + 1) * words], &hi[..words])
                } else {
                    let (lo, hi) = bits.split_at_mut(a * words);
                    (&mut hi[..words], &lo[b * words..(b + 1) * words])
                };
                row_a[b / 64] |= 1 << (b % 64);
                for (x, y) in row_a.iter_mut().zip(row_b) {
                    *x |= *y;
                }
            }
        }
        Self { words, bits }
    }

    pub fn reaches(&self, a: usize, b: usize) -> bool {
        self.bits[a * self.words + b / 64] & (1 << (b % 64)) != 0
    }

    /// Whether `a` happens before `b` or they are the same node.
    pub fn reaches_or_same(&self, a: usize, b: usize) -> bool {
        a == b || self.reaches(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diamond() {
        // 0 -> 1 -> 3, 0 -> 2 -> 3, 4 alone
        let r = Reach::new(5, &[0, 1, 2, 3, 4], [(0, 1), (0, 2), (1, 3), (2, 3)]);
        assert!(r.reaches(0, 3));
        assert!(r.reaches(1, 3));
        assert!(!r.reaches(1, 2));
        assert!(!r.reaches(3, 0));
        assert!(!r.reaches(0, 4));
        assert!(!r.reaches(0, 0));
        assert!(r.reaches_or_same(4, 4));
    }

    #[test]
    fn wide_graph_crosses_word_boundaries() {
        let n = 200;
        let order: Vec<usize> = (0..n).collect();
        let r = Reach::new(n, &order, (0..n - 1).map(|i| (i, i + 1)));
        assert!(r.reaches(0, 199));
        assert!(r.reaches(63, 64));
        assert!(!r.reaches(130, 129));
    }
}
