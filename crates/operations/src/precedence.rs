//! Which machining features are gone when a feature is cut.
//!
//! Stage 6 classified every edge against the features in its machining
//! order (a topological order of the constraints, lowest id first). The
//! shank of a tool cutting deeper than its flute length beside a taller
//! feature rubs that feature if it still stands, so stage 7 keeps the tool
//! out of taller neighbours that come later, and stage 8 must not run a
//! taller neighbour that comes earlier after the feature: for those pairs
//! it gets a `Before` edge here (`shank_edges`). Both stages read the same
//! edges, so they agree on what stands.

use std::collections::{BTreeMap, BTreeSet};

use thinplan_plan::{ConstraintKind, MachiningFeature, MachiningFeatureId, Plan};

/// The machining order stage 6 used for adjacency: Kahn's algorithm over
/// the machining constraints, lowest index first among the ready ones.
pub fn machining_order(plan: &Plan) -> Vec<MachiningFeatureId> {
    let n = plan.machining_features.len();
    let mut succ: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    let mut indeg = vec![0usize; n];
    for c in &plan.machining_constraints {
        let (a, b) = (c.first.0 as usize, c.second.0 as usize);
        if a < n && b < n && a != b && succ[a].insert(b) {
            indeg[b] += 1;
        }
    }
    let mut ready: BTreeSet<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
    let mut order = Vec::with_capacity(n);
    while let Some(v) = ready.pop_first() {
        order.push(MachiningFeatureId(v as u32));
        for &w in &succ[v] {
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.insert(w);
            }
        }
    }
    // A cycle (refused upstream) leaves features out: append them by id.
    let seen: BTreeSet<u32> = order.iter().map(|f| f.0).collect();
    order.extend(
        (0..n as u32)
            .filter(|i| !seen.contains(i))
            .map(MachiningFeatureId),
    );
    order
}

/// A feature's plan-view box (outer loop vertices; arcs as chords).
pub(crate) fn bbox(f: &MachiningFeature) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for v in &f.shape.region.outer.vertices {
        b[0] = b[0].min(v.x);
        b[1] = b[1].min(v.y);
        b[2] = b[2].max(v.x);
        b[3] = b[3].max(v.y);
    }
    b
}

/// Whether two features share one frame (their plan-view coordinates compare).
pub(crate) fn same_frame(a: &MachiningFeature, b: &MachiningFeature) -> bool {
    let (fa, fb) = (&a.shape.frame, &b.shape.frame);
    (fa.origin - fb.origin).length() < 1e-9
        && (fa.x - fb.x).length() < 1e-9
        && (fa.z - fb.z).length() < 1e-9
}

/// Whether `g` stands within `margin` of `f` in plan view (same frame) and
/// higher than `rise` above `f`'s bottom: a shank may meet it.
pub(crate) fn shank_neighbour(
    f: &MachiningFeature,
    g: &MachiningFeature,
    margin: f64,
    rise: f64,
) -> bool {
    if !same_frame(f, g) || g.shape.z_max <= f.shape.z_min + rise {
        return false;
    }
    let (a, b) = (bbox(f), bbox(g));
    b[0] <= a[2] + margin && a[0] <= b[2] + margin && b[1] <= a[3] + margin && a[1] <= b[3] + margin
}

/// The reach and the shortest flute of the plan's tool set: (largest
/// diameter, shortest flute length), or `None` without a tool set.
pub(crate) fn reach_and_rise(plan: &Plan, k: &thinplan_knowledge::Knowledge) -> Option<(f64, f64)> {
    let tools = k.tool_set(&plan.setup.tool_set)?;
    let d = tools.tools.iter().map(|t| t.diameter).fold(0.0, f64::max);
    let flute = tools
        .tools
        .iter()
        .map(|t| t.flute_length)
        .fold(f64::INFINITY, f64::min);
    (d > 0.0 && flute.is_finite()).then_some((d, flute))
}

/// `Before` edges (first, second) for every taller neighbour that comes
/// earlier in the machining order than a feature it stands beside, except
/// where the edge would close a cycle between stage 8's groups (features
/// joined by `Simultaneous` constraints run as one block).
pub fn shank_edges(
    plan: &Plan,
    margin: f64,
    rise: f64,
) -> Vec<(MachiningFeatureId, MachiningFeatureId)> {
    let n = plan.machining_features.len();
    let order = machining_order(plan);
    let mut pos = vec![0usize; n];
    for (k, f) in order.iter().enumerate() {
        pos[f.0 as usize] = k;
    }
    // Groups (union-find by smallest id) and the group graph.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while p[r] != r {
            r = p[r];
        }
        p[x] = r;
        r
    }
    for c in &plan.machining_constraints {
        let (a, b) = (c.first.0 as usize, c.second.0 as usize);
        if c.kind == ConstraintKind::Simultaneous && a < n && b < n {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let group: Vec<usize> = (0..n).map(|i| root(&mut parent, i)).collect();
    let mut succ: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    for c in &plan.machining_constraints {
        let (a, b) = (c.first.0 as usize, c.second.0 as usize);
        if c.kind == ConstraintKind::Before && a < n && b < n {
            succ.entry(group[a]).or_default().insert(group[b]);
        }
    }
    let reaches = |succ: &BTreeMap<usize, BTreeSet<usize>>, from: usize, to: usize| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from];
        while let Some(v) = stack.pop() {
            if v == to {
                return true;
            }
            if seen.insert(v) {
                stack.extend(succ.get(&v).into_iter().flatten().copied());
            }
        }
        false
    };
    let mut out = Vec::new();
    for f in &order {
        let i = f.0 as usize;
        let fi = &plan.machining_features[i];
        for j in order
            .iter()
            .map(|g| g.0 as usize)
            .take_while(|&j| pos[j] < pos[i])
        {
            let fj = &plan.machining_features[j];
            let (gi, gj) = (group[i], group[j]);
            if gi == gj || !shank_neighbour(fi, fj, margin, rise) {
                continue;
            }
            if succ.get(&gj).is_some_and(|s| s.contains(&gi)) {
                out.push((fj.id, fi.id));
                continue;
            }
            if reaches(&succ, gi, gj) {
                continue;
            }
            succ.entry(gj).or_default().insert(gi);
            out.push((fj.id, fi.id));
        }
    }
    out.sort();
    out.dedup();
    out
}
