//! Hand-written fixtures: counts, units, placements and error kinds.

mod common;

use std::collections::BTreeSet;

use glam::DVec3;
use thinplan_brep::{Brep, Curve, Surface};
use thinplan_step::{read_step_bytes, read_step_file, Limits, StepErrorKind, StepModel};

use common::{check_brep, fixture};

fn read(name: &str) -> StepModel {
    match read_step_file(&fixture(name)) {
        Ok(m) => m,
        Err(e) => panic!("{name}: {e}"),
    }
}

fn read_str(text: &str) -> Result<StepModel, thinplan_step::StepError> {
    read_step_bytes(text.as_bytes(), &Limits::default())
}

fn box_text() -> String {
    std::fs::read_to_string(fixture("box_mm.step")).unwrap()
}

/// Rounded vertex coordinates of a solid (through its faces' loops).
fn solid_points(b: &Brep, solid: usize) -> BTreeSet<[i64; 3]> {
    let mut out = BTreeSet::new();
    for f in b.solid_faces(solid) {
        for &l in &b.faces[f].loops {
            for ce in &b.loops[l].coedges {
                let e = &b.edges[ce.edge];
                for v in [e.start, e.end] {
                    out.insert(key(b.vertices[v].point));
                }
            }
        }
    }
    out
}

fn key(p: DVec3) -> [i64; 3] {
    [
        (p.x * 1e6).round() as i64,
        (p.y * 1e6).round() as i64,
        (p.z * 1e6).round() as i64,
    ]
}

fn box_corners(t: impl Fn(DVec3) -> DVec3) -> BTreeSet<[i64; 3]> {
    let mut s = BTreeSet::new();
    for i in 0..2 {
        for j in 0..2 {
            for k in 0..2 {
                let p = DVec3::new(10.0 * i as f64, 20.0 * j as f64, 30.0 * k as f64);
                s.insert(key(t(p)));
            }
        }
    }
    s
}

fn assert_box_10_20_30(m: &StepModel) {
    let b = &m.brep;
    assert_eq!(b.solids.len(), 1);
    assert_eq!(b.shells.len(), 1);
    assert!(b.shells[0].closed);
    assert_eq!(b.faces.len(), 6);
    assert_eq!(b.edges.len(), 12);
    assert_eq!(b.vertices.len(), 8);
    assert_eq!(b.loops.len(), 6);
    assert_eq!(b.loops.iter().map(|l| l.coedges.len()).sum::<usize>(), 24);
    assert!(b.loops.iter().all(|l| l.outer));
    assert_eq!(solid_points(b, 0), box_corners(|p| p));
    for v in &b.vertices {
        for c in v.point.to_array() {
            let nearest = [0.0, 10.0, 20.0, 30.0]
                .iter()
                .map(|x| (c - x).abs())
                .fold(f64::MAX, f64::min);
            assert!(nearest < 1e-9, "coordinate {c} not scaled to mm");
        }
    }
    let names: Vec<&str> = b.faces.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["x-", "x+", "y-", "y+", "z-", "z+"]);
    assert!(check_brep(b).is_empty(), "{:?}", check_brep(b));
    assert_eq!(b.face_kind_counts().plane, 6);
}

#[test]
fn box_in_millimetres() {
    let m = read("box_mm.step");
    assert_eq!(m.units, "mm");
    assert_eq!(m.schema, "AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }");
    assert_box_10_20_30(&m);
    assert_eq!(m.brep.solids[0].name, "box");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
}

#[test]
fn box_in_metres_is_scaled_to_mm() {
    let m = read("box_m.step");
    assert_eq!(m.units, "m");
    assert_box_10_20_30(&m);
}

#[test]
fn box_in_inches_is_scaled_to_mm() {
    let m = read("box_inch.step");
    assert_eq!(m.units, "inch");
    assert_box_10_20_30(&m);
    // The planes' origins are scaled too.
    for f in &m.brep.faces {
        let Surface::Plane { frame } = &f.surface else {
            panic!()
        };
        for c in frame.origin.to_array() {
            assert!([0.0, 10.0, 20.0, 30.0].iter().any(|x| (c - x).abs() < 1e-9));
        }
    }
}

