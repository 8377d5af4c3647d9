//! Stages 7 and 8: operations with modular tool paths, and their order.
//!
//! Per machining feature (after stage Resolve), the method of
//! `knowledge/methods.ron` that matches its adjacency picks the pattern, the
//! tool, stepovers, depths and entries (§6.3.3). Per z-level from the top
//! the modular pattern (§4.3.4, table 6.1) is built in the feature's frame:
//! rest-region passes (zigzag, one-way or a pocket spiral) over the
//! tool-centre region shrunk by the boundary stepover, then boundary passes
//! at exactly the tool radius from every product edge, down milling, with a
//! run-up; mirrored alternating z-levels where the method asks; ramp or helix
//! entries, never plunges; a separate product-adjacent bottom layer with
//! finishing conditions. Cutting conditions come from the material and tool;
//! times from `thinplan-feeds` under the machine's limits. [`order`] is
//! stage 8.

mod arcs;
mod breakthrough;
mod caps;
mod coverage;
mod covered;
mod free;
pub mod geom;
mod layers;
pub mod links;
pub mod order;
pub mod path;
pub mod precedence;
mod ramps;
mod rest;

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_feeds::MachineLimits;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{
    ArcMove, MachiningFeatureId, Operation, OperationId, PathMove, Plan, Provenance,
    ProvenanceSource, Refusal, Region3, Schedule, Stage,
};

pub use order::{order, OrderError};

/// Whether stage 8 runs `op` after its feature's other operations, with the
/// rest passes (floor rest passes, wall rest passes the knowledge defers,
/// passes planned with every other feature gone).
pub fn runs_last(op: &Operation) -> bool {
    !op.schedule.is_with_feature()
}
pub use path::{Kind, LMove};

/// Why stage 7 could not run at all (a single feature that cannot be milled
/// is a refusal, not an error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OperationsError {
    #[error("stage {0:?} has not run: operations need resolved machining features")]
    MissingStage(Stage),
    #[error("the set-up names {what} `{id}`, which the knowledge does not have")]
    UnknownResource { what: &'static str, id: String },
}

/// The result of stage 7.
#[derive(Debug, Clone, PartialEq)]
pub struct Operations {
    pub operations: Vec<Operation>,
    /// Things a planner should look at (material left in sharp corners, a
    /// run-up that did not fit …), each naming the feature.
    pub warnings: Vec<String>,
    /// Features no operation was made for, with the reason.
    pub refusals: Vec<Refusal>,
}

impl Operations {
    /// Writes the operations into the plan: drops stale results from stage
    /// Operations on, then records this stage.
    pub fn apply_to(self, plan: &mut Plan) {
        plan.invalidate_from(Stage::Operations);
        plan.operations = self.operations;
        plan.refusals.extend(self.refusals);
        plan.stages_done.push(Stage::Operations);
    }
}

/// What `plan --json` shows per operation, read back from its provenance.
#[derive(Debug, Clone, PartialEq)]
pub struct OperationSummary {
    pub id: OperationId,
    pub feature: MachiningFeatureId,
    pub tool: String,
    pub pattern: String,
    pub layers: usize,
    pub length_mm: f64,
    pub time_s: f64,
}

/// The summary of an operation made by this stage.
pub fn summary(op: &Operation) -> OperationSummary {
    let v = |k: &str| op.provenance.values.get(k).copied().unwrap_or(0.0);
    let pattern = op
        .provenance
        .note
        .split(';')
        .find_map(|s| s.trim().strip_prefix("pattern="))
        .unwrap_or("")
        .to_string();
    OperationSummary {
        id: op.id,
        feature: op.feature,
        tool: op.tool.clone(),
        pattern,
        layers: v("layers") as usize,
        length_mm: v("length_mm"),
        time_s: v("time_s"),
    }
}

/// Stage 7: operations for every machining feature of the plan.
pub fn operations(plan: &Plan, k: &Knowledge) -> Result<Operations, OperationsError> {
    if !plan.stages_done.contains(&Stage::Resolve) {
        return Err(OperationsError::MissingStage(Stage::Resolve));
    }
    operations_unchecked(plan, k)
}

/// Stage 7 without the stage check (synthetic plans in tests and tools).
pub fn operations_unchecked(plan: &Plan, k: &Knowledge) -> Result<Operations, OperationsError> {
    let (_, tools, _) = resources(plan, k)?;
    let through = breakthrough::extended(plan, k, tools);
    let p = through.as_ref().unwrap_or(plan);
    let mut out = first_pass(p, k)?;
    finish_orphan_stretches(p, k, &mut out)?;
    breakthrough::record(plan, k, tools, &mut out.operations);
    Ok(out)
}

