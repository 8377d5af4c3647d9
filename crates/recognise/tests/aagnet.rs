//! AAGNet `test.step` face accuracy (25 classes), see `crates/recognise/MFCAD.md`.
//!
//! Mapping: as for MFCAD (`thinplan_recognise::mfcad::mfcad_class`), plus
//! round holes: `hole` with a diameter and no floor → `through_hole`, with a
//! floor → `blind_hole`; `fillet` (convex or concave blend) → `round`
//! (AAGNet's only blend class; its rounds are convex edge blends). Classes
//! with no counterpart of ours: `Oring` (an annular groove: would read as a
//! closed pocket ring around a boss), `circular_through_slot`,
//! `circular_end_pocket`, `v/h_circular_end_blind_slot`,
//! `circular_blind_step` (circular-ended variants: read as slots, pockets
//! and steps whose curved sides are counted as corners; they map to the
//! rectangular class of the same topology).

use glam::DVec3;
use thinplan_plan::{StiffnessFeature, StiffnessKind};
use thinplan_recognise::mfcad::mfcad_class;

const CLASSES: [&str; 25] = [
    "chamfer",
    "through_hole",
    "triangular_passage",
    "rectangular_passage",
    "6sides_passage",
    "triangular_through_slot",
    "rectangular_through_slot",
    "circular_through_slot",
    "rectangular_through_step",
    "2sides_through_step",
    "slanted_through_step",
    "Oring",
    "blind_hole",
    "triangular_pocket",
    "rectangular_pocket",
    "6sides_pocket",
    "circular_end_pocket",
    "rectangular_blind_slot",
    "v_circular_end_blind_slot",
    "h_circular_end_blind_slot",
    "triangular_blind_step",
    "circular_blind_step",
    "rectangular_blind_step",
    "round",
    "stock",
];

fn aagnet_class(f: &StiffnessFeature) -> String {
    match f.kind {
        StiffnessKind::Hole if f.diameter.is_some() => {
            if f.provenance.values.get("floor").copied().unwrap_or(0.0) > 0.5 {
                "blind_hole".into()
            } else {
                "through_hole".into()
            }
        }
        StiffnessKind::Fillet => "round".into(),
        _ => mfcad_class(f),
    }
}

/// Area-weighted centroid of a face from its tessellation.
fn centroid(brep: &thinplan_brep::Brep, f: usize) -> DVec3 {
    let tol = thinplan_brep::TessTolerance::default();
    let Ok(m) = thinplan_brep::tessellate_face(brep, f, &tol) else {
        return DVec3::splat(f64::NAN);
    };
    let mut c = DVec3::ZERO;
    let mut a = 0.0;
    for t in &m.triangles {
        let [p, q, r] = t.map(|i| m.positions[i as usize]);
        let w = 0.5 * (q - p).cross(r - p).length();
        c += w * (p + q + r) / 3.0;
        a += w;
    }
    c / a.max(1e-300)
}

#[test]
fn aagnet_test_face_accuracy() {
    let root = thinplan_testdata::repo_root();
    let Some(data) = thinplan_testdata::data_dir("aagnet") else {
        return;
    };
    let brep = thinplan_step::read_step_file(&data.join("test.step"))
        .unwrap()
        .brep;
    let seg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data.join("test.json")).unwrap()).unwrap();
    let seg = seg[0][1]["seg"].as_object().unwrap().clone();
    let oracle: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("tests/oracle/aagnet_test_faces.json")).unwrap(),
    )
    .unwrap();
    let occ = oracle["test.step"].as_array().unwrap();
    assert_eq!(occ.len(), brep.faces.len());

    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let machine = k
        .machine(thinplan_knowledge::DEFAULT_MACHINE)
        .unwrap()
        .clone();
    let rec = thinplan_recognise::recognise(&brep, DVec3::Z, &k, &machine);
    let adjacency = thinplan_brep::edge_adjacency(&brep);
    let alone = thinplan_recognise::depressions::find_depressions(
        &brep,
        &adjacency,
        DVec3::Z,
        &k.depression_recognition,
        &[],
        &mut Vec::new(),
    );
    let ours: Vec<DVec3> = (0..brep.faces.len()).map(|f| centroid(&brep, f)).collect();
    for (name, features) in [
        ("depressions alone", &alone),
        ("full recognise", &rec.features),
    ] {
        let mut predicted = vec!["stock".to_string(); brep.faces.len()];
        for f in features.iter() {
            println!(
                "{name}: {:?} {} faces {:?}",
                f.kind, f.provenance.rule, f.faces
            );
            for &face in &f.faces {
                predicted[face] = aagnet_class(f);
            }
        }
        let mut correct = 0;
        for o in occ {
            let i = o["index"].as_u64().unwrap() as usize;
            let c = o["centroid"].as_array().unwrap();
            let c = DVec3::new(
                c[0].as_f64().unwrap(),
                c[1].as_f64().unwrap(),
                c[2].as_f64().unwrap(),
            );
            let ours_i = (0..ours.len())
                .min_by(|&a, &b| ours[a].distance(c).total_cmp(&ours[b].distance(c)))
                .unwrap();
            assert!(ours[ours_i].distance(c) < 0.05, "face {i} unmatched");
            let truth = CLASSES[seg[&i.to_string()].as_u64().unwrap() as usize];
            let p = &predicted[ours_i];
            if p == truth {
                correct += 1;
            } else {
                println!("{name}: miss occ face {i} (ours {ours_i}): {truth} -> {p}");
            }
        }
        println!("{name}: {correct}/{} faces", occ.len());
        // 23/27: the four faces AAGNet labels rectangular_blind_step around
        // one floor read as a blind slot (a floor, two facing sides and an
        // end wall); see MFCAD.md.
        // The full orchestrator reaches the same: walls share faces with
        // depressions and a face scores as the depression holding it.
        assert!(correct >= 23, "{name}: {correct}");
    }
}
