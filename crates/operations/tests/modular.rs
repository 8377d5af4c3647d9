//! Independent checks of the modular tool paths on synthetic features:
//! product distance, floor, coverage, no plunges, climb boundary passes,
//! mirrored layers, determinism.

mod common;

use common::*;
use glam::DVec2;
use thinplan_knowledge::Knowledge;
use thinplan_operations::{operations, summary, Operations};
use thinplan_plan::{Adjacency, MachiningFeature, Region3};

fn run(f: MachiningFeature) -> (MachiningFeature, Operations, Knowledge) {
    let k = Knowledge::builtin().unwrap();
    let plan = plan_with(vec![f.clone()]);
    let ops = operations(&plan, &k).unwrap();
    assert!(
        ops.refusals.is_empty(),
        "refused: {:?}\nwarnings: {:?}",
        ops.refusals,
        ops.warnings
    );
    assert!(!ops.operations.is_empty());
    (f, ops, k)
}

/// (a) no tool centre of a feed move is closer than r to a product edge;
/// nothing below the floor; rapids only above the feature.
fn check_product_and_floor(f: &MachiningFeature, ops: &Operations, k: &Knowledge) {
    let product: Vec<_> = edges(f)
        .into_iter()
        .filter(|e| e.3 == Adjacency::Product)
        .collect();
    for op in &ops.operations {
        let r = radius(k, op);
        for (p, dir, region) in walk(op, 0.05) {
            if region == Region3::Rapid {
                // Vertical retracts may start low; sideways rapids run above.
                if dir != DVec2::ZERO {
                    assert!(p.z >= f.shape.z_max - 1e-9, "{}: rapid at z {}", op.id, p.z);
                }
                continue;
            }
            // A through feature (an open bottom on the blank's underside) is
            // cut free below it by the corner radius and the breakthrough.
            let floor = if f.bottom_adjacency == Adjacency::Open {
                let rc = k
                    .tool_set("endmills_12_20")
                    .unwrap()
                    .tools
                    .iter()
                    .map(|t| t.corner_radius)
                    .fold(0.0, f64::max);
                f.shape.z_min - rc - k.methods.breakthrough
            } else {
                f.shape.z_min
            };
            assert!(p.z >= floor - 1e-9, "{}: below the floor: {p}", op.id);
            for &(a, b, bulge, _) in &product {
                let q = closest_on_edge(p.truncate(), a, b, bulge);
                let d = q.distance(p.truncate());
                let slack = 1e-6;
                assert!(
                    d >= r - slack,
                    "{} {:?}: centre {p} is {d} from product edge {a}→{b}, r = {r}",
                    op.id,
                    region
                );
            }
        }
    }
}

/// (b) coverage: at the final depth every region sample (0.2 mm grid) is
/// within r of a cutting move at that depth.
fn check_coverage(f: &MachiningFeature, ops: &Operations, k: &Knowledge) {
    // A through feature's final depth is below its floor (the breakthrough).
    let z = if f.bottom_adjacency == Adjacency::Open {
        ops.operations
            .iter()
            .flat_map(|op| walk(op, 0.02))
            .filter(|(_, _, region)| is_cutting(*region))
            .map(|(p, _, _)| p.z)
            .fold(f.shape.z_min, f64::min)
    } else {
        f.shape.z_min
    };
    let mut segs = Vec::new();
    let mut r = f64::INFINITY;
    for op in &ops.operations {
        r = r.min(radius(k, op));
        let pts = walk(op, 0.02);
        for w in pts.windows(2) {
            let (a, b) = (w[0].0, w[1].0);
            if is_cutting(w[1].2) && (a.z - z).abs() < 1e-9 && (b.z - z).abs() < 1e-9 {
                segs.push((a.truncate(), b.truncate()));
            }
        }
    }
    assert!(!segs.is_empty(), "no cutting move at the floor z {z}");
    let idx = LevelIndex::new(&segs, r + 1.0);
    let polys = region_polys(f);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in polys.iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let mut worst = (0.0, DVec2::ZERO);
    let mut y = lo.y + 0.1;
    while y < hi.y {
        let mut x = lo.x + 0.1;
        while x < hi.x {
            let p = DVec2::new(x, y);
            if inside(p, &polys) {
                let d = idx.nearest(p);
                if d > worst.0 {
                    worst = (d, p);
                }
            }
            x += 0.2;
        }
        y += 0.2;
    }
    // 1e-4: chords of sampled arcs (0.02 mm) lie inside the true arcs.
    assert!(
        worst.0 <= r + 1e-4,
        "region point {} is {} from every cutting move at the floor (r = {r})",
        worst.1,
        worst.0
    );
}

