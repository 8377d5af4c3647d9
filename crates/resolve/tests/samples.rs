//! Stage 6 on every sample part, checked independently of the stage's own
//! slicing: volumes from the B-rep's mass properties and the features'
//! prisms (shoelace here), point membership by ray casting against the
//! part's mesh, acyclicity by a topological sort written here.

use glam::DVec3;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{Adjacency, MachiningFeature, Plan, Stage};

fn planned(name: &str) -> Session {
    let k = load_knowledge(None).expect("builtin knowledge");
    let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
    s.run_to(Stage::Resolve, &Default::default(), |_| {})
        .expect("plans");
    s
}

/// Every bundled sample (a new one is covered without editing here).
fn samples() -> Vec<&'static str> {
    thinplan_import::SAMPLES.iter().map(|(n, _)| *n).collect()
}

fn loop_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    0.5 * (0..n)
        .map(|i| pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1])
        .sum::<f64>()
}

fn pts(l: &thinplan_plan::ProfileLoop) -> Vec<[f64; 2]> {
    l.vertices.iter().map(|v| [v.x, v.y]).collect()
}

fn feature_volume(f: &MachiningFeature) -> f64 {
    let r = &f.shape.region;
    let a = loop_area(&pts(&r.outer)).abs()
        - r.holes
            .iter()
            .map(|h| loop_area(&pts(h)).abs())
            .sum::<f64>();
    a * (f.shape.z_max - f.shape.z_min)
}

fn inside_loop(p: [f64; 2], l: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = l.len();
    for i in 0..n {
        let (a, b) = (l[i], l[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) > p[0]
        {
            inside = !inside;
        }
    }
    inside
}

fn in_feature(f: &MachiningFeature, p: DVec3) -> bool {
    let fr = &f.shape.frame;
    let y = fr.z.cross(fr.x);
    let d = p - fr.origin;
    let w = d.dot(fr.z);
    if w <= f.shape.z_min || w >= f.shape.z_max {
        return false;
    }
    let q = [d.dot(fr.x), d.dot(y)];
    inside_loop(q, &pts(&f.shape.region.outer))
        && !f.shape.region.holes.iter().any(|h| inside_loop(q, &pts(h)))
}

/// Ray casting along a skew direction against the part's triangles.
fn in_part(mesh: &thinplan_brep::Mesh, p: DVec3) -> bool {
    let dir = DVec3::new(0.5773, 0.5774, 0.5775).normalize();
    let mut hits = 0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let h = dir.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = p - a;
        let u = s.dot(h) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 {
            hits += 1;
        }
    }
    hits % 2 == 1
}

fn acyclic(plan: &Plan) -> bool {
    let n = plan.machining_features.len();
    let mut indeg = vec![0; n];
    let mut succ = vec![Vec::new(); n];
    for c in &plan.machining_constraints {
        succ[c.first.0 as usize].push(c.second.0 as usize);
        indeg[c.second.0 as usize] += 1;
    }
    let mut ready: Vec<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
    let mut seen = 0;
    while let Some(v) = ready.pop() {
        seen += 1;
        for &w in &succ[v] {
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.push(w);
            }
        }
    }
    seen == n
}

#[test]
fn part_and_features_make_up_the_blank() {
    for name in samples() {
        let s = planned(name);
        let bb = s.brep.bbox();
        let e = bb.extent();
        let blank = e.x * e.y * e.z;
        let part = s.brep.volume();
        let features: f64 = s.plan.machining_features.iter().map(feature_volume).sum();
        let err = (part + features - blank) / blank;
        println!(
            "{name}: blank {blank:.1} part {part:.1} features {features:.1} ({} features) error {:.2e}",
            s.plan.machining_features.len(),
            err
        );
        assert!(
            err.abs() < 1e-3,
            "{name}: part + features − blank = {err:.3e} of the blank"
        );
    }
}

#[test]
fn features_overlap_neither_the_product_nor_each_other() {
    for name in samples() {
        let s = planned(name);
        let mesh = thinplan_brep::tessellate(&s.brep, &s.brep.mass_tolerance());
        let bb = s.brep.bbox();
        let (lo, e) = (bb.min, bb.extent());
        // A deterministic low-discrepancy point set (R3 sequence).
        let (a1, a2, a3) = (0.819_172_513_4, 0.671_043_606_5, 0.549_700_477_5);
        let (mut both, mut none, n) = (0, 0, 3000);
        for i in 0..n {
            let f = i as f64 + 0.5;
            let u = DVec3::new((f * a1).fract(), (f * a2).fract(), (f * a3).fract());
            let p = lo + u * e;
            let inside_part = in_part(&mesh, p);
            let owners = s
                .plan
                .machining_features
                .iter()
                .filter(|m| in_feature(m, p))
                .count();
            assert!(owners <= 1, "{name}: point {p} in {owners} features");
            if inside_part && owners == 1 {
                both += 1;
            }
            if !inside_part && owners == 0 {
                none += 1;
            }
        }
        // Points within the mesh's chord of a curved face may disagree.
        assert!(
            both <= n / 500,
            "{name}: {both} of {n} points in the part and a feature"
        );
        assert!(none <= n / 500, "{name}: {none} of {n} points in neither");
    }
}

