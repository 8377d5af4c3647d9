//! Comparison with the part: a hand-written pocket program on a native part.

use thinplan_brep::Brep;
use thinplan_stocksim::{parse, simulate, CellClass, SimConfig, ToolLibrary, ToolShape};

/// A 60 × 40 × 20 block with a pocket 40 × 20, 15 deep (floor at z = 5),
/// corners rounded by `corner` (0 = sharp).
fn pocket_part(corner: f64) -> Brep {
    let hole = if corner > 0.0 {
        format!("RoundedRect(min: (10.0, 10.0), max: (50.0, 30.0), radius: {corner})")
    } else {
        "Rect(min: (10.0, 10.0), max: (50.0, 30.0))".to_string()
    };
    let text = format!(
        r#"Part(
    name: "pocket",
    description: "stocksim test pocket",
    prisms: [
        Prism(id: "base", extent: (0.0, 5.0), profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)))),
        Prism(id: "ring", extent: (5.0, 20.0),
              profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)), holes: [{hole}])),
    ],
)"#
    );
    thinplan_native::parse_part(&text, "pocket.part.ron")
        .unwrap()
        .build()
        .unwrap()
}

/// Contour at 4 mm from the R5-cornered pocket wall (tool Ø8) plus a middle
/// pass at y = 20; `floor` is the Z of the contour, `mid_z` of the middle pass.
fn pocket_program(floor: &str, mid_z: &str, with_mid: bool) -> String {
    let mid = if with_mid {
        format!("G1 X15 Y20\nG1 Z{mid_z}\nG1 X45\n")
    } else {
        String::new()
    };
    format!(
        "%\nO0001 (pocket)\nG21 G17 G90 G94 G40 G49 G80\nG54\nT1 M6\nG43 H1\nS12000 M3\nM8\nG0 X30 Y20\nG0 Z25\n\
         G1 Z{floor} F300\nG1 X15 Y14\nG1 X45\nG3 X46 Y15 I0 J1\nG1 Y25\nG3 X45 Y26 I-1 J0\nG1 X15\n\
         G3 X14 Y25 I0 J-1\nG1 Y15\nG3 X15 Y14 I1 J0\n{mid}G0 Z25\nM5 M9\nM30\n%\n"
    )
}

fn tools() -> ToolLibrary {
    ToolLibrary::from([(1, ToolShape::flat(8.0))])
}

fn sim(part: &Brep, prog: &str) -> thinplan_stocksim::Simulation {
    let p = parse(prog, "pocket.ngc").unwrap();
    simulate(part, &p, &tools(), &SimConfig::default()).unwrap()
}

#[test]
fn complete_pocket_is_clean() {
    let part = pocket_part(5.0);
    let s = sim(&part, &pocket_program("5", "5", true));
    let r = &s.report;
    assert!(r.clean, "{}", serde_json::to_string_pretty(r).unwrap());
    assert_eq!(r.gouges.cells, 0);
    assert_eq!(r.leftover_missed.cells, 0);
    assert_eq!(r.leftover_unreachable.cells, 0);
    // The pocket: 40 × 20 with R5 corners, 15 deep.
    let area = 40.0 * 20.0 - (4.0 - std::f64::consts::PI) * 25.0;
    assert!(
        (r.removed_volume_mm3 - area * 15.0).abs() < 120.0 * 0.1 * 15.0,
        "{}",
        r.removed_volume_mm3
    );
    assert_eq!(r.tools.len(), 1);
    assert!(r.crashes.is_empty());
    // Deterministic JSON.
    let again = sim(&part, &pocket_program("5", "5", true));
    assert_eq!(
        serde_json::to_string(&again.report).unwrap(),
        serde_json::to_string(r).unwrap()
    );
    let svg = s.svg();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
}

#[test]
fn a_pass_too_deep_is_a_gouge_at_its_place() {
    let part = pocket_part(5.0);
    let prog = pocket_program("5", "4.8", true);
    // The plunge of the middle pass and the pass itself cut 0.2 too deep.
    let lines: Vec<&str> = prog.lines().collect();
    let mid_line = lines.iter().rposition(|l| *l == "G1 X45").unwrap() + 1;
    let s = sim(&part, &prog);
    let g = &s.report.gouges;
    assert!(!s.report.clean);
    assert!((g.worst_mm - 0.2).abs() < 1e-3, "{}", g.worst_mm);
    let line = g.worst_line.unwrap();
    assert!(line == mid_line || line == mid_line - 1, "{line}");
    assert_eq!(g.regions_total, 1);
    let b = g.regions[0].bbox;
    // The Ø8 pass from x 15 to 45 at y 20 (the move in to it also cuts 0.2 deep).
    assert!(
        b[1] >= 15.9 && b[3] <= 24.1 && b[0] >= 10.9 && b[2] <= 49.1,
        "{b:?}"
    );
    let area = 30.0 * 8.0 + std::f64::consts::PI * 16.0;
    assert!(
        (g.volume_mm3 - area * 0.2).abs() < area * 0.2 * 0.1,
        "{}",
        g.volume_mm3
    );
    assert_eq!(s.report.leftover_missed.cells, 0);
}

