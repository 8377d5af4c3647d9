//! Through openings (DESIGN.md "Tool paths"): a feature whose bottom is open
//! and lies on the blank's underside — a hole, a cut-out, the space around
//! the part — ends at that underside, where a bull-nose or ball tool's
//! corner would leave a ring of material at the foot of the opening. Its
//! moves at that height go down by the tool's corner radius plus the
//! knowledge's `methods.breakthrough`, so the opening is cut free.

use std::collections::BTreeMap;

use thinplan_knowledge::{Knowledge, ToolSet};
use thinplan_plan::{Adjacency, MachiningFeatureId, Operation, Plan, Provenance};

/// Heights (along up) within this of a through feature's bottom are its
/// bottom level, mm.
const AT_BOTTOM: f64 = 1e-6;

/// The bottom height along up of every through feature.
fn through_bottoms(plan: &Plan) -> BTreeMap<MachiningFeatureId, f64> {
    let up = plan.setup.up.normalize_or_zero();
    let bottom = |f: &thinplan_plan::MachiningFeature| f.shape.frame.origin.dot(up) + f.shape.z_min;
    let lowest = plan
        .machining_features
        .iter()
        .filter(|f| f.shape.frame.z.dot(up) > 1.0 - 1e-9)
        .map(bottom)
        .fold(f64::INFINITY, f64::min);
    plan.machining_features
        .iter()
        .filter(|f| {
            f.bottom_adjacency == Adjacency::Open
                && f.shape.frame.z.dot(up) > 1.0 - 1e-9
                && bottom(f) <= lowest + AT_BOTTOM
        })
        .map(|f| (f.id, bottom(f)))
        .collect()
}

/// `plan` with every through feature reaching below the blank by the set's
/// largest corner radius plus `methods.breakthrough`: stage 7 then plans
/// its levels, entries and passes down to there like any other depth.
pub(crate) fn extended(plan: &Plan, k: &Knowledge, tools: &ToolSet) -> Option<Plan> {
    let drop = tools
        .tools
        .iter()
        .map(|t| t.corner_radius)
        .fold(0.0, f64::max)
        + k.methods.breakthrough;
    let through = through_bottoms(plan);
    if through.is_empty() || drop <= 0.0 {
        return None;
    }
    let mut out = plan.clone();
    for f in out.machining_features.iter_mut() {
        if through.contains_key(&f.id) {
            f.shape.z_min -= drop;
        }
    }
    Some(out)
}

/// Records the breakthrough in the provenance of the operations on
/// through features.
pub(crate) fn record(plan: &Plan, k: &Knowledge, tools: &ToolSet, ops: &mut [Operation]) {
    let through = through_bottoms(plan);
    for op in ops.iter_mut().filter(|o| through.contains_key(&o.feature)) {
        if let Some(t) = tools.tools.iter().find(|t| t.id == op.tool) {
            note(&mut op.provenance, t.corner_radius + k.methods.breakthrough);
        }
    }
}

fn note(p: &mut Provenance, drop: f64) {
    p.values.insert("breakthrough_mm".into(), drop);
}
