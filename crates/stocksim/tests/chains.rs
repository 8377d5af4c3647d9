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
