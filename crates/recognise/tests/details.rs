//! Details across a standing wall's corner (thesis figure 4.10): a chamfer
//! or convex fillet gets the wedge it removes as its shape, in the wall's
//! frame, and is a leaf of the wall. Checked against the part's own numbers.

use glam::{DVec2, DVec3};
use thinplan_plan::{Prism, StiffnessKind, WallRole};
use thinplan_recognise::{recognise, Recognition};

fn run(ron: &str) -> Recognition {
    let brep = thinplan_native::parse_part(ron, "test")
        .unwrap()
        .build()
        .unwrap();
    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let m = k.machines["hsm_5axis"].clone();
    recognise(&brep, DVec3::Z, &k, &m)
}

/// The wedge's outline in part coordinates, arcs as many chords (my own
/// reading of the bulge: positive = counter-clockwise sweep of 4·atan(b)).
fn outline(p: &Prism) -> Vec<DVec3> {
    let (x, z) = (p.frame.x, p.frame.z);
    let y = z.cross(x);
    let v = &p.region.outer.vertices;
    let mut pts = Vec::new();
    for i in 0..v.len() {
        let (a, b) = (&v[i], &v[(i + 1) % v.len()]);
        let (p0, p1) = (DVec2::new(a.x, a.y), DVec2::new(b.x, b.y));
        let sweep = 4.0 * a.bulge.atan();
        let n = if a.bulge == 0.0 { 1 } else { 256 };
        // Points on the arc through p0 and p1 with that sweep.
        let chord = p1 - p0;
        let centre = if a.bulge == 0.0 {
            DVec2::ZERO
        } else {
            let h = chord.length() / (2.0 * (sweep / 2.0).tan());
            (p0 + p1) * 0.5 + DVec2::new(-chord.y, chord.x).normalize() * h
        };
        for k in 0..n {
            let q = if a.bulge == 0.0 {
                p0
            } else {
                let (s, c) = (sweep * k as f64 / n as f64).sin_cos();
                let r = p0 - centre;
                centre + DVec2::new(r.x * c - r.y * s, r.x * s + r.y * c)
            };
            pts.push(p.frame.origin + x * q.x + y * q.y);
        }
    }
    pts
}

/// Area of a planar loop in 3D (Newell), with its normal's direction.
fn area(pts: &[DVec3]) -> DVec3 {
    let mut a = DVec3::ZERO;
    for i in 0..pts.len() {
        a += pts[i].cross(pts[(i + 1) % pts.len()]);
    }
    a * 0.5
}

#[test]
fn the_chamfered_ribs_chamfer_is_the_wedge_it_cuts_off_and_a_leaf_of_the_rib() {
    let r = run(thinplan_import::sample("chamfered_rib").unwrap());
    let rib = r
        .features
        .iter()
        .find(|f| f.role == Some(WallRole::Rib))
        .unwrap();
    let ch: Vec<_> = r
        .features
        .iter()
        .filter(|f| f.kind == StiffnessKind::Chamfer)
        .collect();
    assert_eq!(ch.len(), 1, "{:?}", r.features);
    let ch = ch[0];
    assert_eq!(ch.provenance.rule, "recognise.chamfer.wall_corner");
    // The part: corner (140, ·, 92) cut from z = 74 to x = 122, 1.5 thick
    // about y = 20.
    let s = ch.shape.as_ref().expect("a wedge");
    let pts = outline(s);
    let a = area(&pts);
    assert!((a.length() - 0.5 * 18.0 * 18.0).abs() < 1e-6, "{a}");
    assert!(
        a.normalize().dot(s.frame.z) > 0.999_999,
        "counter-clockwise"
    );
    assert!((s.z_max - s.z_min - 1.5).abs() < 1e-9);
    for p in &pts {
        assert!((122.0 - 1e-6..=140.0 + 1e-6).contains(&p.x), "{p}");
        assert!((74.0 - 1e-6..=92.0 + 1e-6).contains(&p.z), "{p}");
    }
    assert!(pts
        .iter()
        .any(|p| p.distance(DVec3::new(140.0, p.y, 92.0)) < 1e-6));
    let y = s.frame.origin + s.frame.z * (0.5 * (s.z_min + s.z_max));
    assert!(
        (y.y - 20.0).abs() < 1e-6,
        "swept about the rib's mid-plane: {y}"
    );
    assert!((ch.provenance.values["leg_a"] - 18.0).abs() < 1e-6);
    assert!((ch.provenance.values["leg_b"] - 18.0).abs() < 1e-6);
    let c: Vec<_> = r
        .connections
        .iter()
        .filter(|c| c.leaf == ch.id || c.base == ch.id)
        .collect();
    assert_eq!(c.len(), 1);
    assert_eq!((c[0].base, c[0].leaf), (rib.id, ch.id));
    assert_eq!(c[0].provenance.rule, "connect.detail_on_wall");
}

