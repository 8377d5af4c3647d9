//! Shape-level tests: mass properties against closed forms, tessellation
//! orientation, convexity, and property tests.

use std::f64::consts::PI;

use glam::{DMat4, DQuat, DVec2, DVec3};
use proptest::prelude::*;

use crate::adjacency::{edge_adjacency, face_neighbours, Convexity};
use crate::tess::{tessellate, tessellate_face, Mesh, TessTolerance};
use crate::test_shapes::*;
use crate::Brep;

fn face_named(b: &Brep, name: &str) -> usize {
    b.faces.iter().position(|f| f.name == name).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Every triangle's geometric normal agrees with the stored outward normals.
fn assert_outward(mesh: &Mesh) {
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let avg: DVec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
        assert!(n.dot(avg) > 0.0, "triangle {t:?} wound inwards");
    }
}

/// Closed, consistently oriented: every directed mesh edge between distinct
/// points has an opposite partner (by position, faces are separate meshes).
fn assert_closed(mesh: &Mesh) {
    use std::collections::BTreeMap;
    let key = |p: DVec3| {
        let q = (p * 1e6).round();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut count: BTreeMap<_, i64> = BTreeMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let a = key(mesh.positions[t[k] as usize]);
            let b = key(mesh.positions[t[(k + 1) % 3] as usize]);
            if a != b {
                *count.entry((a, b)).or_default() += 1;
            }
        }
    }
    // Collinear splits on one side make exact pairing impossible; compare
    // the boundary length imbalance instead: directed lengths must cancel.
    let mut sum = DVec3::ZERO;
    for t in &mesh.triangles {
        for k in 0..3 {
            let a = mesh.positions[t[k] as usize];
            let b = mesh.positions[t[(k + 1) % 3] as usize];
            sum += a.cross(b);
        }
    }
    assert!(
        sum.length() < 1e-6 * (1.0 + mesh.area()),
        "open mesh: {sum}"
    );
    assert!(!count.is_empty());
}

#[test]
fn box_volume_area_bbox() {
    let b = box_shape(10.0, 20.0, 30.0);
    let m = b.mass_properties();
    assert!(m.failed_faces.is_empty());
    assert!((m.volume - 6000.0).abs() < 1e-9, "{}", m.volume);
    assert!((m.area - 2.0 * (200.0 + 300.0 + 600.0)).abs() < 1e-9);
    assert!(m.bbox.min.distance(DVec3::ZERO) < 1e-12);
    assert!(m.bbox.max.distance(DVec3::new(10.0, 20.0, 30.0)) < 1e-12);
    assert_eq!(b.volume(), m.volume);
    assert_eq!(b.solid_volume(0), m.volume);
    let mesh = tessellate(&b, &TessTolerance::default());
    assert_outward(&mesh);
    assert_closed(&mesh);
}

#[test]
fn box_with_hole_volume() {
    let (r, h) = (3.0, 30.0);
    let b = box_with_hole(10.0, 20.0, h, DVec2::new(5.0, 8.0), r);
    let m = b.mass_properties();
    assert!(m.failed_faces.is_empty(), "{:?}", m.failed_faces);
    let exact = 6000.0 - PI * r * r * h;
    assert!(
        rel(m.volume, exact) < 5e-4,
        "volume {} vs {exact}",
        m.volume
    );
    let area = 2.0 * (200.0 - PI * r * r) + 2.0 * (10.0 + 20.0) * h + 2.0 * PI * r * h;
    assert!(rel(m.area, area) < 5e-4, "area {} vs {area}", m.area);
    // Default tolerance also well within 0.1 %.
    let mesh = tessellate(&b, &TessTolerance::default());
    assert!(mesh.failed_faces.is_empty());
    assert!(rel(mesh.signed_volume(), exact) < 1e-3);
    assert_outward(&mesh);
    assert_closed(&mesh);
    // The hole's cylinder face has inward-pointing outward normals.
    let hole_face = b
        .faces
        .iter()
        .position(|f| matches!(f.surface, crate::Surface::Cylinder { .. }))
        .unwrap();
    let hm = tessellate_face(&b, hole_face, &TessTolerance::default()).unwrap();
    for (p, n) in hm.positions.iter().zip(&hm.normals) {
        let radial = DVec3::new(p.x - 5.0, p.y - 8.0, 0.0).normalize();
        assert!(n.dot(radial) < -0.99);
    }
}

