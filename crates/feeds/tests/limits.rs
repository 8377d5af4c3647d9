//! No limit violated: on the test paths and on random paths, the scheduled (s, v, t) keeps
//! every per-axis velocity and acceleration, the centripetal cap and the feed caps, and stops
//! at the ends and corners.

mod common;

use glam::DVec3;
use proptest::prelude::*;
use thinplan_feeds::{paths, schedule_polyline, schedule_polyline_uniform, MachineLimits};

fn machines() -> Vec<MachineLimits> {
    let hsm = MachineLimits::typical_hsm();
    vec![
        hsm.clone(),
        // Slow Z, anisotropic X/Y, weak centripetal cap, strict corners.
        MachineLimits {
            v_max: [400.0, 250.0, 100.0],
            a_max: [3000.0, 8000.0, 1000.0],
            a_centripetal: 1500.0,
            corner_angle_deg: 10.0,
        },
        // No centripetal cap (the TOPP-RA comparison setting).
        MachineLimits {
            a_centripetal: f64::INFINITY,
            ..hsm
        },
    ]
}

fn test_paths() -> Vec<(&'static str, Vec<DVec3>)> {
    vec![
        ("zigzag", paths::zigzag(120.0, 60.0, 8.0, 2.0)),
        ("zigzag coarse", paths::zigzag(120.0, 60.0, 8.0, 1000.0)),
        (
            "zigzag rounded",
            paths::zigzag_rounded(120.0, 60.0, 8.0, 0.5),
        ),
        ("circle", paths::circle(40.0, 0.5)),
        ("small circle", paths::circle(2.0, 0.05)),
        ("rounded pentagon", paths::rounded_pentagon(60.0, 8.0, 0.5)),
        ("sharp pentagon", paths::rounded_pentagon(60.0, 0.0, 1.0)),
        ("spiral", paths::spiral(3.0, 50.0, 4.0, 0.5)),
        ("helix", paths::helix(8.0, 3.0, 2.0, 0.3)),
        (
            "line",
            paths::line(DVec3::ZERO, DVec3::new(30.0, -40.0, 5.0), 1.0),
        ),
    ]
}

#[test]
fn test_paths_keep_all_limits() {
    for m in machines() {
        for (name, p) in test_paths() {
            for feed in [1e6, 300.0, 40.0] {
                let caps = vec![feed; p.len() - 1];
                let s = schedule_polyline(&p, &caps, &m);
                let r = common::violations(&p, &caps, &m, &s);
                assert!(
                    r.worst <= 1.0 + common::TOL,
                    "{name}, feed {feed}, {m:?}: ratio {} at {}",
                    r.worst,
                    r.what
                );
                assert!(s.total_time.is_finite() && s.total_time > 0.0, "{name}");
            }
        }
    }
}

#[test]
fn corners_stop_and_smooth_paths_do_not() {
    let m = MachineLimits::typical_hsm();
    // Sharp zigzag: every 90° junction is a corner.
    let p = paths::zigzag(100.0, 40.0, 10.0, 5.0);
    let s = schedule_polyline_uniform(&p, 1e6, &m);
    let g = common::geometry(&p, &m);
    let corners: Vec<usize> = (0..p.len()).filter(|&j| g.corner[j]).collect();
    assert_eq!(corners.len(), 8, "4 stepovers, 2 corners each");
    assert!(corners.iter().all(|&j| s.v[j] == 0.0));
    // Rounded zigzag: no corner, the speed stays up in the turns.
    let p = paths::zigzag_rounded(100.0, 40.0, 10.0, 0.5);
    let s = schedule_polyline_uniform(&p, 1e6, &m);
    assert!(s.v[1..p.len() - 1].iter().all(|&v| v > 10.0));
}

#[test]
fn repeated_points_at_a_corner_still_stop() {
    let m = MachineLimits::typical_hsm();
    let a = DVec3::ZERO;
    let b = DVec3::new(50.0, 0.0, 0.0);
    let c = DVec3::new(50.0, 50.0, 0.0);
    let p = vec![a, b, b, b, c];
    let s = schedule_polyline_uniform(&p, 1e6, &m);
    assert_eq!(&s.v[1..4], &[0.0, 0.0, 0.0]);
    common::check(&p, &[1e6; 4], &m, &s);
    // Same time as without the repeats.
    let s2 = schedule_polyline_uniform(&[a, b, c], 1e6, &m);
    assert!((s.total_time - s2.total_time).abs() < 1e-12);
}

