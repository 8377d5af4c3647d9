//! Properties on random feature sets and random rule priorities: the
//! before-graph with simultaneous groups contracted stays acyclic, `order`
//! honours every constraint, refusals are justified, and the result does not
//! depend on input order.

mod common;

use std::collections::BTreeMap;

use common::*;
use glam::DVec3;
use petgraph::algo::{has_path_connecting, is_cyclic_directed};
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::unionfind::UnionFind;
use proptest::prelude::*;
use thinplan_knowledge::SequencingKnowledge;
use thinplan_plan::*;
use thinplan_sequence::{order, sequence, Sequencing};

const KINDS: [StiffnessKind; 9] = [
    StiffnessKind::Wall,
    StiffnessKind::Hole,
    StiffnessKind::Cutout,
    StiffnessKind::Slot,
    StiffnessKind::Notch,
    StiffnessKind::Pocket,
    StiffnessKind::Step,
    StiffnessKind::Chamfer,
    StiffnessKind::Fillet,
];
const ROLES: [WallRole; 3] = [WallRole::Web, WallRole::Rib, WallRole::Flange];
const AXES: [DVec3; 4] = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(1.0, 0.0, 1.0)];

#[derive(Debug, Clone)]
struct Gen {
    kind: usize,
    role: usize,
    axis: usize,
    /// Bottom and height along z, or no shape.
    level: Option<(u8, u8)>,
}

fn feature(i: usize, g: &Gen) -> StiffnessFeature {
    let kind = if g.kind < 5 {
        KINDS[0]
    } else {
        KINDS[g.kind - 4]
    };
    let axis = AXES[g.axis];
    let x = if axis.cross(DVec3::X).length() > 0.5 {
        DVec3::X
    } else {
        DVec3::Y
    };
    let mut f = depression(i as u32 + 1, kind, DVec3::ZERO, axis, x, 10.0, 10.0, 2.0);
    if kind == StiffnessKind::Wall {
        f.role = Some(ROLES[g.role]);
    }
    // A box over [bottom, bottom + height] along z, whatever the axis.
    f.shape = g.level.map(|(b, h)| Prism {
        frame: PrismFrame {
            origin: DVec3::new(0.0, 0.0, f64::from(b)),
            x: DVec3::X,
            z: DVec3::Z,
        },
        region: Region {
            outer: ProfileLoop {
                vertices: [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
                    .map(|(x, y)| ProfileVertex { x, y, bulge: 0.0 })
                    .to_vec(),
            },
            holes: vec![],
        },
        z_min: 0.0,
        z_max: f64::from(h) + 1.0,
    });
    f
}

fn gen_feature() -> impl Strategy<Value = Gen> {
    (
        0usize..13,
        0usize..3,
        0usize..4,
        prop::option::weighted(0.85, (0u8..100, 0u8..60)),
    )
        .prop_map(|(kind, role, axis, level)| Gen {
            kind,
            role,
            axis,
            level,
        })
}

/// The thesis's rules plus three that fight them, priorities given.
fn rule_set(p: &[i32]) -> SequencingKnowledge {
    // The repository's five rules (priorities 50, 40, 30, 20, 10) get p[0..5].
    let mut text = repo_sequencing_text();
    for old in [50, 40, 30, 20, 10] {
        text = text.replace(&format!("priority: {old},"), &format!("priority: P{old},"));
    }
    for (i, old) in [50, 40, 30, 20, 10].iter().enumerate() {
        text = text.replace(
            &format!("priority: P{old},"),
            &format!("priority: {},", p[i]),
        );
    }
    let extra = format!(
        r#"
        (id: "lower_first", priority: {},
         when: Not(Higher(level: Middle, by_more_than: 0.0)), then: Before),
        (id: "crossing_together", priority: {},
         when: Related(Crossing), then: Simultaneous),
        (id: "leaf_first", priority: {},
         when: Related(FirstOnSecond), then: BeforeUnless(SecondHasLeavesBefore(leaf: Any, at_least: 3))),
    ],"#,
        p[5], p[6], p[7]
    );
    let at = text.rfind("],").unwrap();
    text.replace_range(at..at + 2, &extra);
    rules(&text)
}