/// (c) no plunge: a cutting move that descends has a horizontal run with
/// slope at most the ramp angle.
fn check_no_plunge(ops: &Operations, angle_deg: f64) {
    let tan = angle_deg.to_radians().tan();
    for op in &ops.operations {
        let mut from = op.start;
        for m in &op.moves {
            let dz = from.z - m.to.z;
            if is_cutting(m.region) && dz > 1e-9 {
                let pts = move_points(from, m, 0.01);
                let mut h = 0.0;
                let mut prev = from;
                for p in pts {
                    h += (p - prev).truncate().length();
                    prev = p;
                }
                assert!(
                    dz <= h * tan + 1e-6,
                    "{}: a {:?} move descends {dz} over {h} horizontally",
                    op.id,
                    m.region
                );
            }
            from = m.to;
        }
    }
}

/// (d) boundary passes along product are climb (M3): the product lies on
/// the right of the travel.
fn check_climb(f: &MachiningFeature, ops: &Operations, k: &Knowledge) -> usize {
    let product: Vec<_> = edges(f)
        .into_iter()
        .filter(|e| e.3 == Adjacency::Product)
        .collect();
    let mut checked = 0;
    for op in &ops.operations {
        let r = radius(k, op);
        for (p, dir, region) in walk(op, 0.25) {
            if region != Region3::Boundary || dir == DVec2::ZERO {
                continue;
            }
            let p2 = p.truncate();
            let (q, d) = product
                .iter()
                .map(|&(a, b, bulge, _)| {
                    let q = closest_on_edge(p2, a, b, bulge);
                    (q, q.distance(p2))
                })
                .min_by(|x, y| x.1.total_cmp(&y.1))
                .unwrap();
            if (d - r).abs() > 1e-3 {
                continue; // a run-up or run-off, not along the product
            }
            let towards_product = (q - p2).normalize();
            // Right of travel: cross(dir, n) < 0.
            assert!(
                dir.perp_dot(towards_product) < -0.5,
                "{}: boundary move at {p} is not climb (dir {dir}, product side {towards_product})",
                op.id
            );
            checked += 1;
        }
    }
    checked
}

fn all_checks(f: MachiningFeature) -> (Operations, Knowledge) {
    let (f, ops, k) = run(f);
    check_product_and_floor(&f, &ops, &k);
    check_coverage(&f, &ops, &k);
    check_no_plunge(&ops, 3.0);
    (ops, k)
}

#[test]
fn open_step_beside_a_wall() {
    let (ops, k) = all_checks(step(0));
    let n = check_climb(&step(0), &ops, &k);
    assert!(n > 100, "only {n} boundary samples along the product");
    let op = &ops.operations[0];
    assert_eq!(op.method, "partially_open");
    // Largest tool that fits: Ø20.
    assert_eq!(op.tool, "em20");
    let s = summary(op);
    eprintln!("step: {s:?} warnings {:?}", ops.warnings);
    // Finishing conditions only on boundary moves.
    let fin = op.provenance.values["feed_finish_mm_min"];
    for m in &op.moves {
        if m.region == Region3::Boundary {
            assert_eq!(m.feed, fin);
        } else if m.region != Region3::Rapid {
            assert!(m.feed > fin);
        }
    }
}

#[test]
fn closed_pocket_with_product_floor() {
    let (ops, k) = all_checks(pocket(0));
    assert!(check_climb(&pocket(0), &ops, &k) > 100);
    // The corner radius 8 rules out the Ø20: the Ø12 is used.
    assert!(ops.operations.iter().all(|o| o.tool == "em12"));
    // A main operation and a separate bottom layer.
    assert_eq!(ops.operations.len(), 2, "{:?}", ops.warnings);
    assert!(ops.operations[1].provenance.rule.ends_with("bottom_layer"));
    for o in &ops.operations {
        eprintln!("pocket: {:?} {}", summary(o), o.provenance.note);
    }
    // True arcs reach the program (the boundary pass follows the fillets).
    assert!(ops.operations[0].moves.iter().any(|m| m.arc.is_some()));
}

