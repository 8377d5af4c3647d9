//! A chain of moves swept one after another must leave the stock exactly
//! as the lowest of the moves' own envelopes, each swept alone on a fresh
//! blank: the sweep's shortcuts (cells already below the tool's lowest tip,
//! the disc where the same tool last stood) may skip work, never a cut.

use glam::DVec3;
use proptest::prelude::*;
use thinplan_stocksim::{Blank, ToolShape, ZMap};

fn blank() -> Blank {
    Blank {
        min: DVec3::new(-15.0, -15.0, -20.0),
        max: DVec3::new(15.0, 15.0, 5.0),
    }
}

fn tool_strategy() -> impl Strategy<Value = ToolShape> {
    (2.0f64..10.0, 0u8..3, 0.05f64..0.95).prop_map(|(d, kind, f)| match kind {
        0 => ToolShape::flat(d),
        1 => ToolShape::ball(d),
        _ => ToolShape::bull(d, f * d / 2.0),
    })
}

/// One step of a chain: where it goes from the last end (plan offset and
/// height change; zero offset is a vertical move), and whether it uses the
/// second tool.
fn step() -> impl Strategy<Value = (f64, f64, f64, bool)> {
    (
        prop_oneof![Just(0.0), -6.0f64..6.0],
        prop_oneof![Just(0.0), -6.0f64..6.0],
        prop_oneof![Just(0.0), Just(0.0), -1.5f64..1.0],
        prop::bool::weighted(0.2),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn a_chain_of_moves_cuts_what_its_moves_cut_alone(
        tools in (tool_strategy(), tool_strategy()),
        start in (-5.0f64..5.0, -5.0f64..5.0, -6.0f64..6.0),
        steps in prop::collection::vec(step(), 1..14),
    ) {
        let cell = 0.3;
        let mut chain = ZMap::new(blank(), cell).unwrap();
        let mut alone_min = vec![f32::INFINITY; chain.top.len()];
        let mut p = DVec3::new(start.0, start.1, start.2);
        for (k, (dx, dy, dz, second)) in steps.into_iter().enumerate() {
            let tool = if second { &tools.1 } else { &tools.0 };
            let q = DVec3::new(
                (p.x + dx).clamp(-12.0, 12.0),
                (p.y + dy).clamp(-12.0, 12.0),
                (p.z + dz).clamp(-10.0, 8.0),
            );
            chain.sweep_line(tool, p, q, k as u32 + 1);
            let mut alone = ZMap::new(blank(), cell).unwrap();
            alone.sweep_line(tool, p, q, 1);
            for (m, z) in alone_min.iter_mut().zip(&alone.top) {
                *m = m.min(*z);
            }
            p = q;
        }
        let top = blank().max.z as f32;
        for (k, (c, a)) in chain.top.iter().zip(&alone_min).enumerate() {
            prop_assert_eq!(*c, a.min(top), "cell {}", k);
        }
    }
}

/// A level arc whose end radii differ by the program's rounding (0.001 mm)
/// is swept as one circle, exactly: the tool's rim takes a cell 0.0034 mm
/// inside its reach at the middle of the arc, where chords of a cell/8
/// sagitta would pass it by 0.02 mm.
#[test]
fn a_level_arc_with_rounded_ends_is_swept_exactly() {
    use glam::DVec2;
    use thinplan_stocksim::{parse, ToolLibrary};
    let blank = Blank {
        min: DVec3::new(-10.0, -10.0, -5.0),
        max: DVec3::new(10.0, 10.0, 0.0),
    };
    let mut z = ZMap::new(blank, 0.25).unwrap();
    // Centre (0, 0), start radius 3.87985, end radius 3.88071, ±30°.
    let program = parse(
        "G21 G17 G90\nT1 M6\nS10000 M3\nG0 X3.360 Y-1.940 Z1\nG1 Z-1 F1000\n\
         G3 X3.361 Y1.940 I-3.360 J1.940\nG0 Z5\nM30\n",
        "arc.ngc",
    )
    .unwrap();
    let tools = ToolLibrary::from([(1, ToolShape::flat(2.0))]);
    z.replay(&program, &tools).unwrap();
    // The cell centred at (4.875, 0.125): 0.9966 from the arc.
    let inside = z.height_at(DVec2::new(4.875, 0.125)).unwrap();
    assert!((inside + 1.0).abs() < 1e-6, "{inside}");
    // The next one out, 1.2466 from it, stands.
    let outside = z.height_at(DVec2::new(5.125, 0.125)).unwrap();
    assert_eq!(outside, 0.0);
}
