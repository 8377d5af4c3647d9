//! The bending model against closed forms, its monotonicity, the
//! iteration's guarantees, and the knowledge driving it.

use proptest::prelude::*;
use thinplan_knowledge::{parse_ron, Knowledge, SizingKnowledge};
use thinplan_sizing::*;

fn knowledge() -> SizingKnowledge {
    Knowledge::builtin().unwrap().sizing
}

const E: f64 = 71000.0;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn uniform_cantilever_closed_forms() {
    let (f, l, ei) = (200.0, 36.0, 71000.0 * 1250.0);
    let (d, t) = stepped_cantilever(
        f,
        &[Piece {
            from: 0.0,
            to: l,
            ei,
        }],
    );
    assert!(close(d, f * l.powi(3) / (3.0 * ei), 1e-12));
    assert!(close(t, f * l.powi(2) / (2.0 * ei), 1e-12));
    // Cutting the beam into pieces of the same stiffness changes nothing.
    let pieces: Vec<Piece> = (0..7)
        .map(|i| Piece {
            from: l * f64::from(i) / 7.0,
            to: l * f64::from(i + 1) / 7.0,
            ei,
        })
        .collect();
    let (d2, t2) = stepped_cantilever(f, &pieces);
    assert!(close(d, d2, 1e-12) && close(t, t2, 1e-12));
}

#[test]
fn wall_without_features_is_a_uniform_cantilever_below_d() {
    // B_RF = 0: thickness t everywhere; the beam below D is H_w − h long.
    let k = knowledge();
    let w = Wall {
        length: 500.0,
        thickness: 2.0,
        height: 40.0,
    };
    let s = Sizes {
        b_rf: 0.0,
        h: 10.0,
        big_h: 20.0,
    };
    let b = bending(&w, &s, &k, E, MillingMode::Peripheral).unwrap();
    let le = 160.0; // min(500, 4 · 40)
    assert_eq!(b.effective_length, le);
    let ei = E * le * 8.0 / 12.0;
    let l: f64 = 30.0;
    let f = k.max_milling_force;
    assert!(close(b.delta_d, f * l.powi(3) / (3.0 * ei), 1e-12));
    assert!(close(b.theta_d, f * l.powi(2) / (2.0 * ei), 1e-12));
    assert_eq!(b.danger_zone, 9.0);
    assert!(close(b.delta_e, b.delta_d + 9.0 * b.theta_d, 1e-15));
    // Face milling: danger zone ½ · D = 6.
    let bf = bending(&w, &s, &k, E, MillingMode::Face).unwrap();
    assert_eq!(bf.danger_zone, 6.0);
    assert!(close(bf.delta_e, b.delta_d + 6.0 * b.theta_d, 1e-15));
}

/// Integrates M/EI twice numerically from the clamp (w = w' = 0 there).
fn numeric(f: f64, pieces: &[Piece]) -> (f64, f64) {
    let c = pieces.last().unwrap().to;
    let n = 200_000;
    let dx = c / f64::from(n);
    let ei_at = |x: f64| pieces.iter().find(|p| x <= p.to).unwrap().ei;
    let (mut theta, mut w) = (0.0f64, 0.0f64);
    let mut x = c;
    for _ in 0..n {
        // Midpoint rule: θ(x − dx) = θ(x) + ∫ M/EI, w(x − dx) = w(x) + ∫ θ.
        let xm = x - dx / 2.0;
        let dtheta = f * xm / ei_at(xm) * dx;
        w += (theta + dtheta / 2.0) * dx;
        theta += dtheta;
        x -= dx;
    }
    (w, theta)
}

#[test]
fn stepped_cantilever_matches_numerical_double_integration() {
    let pieces = [
        Piece {
            from: 0.0,
            to: 12.0,
            ei: 71000.0 * 17280.0,
        },
        Piece {
            from: 12.0,
            to: 60.0,
            ei: 71000.0 * 121670.0,
        },
    ];
    let (d, t) = stepped_cantilever(200.0, &pieces);
    let (dn, tn) = numeric(200.0, &pieces);
    assert!(close(d, dn, 1e-6), "{d} vs {dn}");
    assert!(close(t, tn, 1e-6), "{t} vs {tn}");
}

