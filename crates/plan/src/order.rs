//! One topological order for every stage and view that needs the machining
//! features in an order their constraints allow.

use std::collections::BTreeSet;

use crate::{ConstraintKind, MachiningFeatureId, Plan};

/// Kahn's algorithm over `edges` (first before second) among the nodes
/// `0..n`, the lowest index first among those free to go. Nodes on a cycle,
/// or behind one, are left out, so `len() < n` says there is a cycle.
/// Self-loops and edges out of range are ignored; repeated edges count once.
pub fn topological_order(n: usize, edges: impl IntoIterator<Item = (usize, usize)>) -> Vec<usize> {
    let mut succ: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    let mut indeg = vec![0usize; n];
    for (a, b) in edges {
        if a < n && b < n && a != b && succ[a].insert(b) {
            indeg[b] += 1;
        }
    }
    let mut ready: BTreeSet<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
    let mut order = Vec::with_capacity(n);
    while let Some(v) = ready.pop_first() {
        order.push(v);
        for &w in &succ[v] {
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.insert(w);
            }
        }
    }
    order
}

impl Plan {
    /// The machining features in an order honouring every `Before`
    /// machining constraint, the smallest id first among those free to go.
    /// Features on a cycle (only a hand-edited plan has one) follow by id.
    pub fn machining_order(&self) -> Vec<MachiningFeatureId> {
        let n = self.machining_features.len();
        let edges = self
            .machining_constraints
            .iter()
            .filter(|c| c.kind == ConstraintKind::Before)
            .map(|c| (c.first.0 as usize, c.second.0 as usize));
        let mut order = topological_order(n, edges);
        let mut seen = vec![false; n];
        for &i in &order {
            seen[i] = true;
        }
        order.extend((0..n).filter(|&i| !seen[i]));
        order
            .into_iter()
            .map(|i| MachiningFeatureId(i as u32))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lowest_index_first_among_the_ready_and_a_cycle_is_left_out() {
        // 3 → 0, 2 → 1: 2 and 3 are free; 2 goes first, then 1 (freed,
        // lower than 3), then 3, then 0.
        assert_eq!(topological_order(4, [(3, 0), (2, 1)]), vec![2, 1, 3, 0]);
        // 0 ⇄ 1 and 1 → 2: only 3 is outside the cycle and behind it.
        assert_eq!(topological_order(4, [(0, 1), (1, 0), (1, 2)]), vec![3]);
        // Self-loops, repeats and edges out of range are ignored.
        assert_eq!(
            topological_order(2, [(0, 0), (1, 0), (1, 0), (5, 1)]),
            vec![1, 0]
        );
    }
}