/// Stage 7's second pass on `ops` (which [`operations`] runs): wall rest
/// passes, run last, for the product wall stretches of each feature that no
/// operation in `ops` came beside (see `orphan_stretches`). Public so that a
/// driver that edits operations can finish what the edit left.
pub fn finish_orphan_stretches(
    plan: &Plan,
    k: &Knowledge,
    ops: &mut Operations,
) -> Result<(), OperationsError> {
    let env = environment(plan, k)?;
    let d_max = env.tools.reach_and_rise().map_or(0.0, |(d, _)| d);
    let positions = precedence::machining_positions(plan);
    orphan_stretches(plan, &env, ops, d_max, &positions);
    Ok(())
}

/// The knowledge a plan's set-up names, for stage 7.
fn environment<'k>(plan: &Plan, k: &'k Knowledge) -> Result<layers::Env<'k>, OperationsError> {
    let (machine, tools, limits) = resources(plan, k)?;
    let material =
        k.material(&plan.setup.material)
            .ok_or_else(|| OperationsError::UnknownResource {
                what: "material",
                id: plan.setup.material.clone(),
            })?;
    // Links that leave a feature's footprint clear every feature's top.
    let up = plan.setup.up.normalize_or_zero();
    let global_top = plan
        .machining_features
        .iter()
        .map(|f| f.shape.frame.origin.dot(up) + f.shape.z_max)
        .fold(f64::NEG_INFINITY, f64::max);
    Ok(layers::Env {
        k,
        tools,
        material,
        machine,
        limits,
        global_top,
        orphans: None,
    })
}

/// Stage 7's first pass: each feature's operations.
fn first_pass(plan: &Plan, k: &Knowledge) -> Result<Operations, OperationsError> {
    let env = environment(plan, k)?;
    let tools = env.tools;
    let mut out = Operations {
        operations: Vec::new(),
        warnings: Vec::new(),
        refusals: Vec::new(),
    };
    let (d_max, min_flute) = tools.reach_and_rise().unwrap_or((0.0, f64::INFINITY));
    let positions = precedence::machining_positions(plan);
    // How far a feature no tool fits alone may be reached from beside it:
    // the smallest tool's diameter times the largest overhang the method
    // knowledge allows beyond an open edge.
    let rest_reach = tools
        .tools
        .iter()
        .map(|t| t.diameter)
        .fold(f64::INFINITY, f64::min)
        * k.methods
            .methods
            .iter()
            .map(|m| m.overhang.open)
            .fold(0.0, f64::max);
    // The same edges stage 8 honours: what stands when a feature is cut.
    let shank_edges = precedence::shank_edges(plan, d_max, min_flute);
    // Features that get no operation, and every feature they cover from
    // the tool side (accessibility constraints): machining those would
    // plunge or rapid into material that is still there.
    // (reason, whether the material is unreachable in this set-up)
    let mut skipped: std::collections::BTreeMap<usize, (String, bool)> = plan
        .machining_features
        .iter()
        .enumerate()
        .filter(|(_, f)| f.access_blocked)
        .map(|(i, _)| {
            (
                i,
                (
                    "unreachable in this set-up: the part covers it from the tool side \
                     (another set-up)"
                        .to_string(),
                    true,
                ),
            )
        })
        .collect();
    let mut made: Vec<Option<Result<layers::Made, String>>> =
        (0..plan.machining_features.len()).map(|_| None).collect();
    let mut covering = covered::Covering::new(plan.machining_features.len());
    loop {
        for (i, f) in plan.machining_features.iter().enumerate() {
            if made[i].is_some() || skipped.contains_key(&i) {
                continue;
            }
            let free = free::free_space(plan, i, 2.0 * d_max);
            let removed = free::removed_space(plan, i, 2.0 * d_max, &positions);
            let obstacles = free::shank_obstacles(plan, i, d_max, min_flute, &shank_edges);
            if covering.by[i].is_empty() {
                made[i] = Some(feature_made(
                    f,
                    &env,
                    free.as_ref(),
                    removed.as_ref(),
                    &obstacles,
                    rest_reach,
                ));
                continue;
            }
            let reason = covering.reason[i].clone().unwrap_or_default();
            let spaces = free.zip(removed);
            match spaces.and_then(|s| {
                covered_made(
                    plan,
                    i,
                    &covering,
                    s,
                    obstacles,
                    &reason.0,
                    |piece, s, o| feature_made(piece, &env, Some(&s.0), Some(&s.1), o, rest_reach),
                )
            }) {
                Some(m) => made[i] = Some(m),
                None => {
                    skipped.insert(i, reason);
                }
            }
        }
        let changed = covering.spread(plan, &skipped, &mut made);
        if !changed {
            break;
        }
    }
    for (i, f) in plan.machining_features.iter().enumerate() {
        if let Some((reason, unreachable)) = skipped.get(&i) {
            out.warnings
                .push(format!("{}: not machined: {reason}", f.id));
            let rule = if *unreachable {
                "operations.unreachable"
            } else {
                "operations.feature"
            };
            // Material covered from the tool side is an undercut: a height
            // field along the spindle (the stock simulation) never sees it.
            let seen = !f.access_blocked && !reason.contains("another set-up");
            let provenance = if *unreachable {
                unreachable_provenance(feature_volume(f), seen)
            } else {
                Provenance::new(ProvenanceSource::Default, rule)
            };
            out.refusals.push(Refusal {
                stage: Stage::Operations,
                rule: rule.into(),
                reason: format!("no operation for {}: {reason}", f.id),
                provenance,
            });
            continue;
        }
        let made = made[i].take().expect("computed above");
        match made {
            Ok(made) => {
                out.warnings.extend(made.warnings);
                for (reason, volume) in made.unreachable {
                    out.refusals.push(Refusal {
                        stage: Stage::Operations,
                        rule: "operations.unreachable".into(),
                        reason,
                        provenance: unreachable_provenance(volume, true),
                    });
                }
                for lo in made.ops {
                    let id = OperationId(out.operations.len() as u32);
                    out.operations.push(to_operation(id, f, lo, &env));
                }
            }
            Err(reason) => {
                out.warnings.push(format!("{}: {reason}", f.id));
                // No tool fits at all: unreachable material, not a failure.
                let unreachable = layers::is_unreachable(&reason);
                let rule = if unreachable {
                    "operations.unreachable"
                } else {
                    "operations.feature"
                };
                let provenance = if unreachable {
                    unreachable_provenance(feature_volume(f), true)
                } else {
                    Provenance::new(ProvenanceSource::Default, rule)
                };
                out.refusals.push(Refusal {
                    stage: Stage::Operations,
                    rule: rule.into(),
                    reason: format!("no operation for {}: {reason}", f.id),
                    provenance,
                });
            }
        }
    }
    let dropped = drop_covered_rest(&mut out.operations, plan.setup.up, tools);
    out.refusals.extend(dropped);
    Ok(out)
}