#[test]
fn outer_flags_do_not_matter() {
    let mut b = box_with_hole(10.0, 20.0, 30.0, DVec2::new(5.0, 8.0), 3.0);
    let before = b.mass_properties();
    for l in b.loops.iter_mut() {
        l.outer = false;
    }
    let after = b.mass_properties();
    assert_eq!(before, after);
    // Reversed bound marking + reversed coedge order is the same loop.
    for l in b.loops.iter_mut() {
        l.orientation = !l.orientation;
        l.coedges.reverse();
        for c in l.coedges.iter_mut() {
            c.forward = !c.forward;
        }
    }
    let again = b.mass_properties();
    assert!((again.volume - before.volume).abs() < 1e-9);
}

#[test]
fn cylinders_with_and_without_seam() {
    let (r, h) = (4.0, 12.0);
    for b in [cylinder(r, h), cylinder_with_seam(r, h)] {
        let m = b.mass_properties();
        assert!(m.failed_faces.is_empty(), "{:?}", m.failed_faces);
        assert!(rel(m.volume, PI * r * r * h) < 2e-4, "{}", m.volume);
        assert!(rel(m.area, 2.0 * PI * r * r + 2.0 * PI * r * h) < 2e-4);
        assert!(m.bbox.min.distance(DVec3::new(-r, -r, 0.0)) < 1e-9);
        assert!(m.bbox.max.distance(DVec3::new(r, r, h)) < 1e-9);
        let mesh = tessellate(&b, &TessTolerance::default());
        assert_outward(&mesh);
        assert_closed(&mesh);
    }
}

#[test]
fn slot_with_partial_cylinders() {
    let outer = Profile::rect(DVec2::ZERO, DVec2::new(60.0, 30.0));
    let slot = Profile::stadium(DVec2::new(30.0, 15.0), 10.0, 5.0);
    let h = 8.0;
    let b = extrude(&outer, std::slice::from_ref(&slot), h);
    let m = b.mass_properties();
    assert!(m.failed_faces.is_empty(), "{:?}", m.failed_faces);
    let a = 1800.0 - slot.signed_area();
    assert!((slot.signed_area() - (200.0 + PI * 25.0)).abs() < 1e-9);
    assert!(rel(m.volume, a * h) < 2e-4);
    let area = 2.0 * a + (180.0 + slot.perimeter()) * h;
    assert!(rel(m.area, area) < 2e-4);
    let mesh = tessellate(&b, &TessTolerance::default());
    assert_outward(&mesh);
    assert_closed(&mesh);
}

#[test]
fn cone_and_hemisphere() {
    let (r, h) = (3.0, 7.0);
    let c = cone(r, h);
    let m = c.mass_properties();
    assert!(m.failed_faces.is_empty(), "{:?}", m.failed_faces);
    assert!(rel(m.volume, PI * r * r * h / 3.0) < 5e-4, "{}", m.volume);
    let slant = (r * r + h * h).sqrt();
    assert!(
        rel(m.area, PI * r * r + PI * r * slant) < 5e-4,
        "{}",
        m.area
    );
    assert_outward(&tessellate(&c, &TessTolerance::default()));

    let s = hemisphere(5.0);
    let m = s.mass_properties();
    assert!(m.failed_faces.is_empty(), "{:?}", m.failed_faces);
    assert!(rel(m.volume, 2.0 / 3.0 * PI * 125.0) < 5e-4, "{}", m.volume);
    assert!(rel(m.area, 3.0 * PI * 25.0) < 5e-4, "{}", m.area);
    assert!((m.bbox.max.z - 5.0).abs() < 1e-3);
    assert!((m.bbox.min.z).abs() < 1e-12);
    let mesh = tessellate(&s, &TessTolerance::default());
    assert_outward(&mesh);
    assert_closed(&mesh);
}

