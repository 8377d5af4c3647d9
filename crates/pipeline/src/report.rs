//! The plan as the `plan --json` contract (docs/CLI.md): what a script or
//! a later stage reads, in part coordinates, numbers rounded to 1e-6 so the
//! bytes are stable.

use serde_json::{json, Value};
use thinplan_brep::Brep;
use thinplan_plan::{Adjacency, ConstraintKind, MachiningFeature, Plan, ProfileLoop, Stage};

fn r6(x: f64) -> f64 {
    let v = (x * 1e6).round() / 1e6;
    if v == 0.0 {
        0.0
    } else {
        v
    }
}

fn adjacency_name(a: Adjacency) -> &'static str {
    match a {
        Adjacency::Product => "product",
        Adjacency::Open => "open",
        Adjacency::Feature => "feature",
    }
}

fn loop_area(l: &ProfileLoop) -> f64 {
    let v = &l.vertices;
    let n = v.len();
    0.5 * (0..n)
        .map(|i| v[i].x * v[(i + 1) % n].y - v[(i + 1) % n].x * v[i].y)
        .sum::<f64>()
}

/// Plan-view area times height (straight edges: resolved features have no arcs).
pub fn feature_volume(f: &MachiningFeature) -> f64 {
    let r = &f.shape.region;
    let area = loop_area(&r.outer).abs() - r.holes.iter().map(|h| loop_area(h).abs()).sum::<f64>();
    area * (f.shape.z_max - f.shape.z_min)
}

fn machining_feature_json(f: &MachiningFeature) -> Value {
    let fr = &f.shape.frame;
    let z = fr.z.normalize_or_zero();
    let x = fr.x.normalize_or_zero();
    let y = z.cross(x);
    let base = fr.origin.dot(z);
    // The profile drawn at the top of the feature (where the tool enters).
    let loop_points = |l: &ProfileLoop| -> Vec<Value> {
        l.vertices
            .iter()
            .map(|v| {
                let p = fr.origin + x * v.x + y * v.y + z * f.shape.z_max;
                json!([r6(p.x), r6(p.y), r6(p.z)])
            })
            .collect()
    };
    let mut profile = vec![Value::from(loop_points(&f.shape.region.outer))];
    profile.extend(
        f.shape
            .region
            .holes
            .iter()
            .map(|h| Value::from(loop_points(h))),
    );
    let mut edges = vec![Value::from(
        f.side_adjacency
            .iter()
            .map(|a| adjacency_name(*a))
            .collect::<Vec<_>>(),
    )];
    edges.extend(
        f.hole_adjacency
            .iter()
            .map(|h| Value::from(h.iter().map(|a| adjacency_name(*a)).collect::<Vec<_>>())),
    );
    json!({
        "id": f.id.to_string(),
        "owner": f.owner.to_string(),
        "access": [r6(z.x), r6(z.y), r6(z.z)],
        "depth": [r6(base + f.shape.z_max), r6(base + f.shape.z_min)],
        "profile": profile,
        "volume": r6(feature_volume(f)),
        "adjacency": { "edges": edges, "bottom": adjacency_name(f.bottom_adjacency) },
        "rule": f.provenance.rule,
        "note": f.provenance.note,
    })
}

/// The whole contract: summary, stiffness features, connections, machining
/// features, both constraint lists and refusals.
pub fn plan_json(plan: &Plan, brep: &Brep, plan_file: &str, warnings: &[String]) -> Value {
    let kind = |k: ConstraintKind| match k {
        ConstraintKind::Before => "before",
        ConstraintKind::Simultaneous => "simultaneous",
    };
    let constraints = |first: String, then: String, k: ConstraintKind, rule: &str| json!({ "first": first, "then": then, "kind": kind(k), "rule": rule });
    let refused: Vec<Value> = plan
        .refusals
        .iter()
        .map(|r| {
            let prefix = if r.stage <= Stage::Sequence {
                "SF"
            } else {
                "MF"
            };
            let v = &r.provenance.values;
            let pair = match (v.get("first"), v.get("second")) {
                (Some(a), Some(b)) => json!([format!("{prefix}{a}"), format!("{prefix}{b}")]),
                _ => Value::Null,
            };
            json!({ "stage": r.stage, "rule": r.rule, "pair": pair, "reason": r.reason })
        })
        .collect();
    json!({
        "part": plan.part.source,
        "plan_file": plan_file,
        "stages_done": plan.stages_done,
        "solids": plan.part.summary.solids,
        "faces": plan.part.summary.faces,
        "volume": r6(plan.part.summary.volume),
        "stiffness_features": thinplan_recognise::report::features_json(&plan.stiffness_features, brep),
        "connections": thinplan_recognise::report::connections_json(&plan.connections),
        "stiffness_constraints": plan.stiffness_constraints.iter().map(|c| constraints(c.first.to_string(), c.second.to_string(), c.kind, &c.provenance.rule)).collect::<Vec<_>>(),
        "machining_features": plan.machining_features.iter().map(machining_feature_json).collect::<Vec<_>>(),
        "constraints": plan.machining_constraints.iter().map(|c| constraints(c.first.to_string(), c.second.to_string(), c.kind, &c.provenance.rule)).collect::<Vec<_>>(),
        "refused": refused,
        "operations": plan.operations.iter().map(|op| {
            let o = thinplan_operations::summary(op);
            json!({
                "id": o.id.to_string(),
                "feature": o.feature.to_string(),
                "tool": o.tool,
                "pattern": o.pattern,
                "layers": o.layers,
                "length_mm": r6(o.length_mm),
                "time_s": r6(o.time_s),
                "rule": op.provenance.rule,
            })
        }).collect::<Vec<_>>(),
        "operation_order": plan.operation_order.iter().map(|id| id.to_string()).collect::<Vec<_>>(),
        "verdict": plan.verification.as_ref().map(|v| v.verdict.name()),
        "verification": plan.verification,
        "warnings": warnings,
    })
}