/// Stage 7's second pass: product wall stretches no operation came beside.
///
/// Each feature's passes follow its own product edges, in the space that is
/// removed when it is cut. A stretch of wall that its tool could not reach
/// then (a neighbour still stood where the tool had to be) is left to no
/// one: the neighbour, cut later, does not follow another feature's walls.
/// So once every feature has its operations, the features whose product
/// walls have a stretch that no operation came within the wall rest's
/// `min_left` of (at the floor, for the smallest tool's disc touching the
/// wall where it fits) are planned again for those stretches alone
/// ([`layers`]' `Rest::Orphan`): the smallest tool with room, every other
/// feature gone, run last. Features beside sloped faces (slabs of a
/// rounded or drafted face) are taken where some point of their floor was
/// left uncut (`has_uncut_floor`); their stretches are judged by the
/// feature's own material under the disc, which there reaches past open
/// edges into air.
fn orphan_stretches(
    plan: &Plan,
    env: &layers::Env,
    out: &mut Operations,
    d_max: f64,
    positions: &[usize],
) {
    let mk = &env.k.methods;
    let Some(min_left) = mk
        .methods
        .iter()
        .filter_map(|m| m.wall_rest.as_ref().map(|w| w.min_left))
        .reduce(f64::min)
    else {
        return;
    };
    let Some((r_s, rc_s)) = env
        .tools
        .tools
        .iter()
        .map(|t| (0.5 * t.diameter, t.corner_radius))
        .reduce(|a, b| if b.0 < a.0 { b } else { a })
    else {
        return;
    };
    let cov = coverage::Coverage::new(out.operations.iter(), plan.setup.up, env.tools);
    let with_ops: std::collections::BTreeSet<u32> =
        out.operations.iter().map(|o| o.feature.0).collect();
    let orphan_env = layers::Env {
        orphans: Some(&cov),
        ..env.clone_with_tools(env.tools)
    };
    let mut made = Vec::new();
    for (i, f) in plan.machining_features.iter().enumerate() {
        if !with_ops.contains(&(i as u32))
            || !match &f.slopes {
                None => has_orphan_stretch(f, &cov, r_s, min_left),
                Some(sl) => has_uncut_floor(f, sl, &cov, (r_s, r_s - rc_s), min_left),
            }
        {
            continue;
        }
        let free = free::free_space(plan, i, 2.0 * d_max);
        let removed = free::removed_space(plan, i, 2.0 * d_max, positions);
        let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            layers::feature_operations(f, &orphan_env, free.as_ref(), removed.as_ref(), &[])
        }));
        match res {
            Ok(Ok(m)) => {
                out.warnings.extend(m.warnings);
                made.extend(m.ops.into_iter().map(|lo| (f, lo)));
            }
            Ok(Err(e)) => out
                .warnings
                .push(format!("{}: no orphan wall rest pass: {e}", f.id)),
            Err(_) => out.warnings.push(format!(
                "{}: no orphan wall rest pass: the offset geometry failed on this profile \
                 (library panic)",
                f.id
            )),
        }
    }
    for (f, lo) in made {
        let id = OperationId(out.operations.len() as u32);
        out.operations.push(to_operation(id, f, lo, env));
    }
}

