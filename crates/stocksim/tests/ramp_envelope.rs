//! Ramps (moves with XY and Z together) against brute force: the swept
//! stock of a straight 3D move must equal the lowest tool surface over a
//! dense sampling of tool positions along the move, for flat, ball and
//! bull-nose tools.

use glam::DVec3;
use proptest::prelude::*;
use thinplan_stocksim::{Blank, ToolShape, ZMap};

const SAMPLES: usize = 4000;

fn blank() -> Blank {
    Blank {
        min: DVec3::new(-20.0, -20.0, -40.0),
        max: DVec3::new(20.0, 20.0, 10.0),
    }
}

/// Per cell, the lowest tool surface over `SAMPLES + 1` evenly spaced tool
/// positions (both ends included); `None` where no sample covers the cell.
fn brute_force(z: &ZMap, tool: &ToolShape, p0: DVec3, p1: DVec3) -> Vec<Option<f64>> {
    let g = z.grid;
    let r = tool.radius();
    let pos: Vec<DVec3> = (0..=SAMPLES)
        .map(|i| p0.lerp(p1, i as f64 / SAMPLES as f64))
        .collect();
    let mut out = vec![None; g.len()];
    for j in 0..g.ny {
        for i in 0..g.nx {
            let c = g.center(i, j);
            let mut best = f64::INFINITY;
            for p in &pos {
                let rho = (c - p.truncate()).length();
                // The simulation leaves cells exactly at the rim alone.
                if rho < r - 1e-6 {
                    if let Some(h) = tool.height_at(rho) {
                        best = best.min(p.z + h);
                    }
                }
            }
            if best.is_finite() {
                out[j * g.nx + i] = Some(best.max(z.blank.min.z));
            }
        }
    }
    out
}

fn check(tool: ToolShape, p0: DVec3, p1: DVec3) -> Result<(), TestCaseError> {
    let mut z = ZMap::new(blank(), 0.25).unwrap();
    z.sweep_line(&tool, p0, p1, 1);
    let brute = brute_force(&z, &tool, p0, p1);
    // Sampling misses the true minimum by at most the height change over one
    // sample step where the minimum is at the edge of the flat bottom (zero
    // where it is interior: the function is flat there) plus f32 rounding.
    let step = (p1 - p0).length() / SAMPLES as f64;
    let slope = (p1.z - p0.z).abs() / (p1 - p0).truncate().length().max(1e-12);
    let tol = slope * step + 1e-4;
    let top0 = blank().max.z;
    for (k, b) in brute.iter().enumerate() {
        let sim = z.top[k] as f64;
        match b {
            Some(b) if *b < top0 - 1e-4 => {
                // Exact minimum ≤ any sampled position; never below it by
                // more than the sampling error.
                prop_assert!(
                    sim <= b + 2e-5,
                    "cell {k}: simulated {sim} above brute force {b} ({tool:?} {p0} → {p1})"
                );
                prop_assert!(
                    b - sim <= tol,
                    "cell {k}: simulated {sim} below brute force {b} by {} > {tol} ({tool:?} {p0} → {p1})",
                    b - sim
                );
            }
            _ => {}
        }
    }
    Ok(())
}

fn tool_strategy() -> impl Strategy<Value = ToolShape> {
    (2.0f64..12.0, 0u8..3, 0.05f64..0.95).prop_map(|(d, kind, f)| match kind {
        0 => ToolShape::flat(d),
        1 => ToolShape::ball(d),
        _ => ToolShape::bull(d, f * d / 2.0),
    })
}

fn point() -> impl Strategy<Value = DVec3> {
    (-8.0f64..8.0, -8.0f64..8.0, -10.0f64..0.0).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn ramps_match_dense_sampling(tool in tool_strategy(), p0 in point(), p1 in point()) {
        check(tool, p0, p1)?;
    }

    /// Shallow ramps as the planner writes them (a few degrees).
    #[test]
    fn shallow_ramps_match_dense_sampling(
        tool in tool_strategy(),
        p0 in point(),
        dx in -12.0f64..12.0,
        dy in -12.0f64..12.0,
        slope in -0.2f64..0.2,
    ) {
        let d = (dx * dx + dy * dy).sqrt();
        let p1 = p0 + DVec3::new(dx, dy, slope * d);
        check(tool, p0, p1)?;
    }
}

#[test]
fn every_tool_kind_on_a_steep_and_a_shallow_ramp() {
    for tool in [
        ToolShape::flat(10.0),
        ToolShape::ball(10.0),
        ToolShape::bull(12.0, 0.5),
        ToolShape::bull(20.0, 1.0),
        ToolShape::bull(8.0, 3.9),
    ] {
        for p1 in [DVec3::new(6.0, 2.0, -1.0), DVec3::new(3.0, -1.0, -9.0)] {
            check(tool, DVec3::new(-5.0, 0.5, -0.3), p1).unwrap();
            check(tool, p1, DVec3::new(-5.0, 0.5, -0.3)).unwrap();
        }
    }
}
