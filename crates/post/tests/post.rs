mod common;

use common::*;
use glam::DVec3;
use proptest::prelude::*;
use thinplan_plan::OperationId;
use thinplan_post::*;

fn tiny_plan() -> thinplan_plan::Plan {
    let mut plan = empty_plan();
    plan.operations = vec![op(
        1,
        "em20",
        8000.0,
        [0.0, 0.0, 5.0],
        vec![
            line(0.0, 0.0, -2.0, 300.0),
            line(20.0, 0.0, -2.0, 1200.0),
            // Counter-clockwise quarter about (20, 10): from below to the right.
            arc(
                [30.0, 10.0, -2.0],
                [20.0, 10.0, -2.0],
                DVec3::Z,
                false,
                1200.0,
            ),
            // Clockwise half turn down 1 mm: a helix.
            arc(
                [10.0, 10.0, -3.0],
                [20.0, 10.0, -2.0],
                DVec3::Z,
                true,
                1200.0,
            ),
            line(10.0, 10.0, 5.0, 0.0),
        ],
    )];
    plan
}

/// Written by hand from RS274NGC: T2 is em20 (second tool of the set);
/// clearance = highest point 5 + 10; modal F written only when it changes;
/// only changed axes written, except X Y on arcs; I J from the arc start.
#[test]
fn linuxcnc_output_of_a_tiny_plan_is_exactly_as_written_by_hand() {
    let k = knowledge();
    let p = post(
        &tiny_plan(),
        k.post("linuxcnc").unwrap(),
        k.tool_set("endmills_12_20").unwrap(),
    )
    .unwrap();
    let v = env!("CARGO_PKG_VERSION");
    let expected = format!(
        "(thinplan {v}, post linuxcnc)
(part builtin:test, sha256 0123456789abcdef)
(set-up: up 0.000 0.000 1.000, machine hsm_5axis, tool set endmills_12_20, material al7075)
(knowledge builtin:knowledge)
G21 G17 G90 G91.1 G94 G40 G49 G80
G64 P0.005
G54
G0 Z15.000
T2 M6
G43 H2
(OP1 test, feature MF1, tool em20 D20.000)
S8000 M3
M8
G0 X0.000 Y0.000
G0 Z5.000
G1 Z-2.000 F300
G1 X20.000 F1200
G3 X30.000 Y10.000 I0.000 J10.000
G2 X10.000 Y10.000 Z-3.000 I-10.000 J0.000
G0 Z5.000
G0 Z15.000
M5
M9
M2
"
    );
    assert_eq!(p.text, expected);
    let pi = std::f64::consts::PI;
    let feed = 7.0 + 20.0 + 5.0 * pi + (10.0 * pi).hypot(1.0);
    assert!(
        (p.feed_length_mm - feed).abs() < 1e-9,
        "{}",
        p.feed_length_mm
    );
    // Retract and XY positioning start from where the machine is: unmeasured.
    assert_eq!(p.unmeasured_moves, 2);
    // Down to the start (15 → 5), up after the helix (−3 → 5), the final retract (5 → 15).
    assert!(
        (p.rapid_length_mm - (10.0 + 8.0 + 10.0)).abs() < 1e-9,
        "{}",
        p.rapid_length_mm
    );
    assert_eq!(p.arc_count, 2);
    assert_eq!(p.line_count, expected.lines().count());
    assert_eq!(p.tool_changes, 1);
    assert_eq!(p.extension, "ngc");
    assert!(
        p.tool_table.starts_with("T1 P1 D12.000 Z0.000 ;em12"),
        "{}",
        p.tool_table
    );
    assert!(
        p.tool_table.contains("\nT2 P2 D20.000 Z0.000 ;em20"),
        "{}",
        p.tool_table
    );
}