const ROUNDED: &str = r#"Part(name: "rounded_rib", prisms: [
    Prism(id: "base", extent: (0.0, 20.0),
          profile: (outer: Rect(min: (0.0, 0.0), max: (160.0, 40.0)))),
    Prism(id: "rib",
          frame: (origin: (0.0, 20.0, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
          extent: (-1.0, 1.0),
          profile: (outer: Path(start: (20.0, 20.0), segments: [
              Line(to: (140.0, 20.0)),
              Line(to: (140.0, 78.0)),
              Arc(to: (128.0, 90.0), centre: (128.0, 78.0), ccw: true),
              Line(to: (20.0, 90.0)),
              Line(to: (20.0, 20.0)),
          ])),
          cap_names: ("side_a", "side_b")),
])"#;

#[test]
fn a_rounded_top_corner_is_a_fillet_whose_wedge_lies_between_arc_and_corner() {
    let r = run(ROUNDED);
    let rib = r
        .features
        .iter()
        .find(|f| f.role == Some(WallRole::Rib))
        .unwrap();
    let fl: Vec<_> = r
        .features
        .iter()
        .filter(|f| f.kind == StiffnessKind::Fillet)
        .collect();
    assert_eq!(fl.len(), 1, "{:?}", r.features);
    let s = fl[0].shape.as_ref().expect("a wedge");
    let pts = outline(s);
    // The square r × r less a quarter disc.
    let want = 12.0 * 12.0 * (1.0 - std::f64::consts::FRAC_PI_4);
    let a = area(&pts);
    assert!((a.length() - want).abs() < 0.01, "{} vs {want}", a.length());
    assert!(a.normalize().dot(s.frame.z) > 0.999_999);
    // Every point of the wedge is outside the arc and inside the corner square.
    for p in &pts {
        let d = DVec2::new(p.x - 128.0, p.z - 78.0);
        assert!(d.length() >= 12.0 - 1e-6, "{p}");
        assert!((128.0 - 1e-6..=140.0 + 1e-6).contains(&p.x), "{p}");
        assert!((78.0 - 1e-6..=90.0 + 1e-6).contains(&p.z), "{p}");
    }
    assert!(r
        .connections
        .iter()
        .any(|c| c.base == rib.id && c.leaf == fl[0].id));
}

/// Concave corner blends between walls (isogrid) add material: no wedge,
/// no connection.
#[test]
fn concave_blends_between_walls_get_no_wedge() {
    let r = run(thinplan_import::sample("isogrid").unwrap());
    let fillets: Vec<_> = r
        .features
        .iter()
        .filter(|f| f.kind == StiffnessKind::Fillet)
        .collect();
    assert!(!fillets.is_empty());
    for f in fillets {
        assert!(f.shape.is_none(), "{}", f.id);
        assert!(!r
            .connections
            .iter()
            .any(|c| c.leaf == f.id || c.base == f.id));
    }
}