#[test]
fn empty_lists_are_accepted() {
    let text = std::fs::read_to_string(fixture("empty_lists.step")).unwrap();
    assert!(text.contains("FILE_DESCRIPTION((),"));
    assert!(text.contains(",());"));
    let m = read("empty_lists.step");
    assert_box_10_20_30(&m);
}

#[test]
fn plate_with_closed_circle_edges() {
    let m = read("plate_hole.step");
    let b = &m.brep;
    assert_eq!(b.solids.len(), 1);
    assert_eq!(b.faces.len(), 7);
    assert_eq!(b.edges.len(), 14);
    assert_eq!(b.vertices.len(), 10);
    let closed: Vec<_> = b.edges.iter().filter(|e| e.is_closed()).collect();
    assert_eq!(closed.len(), 2);
    for e in closed {
        let Curve::Circle { frame, radius } = &e.curve else {
            panic!("closed edge is not a circle")
        };
        assert!((radius - 10.0).abs() < 1e-12);
        assert!((frame.origin.truncate() - glam::DVec2::new(50.0, 30.0)).length() < 1e-12);
        let p = b.vertices[e.start].point;
        assert!(((p - frame.origin).length() - 10.0).abs() < 1e-9);
    }
    let hole = b.faces.iter().find(|f| f.name == "hole").unwrap();
    assert!(
        matches!(hole.surface, Surface::Cylinder { radius, .. } if (radius - 10.0).abs() < 1e-12)
    );
    assert!(!hole.same_sense);
    assert_eq!(hole.loops.len(), 2);
    let top = b.faces.iter().find(|f| f.name == "top").unwrap();
    assert_eq!(top.loops.len(), 2);
    assert!(b.loops[top.loops[0]].outer && !b.loops[top.loops[1]].outer);
    assert!(check_brep(b).is_empty(), "{:?}", check_brep(b));
    let k = b.face_kind_counts();
    assert_eq!((k.plane, k.cylinder), (6, 1));
}

#[test]
fn cone_semi_angle_in_degrees_is_converted() {
    let m = read("cone_degrees.step");
    let b = &m.brep;
    assert_eq!(b.faces.len(), 3);
    let cone = b
        .faces
        .iter()
        .find_map(|f| match f.surface {
            Surface::Cone {
                radius, semi_angle, ..
            } => Some((radius, semi_angle)),
            _ => None,
        })
        .unwrap();
    assert!((cone.0 - 10.0).abs() < 1e-12);
    assert!(
        (cone.1 - std::f64::consts::FRAC_PI_4).abs() < 1e-9,
        "{}",
        cone.1
    );
    assert!(check_brep(b).is_empty(), "{:?}", check_brep(b));
    assert_eq!(b.edges.iter().filter(|e| e.is_closed()).count(), 2);
}