fn wall_strategy() -> impl Strategy<Value = (Wall, Sizes)> {
    (
        20.0..300.0f64,
        0.3..3.0f64,
        10.0..150.0f64,
        0.0..40.0f64,
        0.05..0.9f64,
        0.0..1.0f64,
    )
        .prop_map(|(length, thickness, height, b_rf, hf, bigf)| {
            let h = hf * height;
            let big_h = h + bigf * (height - h);
            (
                Wall {
                    length,
                    thickness,
                    height,
                },
                Sizes { b_rf, h, big_h },
            )
        })
}

proptest! {
    #[test]
    fn deflection_falls_as_the_wall_or_the_features_thicken(
        (w, s) in wall_strategy(), dt in 0.01..2.0f64, db in 0.01..10.0f64,
    ) {
        let k = knowledge();
        for mode in [MillingMode::Peripheral, MillingMode::Face] {
            let d0 = deflection(&w, &s, &k, E, mode);
            prop_assert!(d0 > 0.0);
            let thicker = Wall { thickness: w.thickness + dt, ..w };
            prop_assert!(deflection(&thicker, &s, &k, E, mode) < d0);
            let wider = Sizes { b_rf: s.b_rf + db, ..s };
            prop_assert!(deflection(&w, &wider, &k, E, mode) < d0);
        }
    }

    #[test]
    fn deflection_grows_with_the_force_and_with_big_h(
        (w, s) in wall_strategy(), ff in 1.01..5.0f64, dh in 0.1..1.0f64,
    ) {
        let k = knowledge();
        let d0 = deflection(&w, &s, &k, E, MillingMode::Peripheral);
        let mut k2 = k.clone();
        k2.max_milling_force *= ff;
        let d1 = deflection(&w, &s, &k2, E, MillingMode::Peripheral);
        prop_assert!(d1 > d0);
        prop_assert!((d1 / d0 - ff).abs() < 1e-9, "linear in F");
        // A taller large feature leaves less of the stiff t + 2·B_RF base.
        let taller = Sizes { big_h: s.big_h + dh * (w.height - s.big_h), ..s };
        if s.b_rf > 0.0 && w.height - s.big_h > 1e-6 {
            prop_assert!(deflection(&w, &taller, &k, E, MillingMode::Peripheral) > d0);
        }
    }

    /// In this reading the load sits at the bottom of the small feature, so
    /// with H fixed a deeper h moves the load towards the clamp and the wall
    /// bends LESS (the thin top [0, h] carries no moment). The opposite
    /// monotonicity, "deflection grows with h", holds only when H moves with
    /// h and h is a large part of the wall (see README).
    #[test]
    fn with_big_h_fixed_a_deeper_load_bends_less(
        (w, s) in wall_strategy(), dh in 0.05..0.95f64,
    ) {
        let k = knowledge();
        let d0 = deflection(&w, &s, &k, E, MillingMode::Peripheral);
        let deeper = Sizes { h: s.h + dh * (s.big_h - s.h), ..s };
        if s.big_h - s.h > 1e-6 {
            prop_assert!(deflection(&w, &deeper, &k, E, MillingMode::Peripheral) < d0);
        }
    }

    #[test]
    fn iteration_meets_the_limit_or_says_impossible(
        length in 10.0..400.0f64, thickness in 0.2..4.0f64, height in 0.5..200.0f64,
        face in any::<bool>(), rule in any::<bool>(),
    ) {
        let mut k = knowledge();
        if !rule {
            k.tall_wall = None;
        }
        let mode = if face { MillingMode::Face } else { MillingMode::Peripheral };
        let w = Wall { length, thickness, height };
        let cuts = CutSizes::new(&k, mode);
        match size_wall(&w, &k, E, mode) {
            Ok(r) => {
                prop_assert!(r.deflection <= k.allowed_deflection);
                prop_assert_eq!(r.deflection, deflection(&w, &r.sizes(), &k, E, mode));
                prop_assert!(r.h <= r.big_h && r.big_h <= height + 1e-9);
                prop_assert!(tall_wall_allows(&k, &w, &r.sizes()));
                // Widths: finishing cut + whole roughing cuts, at least the minimum.
                let n_b = (r.b_rf - cuts.width_first) / cuts.width_step;
                prop_assert!((n_b - n_b.round()).abs() < 1e-9, "B_RF {}", r.b_rf);
                prop_assert!(n_b.round() as u32 + 1 >= cuts.min_width_cuts);
                if height >= cuts.height_step {
                    // Heights: whole finishing cuts; H a whole multiple of h.
                    let n_h = r.h / cuts.height_step;
                    prop_assert!((n_h - n_h.round()).abs() < 1e-9, "h {}", r.h);
                    prop_assert!(n_h.round() >= 1.0);
                    let m = r.big_h / r.h;
                    prop_assert!((m - m.round()).abs() < 1e-9, "H {} h {}", r.big_h, r.h);
                } else {
                    prop_assert_eq!((r.h, r.big_h), (height, height));
                }
                prop_assert!(r.iterations >= 1);
            }
            Err(SizingError::Impossible { deflection, allowed, stiffest, .. }) => {
                prop_assert!(deflection > allowed);
                prop_assert_eq!(stiffest.b_rf, cuts.width(cuts.max_width_cuts));
            }
            Err(e) => prop_assert!(false, "unexpected {e}"),
        }
    }
}