#[test]
fn fanuc_differs_by_tape_marks_program_number_block_numbers_and_capitals() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    let f = post(&tiny_plan(), k.post("fanuc").unwrap(), tools).unwrap();
    let l = post(&tiny_plan(), k.post("linuxcnc").unwrap(), tools).unwrap();
    let lines: Vec<&str> = f.text.lines().collect();
    assert_eq!(lines[0], "%");
    assert_eq!(lines[1], "O0001");
    assert_eq!(
        lines[2],
        format!("(THINPLAN {}, POST FANUC)", env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(lines[6], "N10 G21 G17 G90 G94 G40 G49 G80");
    assert_eq!(lines[7], "N20 G54");
    assert_eq!(lines[8], "N30 G0 Z15.000");
    assert_eq!(lines[9], "N40 T2 M6");
    assert!(
        f.text
            .contains("\nN120 G3 X30.000 Y10.000 I0.000 J10.000\n"),
        "{}",
        f.text
    );
    assert_eq!(&lines[lines.len() - 2..], ["N180 M30", "%"]);
    assert_eq!(f.extension, "nc");
    assert!(!f.text.contains("G91.1") && l.text.contains("G91.1"));
    assert!(l.text.ends_with("M2\n") && !l.text.contains('%'));
    // The same motion: same lengths.
    assert_eq!(f.feed_length_mm, l.feed_length_mm);
    assert_eq!(f.rapid_length_mm, l.rapid_length_mm);
}

#[test]
fn posting_is_deterministic() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    for id in ["linuxcnc", "fanuc"] {
        let a = post(&rich_plan(), k.post(id).unwrap(), tools).unwrap();
        let b = post(&rich_plan(), k.post(id).unwrap(), tools).unwrap();
        assert_eq!(a.text.as_bytes(), b.text.as_bytes());
        assert_eq!(a, b);
    }
}

#[test]
fn tools_change_only_when_the_tool_changes_with_a_retract_before_each() {
    let k = knowledge();
    let mut plan = rich_plan();
    // em12, em12 (OP3 then OP1), em20: two changes.
    plan.operation_order = vec![OperationId(3), OperationId(1), OperationId(2)];
    let p = post(
        &plan,
        k.post("linuxcnc").unwrap(),
        k.tool_set("endmills_12_20").unwrap(),
    )
    .unwrap();
    let lines: Vec<&str> = p.text.lines().collect();
    let changes: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].ends_with(" M6"))
        .collect();
    assert_eq!(changes.len(), 2);
    assert_eq!(p.tool_changes, 2);
    assert_eq!(lines[changes[0]], "T1 M6");
    assert_eq!(lines[changes[1]], "T2 M6");
    // Highest point: OP2's final rapid to Z20, + clearance 10.
    for &i in &changes {
        assert!(
            lines[..i].iter().rev().take(4).any(|l| *l == "G0 Z30.000"),
            "{:?}",
            &lines[i - 4..i]
        );
    }
    // Spindle speed per operation.
    for s in ["S15000 M3", "S12000 M3", "S8000 M3"] {
        assert_eq!(lines.iter().filter(|l| **l == s).count(), 1, "{s}");
    }
    assert!(lines.iter().all(|l| !l.contains("-0.000")));
}

/// Parses `G2`/`G3` blocks: (word, X, Y, I, J).
fn arcs_of(text: &str) -> Vec<(String, f64, f64, f64, f64)> {
    let mut out = Vec::new();
    let (mut x, mut y) = (0.0, 0.0);
    for l in text.lines() {
        let word = |c: char| {
            l.split_whitespace()
                .find_map(|w| w.strip_prefix(c).and_then(|v| v.parse::<f64>().ok()))
        };
        let g = l.split_whitespace().next().unwrap_or("");
        let (nx, ny) = (word('X').unwrap_or(x), word('Y').unwrap_or(y));
        if g == "G2" || g == "G3" {
            out.push((g.to_string(), x, y, word('I').unwrap(), word('J').unwrap()));
        }
        if g.starts_with('G') && !l.starts_with("G5") && !l.starts_with("G4") {
            x = nx;
            y = ny;
        }
    }
    out
}

