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
            for i in 0..succ[a].len() {
                let b = succ[a][i];
                bits[a * words + b / 64] |= 1 << (b % 64);
                for w in 0..words {
                    bits[a * words + w] |= bits[b * words + w];
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
