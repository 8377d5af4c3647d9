//! Helpers shared by the pipeline's tests.

use glam::DVec3;
use thinplan_plan::{Operation, Region3};

/// Tool-centre positions of the cutting moves, every 0.5 mm at most
/// (arcs about the z axis followed along the arc).
pub fn cutting_centres(op: &Operation) -> Vec<DVec3> {
    let mut out = Vec::new();
    let mut from = op.start;
    for m in &op.moves {
        let cutting = m.feed > 0.0
            && matches!(
                m.region,
                Region3::Boundary | Region3::FullCut | Region3::Rest
            );
        if cutting {
            let pts: Vec<DVec3> = match m.arc {
                Some(a) if a.axis.z.abs() > 0.999 => {
                    let c = a.centre;
                    let (u, v) = (from - c, m.to - c);
                    let ccw = (a.axis.z > 0.0) != a.clockwise;
                    let (a0, a1) = (u.y.atan2(u.x), v.y.atan2(v.x));
                    let mut sweep = if ccw { a1 - a0 } else { a0 - a1 };
                    if sweep <= 0.0 {
                        sweep += std::f64::consts::TAU;
                    }
                    let rad = u.truncate().length();
                    let k = ((sweep * rad / 0.5).ceil() as usize).max(1);
                    (0..=k)
                        .map(|s| {
                            let t = s as f64 / k as f64;
                            let ang = if ccw { a0 + sweep * t } else { a0 - sweep * t };
                            DVec3::new(
                                c.x + rad * ang.cos(),
                                c.y + rad * ang.sin(),
                                from.z + (m.to.z - from.z) * t,
                            )
                        })
                        .collect()
                }
                _ => {
                    let k = ((from.distance(m.to) / 0.5).ceil() as usize).max(1);
                    (0..=k)
                        .map(|s| from.lerp(m.to, s as f64 / k as f64))
                        .collect()
                }
            };
            out.extend(pts);
        }
        from = m.to;
    }
    out
}
