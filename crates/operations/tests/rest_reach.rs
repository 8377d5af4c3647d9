//! A notch narrower than any tool at the end of space already cut: the
//! tool reaches into it from that space as far as its radius allows,
//! keeping off the product (through the open edge's overhang, or where that
//! finds no room, `rest.rs`: the region grown into the space cut before
//! it; isogrid's R5 pocket corners take that path, see the CLI's missed
//! material allowance). If the space beside it is a feature still to come,
//! the notch stays unreachable: the tool may not overhang into that.

mod common;

use common::*;
use glam::DVec2;
use thinplan_knowledge::Knowledge;
use thinplan_operations::operations;
use thinplan_plan::{
    Adjacency, Constraint, ConstraintKind, MachiningFeatureId, Plan, Provenance, ProvenanceSource,
};

use Adjacency::{Feature, Open, Product};

/// Blank 100 × 70 × 20. Feature 0: y 0–60 (open to the air on three
/// sides). Feature 1: a notch x 45–53, y 60–70, product on three sides.
/// `first` runs first (a `Before` constraint).
fn notch_beside(first: u32) -> Plan {
    let (edge0, edge1) = if first == 0 {
        (Feature, Open)
    } else {
        (Open, Feature)
    };
    let wide = feature(
        0,
        vec![v(0.0, 0.0), v(100.0, 0.0), v(100.0, 60.0), v(0.0, 60.0)],
        vec![],
        vec![Open, Open, edge0, Open],
        Product,
        (0.0, 20.0),
    );
    let notch = feature(
        1,
        vec![v(45.0, 60.0), v(53.0, 60.0), v(53.0, 70.0), v(45.0, 70.0)],
        vec![],
        vec![edge1, Product, Product, Product],
        Product,
        (0.0, 20.0),
    );
    let mut plan = plan_with(vec![wide, notch]);
    plan.machining_constraints.push(Constraint {
        first: MachiningFeatureId(first),
        second: MachiningFeatureId(1 - first),
        kind: ConstraintKind::Before,
        priority: 0,
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    });
    with_blank(&mut plan, [0.0, 0.0, 100.0, 70.0]);
    plan
}

/// Distance from `p` to the product: the blank less both features.
fn to_product(p: DVec2) -> f64 {
    // The product beside the notch: x < 45 and x > 53 above y = 60, and
    // nothing else inside the blank (y ≤ 70 is the blank's edge).
    let left = DVec2::new((p.x - 45.0).max(0.0), (60.0 - p.y).max(0.0));
    let right = DVec2::new((53.0 - p.x).max(0.0), (60.0 - p.y).max(0.0));
    let top = (70.0 - p.y).max(0.0);
    let in_left = p.x < 45.0 && p.y > 60.0;
    let in_right = p.x > 53.0 && p.y > 60.0;
    if in_left || in_right || p.y > 70.0 {
        return 0.0;
    }
    left.length().min(right.length()).min(top)
}

#[test]
fn a_notch_narrower_than_any_tool_is_reached_from_the_space_cut_beside_it() {
    let k = Knowledge::builtin().unwrap();
    let plan = notch_beside(0);
    let ops = operations(&plan, &k).unwrap();
    let notch_ops: Vec<_> = ops.operations.iter().filter(|o| o.feature.0 == 1).collect();
    assert!(
        !notch_ops.is_empty(),
        "the notch got no operation: {:?}",
        ops.refusals
    );
    // The tool never touches the product, and reaches into the notch as far
    // as its radius allows from the mouth (x = 49: the Ø12 centre at most
    // y = 60 − √20, its edge at y = 61.5).
    let mut deepest = f64::NEG_INFINITY;
    for op in &notch_ops {
        let r = radius(&k, op);
        for (p, _, region) in walk(op, 0.05) {
            if !is_cutting(region) {
                continue;
            }
            let q = p.truncate();
            assert!(
                to_product(q) >= r - 1e-3,
                "{}: the tool at {q} is {:.4} from the product, r = {r}",
                op.id,
                to_product(q)
            );
            if (q.x - 49.0).abs() < 0.5 {
                deepest = deepest.max(q.y + r);
            }
        }
    }
    assert!(
        deepest > 61.0,
        "the tool reaches only y = {deepest:.3} into the notch (y from 60)"
    );
}

#[test]
fn a_notch_beside_a_feature_still_to_come_stays_unreachable() {
    let k = Knowledge::builtin().unwrap();
    let plan = notch_beside(1);
    let ops = operations(&plan, &k).unwrap();
    assert!(ops.operations.iter().all(|o| o.feature.0 != 1));
    assert!(ops
        .refusals
        .iter()
        .any(|r| r.rule == "operations.unreachable" && r.reason.contains("MF1")));
}
