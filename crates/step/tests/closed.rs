//! Import checks: a solid must be closed and consistently oriented, its
//! units known. The damaged files are the box fixture edited as text.

mod common;

use thinplan_step::{read_step_bytes, read_step_file_with, Limits, StepErrorKind, StepModel};

use common::{check_brep, fixture};

fn text(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).unwrap()
}

fn read(t: &str) -> Result<StepModel, thinplan_step::StepError> {
    read_step_bytes(t.as_bytes(), &Limits::default())
}

fn edit(t: &str, from: &str, to: &str) -> String {
    assert!(t.contains(from), "fixture lacks {from}");
    t.replacen(from, to, 1)
}

/// Every edge used twice in opposite senses, plane faces counter-clockwise
/// about their normals, positive volume.
fn assert_consistent(m: &StepModel) {
    let b = &m.brep;
    assert!(check_brep(b).is_empty(), "{:?}", check_brep(b));
    let mut senses: std::collections::BTreeMap<usize, Vec<bool>> = Default::default();
    for f in &b.faces {
        for &l in &f.loops {
            let lp = &b.loops[l];
            for c in &lp.coedges {
                senses
                    .entry(c.edge)
                    .or_default()
                    .push(c.forward == lp.orientation);
            }
        }
    }
    for (e, s) in senses {
        assert!(s.len() == 2 && s[0] != s[1], "edge {e}: {s:?}");
    }
    assert!(b.volume() > 0.0, "volume {}", b.volume());
}

#[test]
fn valid_box_reads_without_warnings() {
    let m = read(&text("box_mm.step")).unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    assert_consistent(&m);
    assert!((m.brep.volume() - 6000.0).abs() < 1e-6);
}

#[test]
fn written_part_reads_back_without_warnings() {
    let dir = thinplan_testdata::repo_root().join("assets/parts");
    let part = thinplan_native::load_part(&dir.join("wall_holes.part.ron")).unwrap();
    let brep = part.build().unwrap();
    let t = thinplan_step::write_step(&brep, "wall_holes");
    let m = read(&t).unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    assert_consistent(&m);
}

#[test]
fn missing_face_is_an_error_naming_shell_and_edges() {
    let t = edit(
        &text("box_mm.step"),
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145,#157));",
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145));",
    );
    let e = read(&t).unwrap_err();
    let StepErrorKind::NotClosed { place, entity, .. } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!(place.id, Some(158));
    assert_eq!(entity, "CLOSED_SHELL of MANIFOLD_SOLID_BREP #159");
    let msg = e.to_string();
    // z+ is bounded by #45, #80, #65, #50.
    for edge in ["#45", "#50", "#65", "#80"] {
        assert!(
            msg.contains(&format!("edge {edge} used once (a face is missing)")),
            "{msg}"
        );
    }
    assert!(msg.contains("4 edges are not shared"), "{msg}");
    assert!(msg.contains("not a closed solid"), "{msg}");
}