#[test]
fn chord_tolerance_holds_on_cylinder_faces() {
    let tol = TessTolerance {
        chord: 0.05,
        angle: 1.0,
    };
    let b = box_with_hole(40.0, 40.0, 25.0, DVec2::new(20.0, 20.0), 10.0);
    let f = b
        .faces
        .iter()
        .position(|f| matches!(f.surface, crate::Surface::Cylinder { .. }))
        .unwrap();
    let m = tessellate_face(&b, f, &tol).unwrap();
    for t in &m.triangles {
        let p = t.map(|i| m.positions[i as usize]);
        for q in [
            (p[0] + p[1] + p[2]) / 3.0,
            (p[0] + p[1]) / 2.0,
            (p[1] + p[2]) / 2.0,
            (p[0] + p[2]) / 2.0,
        ] {
            let d = 10.0 - DVec2::new(q.x - 20.0, q.y - 20.0).length();
            assert!(d <= 0.05 + 1e-9, "chord error {d}");
        }
    }
}

#[test]
fn box_edges_all_convex() {
    let b = box_shape(1.0, 2.0, 3.0);
    let adj = edge_adjacency(&b);
    assert_eq!(adj.len(), 12);
    for a in &adj {
        assert_eq!(a.faces.len(), 2);
        assert_eq!(a.convexity, Convexity::Convex);
    }
    assert_eq!(
        face_neighbours(&b, face_named(&b, "bottom")),
        vec![0, 1, 2, 3]
    );
}

#[test]
fn l_prism_has_one_concave_edge() {
    let b = l_prism(10.0, 8.0, 2.0, 5.0);
    let adj = edge_adjacency(&b);
    let concave: Vec<usize> = (0..adj.len())
        .filter(|&e| adj[e].convexity == Convexity::Concave)
        .collect();
    assert_eq!(concave.len(), 1, "{adj:?}");
    let e = &b.edges[concave[0]];
    let (p, q) = (b.vertices[e.start].point, b.vertices[e.end].point);
    assert!((p.x - 2.0).abs() < 1e-12 && (p.y - 2.0).abs() < 1e-12);
    assert!((q.x - 2.0).abs() < 1e-12 && (q.y - 2.0).abs() < 1e-12);
    assert!(adj
        .iter()
        .all(|a| a.convexity == Convexity::Convex || a.convexity == Convexity::Concave));
    let m = b.mass_properties();
    assert!((m.volume - (10.0 * 2.0 + 2.0 * 6.0) * 5.0).abs() < 1e-9);
}

#[test]
fn hole_edges_concave_seam_smooth() {
    let b = extrude_with_seams(
        &Profile::rect(DVec2::ZERO, DVec2::new(10.0, 10.0)),
        &[Profile::Circle {
            center: DVec2::new(5.0, 5.0),
            radius: 2.0,
        }],
        4.0,
    );
    let adj = edge_adjacency(&b);
    for (e, a) in adj.iter().enumerate() {
        let edge = &b.edges[e];
        match edge.curve {
            // The rim of a hole meets the top/bottom at a convex edge.
            crate::Curve::Circle { .. } => assert_eq!(a.convexity, Convexity::Convex),
            _ if a.faces.len() == 1 => assert_eq!(a.convexity, Convexity::Smooth),
            _ => assert_eq!(a.convexity, Convexity::Convex),
        }
    }
    let m = b.mass_properties();
    assert!(rel(m.volume, (100.0 - PI * 4.0) * 4.0) < 2e-4);
}

