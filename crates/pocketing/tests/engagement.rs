//! The engagement measure against textbook cases: a slot through uncut stock engages half the
//! tool (180°, radial D); a straight pass at radial width a beside a straight wall of uncut
//! material engages acos(1 − 2a/D); a pass over cleared stock engages nothing.

use glam::DVec2;
use proptest::prelude::*;
use thinplan_pocketing::engagement::{
    engagement_profile, engagement_stats, summarize, EngagementParams, Entry,
};

/// Angle resolution of the default measure (180° / 360 probes) plus rounding.
const TOL_DEG: f64 = 0.5 + 1e-9;

fn rot(p: DVec2, ang: f64, origin: DVec2) -> DVec2 {
    origin + DVec2::from_angle(ang).rotate(p)
}

#[test]
fn slot_through_uncut_stock_is_180_degrees() {
    let d = 10.0;
    let path = [DVec2::new(0.0, 0.0), DVec2::new(10.0 * d, 0.0)];
    let prof = engagement_profile(&path, d, Entry::Plunge, &EngagementParams::default());
    assert!(prof.len() >= 400, "{} positions", prof.len());
    for e in &prof {
        assert!((e.angle_deg - 180.0).abs() <= TOL_DEG, "{e:?}");
        assert!((e.radial_mm - d).abs() <= 1e-3 * d, "{e:?}");
    }
    let st = engagement_stats(&path, d, Entry::Plunge, &EngagementParams::default()).unwrap();
    assert!((st.max_engagement_deg - 180.0).abs() <= TOL_DEG);
    assert!((st.p99_engagement_deg - 180.0).abs() <= TOL_DEG);
}

/// A slot along +x (its material removed up to y = R), back to the start on the line y = a
/// (moving −x) — the second pass's disc reaches y = a + R, so it removes a strip of width a
/// of the uncut wall y > R. Its cutting edge meets uncut material where R·sin ψ > R − a, ψ the
/// angle of the edge point from the direction of motion towards the wall (ψ ∈ (0°, 90°], the
/// front half): ψ from asin(1 − a/R) to 90°, an arc of 90° − asin(1 − 2a/D) = acos(1 − 2a/D).
fn wall_pass(d: f64, a: f64, ang: f64, origin: DVec2) -> (f64, f64) {
    let l = 8.0 * d;
    let path: Vec<DVec2> = [
        DVec2::new(0.0, 0.0),
        DVec2::new(l, 0.0),
        DVec2::new(l, a),
        DVec2::new(0.0, a),
    ]
    .iter()
    .map(|p| rot(*p, ang, origin))
    .collect();
    let prof = engagement_profile(&path, d, Entry::Plunge, &EngagementParams::default());
    // the return pass, away from both ends
    let s0 = l + a;
    let mid: Vec<_> = prof
        .iter()
        .filter(|e| e.s > s0 + 2.0 * d && e.s < s0 + l - 2.0 * d)
        .collect();
    assert!(mid.len() > 50);
    let amax = mid.iter().map(|e| e.angle_deg).fold(0.0, f64::max);
    let amin = mid
        .iter()
        .map(|e| e.angle_deg)
        .fold(f64::INFINITY, f64::min);
    assert!(amax - amin <= 2.0 * TOL_DEG, "not steady: {amin}..{amax}");
    let rmax = mid.iter().map(|e| e.radial_mm).fold(0.0, f64::max);
    (amax, rmax)
}

#[test]
fn pass_beside_a_wall_gives_the_textbook_angle() {
    let d: f64 = 12.0;
    for frac in [0.05, 0.1, 0.25, 0.4, 0.5, 0.75, 1.0] {
        let a = frac * d;
        let want = (1.0 - 2.0 * a / d).acos().to_degrees();
        let (got, radial) = wall_pass(d, a, 0.0, DVec2::ZERO);
        assert!(
            (got - want).abs() <= TOL_DEG,
            "a = {a}: engagement {got}° vs acos(1 − 2a/D) = {want}°"
        );
        // the probes nearest the arc's ends lie within half a probe spacing of them
        let res = d / 2.0 * (std::f64::consts::PI / 360.0);
        assert!((radial - a).abs() <= res, "a = {a}: radial {radial}");
    }
}

#[test]
fn pass_over_cleared_stock_engages_nothing() {
    let d = 8.0;
    // a slot, then back along it and along it again: everything under the tool is cleared
    let path = [
        DVec2::new(0.0, 0.0),
        DVec2::new(6.0 * d, 0.0),
        DVec2::new(0.0, 0.0),
        DVec2::new(5.0 * d, 0.0),
    ];
    let prof = engagement_profile(&path, d, Entry::Plunge, &EngagementParams::default());
    let back: Vec<_> = prof.iter().filter(|e| e.s > 6.0 * d + 1e-6).collect();
    assert!(back.len() > 100);
    for e in back {
        assert_eq!(e.angle_deg, 0.0, "{e:?}");
        assert_eq!(e.radial_mm, 0.0, "{e:?}");
    }
}

