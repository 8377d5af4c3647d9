//! The `Details` block (thesis figure 4.10) on the chamfered rib: the
//! chamfer's own machining feature (its wedge) right after the wall step
//! that exposes it, or before all of the wall's features when large.
//! Heights are measured from the features' prisms, not their provenance.

mod common;

use std::collections::{BTreeMap, BTreeSet};

use thinplan_determine::{prism_points, Determination};
use thinplan_knowledge::{Block, Knowledge};
use thinplan_plan::{MachiningFeature, MachiningFeatureId, Plan, StiffnessKind, WallRole};

fn planned(k: &Knowledge) -> (Plan, Determination) {
    let (plan, _, d) = common::planned("chamfered_rib", k);
    (plan, d)
}

fn v(f: &MachiningFeature, name: &str) -> f64 {
    *f.provenance
        .values
        .get(name)
        .unwrap_or_else(|| panic!("{} has no `{name}`: {:?}", f.id, f.provenance))
}

fn z_span(f: &MachiningFeature) -> (f64, f64) {
    prism_points(&f.shape)
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.z), hi.max(p.z))
        })
}

/// `a` is machined before `b`: a path of `Before` constraints.
fn precedes(d: &Determination, a: MachiningFeatureId, b: MachiningFeatureId) -> bool {
    let mut succ: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
    for c in &d.constraints {
        succ.entry(c.first).or_default().push(c.second);
    }
    let mut seen = BTreeSet::new();
    let mut stack = vec![a];
    while let Some(x) = stack.pop() {
        for &y in succ.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
            if y == b {
                return true;
            }
            if seen.insert(y) {
                stack.push(y);
            }
        }
    }
    false
}

/// The chamfer's one feature and the rib's step features in their order.
fn chamfer_and_steps(plan: &Plan, d: &Determination) -> (MachiningFeature, Vec<MachiningFeature>) {
    let ch: Vec<_> = plan
        .stiffness_features
        .iter()
        .filter(|f| f.kind == StiffnessKind::Chamfer)
        .collect();
    assert_eq!(ch.len(), 1);
    let rib = plan
        .stiffness_features
        .iter()
        .find(|f| f.role == Some(WallRole::Rib))
        .unwrap();
    let mine: Vec<_> = d.features.iter().filter(|f| f.owner == ch[0].id).collect();
    assert_eq!(mine.len(), 1, "one machining feature owned by the chamfer");
    let mut steps: Vec<MachiningFeature> = d
        .features
        .iter()
        .filter(|f| f.owner == rib.id && f.provenance.rule == "strategies.wall_steps")
        .cloned()
        .collect();
    assert!(steps.len() > 2);
    // The wall's own chain: sort by precedence (a total order on a chain).
    steps.sort_by(|a, b| {
        if precedes(d, a.id, b.id) {
            std::cmp::Ordering::Less
        } else {
            std::cmp::Ordering::Greater
        }
    });
    for w in steps.windows(2) {
        assert!(
            precedes(d, w[0].id, w[1].id),
            "the rib's steps form a chain"
        );
    }
    (mine[0].clone(), steps)
}

