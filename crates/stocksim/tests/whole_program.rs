//! A whole program (about 50 m of path): roughing the bundled `tall_rib`
//! sample around its rib in 2 mm layers with a Ø12 r0.5 bull-nose, written
//! here by hand (no planner code). The simulated stock must equal the part
//! except the rib-foot fillet the corner radius leaves (unreachable).

use std::fmt::Write;

use thinplan_stocksim::{parse, parse_tool_table, simulate, SimConfig};

/// Rib: x 20..140, y 19.5..20.5, z 20..92 on a base 160 × 40 × 20.
fn program() -> String {
    let mut s = String::from("%\nO0100 (tall_rib roughing)\nG21 G17 G90 G94 G40 G49 G80 G64 P0.01\nG54\nT1 M6\nG43 H1\nS16000 M3\nM8\nG0 X-10 Y-10\nG0 Z100\n");
    let safe = 95.0;
    let mut z = 90.0;
    let mut layers = vec![];
    while z > 20.0 + 1e-9 {
        layers.push(z);
        z -= 2.0;
    }
    layers.push(20.0);
    for z in layers {
        // Raster lines clear of the rib (tool radius 6).
        for y in [0.0, 6.0, 12.0, 28.0, 34.0, 40.0] {
            let _ = write!(s, "G0 X-6 Y{y}\nG1 Z{z} F2000\nG1 X166\nG0 Z{safe}\n");
        }
        // Ends of the middle band.
        let _ = write!(s, "G0 X-6 Y20\nG1 Z{z}\nG1 X8\nG0 Z{safe}\n");
        let _ = write!(s, "G0 X166 Y20\nG1 Z{z}\nG1 X152\nG0 Z{safe}\n");
        // Contour 6 mm from the rib, climb-free order irrelevant here.
        let _ = write!(
            s,
            "G0 X20 Y13.5\nG1 Z{z}\nG1 X140\nG3 X146 Y19.5 I0 J6\nG1 Y20.5\nG3 X140 Y26.5 I-6 J0\n\
             G1 X20\nG3 X14 Y20.5 I0 J-6\nG1 Y19.5\nG3 X20 Y13.5 I6 J0\nG0 Z{safe}\n"
        );
    }
    s.push_str("M5 M9\nG0 Z100\nM30\n%\n");
    s
}

#[test]
fn tall_rib_roughing_comes_out_exact() {
    let part = thinplan_import::import("builtin:tall_rib").unwrap().brep;
    let prog = parse(&program(), "tall_rib.ngc").unwrap();
    let tools = parse_tool_table("T1 P1 D12.000 Z+0.000 ;em12 r0.5\n", "tool.tbl").unwrap();
    let sim = simulate(&part, &prog, &tools, &SimConfig::default()).unwrap();
    let r = &sim.report;
    eprintln!(
        "tall_rib: feed {:.0} mm, rapid {:.0} mm, {} cells visited in {:.3} s = {:.1} M cells/s; comparison {:.3} s",
        r.program.feed_length_mm,
        r.program.rapid_length_mm,
        r.cells_visited,
        sim.replay_time.as_secs_f64(),
        sim.cells_per_second() / 1e6,
        sim.compare_time.as_secs_f64()
    );
    assert!(
        r.program.feed_length_mm > 40_000.0,
        "{}",
        r.program.feed_length_mm
    );
    assert!(r.crashes.is_empty(), "{:?}", r.crashes);
    assert_eq!(r.gouges.cells, 0, "{:?}", r.gouges);
    assert_eq!(r.leftover_missed.cells, 0, "{:?}", r.leftover_missed);
    assert!(r.clean);
    // The r0.5 corner leaves a fillet at the rib foot: unreachable, thin.
    assert!(
        r.leftover_unreachable.worst_mm <= 0.5 + 1e-3,
        "{:?}",
        r.leftover_unreachable
    );
    // Removed = blank − part, less the fillet and the cells' sampling.
    let blank = 160.0 * 40.0 * 92.0;
    let part_v = 160.0 * 40.0 * 20.0 + 120.0 * 1.0 * 72.0;
    let want = blank - part_v;
    assert!(
        (r.removed_volume_mm3 - want).abs() < 0.005 * want,
        "{} vs {want}",
        r.removed_volume_mm3
    );
}
