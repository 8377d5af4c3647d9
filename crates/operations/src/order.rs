//! Stage 8: the operation order (§5.4.3).
//!
//! Every machining constraint is honoured: all operations of `first` before
//! all of `second` (`Before`); the operations of a simultaneous group run as
//! one block. Within a feature the operations keep the order stage 7 made
//! them in (main layers before the bottom layer). Among the groups ready to
//! run, the one that needs no tool change wins, then the one whose start is
//! nearest to where the tool is, then the lowest id — deterministic.

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{ConstraintKind, MachiningFeatureId, OperationId, Plan, Stage};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrderError {
    #[error("stage {0:?} has not run: order needs operations")]
    MissingStage(Stage),
    #[error("the machining constraints form a cycle through {0:?}")]
    Cycle(Vec<MachiningFeatureId>),
}

/// Stage 8: a topological order of the plan's operations. Besides the
/// machining constraints it honours the edges of `precedence.rs`: a taller
/// neighbour that stage 7 took as removed runs first (shank), and so does
/// every earlier feature an operation cuts into (stage 7 let the tool
/// overhang an open edge by a whole diameter).
pub fn order(plan: &Plan, k: &Knowledge) -> Result<Vec<OperationId>, OrderError> {
    if !plan.stages_done.contains(&Stage::Operations) {
        return Err(OrderError::MissingStage(Stage::Operations));
    }
    // A rest pass runs before what is cut below it within reach of the
    // set's largest tool, where that tool's flutes do not reach its top.
    let set = k.tool_set(&plan.setup.tool_set);
    let reach = set.map_or(0.0, |set| {
        set.tools.iter().map(|t| t.diameter).fold(0.0, f64::max)
    });
    let sizes: BTreeMap<String, Size> = set
        .map(|set| {
            set.tools
                .iter()
                .map(|t| {
                    let size = Size {
                        flute_length: t.flute_length,
                        diameter: t.diameter,
                    };
                    (t.id.clone(), size)
                })
                .collect()
        })
        .unwrap_or_default();
    order_with_edges(
        plan,
        &crate::precedence::stage8_edges(plan, k),
        (reach, &sizes),
    )
}

/// What stage 8 reads of a tool: how high its flutes reach (a rest pass
/// before what is cut below it) and its diameter (rest passes, larger
/// tools first).
#[derive(Debug, Clone, Copy)]
struct Size {
    flute_length: f64,
    diameter: f64,
}

/// Fills `plan.operation_order` and records stage 8.
pub fn apply_order(plan: &mut Plan, order: Vec<OperationId>) {
    plan.invalidate_from(Stage::Order);
    plan.operation_order = order;
    plan.stages_done.push(Stage::Order);
}

fn find(
    p: &mut BTreeMap<MachiningFeatureId, MachiningFeatureId>,
    x: MachiningFeatureId,
) -> MachiningFeatureId {
    let mut r = x;
    while let Some(&q) = p.get(&r) {
        if q == r {
            break;
        }
        r = q;
    }
    p.insert(x, r);
    r
}

/// Stage 8 without the stage check, without shank edges, and with rest
/// passes before features below them only where their plan boxes overlap.
pub fn order_unchecked(plan: &Plan) -> Result<Vec<OperationId>, OrderError> {
    order_with_edges(plan, &[], (0.0, &BTreeMap::new()))
}

