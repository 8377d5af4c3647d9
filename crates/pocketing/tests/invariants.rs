//! Path invariants on every bench pocket and on random star-shaped pockets: no gouge, gap ≤
//! stepover, continuity, and full coverage of the pocket interior (an independent raster
//! check that does not use the gap measure).

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use glam::DVec2;
use proptest::prelude::*;
use thinplan_pocketing::bench::{bench_family, bench_params, rounded_rect};
use thinplan_pocketing::geom::{point_in_loop, sample_pline, SegIndex};
use thinplan_pocketing::{curvilinear_path, offset_path, Method, Pocket, PocketParams, PocketPath};

fn check(pocket: &Pocket, params: &PocketParams, path: &PocketPath, label: &str) {
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
    if path.method == Method::Curvilinear {
        assert!(
            path.max_gap <= params.stepover + 1e-9,
            "{label}: gap {} > stepover {}",
            path.max_gap,
            params.stepover
        );
    }
    // 3. continuity (offset links are straight moves of one stepover between sampled rings)
    let slack = if path.method == Method::Curvilinear {
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

#[test]
fn bench_pockets_satisfy_invariants() {
    for l in [12.5, 100.0] {
        for bp in bench_family(l) {
            let params = bench_params(&bp);
            let off = offset_path(&bp.pocket, &params).unwrap();
            check(
                &bp.pocket,
                &params,
                &off,
                &format!("offset {} L={l}", bp.pocket.name),
            );
            let cur = curvilinear_path(&bp.pocket, &params).unwrap();
            assert_eq!(
                cur.method,
                Method::Curvilinear,
                "{}: fell back: {:?}",
                bp.pocket.name,
                cur.fallback_reason
            );
            check(
                &bp.pocket,
                &params,
                &cur,
                &format!("curvilinear {} L={l}", bp.pocket.name),
            );
        }
    }
}

#[test]
fn eigenfunction_field_also_works() {
    let bp = &bench_family(100.0)[2]; // pentagon
    let mut params = bench_params(bp);
    params.field = thinplan_pocketing::Field::Eigen;
    let cur = curvilinear_path(&bp.pocket, &params).unwrap();
    assert_eq!(cur.method, Method::Curvilinear);
    check(&bp.pocket, &params, &cur, "pentagon eigen");
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]
    #[test]
    fn random_star_shaped_pockets(
        a2 in 0.0..0.12f64, p2 in 0.0..std::f64::consts::TAU,
        a3 in 0.0..0.06f64, p3 in 0.0..std::f64::consts::TAU,
        a4 in 0.0..0.03f64, p4 in 0.0..std::f64::consts::TAU,
        size in 40.0..160.0f64,
    ) {
        let pocket = star_pocket(&[(a2, p2), (a3, p3), (a4, p4)], size);
        let params = PocketParams::for_tool(size / 8.0);
        let cur = curvilinear_path(&pocket, &params).unwrap();
        check(&pocket, &params, &cur, &format!("star {a2:.3} {a3:.3} {a4:.3} {size:.1} {:?}", cur.method));
        let off = offset_path(&pocket, &params).unwrap();
        check(&pocket, &params, &off, "star offset");
    }
}