#[test]
fn a_missing_pass_is_missed_leftover() {
    let part = pocket_part(5.0);
    let s = sim(&part, &pocket_program("5", "5", false));
    let r = &s.report;
    assert!(!r.clean);
    assert_eq!(r.gouges.cells, 0);
    assert!(r.leftover_missed.cells > 0);
    assert!((r.leftover_missed.worst_mm - 15.0).abs() < 1e-3);
    let at = r.leftover_missed.worst_at.unwrap();
    assert!(
        (at[1] - 20.0).abs() < 2.0 && at[0] > 18.0 && at[0] < 42.0,
        "{at:?}"
    );
    assert_eq!(r.leftover_unreachable.cells, 0);
}

#[test]
fn sharp_inside_corners_are_unreachable() {
    // Sharp corners, tool path with sharp corners at 4 mm from the walls.
    let part = pocket_part(0.0);
    let prog = "G21 G90 G17\nT1 M6\nM3\nG0 X30 Y20 Z25\nG1 Z5 F300\nG1 X14 Y14\nG1 X46\nG1 Y26\nG1 X14\nG1 Y14\nG1 X14 Y20\nG1 X46\nG0 Z25\nM30\n";
    let s = sim(&part, prog);
    let r = &s.report;
    assert_eq!(r.gouges.cells, 0, "{:?}", r.gouges);
    assert_eq!(r.leftover_missed.cells, 0, "{:?}", r.leftover_missed);
    assert_eq!(r.leftover_unreachable.regions_total, 4);
    // Each corner keeps (R² − πR²/4) × 15.
    let corner = (16.0 - std::f64::consts::PI * 4.0) * 15.0;
    let v = r.leftover_unreachable.volume_mm3;
    assert!(
        (v - 4.0 * corner).abs() < 0.25 * 4.0 * corner,
        "{v} vs {}",
        4.0 * corner
    );
    assert!(r.clean, "unreachable leftover alone is clean");
    let k = s
        .classes
        .iter()
        .filter(|c| **c == CellClass::Unreachable)
        .count();
    assert_eq!(k, r.leftover_unreachable.cells);
}

/// A bull-nose Ø8 (corner radius 0.5) taken exactly into each sharp corner
/// of the pocket: what it leaves there is beyond its reach, so nothing is
/// missed, although the ideal (tool positions at cell centres) reaches up
/// to a cell further. Cutting one corner short by 1 mm is still missed.
#[test]
fn leftover_at_the_limit_of_reach_is_unreachable_but_a_short_corner_is_missed() {
    let part = pocket_part(0.0);
    let lib = ToolLibrary::from([(1, ToolShape::bull(8.0, 0.5))]);
    let run = |prog: &str| {
        let p = parse(prog, "pocket.ngc").unwrap();
        simulate(&part, &p, &lib, &SimConfig::default()).unwrap()
    };
    let exact = "G21 G90 G17\nT1 M6\nM3\nG0 X30 Y20 Z25\nG1 Z5 F300\nG1 X14 Y14\nG1 X46\nG1 Y26\nG1 X14\nG1 Y14\nG1 X14 Y20\nG1 X46\nG0 Z25\nM30\n";
    let s = run(exact);
    let r = &s.report;
    assert_eq!(r.gouges.cells, 0, "{:?}", r.gouges);
    assert_eq!(r.leftover_missed.cells, 0, "{:?}", r.leftover_missed);
    // The four corners (and the corner radius's fillet along the walls'
    // feet, which joins them into one region).
    let corner = (16.0 - std::f64::consts::PI * 4.0) * 15.0;
    assert!(r.leftover_unreachable.volume_mm3 > 0.75 * 4.0 * corner);
    // The last corner cut short: from (14, 25) straight to (15, 26)
    // instead of through (14, 26).
    let short = exact.replace(
        "G1 Y26\nG1 X14\nG1 Y14",
        "G1 Y26\nG1 X15\nG1 X14 Y25\nG1 Y14",
    );
    assert_ne!(short, exact);
    let s = run(&short);
    let m = &s.report.leftover_missed;
    assert!(m.cells > 0, "{m:?}");
    let at = m.worst_at.unwrap();
    assert!(at[0] < 14.0 && at[1] > 26.0, "{at:?}");
    // Measured down to what the tool reaches there: the floor, less the
    // torus its corner radius leaves (15 mm of pocket).
    assert!(m.worst_mm > 14.5 && m.worst_mm <= 15.0, "{}", m.worst_mm);
}

#[test]
fn air_cutting_share() {
    let part = pocket_part(5.0);
    // The clean program plus 100 mm of feed in the air above the part.
    let prog = pocket_program("5", "5", true).replace(
        "G0 Z25\nM5",
        "G0 Z25\nG1 X45 Y20 Z30 F1000\nG1 X-55\nG0 Z35\nM5",
    );
    let s = sim(&part, &prog);
    let a = &s.report.air_cutting;
    // G1 X45 Y20 Z30 from (45,20,25) rises 5 mm: air too.
    assert!(
        (a.air_length_mm - 105.0).abs() < 1e-9,
        "{}",
        a.air_length_mm
    );
    let share = 105.0 / s.report.program.feed_length_mm;
    assert!((a.share - share).abs() < 1e-12);
    assert!(s.report.clean);
}