/// Stage 8 with extra `Before` edges between features; `reach`: how far
/// apart in plan a feature below a rest pass's may lie and still come first,
/// and the tools' sizes by id (flute lengths for `rest_before_below`, a
/// tool not listed has none; diameters to run rest passes larger tools
/// first).
fn order_with_edges(
    plan: &Plan,
    extra: &[(MachiningFeatureId, MachiningFeatureId)],
    (reach, sizes): (f64, &BTreeMap<String, Size>),
) -> Result<Vec<OperationId>, OrderError> {
    // Features that have operations, and their operations in stage-7 order.
    let mut ops_of: BTreeMap<MachiningFeatureId, Vec<usize>> = BTreeMap::new();
    for (i, o) in plan.operations.iter().enumerate() {
        ops_of.entry(o.feature).or_default().push(i);
    }
    let mut feats: BTreeSet<MachiningFeatureId> = ops_of.keys().copied().collect();
    for c in &plan.machining_constraints {
        feats.insert(c.first);
        feats.insert(c.second);
    }
    for (a, b) in extra {
        feats.insert(*a);
        feats.insert(*b);
    }
    // Simultaneous groups by union-find (the smallest id represents).
    let mut parent: BTreeMap<MachiningFeatureId, MachiningFeatureId> =
        feats.iter().map(|f| (*f, *f)).collect();
    for c in &plan.machining_constraints {
        if c.kind == ConstraintKind::Simultaneous {
            let (a, b) = (find(&mut parent, c.first), find(&mut parent, c.second));
            if a != b {
                let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                parent.insert(hi, lo);
            }
        }
    }
    let mut group_of = BTreeMap::new();
    for f in &feats {
        group_of.insert(*f, find(&mut parent, *f));
    }
    let groups: BTreeSet<MachiningFeatureId> = group_of.values().copied().collect();
    let mut preds: BTreeMap<MachiningFeatureId, BTreeSet<MachiningFeatureId>> =
        groups.iter().map(|g| (*g, BTreeSet::new())).collect();
    for c in &plan.machining_constraints {
        if c.kind == ConstraintKind::Before {
            let (a, b) = (group_of[&c.first], group_of[&c.second]);
            if a == b {
                return Err(OrderError::Cycle(vec![c.first, c.second]));
            }
            preds.get_mut(&b).expect("every group").insert(a);
        }
    }
    for (a, b) in extra {
        let (a, b) = (group_of[a], group_of[b]);
        if a != b {
            preds.get_mut(&b).expect("every group").insert(a);
        }
    }
    // A group's operations: its features' operations, interleaved by
    // feature order (simultaneous features are machined together).
    let is_rest_pass = |i: usize| crate::runs_last(&plan.operations[i]);
    let diameter = |o: &thinplan_plan::Operation| sizes.get(&o.tool).map_or(0.0, |s| s.diameter);
    let members = |g: MachiningFeatureId| -> Vec<usize> {
        let mut v = Vec::new();
        for (f, ops) in &ops_of {
            if group_of[f] == g {
                v.extend(ops.iter().copied());
            }
        }
        // Fewest tool changes inside the block: by tool, larger tools first
        // (a feature's wall rest passes finish what its larger tool left),
        // stable.
        v.retain(|i| !is_rest_pass(*i));
        v.sort_by(|&a, &b| {
            let (oa, ob) = (&plan.operations[a], &plan.operations[b]);
            diameter(ob)
                .total_cmp(&diameter(oa))
                .then_with(|| oa.tool.cmp(&ob.tool))
        });
        v
    };
    let mut done: BTreeSet<MachiningFeatureId> = BTreeSet::new();
    let mut out = Vec::with_capacity(plan.operations.len());
    let mut tool: Option<String> = None;
    let mut pos: Option<DVec3> = None;
    while done.len() < groups.len() {
        let ready: Vec<MachiningFeatureId> = groups
            .iter()
            .copied()
            .filter(|g| !done.contains(g) && preds[g].iter().all(|p| done.contains(p)))
            .collect();
        if ready.is_empty() {
            let rest: Vec<MachiningFeatureId> = groups
                .iter()
                .copied()
                .filter(|g| !done.contains(g))
                .collect();
            return Err(OrderError::Cycle(rest));
        }
        let key = |g: MachiningFeatureId| {
            let ms = members(g);
            let first = ms.first().map(|i| &plan.operations[*i]);
            let change = match (&tool, first) {
                (Some(t), Some(o)) => usize::from(*t != o.tool),
                _ => 0,
            };
            let travel = match (pos, first) {
                (Some(p), Some(o)) => p.distance(o.start),
                _ => 0.0,
            };
            (change, travel, g)
        };
        let best = ready
            .iter()
            .copied()
            .min_by(|a, b| {
                let (ka, kb) = (key(*a), key(*b));
                ka.0.cmp(&kb.0)
                    .then(ka.1.total_cmp(&kb.1))
                    .then(ka.2.cmp(&kb.2))
            })
            .expect("ready is not empty");
        for i in members(best) {
            let o = &plan.operations[i];
            out.push(o.id);
            tool = Some(o.tool.clone());
            pos = Some(o.moves.last().map_or(o.start, |m| m.to));
        }
        done.insert(best);
    }
    // Rest passes last, by tool, in their features' order: each only
    // finishes its own feature's floor or wall stretches (after its other
    // operations), and one tool change serves them all. But not after an
    // operation below it: that tool's shank passes up through the corners
    // the rest pass has still to cut (`rest_before_below`).
    let feature_of: BTreeMap<OperationId, MachiningFeatureId> =
        plan.operations.iter().map(|o| (o.id, o.feature)).collect();
    let place: BTreeMap<MachiningFeatureId, usize> = out
        .iter()
        .enumerate()
        .rev()
        .map(|(k, id)| (feature_of[id], k))
        .collect();
    // How high above its floor each feature's shortest flutes reach (its
    // operations in `out`).
    let mut flute_of: BTreeMap<MachiningFeatureId, f64> = BTreeMap::new();
    for o in plan.operations.iter().filter(|o| !crate::runs_last(o)) {
        let l = sizes.get(&o.tool).map_or(0.0, |s| s.flute_length);
        let e = flute_of.entry(o.feature).or_insert(l);
        *e = e.min(l);
    }
    let mut rest: Vec<(usize, usize)> = (0..plan.operations.len())
        .filter(|i| is_rest_pass(*i))
        .map(|i| {
            let at = rest_before_below(plan, (&out, &feature_of, &place), (reach, &flute_of), i);
            (at, i)
        })
        .collect();
    // Larger tools first: a feature's wall rest passes each finish what the
    // larger tool before them left (stage 7 plans them so), and one tool
    // change serves all passes of a tool.
    rest.sort_by(|&(at_a, a), &(at_b, b)| {
        let (oa, ob) = (&plan.operations[a], &plan.operations[b]);
        at_a.cmp(&at_b)
            .then(diameter(ob).total_cmp(&diameter(oa)))
            .then_with(|| oa.tool.cmp(&ob.tool))
            .then_with(|| place.get(&oa.feature).cmp(&place.get(&ob.feature)))
            .then(a.cmp(&b))
    });
    let mut merged = Vec::with_capacity(out.len() + rest.len());
    let mut rest = rest.into_iter().peekable();
    for (k, id) in out.into_iter().enumerate() {
        while let Some((_, i)) = rest.next_if(|&(at, _)| at <= k) {
            merged.push(plan.operations[i].id);
        }
        merged.push(id);
    }
    merged.extend(rest.map(|(_, i)| plan.operations[i].id));
    Ok(merged)
}