#[test]
fn constraints_stay_acyclic_and_adjacency_is_complete() {
    for name in samples() {
        let s = planned(name);
        let up = s.plan.setup.up;
        assert!(
            acyclic(&s.plan),
            "{name}: machining constraints have a cycle"
        );
        for f in &s.plan.machining_features {
            assert!(
                (f.shape.frame.z - up).length() < 1e-9,
                "{name}: {} not along up",
                f.id
            );
            assert_eq!(f.side_adjacency.len(), f.shape.region.outer.vertices.len());
            assert_eq!(f.hole_adjacency.len(), f.shape.region.holes.len());
            for (h, a) in f.shape.region.holes.iter().zip(&f.hole_adjacency) {
                assert_eq!(h.vertices.len(), a.len());
            }
        }
        // Every wall stands in the blank with product beside some feature.
        assert!(
            s.plan
                .machining_features
                .iter()
                .any(|f| f.side_adjacency.contains(&Adjacency::Product)),
            "{name}: no feature borders the product"
        );
    }
}

/// A feature lying on another (touching along up, overlapping in plan
/// view, found here by sampling) is machined before it: the tool comes
/// from above.
#[test]
fn a_feature_on_top_of_another_comes_first() {
    for name in samples() {
        let s = planned(name);
        let mf = &s.plan.machining_features;
        let n = mf.len();
        let mut succ = vec![Vec::new(); n];
        for c in &s.plan.machining_constraints {
            succ[c.first.0 as usize].push(c.second.0 as usize);
        }
        let reaches = |a: usize, b: usize| {
            let mut seen = vec![false; n];
            let mut stack = vec![a];
            while let Some(v) = stack.pop() {
                if v == b {
                    return true;
                }
                for &w in &succ[v] {
                    if !seen[w] {
                        seen[w] = true;
                        stack.push(w);
                    }
                }
            }
            false
        };
        for (b, fb) in mf.iter().enumerate() {
            let outer = pts(&fb.shape.region.outer);
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in &outer {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            for (a, fa) in mf.iter().enumerate() {
                if a == b || (fa.shape.z_min - fb.shape.z_max).abs() > 1e-6 {
                    continue;
                }
                let z = 0.5 * (fb.shape.z_min + fb.shape.z_max);
                let z_above = fa.shape.z_min + 1e-3;
                let fr = &fb.shape.frame;
                let y = fr.z.cross(fr.x);
                let mut shared = false;
                'grid: for i in 1..20 {
                    for j in 1..20 {
                        let (u, v) = (
                            lo[0] + (hi[0] - lo[0]) * i as f64 / 20.0,
                            lo[1] + (hi[1] - lo[1]) * j as f64 / 20.0,
                        );
                        let p = fr.origin + fr.x * u + y * v;
                        if in_feature(fb, p + fr.z * z) && in_feature(fa, p + fr.z * z_above) {
                            shared = true;
                            break 'grid;
                        }
                    }
                }
                if shared {
                    assert!(
                        reaches(a, b),
                        "{name}: {} lies on {} but is not before it",
                        fa.id,
                        fb.id
                    );
                }
            }
        }
    }
}

