//! Property test: random rib-on-web parts (native RON text) give exactly the
//! web and the ribs, with the right thicknesses, roles and connections.

use glam::DVec3;
use proptest::prelude::*;
use thinplan_plan::{ConnectionKind, StiffnessKind, WallRole};

#[derive(Debug, Clone)]
struct Rib {
    t: f64,
    h: f64,
    x0: f64,
    x1: f64,
}

fn part_text(w: f64, d: f64, tw: f64, ribs: &[Rib]) -> String {
    let mut s = format!(
        "Part(name: \"random\", prisms: [\n  Prism(id: \"web\", extent: (0.0, {tw}), \
         profile: (outer: Rect(min: (0.0, 0.0), max: ({w}, {d})))),\n"
    );
    let n = ribs.len() as f64;
    for (i, r) in ribs.iter().enumerate() {
        let y = d * (i as f64 + 1.0) / (n + 1.0);
        s += &format!(
            "  Prism(id: \"rib{i}\", frame: (origin: (0.0, {y}, 0.0), x_dir: (1.0, 0.0, 0.0), \
             y_dir: (0.0, 0.0, 1.0)), extent: ({}, {}), cap_names: (\"side_a\", \"side_b\"), \
             profile: (outer: Rect(min: ({}, {tw}), max: ({}, {})))),\n",
            -0.5 * r.t,
            0.5 * r.t,
            r.x0,
            r.x1,
            tw + r.h
        );
    }
    s += "])\n";
    s
}

fn rib() -> impl Strategy<Value = Rib> {
    // Thickness 0.8..4 mm, height at least 5 × thickness (thin: ≥ 4).
    (0.8f64..4.0, 5.0f64..20.0, 5.0f64..40.0, 60.0f64..95.0).prop_map(|(t, k, x0, x1)| Rib {
        t: (t * 100.0).round() / 100.0,
        h: (t * k).round().max(5.0 * t).ceil(),
        x0: x0.round(),
        x1: x1.round() + 100.0,
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, .. ProptestConfig::default() })]
    #[test]
    fn ribs_on_a_web(
        tw in 1.0f64..4.0,
        d in 60.0f64..160.0,
        ribs in prop::collection::vec(rib(), 1..5),
    ) {
        let tw = (tw * 10.0).round() / 10.0;
        let d = d.round();
        let w = 220.0;
        let text = part_text(w, d, tw, &ribs);
        let brep = thinplan_native::parse_part(&text, "random").unwrap().build().unwrap();
        let k = thinplan_knowledge::Knowledge::builtin().unwrap();
        let m = k.machines["hsm_5axis"].clone();
        let r = thinplan_recognise::recognise(&brep, DVec3::Z, &k, &m);
        let walls: Vec<_> = r.features.iter().filter(|f| f.kind == StiffnessKind::Wall).collect();
        prop_assert_eq!(walls.len(), ribs.len() + 1, "{:#?}", walls);
        let webs: Vec<_> = walls.iter().filter(|f| f.role == Some(WallRole::Web)).collect();
        prop_assert_eq!(webs.len(), 1);
        prop_assert!((webs[0].thickness.unwrap() - tw).abs() < 0.01);
        for (i, rb) in ribs.iter().enumerate() {
            let name = format!("rib{i}.side_a");
            let f = walls
                .iter()
                .find(|f| f.faces.iter().any(|&x| brep.faces[x].name == name))
                .expect("rib found");
            prop_assert_eq!(f.role, Some(WallRole::Rib));
            prop_assert!((f.thickness.unwrap() - rb.t).abs() < 0.01);
            prop_assert!((f.height - rb.h).abs() < 0.01);
            prop_assert!((f.length - (rb.x1 - rb.x0)).abs() < 0.01);
            prop_assert!(f.axis.dot(DVec3::Y).abs() > 0.999);
            prop_assert!(r.connections.iter().any(|c| c.base == webs[0].id
                && c.leaf == f.id
                && c.kind == ConnectionKind::BaseLeaf));
        }
        let wall_conns = r.connections.iter().filter(|c| {
            walls.iter().any(|w| w.id == c.base) && walls.iter().any(|w| w.id == c.leaf)
        }).count();
        prop_assert_eq!(wall_conns, ribs.len());
    }
}
