//! Bad inputs give the right error kind, with file/line/column where it
//! applies, and never panic.

use proptest::prelude::*;
use thinplan_native::{parse_labels, parse_part, NativeError};

const GOOD: &str = r#"Part(
    name: "t",
    prisms: [
        Prism(id: "web", extent: (0.0, 2.0),
              profile: (outer: Rect(min: (0.0, 0.0), max: (100.0, 50.0)))),
        Prism(id: "rib", frame: (origin: (0.0, 25.0, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
              extent: (-1.0, 1.0),
              profile: (outer: Rect(min: (10.0, 2.0), max: (90.0, 30.0)))),
    ],
)"#;

fn build(text: &str) -> Result<thinplan_brep::Brep, NativeError> {
    parse_part(text, "test.part.ron")?.build()
}

fn web_and(extra: &str) -> String {
    format!(
        r#"Part(name: "t", prisms: [
            Prism(id: "web", extent: (0.0, 2.0), profile: (outer: Rect(min: (0.0, 0.0), max: (100.0, 50.0)))),
            {extra}
        ])"#
    )
}

#[test]
fn good_builds() {
    build(GOOD).unwrap();
}

#[test]
fn syntax_error_has_line_and_column() {
    let bad = GOOD.replace("extent: (-1.0, 1.0),", "extent: (-1.0, 1.0)");
    let e = build(&bad).unwrap_err();
    assert_eq!(e.kind(), "syntax");
    let NativeError::Syntax { line, column, .. } = &e else {
        unreachable!()
    };
    // The comma is missing at the end of line 7; ron reports the token after it.
    assert_eq!((*line, *column), (8, 15), "{e}");
    let msg = e.to_string();
    assert!(msg.starts_with("test.part.ron:8:15: "), "{msg}");
}

#[test]
fn unknown_field_is_rejected() {
    let bad = GOOD.replace("extent: (0.0, 2.0)", "extent: (0.0, 2.0), thikness: 3.0");
    let e = build(&bad).unwrap_err();
    assert_eq!(e.kind(), "syntax");
    assert!(e.to_string().contains("thikness"), "{e}");
    // Also inside enum variants and frames.
    let bad = GOOD.replace("Rect(min: (0.0, 0.0),", "Rect(minn: (0.0, 0.0),");
    assert_eq!(build(&bad).unwrap_err().kind(), "syntax");
    let bad = GOOD.replace("x_dir: (1.0, 0.0, 0.0)", "xdir: (1.0, 0.0, 0.0)");
    assert_eq!(build(&bad).unwrap_err().kind(), "syntax");
}

