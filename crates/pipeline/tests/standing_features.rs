//! Stage 7 lets a tool overhang an edge to a feature stage 6 calls open (cut
//! before) by a whole diameter, and an edge to a feature still to come by
//! at most half of one: the tool centre stays on its own side. Stage 8 must
//! therefore never run an operation whose tool centre goes inside a feature
//! none of whose operations has run yet. Checked on every sample's planned
//! operations with geometry computed here (tool centres sampled every
//! 0.5 mm, point in polygon), not with the crate's own test.

mod common;

use std::collections::BTreeMap;

use common::cutting_centres;
use glam::{DVec2, DVec3};
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{MachiningFeature, Operation};

/// How far (mm) a tool centre may lie inside a feature not yet started.
/// Stage 7 grows a region beyond two non-product edges that meet at a
/// convex vertex by a square patch, not a round one, so near such a vertex
/// the centre strays up to (√2 − 1)·D/2 past the edge line diagonally
/// (measured at most 1.7 mm, isogrid's pocket centres). Before stage 8
/// honoured the open edges, centres went 5–10 mm into standing features.
const SLACK: f64 = 2.0;

fn inside(p: DVec2, ring: &[DVec2]) -> bool {
    let mut c = false;
    let n = ring.len();
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            c = !c;
        }
    }
    c
}

fn dist_seg(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// How deep `p` lies inside the feature's region (mm); ≤ 0 outside.
fn depth_inside(p: DVec2, f: &MachiningFeature) -> f64 {
    let rings: Vec<Vec<DVec2>> = std::iter::once(&f.shape.region.outer)
        .chain(&f.shape.region.holes)
        .map(|l| l.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect())
        .collect();
    let within = rings.iter().filter(|r| inside(p, r)).count() % 2 == 1;
    if !within {
        return 0.0;
    }
    rings
        .iter()
        .flat_map(|r| (0..r.len()).map(move |i| dist_seg(p, r[i], r[(i + 1) % r.len()])))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn no_tool_centre_enters_a_feature_that_has_not_been_started() {
    let k = load_knowledge(None).unwrap();
    let mut checked = 0usize;
    let mut worst: BTreeMap<(String, u32, u32), (f64, DVec3, String)> = BTreeMap::new();
    for (name, _) in thinplan_import::SAMPLES {
        let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
        let mut s = Session::open(&format!("builtin:{name}"), setup, k.clone()).expect("opens");
        s.run_all(|_| {}).expect("plans through stage 8");
        let plan = &s.plan;
        let flute: BTreeMap<&str, f64> = k
            .tool_set(&plan.setup.tool_set)
            .unwrap()
            .tools
            .iter()
            .map(|t| (t.id.as_str(), t.flute_length))
            .collect();
        // Rest passes stage 8 runs last, after every feature.
        let rest = |o: &Operation| thinplan_operations::runs_last(o);
        let by_id: BTreeMap<_, &Operation> = plan.operations.iter().map(|o| (o.id, o)).collect();
        let mut first: BTreeMap<u32, usize> = BTreeMap::new();
        for (at, id) in plan.operation_order.iter().enumerate() {
            let o = by_id[id];
            if !rest(o) {
                first.entry(o.feature.0).or_insert(at);
            }
        }
        for (at, id) in plan.operation_order.iter().enumerate() {
            let o = by_id[id];
            if rest(o) {
                continue;
            }
            let centres = cutting_centres(o);
            checked += centres.len();
            for g in &plan.machining_features {
                // Features with no operation and those started before.
                if g.id == o.feature || first.get(&g.id.0).is_none_or(|&s| s < at) {
                    continue;
                }
                let fr = &g.shape.frame;
                assert!(
                    (fr.z - DVec3::Z).length() < 1e-9,
                    "{name}: one set-up along z"
                );
                let top = fr.origin.z + g.shape.z_max;
                let bottom = fr.origin.z + g.shape.z_min;
                for c in &centres {
                    let d = *c - fr.origin;
                    let local = DVec2::new(d.dot(fr.x), d.dot(fr.z.cross(fr.x)));
                    if c.z < top - 0.1 && c.z + flute[o.tool.as_str()] > bottom + 0.1 {
                        let d = depth_inside(local, g);
                        if d > SLACK {
                            let key = (name.to_string(), o.id.0, g.id.0);
                            let e = worst.entry(key).or_insert((0.0, *c, o.method.clone()));
                            if d > e.0 {
                                *e = (d, *c, o.method.clone());
                            }
                        }
                    }
                }
            }
        }
    }
    for ((name, op, g), (d, c, method)) in &worst {
        eprintln!("{name}: OP{op} ({method}) centre {d:.2} mm inside MF{g} at {c:?}");
    }
    assert!(
        worst.is_empty(),
        "{} operations put the tool centre inside a feature before any of its operations ran",
        worst.len()
    );
    assert!(checked > 10_000, "only {checked} tool positions checked");
}