/// The sloped faces stage 6 records (`MachiningFeature::slopes`), checked
/// against the part's mesh by ray casting: at every sampled height inside
/// the part, just short of the recorded offset beyond a product edge's
/// midpoint is no product and just past it is. The chamfer's offsets are
/// those of a 45° plane; every sloped feature samples the face at least a
/// corner radius (em20: 1 mm) above its top, or past the part's top.
#[test]
fn recorded_sloped_faces_lie_where_the_part_is() {
    for name in ["chamfered_rib", "flange_cutouts"] {
        let s = planned(name);
        let mesh = thinplan_brep::tessellate(&s.brep, &s.brep.mass_tolerance());
        let top = mesh
            .positions
            .iter()
            .map(|p| p.dot(s.plan.setup.up.normalize()))
            .fold(f64::NEG_INFINITY, f64::max);
        let mut checked = 0;
        let sloped: Vec<&MachiningFeature> = s
            .plan
            .machining_features
            .iter()
            .filter(|f| f.slopes.is_some())
            .collect();
        assert!(!sloped.is_empty(), "{name}: no sloped feature");
        for f in sloped {
            let sl = f.slopes.as_ref().unwrap();
            let h = &sl.heights;
            assert!(h.windows(2).all(|w| w[0] < w[1]), "{name} {}: {h:?}", f.id);
            assert!((h[0] - f.shape.z_min).abs() < 1e-9);
            assert!(
                h.contains(&f.shape.z_max)
                    && (*h.last().unwrap() >= f.shape.z_max + 1.0 - 1e-9
                        || *h.last().unwrap() > top),
                "{name} {}: sampled up to {:?}, top {}",
                f.id,
                h.last(),
                f.shape.z_max
            );
            let fr = &f.shape.frame;
            let y = fr.z.cross(fr.x);
            let outer = pts(&f.shape.region.outer);
            let n = outer.len();
            for (i, offs) in sl.side.iter().enumerate() {
                if offs.is_empty() {
                    continue;
                }
                assert_eq!(f.side_adjacency[i], Adjacency::Product);
                assert_eq!(offs.len(), h.len());
                let (a, b) = (outer[i], outer[(i + 1) % n]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let len = (dx * dx + dy * dy).sqrt();
                let nrm = [dy / len, -dx / len];
                let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                for (k, (&z, &o)) in h.iter().zip(offs).enumerate() {
                    // The region's own section (offset 0) and heights
                    // above the part (nothing there) say nothing here.
                    if k == 1 || z >= top - 1e-6 {
                        continue;
                    }
                    let z = if k == 0 { z + 1e-3 } else { z - 1e-3 };
                    let at = |t: f64| {
                        fr.origin
                            + fr.x * (mid[0] + nrm[0] * t)
                            + y * (mid[1] + nrm[1] * t)
                            + fr.z * z
                    };
                    // Slopes up to 10 (a round bottom): 1e-3 in height is
                    // 0.01 across.
                    let tol = 0.02;
                    assert!(
                        !in_part(&mesh, at(o - tol)),
                        "{name} {} edge {i}: product short of offset {o} at z {z}",
                        f.id
                    );
                    assert!(
                        in_part(&mesh, at(o + tol)),
                        "{name} {} edge {i}: no product past offset {o} at z {z}",
                        f.id
                    );
                    if name == "chamfered_rib" {
                        // The 45° chamfer: the face recedes as fast as it rises.
                        let at_z = h[1];
                        assert!(
                            (o - (z - at_z)).abs() < 2e-3,
                            "{} edge {i}: offset {o} at z {z}, section at {at_z}",
                            f.id
                        );
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 20, "{name}: {checked} samples checked");
    }
}

/// Shallow faces thin their slabs (`interference.shallow_slabs`): the
/// cut-outs' round bottoms (R8) are sliced thinner near their lowest point
/// than up their sides, never below the knowledge's minimum nor above its
/// largest thickness, and each slab no thicker than `along_face · sin α`
/// allows for the arc's slope at its top (the arc is steeper higher up).
#[test]
fn shallow_faces_get_thinner_slabs() {
    let s = planned("flange_cutouts");
    let kn = &s.knowledge.interference;
    let sh = kn
        .shallow_slabs
        .as_ref()
        .expect("shallow slabs in the knowledge");
    // The first cut-out: x 42..58, its arc's centre at z 33, radius 8.
    let mut slabs: Vec<(f64, f64)> = s
        .plan
        .machining_features
        .iter()
        .filter(|f| f.slopes.is_some())
        .filter(|f| {
            let b = f.plan_box();
            b[0] >= 41.0 && b[2] <= 59.0
        })
        .map(|f| (f.shape.z_min, f.shape.z_max))
        .collect();
    slabs.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(slabs.len() >= 10, "{slabs:?}");
    let (lowest, highest) = (slabs[0], slabs[slabs.len() - 1]);
    assert!(
        lowest.1 - lowest.0 < 0.5 * (highest.1 - highest.0),
        "{slabs:?}"
    );
    for &(a, b) in &slabs {
        let t = b - a;
        assert!(
            t >= sh.min_thickness - 1e-9 && t <= kn.sloped_slab_thickness + 1e-9,
            "{slabs:?}"
        );
        // Slope of the arc at the slab's top: sin α = u / 8, u the half-width.
        let u = (64.0 - (33.0 - b).powi(2)).max(0.0).sqrt();
        let allowed = (sh.along_face * u / 8.0).clamp(sh.min_thickness, kn.sloped_slab_thickness);
        assert!(t <= allowed + 1e-6, "slab {a}..{b}: {t} > {allowed}");
    }
}