#[test]
fn arc_direction_follows_the_geometry_and_ij_are_relative_to_the_start() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    // Quarter arcs starting at (3.1, 4.2) about (10, 10): the cross product
    // of (start − centre) and (end − centre) says which way they turn.
    let cases = [
        // start − centre = (−6.9, −5.8); turned +90° (counter-clockwise
        // seen from +Z) it is (5.8, −6.9), turned −90° it is (−5.8, 6.9).
        (DVec3::Z, false, [10.0 + 5.8, 10.0 - 6.9]),
        (DVec3::Z, true, [10.0 - 5.8, 10.0 + 6.9]),
        (-DVec3::Z, false, [10.0 - 5.8, 10.0 + 6.9]),
        (-DVec3::Z, true, [10.0 + 5.8, 10.0 - 6.9]),
    ];
    for (axis, clockwise, end) in cases {
        let mut plan = empty_plan();
        plan.operations = vec![op(
            1,
            "em12",
            10000.0,
            [3.1, 4.2, 0.0],
            vec![arc(
                [end[0], end[1], 0.0],
                [10.0, 10.0, 0.0],
                axis,
                clockwise,
                500.0,
            )],
        )];
        let p = post(&plan, k.post("linuxcnc").unwrap(), tools).unwrap();
        let arcs = arcs_of(&p.text);
        assert_eq!(arcs.len(), 1, "{}", p.text);
        let (g, sx, sy, i, j) = arcs[0].clone();
        assert_eq!((sx, sy), (3.1, 4.2));
        assert_eq!((i, j), (6.9, 5.8), "I J are centre − start");
        let (cx, cy) = (sx + i, sy + j);
        let cross = (sx - cx) * (end[1] - cy) - (sy - cy) * (end[0] - cx);
        let expect = if cross > 0.0 { "G3" } else { "G2" };
        assert_eq!(g, expect, "axis {axis} clockwise {clockwise}:\n{}", p.text);
        // A quarter turn, not three quarters.
        let quarter = 0.5 * std::f64::consts::PI * 6.9_f64.hypot(5.8);
        assert!(
            (p.feed_length_mm - quarter).abs() < 2e-3,
            "{}",
            p.feed_length_mm
        );
    }
}

#[test]
fn arcs_outside_the_xy_plane_or_too_large_are_linearised_within_tolerance() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    let post_l = k.post("linuxcnc").unwrap();
    let p = post(&rich_plan(), post_l, tools).unwrap();
    // Every G1 after the XZ semicircle's start lies on its circle.
    let lines: Vec<&str> = p.text.lines().collect();
    let at = lines
        .iter()
        .position(|l| *l == "G1 X100.000 F2000")
        .unwrap();
    let mut n = 0;
    for l in &lines[at + 1..] {
        if !l.starts_with("G1") {
            break;
        }
        let z: f64 = l
            .split_whitespace()
            .find_map(|w| w.strip_prefix('Z'))
            .unwrap()
            .parse()
            .unwrap();
        let x: f64 = l
            .split_whitespace()
            .find_map(|w| w.strip_prefix('X'))
            .map_or(100.0, |v| v.parse().unwrap());
        let r = (x - 100.0).hypot(z - 6.0);
        assert!((r - 10.0).abs() < 1e-3, "{l}: r = {r}");
        n += 1;
    }
    // A semicircle of radius 10 within 0.005 mm: chords of at most
    // 2·acos(1 − 0.005/10) rad, so ⌈π / 0.06325⌉ = 50 of them.
    assert_eq!(n, 50);
    // A radius beyond max_radius is linearised too.
    let mut small = post_l.clone();
    small.arcs.max_radius = 3.0;
    let q = post(&rich_plan(), &small, tools).unwrap();
    assert!(
        q.arc_count < p.arc_count,
        "{} vs {}",
        q.arc_count,
        p.arc_count
    );
    // Chords are shorter than their arcs, by about δ²/24 relatively.
    let rel = (q.feed_length_mm - p.feed_length_mm).abs() / p.feed_length_mm;
    assert!(rel < 1e-3, "{rel}");
    let mut none = post_l.clone();
    none.arcs.enabled = false;
    let r = post(&rich_plan(), &none, tools).unwrap();
    assert_eq!(r.arc_count, 0);
    assert!(!r
        .text
        .lines()
        .any(|l| l.starts_with("G2 ") || l.starts_with("G3 ")));
}

