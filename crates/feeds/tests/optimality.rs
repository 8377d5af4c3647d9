//! Optimality against independent references computed here: closed forms on a straight line
//! and a circle, and a brute-force envelope on a line with varying feed caps.

mod common;

use glam::DVec3;
use thinplan_feeds::{paths, schedule_polyline, schedule_polyline_uniform, MachineLimits};

/// Rest-to-rest time over a straight line of length `l` with speed cap `v` and acceleration
/// `a`: accelerate–cruise–decelerate, or accelerate–decelerate when too short to reach `v`.
fn line_time(l: f64, v: f64, a: f64) -> f64 {
    if l >= v * v / a {
        l / v + v / a
    } else {
        2.0 * (l / a).sqrt()
    }
}

fn assert_rel(ours: f64, reference: f64, tol: f64, what: &str) {
    let rel = (ours - reference).abs() / reference;
    assert!(
        rel <= tol,
        "{what}: ours {ours}, reference {reference}, relative error {rel:e}"
    );
}

#[test]
fn straight_line_matches_closed_form() {
    let m = MachineLimits::typical_hsm(); // 500 mm/s, 5000 mm/s²: D = 25 mm
    for dir in [
        DVec3::X,
        DVec3::new(3.0, 4.0, 0.0).normalize(),
        DVec3::new(1.0, -2.0, 2.0).normalize(),
    ] {
        // Governing axis: the one with the largest component.
        let dmax = dir.abs().max_element();
        let (v, a) = (500.0 / dmax, 5000.0 / dmax);
        for l in [1.0, 10.0, 49.0, 50.0, 51.0, 200.0, 1000.0] {
            for spacing in [0.1, 0.7, 3.0, 1e9] {
                let p = paths::line(DVec3::ZERO, dir * l, spacing);
                let s = schedule_polyline_uniform(&p, 1e6, &m);
                assert_rel(
                    s.total_time,
                    line_time(l, v, a),
                    1e-6,
                    &format!("line {l} mm along {dir}, spacing {spacing}"),
                );
                common::check(&p, &vec![1e6; p.len() - 1], &m, &s);
                // And with a feed cap below the machine's limit.
                let s = schedule_polyline_uniform(&p, 120.0, &m);
                assert_rel(
                    s.total_time,
                    line_time(l, 120.0, a),
                    1e-6,
                    &format!("line {l} at 120 mm/s"),
                );
            }
        }
    }
}

#[test]
fn circle_matches_constant_centripetal_speed() {
    // Axis limits far away, so the centripetal cap alone sets the speed v = sqrt(A_c·R) and
    // the start and stop take negligible time: time = length / v.
    let m = MachineLimits {
        v_max: [1e9; 3],
        a_max: [1e13; 3],
        a_centripetal: 5000.0,
        corner_angle_deg: 30.0,
    };
    for (r, spacing) in [(50.0, 0.5), (10.0, 0.1), (100.0, 2.0), (3.0, 0.3)] {
        let p = paths::circle(r, spacing);
        let s = schedule_polyline_uniform(&p, 1e6, &m);
        let length: f64 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
        let v = (5000.0 * r).sqrt();
        assert_rel(s.total_time, length / v, 1e-6, &format!("circle R{r}"));
        assert!(s.v[1..p.len() - 1]
            .iter()
            .all(|&x| (x - v).abs() < 1e-9 * v));
        common::check(&p, &vec![1e6; p.len() - 1], &m, &s);
    }
}

#[test]
fn circle_below_feed_cap_and_axis_limits() {
    // Centripetal-limited speed above the feed cap: the feed cap rules.
    let m = MachineLimits {
        a_max: [1e13; 3],
        ..MachineLimits::typical_hsm()
    };
    let p = paths::circle(50.0, 0.5);
    let s = schedule_polyline_uniform(&p, 200.0, &m);
    let length: f64 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
    assert_rel(s.total_time, length / 200.0, 1e-6, "circle at feed cap");
}

/// Brute force on a straight line with a feed cap per segment: the optimal speed² is the
/// lower envelope u*(s) = min(2As, 2A(L−s), min_j f_j² + 2A·dist(s, segment j)), integrated
/// on a fine grid (u* is piecewise linear, and 2h/(√u_a + √u_b) is exact on a linear piece).
#[test]
fn line_with_varying_feed_caps_matches_brute_force() {
    let a = 5000.0;
    let m = MachineLimits {
        v_max: [1e6; 3],
        ..MachineLimits::typical_hsm()
    };
    // Deterministic pseudo-random segment lengths and caps.
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..20 {
        let nseg = 2 + (rnd() * 12.0) as usize;
        let mut s_pts = vec![0.0];
        let mut caps = Vec::new();
        for _ in 0..nseg {
            s_pts.push(s_pts.last().unwrap() + 0.5 + 60.0 * rnd());
            caps.push(20.0 + 600.0 * rnd());
        }
        let l = *s_pts.last().unwrap();
        let p: Vec<DVec3> = s_pts.iter().map(|&s| DVec3::new(s, 0.0, 0.0)).collect();
        let ours = schedule_polyline(&p, &caps, &m).total_time;

        let ustar = |s: f64| {
            let mut u = (2.0 * a * s).min(2.0 * a * (l - s));
            for j in 0..nseg {
                let d = if s < s_pts[j] {
                    s_pts[j] - s
                } else if s > s_pts[j + 1] {
                    s - s_pts[j + 1]
                } else {
                    0.0
                };
                u = u.min(caps[j] * caps[j] + 2.0 * a * d);
            }
            u.max(0.0)
        };
        let n = 300_000;
        let h = l / n as f64;
        let mut t = 0.0;
        let mut va = 0.0;
        for i in 1..=n {
            let vb = ustar(i as f64 * h).sqrt();
            t += 2.0 * h / (va + vb);
            va = vb;
        }
        assert_rel(ours, t, 1e-6, &format!("{nseg} segments, caps {caps:?}"));
    }
}

#[test]
fn finer_sampling_converges() {
    // Under refinement the time converges (about first order): from above on smooth curves
    // (circle, spiral), from below on the rounded pentagon, whose line–arc junctions are
    // curvature jumps that the three-point curvature of the junction sample smooths. At 1 mm
    // spacing the pentagon is within 0.3 % of its limit.
    let m = MachineLimits {
        a_centripetal: f64::INFINITY,
        ..MachineLimits::typical_hsm()
    };
    let hs = [1.0, 0.5, 0.25, 0.125, 0.0625];
    for (name, gen) in [
        (
            "rounded pentagon",
            (|h| paths::rounded_pentagon(60.0, 10.0, h)) as fn(f64) -> Vec<glam::DVec3>,
        ),
        ("circle", |h| paths::circle(40.0, h)),
        ("spiral", |h| paths::spiral(3.0, 50.0, 4.0, h)),
    ] {
        let times: Vec<f64> = hs
            .iter()
            .map(|&h| schedule_polyline_uniform(&gen(h), 1e6, &m).total_time)
            .collect();
        let diffs: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        for w in diffs.windows(2) {
            assert!(
                w[1].abs() < 0.75 * w[0].abs() && w[0] * w[1] > 0.0,
                "{name}: not converging {times:?}"
            );
        }
        let finest = *times.last().unwrap();
        assert!(
            (times[0] / finest - 1.0).abs() < 3e-3,
            "{name}: 1 mm spacing off by more than 0.3 %: {times:?}"
        );
    }
}