#[test]
fn appendix_walls_get_the_sizes_the_tests_found_good() {
    let k = knowledge();
    let size = |l, t, h| {
        size_wall(
            &Wall {
                length: l,
                thickness: t,
                height: h,
            },
            &k,
            E,
            MillingMode::Peripheral,
        )
        .unwrap()
    };
    let r = size(120.0, 1.0, 48.0);
    assert_eq!((r.b_rf, r.h, r.big_h), (11.0, 12.0, 48.0)); // TEST6: good
    let r = size(120.0, 1.0, 60.0);
    assert_eq!((r.b_rf, r.h, r.big_h), (11.0, 12.0, 60.0)); // TEST1 (60): good
    let r = size(120.0, 1.0, 72.0);
    assert_eq!((r.b_rf, r.h, r.big_h), (11.0, 12.0, 36.0)); // TEST9: good
    let names: Vec<&str> = r.provenance.iter().map(|(n, _)| n.as_str()).collect();
    for n in [
        "allowed_deflection",
        "max_milling_force",
        "e_modulus",
        "effective_length",
        "peripheral.danger_zone",
        "peripheral.height_step",
        "b_rf_rule_of_thumb",
        "tall_wall.max_big_h_over_h",
    ] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    // Without the tall-wall rule the 72 mm wall gets H = 60 (δ_E 0.0095),
    // the 4·h and 5·h that TEST10's remark warns against.
    let mut k2 = k.clone();
    k2.tall_wall = None;
    let w = Wall {
        length: 120.0,
        thickness: 1.0,
        height: 72.0,
    };
    let r = size_wall(&w, &k2, E, MillingMode::Peripheral).unwrap();
    assert_eq!((r.b_rf, r.h, r.big_h), (11.0, 12.0, 60.0));
}

#[test]
fn an_impossible_wall_is_a_typed_result() {
    let k = knowledge();
    let w = Wall {
        length: 5.0,
        thickness: 0.3,
        height: 300.0,
    };
    match size_wall(&w, &k, E, MillingMode::Peripheral) {
        Err(e @ SizingError::Impossible { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("no machining-feature sizes"), "{msg}");
        }
        other => panic!("expected impossible, got {other:?}"),
    }
    let bad = Wall { length: -1.0, ..w };
    assert!(matches!(
        size_wall(&bad, &k, E, MillingMode::Peripheral),
        Err(SizingError::InvalidInput(_))
    ));
    assert!(deflection(
        &bad,
        &Sizes {
            b_rf: 1.0,
            h: 1.0,
            big_h: 2.0
        },
        &k,
        E,
        MillingMode::Face
    )
    .is_nan());
}