#[test]
fn bad_plans_are_refused_naming_the_operation() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    let lc = k.post("linuxcnc").unwrap();
    let mut plan = rich_plan();
    plan.operations[1].tool_axis = DVec3::X;
    let e = post(&plan, lc, tools).unwrap_err().to_string();
    assert!(e.contains("OP2") && e.contains("not +Z"), "{e}");

    let mut plan = rich_plan();
    plan.operations[2].tool = "em99".into();
    let e = post(&plan, lc, tools).unwrap_err().to_string();
    assert!(
        e.contains("OP3") && e.contains("em99") && e.contains("endmills_12_20"),
        "{e}"
    );

    let mut plan = rich_plan();
    plan.operations[0].moves[3].to.x += 1.0; // end off its circle
    let e = post(&plan, lc, tools).unwrap_err().to_string();
    assert!(
        e.contains("OP1, move 3") && e.contains("not on its circle"),
        "{e}"
    );

    let mut plan = rich_plan();
    plan.operation_order.pop();
    assert_eq!(
        post(&plan, lc, tools).unwrap_err(),
        PostError::OmittedOperation(OperationId(3))
    );

    let mut plan = rich_plan();
    plan.operation_order.push(OperationId(9));
    assert_eq!(
        post(&plan, lc, tools).unwrap_err(),
        PostError::UnknownOperation(OperationId(9))
    );

    let mut plan = rich_plan();
    plan.operations[0].moves[0].feed = f64::NAN;
    let e = post(&plan, lc, tools).unwrap_err().to_string();
    assert!(e.contains("OP1, move 0"), "{e}");

    let mut plan = rich_plan();
    plan.operations[1].link_z = Some(f64::INFINITY);
    let e = post(&plan, lc, tools).unwrap_err().to_string();
    assert!(e.contains("OP2") && e.contains("link_z"), "{e}");

    let e = post(&empty_plan(), lc, tools).unwrap_err();
    assert_eq!(e, PostError::NoOperations);

    let mut plan = rich_plan();
    plan.setup.tool_set = "other".into();
    assert!(matches!(
        post(&plan, lc, tools),
        Err(PostError::ToolSetMismatch { .. })
    ));
}

#[test]
fn an_empty_order_posts_in_id_order() {
    let k = knowledge();
    let tools = k.tool_set("endmills_12_20").unwrap();
    let mut plan = rich_plan();
    let a = post(&plan, k.post("linuxcnc").unwrap(), tools).unwrap();
    plan.operation_order.clear();
    plan.operations.reverse();
    let b = post(&plan, k.post("linuxcnc").unwrap(), tools).unwrap();
    assert_eq!(a.text, b.text);
}

#[test]
fn numbers_are_fixed_and_never_negative_zero() {
    assert_eq!(number(-0.0001, 3), "0.000");
    assert_eq!(number(-0.0, 3), "0.000");
    assert_eq!(number(-0.0006, 3), "-0.001");
    assert_eq!(number(2.5, 0), "2");
    assert_eq!(number(12.0, 3), "12.000");
}

