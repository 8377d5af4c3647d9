//! Depressions on hand-built native parts.

use glam::DVec3;
use thinplan_plan::{StiffnessFeature, StiffnessKind};

fn recognise(ron: &str) -> Vec<StiffnessFeature> {
    let part = thinplan_native::parse_part(ron, "test").unwrap();
    let brep = part.build().unwrap();
    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let adjacency = thinplan_brep::edge_adjacency(&brep);
    thinplan_recognise::depressions::find_depressions(
        &brep,
        &adjacency,
        DVec3::Z,
        &k.depression_recognition,
        &[],
        &mut Vec::new(),
    )
}

#[test]
fn plate_with_round_hole() {
    let f = recognise(
        r#"Part(name: "plate", prisms: [Prism(id: "p", extent: (0.0, 4.0),
            profile: (outer: Rect(min: (0.0, 0.0), max: (100.0, 60.0)),
                      holes: [Circle(centre: (50.0, 30.0), radius: 10.0)]))])"#,
    );
    assert_eq!(f.len(), 1, "{f:#?}");
    assert_eq!(f[0].kind, StiffnessKind::Hole);
    assert_eq!(f[0].provenance.rule, "recognise.hole.round");
    assert!((f[0].diameter.unwrap() - 20.0).abs() < 1e-6);
    assert!(f[0].axis.cross(DVec3::Z).length() < 1e-9);
    assert!((f[0].height - 4.0).abs() < 1e-6);
}

#[test]
fn block_with_rectangular_pocket() {
    let f = recognise(
        r#"Part(name: "block", prisms: [
            Prism(id: "base", extent: (0.0, 5.0),
                  profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)))),
            Prism(id: "ring", extent: (5.0, 20.0),
                  profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)),
                            holes: [Rect(min: (10.0, 10.0), max: (50.0, 30.0))]))])"#,
    );
    assert_eq!(f.len(), 1, "{f:#?}");
    let p = &f[0];
    assert_eq!(p.kind, StiffnessKind::Pocket);
    assert_eq!(p.faces.len(), 5);
    assert!((p.axis - DVec3::Z).length() < 1e-9);
    assert_eq!(p.provenance.values["sides"], 4.0);
    assert_eq!(p.provenance.values["right_corners"], 1.0);
    let shape = p.shape.as_ref().unwrap();
    assert_eq!(shape.region.outer.vertices.len(), 4);
    assert!((shape.z_max - shape.z_min - 15.0).abs() < 1e-6);
    assert!((p.length - 40.0).abs() < 1e-6);
}

#[test]
fn block_with_through_step_and_slot() {
    // A step along one side and a slot across the top: 10 mm block.
    let f = recognise(
        r#"Part(name: "steps", prisms: [
            Prism(id: "base", extent: (0.0, 6.0),
                  profile: (outer: Rect(min: (0.0, 0.0), max: (40.0, 30.0)))),
            Prism(id: "a", extent: (6.0, 10.0),
                  profile: (outer: Rect(min: (5.0, 0.0), max: (15.0, 30.0)))),
            Prism(id: "b", extent: (6.0, 10.0),
                  profile: (outer: Rect(min: (20.0, 0.0), max: (40.0, 30.0))))])"#,
    );
    let kinds: Vec<(StiffnessKind, &str)> = f
        .iter()
        .map(|x| (x.kind, x.provenance.rule.as_str()))
        .collect();
    assert!(
        kinds.contains(&(StiffnessKind::Slot, "recognise.slot.through")),
        "{kinds:?}"
    );
    assert!(
        kinds.contains(&(StiffnessKind::Step, "recognise.step.through")),
        "{kinds:?}"
    );
}