fn sizing_ron_with(from: &str, to: &str) -> SizingKnowledge {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge/sizing.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from} not in sizing.ron");
    let k: SizingKnowledge = parse_ron(&text.replace(from, to), &path).unwrap();
    assert!(k.problems().is_empty(), "{:?}", k.problems());
    k
}

/// Whether `b` is at least as careful as `a`: wider, or as wide with a
/// lower h, or both the same with a lower or equal H.
fn no_less_careful(a: &Sizes, b: &Sizes) -> bool {
    b.b_rf > a.b_rf || (b.b_rf == a.b_rf && (b.h < a.h || (b.h == a.h && b.big_h <= a.big_h)))
}

#[test]
fn halving_the_allowed_deflection_in_sizing_ron_gives_more_careful_sizes() {
    let k = sizing_ron_with("allowed_deflection: 0.01", "allowed_deflection: 0.01");
    assert_eq!(k, knowledge());
    let half = sizing_ron_with("allowed_deflection: 0.01", "allowed_deflection: 0.005");
    assert_eq!(half.allowed_deflection, 0.005);
    let double_force = sizing_ron_with("max_milling_force: 200.0", "max_milling_force: 400.0");
    let mut changed = 0;
    for (l, t, h) in [
        (120.0, 1.0, 48.0),
        (120.0, 1.0, 60.0),
        (120.0, 0.8, 60.0),
        (70.0, 0.85, 60.0),
        (28.0, 0.85, 60.0),
        (120.0, 0.75, 72.0),
        (120.0, 1.0, 72.0),
        (144.0, 1.0, 72.0),
        (300.0, 2.0, 120.0),
    ] {
        let w = Wall {
            length: l,
            thickness: t,
            height: h,
        };
        for mode in [MillingMode::Peripheral, MillingMode::Face] {
            let a = size_wall(&w, &k, E, mode).unwrap();
            let b = size_wall(&w, &half, E, mode).unwrap();
            assert!(b.deflection <= 0.005);
            assert!(
                no_less_careful(&a.sizes(), &b.sizes()),
                "{w:?} {mode:?}: {:?} -> {:?}",
                a.sizes(),
                b.sizes()
            );
            println!(
                "{}×{}×{} {:?}: ({}, {}, {}) δ {:.4} -> ({}, {}, {}) δ {:.4}",
                l,
                t,
                h,
                mode,
                a.b_rf,
                a.h,
                a.big_h,
                a.deflection,
                b.b_rf,
                b.h,
                b.big_h,
                b.deflection
            );
            changed += usize::from(a.sizes() != b.sizes());
            // δ is linear in F: twice the force is half the allowance.
            let c = size_wall(&w, &double_force, E, mode).unwrap();
            assert_eq!(c.sizes(), b.sizes());
        }
    }
    // Four of the eighteen change; the others already bend less than
    // 0.005 mm at their sizes.
    assert_eq!(changed, 4);
    let size = |l, t, h, k: &SizingKnowledge| {
        let w = Wall {
            length: l,
            thickness: t,
            height: h,
        };
        size_wall(&w, k, E, MillingMode::Peripheral)
            .unwrap()
            .sizes()
    };
    // 120×1×60: H = 60 bends 0.0077 mm; at 0.005 H drops to 36.
    assert_eq!(size(120.0, 1.0, 60.0, &k).big_h, 60.0);
    assert_eq!(size(120.0, 1.0, 60.0, &half).big_h, 36.0);
    // 28×0.85×60 (L_e = 28): B_RF widens by one roughing cut, 11 -> 20.
    assert_eq!(size(28.0, 0.85, 60.0, &k).b_rf, 11.0);
    assert_eq!(size(28.0, 0.85, 60.0, &half).b_rf, 20.0);
}