fn ids_of(features: &[StiffnessFeature]) -> Vec<StiffnessFeatureId> {
    let mut v: Vec<_> = features.iter().map(|f| f.id).collect();
    v.sort();
    v
}

/// Independent check of a sequencing: groups from the constraints, the
/// contracted before-graph acyclic, refusals justified, order honoured.
fn check(features: &[StiffnessFeature], s: &Sequencing) -> Result<(), TestCaseError> {
    let ids = ids_of(features);
    let index: BTreeMap<StiffnessFeatureId, usize> =
        ids.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    let mut uf = UnionFind::<usize>::new(ids.len());
    for c in &s.constraints {
        if c.kind == ConstraintKind::Simultaneous {
            uf.union(index[&c.first], index[&c.second]);
        }
    }
    // The reported groups are exactly the union-find's classes of size > 1.
    let mut classes: BTreeMap<usize, Vec<StiffnessFeatureId>> = BTreeMap::new();
    for (i, id) in ids.iter().enumerate() {
        classes.entry(uf.find(i)).or_default().push(*id);
    }
    let mut groups: Vec<_> = classes.into_values().filter(|g| g.len() > 1).collect();
    groups.sort();
    prop_assert_eq!(&groups, &s.groups);

    let mut g: DiGraph<(), ()> = DiGraph::new();
    let nodes: Vec<NodeIndex> = (0..ids.len()).map(|_| g.add_node(())).collect();
    let node = |id: &StiffnessFeatureId| nodes[uf.find(index[id])];
    for c in &s.constraints {
        prop_assert!(c.provenance.rule.starts_with("sequencing."));
        prop_assert!(c.provenance.values.contains_key("priority"));
        if c.kind == ConstraintKind::Before {
            prop_assert!(
                node(&c.first) != node(&c.second),
                "before within a group: {:?}",
                c
            );
            g.add_edge(node(&c.first), node(&c.second), ());
        }
    }
    prop_assert!(!is_cyclic_directed(&g), "cycle in {:#?}", s.constraints);

    // Each refusal for a cycle or an order is still justified now.
    for r in &s.refusals {
        prop_assert_eq!(r.stage, Stage::Sequence);
        let first = StiffnessFeatureId(r.provenance.values["first"] as u32);
        let second = StiffnessFeatureId(r.provenance.values["second"] as u32);
        let (a, b) = (node(&first), node(&second));
        if r.reason.contains("unless-condition") {
            continue;
        }
        let before = format!("{first} before {second}");
        let together = format!("{first} simultaneous with {second}");
        if r.reason.starts_with(&before) {
            prop_assert!(
                a == b || has_path_connecting(&g, b, a, None),
                "{}",
                r.reason
            );
        } else {
            prop_assert!(r.reason.starts_with(&together), "{}", r.reason);
            prop_assert!(
                a != b
                    && (has_path_connecting(&g, a, b, None) || has_path_connecting(&g, b, a, None)),
                "{}",
                r.reason
            );
        }
    }

    // The order: a permutation honouring every constraint, groups together.
    let o = order(features, s);
    let mut sorted = o.clone();
    sorted.sort();
    prop_assert_eq!(&sorted, &ids);
    let pos: BTreeMap<StiffnessFeatureId, usize> =
        o.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    for c in &s.constraints {
        if c.kind == ConstraintKind::Before {
            prop_assert!(pos[&c.first] < pos[&c.second], "{:?} in {:?}", c, o);
        }
    }
    for group in &s.groups {
        let mut p: Vec<usize> = group.iter().map(|id| pos[id]).collect();
        p.sort();
        prop_assert_eq!(
            p[p.len() - 1] - p[0],
            p.len() - 1,
            "group {:?} split in {:?}",
            group,
            o
        );
    }
    Ok(())
}

fn shuffled<T: Clone>(v: &[T], seed: u64) -> Vec<T> {
    let mut v = v.to_vec();
    let mut x = seed | 1;
    for i in (1..v.len()).rev() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        v.swap(i, (x % (i as u64 + 1)) as usize);
    }
    v
}