/// The spiral is entered by a helix about its own centre (radius from the
/// closed-pocket method) and starts where it leaves the helix's circle,
/// where the helix ended (the part of the spiral inside that circle lies in
/// the hole the helix clears and is left out); the floor is still fully
/// covered (the coverage check in `all_checks`).
#[test]
fn a_closed_pocket_is_entered_by_a_helix_about_the_spiral_centre() {
    let (ops, _) = all_checks(pocket(0));
    let op = &ops.operations[0];
    assert!(
        op.provenance.note.contains("entry=centred helix"),
        "{}",
        op.provenance.note
    );
    let cutting: Vec<&thinplan_plan::PathMove> = op
        .moves
        .iter()
        .filter(|m| !matches!(m.region, Region3::Rapid | Region3::Link))
        .collect();
    let first = cutting[0]
        .arc
        .expect("the first cutting move is a helix arc");
    let c = first.centre.truncate();
    let helix_len = cutting
        .iter()
        .take_while(|m| {
            m.arc
                .is_some_and(|a| a.centre.truncate().distance(c) < 1e-6)
        })
        .count();
    assert!(helix_len >= 2, "a helix of at least one turn");
    let end = cutting[helix_len - 1].to;
    let rho = end.truncate().distance(c);
    let scales = &thinplan_knowledge::Knowledge::builtin()
        .unwrap()
        .methods
        .fit_scales;
    assert!(
        scales.iter().any(|s| (rho - s * 0.4 * 12.0).abs() < 1e-3),
        "ρ = {rho} for scales {scales:?}"
    );
    // Right after the helix the spiral goes on from where the helix ended,
    // at the same height: no descent, no jump back to the centre.
    let next = cutting[helix_len].to;
    assert!((next.z - end.z).abs() < 1e-9);
    assert!(next.truncate().distance(c) > 0.5 * rho, "{next:?}");
}

#[test]
fn l_shape_with_an_island() {
    let (ops, k) = all_checks(l_with_island(0));
    assert!(check_climb(&l_with_island(0), &ops, &k) > 100);
    for o in &ops.operations {
        eprintln!("L: {:?}", summary(o));
    }
}

#[test]
fn feature_edge_lets_the_tool_cross_half_its_diameter_at_most() {
    let f = with_feature_edge(0);
    let (ops, k) = all_checks(f.clone());
    check_climb(&f, &ops, &k);
    for op in &ops.operations {
        let r = radius(&k, op);
        for (p, _, region) in walk(op, 0.1) {
            if region == Region3::Rapid {
                continue;
            }
            // The Feature edge is x = 60 for y in [0, 40]: the tool's edge
            // passes it by at most r (the centre stays at x ≤ 60).
            if p.y > 0.0 && p.y < 40.0 {
                assert!(
                    p.x <= 60.0 + 1e-6,
                    "{}: centre {p} beyond the feature edge",
                    op.id
                );
            }
            let _ = r;
        }
    }
}