/// Whether some point of a sloped feature's floor was cut down to its
/// bottom by no operation, though the smallest tool could stand there: the
/// region sampled every 0.25 mm, less the band along its product edges
/// where the sloped faces reach into it at the bottom (the part stands
/// above the floor there); a point is cut when it lies within `min_left`
/// of some operation's disc at or below the bottom, and reachable when
/// some centre within `tool_r` of it keeps the flat bottom (`tool_flat`)
/// off those faces. A quick test: the feature's full geometry decides
/// (`layers`' `Rest::Orphan`).
fn has_uncut_floor(
    f: &thinplan_plan::MachiningFeature,
    slopes: &thinplan_plan::EdgeSlopes,
    cov: &coverage::Coverage,
    (tool_r, tool_flat): (f64, f64),
    min_left: f64,
) -> bool {
    const STEP: f64 = 0.25;
    // The points and the centres (5° apart) are sampled coarsely, and the
    // tool's corner meets a rising face later than its flat bottom: a test
    // this strict would refuse points the full geometry reaches.
    const SLACK: f64 = 0.05;
    let loops = geom::adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let offsets: Vec<&Vec<f64>> = slopes
        .side
        .iter()
        .chain(slopes.holes.iter().flatten())
        .collect();
    let polys: Vec<Vec<DVec2>> = loops
        .iter()
        .map(|(es, _)| es.iter().flat_map(|e| e.sample(STEP)).collect())
        .collect();
    // the product edges as chords, each with how far its face reaches
    // into the region at the bottom
    let product: Vec<(DVec2, DVec2, f64)> = loops
        .iter()
        .flat_map(|(es, adj)| es.iter().zip(adj))
        .enumerate()
        .filter(|(_, (_, a))| **a == thinplan_plan::Adjacency::Product)
        .flat_map(|(k, (e, _))| {
            let grow = offsets
                .get(k)
                .map_or(0.0, |o| (-slopes.beyond(o, f.shape.z_min)).max(0.0));
            e.chords(STEP).into_iter().map(move |(a, b)| (a, b, grow))
        })
        .collect();
    let band = product.iter().map(|c| c.2).fold(0.0, f64::max);
    // Whether the smallest tool could stand at the bottom over `q`: some
    // centre within its radius of `q` keeps its flat bottom off the faces
    // there (only those faces: a quick test before the full geometry).
    let reachable = |q: DVec2| {
        [tool_r - 1e-3, 0.5 * tool_r].iter().any(|&rho| {
            (0..72).any(|k| {
                let a = std::f64::consts::TAU * k as f64 / 72.0;
                let c = q + rho * DVec2::new(a.cos(), a.sin());
                product
                    .iter()
                    .all(|&(a, b, grow)| geom::dist_point_seg(c, a, b) >= tool_flat + grow - SLACK)
            })
        })
    };
    let (lo, hi) = polys.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(l, h), p| (l.min(*p), h.max(*p)),
    );
    let (nx, ny) = (
        ((hi.x - lo.x) / STEP).ceil().max(0.0) as usize,
        ((hi.y - lo.y) / STEP).ceil().max(0.0) as usize,
    );
    (0..=ny).any(|j| {
        (0..=nx).any(|i| {
            // the cheap test first: most points of a feature were cut
            let q = lo + DVec2::new(i as f64, j as f64) * STEP;
            !cov.covers(to_part(f, q, f.shape.z_min), 0.0, min_left)
                && geom::inside(q, &polys)
                && product
                    .iter()
                    .all(|&(a, b, _)| geom::dist_point_seg(q, a, b) > band + min_left)
                && reachable(q)
        })
    })
}