/// Features, connections (base, leaf, base–leaf?), rule priorities, a seed.
type Case = (Vec<Gen>, Vec<(usize, usize, bool)>, Vec<i32>, u64);

fn case() -> impl Strategy<Value = Case> {
    prop::collection::vec(gen_feature(), 2..14).prop_flat_map(|fs| {
        let n = fs.len();
        (
            Just(fs),
            prop::collection::vec((0..n, 0..n, prop::bool::weighted(0.8)), 0..(2 * n)),
            Just((1..=8).map(|p| p * 10).collect::<Vec<i32>>()).prop_shuffle(),
            any::<u64>(),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn constraints_stay_acyclic_and_order_honours_them((gens, links, priorities, seed) in case()) {
        let features: Vec<StiffnessFeature> =
            gens.iter().enumerate().map(|(i, g)| feature(i, g)).collect();
        let connections: Vec<Connection> = links
            .iter()
            .filter(|(b, l, _)| b != l)
            .map(|&(b, l, base_leaf)| Connection {
                base: features[b].id,
                leaf: features[l].id,
                kind: if base_leaf { ConnectionKind::BaseLeaf } else { ConnectionKind::Crossing },
                provenance: Provenance::new(ProvenanceSource::User, "test"),
            })
            .collect();
        let k = rule_set(&priorities);
        let s = sequence(&features, &connections, UP, &k);
        check(&features, &s)?;

        // Same input, any order: the same result, byte for byte.
        let mut k2 = k.clone();
        k2.rules = shuffled(&k.rules, seed ^ 0x9e37);
        let s2 = sequence(
            &shuffled(&features, seed),
            &shuffled(&connections, seed.rotate_left(17)),
            UP,
            &k2,
        );
        prop_assert_eq!(&s, &s2);
        prop_assert_eq!(ron::to_string(&s).unwrap(), ron::to_string(&s2).unwrap());
        prop_assert_eq!(order(&features, &s), order(&shuffled(&features, seed), &s2));
    }
}

#[test]
fn the_same_part_gives_identical_bytes_every_time() {
    let (features, connections) = thesis_part();
    let k = repo_rules();
    let first = ron::to_string(&sequence(&features, &connections, UP, &k)).unwrap();
    for seed in 1..20u64 {
        let s = sequence(
            &shuffled(&features, seed),
            &shuffled(&connections, seed * 7),
            UP,
            &k,
        );
        assert_eq!(ron::to_string(&s).unwrap(), first);
    }
}

#[test]
fn a_large_part_is_sequenced_quickly() {
    // 200 walls (a grid of ribs on webs at 20 levels) and 200 holes.
    let mut features = Vec::new();
    let mut connections = Vec::new();
    for i in 0..200u32 {
        let level = f64::from(i % 20) * 5.0;
        let g = Gen {
            kind: 0,
            role: (i % 3) as usize,
            axis: (i % 3) as usize,
            level: None,
        };
        let mut f = feature(i as usize, &g);
        f.shape = feature(
            i as usize,
            &Gen {
                level: Some((level as u8, 10)),
                ..g
            },
        )
        .shape;
        features.push(f);
        if i >= 20 {
            connections.push(base_leaf(i - 19, i + 1));
        }
    }
    for i in 0..200u32 {
        let mut h = hole(
            201 + i,
            DVec3::new(0.0, 0.0, f64::from(i % 50)),
            DVec3::X,
            DVec3::Y,
            4.0,
            2.0,
        );
        h.axis = DVec3::X;
        features.push(h);
        connections.push(base_leaf(i + 1, 201 + i));
    }
    let t = std::time::Instant::now();
    let s = sequence(&features, &connections, UP, &repo_rules());
    let took = t.elapsed();
    check(&features, &s).unwrap();
    eprintln!(
        "400 features: {} constraints, {} refusals in {:?}",
        s.constraints.len(),
        s.refusals.len(),
        took
    );
    // Speed is a benchmark, not a test assertion (docs/BENCHMARKS.md).
}