/// Distance from `p` to the segment `a`–`b`.
fn to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + t * d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Every point of the true arc is within the chord tolerance of the
    /// chord that replaces it, and the chords end on the arc's end.
    #[test]
    fn linearised_arcs_stay_within_the_chord_tolerance(
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in -1.0f64..1.0,
        radius in 0.05f64..500.0,
        a0 in 0.0f64..std::f64::consts::TAU, sweep in 0.01f64..std::f64::consts::TAU,
        rise in -5.0f64..5.0,
        clockwise in any::<bool>(),
        tol in 0.001f64..0.1,
    ) {
        let axis = DVec3::new(ax, ay, az);
        prop_assume!(axis.length() > 0.1);
        let a = axis.normalize();
        let u = a.any_orthonormal_vector();
        let v = a.cross(u);
        let centre = DVec3::new(1.0, 2.0, 3.0);
        // Turning the given way by `sweep`: clockwise is negative about a.
        let signed = if clockwise { -sweep } else { sweep };
        let at = |t: f64| {
            let ang = a0 + t * signed;
            centre + t * rise * a + radius * (ang.cos() * u + ang.sin() * v)
        };
        let (start, end) = (at(0.0), at(1.0));
        let pts = linearise_arc(start, end, centre, axis, clockwise, tol);
        prop_assert_eq!(*pts.last().unwrap(), end);
        let n = pts.len();
        let mut prev = start;
        for (i, p) in pts.iter().enumerate() {
            for k in 0..=8 {
                let t = (i as f64 + k as f64 / 8.0) / n as f64;
                let d = to_segment(at(t), prev, *p);
                prop_assert!(d <= tol * (1.0 + 1e-6) + 1e-9, "segment {i}: {d} > {tol}");
            }
            prev = *p;
        }
    }
}

/// A link stage 8 planned on the in-process stock (`link_z`, same tool) is
/// one rapid straight across at that height; without it, or across a tool
/// change, the post climbs over its clearance height.
#[test]
fn a_planned_link_runs_straight_across_at_its_height() {
    let k = knowledge();
    let two = |link_z: Option<f64>, tool2: &str| {
        let mut plan = empty_plan();
        let mut second = op(
            2,
            tool2,
            8000.0,
            [50.0, 0.0, 2.0],
            vec![line(50.0, 0.0, -1.0, 300.0), line(50.0, 0.0, 2.0, 0.0)],
        );
        second.link_z = link_z;
        plan.operations = vec![
            op(
                1,
                "em20",
                8000.0,
                [0.0, 0.0, 2.0],
                vec![line(0.0, 0.0, -1.0, 300.0), line(0.0, 0.0, 2.0, 0.0)],
            ),
            second,
        ];
        post(
            &plan,
            k.post("linuxcnc").unwrap(),
            k.tool_set("endmills_12_20").unwrap(),
        )
        .unwrap()
    };
    // Between OP1 and OP2's comment lines.
    let between = |text: &str| -> Vec<String> {
        let a = text.find("(OP2").unwrap();
        let b = text[a..].find("G1").unwrap();
        text[a..a + b]
            .lines()
            .filter(|l| l.starts_with("G0"))
            .map(str::to_string)
            .collect()
    };
    let planned = two(Some(2.0), "em20");
    assert_eq!(between(&planned.text), ["G0 X50.000"], "{}", planned.text);
    let over = two(None, "em20");
    assert_eq!(
        between(&over.text),
        ["G0 Z12.000", "G0 X50.000", "G0 Z2.000"],
        "{}",
        over.text
    );
    assert!((over.rapid_length_mm - planned.rapid_length_mm - 20.0).abs() < 1e-9);
    // A tool change ignores the planned link.
    let changed = two(Some(2.0), "em12");
    assert_eq!(
        between(&changed.text),
        ["G0 X50.000", "G0 Z2.000"],
        "{}",
        changed.text
    );
    assert!(
        changed.text.contains("G0 Z12.000\nM5\nM9\nT1 M6"),
        "{}",
        changed.text
    );
}
