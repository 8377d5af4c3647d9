//! Simulation against analytic truth.

use std::f64::consts::PI;

use glam::{DVec2, DVec3};
use thinplan_stocksim::{parse, Blank, ToolLibrary, ToolShape, ZMap};

fn blank() -> Blank {
    Blank {
        min: DVec3::new(0.0, 0.0, 0.0),
        max: DVec3::new(140.0, 100.0, 20.0),
    }
}

fn run(prog: &str, tool: ToolShape, cell: f64) -> (ZMap, thinplan_stocksim::ReplayStats) {
    let p = parse(prog, "t.ngc").unwrap();
    let mut z = ZMap::new(blank(), cell).unwrap();
    let tools = ToolLibrary::from([(1, tool)]);
    let st = z.replay(&p, &tools).unwrap();
    (z, st)
}

fn header(body: &str) -> String {
    format!("G21 G90 G17\nT1 M6\nS10000 M3\nG0 X10 Y30\nG0 Z25\n{body}G0 Z25\nM30\n")
}

/// Sampling a region by cell centres: the area error is below
/// perimeter × cell / 2 (a generous bound; it is far smaller on average).
fn area_tol(perimeter: f64, cell: f64) -> f64 {
    perimeter * cell / 2.0
}

#[test]
fn straight_slot_volume() {
    for cell in [0.2, 0.05] {
        let (z, st) = run(
            &header("G1 Z15 F300\nG1 X90\n"),
            ToolShape::flat(10.0),
            cell,
        );
        let exact = 80.0 * 10.0 * 5.0 + PI * 25.0 * 5.0;
        let tol = area_tol(2.0 * 80.0 + PI * 10.0, cell) * 5.0;
        assert!(
            (st.cut.volume - exact).abs() < tol,
            "cell {cell}: {} vs {exact} ± {tol}",
            st.cut.volume
        );
        assert!((z.volume() - (140.0 * 100.0 * 20.0 - st.cut.volume)).abs() < 1e-3 * exact);
        assert_eq!(z.height_at(DVec2::new(50.0, 30.0)), Some(15.0));
        assert_eq!(z.height_at(DVec2::new(50.0, 35.5)), Some(20.0));
        assert_eq!(z.height_at(DVec2::new(50.0, 34.5)), Some(15.0));
        assert!(st.crashes.is_empty());
        assert_eq!(st.air_length, 0.0);
        assert!((st.feed_length - 90.0).abs() < 1e-9);
    }
}

/// Annular sector swept by a flat Ø`2R` tool along an arc of radius `r`
/// turning `theta`, plus the two end half-discs.
fn arc_area(r: f64, tool_r: f64, theta: f64) -> f64 {
    theta * 2.0 * r * tool_r + PI * tool_r * tool_r
}

#[test]
fn arcs_remove_annular_sectors() {
    // Quarter arcs of radius 20 about (50, 30) from (70, 30) to (50, 50), depth 2,
    // and a three-quarter arc by a negative R.
    let q = PI / 2.0;
    let cases = [
        ("G3 X50 Y50 I-20 J0", q),
        ("G3 X50 Y50 R20", q),
        ("G2 X50 Y50 I-20 J0", 3.0 * q),
        ("G2 X50 Y50 R-20", 3.0 * q),
        ("G2 X50 Y50 R20", q),
        ("G3 X50 Y50 R-20", 3.0 * q),
    ];
    for (arc, theta) in cases {
        let prog = format!("G21 G90 G17\nT1 M6\nM3\nG0 X70 Y30 Z25\nG1 Z18 F200\n{arc}\nG0 Z25\n");
        let (_, st) = run(&prog, ToolShape::flat(4.0), 0.1);
        let exact = arc_area(20.0, 2.0, theta) * 2.0;
        let perim = 2.0 * theta * 20.0 + 2.0 * PI * 2.0;
        let tol = area_tol(perim, 0.1) * 2.0;
        assert!(
            (st.cut.volume - exact).abs() < tol,
            "{arc}: {} vs {exact} ± {tol}",
            st.cut.volume
        );
    }
}