/// Whether some stretch of `f`'s product walls was not cut round at its
/// floor: the smallest tool's disc (radius `r`) touching the wall, where it
/// fits between the feature's product edges, lies inside no operation's
/// disc within `min_left`.
fn has_orphan_stretch(
    f: &thinplan_plan::MachiningFeature,
    cov: &coverage::Coverage,
    r: f64,
    min_left: f64,
) -> bool {
    const STEP: f64 = 0.5;
    let loops = geom::adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let product: Vec<geom::Edge2> = loops
        .iter()
        .flat_map(|(es, adj)| es.iter().zip(adj))
        .filter(|(_, a)| **a == thinplan_plan::Adjacency::Product)
        .map(|(e, _)| *e)
        .collect();
    // the product edges as chords, sampled once
    let chords: Vec<(DVec2, DVec2)> = product.iter().flat_map(|e| e.chords(STEP)).collect();
    let near_product = |c: DVec2| {
        chords
            .iter()
            .any(|&(a, b)| geom::dist_point_seg(c, a, b) < r - 1e-3)
    };
    for (k, (es, adj)) in loops.iter().enumerate() {
        // the region lies left of a counter-clockwise outer loop and right
        // of a counter-clockwise hole
        let pts: Vec<DVec2> = es.iter().flat_map(|e| e.sample(STEP)).collect();
        let area: f64 = (0..pts.len())
            .map(|i| pts[i].perp_dot(pts[(i + 1) % pts.len()]))
            .sum();
        let left = (area > 0.0) == (k == 0);
        for (e, a) in es.iter().zip(adj) {
            if *a != thinplan_plan::Adjacency::Product {
                continue;
            }
            for w in e.sample(STEP).windows(2) {
                let d = (w[1] - w[0]).normalize_or_zero();
                let n = if left { d.perp() } else { -d.perp() };
                let c = 0.5 * (w[0] + w[1]) + n * (r + 1e-3);
                if near_product(c) {
                    continue; // no room for the disc here (a corner)
                }
                if !cov.covers(to_part(f, c, f.shape.z_min), r, min_left) {
                    return true;
                }
            }
        }
    }
    false
}

/// Wall rest passes with the feature's own tool after every feature
/// (scheduled at the end with `covered_within_mm`) are planned per feature,
/// without knowing what the other features' operations cut. One whose every boundary point
/// another operation already cut (a move at or below its level whose disc
/// holds its disc within `min_left`) would only re-machine the product:
/// it is dropped, with a refusal naming its feature and rule. Ids are
/// renumbered in order.
fn drop_covered_rest(
    ops: &mut Vec<Operation>,
    up: DVec3,
    tools: &thinplan_knowledge::ToolSet,
) -> Vec<Refusal> {
    let within = |o: &Operation| match o.schedule {
        Schedule::AtEnd {
            covered_within_mm: Some(ml),
        } => Some(ml),
        _ => None,
    };
    let own = |o: &Operation| within(o).is_some();
    if !ops.iter().any(own) {
        return Vec::new();
    }
    let radius = |o: &Operation| {
        tools
            .tools
            .iter()
            .find(|t| t.id == o.tool)
            .map_or(0.0, |t| 0.5 * t.diameter)
    };
    // Every other operation's cutting moves.
    let cov = coverage::Coverage::new(ops.iter().filter(|o| !own(o)), up, tools);
    let view = cov.view();
    let mut drop = Vec::new();
    for (idx, o) in ops.iter().enumerate().filter(|(_, o)| own(o)) {
        let r = radius(o);
        let ml = within(o).unwrap_or(0.0);
        let mut from = o.start;
        let mut covered = true;
        'moves: for m in &o.moves {
            if m.region == Region3::Boundary {
                let (a, b) = (from, m.to);
                let z = view.z(a).min(view.z(b));
                let n = ((view.xy(a).distance(view.xy(b)) / 0.5).ceil() as usize).max(1);
                for s in 0..=n {
                    let c = a.lerp(b, s as f64 / n as f64);
                    // at the move's lowest height
                    let c = c + view.up() * (z - view.z(c));
                    if !cov.covers(c, r, ml) {
                        covered = false;
                        break 'moves;
                    }
                }
            }
            from = m.to;
        }
        if covered {
            drop.push(idx);
        }
    }
    let mut refusals = Vec::new();
    for &idx in drop.iter().rev() {
        let o = ops.remove(idx);
        let mut provenance =
            Provenance::new(ProvenanceSource::Knowledge, o.provenance.rule.clone());
        provenance
            .values
            .insert("feature".into(), f64::from(o.feature.0));
        if let Some(ml) = o.provenance.values.get("min_left_mm") {
            provenance.values.insert("min_left_mm".into(), *ml);
        }
        refusals.push(Refusal {
            stage: Stage::Operations,
            rule: o.provenance.rule.clone(),
            reason: format!(
                "{}: no wall rest pass with its own tool after every feature: other operations \
                 already cut every stretch of it",
                o.feature
            ),
            provenance,
        });
    }
    refusals.reverse();
    for (i, o) in ops.iter_mut().enumerate() {
        o.id = OperationId(i as u32);
    }
    refusals
}

/// A point of a feature's local frame (plan position `c`, height `z`) in
/// part coordinates.
pub(crate) fn to_part(f: &thinplan_plan::MachiningFeature, c: DVec2, z: f64) -> DVec3 {
    let fr = &f.shape.frame;
    let zz = fr.z.normalize_or_zero();
    let x = (fr.x - zz * fr.x.dot(zz)).normalize_or_zero();
    let y = zz.cross(x);
    fr.origin + x * c.x + y * c.y + zz * z
}