#[test]
fn alternate_layers_are_mirrored() {
    let (f, ops, _k) = run(open_block(0));
    check_no_plunge(&ops, 3.0);
    let op = &ops.operations[0];
    assert!(
        op.provenance.note.contains("mirror=alternate"),
        "{}",
        op.provenance.note
    );
    // Flat rest moves per z-level, as xy points in order.
    let mut levels: Vec<(f64, Vec<DVec2>)> = Vec::new();
    let mut from = op.start;
    for m in &op.moves {
        if m.region == Region3::Rest && (from.z - m.to.z).abs() < 1e-12 {
            match levels.last_mut() {
                Some((z, pts)) if (*z - m.to.z).abs() < 1e-12 => pts.push(m.to.truncate()),
                _ => levels.push((m.to.z, vec![from.truncate(), m.to.truncate()])),
            }
        }
        from = m.to;
    }
    let levels: Vec<_> = {
        // Ramps end with a flat return; keep each level's pattern from
        // where the ramp finished (the last run of flat moves).
        let mut by_z: Vec<(f64, Vec<DVec2>)> = Vec::new();
        for (z, pts) in levels {
            match by_z.last_mut() {
                Some((zz, p)) if (*zz - z).abs() < 1e-12 => *p = pts,
                _ => by_z.push((z, pts)),
            }
        }
        by_z
    };
    assert!(levels.len() >= 2, "levels: {}", levels.len());
    let a = &levels[0].1;
    let b = &levels[1].1;
    // The second level starts where the first ended (no link between
    // them) and retraces it backwards; its ramp may add a flat return first.
    let a_end = *a.last().unwrap();
    let j = b
        .iter()
        .position(|p| p.distance(a_end) < 1e-6)
        .expect("level 2 passes through the end of level 1");
    let mut ra: Vec<DVec2> = a.clone();
    ra.reverse();
    let pattern = &b[j..];
    for (p, q) in pattern.iter().zip(&ra) {
        assert!(p.distance(*q) < 1e-6, "{p} vs {q}");
    }
    // Both levels run the same passes (same length of pattern).
    assert!(pattern.len() >= 5);
    let _ = f;
}

#[test]
fn same_plan_same_operations_twice() {
    let k = Knowledge::builtin().unwrap();
    let plan = plan_with(vec![
        step(0),
        pocket(1),
        l_with_island(2),
        with_feature_edge(3),
    ]);
    let a = operations(&plan, &k).unwrap();
    let b = operations(&plan, &k).unwrap();
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    let mut p = plan.clone();
    a.apply_to(&mut p);
    let order = thinplan_operations::order(&p, &k).unwrap();
    thinplan_operations::order::apply_order(&mut p, order);
    assert_eq!(p.operation_order.len(), p.operations.len());
    let mut total = 0.0;
    for o in &p.operations {
        let s = summary(o);
        total += s.time_s;
        eprintln!(
            "{} {} {} {} layers {} length {:.1} mm time {:.2} s",
            s.id, s.feature, s.tool, s.pattern, s.layers, s.length_mm, s.time_s
        );
    }
    eprintln!("total {total:.1} s");
}

#[test]
fn a_plan_without_resolve_is_an_error() {
    let k = Knowledge::builtin().unwrap();
    let mut plan = plan_with(vec![step(0)]);
    plan.stages_done
        .retain(|s| *s != thinplan_plan::Stage::Resolve);
    assert!(operations(&plan, &k).is_err());
}

/// A strip narrower than the tool with every edge open: the centre region
/// reaches a radius past each long side, but one line down the middle clears
/// the strip (every point within r of it); lines farther out would only
/// graze what it cut. With all edges open the flange's cut-out
/// slabs got three times the lines they needed.
#[test]
fn a_narrow_open_strip_is_cleared_by_one_line_down_its_middle() {
    let strip = feature(
        0,
        vec![v(0.0, 0.0), v(80.0, 0.0), v(80.0, 8.0), v(0.0, 8.0)],
        vec![],
        vec![Adjacency::Open; 4],
        Adjacency::Open,
        (0.0, 3.0),
    );
    let (f, ops, k) = run(strip);
    check_no_plunge(&ops, 3.0);
    let mut lines = 0;
    for op in &ops.operations {
        let r = radius(&k, op);
        assert!(r > 4.0, "the tool (r {r}) is wider than the strip");
        let mut from = op.start;
        for m in &op.moves {
            let flat = (from.z - m.to.z).abs() < 1e-9 && m.arc.is_none();
            let d = m.to.truncate() - from.truncate();
            if flat && is_cutting(m.region) && d.x.abs() > 40.0 {
                lines += 1;
                // Along the strip, on its middle.
                assert!(d.y.abs() < 1e-6, "{from} -> {}", m.to);
                assert!((m.to.y - 4.0).abs() < 1e-6, "line at y {}", m.to.y);
            }
            from = m.to;
        }
    }
    assert!(lines >= 1);
    check_product_and_floor(&f, &ops, &k);
}