#[test]
fn bull_nose_leaves_its_fillet_at_the_slot_wall() {
    let tool = ToolShape::bull(10.0, 2.0);
    let cell = 0.1;
    let (z, _) = run(&header("G1 Z15 F300\nG1 X90\n"), tool, cell);
    // Across the slot at x = 50: cells at distance ρ from the tool path y = 30.
    for j in 0..600 {
        let y = (j as f64 + 0.5) * cell;
        let rho = (y - 30.0).abs();
        let got = z.height_at(DVec2::new(50.05, y)).unwrap();
        let expect = if rho <= 3.0 {
            15.0
        } else if rho < 5.0 - 1e-6 {
            15.0 + 2.0 - (4.0 - (rho - 3.0) * (rho - 3.0)).sqrt()
        } else {
            20.0
        };
        assert!((got - expect).abs() < 1e-4, "y {y}: {got} vs {expect}");
    }
}

#[test]
fn ramps_leave_the_right_floor() {
    // Flat Ø10 ramp from (10,30,20) down to (90,30,12): on the path line the floor
    // at x is the tip height R ahead (the tool's leading edge cuts lowest).
    let (z, _) = run(
        &header("G1 X10 Y30 Z20 F300\nG1 X90 Z12\n"),
        ToolShape::flat(10.0),
        0.1,
    );
    let k = 8.0 / 80.0;
    for x in [20.05, 40.05, 70.05] {
        let expect = 20.0 - k * (x + 5.0 - 10.0);
        let got = z.height_at(DVec2::new(x, 30.05)).unwrap();
        // The cell centre is 0.05 off the path line: the chord there is shorter by ≪ 0.001.
        assert!((got - expect).abs() < 2e-3, "x {x}: {got} vs {expect}");
    }
    // Ball Ø10 on the same ramp: below the tip line by r(1/cos α − 1).
    let (z, _) = run(
        &header("G1 X10 Y30 Z20 F300\nG1 X90 Z12\n"),
        ToolShape::ball(10.0),
        0.1,
    );
    let alpha = k.atan();
    for x in [20.05, 40.05, 70.05] {
        let tip = 20.0 - k * (x - 10.0);
        let expect = tip + 5.0 * (1.0 - 1.0 / alpha.cos());
        let got = z.height_at(DVec2::new(x, 30.0 + 1e-9)).unwrap();
        // Sampled 0.05 off-line in x is exact; y on a cell centre boundary is 0.05 off.
        assert!((got - expect).abs() < 2e-3, "x {x}: {got} vs {expect}");
    }
}

#[test]
fn helix_then_circle_leaves_a_flat_annulus() {
    // Helix one turn from Z20 to Z18 at radius 10 about (50,30), then a flat circle.
    let prog = "G21 G90 G17\nT1 M6\nM3\nG0 X60 Y30 Z25\nG1 Z20 F200\nG3 X60 Y30 I-10 J0 Z18\nG3 X60 Y30 I-10 J0\nG0 Z25\n";
    let (z, st) = run(prog, ToolShape::flat(6.0), 0.1);
    let exact = PI * (13.0f64.powi(2) - 7.0f64.powi(2)) * 2.0;
    let tol = area_tol(2.0 * PI * 20.0, 0.1) * 2.0;
    assert!(
        (st.cut.volume - exact).abs() < tol,
        "{} vs {exact}",
        st.cut.volume
    );
    for ang in [0.3f64, 1.7, 4.0] {
        let p = DVec2::new(50.0, 30.0) + 10.0 * DVec2::from_angle(ang);
        assert!((z.height_at(p).unwrap() - 18.0).abs() < 1e-4);
    }
    assert_eq!(z.height_at(DVec2::new(50.0, 30.0)), Some(20.0));
    // The helix alone descends: a quarter turn in, the floor is above 18.
    let (z, _) = run(
        &prog.replace("G3 X60 Y30 I-10 J0\nG0", "G0"),
        ToolShape::flat(6.0),
        0.1,
    );
    let mid = z.height_at(DVec2::new(50.0, 40.0)).unwrap();
    assert!(mid > 18.5 && mid < 19.8, "{mid}");
}

