//! Independent checks of stage 5 on the appendix A wall and every sample.

mod common;

use std::collections::BTreeMap;

use glam::DVec3;
use thinplan_determine::Determination;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{ConstraintKind, MachiningFeature, MachiningFeatureId, Plan, Stage, WallRole};

fn planned(name: &str, k: &Knowledge) -> (Plan, Determination) {
    let (plan, _, d) = common::planned(name, k);
    (plan, d)
}

fn value(f: &MachiningFeature, name: &str) -> f64 {
    f.provenance.values[name]
}

/// A topological order by my own Kahn's algorithm; panics on a cycle.
fn topo(d: &Determination) -> Vec<MachiningFeatureId> {
    let mut indeg: BTreeMap<MachiningFeatureId, usize> =
        d.features.iter().map(|f| (f.id, 0)).collect();
    let mut succ: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
    for c in &d.constraints {
        assert_eq!(c.kind, ConstraintKind::Before);
        assert!(indeg.contains_key(&c.first) && indeg.contains_key(&c.second));
        *indeg.get_mut(&c.second).unwrap() += 1;
        succ.entry(c.first).or_default().push(c.second);
    }
    let mut ready: Vec<_> = indeg
        .iter()
        .filter(|(_, n)| **n == 0)
        .map(|(i, _)| *i)
        .collect();
    let mut order = Vec::new();
    while let Some(i) = ready.pop() {
        order.push(i);
        for s in succ.get(&i).cloned().unwrap_or_default() {
            let n = indeg.get_mut(&s).unwrap();
            *n -= 1;
            if *n == 0 {
                ready.push(s);
            }
        }
    }
    assert_eq!(
        order.len(),
        d.features.len(),
        "the constraint graph has a cycle"
    );
    order
}

/// Acyclic by depth-first search with colours.
fn acyclic(d: &Determination) -> bool {
    let mut succ: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for c in &d.constraints {
        succ.entry(c.first.0).or_default().push(c.second.0);
    }
    let mut colour = vec![0u8; d.features.len()];
    fn visit(v: u32, succ: &BTreeMap<u32, Vec<u32>>, colour: &mut [u8]) -> bool {
        colour[v as usize] = 1;
        for &w in succ.get(&v).map(|v| v.as_slice()).unwrap_or(&[]) {
            let c = colour[w as usize];
            if c == 1 || (c == 0 && !visit(w, succ, colour)) {
                return false;
            }
        }
        colour[v as usize] = 2;
        true
    }
    (0..d.features.len() as u32).all(|v| colour[v as usize] != 0 || visit(v, &succ, &mut colour))
}

#[test]
fn tall_rib_gets_two_large_and_six_small_features() {
    let k = Knowledge::builtin().unwrap();
    let (plan, d) = planned("tall_rib", &k);
    let rib = plan
        .stiffness_features
        .iter()
        .find(|f| f.role == Some(WallRole::Rib))
        .expect("a rib");
    let mine: Vec<_> = d.features.iter().filter(|f| f.owner == rib.id).collect();
    for f in &mine {
        assert_eq!(value(f, "b_rf"), 11.0);
        assert_eq!(value(f, "h"), 12.0);
        assert_eq!(value(f, "big_h"), 36.0);
    }
    let large: Vec<_> = mine.iter().filter(|f| value(f, "large") == 1.0).collect();
    let small: Vec<_> = mine.iter().filter(|f| value(f, "large") == 0.0).collect();
    assert_eq!(large.len(), 2);
    assert_eq!(small.len(), 6);
    let ranges = |v: &[&&MachiningFeature]| -> Vec<(f64, f64)> {
        v.iter()
            .map(|f| (value(f, "depth_from"), value(f, "depth_to")))
            .collect()
    };
    assert_eq!(ranges(&large), vec![(0.0, 36.0), (36.0, 72.0)]);
    let expect: Vec<(f64, f64)> = (0..6)
        .map(|i| (12.0 * i as f64, 12.0 * (i + 1) as f64))
        .collect();
    for (got, want) in ranges(&small).iter().zip(&expect) {
        assert!(
            (got.0 - want.0).abs() < 1e-9 && (got.1 - want.1).abs() < 1e-9,
            "{got:?}"
        );
    }
    let side_a = value(large[0], "side");
    assert!(large.iter().all(|f| value(f, "side") == side_a));
    assert!(small.iter().all(|f| value(f, "side") == -side_a));
    for f in &mine {
        assert_eq!(value(f, "width"), 11.0);
        println!(
            "{} side {} {} depth {}–{} width {}",
            f.id,
            if value(f, "side") == side_a { "A" } else { "B" },
            if value(f, "large") == 1.0 {
                "large"
            } else {
                "small"
            },
            value(f, "depth_from"),
            value(f, "depth_to"),
            value(f, "width")
        );
    }
}

