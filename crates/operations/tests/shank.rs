//! The shank beside a taller machining feature that still stands: levels
//! deeper than a flute length below its top keep the tool out of it (the
//! cutter only touches it), higher levels may overhang it, and stage 8
//! runs a taller neighbour that stage 7 took as removed first.

mod common;

use common::*;
use glam::DVec2;
use thinplan_knowledge::Knowledge;
use thinplan_operations::{operations, precedence};
use thinplan_plan::{Adjacency, MachiningFeature, Plan};

use Adjacency::{Feature, Open, Product};

/// A resolved-looking plan: blank 100 × 70; product (a wall) along
/// y < 10; feature 0 from y = 10 to `split`, beside feature 1 from `split`
/// to 70, both 40 tall. Feature 1 comes later, so feature 0's edge towards
/// it is `feature`.
fn beside(split: f64) -> Plan {
    let f = feature(
        0,
        vec![v(0.0, 10.0), v(100.0, 10.0), v(100.0, split), v(0.0, split)],
        vec![],
        vec![Product, Open, Feature, Open],
        Open,
        (0.0, 40.0),
    );
    let n = feature(
        1,
        vec![v(0.0, split), v(100.0, split), v(100.0, 70.0), v(0.0, 70.0)],
        vec![],
        vec![Open, Open, Open, Open],
        Open,
        (0.0, 40.0),
    );
    let mut plan = plan_with(vec![f, n]);
    with_blank(&mut plan, [0.0, 0.0, 100.0, 70.0]);
    plan
}

fn flute(k: &Knowledge, tool: &str) -> f64 {
    k.tool_set("endmills_12_20")
        .unwrap()
        .tools
        .iter()
        .find(|t| t.id == tool)
        .unwrap()
        .flute_length
}

fn of(plan: &Plan, i: usize) -> &MachiningFeature {
    &plan.machining_features[i]
}

#[test]
fn deep_levels_keep_the_tool_out_of_a_taller_feature_that_stands() {
    let k = Knowledge::builtin().unwrap();
    let plan = beside(40.0);
    let ops = operations(&plan, &k).unwrap();
    assert!(ops.refusals.is_empty(), "{:?}", ops.refusals);
    let top = of(&plan, 1).shape.z_max;
    let (mut deep, mut overhang_above) = (0, 0);
    for op in ops.operations.iter().filter(|o| o.feature.0 == 0) {
        let r = radius(&k, op);
        let z_shank = top - flute(&k, &op.tool);
        for (p, _, region) in walk(op, 0.1) {
            if !is_cutting(region) {
                continue;
            }
            // Distance from the tool axis to feature 1 ([0, 100] × [40, 70]).
            let dx = (0.0 - p.x).max(p.x - 100.0).max(0.0);
            let dy = (40.0 - p.y).max(p.y - 70.0).max(0.0);
            let room = if p.y >= 40.0 && dx == 0.0 {
                0.0
            } else {
                dx.hypot(dy)
            };
            // 1e-3: contact, as in the holder and shank check.
            if p.z < z_shank - 1e-3 {
                deep += 1;
                assert!(
                    room >= r - 1e-3,
                    "{}: at {p} z {:.3} (shank from {:.3}) the axis is {room:.4} from the \
                     standing feature, r = {r}",
                    op.id,
                    p.z,
                    p.z + flute(&k, &op.tool)
                );
            } else if room < r - 0.5 {
                overhang_above += 1;
            }
        }
    }
    assert!(deep > 0, "no cutting move below the shank height");
    // Above that height the overhang onto the later feature is still used:
    // the limit applies only where the shank would be in material.
    assert!(overhang_above > 0, "the overhang vanished at every level");
    // The deep band says why, with the feature and the flute length.
    let notes = ops
        .operations
        .iter()
        .filter(|o| o.feature.0 == 0)
        .filter(|o| o.provenance.note.contains("shank_clear_of=MF1"))
        .count();
    assert!(notes > 0, "no operation records its shank clearance");
    // Floor coverage: every point of feature 0 at its floor within r of a
    // cutting move there.
    let f = of(&plan, 0);
    let mut pts = Vec::new();
    let mut r = f64::INFINITY;
    // The floor passes: at the floor, or below it where a through feature
    // is cut free (`methods.breakthrough`).
    let through = f.bottom_adjacency == thinplan_plan::Adjacency::Open;
    for op in ops.operations.iter().filter(|o| o.feature.0 == 0) {
        r = r.min(radius(&k, op));
        let lowest = walk(op, 0.1)
            .iter()
            .filter(|(_, _, region)| is_cutting(*region))
            .map(|(p, _, _)| p.z)
            .fold(f64::INFINITY, f64::min);
        let floor = if through { lowest } else { f.shape.z_min };
        for (p, _, region) in walk(op, 0.1) {
            if is_cutting(region) && (p.z - floor).abs() < 1e-9 {
                pts.push(p.truncate());
            }
        }
    }
    let polys = region_polys(f);
    let mut y = 10.25;
    while y < 40.0 {
        let mut x = 0.25;
        while x < 100.0 {
            let q = DVec2::new(x, y);
            if inside(q, &polys) {
                let d = pts
                    .iter()
                    .map(|p| p.distance(q))
                    .fold(f64::INFINITY, f64::min);
                assert!(d <= r + 0.1, "floor point {q} is {d} from the floor passes");
            }
            x += 1.0;
        }
        y += 1.0;
    }
}