/// Where in `out` (an index: before that operation; `out.len()`: at the
/// end) the rest pass `plan.operations[i]` runs: after its own feature, and
/// before the first operation after it whose feature lies below it (its top
/// no higher than the rest pass's feature's floor, their plan boxes within
/// `reach` of each other, both cut along +Z) so far that its shortest
/// flutes, at its floor, do not reach the rest pass's feature's top (there
/// they would cut what the rest pass leaves, and above them a shank would
/// meet it). A
/// pass planned with every other feature gone (orphan stretches, the
/// feature's own tool with every edge open) runs at the end.
fn rest_before_below(
    plan: &Plan,
    (out, feature_of, place): (
        &[OperationId],
        &BTreeMap<OperationId, MachiningFeatureId>,
        &BTreeMap<MachiningFeatureId, usize>,
    ),
    (margin, flute_of): (f64, &BTreeMap<MachiningFeatureId, f64>),
    i: usize,
) -> usize {
    let o = &plan.operations[i];
    if matches!(o.schedule, thinplan_plan::Schedule::AtEnd { .. }) {
        return out.len();
    }
    let feats = &plan.machining_features;
    let along_z =
        |f: &thinplan_plan::MachiningFeature| (f.shape.frame.z - DVec3::Z).length() < 1e-9;
    let (Some(f), Some(&after)) = (feats.get(o.feature.0 as usize), place.get(&o.feature)) else {
        return out.len();
    };
    if !along_z(f) {
        return out.len();
    }
    let fb = f.plan_box();
    let below = |g: &thinplan_plan::MachiningFeature| {
        let gb = g.plan_box();
        along_z(g)
            && g.shape.z_max <= f.shape.z_min + 1e-6
            && g.shape.z_min + flute_of.get(&g.id).copied().unwrap_or(0.0) < f.shape.z_max - 1e-6
            && gb[0] <= fb[2] + margin
            && fb[0] <= gb[2] + margin
            && gb[1] <= fb[3] + margin
            && fb[1] <= gb[3] + margin
    };
    (after + 1..out.len())
        .find(|&k| feats.get(feature_of[&out[k]].0 as usize).is_some_and(below))
        .unwrap_or(out.len())
}