#[test]
fn boss_edges_are_concave() {
    // A plate with a cylinder standing on it: the foot circle is concave.
    let mut plate = box_shape(20.0, 20.0, 2.0);
    let mut boss = cylinder(3.0, 5.0);
    boss.transform(&DMat4::from_translation(DVec3::new(10.0, 10.0, 2.0)));
    // Reuse the boss's bottom circle edge in the plate's top face as a hole
    // loop: merge by hand into one B-rep.
    let base = plate.edges.len();
    let vbase = plate.vertices.len();
    let lbase = plate.loops.len();
    plate.append(&boss);
    let boss_bottom = plate
        .faces
        .iter()
        .rposition(|f| f.name == "bottom")
        .unwrap();
    let circle = plate.loops[plate.faces[boss_bottom].loops[0]].coedges[0];
    assert_eq!(circle.edge, base);
    let _ = (vbase, lbase);
    let top = face_named(&plate, "top");
    let l = plate.add_loop(crate::Loop {
        coedges: vec![crate::Coedge {
            edge: circle.edge,
            forward: false,
        }],
        vertex: None,
        orientation: true,
        outer: false,
    });
    plate.faces[top].loops.push(l);
    plate.faces[boss_bottom].loops.clear();
    let adj = edge_adjacency(&plate);
    let a = &adj[circle.edge];
    assert_eq!(a.faces.len(), 2);
    assert_eq!(a.convexity, Convexity::Concave);
}

fn rigid(axis: DVec3, angle: f64, t: DVec3) -> DMat4 {
    DMat4::from_rotation_translation(DQuat::from_axis_angle(axis.normalize(), angle), t)
}

fn star_polygon(n: usize, radii: &[f64]) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * 2.0 * PI;
            DVec2::from_angle(a) * radii[i]
        })
        .collect()
}

