//! The move checks of the verification stage: straight plunges into solid
//! stock and cuts deeper than the flutes are crashes; ramps within the
//! entry limit, descents in air and cuts within the flutes are not.

use glam::DVec3;
use thinplan_stocksim::{parse, parse_tool_table, Blank, CrashKind, MoveChecks, ZMap};

/// A 40 × 40 × 30 block, cells of 0.5 mm.
fn block() -> ZMap {
    ZMap::new(
        Blank {
            min: DVec3::ZERO,
            max: DVec3::new(40.0, 40.0, 30.0),
        },
        0.5,
    )
    .unwrap()
}

fn checks(flute: f64) -> MoveChecks {
    MoveChecks {
        flute_length: [(1, flute)].into_iter().collect(),
        max_descent_deg: Some(45.0),
        max_plunge_mm3: 0.5,
        tol: 0.05,
        rim: 0.0,
        operations: Vec::new(),
    }
}

fn crashes(body: &str, c: &MoveChecks) -> Vec<CrashKind> {
    crashes_on(block(), body, c)
}

fn crashes_on(mut z: ZMap, body: &str, c: &MoveChecks) -> Vec<CrashKind> {
    let text = format!("G21 G90 G17\nT1 M6\nS10000 M3\n{body}\nM5\nM30\n");
    let prog = parse(&text, "t.ngc").unwrap();
    let tools = parse_tool_table("T1 P1 D10 ;em10 r0.5\n", "t.tbl").unwrap();
    let rs = z.replay_checked(&prog, &tools, c).unwrap();
    rs.crashes.iter().map(|c| c.kind).collect()
}

#[test]
fn straight_plunge_into_solid_stock_is_a_crash() {
    let k = crashes("G0 X20 Y20 Z40\nG1 Z25 F500", &checks(30.0));
    assert_eq!(k, vec![CrashKind::PlungeIntoStock]);
}

#[test]
fn plunge_in_air_is_not_a_crash() {
    let k = crashes("G0 X20 Y20 Z40\nG1 Z31 F500", &checks(30.0));
    assert!(k.is_empty(), "{k:?}");
}

#[test]
fn ramp_within_the_limit_is_not_a_crash() {
    // 1 mm down over 20 mm: about 3°.
    let k = crashes("G0 X5 Y20 Z40\nG1 Z30 F500\nG1 X25 Z29", &checks(30.0));
    assert!(k.is_empty(), "{k:?}");
}

#[test]
fn ramp_steeper_than_the_limit_is_a_plunge() {
    // 5 mm down over 2 mm of travel: 68°.
    let k = crashes("G0 X5 Y20 Z40\nG1 Z30 F500\nG1 X7 Z25", &checks(30.0));
    assert_eq!(k, vec![CrashKind::PlungeIntoStock]);
}

#[test]
fn a_cut_deeper_than_the_flutes_is_shank_contact() {
    // Into the block's side 8 mm deep, flutes 5 mm: the shank cuts.
    let body = "G0 X-10 Y20 Z40\nG0 Z22\nG1 X30 F500";
    assert_eq!(crashes(body, &checks(5.0)), vec![CrashKind::ShankContact]);
    assert!(crashes(body, &checks(12.0)).is_empty());
}

/// A move whose edge only just reaches the first column of cells (their
/// centres 5 µm inside it) grazes a sliver where a part face runs along
/// those cells: within a 10 µm rim band it is no shank contact; where no
/// face runs, or 1 mm in, it is.
#[test]
fn a_graze_of_a_face_sliver_within_the_rim_band_is_not_shank_contact() {
    let on_face = || {
        let mut z = block();
        let nx = z.grid.nx;
        z.faces = Some((0..z.grid.len()).map(|k| k % nx == 0).collect());
        z
    };
    let graze = "G0 X-4.745 Y-10 Z40\nG0 Z22\nG1 Y50 F500";
    let mut c = checks(5.0);
    assert_eq!(
        crashes_on(on_face(), graze, &c),
        vec![CrashKind::ShankContact]
    );
    c.rim = 0.01;
    assert!(crashes_on(on_face(), graze, &c).is_empty());
    assert_eq!(crashes(graze, &c), vec![CrashKind::ShankContact]);
    let cut = "G0 X-4 Y-10 Z40\nG0 Z22\nG1 Y50 F500";
    assert_eq!(
        crashes_on(on_face(), cut, &c),
        vec![CrashKind::ShankContact]
    );
}

#[test]
fn default_checks_report_no_plunge() {
    let k = crashes("G0 X20 Y20 Z40\nG1 Z25 F500", &MoveChecks::default());
    assert!(k.is_empty(), "{k:?}");
}

/// With the operations named, one that plunges is undone and skipped; the
/// next one is judged on the stock without it (here it cuts the same slot
/// with a ramp, and is kept).
#[test]
fn an_operation_that_plunges_is_undone_and_the_next_judged_without_it() {
    let text = "G21 G90 G17\nT1 M6\nS10000 M3\n\
                (OP1)\nG0 X20 Y20 Z40\nG1 Z25 F500\nG1 X30\nG0 Z40\n\
                (OP2)\nG0 X0 Y20 Z40\nG1 Z30 F500\nG1 X20 Z29\nG1 X30\nG0 Z40\nM5\nM30\n";
    let prog = parse(text, "t.ngc").unwrap();
    let tools = parse_tool_table("T1 P1 D10 ;em10 r0.5\n", "t.tbl").unwrap();
    let line = |tag: &str| text.lines().position(|l| l == tag).unwrap() + 1;
    let mut c = checks(30.0);
    c.operations = vec![(line("(OP1)"), 1), (line("(OP2)"), 2)];
    let mut z = block();
    let rs = z.replay_checked(&prog, &tools, &c).unwrap();
    assert_eq!(rs.excluded.len(), 1, "{:?}", rs.excluded);
    assert_eq!(rs.excluded[0].0, 1);
    assert_eq!(rs.excluded[0].1.kind, CrashKind::PlungeIntoStock);
    assert!(rs.crashes.is_empty(), "{:?}", rs.crashes);
    // OP1's slot at depth 5 was undone: only OP2's 1 mm cut is there.
    let h = z.height_at(glam::DVec2::new(25.0, 20.0)).unwrap();
    assert!((h - 29.0).abs() < 1e-3, "{h}");
}