#[test]
fn builtin_part_and_empty_program() {
    let part = thinplan_import::import("builtin:tall_rib").unwrap().brep;
    let p = parse("G0 X0 Y0 Z200\nM30\n", "empty.ngc").unwrap();
    let cfg = SimConfig {
        cell: 1.0,
        ..SimConfig::default()
    };
    let s = simulate(&part, &p, &ToolLibrary::new(), &cfg).unwrap();
    // Nothing cut: everything above the part is leftover.
    assert!(s.report.leftover_missed.cells > 0);
    assert_eq!(s.report.removed_volume_mm3, 0.0);
    assert_eq!(s.report.program.feed_length_mm, 0.0);
}

/// The classes by hand: leftover a tool could take down to the part is
/// missed; where no tool reaches the part, leftover a tool could still
/// take some off the top of is above reach, and the rest unreachable.
#[test]
fn leftover_is_missed_only_where_a_tool_reaches_the_part() {
    use thinplan_stocksim::compare::{classify, PartField};
    // (stock, part, ideal, expected)
    let cells = [
        (1.0, 1.0, 1.0, CellClass::Ok),
        (1.04, 1.0, 1.0, CellClass::Ok),
        (0.9, 1.0, 1.0, CellClass::Gouge),
        (2.0, 1.0, 1.02, CellClass::Missed),
        (2.0, 1.0, 1.0, CellClass::Missed),
        (5.0, 1.0, 5.0, CellClass::Unreachable),
        (5.0, 1.0, 4.97, CellClass::Unreachable),
        // the rim of a column in a corner no tool fits: 0.11 shavable
        (5.0, 1.0, 4.89, CellClass::AboveReach),
        // a ridge on a face no flat bottom follows
        (1.4, 1.0, 1.3, CellClass::AboveReach),
    ];
    let f = |k: usize| {
        cells
            .iter()
            .map(|c| [c.0, c.1, c.2][k] as f32)
            .collect::<Vec<_>>()
    };
    let part = PartField {
        top: f(1),
        lo: f(1),
        hi: f(1),
        face: vec![false; cells.len()],
    };
    let got = classify(&f(0), &part, &f(2), 0.05);
    let want: Vec<CellClass> = cells.iter().map(|c| c.3).collect();
    assert_eq!(got, want);
}

/// A cut into a wall is seen wherever a row of cell centres lies inside
/// the wall by more than the wall tolerance (the tessellation's error), not
/// only by more than the gouge tolerance: a centre 0.03 mm inside a wall is
/// judged, so a pass 0.1 mm into the wall is a gouge the height of the
/// wall, and a pass tangent to it is not.
#[test]
fn a_pass_into_a_wall_between_rows_of_centres_is_a_gouge() {
    // The pocket's wall at y = 9.93: the centres (cell 0.2) at y = 9.9
    // lie 0.03 inside it, those at 10.1 in the pocket.
    let text = r#"Part(
    name: "wall",
    description: "stocksim wall tolerance",
    prisms: [
        Prism(id: "base", extent: (0.0, 5.0), profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)))),
        Prism(id: "ring", extent: (5.0, 20.0),
              profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 40.0)),
                        holes: [Rect(min: (10.0, 9.93), max: (50.0, 30.0))])),
    ],
)"#;
    let part = thinplan_native::parse_part(text, "wall.part.ron")
        .unwrap()
        .build()
        .unwrap();
    let pass = |y: f64| {
        format!(
            "G21 G17 G90\nT1 M6\nS12000 M3\nG0 X15 Y20\nG0 Z25\nG1 Z5 F300\nG1 Y{y}\nG1 X45\n\
             G0 Z25\nM5\nM30\n"
        )
    };
    let run = |y: f64, wall_tol: f64| {
        let p = parse(&pass(y), "wall.ngc").unwrap();
        let cfg = SimConfig {
            wall_tol,
            ..SimConfig::default()
        };
        simulate(&part, &p, &tools(), &cfg).unwrap().report.gouges
    };
    // Ø8 at y = 13.83 reaches y = 9.83, 0.1 into the wall.
    let into = run(13.83, thinplan_stocksim::DEFAULT_WALL_TOL);
    assert!(into.cells >= 100, "{into:?}");
    assert!((into.worst_mm - 15.0).abs() < 0.01, "{}", into.worst_mm);
    // Tangent to the wall: nothing.
    assert_eq!(run(13.93, thinplan_stocksim::DEFAULT_WALL_TOL).cells, 0);
    // Judged only 0.05 inside the wall (the gouge tolerance), the same
    // pass goes unseen: the blind spot the wall tolerance closes.
    assert_eq!(run(13.83, 0.05).cells, 0);
}