#[test]
fn rapid_into_stock_and_spindle_off_are_crashes() {
    let prog = header("G0 Z15\nG1 X30 F300\nM5\nG1 X50\nG0 X80\n");
    let (_, st) = run(&prog, ToolShape::flat(10.0), 0.2);
    let kinds: Vec<_> = st
        .crashes
        .iter()
        .map(|c| (c.line, format!("{:?}", c.kind)))
        .collect();
    assert_eq!(
        kinds,
        vec![
            (6, "RapidIntoStock".to_string()),
            (9, "SpindleOff".to_string()),
            (10, "RapidIntoStock".to_string())
        ]
    );
    assert!((st.crashes[0].depth_mm - 5.0).abs() < 1e-6);
}

#[test]
fn air_cutting_is_measured() {
    // 80 mm cut, then the same 80 mm back over it (air), then 40 mm in air above.
    let prog = header("G1 Z15 F300\nG1 X90\nG1 X10\nG1 Z21\nG1 X50\n");
    let (_, st) = run(&prog, ToolShape::flat(10.0), 0.2);
    assert!((st.feed_length - (10.0 + 80.0 + 80.0 + 6.0 + 40.0)).abs() < 1e-9);
    assert!(
        (st.air_length - (80.0 + 6.0 + 40.0)).abs() < 1e-9,
        "{}",
        st.air_length
    );
}

#[test]
fn missing_tool_shape_is_an_error() {
    let p = parse("T7 M6\nM3\nG0 X0 Y0 Z30\nG1 Z0 F10\n", "t.ngc").unwrap();
    let mut z = ZMap::new(blank(), 0.5).unwrap();
    let e = z.replay(&p, &ToolLibrary::new()).unwrap_err();
    assert!(e.0.contains("line 3") && e.0.contains("T7"), "{e}");
}

/// Highest stock any cell shows between `x0` and `x1` along `y`.
fn highest_between(z: &ZMap, x0: f64, x1: f64, y: f64) -> f64 {
    let n = ((x1 - x0) / 0.005).ceil() as usize;
    (0..=n)
        .filter_map(|k| z.height_at(DVec2::new(x0 + (x1 - x0) * k as f64 / n as f64, y)))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A fin wider than the larger gap between the centres of the grid and of
/// the grid shifted by 0.45 of a cell (0.55 of a cell) stands at a centre
/// of one of them, wherever it lies; the grid alone misses some of them.
#[test]
fn a_fin_over_half_a_cell_wide_stands_on_one_of_two_grids_shifted_apart() {
    let cell = 0.25;
    let mut missed_by_one = 0;
    for k in 0..97 {
        let a = 50.0 + k as f64 * 0.0103;
        for w in [0.55 * cell + 1e-3, 0.6 * cell, 0.9 * cell] {
            let prog = header(&format!(
                "G0 X{:.4} Y20\nG1 Z15 F300\nG1 Y80\nG0 Z25\nG0 X{:.4} Y20\nG1 Z15\nG1 Y80\n",
                a - 5.0,
                a + w + 5.0
            ));
            let p = parse(&prog, "t.ngc").unwrap();
            let tools = ToolLibrary::from([(1, ToolShape::flat(10.0))]);
            let seen: Vec<bool> = [0.0, 0.45]
                .iter()
                .map(|&shift| {
                    let mut z = ZMap::shifted(blank(), cell, shift).unwrap();
                    z.replay(&p, &tools).unwrap();
                    highest_between(&z, a - 2.0, a + w + 2.0, 50.0) > 19.999
                })
                .collect();
            assert!(
                seen[0] || seen[1],
                "fin at {a} wide {w} seen on neither grid"
            );
            if !seen[0] {
                missed_by_one += 1;
            }
        }
    }
    assert!(missed_by_one > 0);
}

#[test]
fn a_grid_shift_outside_a_cell_is_refused() {
    for s in [-0.1, 1.0, f64::NAN] {
        assert!(ZMap::shifted(blank(), 0.25, s).is_err(), "{s}");
    }
}