/// A step narrower than the tools beside a taller feature that stands: its
/// deep levels keep the shank out of the neighbour even though they then
/// reach less of the step (a shank in standing material is a collision the
/// verification would take the whole operation out for) and say what they
/// leave; the operations after it (the neighbour's, open towards it, and
/// stage 7's second pass along the product wall) still cut the whole floor.
#[test]
fn a_step_narrower_than_the_tool_keeps_the_shank_out_and_leaves_the_rest_to_later_operations() {
    let k = Knowledge::builtin().unwrap();
    // 11 mm wide: no Ø12 or Ø20 fits between the wall and feature 1.
    let plan = beside(21.0);
    let ops = operations(&plan, &k).unwrap();
    assert!(ops.refusals.is_empty(), "{:?}", ops.refusals);
    assert!(
        ops.warnings.iter().any(|w| w.starts_with("MF0:")
            && w.contains("keep the shank out of MF1")
            && w.contains("left to the features cut after it")),
        "{:?}",
        ops.warnings
    );
    // The band's own passes: over the blank (0 ≤ x ≤ 100) their floor
    // discs stay out of feature 1.
    let band: Vec<_> = ops
        .operations
        .iter()
        .filter(|o| o.feature.0 == 0 && o.provenance.values.contains_key("shank_band_lost_mm2"))
        .collect();
    assert!(!band.is_empty(), "the band's loss is recorded");
    for o in band {
        let r = radius(&k, o);
        for (p, _, reg) in walk(o, 0.1) {
            if is_cutting(reg) && p.z < 1e-6 && (0.0..=100.0).contains(&p.x) {
                assert!(
                    p.y + r <= 21.0 + 0.1,
                    "{}: disc at {p} reaches into MF1",
                    o.id
                );
            }
        }
    }
    // Every point of the step's floor is under some operation's floor pass.
    let floor: Vec<(DVec2, f64)> = ops
        .operations
        .iter()
        .flat_map(|o| {
            let r = radius(&k, o);
            walk(o, 0.1)
                .into_iter()
                .filter(|(p, _, reg)| is_cutting(*reg) && p.z < 1e-6)
                .map(move |(p, _, _)| (p.truncate(), r))
        })
        .collect();
    let mut y = 10.25;
    while y < 21.0 {
        let mut x = 0.25;
        while x < 100.0 {
            let q = DVec2::new(x, y);
            assert!(
                floor.iter().any(|(p, r)| p.distance(q) <= r + 0.1),
                "floor point {q} of the step is cut by no operation"
            );
            x += 1.0;
        }
        y += 1.0;
    }
}

#[test]
fn stage_8_runs_a_taller_earlier_neighbour_first() {
    let k = Knowledge::builtin().unwrap();
    let plan = beside(40.0);
    // Feature 0 comes first in the machining order, and stands 40 mm over
    // feature 1's floor: feature 1 is cut after it, whatever the tools.
    let edges = precedence::shank_edges(&plan, 20.0, 14.0);
    assert_eq!(
        edges,
        vec![(of(&plan, 0).id, of(&plan, 1).id)],
        "one edge, from the earlier to the later feature"
    );
    // A lower neighbour (top within a flute of the floor) gets none.
    let mut low = plan.clone();
    low.machining_features[0].shape.z_max = 10.0;
    assert!(precedence::shank_edges(&low, 20.0, 14.0).is_empty());
    let ops = operations(&plan, &k).unwrap();
    let mut p = plan.clone();
    ops.apply_to(&mut p);
    let order = thinplan_operations::order(&p, &k).unwrap();
    let feature_at = |id| p.operations.iter().find(|o| o.id == id).unwrap().feature;
    let last_0 = order.iter().rposition(|id| feature_at(*id).0 == 0).unwrap();
    let first_1 = order.iter().position(|id| feature_at(*id).0 == 1).unwrap();
    assert!(last_0 < first_1, "{order:?}");
}
