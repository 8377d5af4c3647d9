//! Path invariants on every bench pocket and on random star-shaped pockets: no gouge, gap ≤
//! stepover, continuity, and full coverage of the pocket interior (an independent raster
//! check that does not use the gap measure).

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use glam::DVec2;
use proptest::prelude::*;
use thinplan_pocketing::bench::{bench_family, bench_params, rounded_rect};
use thinplan_pocketing::geom::{point_in_loop, sample_pline, SegIndex};
use thinplan_pocketing::{
    curvilinear_path, offset_path, offset_path_gap_matched, offset_path_sharp, zigzag_path, Field,
    Method, Pocket, PocketParams, PocketPath,
};

fn check(pocket: &Pocket, params: &PocketParams, path: &PocketPath, label: &str) {
    check_opt(pocket, params, path, label, true);
}

fn check_opt(
    pocket: &Pocket,
    params: &PocketParams,
    path: &PocketPath,
    label: &str,
    coverage: bool,
) {
    let r = params.tool_diameter / 2.0;
    let l = pocket.size();
    let wall = sample_pline(&pocket.outer, l / 2000.0, 0.25f64.to_radians());
    let wall_idx = SegIndex::new(&[&wall], true);
    // 1. no gouge: every path point at least R from the wall and inside the pocket
    let tol = 1e-6 * l + 1e-9;
    for p in &path.points {
        assert!(
            point_in_loop(*p, &wall),
            "{label}: point {p} outside the pocket"
        );
        let d = wall_idx.nearest(*p);
        assert!(
            d >= r - tol,
            "{label}: gouge, point {p} is {d} from the wall (R = {r})"
        );
    }
    // 2. gap between successive orbits ≤ stepover (measured by the generator)
    if matches!(path.method, Method::Curvilinear | Method::OffsetSpiral) {
        assert!(
            path.max_gap <= params.stepover + 1e-9,
            "{label}: gap {} > stepover {}",
            path.max_gap,
            params.stepover
        );
    }
    // 3. continuity (offset links are straight moves of one stepover between sampled rings)
    let slack = if matches!(path.method, Method::Curvilinear | Method::OffsetSpiral) {
        1e-9
    } else {
        0.01
    };
    assert!(
        path.max_step() <= params.stepover * (1.0 + slack),
        "{label}: jump {} > stepover",
        path.max_step()
    );
    // 4. coverage: raster points of the pocket farther than a margin from the wall are within
    //    R of the path
    if !coverage {
        return;
    }
    let path_idx = SegIndex::new(&[&path.points], false);
    let margin = 0.02 * params.tool_diameter;
    let n = 120;
    let (lo, hi) = wall.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let mut uncut = 0;
    let mut worst: f64 = 0.0;
    for i in 0..=n {
        for j in 0..=n {
            let q = lo + (hi - lo) * DVec2::new(i as f64 / n as f64, j as f64 / n as f64);
            if !point_in_loop(q, &wall) || wall_idx.nearest(q) <= margin {
                continue;
            }
            let d = path_idx.nearest(q);
            if d > r + 1e-9 {
                uncut += 1;
                worst = worst.max(d - r);
            }
        }
    }
    assert_eq!(
        uncut, 0,
        "{label}: {uncut} raster points uncut (worst {worst} beyond R)"
    );
}

/// The spiral entered by a helix about its centre and started where it leaves the helix
/// circle ([`PocketPath::after_centred_helix`], radius 0.4 D as in knowledge/methods.ron's
/// closed-pocket method, or smaller where that does not fit): the helix circle (one revolution
/// ending at the new start) followed by the shortened path keeps every invariant of the whole
/// path (inside ∂Ω, no gouge, one continuous path, coverage), the path is a tail of the
/// original from a point on the circle, and it is shorter.
fn check_centred_helix(pocket: &Pocket, params: &PocketParams, path: &PocketPath, label: &str) {
    let d = params.tool_diameter;
    let radii = [0.4 * d, 0.2 * d, 0.1 * d];
    let Some((short, helix)) = path.after_centred_helix(&radii) else {
        panic!("{label}: no centred helix fits");
    };
    assert_eq!(helix.center, path.points[0], "{label}");
    // the helix fits: its circle inside ∂Ω
    let bidx = SegIndex::new(&[&path.boundary], true);
    assert!(point_in_loop(helix.center, &path.boundary), "{label}");
    assert!(bidx.nearest(helix.center) >= helix.radius, "{label}");
    let q = short.points[0];
    assert!(
        (q.distance(helix.center) - helix.radius).abs() <= 1e-9 * d,
        "{label}: start {q} not on the helix circle"
    );
    // a tail of the original path
    let k = path.points.len() - short.points.len() + 1;
    assert_eq!(&short.points[1..], &path.points[k..], "{label}");
    assert!(
        path.points[..k]
            .iter()
            .all(|p| p.distance(helix.center) <= helix.radius + 1e-9),
        "{label}: a dropped point lies outside the helix circle"
    );
    assert_eq!(
        path.points.len() - short.points.len(),
        path.finish_start - short.finish_start,
        "{label}: finishing pass moved"
    );
    assert!(short.length() < path.length(), "{label}: not shorter");
    // helix, then the path, as one tool-centre path
    let n =
        ((std::f64::consts::TAU * helix.radius / (0.25 * params.stepover)).ceil() as usize).max(8);
    let a0 = (q - helix.center).to_angle();
    let mut whole = short.clone();
    whole.points = (0..n)
        .map(|j| {
            let a = a0 + std::f64::consts::TAU * j as f64 / n as f64;
            helix.center + helix.radius * DVec2::from_angle(a)
        })
        .chain(short.points.iter().copied())
        .collect();
    whole.finish_start += n;
    check(pocket, params, &whole, &format!("{label} + centred helix"));
}

