//! The G-code reader: every supported word, errors with places, no panics.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use thinplan_stocksim::gcode::{parse, parse_bytes, MoveKind, Spindle};

const FULL: &str = "%
O1234 (header)
N10 G21 G17 G90 G91.1 G94 G40 G49 G80 ; modal set-up
G64 P0.01 Q0.01
G55
T2 M6
G43 H2
S12000 M3 M8
G0 X0 Y0
G0 Z10
G1 Z-1 F300
G1 X10
G2 X20 Y0 I5 J0
G3 X30 Y0 R5
G91 G1 X5 Y5
G90 Z5
G20 G1 X1 Y1 F10
G21
M4
M5 M9
T1 M6
M30
G1 X999 (ignored after M30)
%
";

#[test]
fn reads_every_supported_word() {
    let p = parse(FULL, "full.ngc").unwrap();
    assert!(p.ended);
    assert_eq!(p.tool_changes, vec![(6, 2), (21, 1)]);
    let m = &p.moves;
    // G0 X0 Y0 (positioning, Z unknown), G0 Z10, G1 Z-1, G1 X10, G2, G3, G91 move, G90 Z5, G20 move.
    assert_eq!(m.len(), 9, "{m:#?}");
    assert!(m[0].positioning() && m[0].end.z.is_nan());
    assert!(m[1].positioning());
    assert_eq!(m[1].end, DVec3::new(0.0, 0.0, 10.0));
    assert_eq!(m[2].kind, MoveKind::Line);
    assert_eq!(m[2].feed, 300.0);
    assert_eq!(m[2].tool, Some(2));
    assert_eq!(m[2].spindle, Spindle::Cw);
    assert_eq!(m[2].line, 11);
    assert_eq!(m[3].end, DVec3::new(10.0, 0.0, -1.0));
    match m[4].kind {
        MoveKind::Arc { center, ccw, sweep } => {
            assert_eq!(center, DVec2::new(15.0, 0.0));
            assert!(!ccw);
            assert!((sweep + std::f64::consts::PI).abs() < 1e-12);
        }
        k => panic!("{k:?}"),
    }
    assert!((m[4].length() - 5.0 * std::f64::consts::PI).abs() < 1e-9);
    match m[5].kind {
        MoveKind::Arc { center, ccw, .. } => {
            assert!(ccw);
            assert!((center - DVec2::new(25.0, 0.0)).length() < 1e-9, "{center}");
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(m[6].end, DVec3::new(35.0, 5.0, -1.0));
    assert_eq!(m[7].end, DVec3::new(35.0, 5.0, 5.0));
    assert_eq!(m[8].end, DVec3::new(25.4, 25.4, 5.0));
    assert_eq!(m[8].feed, 254.0);
    let feed = p.feed_length();
    assert!(
        feed > 0.0 && p.rapid_length() == 0.0,
        "positioning moves count no length"
    );
}

#[test]
fn r_arcs_pick_the_right_side() {
    // Quarter arcs from (10,0) to (0,10): short way (R>0) and long way (R<0).
    for (g, r, centre) in [
        ("G3", "10", DVec2::ZERO),
        ("G2", "10", DVec2::new(10.0, 10.0)),
        ("G3", "-10", DVec2::new(10.0, 10.0)),
        ("G2", "-10", DVec2::ZERO),
    ] {
        let p = parse(&format!("G0 X10 Y0 Z0\n{g} X0 Y10 R{r} F100\n"), "r.ngc").unwrap();
        let MoveKind::Arc { center, sweep, .. } = p.moves[1].kind else {
            panic!()
        };
        assert!((center - centre).length() < 1e-9, "{g} R{r}: {center}");
        let expect = if r.starts_with('-') { 1.5 } else { 0.5 } * std::f64::consts::PI;
        assert!((sweep.abs() - expect).abs() < 1e-9, "{g} R{r}: {sweep}");
    }
    // A full circle by I/J.
    let p = parse("G0 X10 Y0 Z0\nG2 X10 Y0 I-10 J0 Z-1 F100\n", "c.ngc").unwrap();
    let MoveKind::Arc { sweep, .. } = p.moves[1].kind else {
        panic!()
    };
    assert!((sweep + std::f64::consts::TAU).abs() < 1e-12);
}

fn err(text: &str) -> (usize, usize, String) {
    let e = parse(text, "bad.ngc").unwrap_err();
    assert!(e.to_string().starts_with("bad.ngc:"), "{e}");
    (e.line, e.column, e.message)
}

#[test]
fn errors_name_line_and_column() {
    let cases: &[(&str, usize, usize, &str)] = &[
        ("G21\nG0 X0 Y0 Z0\nG28 Z0\n", 3, 1, "G28 is not supported"),
        ("G0 X1 Y2 Z3 A4\n", 1, 13, "axis `A`"),
        ("G0 X1\n  G1 Y\n", 2, 7, "needs a number"),
        ("G0 X0 (open comment\n", 1, 7, "not closed"),
        ("X1 Y1\n", 1, 1, "no motion mode"),
        ("G0 X0 Y0 Z0\nG1 X1\n", 2, 4, "no feed rate"),
        ("G0 G1 X1\n", 1, 4, "same modal group"),
        ("G91 G0 X1\n", 1, 8, "not yet known"),
        (
            "G0 X0 Y0 Z0\nG2 X10 Y0 I3 J0 F10\n",
            2,
            4,
            "differs from the radius",
        ),
        (
            "G0 X0 Y0 Z0\nG2 X10 Y0 R2 F10\n",
            2,
            11,
            "smaller than half the chord",
        ),
        ("G0 X0 Y0 Z0\nG2 X10 Y0 K3 F10\n", 2, 11, "`K`"),
        ("G0 X0 Y0 Z0\nG1 X1 I2 F10\n", 2, 7, "only read with G2/G3"),
        ("G1 X1 F10 F20\n", 1, 11, "twice"),
        ("M7\n", 1, 1, "M7 is not supported"),
        ("M6\n", 1, 1, "no tool selected"),
        ("G1 F-3\n", 1, 4, "negative feed"),
        ("H1\n", 1, 1, "without G43"),
        ("G0 X1 P3\n", 1, 7, "only read with G64"),
        ("G0 X1 $\n", 1, 7, "unexpected character"),
        ("G0 X1e5\n", 1, 6, "word `E` is not supported"),
        ("G0 X0 Y0 Z0\nG2 X10 Y0 F10\n", 2, 4, "needs `I`/`J`"),
        ("G0 X0 Y0 Z0\nG2 X0 Y0 R5 F10\n", 2, 10, "full circle"),
        ("G0 X0\nG1 X1 O5\n", 2, 7, "must start the line"),
        ("%garbage\n", 1, 2, "after `%`"),
        ("G1.5 X0\n", 1, 1, "G1.5 is not supported"),
        ("G0 X99999999999\n", 1, 5, "out of range"),
        ("T1.5 M6\n", 1, 1, "whole number"),
    ];
    let mut bad = Vec::new();
    for (text, line, col, msg) in cases {
        let (l, c, m) = err(text);
        if !m.contains(msg) || (l, c) != (*line, *col) {
            bad.push(format!("{text:?}: got {l}:{c} {m:?}"));
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn non_utf8_is_an_error_with_a_place() {
    let e = parse_bytes(b"G0 X0\nG1 \xff", "b.ngc").unwrap_err();
    assert_eq!((e.line, e.column), (2, 4));
}

#[test]
fn text_after_m2_and_closing_percent_is_ignored() {
    let p = parse("%\nG0 X0 Y0 Z0\n%\nthis is not gcode\n", "p.ngc").unwrap();
    assert_eq!(p.moves.len(), 1);
    let p = parse("G0 X0 Y0 Z0\nM2\n$$$\n", "p.ngc").unwrap();
    assert!(p.ended);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse_bytes(&bytes, "fuzz.ngc");
    }

    #[test]
    fn gcode_like_text_never_panics(s in "[GMXYZIJRFSTHPQNO0-9 .+\\-;()%\n]{0,300}") {
        let _ = parse(&s, "fuzz.ngc");
    }

    #[test]
    fn mutations_never_panic(pos in 0usize..FULL.len(), len in 0usize..8, with in "[ -~\n]{0,8}") {
        let mut s = FULL.as_bytes().to_vec();
        let end = (pos + len).min(s.len());
        s.splice(pos..end, with.bytes());
        let _ = parse_bytes(&s, "mut.ngc");
    }
}
