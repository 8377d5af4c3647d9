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

/// The machining order stage 6 used for adjacency ([`Plan::machining_order`]).
pub fn machining_order(plan: &Plan) -> Vec<MachiningFeatureId> {
    plan.machining_order()
}

/// Each feature's place in [`machining_order`], by feature index.
pub(crate) fn machining_positions(plan: &Plan) -> Vec<usize> {
    let mut pos = vec![0usize; plan.machining_features.len()];
    for (k, f) in machining_order(plan).iter().enumerate() {
        pos[f.0 as usize] = k;
    }
    pos
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
    edges(
        plan,
        |fi, fj| fi.shank_neighbour(fj, margin, rise),
        |_, _| false,
    )
}

/// Stage 8's extra `Before` edges: the shank edges, and an edge from every
/// feature an operation cuts into (`cutting_pairs`) that comes earlier in
/// the machining order, in one pass so that together they close no cycle.
pub fn stage8_edges(
    plan: &Plan,
    k: &thinplan_knowledge::Knowledge,
) -> Vec<(MachiningFeatureId, MachiningFeatureId)> {
    let Some(tools) = k.tool_set(&plan.setup.tool_set) else {
        return Vec::new();
    };
    let Some((margin, rise)) = tools.reach_and_rise() else {
        return Vec::new();
    };
    let cuts = cutting_pairs(plan, tools);
    edges(
        plan,
        |fi, fj| fi.shank_neighbour(fj, margin, rise) || cuts.contains(&(fi.id, fj.id)),
        |fi, fj| cuts.contains(&(fi.id, fj.id)),
    )
}