/// Offset and curvilinear paths of one bench pocket at size `l`, checked. `coarse` meshes the
/// PDE at half the stepover instead of a third (2.25× fewer elements) for the
/// default test run; the ignored sweeps use the production mesh.
fn bench_case(name: &str, l: f64, coarse: bool, field: thinplan_pocketing::Field) {
    let bp = bench_family(l)
        .into_iter()
        .find(|b| b.pocket.name == name)
        .unwrap();
    let mut params = bench_params(&bp);
    params.field = field;
    if coarse {
        params.mesh_size = Some(params.stepover / 2.0);
    }
    let off = offset_path(&bp.pocket, &params).unwrap();
    check(&bp.pocket, &params, &off, &format!("offset {name} L={l}"));
    check_baselines(&bp.pocket, &params, &off, &format!("{name} L={l}"));
    let cur = curvilinear_path(&bp.pocket, &params).unwrap();
    assert!(
        matches!(cur.method, Method::Curvilinear | Method::OffsetSpiral),
        "{name}: fell back: {:?}",
        cur.fallback_reason
    );
    assert!(cur.choice.is_some(), "{name}: no provenance of the choice");
    // every bench pocket is star-shaped about its centre or ridge, so both spirals must be
    // built and compared (the triangle's offset spiral was refused while its contours came
    // from the distance interpolated on the mesh, notched at the ridge)
    let choice = cur.choice.as_deref().unwrap_or("");
    assert!(
        !choice.contains("failed"),
        "{name} L={l}: a spiral was refused: {choice}"
    );
    check(
        &bp.pocket,
        &params,
        &cur,
        &format!("curvilinear {name} L={l} {field:?}"),
    );
    check_centred_helix(
        &bp.pocket,
        &params,
        &cur,
        &format!("curvilinear {name} L={l} {field:?}"),
    );
    // the spiral can never have fewer turns than the radial bound (a spiral with gap ≤ s); the
    // bench reports how far above it each pocket is (slot: 19 vs 16, crowding at the ends)
    if let Some(bound) = cur.turns_lower_bound(params.stepover) {
        let turns = cur.roughing_turns();
        assert!(
            turns >= bound,
            "{name} L={l}: {turns} spiral turns below the bound {bound}"
        );
    } else {
        assert_eq!(cur.method, Method::OffsetSpiral, "{name}: no turn bound");
    }
}

/// The sharp-cornered and the gap-matched offset baselines: same invariants as the offset
/// path (no gouge, coverage, links ≤ one ring step); sharp rings are polylines (no roughing arc
/// left: fewer points, never longer, the same finishing pass); gap-matched rings
/// keep the measured gap ≤ the stepover.
fn check_baselines(pocket: &Pocket, params: &PocketParams, off: &PocketPath, label: &str) {
    let sharp = offset_path_sharp(pocket, params).unwrap();
    check(pocket, params, &sharp, &format!("offset-sharp {label}"));
    // same rings, arcs → chords: never longer, fewer points, the same finishing pass
    assert!(
        sharp.length() <= off.length() + 1e-6,
        "{label}: sharp longer"
    );
    // a circle's rings have no straight sides, so no fillet to flatten: the same path
    let fillets = pocket.name != "circle";
    assert!(
        sharp.points.len() < off.points.len() || (!fillets && sharp.points == off.points),
        "{label}: no arc flattened"
    );
    let finish_len = |p: &PocketPath| -> f64 {
        p.points[p.finish_start..]
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .sum()
    };
    assert!(
        (finish_len(&sharp) - finish_len(off)).abs() <= 1e-6 * finish_len(off),
        "{label}: finishing pass differs"
    );
    let (gm, ring_step) = offset_path_gap_matched(pocket, params).unwrap();
    assert!(ring_step <= params.stepover && ring_step > 0.3 * params.stepover);
    assert!(
        gm.max_gap <= params.stepover + 1e-9,
        "{label}: gap-matched gap {} > {}",
        gm.max_gap,
        params.stepover
    );
    let mut p = params.clone();
    p.stepover = ring_step.max(p.finish_stepover);
    check(pocket, &p, &gm, &format!("offset-gap-matched {label}"));
    for deg in [0.0, 30.0, 90.0] {
        let zz = zigzag_path(pocket, params, f64::to_radians(deg)).unwrap();
        let label = format!("zigzag {deg}° {label}");
        check(pocket, params, &zz, &label);
        check_zigzag_passes(params, &zz, deg, &label);
    }
}