/// A whole feature's volume (mm³): its region over its depth.
/// `plan.machining_features[i]`'s operations on the pieces of it outside
/// the features above it that get no operation (`covering`), with the
/// material under them reported as unreachable (`reason`, why they get
/// none); `None` where nothing of it lies outside them.
fn covered_made(
    plan: &Plan,
    i: usize,
    covering: &covered::Covering,
    (free, removed): (free::Shapes, free::Shapes),
    mut obstacles: Vec<free::Obstacle>,
    reason: &str,
    make: impl Fn(
        &thinplan_plan::MachiningFeature,
        &(free::Shapes, free::Shapes),
        &[free::Obstacle],
    ) -> Result<layers::Made, String>,
) -> Option<Result<layers::Made, String>> {
    let f = &plan.machining_features[i];
    let keep = covered::footprint(covering.by[i].iter().map(|&j| &plan.machining_features[j]));
    let spaces = (covered::less(&free, &keep), covered::less(&removed, &keep));
    let (pieces, under) = covered::uncovered(f, &keep, &spaces.0, &spaces.1);
    if pieces.is_empty() {
        return None;
    }
    obstacles.extend(covered::obstacles(plan, &covering.by[i]));
    let mut whole = layers::Made::default();
    for piece in &pieces {
        match make(piece, &spaces, &obstacles) {
            Ok(p) => whole.absorb(p),
            Err(e) => return Some(Err(e)),
        }
    }
    let depth = (f.shape.z_max - f.shape.z_min).max(0.0);
    whole.unreachable.insert(
        0,
        (
            format!("{}: {under:.1} mm² of it left: {reason}", f.id),
            under * depth,
        ),
    );
    whole.warnings.insert(
        0,
        format!(
            "{}: planned on the {} piece(s) outside the features above it that get no \
             operation ({under:.1} mm² left)",
            f.id,
            pieces.len()
        ),
    );
    Some(Ok(whole))
}

/// A feature's operations: its own region first; where no tool fits it
/// alone, reached from the space cut beside it; where the safety net
/// refused the paths, with smaller tools.
fn feature_made(
    f: &thinplan_plan::MachiningFeature,
    env: &layers::Env,
    free: Option<&free::Shapes>,
    removed: Option<&free::Shapes>,
    obstacles: &[free::Obstacle],
    rest_reach: f64,
) -> Result<layers::Made, String> {
    // A geometry library panicking on an awkward profile
    // (cavalier_contours asserts on some degenerate offsets) refuses
    // this feature, not the plan.
    let attempt_on = |f: &thinplan_plan::MachiningFeature, env: &layers::Env| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            layers::feature_operations(f, env, free, removed, obstacles)
        }))
        .unwrap_or_else(|_| {
            Err("the offset geometry failed on this profile (library panic)".into())
        })
    };
    let attempt = |env: &layers::Env| attempt_on(f, env);
    let mut m = attempt(env);
    // No tool fits its own region: reach it from the space cut beside it
    // (a pocket corner between the walls' steps).
    if matches!(&m, Err(e) if e.starts_with(layers::NO_TOOL_FITS)) {
        let grown = free
            .zip(removed)
            .and_then(|(free, removed)| rest::reached_from_beside(f, free, removed, rest_reach));
        if let Some(g) = grown {
            if let Ok(mut made) = attempt_on(&g, env) {
                let note = format!(
                    "reached from the space cut beside it (region grown by up to \
                     {rest_reach:.3} mm: {:.1} → {:.1} mm²)",
                    layers::region_area(f),
                    layers::region_area(&g)
                );
                for op in &mut made.ops {
                    op.provenance.note.push_str(&format!("; {note}"));
                    op.provenance
                        .values
                        .insert("rest_reach_mm".into(), rest_reach);
                }
                made.warnings.insert(
                    0,
                    format!("{}: no tool fits its region alone; {note}", f.id),
                );
                m = Ok(made);
            }
        }
    }
    // A path the safety net refused with one tool may pass with a smaller
    // one: retry without the largest tools, one at a time.
    let mut fewer = env.tools.clone();
    while matches!(&m, Err(e) if !layers::is_unreachable(e)) && fewer.tools.len() > 1 {
        let largest = fewer
            .tools
            .iter()
            .enumerate()
            .max_by(|a, b| {
                a.1.diameter
                    .total_cmp(&b.1.diameter)
                    .then_with(|| b.1.id.cmp(&a.1.id))
            })
            .map(|(k, _)| k)
            .expect("more than one tool");
        let dropped = fewer.tools.remove(largest);
        let first = m.as_ref().err().cloned().unwrap_or_default();
        let sub = env.clone_with_tools(&fewer);
        m = attempt(&sub);
        if let Ok(made) = &mut m {
            made.warnings.insert(
                0,
                format!(
                    "{}: without {} ({first}); a smaller tool is used",
                    f.id, dropped.id
                ),
            );
        }
    }
    m
}

