//! The constraint graph being built: simultaneous groups (a union-find) and
//! the before-relation between groups, kept transitively closed so that the
//! questions "is A already before B?" and "would A before B close a cycle?"
//! are answered in constant time. Paths (for explanations) are searched only
//! when a constraint is refused.

use std::collections::{BTreeMap, VecDeque};

use petgraph::unionfind::UnionFind;

/// A fixed-size set of feature indices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Bits(Vec<u64>);

impl Bits {
    pub fn new(n: usize) -> Self {
        Bits(vec![0; n.div_ceil(64)])
    }
    pub fn insert(&mut self, i: usize) {
        self.0[i / 64] |= 1 << (i % 64);
    }
    pub fn contains(&self, i: usize) -> bool {
        self.0[i / 64] & (1 << (i % 64)) != 0
    }
    pub fn union_with(&mut self, o: &Bits) {
        for (a, b) in self.0.iter_mut().zip(&o.0) {
            *a |= *b;
        }
    }
    pub fn intersects(&self, o: &Bits) -> bool {
        self.0.iter().zip(&o.0).any(|(a, b)| a & b != 0)
    }
}

/// One step of an explanation path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// `from` before `to` by constraint number `c`.
    Before { from: usize, to: usize, c: usize },
    /// `from` simultaneous with `to` by constraint number `c`.
    Together { from: usize, to: usize, c: usize },
}

/// Groups and the closed before-relation over `n` features (by index).
pub(crate) struct State {
    n: usize,
    uf: UnionFind<usize>,
    /// Per group representative: its members.
    members: Vec<Bits>,
    /// Per group representative: every feature in a group strictly after it.
    after: Vec<Bits>,
    /// Accepted before-constraints `(from, to, constraint number)`.
    before: Vec<(usize, usize, usize)>,
    /// Accepted simultaneous constraints `(a, b, constraint number)`.
    together: Vec<(usize, usize, usize)>,
}

impl State {
    pub fn new(n: usize) -> Self {
        let members = (0..n)
            .map(|i| {
                let mut b = Bits::new(n);
                b.insert(i);
                b
            })
            .collect();
        State {
            n,
            uf: UnionFind::new(n),
            members,
            after: vec![Bits::new(n); n],
            before: Vec::new(),
            together: Vec::new(),
        }
    }

    pub fn same_group(&self, a: usize, b: usize) -> bool {
        self.uf.equiv(a, b)
    }

    /// Whether `a`'s group is (transitively) before `b`'s.
    pub fn precedes(&self, a: usize, b: usize) -> bool {
        self.after[self.uf.find(a)].contains(b)
    }

    fn reps(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n).filter(|&i| self.uf.find(i) == i)
    }

    /// Records `a` before `b`; the caller has checked that this closes no
    /// cycle (`!precedes(b, a)` and not one group).
    pub fn add_before(&mut self, a: usize, b: usize, c: usize) {
        self.before.push((a, b, c));
        let (ra, rb) = (self.uf.find(a), self.uf.find(b));
        if self.after[ra].contains(b) {
            return;
        }
        let mut add = self.members[rb].clone();
        add.union_with(&self.after[rb]);
        let reps: Vec<usize> = self.reps().collect();
        for x in reps {
            if x == ra || self.after[x].contains(a) {
                self.after[x].union_with(&add);
            }
        }
    }

    /// Puts `a` and `b` in one group; the caller has checked that neither
    /// group precedes the other.
    pub fn add_together(&mut self, a: usize, b: usize, c: usize) {
        self.together.push((a, b, c));
        let (ra, rb) = (self.uf.find(a), self.uf.find(b));
        if ra == rb {
            return;
        }
        self.uf.union(ra, rb);
        let r = self.uf.find(ra);
        let mut members = self.members[ra].clone();
        members.union_with(&self.members[rb]);
        let mut after = self.after[ra].clone();
        after.union_with(&self.after[rb]);
        let mut add = members.clone();
        add.union_with(&after);
        let reps: Vec<usize> = self.reps().collect();
        for x in reps {
            if x != r && self.after[x].intersects(&members) {
                self.after[x].union_with(&add);
            }
        }
        self.members[r] = members;
        self.after[r] = after;
    }

    /// The groups with more than one member, each as sorted indices, sorted.
    pub fn groups(&self) -> Vec<Vec<usize>> {
        let mut by_rep: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for i in 0..self.n {
            by_rep.entry(self.uf.find(i)).or_default().push(i);
        }
        let mut g: Vec<Vec<usize>> = by_rep.into_values().filter(|g| g.len() > 1).collect();
        g.sort();
        g
    }

    /// Simultaneous links from `a` to `b` (same group), fewest first.
    pub fn together_path(&self, a: usize, b: usize) -> Vec<Step> {
        let mut adj: BTreeMap<usize, Vec<(usize, usize)>> = BTreeMap::new();
        for &(x, y, c) in &self.together {
            adj.entry(x).or_default().push((y, c));
            adj.entry(y).or_default().push((x, c));
        }
        let mut prev: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
        let mut queue = VecDeque::from([a]);
        let mut seen = Bits::new(self.n);
        seen.insert(a);
        while let Some(x) = queue.pop_front() {
            if x == b {
                break;
            }
            for &(y, c) in adj.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
                if !seen.contains(y) {
                    seen.insert(y);
                    prev.insert(y, (x, c));
                    queue.push_back(y);
                }
            }
        }
        let mut steps = Vec::new();
        let mut x = b;
        while x != a {
            let Some(&(p, c)) = prev.get(&x) else {
                return Vec::new();
            };
            steps.push(Step::Together { from: p, to: x, c });
            x = p;
        }
        steps.reverse();
        steps
    }

    /// A before-path from `a`'s group to `b`'s group (fewest before-steps,
    /// ties by constraint order), with the simultaneous links that join its
    /// steps; empty when there is none.
    pub fn before_path(&self, a: usize, b: usize) -> Vec<Step> {
        let (ra, rb) = (self.uf.find(a), self.uf.find(b));
        let mut out_of: BTreeMap<usize, Vec<(usize, usize, usize)>> = BTreeMap::new();
        for &(x, y, c) in &self.before {
            out_of.entry(self.uf.find(x)).or_default().push((x, y, c));
        }
        // prev[group] = the before-step that reached it.
        let mut prev: BTreeMap<usize, (usize, usize, usize)> = BTreeMap::new();
        let mut queue = VecDeque::from([ra]);
        let mut seen = Bits::new(self.n);
        seen.insert(ra);
        while let Some(g) = queue.pop_front() {
            if g == rb {
                break;
            }
            for &(x, y, c) in out_of.get(&g).map(Vec::as_slice).unwrap_or(&[]) {
                let gy = self.uf.find(y);
                if !seen.contains(gy) {
                    seen.insert(gy);
                    prev.insert(gy, (x, y, c));
                    queue.push_back(gy);
                }
            }
        }
        let mut edges = Vec::new();
        let mut g = rb;
        loop {
            let Some(&(x, y, c)) = prev.get(&g) else {
                return Vec::new();
            };
            edges.push((x, y, c));
            g = self.uf.find(x);
            if g == ra {
                break;
            }
            if edges.len() > self.n {
                return Vec::new();
            }
        }
        edges.reverse();
        let mut steps = Vec::new();
        let mut at = a;
        for (x, y, c) in edges {
            if at != x {
                steps.extend(self.together_path(at, x));
            }
            steps.push(Step::Before { from: x, to: y, c });
            at = y;
        }
        if at != b {
            steps.extend(self.together_path(at, b));
        }
        steps
    }
}