/// A drafted wall (sloped faces): the step's product wall (y = 30)
/// leans into the step at its bottom — the face lies `(z − 10)·0.05` beyond
/// the region's edge. Followed, every cutting tool centre at the bottom
/// level keeps the distance the tool's profile needs from that face (the
/// largest section radius less the face's offset over the profile's
/// heights, sampled densely here), which is more than r; samples a
/// hand-edited plan spoils are refused with the reason, and the step is
/// then planned as if the wall were vertical.
#[test]
fn a_drafted_wall_keeps_the_tool_off_its_foot() {
    let slopes = |heights: Vec<f64>| thinplan_plan::EdgeSlopes {
        side: vec![
            Vec::new(),
            Vec::new(),
            heights.iter().map(|z| (z - 10.0) * 0.05).collect(),
            Vec::new(),
        ],
        heights,
        holes: Vec::new(),
    };
    let mut f = step(1);
    f.slopes = Some(slopes(vec![0.0, 10.0, 20.0]));
    let (_, ops, k) = run(f.clone());
    let tool = k
        .tool_sets
        .values()
        .flat_map(|s| &s.tools)
        .find(|t| t.id == ops.operations[0].tool)
        .unwrap()
        .clone();
    let (r, rc) = (tool.diameter / 2.0, tool.corner_radius);
    let need = (0..=100_000)
        .map(|i| {
            let h = 25.0 * i as f64 / 100_000.0;
            let rho = if h >= rc {
                r
            } else {
                r - rc + (rc * rc - (rc - h) * (rc - h)).sqrt()
            };
            rho - (h.min(20.0) - 10.0) * 0.05
        })
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(need > r + 0.4, "{need}");
    let mut nearest = f64::INFINITY;
    for op in &ops.operations {
        let shift = op.provenance.values["slope_shift_mm"];
        assert!((shift - (r - need)).abs() < 1e-3, "{shift} vs {}", r - need);
        for m in &op.moves {
            // Along the wall: past its ends (x < 0, x > 100) the tool may
            // pivot about them, nearer the wall's line.
            if m.region != Region3::Rapid && m.to.z < 1e-6 && (0.0..=100.0).contains(&m.to.x) {
                nearest = nearest.min(30.0 - m.to.y);
            }
        }
    }
    assert!(nearest >= need - 1e-6, "{nearest} < {need}");
    assert!(
        nearest < need + 0.05,
        "the boundary pass runs at it: {nearest}"
    );

    // Spoilt samples: heights not ascending.
    f.slopes = Some(slopes(vec![0.0, 20.0, 10.0]));
    let (_, spoilt, _) = run(f.clone());
    assert!(
        spoilt
            .warnings
            .iter()
            .any(|w| w.contains("MF1") && w.contains("cannot be used")),
        "{:?}",
        spoilt.warnings
    );
    f.slopes = None;
    let (_, vertical, _) = run(f);
    let moves = |o: &Operations| -> Vec<String> {
        o.operations
            .iter()
            .map(|op| format!("{:?}", op.moves))
            .collect()
    };
    assert_eq!(moves(&spoilt), moves(&vertical));
}

/// A cut-out exactly as wide as the largest tool in a 2 mm flange (the
/// wing rib's stringer cut-outs): the Ø20's centre region across the flange
/// is a line, so its passes reach in from beside the flange only, and their
/// discs leave strips along the cut-out's sides at the flange's far faces.
/// The wall rest pass takes them with the Ø12 inside the cut-out: every
/// point 0.05 mm from a side, across the flange's thickness, lies within a
/// tool radius of a cutting move at the floor.
#[test]
fn a_cut_out_as_wide_as_the_tool_gets_its_sides_finished() {
    let f = feature(
        0,
        vec![
            v(140.0, 118.0),
            v(160.0, 118.0),
            v(160.0, 120.0),
            v(140.0, 120.0),
        ],
        vec![],
        vec![
            Adjacency::Open,
            Adjacency::Product,
            Adjacency::Open,
            Adjacency::Product,
        ],
        Adjacency::Product,
        (23.0, 25.0),
    );
    let k = Knowledge::builtin().unwrap();
    let mut plan = plan_with(vec![f.clone()]);
    // the flange: product beside the cut-out, air on both sides of it
    with_blank(&mut plan, [100.0, 118.0, 200.0, 120.0]);
    let ops = operations(&plan, &k).unwrap();
    assert!(ops.refusals.is_empty(), "{:?}", ops.refusals);
    check_product_and_floor(&f, &ops, &k);
    let z = f.shape.z_min;
    let mut discs = Vec::new();
    for op in &ops.operations {
        let r = radius(&k, op);
        for w in walk(op, 0.02).windows(2) {
            let (a, b) = (w[0].0, w[1].0);
            if is_cutting(w[1].2) && (a.z - z).abs() < 1e-9 && (b.z - z).abs() < 1e-9 {
                discs.push((a.truncate(), b.truncate(), r));
            }
        }
    }
    for x in [140.05, 159.95] {
        for j in 0..=18 {
            let p = DVec2::new(x, 118.05 + 0.1 * j as f64);
            let reached = discs
                .iter()
                .any(|(a, b, r)| seg_dist(p, *a, *b) <= r + 1e-4);
            assert!(
                reached,
                "the cut-out's side at {p} is never reached at the floor"
            );
        }
    }
}