#[test]
fn error_names_the_file() {
    let dir = std::env::temp_dir().join(format!("thinplan-step-closed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("open_box.step");
    let t = edit(&text("box_mm.step"), ",#157));", "));");
    std::fs::write(&path, t).unwrap();
    let e = thinplan_step::read_step_file(&path).unwrap_err();
    std::fs::remove_dir_all(&dir).ok();
    let msg = e.to_string();
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    assert!(msg.contains("#158"), "{msg}");
}

#[test]
fn face_bound_flipped_is_turned_over_with_a_warning() {
    let t = edit(
        &text("box_mm.step"),
        "#151=FACE_OUTER_BOUND('',#150,.T.);",
        "#151=FACE_OUTER_BOUND('',#150,.F.);",
    );
    let m = read(&t).unwrap();
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    assert!(w.contains("#158"), "{w}");
    assert!(
        w.contains("face #157 ran against all its neighbours; turned over"),
        "{w}"
    );
    assert_consistent(&m);
    assert!((m.brep.volume() - 6000.0).abs() < 1e-6);
}

#[test]
fn whole_face_flipped_is_turned_over_with_a_warning() {
    // Bound and same_sense both reversed: the face points inwards.
    let t = edit(
        &text("box_mm.step"),
        "#151=FACE_OUTER_BOUND('',#150,.T.);",
        "#151=FACE_OUTER_BOUND('',#150,.F.);",
    );
    let t = edit(
        &t,
        "#157=ADVANCED_FACE('z+',(#151),#156,.T.);",
        "#157=ADVANCED_FACE('z+',(#151),#156,.F.);",
    );
    let m = read(&t).unwrap();
    assert_eq!(m.warnings.len(), 2, "{:?}", m.warnings);
    assert!(
        m.warnings[0].contains("face #157 ran against"),
        "{:?}",
        m.warnings
    );
    assert!(
        m.warnings[1].contains("face #157 pointed against its bounds"),
        "{:?}",
        m.warnings
    );
    assert_consistent(&m);
    assert!((m.brep.volume() - 6000.0).abs() < 1e-6);
}

#[test]
fn same_sense_flag_flipped_is_turned_with_a_warning() {
    let t = edit(
        &text("box_mm.step"),
        "#157=ADVANCED_FACE('z+',(#151),#156,.T.);",
        "#157=ADVANCED_FACE('z+',(#151),#156,.F.);",
    );
    let m = read(&t).unwrap();
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    assert!(
        w.contains("#158") && w.contains("face #157 pointed against its bounds"),
        "{w}"
    );
    assert!(m.brep.faces[5].same_sense, "the flag is turned back");
    assert!((m.brep.volume() - 6000.0).abs() < 1e-6);
}

#[test]
fn flipped_curved_face_is_an_error_naming_it() {
    // The hole's two bounds reversed: its circles run with the plate's.
    let t = edit(
        &text("plate_hole.step"),
        "#188=FACE_OUTER_BOUND('',#187,.T.);",
        "#188=FACE_OUTER_BOUND('',#187,.F.);",
    );
    let t = edit(
        &t,
        "#190=FACE_BOUND('',#189,.T.);",
        "#190=FACE_BOUND('',#189,.F.);",
    );
    let e = read(&t).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e.kind, StepErrorKind::NotClosed { .. }), "{msg}");
    assert!(msg.contains("#192 (line"), "{msg}");
    assert!(
        msg.contains("used twice in the same sense (face #191 is flipped)"),
        "{msg}"
    );
    assert!(msg.contains("2 edges are not shared"), "{msg}");
}

#[test]
fn one_bound_of_a_face_flipped_is_an_error() {
    let t = edit(
        &text("plate_hole.step"),
        "#190=FACE_BOUND('',#189,.T.);",
        "#190=FACE_BOUND('',#189,.F.);",
    );
    let e = read(&t).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("1 edge is not shared"), "{msg}");
    assert!(
        msg.contains("used twice in the same sense (faces #"),
        "{msg}"
    );
    assert!(msg.contains("#191"), "{msg}");
}

#[test]
fn face_listed_twice_is_dropped_with_a_warning() {
    let t = edit(
        &text("box_mm.step"),
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145,#157));",
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145,#157,#121));",
    );
    let m = read(&t).unwrap();
    assert_eq!(
        m.warnings,
        ["#158 CLOSED_SHELL: face #121 listed twice; the repeat dropped"]
    );
    assert_eq!(m.brep.faces.len(), 6);
    assert_consistent(&m);
}

#[test]
fn face_listed_again_through_an_oriented_face_is_an_error() {
    let t = edit(
        &text("box_mm.step"),
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145,#157));",
        "CLOSED_SHELL('',(#97,#109,#121,#133,#145,#157,#9000));#9000=ORIENTED_FACE('',*,#157,.F.);",
    );
    let e = read(&t).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("edge #45 used 3 times (a face is listed twice"),
        "{msg}"
    );
}

#[test]
fn inside_out_shell_is_turned_over_with_a_warning() {
    // Every face reversed through ORIENTED_CLOSED_SHELL(.F.) of the box.
    let t = edit(
        &text("box_mm.step"),
        "#159=MANIFOLD_SOLID_BREP('box',#158);",
        "#159=MANIFOLD_SOLID_BREP('box',#9000);#9000=ORIENTED_CLOSED_SHELL('',*,#158,.F.);",
    );
    let m = read(&t).unwrap();
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    assert!(
        w.contains("#158 (line") && w.contains("all turned over"),
        "{w}"
    );
    assert_consistent(&m);
    assert!((m.brep.volume() - 6000.0).abs() < 1e-6);
}