#[test]
fn nested_assembly_places_every_instance() {
    let m = read("assembly_nested.step");
    let b = &m.brep;
    assert_eq!(b.solids.len(), 3, "{:?}", m.warnings);
    assert_eq!(b.faces.len(), 18);
    assert!(check_brep(b).is_empty());
    // Expected placements, written out independently of the reader.
    let expected = [
        // SUB at (0,0,200); box translated (100,0,0) in SUB.
        box_corners(|p| p + DVec3::new(100.0, 0.0, 200.0)),
        // SUB at (0,0,200); box turned 90 degrees about z, then moved to (0,50,0).
        box_corners(|p| DVec3::new(-p.y, p.x, p.z) + DVec3::new(0.0, 50.0, 200.0)),
        // Mapped item: origin (5,0,0) onto target (-50,0,0).
        box_corners(|p| p + DVec3::new(-55.0, 0.0, 0.0)),
    ];
    let mut got: Vec<_> = (0..3).map(|s| solid_points(b, s)).collect();
    for (i, e) in expected.iter().enumerate() {
        let pos = got.iter().position(|g| g == e);
        assert!(pos.is_some(), "instance {i} not found; got {got:?}");
        got.remove(pos.unwrap());
    }
    // A rotated instance keeps its analytic geometry consistent.
    let rotated = (0..3).find(|&s| solid_points(b, s) == expected[1]).unwrap();
    for f in b.solid_faces(rotated) {
        let Surface::Plane { frame } = &b.faces[f].surface else {
            panic!()
        };
        for &l in &b.faces[f].loops {
            for ce in &b.loops[l].coedges {
                let p = b.vertices[b.edges[ce.edge].start].point;
                assert!((p - frame.origin).dot(frame.z).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn surface_only_file_is_not_a_solid() {
    // One open sheet: not a part to plan.
    let e = read_step_file(&fixture("surface_only.step")).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::NoSolid { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("surface_only.step"), "{msg}");
    assert!(
        msg.contains("#46 (line") && msg.contains("OPEN_SHELL of SHELL_BASED_SURFACE_MODEL #47"),
        "{msg}"
    );
    assert!(
        msg.contains("edge #18 used once (a face is missing)"),
        "{msg}"
    );
}

#[test]
fn tessellated_only_file_has_no_solid() {
    let e = read_step_file(&fixture("tessellated_only.step")).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::NoSolid { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("no solid in this file"), "{msg}");
    assert!(msg.contains("tessellated_only.step"), "{msg}");
}

#[test]
fn product_only_file_has_no_solid() {
    let text = "ISO-10303-21;HEADER;FILE_SCHEMA(('X'));ENDSEC;DATA;#1=PRODUCT('a','a','',());ENDSEC;END-ISO-10303-21;";
    let e = read_str(text).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::NoSolid { .. }), "{e}");
}

#[test]
fn truncated_file_is_a_syntax_error_with_its_place() {
    let e = read_step_file(&fixture("broken_truncated.step")).unwrap_err();
    let StepErrorKind::Syntax { place, reason } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(place.line, 39);
    assert!(reason.contains("end of file"), "{reason}");
    let msg = e.to_string();
    assert!(msg.contains("broken_truncated.step"), "{msg}");
    assert!(msg.contains("line 39"), "{msg}");
}

#[test]
fn dangling_reference_names_both_ends() {
    let e = read_step_file(&fixture("broken_dangling.step")).unwrap_err();
    let StepErrorKind::Dangling { place, target } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(*target, 99999);
    assert_eq!(place.id, Some(11));
    assert_eq!(place.line, 20);
    let msg = e.to_string();
    assert!(
        msg.contains("#11") && msg.contains("refers to #99999 which does not exist"),
        "{msg}"
    );
}

#[test]
fn cyclic_curve_references_are_an_error() {
    let e = read_step_file(&fixture("broken_cyclic.step")).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Cyclic { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("#29") || msg.contains("#170"), "{msg}");
}

#[test]
fn cyclic_assembly_is_an_error() {
    let e = read_step_file(&fixture("cyclic_assembly.step")).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Cyclic { .. }), "{e}");
}

#[test]
fn cyclic_oriented_edges_are_an_error() {
    let t = box_text().replace(
        "#30=EDGE_CURVE('',#11,#19,#29,.T.);",
        "#30=EDGE_CURVE('',#11,#19,#29,.T.);#9001=ORIENTED_EDGE('',*,*,#9002,.T.);#9002=ORIENTED_EDGE('',*,*,#9001,.T.);",
    );
    // Point the first loop's first oriented edge at the cycle.
    let t = t.replacen("EDGE_LOOP('',(#", "EDGE_LOOP('',(#9001,#", 1);
    let e = read_str(&t).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Cyclic { .. }), "{e}");
}

