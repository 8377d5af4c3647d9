//! Stage 8 on random constraint graphs: every constraint honoured,
//! simultaneous groups contiguous, no avoidable tool change, deterministic.

mod common;

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use proptest::prelude::*;
use thinplan_operations::order::order_unchecked;
use thinplan_plan::*;

fn op(id: u32, feature: u32, tool: &str, x: f64) -> Operation {
    Operation {
        id: OperationId(id),
        feature: MachiningFeatureId(feature),
        method: "m".into(),
        tool: tool.into(),
        tool_axis: DVec3::Z,
        spindle_rpm: 1.0,
        start: DVec3::new(x, 0.0, 0.0),
        moves: vec![],
        schedule: Schedule::WithFeature,
        provenance: Provenance::new(ProvenanceSource::Default, "t"),
        link_z: None,
    }
}

fn constraint(a: u32, b: u32, kind: ConstraintKind) -> Constraint<MachiningFeatureId> {
    Constraint {
        first: MachiningFeatureId(a),
        second: MachiningFeatureId(b),
        kind,
        priority: 0,
        provenance: Provenance::new(ProvenanceSource::Default, "t"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn order_honours_constraints_and_groups_tools(
        n in 1usize..12,
        edges in proptest::collection::vec((0u32..12, 0u32..12, 0u8..10), 0..30),
        tools in proptest::collection::vec(0u8..3, 12),
        two_ops in proptest::collection::vec(any::<bool>(), 12),
    ) {
        let mut plan = common::plan_with(vec![]);
        let mut id = 0;
        for f in 0..n as u32 {
            let t = format!("T{}", tools[f as usize]);
            plan.operations.push(op(id, f, &t, f as f64 * 10.0));
            id += 1;
            if two_ops[f as usize] {
                plan.operations.push(op(id, f, &t, f as f64 * 10.0 + 1.0));
                id += 1;
            }
        }
        // A DAG: edges only from lower to higher feature ids; some simultaneous
        // pairs between features that no Before path joins (adjacent ids, no
        // Before edge touching either).
        let mut before = BTreeSet::new();
        for (a, b, k) in &edges {
            let (a, b) = (*a % n as u32, *b % n as u32);
            if a < b && *k < 8 {
                before.insert((a, b));
            }
        }
        for (a, b) in &before {
            plan.machining_constraints.push(constraint(*a, *b, ConstraintKind::Before));
        }
        let touched: BTreeSet<u32> = before.iter().flat_map(|(a, b)| [*a, *b]).collect();
        for (a, _, k) in &edges {
            let a = *a % n as u32;
            if *k >= 8 && a + 1 < n as u32 && !touched.contains(&a) && !touched.contains(&(a + 1)) {
                plan.machining_constraints.push(constraint(a, a + 1, ConstraintKind::Simultaneous));
            }
        }
        let order = order_unchecked(&plan).unwrap();
        let again = order_unchecked(&plan).unwrap();
        prop_assert_eq!(&order, &again);
        // A permutation of all operations.
        let all: BTreeSet<_> = plan.operations.iter().map(|o| o.id).collect();
        prop_assert_eq!(order.len(), all.len());
        prop_assert_eq!(order.iter().copied().collect::<BTreeSet<_>>(), all);
        let by_id: BTreeMap<_, _> = plan.operations.iter().map(|o| (o.id, o)).collect();
        let pos: BTreeMap<_, _> = order.iter().enumerate().map(|(i, id)| (*id, i)).collect();
        let ops_of = |f: MachiningFeatureId| -> Vec<usize> {
            plan.operations.iter().filter(|o| o.feature == f).map(|o| pos[&o.id]).collect()
        };
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(p: &mut [u32], x: u32) -> u32 {
            let mut r = x;
            while p[r as usize] != r {
                r = p[r as usize];
            }
            r
        }
        for c in &plan.machining_constraints {
            if c.kind == ConstraintKind::Simultaneous {
                let (x, y) = (root(&mut parent, c.first.0), root(&mut parent, c.second.0));
                parent[x as usize] = y;
            }
        }
        let comp = |f: u32| root(&mut parent.clone(), f);
        for c in &plan.machining_constraints {
            let (a, b) = (ops_of(c.first), ops_of(c.second));
            match c.kind {
                ConstraintKind::Before => {
                    prop_assert!(a.iter().max() < b.iter().min(), "before violated: {:?}", c);
                }
                ConstraintKind::Simultaneous => {
                    // Everything between them belongs to their simultaneous
                    // group (the transitive closure of the pairs).
                    let lo = *a.iter().chain(&b).min().unwrap();
                    let hi = *a.iter().chain(&b).max().unwrap();
                    let g = comp(c.first.0);
                    for id in &order[lo..=hi] {
                        prop_assert_eq!(comp(by_id[id].feature.0), g);
                    }
                }
            }
        }
        // Within a feature, stage 7's order is kept.
        for f in 0..n as u32 {
            let v = ops_of(MachiningFeatureId(f));
            prop_assert!(v.windows(2).all(|w| w[0] < w[1]));
        }
        // No avoidable tool change: when the tool changes at a feature
        // without simultaneous partners, no ready feature had the old tool.
        let simult: BTreeSet<u32> = plan
            .machining_constraints
            .iter()
            .filter(|c| c.kind == ConstraintKind::Simultaneous)
            .flat_map(|c| [c.first.0, c.second.0])
            .collect();
        if simult.is_empty() {
            let mut done: BTreeSet<u32> = BTreeSet::new();
            let mut prev_tool: Option<String> = None;
            for id in &order {
                let o = by_id[id];
                let f = o.feature.0;
                if done.contains(&f) {
                    continue;
                }
                if let Some(t) = &prev_tool {
                    if *t != o.tool {
                        for g in 0..n as u32 {
                            let ready = !done.contains(&g)
                                && before.iter().filter(|(_, b)| *b == g).all(|(a, _)| done.contains(a));
                            let tool_g = &plan.operations.iter().find(|x| x.feature.0 == g).unwrap().tool;
                            prop_assert!(!(ready && tool_g == t), "feature {} with {} was ready", g, t);
                        }
                    }
                }
                done.insert(f);
                prev_tool = Some(plan.operations.iter().rfind(|x| x.feature.0 == f).unwrap().tool.clone());
            }
        }
    }
}

#[test]
fn a_cycle_is_an_error_not_a_panic() {
    let mut plan = common::plan_with(vec![]);
    plan.operations.push(op(0, 0, "T", 0.0));
    plan.operations.push(op(1, 1, "T", 0.0));
    plan.machining_constraints
        .push(constraint(0, 1, ConstraintKind::Before));
    plan.machining_constraints
        .push(constraint(1, 0, ConstraintKind::Before));
    assert!(order_unchecked(&plan).is_err());
}

/// A wall rest pass of an upper slab runs before the slab below it starts
/// (that tool's shank passes up through the corners still to be cut); one
/// of a slab beside no lower feature, and one planned with every other
/// feature gone (orphan stretches), still run at the end.
#[test]
fn rest_passes_run_before_the_features_below_them() {
    use Adjacency::{Feature, Open, Product};
    let slab = |id: u32, x0: f64, z: (f64, f64)| {
        common::feature(
            id,
            vec![
                common::v(x0, 0.0),
                common::v(x0 + 50.0, 0.0),
                common::v(x0 + 50.0, 30.0),
                common::v(x0, 30.0),
            ],
            vec![],
            vec![Open, Open, Product, Open],
            Feature,
            z,
        )
    };
    // 0 above 1 (same plan box); 2 far away at the height of 1
    let mut plan = common::plan_with(vec![
        slab(0, 0.0, (10.0, 20.0)),
        slab(1, 0.0, (0.0, 10.0)),
        slab(2, 500.0, (10.0, 20.0)),
    ]);
    plan.operations.push(op(0, 0, "A", 0.0));
    plan.operations.push(op(1, 1, "A", 0.0));
    plan.operations.push(op(2, 2, "A", 500.0));
    let rest = |id: u32, feature: u32, orphan: bool| {
        let mut o = op(id, feature, "B", 0.0);
        o.schedule = if orphan {
            Schedule::AtEnd {
                covered_within_mm: None,
            }
        } else {
            Schedule::AfterFeature
        };
        o
    };
    plan.operations.push(rest(3, 0, false));
    plan.operations.push(rest(4, 0, true));
    plan.operations.push(rest(5, 2, false));
    plan.machining_constraints
        .push(constraint(0, 1, ConstraintKind::Before));
    let order = order_unchecked(&plan).unwrap();
    let at = |id: u32| order.iter().position(|o| o.0 == id).unwrap();
    assert!(at(0) < at(3) && at(3) < at(1), "{order:?}");
    assert!(at(4) > at(1) && at(4) > at(2), "{order:?}");
    assert!(at(5) > at(1) && at(5) > at(2), "{order:?}");
}

#[test]
fn a_features_passes_run_larger_tools_first_whatever_their_names() {
    use Adjacency::{Feature, Open, Product};
    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let mut plan = common::plan_with(vec![common::feature(
        0,
        vec![
            common::v(0.0, 0.0),
            common::v(50.0, 0.0),
            common::v(50.0, 30.0),
            common::v(0.0, 30.0),
        ],
        vec![],
        vec![Open, Open, Product, Open],
        Feature,
        (0.0, 10.0),
    )]);
    plan.setup.tool_set = "alu_hsm".into();
    plan.stages_done.push(Stage::Operations);
    // Stage 7's order: the feature's tool, a wall rest with it, then rest
    // passes after it, each with a smaller tool than the last. By name
    // "em10_r1" < "em12_r1" < "em16_r1" < "em20_r1".
    plan.operations.push(op(0, 0, "em20_r1", 0.0));
    plan.operations.push(op(1, 0, "em10_r1", 0.0));
    for (id, tool) in [(2, "em16_r1"), (3, "em12_r1"), (4, "em10_r1")] {
        let mut o = op(id, 0, tool, 0.0);
        o.schedule = Schedule::AfterFeature;
        plan.operations.push(o);
    }
    let order = thinplan_operations::order(&plan, &k).unwrap();
    let ids: Vec<u32> = order.iter().map(|o| o.0).collect();
    assert_eq!(ids, vec![0, 1, 2, 3, 4]);
}