#[test]
fn entry_is_excluded_and_a_helix_clears_its_hole() {
    let d = 10.0;
    // first move out of the plunge is already a 180° slot, never the 360° of the plunge
    let path = [DVec2::new(0.0, 0.0), DVec2::new(d, 0.0)];
    let prof = engagement_profile(&path, d, Entry::Plunge, &EngagementParams::default());
    assert!(prof[0].angle_deg <= 180.0 + TOL_DEG);
    // a helix of radius D about the start: the first D of a straight move stays inside the
    // hole of radius 1.5 D (the tool's edge reaches 1.5 D at s = D); the whole front half is
    // out of it once s² + R² > (1.5 D)², s > √2 D
    let path = [DVec2::new(0.0, 0.0), DVec2::new(3.0 * d, 0.0)];
    let helix = Entry::Helix {
        center: DVec2::ZERO,
        radius: d,
    };
    let prof = engagement_profile(&path, d, helix, &EngagementParams::default());
    for e in &prof {
        if e.s < 0.99 * d {
            assert_eq!(e.angle_deg, 0.0, "{e:?}");
        }
        if e.s > 1.42 * d {
            assert!((e.angle_deg - 180.0).abs() <= TOL_DEG, "{e:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// The textbook angle for any tool, width, direction and place.
    #[test]
    fn wall_pass_matches_acos_anywhere(
        d in 1.0f64..50.0,
        frac in 0.02f64..1.0,
        ang in 0.0f64..std::f64::consts::TAU,
        ox in -500.0f64..500.0,
        oy in -500.0f64..500.0,
    ) {
        let a = frac * d;
        let want = (1.0 - 2.0 * a / d).acos().to_degrees();
        let (got, _) = wall_pass(d, a, ang, DVec2::new(ox, oy));
        prop_assert!((got - want).abs() <= TOL_DEG, "a/D {frac}: {got}° vs {want}°");
    }
}

/// Bench JSON written before the engagement fields still reads (they default to null).
#[test]
fn old_bench_json_without_engagement_still_reads() {
    use thinplan_pocketing::bench::{CurvilinearStats, PathStats};
    let p: PathStats =
        serde_json::from_str(r#"{"length_mm": 1.0, "time_s": 2.0, "max_gap_mm": null}"#).unwrap();
    assert_eq!(p.max_engagement_deg, None);
    assert_eq!(p.max_radial_mm, None);
    let c: CurvilinearStats = serde_json::from_str(
        r#"{"length_mm": 1.0, "time_s": 2.0, "max_gap_mm": 0.5, "method": "curvilinear"}"#,
    )
    .unwrap();
    assert_eq!(c.p99_engagement_deg, None);
}

/// Bench JSON written before the entry fields still reads (measured with a plunge then).
#[test]
fn old_bench_json_without_entry_still_reads() {
    use thinplan_pocketing::bench::{CurvilinearStats, PathStats};
    let p: PathStats = serde_json::from_str(
        r#"{"length_mm": 1.0, "time_s": 2.0, "max_gap_mm": null, "max_engagement_deg": 180.0}"#,
    )
    .unwrap();
    assert_eq!(p.entry, None);
    let c: CurvilinearStats = serde_json::from_str(
        r#"{"length_mm": 1.0, "time_s": 2.0, "max_gap_mm": 0.5, "method": "curvilinear"}"#,
    )
    .unwrap();
    assert_eq!(c.entry, None);
    assert!(c.plunge.is_none());
}

/// The bench reads the helix radius of the built-in closed-pocket method, as stage 7 does.
#[test]
fn helix_rule_comes_from_the_closed_pocket_method() {
    use thinplan_pocketing::bench::{BenchConfig, HelixEntryRule};
    let rule = HelixEntryRule::builtin().expect("the closed-pocket method enters by a helix");
    assert!(rule.radius > 0.0 && rule.radius <= 1.0, "{rule:?}");
    assert!(rule.source.contains("closed_pocket"), "{rule:?}");
    assert_eq!(BenchConfig::default().helix_entry, Some(rule));
}

/// Stage 7's fit rule on a circular ∂Ω of radius `b` about the origin, the path starting at the
/// origin: the helix circle about (−ρ, 0) fits when b ≥ 2ρ, tried at ρ, ρ/2, ρ/4.
#[test]
fn helix_entry_shrinks_until_it_fits_then_plunges() {
    use thinplan_pocketing::bench::HelixEntryRule;
    let d = 10.0;
    let rule = HelixEntryRule {
        radius: 0.4,
        source: "test".into(),
    };
    let circle = |b: f64| -> Vec<DVec2> {
        (0..720)
            .map(|i| b * DVec2::from_angle(std::f64::consts::TAU * i as f64 / 720.0))
            .collect()
    };
    // (∂Ω radius, expected helix radius or None for a plunge)
    for (b, want) in [
        (20.0, Some(4.0)),
        (8.05, Some(4.0)),
        (7.9, Some(2.0)),
        (4.05, Some(2.0)),
        (3.9, Some(1.0)),
        (1.9, None),
    ] {
        let e = rule.entry(DVec2::ZERO, &circle(b), d);
        match (e.entry, want) {
            (Entry::Helix { center, radius }, Some(r)) => {
                assert!((radius - r).abs() < 1e-12, "b = {b}: {e:?}");
                assert!(
                    (center - DVec2::new(-r, 0.0)).length() < 1e-12,
                    "b = {b}: {e:?}"
                );
                assert_eq!(e.label, format!("helix r={:.2}D", r / d));
                // the helix circle stays inside ∂Ω
                assert!(center.length() + radius <= b, "b = {b}: {e:?}");
            }
            (Entry::Plunge, None) => assert!(e.label.starts_with("plunge"), "{e:?}"),
            _ => panic!("b = {b}: {e:?}, expected {want:?}"),
        }
    }
    // no boundary at all: a plunge, no panic
    assert_eq!(rule.entry(DVec2::ZERO, &[], d).entry, Entry::Plunge);
}

/// The curvilinear spiral of a bench pocket (tool = width / 6) and its first orbit's largest
/// distance from the spiral's centre: the points until the winding angle about the centre
/// reaches a full turn, counted here independently of the generator.
fn spiral_and_first_orbit(name: &str) -> (thinplan_pocketing::PocketPath, f64, f64) {
    use thinplan_pocketing::bench::{bench_family, bench_params};
    let bp = bench_family(60.0)
        .into_iter()
        .find(|b| b.pocket.name == name)
        .unwrap();
    let mut params = bench_params(&bp);
    params.mesh_size = Some(params.stepover / 2.0);
    let path = thinplan_pocketing::curvilinear_path(&bp.pocket, &params).unwrap();
    assert_eq!(
        path.method,
        thinplan_pocketing::Method::Curvilinear,
        "{name}"
    );
    let c = path.center.unwrap();
    let (mut acc, mut r1) = (0.0, 0.0f64);
    for w in path.points.windows(2) {
        let (a, b) = (w[0] - c, w[1] - c);
        if a.length() > 1e-9 && b.length() > 1e-9 {
            acc += a.perp_dot(b).atan2(a.dot(b));
        }
        if acc.abs() > std::f64::consts::TAU {
            break;
        }
        r1 = r1.max(b.length());
    }
    // the first contour is within the stepover of every point inside it, so its farthest
    // point lies at about a stepover (beyond it where the contour is not round)
    assert!(
        r1 > 0.5 * params.stepover && r1 < params.tool_diameter,
        "{name}: r1 {r1}"
    );
    (path, params.tool_diameter, r1)
}

/// A spiral that plunges at its centre starts with a slot (180°); entered by a helix about its
/// centre of radius ≥ its first orbit's, the first orbit is inside the helix hole and every
/// later position cuts beside material already removed: never 180°. Stage 7's helix (radius
/// from the knowledge, centred beside the first point) also removes the 180° start.
#[test]
fn helix_entry_removes_the_spirals_slot_start() {
    use thinplan_pocketing::bench::HelixEntryRule;
    let ep = EngagementParams {
        step: 1.0 / 20.0,
        probes: 180,
    };
    for name in ["circle", "pentagon"] {
        let (path, d, r1) = spiral_and_first_orbit(name);
        let plunge = engagement_stats(&path.points, d, Entry::Plunge, &ep).unwrap();
        assert!(
            plunge.max_engagement_deg >= 180.0 - 1.0,
            "{name}: plunge {plunge:?}"
        );
        let centred = Entry::Helix {
            center: path.center.unwrap(),
            radius: r1,
        };
        let prof = engagement_profile(&path.points, d, centred, &ep);
        // the first orbit lies inside the helix hole: it cuts nothing
        let c = path.center.unwrap();
        let inside: Vec<_> = prof
            .iter()
            .filter(|e| e.position.distance(c) <= r1)
            .collect();
        assert!(inside.len() > 20, "{name}: {} positions", inside.len());
        for e in inside {
            assert_eq!(e.angle_deg, 0.0, "{name}: {e:?}");
        }
        // measured: circle 95°, pentagon 113° (at a corner, 0.69 of the way along)
        let helix = summarize(&prof).unwrap();
        assert!(
            helix.max_engagement_deg < 120.0,
            "{name}: helix r = {r1} ({} D): {helix:?}",
            r1 / d
        );
        let rule = HelixEntryRule::builtin().unwrap();
        let e = rule.entry(path.points[0], &path.boundary, d);
        assert!(matches!(e.entry, Entry::Helix { .. }), "{name}: {e:?}");
        let stage7 = engagement_stats(&path.points, d, e.entry, &ep).unwrap();
        assert!(
            stage7.max_engagement_deg < 135.0,
            "{name}: {}: {stage7:?}",
            e.label
        );
    }
}
