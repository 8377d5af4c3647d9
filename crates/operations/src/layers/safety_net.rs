//! The safety net: every operation a band plans is checked before it is
//! kept, so a pass the region's construction got wrong is refused rather
//! than cut into the product. Feed moves keep the tool's radius from every
//! product edge and free-space boundary (its section radius from sloped
//! faces) and stay above the floor; rapids stay above the feature's top.

use glam::DVec2;
use thinplan_plan::MachiningFeature;

use super::region::Geometry;
use super::{EPS, STEP};
use crate::geom::Edge2;
use crate::path::{Builder, Kind};

/// Distance slack of the sloped-face safety net (mm): the tool's profile
/// is tangent to the face there, and the torus's sagitta between the
/// net's sample heights is smaller still.
const EPS_SLOPE: f64 = 1e-5;

/// The safety net: every feed move's tool centre at least r from every
/// product edge and never below the feature's floor; rapids above its top.
pub(super) fn check(
    b: &Builder,
    g: &Geometry,
    z_min: f64,
    z_top: f64,
    f: &MachiningFeature,
) -> Result<(), String> {
    // Only edges within r of a centre can fail it: bucketed once.
    let grids = (
        crate::geom::EdgeGrid::new(&g.product_offset, g.r),
        crate::geom::EdgeGrid::new(&g.keep_out, g.r),
    );
    let slope_grids: Vec<crate::geom::EdgeGrid> = g
        .slope_check
        .iter()
        .map(|(rho, e)| crate::geom::EdgeGrid::new(e, *rho))
        .collect();
    let near = |p: DVec2, edges: &[Edge2], grid: &crate::geom::EdgeGrid| {
        grid.candidates(p)
            .iter()
            .map(|&k| edges[k as usize].distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let mut from = b.start;
    for mv in &b.moves {
        if mv.kind == Kind::Rapid {
            // Rapids: straight up out of cleared space, or above the top.
            let vertical_up =
                from.truncate().distance(mv.to.truncate()) < 1e-9 && mv.to.z >= from.z;
            if !vertical_up && from.z.min(mv.to.z) < z_top - 1e-9 {
                let p = mv.to;
                return Err(format!(
                    "internal: a rapid move of {} runs below the feature top at ({:.3}, {:.3}, {:.3})",
                    f.id, p.x, p.y, p.z
                ));
            }
            from = mv.to;
            continue;
        }
        for p in crate::path::move_points(from, mv, STEP)
            .into_iter()
            .chain([from])
        {
            if mv.kind == Kind::Rapid {
                if p.z < z_top - 1e-9 {
                    return Err(format!(
                        "internal: a rapid move of {} runs below the feature top at ({:.3}, {:.3}, {:.3})",
                        f.id, p.x, p.y, p.z
                    ));
                }
                continue;
            }
            if p.z < z_min - 1e-9 {
                return Err(format!("a move goes below the floor at z {:.4}", p.z));
            }
            for ((rho, edges), grid) in g.slope_check.iter().zip(&slope_grids) {
                let dist = near(p.truncate(), edges, grid);
                if dist < rho - EPS_SLOPE {
                    return Err(format!(
                        "a move would touch a sloped product face: tool centre ({:.3}, {:.3}, \
                         {:.3}) is {dist:.6} mm from it where the tool's section radius is \
                         {rho:.6}",
                        p.x, p.y, p.z
                    ));
                }
            }
            let own = near(p.truncate(), &g.product_offset, &grids.0);
            let other = near(p.truncate(), &g.keep_out, &grids.1);
            let dist = own.min(other);
            if dist < g.r - EPS {
                let which = if own <= other {
                    "product edge"
                } else {
                    "free-space boundary (other product)"
                };
                return Err(format!(
                    "a move would touch product: tool centre ({:.3}, {:.3}) of a {:?} move is \
                     {:.4} mm from a {which}, tool radius {:.3}",
                    p.x, p.y, mv.kind, dist, g.r
                ));
            }
        }
        from = mv.to;
    }
    Ok(())
}