#[test]
fn the_chamfer_comes_right_after_the_step_that_exposes_it() {
    let k = Knowledge::builtin().unwrap();
    let (plan, d) = planned(&k);
    let (ch, steps) = chamfer_and_steps(&plan, &d);
    assert_eq!(ch.provenance.rule, "strategies.details");
    // The wedge: z 74–92 (the part's 18 mm chamfer below the 92 mm top).
    let (lo, hi) = z_span(&ch);
    assert!(
        (lo - 74.0).abs() < 1e-6 && (hi - 92.0).abs() < 1e-6,
        "{lo} {hi}"
    );
    assert_eq!(v(&ch, "large"), 0.0);
    assert!((v(&ch, "detail_height") - 18.0).abs() < 1e-6);
    // H = 36 for the 120 × 1.5 × 72 rib: the threshold 1.0 · H.
    assert!((v(&ch, "large_above") - v(&ch, "big_h")).abs() < 1e-9);
    // The step that exposes it: the first in the chain reaching down to
    // the wedge's bottom (measured from the prisms).
    let i = steps
        .iter()
        .position(|s| z_span(s).0 <= lo + 1e-6)
        .expect("a step exposes the chamfer");
    assert_eq!(i, 0, "A1 (H = 36 > 18) exposes it");
    assert!(precedes(&d, steps[i].id, ch.id), "after the exposing step");
    assert!(precedes(&d, ch.id, steps[i + 1].id), "before the next step");
    // Nothing in between: only the exposing step and those before it
    // precede the chamfer.
    for (j, s) in steps.iter().enumerate() {
        assert_eq!(precedes(&d, s.id, ch.id), j <= i, "{}", s.id);
    }
    // Provenance and the constraints' notes explain it.
    assert!(
        ch.provenance.note.contains("as soon as exposed"),
        "{}",
        ch.provenance.note
    );
    let rules: BTreeSet<_> = d
        .constraints
        .iter()
        .filter(|c| c.first == ch.id || c.second == ch.id)
        .map(|c| c.provenance.rule.as_str())
        .collect();
    assert_eq!(rules, BTreeSet::from(["strategies.details"]));
}

fn set_threshold(k: &mut Knowledge, to: f64) {
    for s in &mut k.strategies.strategies {
        for b in &mut s.blocks {
            if let Block::Details(x) = b {
                x.large_above_big_h = to;
            }
        }
    }
}

#[test]
fn a_large_chamfer_goes_before_all_of_the_walls_features() {
    let mut k = Knowledge::builtin().unwrap();
    // 0.25 · H = 9 mm < 18 mm: the chamfer is large.
    set_threshold(&mut k, 0.25);
    let (plan, d) = planned(&k);
    let (ch, steps) = chamfer_and_steps(&plan, &d);
    assert_eq!(v(&ch, "large"), 1.0);
    assert!((v(&ch, "large_above") - 9.0).abs() < 1e-9);
    for s in &steps {
        assert!(precedes(&d, ch.id, s.id), "{} before {}", ch.id, s.id);
        assert!(!precedes(&d, s.id, ch.id));
    }
    assert!(
        ch.provenance.note.contains("before all"),
        "{}",
        ch.provenance.note
    );
    // Exactly at the threshold it is not large (taller than, not as tall as).
    set_threshold(&mut k, 0.5);
    let (plan, d) = planned(&k);
    let (ch, steps) = chamfer_and_steps(&plan, &d);
    assert_eq!(v(&ch, "large"), 0.0);
    assert!(precedes(&d, steps[0].id, ch.id));
}

#[test]
fn without_the_block_the_chamfer_gets_no_feature_here() {
    let mut k = Knowledge::builtin().unwrap();
    for s in &mut k.strategies.strategies {
        s.blocks.retain(|b| !matches!(b, Block::Details(_)));
    }
    let (plan, d) = planned(&k);
    let ch = plan
        .stiffness_features
        .iter()
        .find(|f| f.kind == StiffnessKind::Chamfer)
        .unwrap();
    assert!(d.features.iter().all(|f| f.owner != ch.id));
}

#[test]
fn details_after_the_steps_or_with_a_bad_threshold_are_refused() {
    let k = Knowledge::builtin().unwrap();
    assert!(k.strategies.problems().is_empty());
    let mut s = k.strategies.clone();
    let blocks = &mut s.strategies[0].blocks;
    let i = blocks
        .iter()
        .position(|b| matches!(b, Block::Details(_)))
        .expect("a Details block in the standing-wall strategy");
    let steps = blocks
        .iter()
        .position(|b| matches!(b, Block::WallSteps(_)))
        .unwrap();
    assert!(i < steps, "read before the wall steps");
    let mut b = blocks.remove(i);
    if let Block::Details(x) = &mut b {
        x.large_above_big_h = 0.0;
    }
    blocks.push(b);
    let p = s.problems();
    assert!(
        p.iter()
            .any(|m| m.contains("`details` comes after the wall steps")),
        "{p:?}"
    );
    assert!(p.iter().any(|m| m.contains("large_above_big_h 0")), "{p:?}");
}