fn shoelace(p: &[DVec2]) -> f64 {
    (0..p.len())
        .map(|i| 0.5 * p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn rigid_motion_invariance(
        dx in 1.0f64..50.0, dy in 1.0f64..50.0, dz in 1.0f64..50.0,
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in 0.1f64..1.0,
        angle in -3.0f64..3.0,
        tx in -100.0f64..100.0, ty in -100.0f64..100.0, tz in -100.0f64..100.0,
        hole in proptest::bool::ANY,
    ) {
        let r = 0.3 * dx.min(dy);
        let mut b = if hole {
            box_with_hole(dx, dy, dz, DVec2::new(dx / 2.0, dy / 2.0), r)
        } else {
            box_shape(dx, dy, dz)
        };
        let m0 = b.mass_properties();
        let m = rigid(DVec3::new(ax, ay, az), angle, DVec3::new(tx, ty, tz));
        b.transform(&m);
        let m1 = b.mass_properties();
        prop_assert!(m1.failed_faces.is_empty());
        prop_assert!(rel(m1.volume, m0.volume) < 1e-4, "{} {}", m1.volume, m0.volume);
        prop_assert!(rel(m1.area, m0.area) < 1e-4);
        if !hole {
            prop_assert!((m0.volume - dx * dy * dz).abs() < 1e-9 * dx * dy * dz);
        }
        // The box of the moved part is the box of the moved corners.
        let mut expect = crate::Aabb::EMPTY;
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { 0.0 } else { dx },
                if i & 2 == 0 { 0.0 } else { dy },
                if i & 4 == 0 { 0.0 } else { dz },
            );
            expect.include(m.transform_point3(c));
        }
        let diag = expect.extent().length();
        prop_assert!(m1.bbox.min.distance(expect.min) < 1e-9 * (1.0 + diag));
        prop_assert!(m1.bbox.max.distance(expect.max) < 1e-9 * (1.0 + diag));
    }

    #[test]
    fn plate_with_random_holes(
        w in 20.0f64..120.0, l in 20.0f64..120.0, t in 0.5f64..10.0,
        cells in proptest::collection::vec((proptest::bool::ANY, 0.05f64..0.45, 0.0f64..1.0, 0.0f64..1.0), 9),
    ) {
        // A 3×3 grid of cells, each with an optional hole inside it.
        let (cw, cl) = (w / 3.0, l / 3.0);
        let mut holes = Vec::new();
        for (k, &(on, rf, fx, fy)) in cells.iter().enumerate() {
            if !on { continue; }
            let r = rf * cw.min(cl) * 0.9;
            let room = DVec2::new(cw / 2.0 - r - 0.05 * cw, cl / 2.0 - r - 0.05 * cl);
            let c = DVec2::new((k % 3) as f64 * cw + cw / 2.0, (k / 3) as f64 * cl + cl / 2.0)
                + DVec2::new((2.0 * fx - 1.0) * room.x.max(0.0), (2.0 * fy - 1.0) * room.y.max(0.0));
            holes.push((c, r));
        }
        let b = plate_with_holes(w, l, t, &holes);
        let mesh = tessellate(&b, &TessTolerance::default());
        prop_assert!(mesh.failed_faces.is_empty());
        let holes_area: f64 = holes.iter().map(|h| PI * h.1 * h.1).sum();
        let holes_perim: f64 = holes.iter().map(|h| 2.0 * PI * h.1).sum();
        let area = 2.0 * (w * l - holes_area) + 2.0 * (w + l) * t + holes_perim * t;
        // Default chord 0.01 mm on radii >= 0.3 mm: well within 0.1 %.
        prop_assert!(rel(mesh.area(), area) < 1e-3, "{} {}", mesh.area(), area);
        prop_assert!(rel(mesh.signed_volume(), (w * l - holes_area) * t) < 1e-3);
        // The top face alone: exact polygon area up to the chord error of arcs.
        let top = tessellate_face(&b, face_named(&b, "top"), &TessTolerance::default()).unwrap();
        let top_area = top.area();
        let err_bound: f64 = holes.iter().map(|h| 2.0 * PI * h.1 * 0.01).sum::<f64>() + 1e-9 * w * l;
        prop_assert!((top_area - (w * l - holes_area)).abs() <= err_bound);
    }

    #[test]
    fn star_polygon_with_holes_area(
        n in 5usize..40,
        radii in proptest::collection::vec(10.0f64..30.0, 40),
        hs in proptest::collection::vec((0.0f64..1.0, 0.5f64..2.0), 0..4),
    ) {
        let outer = star_polygon(n, &radii[..n]);
        // Small square holes placed well inside the kernel (radius < 10).
        let mut holes = Vec::new();
        for (k, &(f, s)) in hs.iter().enumerate() {
            let a = k as f64 * PI / 2.0 + f;
            let c = DVec2::from_angle(a) * 5.0;
            holes.push(Profile::rect(c - DVec2::splat(s / 2.0), c + DVec2::splat(s / 2.0)));
        }
        let b = extrude(&Profile::polygon(&outer), &holes, 1.0);
        let m = tessellate_face(&b, face_named(&b, "top"), &TessTolerance::default()).unwrap();
        let hole_area: f64 = hs.iter().map(|h| h.1 * h.1).sum();
        let exact = shoelace(&outer) - hole_area;
        prop_assert!((m.area() - exact).abs() < 1e-9 * exact, "{} {}", m.area(), exact);
        let bottom = tessellate_face(&b, face_named(&b, "bottom"), &TessTolerance::default()).unwrap();
        prop_assert!((bottom.area() - exact).abs() < 1e-9 * exact);
        prop_assert!((b.volume() - exact).abs() < 1e-9 * exact);
    }
}

#[test]
fn deterministic() {
    let b = box_with_hole(10.0, 20.0, 30.0, DVec2::new(5.0, 8.0), 3.0);
    let a = tessellate(&b, &TessTolerance::default());
    let c = tessellate(&b, &TessTolerance::default());
    assert_eq!(a, c);
    let _ = Brep::default().mass_properties();
}
