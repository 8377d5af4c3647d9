//! Stage 7's second pass: a stretch of product wall that no operation came
//! beside gets a wall rest pass of its own, run last; a wall every stretch
//! of which was cut gets none. The stretch is made here by taking the
//! cutting moves off half of a finished wall, and the new pass is checked
//! against the wall geometry computed here.

mod common;

use common::*;
use thinplan_knowledge::Knowledge;
use thinplan_operations::{finish_orphan_stretches, operations, runs_last};
use thinplan_plan::Region3;

/// The step's wall: product along y = 30, x 0..100, the feature below it.
const WALL_Y: f64 = 30.0;

fn orphan_ops(ops: &thinplan_operations::Operations) -> Vec<&thinplan_plan::Operation> {
    ops.operations
        .iter()
        .filter(|o| o.provenance.values.get("orphan_stretches") == Some(&1.0))
        .collect()
}

#[test]
fn a_wall_stretch_no_operation_came_beside_gets_a_pass_of_its_own() {
    let k = Knowledge::builtin().unwrap();
    let plan = plan_with(vec![step(0)]);
    let mut ops = operations(&plan, &k).unwrap();
    // Every stretch of the wall was cut: no second-pass operation.
    assert!(orphan_ops(&ops).is_empty(), "{:?}", ops.warnings);
    let n0 = ops.operations.len();

    // Take every cut beyond x = 50 off (the coverage reads only cutting
    // moves; a straight move across x = 50 is split there): the wall from
    // there on is left to no one.
    const CUT_X: f64 = 50.0;
    for o in &mut ops.operations {
        let mut from = o.start;
        let mut moves = Vec::new();
        for m in &o.moves {
            let (a, b) = (from.x > CUT_X, m.to.x > CUT_X);
            if m.region != Region3::Rapid && m.arc.is_none() && a != b {
                let t = (CUT_X - from.x) / (m.to.x - from.x);
                let mut first = m.clone();
                first.to = from.lerp(m.to, t);
                let mut second = m.clone();
                if a {
                    first.region = Region3::Rapid;
                } else {
                    second.region = Region3::Rapid;
                }
                moves.push(first);
                moves.push(second);
            } else {
                let mut m = m.clone();
                if a || b {
                    m.region = Region3::Rapid;
                }
                moves.push(m);
            }
            from = m.to;
        }
        o.moves = moves;
    }
    finish_orphan_stretches(&plan, &k, &mut ops).unwrap();
    let orphans = orphan_ops(&ops);
    assert_eq!(ops.operations.len(), n0 + orphans.len());
    assert!(
        !orphans.is_empty(),
        "no pass for the orphan stretch: {:?}",
        ops.warnings
    );
    for o in &orphans {
        assert!(runs_last(o), "op {:?} does not run last", o.id);
        assert_eq!(o.feature.0, 0);
        assert!(o.provenance.note.contains("orphan stretches"));
    }
    // Its boundary moves: r from the wall (never closer), along the
    // stretch that lost its cuts, and not back along the half still cut.
    let r = radius(&k, orphans[0]);
    let mut along = Vec::new();
    for o in &orphans {
        for (p, _, region) in walk(o, 0.25) {
            if region == Region3::Rapid {
                continue;
            }
            assert!(
                WALL_Y - p.y >= r - 1e-6,
                "tool centre {p} within {r} of the wall"
            );
            if region == Region3::Boundary && (WALL_Y - p.y - r).abs() < 1e-6 {
                along.push(p.x);
            }
        }
    }
    assert!(!along.is_empty(), "no boundary move along the wall");
    let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(
        lo > 40.0,
        "the pass runs back along the cut half (from x {lo})"
    );
    // The wall from x 55 to where the step's end lets the tool reach is
    // covered by the pass: every sample within a tool radius of a pass
    // point at r from the wall.
    assert!(hi >= 100.0 - r - 0.5, "the pass stops at x {hi}");
    for i in 0..=40 {
        let x = 55.0 + (hi - 55.0) * i as f64 / 40.0;
        let near = along.iter().any(|&a| (a - x).abs() <= 0.5);
        assert!(near, "wall at x {x} not passed along");
    }
}