#[test]
fn overlapping_prisms_are_rejected() {
    // A rib sunk 1 mm into the web (perpendicular prisms).
    let bad = GOOD.replace("min: (10.0, 2.0)", "min: (10.0, 1.0)");
    let e = build(&bad).unwrap_err();
    assert_eq!(e.kind(), "overlap", "{e}");
    assert!(
        e.to_string().contains("`web`") && e.to_string().contains("`rib`"),
        "{e}"
    );
    // Two parallel blocks sharing volume.
    let e = build(&web_and(
        r#"Prism(id: "boss", extent: (1.0, 10.0), profile: (outer: Circle(centre: (50.0, 25.0), radius: 5.0)))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "overlap", "{e}");
    // Coplanar same-direction faces covering each other (stacked equal blocks offset).
    let e = build(&web_and(
        r#"Prism(id: "web2", extent: (0.0, 2.0), profile: (outer: Rect(min: (50.0, 0.0), max: (150.0, 50.0))))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "overlap", "{e}");
}

#[test]
fn touching_prisms_build() {
    // A boss on the web, a block beside it, a second web piece sharing a side.
    let ok = web_and(
        r#"Prism(id: "boss", extent: (2.0, 10.0), profile: (outer: Circle(centre: (50.0, 25.0), radius: 5.0))),
           Prism(id: "web2", extent: (0.0, 2.0), profile: (outer: Rect(min: (100.0, 0.0), max: (150.0, 50.0))))"#,
    );
    let b = build(&ok).unwrap();
    // web + web2 merge: one bottom face, one top face (with the boss footprint).
    let bottoms = b.faces.iter().filter(|f| f.name.contains("bottom")).count();
    assert_eq!(bottoms, 1);
}

#[test]
fn self_intersecting_profile() {
    let e = build(&web_and(
        r#"Prism(id: "bow", extent: (2.0, 5.0), profile: (outer: Polygon(points: [(10.0, 10.0), (40.0, 10.0), (40.0, 20.0), (25.0, 5.0), (10.0, 20.0)])))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "bad_profile", "{e}");
    assert!(e.to_string().contains("`bow`"), "{e}");
    assert!(e.to_string().contains("intersects itself"), "{e}");
}

#[test]
fn bad_profiles() {
    let cases = [
        // Path that does not close.
        (
            r#"Path(start: (10.0, 10.0), segments: [Line(to: (20.0, 10.0)), Line(to: (20.0, 20.0))])"#,
            "does not close",
        ),
        // Arc whose end is not on its circle.
        (
            r#"Path(start: (10.0, 10.0), segments: [Line(to: (20.0, 10.0)), Arc(to: (10.0, 10.0), centre: (14.0, 14.0), ccw: true)])"#,
            "not on its circle",
        ),
        // Zero area.
        (
            r#"Path(start: (10.0, 10.0), segments: [Line(to: (20.0, 10.0)), Line(to: (10.0, 10.0))])"#,
            "zero area",
        ),
        (r#"Rect(min: (10.0, 10.0), max: (10.0, 20.0))"#, "max > min"),
        (r#"Circle(centre: (10.0, 10.0), radius: 0.0)"#, "radius"),
        (
            r#"Polygon(points: [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)], radius: 20.0)"#,
            "does not fit",
        ),
    ];
    for (outer, why) in cases {
        let e = build(&web_and(&format!(
            r#"Prism(id: "p", extent: (2.0, 5.0), profile: (outer: {outer}))"#
        )))
        .unwrap_err();
        assert_eq!(e.kind(), "bad_profile", "{outer}: {e}");
        assert!(e.to_string().contains(why), "{outer}: {e}");
    }
    // Holes crossing the outer loop or each other.
    let e = build(&web_and(
        r#"Prism(id: "p", extent: (2.0, 5.0), profile: (outer: Rect(min: (10.0, 10.0), max: (40.0, 40.0)),
           holes: [Circle(centre: (10.0, 25.0), radius: 3.0)]))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "bad_profile", "{e}");
    let e = build(&web_and(
        r#"Prism(id: "p", extent: (2.0, 5.0), profile: (outer: Rect(min: (10.0, 10.0), max: (40.0, 40.0)),
           holes: [Circle(centre: (20.0, 25.0), radius: 3.0), Circle(centre: (23.0, 25.0), radius: 3.0)]))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "bad_profile", "{e}");
}

#[test]
fn bad_prisms() {
    let e = build(&GOOD.replace("id: \"rib\"", "id: \"web\"")).unwrap_err();
    assert_eq!(e.kind(), "bad_prism");
    let e = build(&GOOD.replace("extent: (0.0, 2.0)", "extent: (2.0, 2.0)")).unwrap_err();
    assert_eq!(e.kind(), "bad_prism");
    let e = build(&GOOD.replace("y_dir: (0.0, 0.0, 1.0)", "y_dir: (1.0, 0.0, 1.0)")).unwrap_err();
    assert_eq!(e.kind(), "bad_prism");
}

#[test]
fn disconnected_or_edge_touching_prisms() {
    // A block floating above the web.
    let e = build(&web_and(
        r#"Prism(id: "float", extent: (5.0, 8.0), profile: (outer: Rect(min: (10.0, 10.0), max: (20.0, 20.0))))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "invalid_shell", "{e}");
    // A block touching the web along an edge only.
    let e = build(&web_and(
        r#"Prism(id: "edge", extent: (2.0, 8.0), profile: (outer: Rect(min: (100.0, 10.0), max: (120.0, 20.0))))"#,
    ))
    .unwrap_err();
    assert_eq!(e.kind(), "invalid_shell", "{e}");
}

#[test]
fn oblique_prisms() {
    // A rib at an oblique angle standing on the web builds (the union itself
    // works at any angle) …
    let rib = |z0: f64| {
        web_and(&format!(
            r#"Prism(id: "skew", frame: (origin: (50.0, 25.0, 0.0), x_dir: (0.8, 0.6, 0.0), y_dir: (0.0, 0.0, 1.0)),
           extent: (-1.0, 1.0), profile: (outer: Rect(min: (-10.0, {z0}), max: (10.0, 10.0))))"#
        ))
    };
    let b = build(&rib(2.0)).unwrap();
    assert_eq!(b.faces.len(), 11);
    // Sunk into the web it overlaps (the web and the rib are perpendicular).
    let e = build(&rib(1.0)).unwrap_err();
    assert_eq!(e.kind(), "overlap", "{e}");
    // Two ribs at 53° whose boxes meet: the overlap check cannot decide at
    // that angle and says so.
    let two = rib(2.0).replace(
        "])",
        r#", Prism(id: "straight", frame: (origin: (0.0, 25.0, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
           extent: (-1.0, 1.0), profile: (outer: Rect(min: (45.0, 2.0), max: (90.0, 10.0))))])"#,
    );
    let e = build(&two).unwrap_err();
    assert_eq!(e.kind(), "unsupported", "{e}");
}

#[test]
fn labels_errors() {
    let e = parse_labels(
        r#"Labels(features: [Feature(id: "a", kind: wall), Feature(id: "a", kind: hole)])"#,
        "x.labels.ron",
    )
    .unwrap_err();
    assert_eq!(e.kind(), "bad_labels");
    let e = parse_labels(
        r#"Labels(features: [Feature(id: "a", kind: wall)], connections: [Connection(base: "a", leaf: "b", kind: crossing)])"#,
        "x.labels.ron",
    )
    .unwrap_err();
    assert_eq!(e.kind(), "bad_labels");
    let e = parse_labels(
        r#"Labels(features: [Feature(id: "a", kind: wal)])"#,
        "x.labels.ron",
    )
    .unwrap_err();
    assert_eq!(e.kind(), "syntax");
    let e = parse_labels(
        r#"Labels(features: [Feature(id: "a", kind: wall, colour: 3)])"#,
        "x.labels.ron",
    )
    .unwrap_err();
    assert_eq!(e.kind(), "syntax");
    let e =
        thinplan_native::load_part(std::path::Path::new("/nonexistent/x.part.ron")).unwrap_err();
    assert_eq!(e.kind(), "io");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Mangled files (bytes cut, replaced or inserted) never panic.
    #[test]
    fn mangled_files_never_panic(pos in 0usize..GOOD.len(), len in 0usize..8, ins in "[-(),.:0-9a-z\" ]{0,6}") {
        let mut s: String = GOOD.chars().take(pos).collect();
        s.push_str(&ins);
        s.extend(GOOD.chars().skip(pos + len));
        let _ = build(&s);
    }

    /// Random numbers in the geometry never panic.
    #[test]
    fn random_numbers_never_panic(a in -200.0f64..200.0, b in -200.0f64..200.0, c in -5.0f64..40.0, d in -5.0f64..40.0) {
        let s = GOOD.replace("min: (10.0, 2.0), max: (90.0, 30.0)", &format!("min: ({a}, {c}), max: ({b}, {d})"));
        let _ = build(&s);
    }
}

#[test]
fn floor_fillet_prism_merges_with_rib_ends() {
    // A square-minus-quarter-circle prism along the foot of the rib.
    let text = GOOD.replace(
        "    ],\n)",
        r#"        Prism(id: "fillet", frame: (x_dir: (0.0, 1.0, 0.0), y_dir: (0.0, 0.0, 1.0)), extent: (10.0, 90.0),
              profile: (outer: Path(start: (26.0, 2.0), segments: [Line(to: (29.0, 2.0)),
                  Arc(to: (26.0, 5.0), centre: (29.0, 5.0), ccw: false, name: "round"), Line(to: (26.0, 2.0))]))),
    ],
)"#,
    );
    let b = build(&text).unwrap();
    let c = b.face_kind_counts();
    // web 6 + rib 5 (its two ends merged with the fillet's caps) = 11 planes.
    assert_eq!((c.plane, c.cylinder), (11, 1));
    let round = b.faces.iter().find(|f| f.name == "fillet.round").unwrap();
    assert!(!round.same_sense, "a concave fillet faces its axis");
    assert!(b.faces.iter().any(|f| f.name == "rib.e1+fillet.top"));
}
