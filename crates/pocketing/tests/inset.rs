//! The inward offset of sections through fillets (`inset`).

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use proptest::prelude::*;
use thinplan_pocketing::inset::{inset, simplified};

fn fillet_section() -> Polyline<f64> {
    let v: serde_json::Value =
        serde_json::from_str(include_str!("data/fillet_section.json")).unwrap();
    let mut p = Polyline::new_closed();
    for q in v["outer"].as_array().unwrap() {
        let f = |i: usize| q[i].as_f64().unwrap();
        p.add(f(0), f(1), f(2));
    }
    if p.area() < 0.0 {
        p.invert_direction_mut();
    }
    p
}

/// Distance from (x, y) to the straight-edged loop `p`.
fn dist_to(p: &Polyline<f64>, x: f64, y: f64) -> f64 {
    let n = p.vertex_count();
    (0..n)
        .map(|i| {
            let (a, b) = (p.at(i), p.at((i + 1) % n));
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            let l2 = dx * dx + dy * dy;
            let s = if l2 < 1e-24 {
                0.0
            } else {
                (((x - a.x) * dx + (y - a.y) * dy) / l2).clamp(0.0, 1.0)
            };
            (x - a.x - s * dx).hypot(y - a.y - s * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// A 58 × 45 mm floor slab cut through filleted corners: the plain offset
/// by a Ø6 tool's radius falls apart into pieces of no area; the inset is
/// one loop, at least the radius from the section everywhere, and gives up
/// no more than the simplification's 0.01 mm.
#[test]
fn a_section_through_fillets_insets_by_a_small_tools_radius() {
    let p = fillet_section();
    for d in [3.0, 4.0] {
        let plain = std::panic::catch_unwind(|| p.parallel_offset(d)).ok();
        assert!(
            plain.is_none_or(|l| l.is_empty() || l.iter().any(|q| q.area().abs() <= 1e-12)),
            "the plain offset by {d} is sound: this test shows nothing"
        );
        let s = inset(std::slice::from_ref(&p), d);
        assert_eq!(s.ccw_plines.len(), 1, "d {d}");
        assert!(s.cw_plines.is_empty());
        let q = &s.ccw_plines[0].polyline;
        for i in 0..q.vertex_count() {
            let v = q.at(i);
            let dist = dist_to(&p, v.x, v.y);
            assert!(
                dist >= d - 1e-6,
                "d {d}: vertex {i} only {dist} from the section"
            );
        }
        // The offset by d + 0.01 of the section, which the inset contains.
        let wider = inset(std::slice::from_ref(&p), d + 0.01 + 1e-3);
        assert!(q.area() >= wider.ccw_plines[0].polyline.area());
    }
}

proptest! {
    /// Every vertex of a loop lies within `t` of its simplification, which
    /// keeps only vertices of the loop.
    #[test]
    fn a_simplified_loop_stays_within_its_tolerance(
        radii in prop::collection::vec(10.0f64..20.0, 8..200),
        t in 1e-4f64..0.05,
    ) {
        let n = radii.len();
        let mut p = Polyline::new_closed();
        for (i, r) in radii.iter().enumerate() {
            let a = i as f64 / n as f64 * std::f64::consts::TAU;
            p.add(r * a.cos(), r * a.sin(), 0.0);
        }
        let s = simplified(&p, t);
        prop_assert!(s.vertex_count() <= n && s.vertex_count() >= 3);
        for i in 0..s.vertex_count() {
            let v = s.at(i);
            prop_assert!((0..n).any(|j| p.at(j).x == v.x && p.at(j).y == v.y));
        }
        for i in 0..n {
            let v = p.at(i);
            prop_assert!(dist_to(&s, v.x, v.y) <= t + 1e-9, "vertex {} is {} from the simplification", i, dist_to(&s, v.x, v.y));
        }
    }
}