/// The zigzag's passes, found independently of its generator: the straight runs along the pass
/// direction longer than a tool radius. Successive passes lie at most one stepover apart, and
/// alternate in direction; the finishing pass is the same loop as the offset path's.
fn check_zigzag_passes(params: &PocketParams, zz: &PocketPath, deg: f64, label: &str) {
    let dir = DVec2::from_angle(deg.to_radians());
    let normal = dir.perp();
    let rough = &zz.points[..zz.finish_start];
    // runs of consecutive segments along ±dir
    let mut passes: Vec<(f64, f64)> = Vec::new(); // (offset across, signed length)
    let mut i = 0;
    while i + 1 < rough.len() {
        let along = |k: usize| {
            let d = rough[k + 1] - rough[k];
            let l = d.length();
            (l > 0.0 && (d.dot(normal) / l).abs() < 1e-9).then(|| d.dot(dir).signum())
        };
        if let Some(sign) = along(i) {
            let start = i;
            while i + 1 < rough.len() && along(i) == Some(sign) {
                i += 1;
            }
            let len = (rough[i] - rough[start]).dot(dir);
            if len.abs() > params.tool_diameter / 2.0 {
                passes.push((rough[start].dot(normal), len));
            }
        } else {
            i += 1;
        }
    }
    assert!(passes.len() >= 2, "{label}: {} passes", passes.len());
    for w in passes.windows(2) {
        let gap = (w[1].0 - w[0].0).abs();
        assert!(
            gap <= params.stepover * (1.0 + 1e-9) && gap > 0.0,
            "{label}: passes {gap} apart (stepover {})",
            params.stepover
        );
        assert!(w[0].1 * w[1].1 < 0.0, "{label}: passes not alternating");
    }
}

// Default run: a representative subset on coarser (still converged-enough) meshes. The full
// sweeps are `#[ignore]`d: `cargo test --release -p thinplan-pocketing -- --ignored`.

#[test]
fn pentagon_satisfies_invariants() {
    bench_case("pentagon", 50.0, true, Field::Poisson);
}

#[test]
fn isogrid_triangle_satisfies_invariants() {
    bench_case("isogrid-triangle", 50.0, true, Field::Poisson);
}

#[test]
fn slot_satisfies_invariants() {
    // elongated: the offset spiral about the ridge wins (the PDE's contours crowd at the ends)
    bench_case("slot", 50.0, false, Field::Poisson);
}

/// The slot's offset spiral: wound about its ridge (a segment), it needs about as many turns as
/// the offset path has rings (half-width / stepover), not the PDE spiral's crowded ends, so it is
/// far shorter than the PDE spiral and no longer than the offsets held to the same gap.
#[test]
fn slot_uses_the_offset_spiral_about_its_ridge() {
    let bp = bench_family(50.0)
        .into_iter()
        .find(|b| b.pocket.name == "slot")
        .unwrap();
    let params = bench_params(&bp);
    let cur = curvilinear_path(&bp.pocket, &params).unwrap();
    assert_eq!(cur.method, Method::OffsetSpiral, "{:?}", cur.choice);
    assert!(cur.max_gap <= params.stepover + 1e-9);
    let (gm, _) = offset_path_gap_matched(&bp.pocket, &params).unwrap();
    assert!(
        cur.length() <= 1.02 * gm.length(),
        "offset spiral {} vs gap-matched offsets {}",
        cur.length(),
        gm.length()
    );
}

#[test]
fn eigenfunction_field_also_works() {
    bench_case("isogrid-triangle", 100.0, true, Field::Eigen);
}