fn feature_volume(f: &thinplan_plan::MachiningFeature) -> f64 {
    layers::region_area(f) * (f.shape.z_max - f.shape.z_min).max(0.0)
}

/// Provenance of unreachable material: `volume_mm3`, the estimate, and
/// `seen_from_spindle` (1: open to the spindle, so a height-field stock
/// simulation counts it; 0: an undercut only another set-up reaches).
fn unreachable_provenance(volume: f64, seen: bool) -> Provenance {
    let mut p = Provenance::new(ProvenanceSource::Default, "operations.unreachable");
    p.values.insert("volume_mm3".into(), volume);
    p.values
        .insert("seen_from_spindle".into(), f64::from(u8::from(seen)));
    p
}

/// The set-up's machine and tool set from the knowledge, and the machine's
/// limits for the time model.
fn resources<'k>(
    plan: &Plan,
    k: &'k Knowledge,
) -> Result<
    (
        &'k thinplan_knowledge::Machine,
        &'k thinplan_knowledge::ToolSet,
        MachineLimits,
    ),
    OperationsError,
> {
    let unknown = |what: &'static str, id: &str| OperationsError::UnknownResource {
        what,
        id: id.to_string(),
    };
    let machine = k
        .machine(&plan.setup.machine)
        .ok_or_else(|| unknown("machine", &plan.setup.machine))?;
    let tools = k
        .tool_set(&plan.setup.tool_set)
        .ok_or_else(|| unknown("tool set", &plan.setup.tool_set))?;
    Ok((machine, tools, machine_limits(machine, k)))
}

/// The machine's limits for the time model.
fn machine_limits(machine: &thinplan_knowledge::Machine, k: &Knowledge) -> MachineLimits {
    MachineLimits {
        v_max: [machine.x.v_max, machine.y.v_max, machine.z.v_max],
        a_max: [machine.x.a_max, machine.y.a_max, machine.z.a_max],
        a_centripetal: machine.a_centripetal,
        corner_angle_deg: k.methods.corner_angle_deg,
    }
}

/// Length (mm) and time (s) of local moves from `start`, each with its
/// speed cap (mm/s), under `limits`: the one time model of every operation.
fn length_and_time<'a>(
    start: DVec3,
    moves: impl Iterator<Item = (&'a LMove, f64)>,
    limits: &MachineLimits,
) -> (f64, f64) {
    let mut from = start;
    let mut length = 0.0;
    let mut pts = vec![start];
    let mut caps = Vec::new();
    for (m, cap) in moves {
        length += path::move_length(from, m);
        for p in path::move_points(from, m, 1.0) {
            pts.push(p);
            caps.push(cap);
        }
        from = m.to;
    }
    let time = thinplan_feeds::schedule_polyline(&pts, &caps, limits).total_time;
    (length, time)
}

/// A local operation mapped to part coordinates with its feeds and time.
fn to_operation(
    id: OperationId,
    f: &thinplan_plan::MachiningFeature,
    mut lo: layers::LocalOp,
    env: &layers::Env,
) -> Operation {
    lo.moves = arcs::fit(lo.start, std::mem::take(&mut lo.moves));
    let z = f.shape.frame.z.normalize_or_zero();
    let to_part2 = |c: DVec2, zz: f64| to_part(f, c, zz);
    let to_part = |p: DVec3| to_part(f, p.truncate(), p.z);
    let feed = |kind: Kind| match kind {
        Kind::Rest | Kind::FullCut => lo.feed_rough,
        Kind::Boundary => lo.feed_boundary,
        Kind::BottomFinish => lo.feed_finish,
        Kind::Link => lo.feed_link,
        Kind::Rapid => 0.0,
    };
    let region = |kind: Kind| match kind {
        Kind::Rest | Kind::BottomFinish => Region3::Rest,
        Kind::FullCut => Region3::FullCut,
        Kind::Boundary => Region3::Boundary,
        Kind::Link => Region3::Link,
        Kind::Rapid => Region3::Rapid,
    };
    let mut moves = Vec::with_capacity(lo.moves.len());
    let rapid_cap = env.limits.v_max.iter().copied().fold(0.0, f64::max);
    let cap = |m: &LMove| {
        if m.kind == Kind::Rapid {
            rapid_cap
        } else {
            feed(m.kind) / 60.0
        }
    };
    let (length, time) =
        length_and_time(lo.start, lo.moves.iter().map(|m| (m, cap(m))), &env.limits);
    for m in &lo.moves {
        moves.push(PathMove {
            to: to_part(m.to),
            arc: m.arc.map(|(c, ccw)| ArcMove {
                centre: to_part2(c, m.to.z),
                axis: z,
                clockwise: !ccw,
            }),
            feed: feed(m.kind),
            region: region(m.kind),
        });
    }
    let mut prov = lo.provenance;
    prov.values.insert("length_mm".into(), length);
    prov.values.insert("time_s".into(), time);
    Operation {
        id,
        feature: f.id,
        method: lo.method,
        tool: lo.tool,
        tool_axis: z,
        spindle_rpm: lo.rpm,
        start: to_part(lo.start),
        moves,
        schedule: lo.schedule,
        provenance: prov,
        link_z: None,
    }
}