/// A pocket open along one side, its far corners rounded for the Ø20, with
/// an island 18 mm below its far wall: the Ø20 never comes between them,
/// the Ø16 (corner radius 1) finishes both walls of the gap at every level
/// and leaves its fillet along their feet. The floor rest pass (corner
/// radius 0.5) finishes that fillet too: at 0.3 mm from each wall, along the
/// gap's middle, the lowest tip of any cutting move's bull-nose envelope
/// lies within 0.05 mm of the floor (the Ø16 alone leaves 0.29 mm).
#[test]
fn the_floor_rest_pass_finishes_the_fillet_a_wall_rest_pass_leaves() {
    // Resolved features have straight edges: the corners as 24 chords each.
    let corner = |c: (f64, f64), from: f64| {
        (0..24).map(move |k| {
            let a = (from + 90.0 * k as f64 / 24.0).to_radians();
            v(c.0 + 10.5 * a.cos(), c.1 + 10.5 * a.sin())
        })
    };
    let mut outer = vec![v(0.0, 0.0), v(60.0, 0.0)];
    outer.extend(corner((49.5, 29.5), 0.0));
    outer.extend(corner((10.5, 29.5), 90.0));
    outer.push(v(0.0, 29.5));
    let mut side = vec![Adjacency::Product; outer.len()];
    side[0] = Adjacency::Open;
    let f = feature(
        0,
        outer,
        vec![vec![
            v(20.0, 12.0),
            v(20.0, 26.0),
            v(40.0, 26.0),
            v(40.0, 12.0),
        ]],
        side,
        Adjacency::Product,
        (2.0, 8.0),
    );
    let k = Knowledge::builtin().unwrap();
    let mut plan = plan_with(vec![f.clone()]);
    plan.setup.tool_set = "alu_hsm".into();
    with_blank(&mut plan, [0.0, 0.0, 60.0, 40.0]);
    let ops = operations(&plan, &k).unwrap();
    assert!(ops.refusals.is_empty(), "{:?}", ops.refusals);
    let tools = &k.tool_set("alu_hsm").unwrap().tools;
    let z = f.shape.z_min;
    // (a, b, R, corner radius) of every cutting stretch
    let mut cuts = Vec::new();
    for op in &ops.operations {
        let t = tools.iter().find(|t| t.id == op.tool).unwrap();
        for w in walk(op, 0.02).windows(2) {
            if is_cutting(w[1].2) {
                cuts.push((w[0].0, w[1].0, 0.5 * t.diameter, t.corner_radius));
            }
        }
    }
    let lowest = |p: DVec2| {
        cuts.iter()
            .filter_map(|&(a, b, big, r)| {
                let d = seg_dist(p, a.truncate(), b.truncate());
                if d > big {
                    return None;
                }
                let out = (d - (big - r)).max(0.0);
                let lift = r - (r * r - out * out).max(0.0).sqrt();
                Some(a.z.max(b.z) + lift)
            })
            .fold(f64::INFINITY, f64::min)
    };
    for y in [26.3, 39.7] {
        for j in 0..=8 {
            let p = DVec2::new(26.0 + j as f64, y);
            let h = lowest(p);
            assert!(
                h <= z + 0.05,
                "at {p} the floor is left {:.3} mm high",
                h - z
            );
        }
    }
}