#[test]
fn tall_rib_order_alternates_sides_top_down() {
    let k = Knowledge::builtin().unwrap();
    let (_, d) = planned("tall_rib", &k);
    assert!(acyclic(&d));
    let order = topo(&d);
    let pos: BTreeMap<_, _> = order.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    let walls: Vec<&MachiningFeature> = d
        .features
        .iter()
        .filter(|f| f.provenance.values.contains_key("large"))
        .collect();
    for b in walls.iter().filter(|f| value(f, "large") == 0.0) {
        // The large feature on the other side covering this depth …
        let covering: Vec<_> = walls
            .iter()
            .filter(|a| a.owner == b.owner && value(a, "large") == 1.0)
            .filter(|a| value(a, "depth_to") >= value(b, "depth_to") - 1e-9)
            .filter(|a| value(a, "depth_from") <= value(b, "depth_from") + 1e-9)
            .collect();
        assert_eq!(covering.len(), 1);
        assert!(
            pos[&covering[0].id] < pos[&b.id],
            "{} before {}",
            covering[0].id,
            b.id
        );
        // … and small features go top-down.
        for b2 in walls
            .iter()
            .filter(|f| f.owner == b.owner && value(f, "large") == 0.0)
        {
            if value(b2, "depth_from") < value(b, "depth_from") {
                assert!(pos[&b2.id] < pos[&b.id]);
            }
        }
        // The next large feature waits for the small ones above it.
        for a in walls
            .iter()
            .filter(|a| a.owner == b.owner && value(a, "large") == 1.0)
        {
            if value(a, "depth_from") >= value(b, "depth_to") - 1e-9 {
                assert!(pos[&b.id] < pos[&a.id], "{} before {}", b.id, a.id);
            }
        }
    }
}

/// The prism's corner points in part coordinates.
fn corners(f: &MachiningFeature) -> Vec<DVec3> {
    thinplan_determine::prism_points(&f.shape)
}

#[test]
fn tall_rib_features_clear_the_rib_and_each_other() {
    let k = Knowledge::builtin().unwrap();
    let (plan, d) = planned("tall_rib", &k);
    let rib = plan
        .stiffness_features
        .iter()
        .find(|f| f.role == Some(WallRole::Rib))
        .unwrap();
    let shape = rib.shape.as_ref().unwrap();
    let (n, o) = (shape.frame.z.normalize(), shape.frame.origin);
    let t = rib.thickness.unwrap();
    let mine: Vec<_> = d.features.iter().filter(|f| f.owner == rib.id).collect();
    // Each feature on one side of the mid-plane, at least t/2 from it.
    for f in &mine {
        let ds: Vec<f64> = corners(f).iter().map(|p| (*p - o).dot(n)).collect();
        let all_plus = ds.iter().all(|d| *d >= t / 2.0 - 1e-9);
        let all_minus = ds.iter().all(|d| *d <= -t / 2.0 + 1e-9);
        assert!(all_plus || all_minus, "{} crosses the rib: {ds:?}", f.id);
    }
    // Pairwise: boxes in the wall frame (length, height, normal) overlap
    // in at most a face.
    let x = shape.frame.x.normalize();
    let y = n.cross(x);
    let boxes: Vec<[(f64, f64); 3]> = mine
        .iter()
        .map(|f| {
            let pts = corners(f);
            let sp = |d: DVec3| thinplan_determine::span(&pts, d);
            [sp(x), sp(y), sp(n)]
        })
        .collect();
    for i in 0..boxes.len() {
        for j in i + 1..boxes.len() {
            let overlap = (0..3).all(|a| {
                boxes[i][a].1.min(boxes[j][a].1) - boxes[i][a].0.max(boxes[j][a].0) > 1e-9
            });
            assert!(!overlap, "{} and {} overlap", mine[i].id, mine[j].id);
        }
    }
}

#[test]
fn a_tighter_allowed_deflection_makes_more_features() {
    let k = Knowledge::builtin().unwrap();
    let (_, base) = planned("tall_rib", &k);
    let mut tight = k.clone();
    tight.sizing.allowed_deflection = 0.002;
    let (_, d) = planned("tall_rib", &tight);
    let first = |d: &Determination| d.features[0].provenance.values.clone();
    let (a, b) = (first(&base), first(&d));
    assert!(
        b["big_h"] < a["big_h"] || b["b_rf"] > a["b_rf"] || b["h"] < a["h"],
        "{a:?} vs {b:?}"
    );
    // Smaller heights mean more features; a wider B_RF, wider ones (up to
    // the blank).
    let width = |d: &Determination| d.features[0].provenance.values["width"];
    assert!(
        d.features.len() > base.features.len() || width(&d) > width(&base),
        "{} vs {} features, {b:?}",
        d.features.len(),
        base.features.len()
    );
    println!("0.002: {b:?}, {} features", d.features.len());
    assert!(acyclic(&d));
}

#[test]
fn every_sample_determines_with_acyclic_constraints() {
    let k = Knowledge::builtin().unwrap();
    for (name, _) in thinplan_import::SAMPLES {
        let (mut plan, d) = planned(name, &k);
        assert!(acyclic(&d), "{name}");
        topo(&d);
        for (i, f) in d.features.iter().enumerate() {
            assert_eq!(f.id.0 as usize, i);
            assert!(f.shape.z_max > f.shape.z_min, "{name} {}", f.id);
        }
        println!(
            "{name}: {} features, {} constraints, {} refusals, warnings {:?}",
            d.features.len(),
            d.constraints.len(),
            d.refusals.len(),
            d.warnings
        );
        let again = planned(name, &k).1;
        assert_eq!(again, d, "{name}: deterministic");
        d.apply_to(&mut plan);
        assert_eq!(plan.stages_done.last(), Some(&Stage::Determine));
    }
}