#[test]
#[ignore]
fn full_sweep_bench_pockets_satisfy_invariants() {
    for l in [12.5, 100.0] {
        for bp in bench_family(l) {
            bench_case(&bp.pocket.name, l, false, Field::Poisson);
        }
    }
}

#[test]
#[ignore]
fn full_sweep_eigenfunction_field() {
    for bp in bench_family(100.0) {
        bench_case(&bp.pocket.name, 100.0, false, Field::Eigen);
    }
}

#[test]
fn islands_fall_back_to_offsets() {
    let mut island = rounded_rect(20.0, 20.0, 4.0);
    island.invert_direction_mut();
    let pocket = Pocket::with_islands("island", rounded_rect(100.0, 80.0, 12.0), vec![island]);
    let params = PocketParams::for_tool(10.0);
    let cur = curvilinear_path(&pocket, &params).unwrap();
    assert_eq!(cur.method, Method::OffsetFallback);
    assert!(cur.fallback_reason.as_deref().unwrap().contains("island"));
}

#[test]
fn non_star_shaped_pocket_falls_back_and_is_still_safe() {
    // a C shape: the offset region is not star-shaped about any interior maximum
    let mut pl = Polyline::new_closed();
    for (x, y) in [
        (0.0, 0.0),
        (100.0, 0.0),
        (100.0, 30.0),
        (30.0, 30.0),
        (30.0, 70.0),
        (100.0, 70.0),
        (100.0, 100.0),
        (0.0, 100.0),
    ] {
        pl.add(x, y, 0.0);
    }
    let pocket = Pocket::new("C", pl);
    let params = PocketParams::for_tool(8.0);
    let cur = curvilinear_path(&pocket, &params).unwrap();
    eprintln!("C shape: {:?} {:?}", cur.method, cur.fallback_reason);
    assert_eq!(cur.method, Method::OffsetFallback);
    // sharp pocket corners leave material the tool cannot reach; check only no gouge here
    let wall = sample_pline(&pocket.outer, 0.05, 0.01);
    let idx = SegIndex::new(&[&wall], true);
    for p in &cur.points {
        assert!(idx.nearest(*p) >= 4.0 - 1e-6);
    }
}

fn star_pocket(amps: &[(f64, f64)], size: f64) -> Pocket {
    let n = 96;
    let mut pl = Polyline::new_closed();
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        let mut r = 1.0;
        for (k, (a, ph)) in amps.iter().enumerate() {
            r += a * ((k as f64 + 2.0) * t + ph).cos();
        }
        let p = 0.5 * size * r * DVec2::from_angle(t);
        pl.add(p.x, p.y, 0.0);
    }
    assert!(pl.area() > 0.0);
    Pocket::new("star", pl)
}

fn star_case(a: [(f64, f64); 3], size: f64, coarse: bool) {
    let pocket = star_pocket(&a, size);
    let mut params = PocketParams::for_tool(size / 8.0);
    if coarse {
        params.mesh_size = Some(params.stepover / 2.0);
    }
    let cur = curvilinear_path(&pocket, &params).unwrap();
    check(
        &pocket,
        &params,
        &cur,
        &format!("star {a:?} {size:.1} {:?}", cur.method),
    );
    if cur.method != Method::OffsetFallback {
        check_centred_helix(&pocket, &params, &cur, &format!("star {a:?} {size:.1}"));
    }
    // The offset baseline is not checked for coverage here: on star pockets whose inner rings
    // get corners sharper than ~47° the gap between rings exceeds 2R and plain parallel
    // offsets leave material (README, known gaps; seed in invariants.proptest-regressions).
    let off = offset_path(&pocket, &params).unwrap();
    check_opt(&pocket, &params, &off, "star offset", false);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2))]
    #[test]
    fn random_star_shaped_pockets(
        a2 in 0.0..0.12f64, p2 in 0.0..std::f64::consts::TAU,
        a3 in 0.0..0.06f64, p3 in 0.0..std::f64::consts::TAU,
        a4 in 0.0..0.03f64, p4 in 0.0..std::f64::consts::TAU,
        size in 40.0..160.0f64,
    ) {
        star_case([(a2, p2), (a3, p3), (a4, p4)], size, true);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    #[test]
    #[ignore]
    fn full_sweep_random_star_shaped_pockets(
        a2 in 0.0..0.12f64, p2 in 0.0..std::f64::consts::TAU,
        a3 in 0.0..0.06f64, p3 in 0.0..std::f64::consts::TAU,
        a4 in 0.0..0.03f64, p4 in 0.0..std::f64::consts::TAU,
        size in 40.0..160.0f64,
    ) {
        star_case([(a2, p2), (a3, p3), (a4, p4)], size, false);
    }
}