/// Per-operation numbers by id (for reports and benchmarks).
pub fn summaries(plan: &Plan) -> BTreeMap<OperationId, OperationSummary> {
    plan.operations.iter().map(|o| (o.id, summary(o))).collect()
}

/// A bull-nose end mill for unit tests (flutes 100 mm, holder Ø40).
#[cfg(test)]
pub(crate) fn test_tool(d: f64, rc: f64) -> thinplan_knowledge::Tool {
    thinplan_knowledge::Tool {
        id: "t".into(),
        kind: thinplan_knowledge::ToolKind::BullNoseEndMill,
        diameter: d,
        corner_radius: rc,
        flutes: 3,
        flute_length: 100.0,
        stickout: 120.0,
        shank_diameter: d,
        holder_diameter: 40.0,
        holder_length: 50.0,
        max_slot_depth_ratio: 0.5,
        neck_diameter: None,
        reach: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::MachiningFeatureId;

    fn op(feature: u32, own: bool, z: f64, a: (f64, f64), b: (f64, f64)) -> Operation {
        let mut provenance = Provenance::new(ProvenanceSource::Knowledge, "methods.t.wall_rest");
        if own {
            provenance.values.insert("after_every_feature".into(), 1.0);
            provenance.values.insert("min_left_mm".into(), 0.1);
        }
        let mv = |x: f64, y: f64, z: f64, region| PathMove {
            to: DVec3::new(x, y, z),
            arc: None,
            feed: if region == Region3::Rapid {
                0.0
            } else {
                1000.0
            },
            region,
        };
        Operation {
            id: OperationId(99),
            feature: MachiningFeatureId(feature),
            method: "t".into(),
            tool: "em12".into(),
            tool_axis: DVec3::Z,
            spindle_rpm: 10000.0,
            start: DVec3::new(a.0, a.1, 20.0),
            moves: vec![
                mv(a.0, a.1, z, Region3::Link),
                mv(
                    b.0,
                    b.1,
                    z,
                    if own {
                        Region3::Boundary
                    } else {
                        Region3::Rest
                    },
                ),
                mv(b.0, b.1, 20.0, Region3::Rapid),
            ],
            schedule: if own {
                Schedule::AtEnd {
                    covered_within_mm: Some(0.1),
                }
            } else {
                Schedule::WithFeature
            },
            provenance,
            link_z: None,
        }
    }

    /// A wall rest pass with the feature's own tool is dropped exactly when
    /// another operation's disc, at or below its level, held its disc
    /// everywhere along it (within `min_left`).
    #[test]
    fn an_own_tool_rest_pass_others_already_cut_is_dropped() {
        let k = Knowledge::builtin().unwrap();
        let tools = k.tool_set("endmills_12_20").unwrap();
        let mut ops = vec![
            op(1, false, 0.0, (0.0, 0.0), (50.0, 0.0)),
            op(2, true, 0.0, (10.0, 0.0), (40.0, 0.0)),
            op(3, true, 0.0, (10.0, 1.0), (40.0, 1.0)),
            op(4, true, -1.0, (10.0, 0.0), (40.0, 0.0)),
            op(5, true, 0.0, (10.0, 0.05), (60.0, 0.05)),
        ];
        let refused = drop_covered_rest(&mut ops, DVec3::Z, tools);
        let features: Vec<u32> = ops.iter().map(|o| o.feature.0).collect();
        // 2: on the same line at the same level; 3: 1 mm aside (> min_left);
        // 4: deeper; 5: runs 10 mm past the other's end.
        assert_eq!(features, [1, 3, 4, 5]);
        assert_eq!(refused.len(), 1);
        assert!(
            refused[0].reason.starts_with("MF2:"),
            "{}",
            refused[0].reason
        );
        assert_eq!(refused[0].rule, "methods.t.wall_rest");
        let ids: Vec<u32> = ops.iter().map(|o| o.id.0).collect();
        assert_eq!(ids, [0, 1, 2, 3]);
    }
}