#[test]
fn wrong_parameter_type_names_the_entity() {
    let t = box_text().replace(
        "#30=EDGE_CURVE('',#11,#19,#29,.T.);",
        "#30=EDGE_CURVE('',#11,#19,#29,5);",
    );
    let e = read_str(&t).unwrap_err();
    let StepErrorKind::WrongParameter { place, entity, .. } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(place.id, Some(30));
    assert_eq!(entity, "EDGE_CURVE");
    let t = box_text().replace("#29=LINE('',#28,#27);", "#29=LINE('',#28);");
    let e = read_str(&t).unwrap_err();
    assert!(e.to_string().contains("#29"), "{e}");
}

#[test]
fn unknown_curve_becomes_a_polyline_through_its_vertices() {
    let t = box_text().replace("#29=LINE('',#28,#27);", "#29=HYPERBOLA('',#9,5.,3.);");
    let m = read_str(&t).unwrap();
    assert!(
        m.warnings.iter().any(|w| w.contains("HYPERBOLA")),
        "{:?}",
        m.warnings
    );
    let b = &m.brep;
    let e = b
        .edges
        .iter()
        .find(|e| matches!(e.curve, Curve::Polyline { .. }))
        .unwrap();
    let Curve::Polyline { points } = &e.curve else {
        unreachable!()
    };
    assert_eq!(
        points,
        &[b.vertices[e.start].point, b.vertices[e.end].point]
    );
    assert_eq!(points[1], DVec3::new(10.0, 0.0, 0.0));
}

#[test]
fn bspline_curves_simple_and_rational() {
    let t = box_text().replace(
        "#29=LINE('',#28,#27);",
        "#29=B_SPLINE_CURVE_WITH_KNOTS('',1,(#10,#18),.POLYLINE_FORM.,.F.,.F.,(2,2),(0.,1.),.UNSPECIFIED.);",
    );
    let m = read_str(&t).unwrap();
    let c = m
        .brep
        .edges
        .iter()
        .find(|e| matches!(e.curve, Curve::BSpline { .. }))
        .unwrap();
    let Curve::BSpline {
        degree,
        control_points,
        knots,
        weights,
    } = &c.curve
    else {
        unreachable!()
    };
    assert_eq!(*degree, 1);
    assert_eq!(control_points, &[DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)]);
    assert_eq!(knots, &[0.0, 0.0, 1.0, 1.0]);
    assert!(weights.is_empty());

    let t = box_text().replace(
        "#29=LINE('',#28,#27);",
        "#29=( BOUNDED_CURVE() B_SPLINE_CURVE(2,(#10,#28,#18),.UNSPECIFIED.,.F.,.F.) \
         B_SPLINE_CURVE_WITH_KNOTS((3,3),(0.,2.),.UNSPECIFIED.) CURVE() GEOMETRIC_REPRESENTATION_ITEM() \
         RATIONAL_B_SPLINE_CURVE((1.,0.5,1.)) REPRESENTATION_ITEM('') );",
    );
    let m = read_str(&t).unwrap();
    let c = m
        .brep
        .edges
        .iter()
        .find(|e| matches!(e.curve, Curve::BSpline { .. }))
        .unwrap();
    let Curve::BSpline {
        degree,
        knots,
        weights,
        ..
    } = &c.curve
    else {
        unreachable!()
    };
    assert_eq!(*degree, 2);
    assert_eq!(knots, &[0.0, 0.0, 0.0, 2.0, 2.0, 2.0]);
    assert_eq!(weights, &[1.0, 0.5, 1.0]);
}

