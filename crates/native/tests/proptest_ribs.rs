//! Random rib-on-web parts (random sizes, rib count, holes in the ribs,
//! ribs flush with the web edge or not) always build a closed manifold
//! solid with the right volume.

use std::f64::consts::PI;
use std::fmt::Write;

use proptest::prelude::*;

#[derive(Debug, Clone)]
struct Rib {
    x0: f64,
    x1: f64,
    t: f64,
    h: f64,
    holes: usize,
    hole_frac: f64,
}

fn rib() -> impl Strategy<Value = Rib> {
    (
        0.0f64..0.3,
        0.7f64..1.0,
        1.0f64..3.0,
        10.0f64..60.0,
        0usize..4,
        0.2f64..0.9,
    )
        .prop_map(|(a, b, t, h, holes, hole_frac)| Rib {
            // Snap some ends to the web edge to exercise face merging.
            x0: if a < 0.08 { 0.0 } else { a },
            x1: if b > 0.93 { 1.0 } else { b },
            t,
            h,
            holes,
            hole_frac,
        })
}

fn part(l: f64, w: f64, tw: f64, ribs: &[Rib]) -> (String, f64) {
    let mut s = String::new();
    let mut vol = l * w * tw;
    writeln!(s, "Part(name: \"random\", prisms: [").unwrap();
    writeln!(
        s,
        "Prism(id: \"web\", extent: (0.0, {tw}), profile: (outer: Rect(min: (0.0, 0.0), max: ({l}, {w})))),"
    )
    .unwrap();
    let n = ribs.len();
    for (i, r) in ribs.iter().enumerate() {
        let y = w * (i as f64 + 0.5) / n as f64;
        let (x0, x1) = (r.x0 * l, r.x1 * l);
        let len = x1 - x0;
        let mut holes = String::new();
        let mut hole_area = 0.0;
        if r.holes > 0 {
            let pitch = len / r.holes as f64;
            let rad = (r.h / 2.0 - 1.0).min(pitch / 2.0 - 1.0) * r.hole_frac;
            if rad > 0.5 {
                for k in 0..r.holes {
                    let cx = x0 + pitch * (k as f64 + 0.5);
                    let cz = tw + r.h / 2.0;
                    write!(holes, "Circle(centre: ({cx}, {cz}), radius: {rad}),").unwrap();
                    hole_area += PI * rad * rad;
                }
            }
        }
        writeln!(
            s,
            "Prism(id: \"rib{i}\", frame: (origin: (0.0, {y}, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)), \
             extent: ({}, {}), profile: (outer: Rect(min: ({x0}, {tw}), max: ({x1}, {})), holes: [{holes}])),",
            -r.t / 2.0,
            r.t / 2.0,
            tw + r.h
        )
        .unwrap();
        vol += (len * r.h - hole_area) * r.t;
    }
    writeln!(s, "])").unwrap();
    (s, vol)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_rib_on_web_parts_build(
        l in 60.0f64..300.0,
        w in 40.0f64..200.0,
        tw in 1.5f64..3.0,
        ribs in prop::collection::vec(rib(), 1..5),
    ) {
        let (text, vol) = part(l, w, tw, &ribs);
        let p = thinplan_native::parse_part(&text, "random").map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        let b = p.build().map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        thinplan_native::check::check_solid(&b).map_err(TestCaseError::fail)?;
        // Every edge used twice, in opposite directions (independent count).
        let mut uses = vec![(0, 0); b.edges.len()];
        for f in &b.faces {
            for &lp in &f.loops {
                for c in &b.loops[lp].coedges {
                    if c.forward { uses[c.edge].0 += 1 } else { uses[c.edge].1 += 1 }
                }
            }
        }
        prop_assert!(uses.iter().all(|u| *u == (1, 1)));
        let v = thinplan_native::mass::volume(&b);
        prop_assert!((v - vol).abs() <= 1e-6 * vol, "volume {} vs {}", v, vol);
        // Cylinders only from holes: one per hole.
        let holes: usize = b.faces.iter().filter(|f| matches!(f.surface, thinplan_brep::Surface::Cylinder { .. })).count();
        prop_assert_eq!(holes, text.matches("Circle(").count());
    }
}