/// `Before` edges (j, i) for every pair where `j` comes earlier than `i` in
/// the machining order and `wanted(i, j)` holds, then for every pair where
/// `j` comes later and `later(i, j)` holds (an operation of `i` reaches
/// into a neighbour stage 6 took as standing: it must be gone first), except
/// where the edge would close a cycle between stage 8's groups (features
/// joined by `Simultaneous` constraints run as one block). Pairs are
/// visited in machining order, so the result is deterministic.
fn edges(
    plan: &Plan,
    mut wanted: impl FnMut(&MachiningFeature, &MachiningFeature) -> bool,
    mut later: impl FnMut(&MachiningFeature, &MachiningFeature) -> bool,
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
            if gi == gj || !wanted(fi, fj) {
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
    for f in &order {
        let i = f.0 as usize;
        let fi = &plan.machining_features[i];
        for j in order
            .iter()
            .map(|g| g.0 as usize)
            .filter(|&j| pos[j] > pos[i])
        {
            let fj = &plan.machining_features[j];
            let (gi, gj) = (group[i], group[j]);
            if gi == gj || !later(fi, fj) || reaches(&succ, gi, gj) {
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

/// Depth (mm) by which a tool must enter a feature before it counts as
/// cutting it: a pass that only grazes a shared edge leaves it alone.
const CUT_INTO: f64 = 0.05;

/// Pairs (i, j), by feature id, where an operation of feature `i` (its
/// cutting moves; floor rest passes excepted, stage 8 runs them last) takes
/// more than `CUT_INTO` of feature `j`'s material: the tool's disc at some
/// point of a cutting move reaches that far into `j`'s region below `j`'s
/// top, where the flutes cut it or, above them, the shank rubs it. Stage 7
/// lets a tool overhang an edge to a feature earlier in the machining order
/// by up to a whole diameter (stage 6 calls it open), and a rest pass may
/// reach past an edge to a feature stage 6 took as standing, so `j` must be
/// gone when such an operation runs.
pub fn cutting_pairs(
    plan: &Plan,
    tools: &thinplan_knowledge::ToolSet,
) -> BTreeSet<(MachiningFeatureId, MachiningFeatureId)> {
    use glam::{DVec2, DVec3};
    let feats = &plan.machining_features;
    let boxes: Vec<[f64; 4]> = feats.iter().map(|f| f.plan_box()).collect();
    let rings: Vec<Vec<Vec<DVec2>>> = feats
        .iter()
        .map(|f| {
            std::iter::once(&f.shape.region.outer)
                .chain(&f.shape.region.holes)
                .map(|l| l.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect())
                .collect()
        })
        .collect();
    let mut out = BTreeSet::new();
    for op in &plan.operations {
        let i = op.feature.0 as usize;
        if i >= feats.len() || crate::runs_last(op) {
            continue;
        }
        let Some(tool) = tools.tools.iter().find(|t| t.id == op.tool) else {
            continue;
        };
        let r = tool.diameter / 2.0 - CUT_INTO;
        let fi = &feats[i];
        let fr = &fi.shape.frame;
        let y = fr.z.cross(fr.x);
        let local = |p: DVec3| {
            let d = p - fr.origin;
            DVec3::new(d.dot(fr.x), d.dot(y), d.dot(fr.z))
        };
        // Cutting segments in the feature's frame (arcs as 10° chords).
        let mut segs: Vec<(DVec3, DVec3)> = Vec::new();
        let mut from = op.start;
        for m in &op.moves {
            let cutting = m.feed > 0.0
                && matches!(
                    m.region,
                    thinplan_plan::Region3::Boundary
                        | thinplan_plan::Region3::FullCut
                        | thinplan_plan::Region3::Rest
                );
            if cutting {
                match m.arc {
                    None => segs.push((local(from), local(m.to))),
                    Some(a) => {
                        let (u, v) = (from - a.centre, m.to - a.centre);
                        let ax = if a.clockwise { -a.axis } else { a.axis };
                        let (pu, pv) = (u - ax * u.dot(ax), v - ax * v.dot(ax));
                        let mut sweep = pu.cross(pv).dot(ax).atan2(pu.dot(pv));
                        if sweep <= 0.0 {
                            sweep += std::f64::consts::TAU;
                        }
                        let k = ((sweep / 10f64.to_radians()).ceil() as usize).max(1);
                        let mut prev = local(from);
                        for s in 1..=k {
                            let t = s as f64 / k as f64;
                            let (sn, cs) = (sweep * t).sin_cos();
                            let q = a.centre
                                + pu * cs
                                + ax.cross(pu) * sn
                                + (u.dot(ax) + (v.dot(ax) - u.dot(ax)) * t) * ax;
                            let q = local(q);
                            segs.push((prev, q));
                            prev = q;
                        }
                    }
                }
            }
            from = m.to;
        }
        if segs.is_empty() {
            continue;
        }
        let mut sb = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for (a, b) in &segs {
            for p in [a, b] {
                sb = [
                    sb[0].min(p.x),
                    sb[1].min(p.y),
                    sb[2].max(p.x),
                    sb[3].max(p.y),
                ];
            }
        }
        for (j, fj) in feats.iter().enumerate() {
            let b = boxes[j];
            if j == i
                || out.contains(&(fi.id, fj.id))
                || b[0] > sb[2] + r
                || sb[0] > b[2] + r
                || b[1] > sb[3] + r
                || sb[1] > b[3] + r
                || !fi.same_frame(fj)
            {
                continue;
            }
            let zhi = fj.shape.z_max - CUT_INTO;
            let hit = segs.iter().any(|(a, b)| {
                if a.z.min(b.z) >= zhi {
                    return false;
                }
                let (p, q) = (a.truncate(), b.truncate());
                crate::geom::inside(p, &rings[j])
                    || rings[j].iter().any(|ring| {
                        let n = ring.len();
                        (0..n).any(|k| seg_seg_distance(p, q, ring[k], ring[(k + 1) % n]) < r)
                    })
            });
            if hit {
                out.insert((fi.id, fj.id));
            }
        }
    }
    out
}

/// Shortest distance between segments ab and cd.
fn seg_seg_distance(a: glam::DVec2, b: glam::DVec2, c: glam::DVec2, d: glam::DVec2) -> f64 {
    let cross = |o: glam::DVec2, p: glam::DVec2, q: glam::DVec2| (p - o).perp_dot(q - o);
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    use crate::geom::dist_point_seg;
    dist_point_seg(a, c, d)
        .min(dist_point_seg(b, c, d))
        .min(dist_point_seg(c, a, b))
        .min(dist_point_seg(d, a, b))
}