#[test]
fn surface_model_that_closes_is_kept() {
    let t = edit(
        &text("box_mm.step"),
        "#159=MANIFOLD_SOLID_BREP('box',#158);",
        "#159=SHELL_BASED_SURFACE_MODEL('box',(#158));",
    );
    let m = read(&t).unwrap();
    assert!(m.brep.solids.is_empty());
    assert!(m.brep.shells[0].closed);
    assert!(
        m.warnings.iter().any(|w| w.contains("1 closed shell(s)")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn open_shell_beside_a_solid_is_a_warning() {
    let t = edit(
        &text("box_mm.step"),
        "#160=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#9,#159),#5);",
        "#160=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#9,#159,#9001),#5);\
         #9000=OPEN_SHELL('',(#157));#9001=SHELL_BASED_SURFACE_MODEL('',(#9000));",
    );
    let m = read(&t).unwrap();
    assert_eq!(m.brep.solids.len(), 1);
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("not closed") && w.contains("#9000")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn unknown_unit_name_is_an_error_naming_it() {
    let t = edit(
        &text("box_inch.step"),
        "#4=( CONVERSION_BASED_UNIT('INCH',#3) LENGTH_UNIT() NAMED_UNIT(#2) );",
        "#4=( CONVERSION_BASED_UNIT('FURLONG',$) LENGTH_UNIT() NAMED_UNIT(#2) );",
    );
    let e = read(&t).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.kind.place().and_then(|p| p.id), Some(4), "{msg}");
    assert!(msg.contains("unknown unit name 'FURLONG'"), "{msg}");
}

#[test]
fn zero_or_bad_unit_factor_is_an_error_naming_it() {
    for (value, says) in [
        (
            "0.",
            "conversion factor 0 of unit 'INCH' is not a positive number",
        ),
        ("-25.4", "conversion factor -25.4"),
    ] {
        let t = edit(
            &text("box_inch.step"),
            "LENGTH_MEASURE(25.4)",
            &format!("LENGTH_MEASURE({value})"),
        );
        let e = read(&t).unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.kind.place().and_then(|p| p.id), Some(3), "{msg}");
        assert!(msg.contains("LENGTH_MEASURE_WITH_UNIT"), "{msg}");
        assert!(msg.contains(says), "{msg}");
    }
    // A length SI unit that is no length.
    let t = edit(
        &text("box_mm.step"),
        "SI_UNIT(.MILLI.,.METRE.)",
        "SI_UNIT(.MILLI.,.GRAM.)",
    );
    let e = read(&t).unwrap_err();
    assert!(
        e.to_string().contains("#1 (line") && e.to_string().contains("unknown length unit .GRAM."),
        "{e}"
    );
}

#[test]
fn file_size_is_checked_before_reading() {
    let path = fixture("box_mm.step");
    let len = std::fs::metadata(&path).unwrap().len();
    let small = Limits {
        max_bytes: 100,
        ..Limits::default()
    };
    let e = read_step_file_with(&path, &small).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Limit { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains(&format!(
            "file is {len} bytes, more than the limit of 100 bytes"
        )),
        "{msg}"
    );
    assert!(msg.contains("box_mm.step"), "{msg}");
}

#[test]
fn absurd_bspline_is_bounded() {
    // A degree past the bound, and a net too big for the work budget.
    let t = text("box_mm.step").replace(
        "#96=PLANE('',#95);",
        "#96=B_SPLINE_SURFACE_WITH_KNOTS('',65,1,((#10,#12),(#14,#16)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);",
    );
    let e = read(&t).unwrap_err();
    assert!(e.to_string().contains("degree 65 out of range"), "{e}");
    let row = vec!["#10"; 400].join(",");
    let net = vec![format!("({row})"); 400].join(",");
    let t = text("box_mm.step").replace(
        "#96=PLANE('',#95);",
        &format!("#96=B_SPLINE_SURFACE_WITH_KNOTS('',3,3,({net}),.UNSPECIFIED.,.F.,.F.,.F.,(4,396,4),(4,396,4),(0.,0.5,1.),(0.,0.5,1.),.UNSPECIFIED.);"),
    );
    let small = Limits {
        max_work: 1_000_000,
        ..Limits::default()
    };
    let e = read_step_bytes(t.as_bytes(), &small).unwrap_err();
    assert!(matches!(e.kind, StepErrorKind::Limit { .. }), "{e}");
    // Knots that decrease would hang evaluation.
    let t = text("box_mm.step").replace(
        "#96=PLANE('',#95);",
        "#96=B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#10,#12),(#14,#16)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(1.,0.),(0.,1.),.UNSPECIFIED.);",
    );
    let e = read(&t).unwrap_err();
    assert!(
        e.to_string().contains("#96") && e.to_string().contains("knots decrease"),
        "{e}"
    );
}