#[test]
fn surfaces_of_every_supported_kind() {
    let cases = [
        ("B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#10,#12),(#14,#16)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.)", "bspline"),
        ("( BOUNDED_SURFACE() B_SPLINE_SURFACE(1,1,((#10,#12),(#14,#16)),.UNSPECIFIED.,.F.,.F.,.F.) B_SPLINE_SURFACE_WITH_KNOTS((2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.) GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(((1.,1.),(1.,2.))) REPRESENTATION_ITEM('') SURFACE() )", "bspline"),
        ("CYLINDRICAL_SURFACE('',#95,2.5)", "cylinder"),
        ("CONICAL_SURFACE('',#95,2.5,0.3)", "cone"),
        ("SPHERICAL_SURFACE('',#95,2.5)", "sphere"),
        ("TOROIDAL_SURFACE('',#95,5.,1.)", "torus"),
        ("SURFACE_OF_LINEAR_EXTRUSION('',#29,#27)", "other"),
        ("SURFACE_OF_REVOLUTION('',#29,#9100)", "other"),
        ("OFFSET_SURFACE('',#9101,1.,.F.)", "other"),
    ];
    for (text, kind) in cases {
        let t = box_text()
            .replace("#96=PLANE('',#95);", &format!("#96={text};"))
            .replace(
                "ENDSEC;\nEND",
                "#9100=AXIS1_PLACEMENT('',#6,#7);\n#9101=PLANE('',#95);\nENDSEC;\nEND",
            );
        let m = read_str(&t).unwrap_or_else(|e| panic!("{text}: {e}"));
        let s = &m
            .brep
            .faces
            .iter()
            .find(|f| !matches!(f.surface, Surface::Plane { .. }))
            .unwrap()
            .surface;
        assert_eq!(s.kind_name(), kind, "{text}");
        match s {
            Surface::BSpline {
                u_knots,
                v_knots,
                control_points,
                weights,
                ..
            } => {
                assert_eq!(u_knots, &[0.0, 0.0, 1.0, 1.0]);
                assert_eq!(v_knots, &[0.0, 0.0, 1.0, 1.0]);
                assert_eq!(control_points.len(), 2);
                assert_eq!(control_points[1][1], DVec3::new(0.0, 20.0, 30.0));
                assert!(weights.is_empty() || weights[1][1] == 2.0);
            }
            Surface::Extrusion { dir, .. } => assert_eq!(*dir, DVec3::X),
            Surface::Revolution { axis_dir, .. } => assert_eq!(*axis_dir, DVec3::Z),
            Surface::Other { kind } => assert_eq!(kind, "OFFSET_SURFACE"),
            _ => {}
        }
    }
}

#[test]
fn bounded_limits_end_in_errors() {
    let t = box_text();
    let small = Limits {
        max_bytes: 100,
        ..Limits::default()
    };
    assert!(matches!(
        read_step_bytes(t.as_bytes(), &small).unwrap_err().kind,
        StepErrorKind::Limit { .. }
    ));
    let small = Limits {
        max_entities: 10,
        ..Limits::default()
    };
    assert!(matches!(
        read_step_bytes(t.as_bytes(), &small).unwrap_err().kind,
        StepErrorKind::Limit { .. }
    ));
    let small = Limits {
        max_work: 50,
        ..Limits::default()
    };
    assert!(matches!(
        read_step_bytes(t.as_bytes(), &small).unwrap_err().kind,
        StepErrorKind::Limit { .. }
    ));
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = read_step_file(&fixture("no_such_file.step")).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Io(_)));
    assert!(e.to_string().contains("no_such_file.step"));
}

#[test]
fn unsupported_topology_and_wrong_kinds_are_told_apart() {
    let t = box_text().replace(
        "#30=EDGE_CURVE('',#11,#19,#29,.T.);",
        "#30=SUBEDGE('',#11,#19,#9200);#9200=EDGE_CURVE('',#11,#19,#29,.T.);",
    );
    let e = read_str(&t).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Unsupported { .. }), "{e}");
    assert!(
        e.to_string().contains("#30") && e.to_string().contains("SUBEDGE"),
        "{e}"
    );
    // A point where a face belongs.
    let t = box_text().replacen("CLOSED_SHELL('',(#", "CLOSED_SHELL('',(#10,#", 1);
    let e = read_str(&t).unwrap_err();
    let StepErrorKind::WrongParameter {
        place,
        entity,
        reason,
    } = &e.kind
    else {
        panic!("{e}")
    };
    assert_eq!(place.id, Some(10));
    assert_eq!(entity, "CARTESIAN_POINT");
    assert!(reason.contains("expected a face"), "{reason}");
}