#[test]
fn smooth_paths_keep_axis_acceleration_by_position_differences() {
    // A physical check independent of the model's curvature: second differences of the
    // positions over the scheduled times. On finely sampled smooth paths they approximate the
    // true axis accelerations, so they must stay within the limits up to the sampling error.
    let m = MachineLimits {
        a_centripetal: f64::INFINITY,
        ..MachineLimits::typical_hsm()
    };
    for (name, p) in [
        ("circle", paths::circle(40.0, 0.2)),
        ("spiral", paths::spiral(3.0, 50.0, 4.0, 0.2)),
        ("helix", paths::helix(8.0, 3.0, 2.0, 0.1)),
        ("rounded pentagon", paths::rounded_pentagon(60.0, 8.0, 0.2)),
    ] {
        let s = schedule_polyline_uniform(&p, 1e6, &m);
        let r = common::max_axis_accel_ratio_from_positions(&p, &s, &m);
        assert!(r <= 1.02, "{name}: axis acceleration {r} × the limit");
        assert!(
            r >= 0.9,
            "{name}: the schedule should use the acceleration ({r})"
        );
    }
}

/// A random path: a walk with random step lengths and turning angles in 3D, some steps
/// repeated points, some long straight runs.
fn random_path() -> impl Strategy<Value = (Vec<DVec3>, Vec<f64>)> {
    prop::collection::vec(
        (
            0.0f64..1.0,
            -1.0f64..1.0,
            -1.0f64..1.0,
            0.0f64..1.0,
            1.0f64..600.0,
        ),
        2..80,
    )
    .prop_map(|steps| {
        let mut p = vec![DVec3::ZERO];
        let mut dir = DVec3::X;
        let mut caps = Vec::new();
        for (l, yaw, pitch, kind, cap) in steps {
            let len = if kind < 0.05 {
                0.0
            } else if kind < 0.2 {
                20.0 + 80.0 * l
            } else {
                0.01 + 3.0 * l
            };
            // Turn by up to ~70° (sometimes a corner, sometimes a smooth bend).
            let turn = if kind > 0.6 { 0.2 } else { 1.2 };
            let side = dir.any_orthonormal_pair();
            dir = (dir + side.0 * yaw * turn + side.1 * pitch * turn * 0.5).normalize();
            let last = *p.last().unwrap();
            p.push(last + dir * len);
            caps.push(cap);
        }
        (p, caps)
    })
}

fn random_limits() -> impl Strategy<Value = MachineLimits> {
    (
        prop::array::uniform3(50.0f64..800.0),
        prop::array::uniform3(500.0f64..20000.0),
        prop_oneof![Just(f64::INFINITY), 100.0f64..20000.0],
        5.0f64..90.0,
    )
        .prop_map(
            |(v_max, a_max, a_centripetal, corner_angle_deg)| MachineLimits {
                v_max,
                a_max,
                a_centripetal,
                corner_angle_deg,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_paths_keep_all_limits((p, caps) in random_path(), m in random_limits()) {
        let s = schedule_polyline(&p, &caps, &m);
        let r = common::violations(&p, &caps, &m, &s);
        prop_assert!(r.worst <= 1.0 + common::TOL, "ratio {} at {}", r.worst, r.what);
        prop_assert!(s.total_time.is_finite());
    }

    // Monotone in the limits. What it depends on: the in-segment profile is the exact
    // optimum (not one constant acceleration up to the cruise cap); a segment constraint
    // with both coefficients of the same sign is replaced by the separable pair at its
    // constant-speed point (TOPP-RA's greedy pass is optimal only on a lattice); an end
    // speed above the in-segment cap is timed from the end speeds lowered to the cap;
    // the hybrid profile's root search stops on the residual, not on a short step.
    #[test]
    fn slower_machine_never_faster((p, caps) in random_path(), m in random_limits(), f in 0.3f64..1.0) {
        // Monotonicity: tighter limits never give a shorter time.
        let slow = MachineLimits {
            v_max: m.v_max.map(|v| v * f),
            a_max: m.a_max.map(|a| a * f),
            a_centripetal: m.a_centripetal * f,
            ..m.clone()
        };
        let t_fast = schedule_polyline(&p, &caps, &m).total_time;
        let t_slow = schedule_polyline(&p, &caps, &slow).total_time;
        prop_assert!(t_slow >= t_fast * (1.0 - 1e-12), "{t_slow} < {t_fast}");
    }
}
