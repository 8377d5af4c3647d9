//! The safety net: every operation a band plans is checked before it is
//! kept, so a pass the region's construction got wrong is refused rather
//! than cut into the product. Feed moves keep the tool's radius from every
//! product edge and free-space boundary (its section radius from sloped
//! faces) and stay above the floor; rapids stay above the feature's top.

use glam::{DVec2, DVec3};
use thinplan_plan::MachiningFeature;

use super::region::Geometry;
use super::{EPS, STEP};
use crate::geom::Edge2;
use crate::path::{Builder, Kind};

/// Distance slack of the sloped-face safety net (mm): the tool's profile
/// is tangent to the face there, and the torus's sagitta between the
/// net's sample heights is smaller still.
const EPS_SLOPE: f64 = 1e-5;

/// The product checks of the safety net at one tool centre: the grids of
/// the edges it keeps the radius from, built once per geometry.
pub(super) struct Net<'g> {
    g: &'g Geometry,
    product: crate::geom::EdgeGrid,
    keep_out: crate::geom::EdgeGrid,
    slopes: Vec<crate::geom::EdgeGrid>,
}

impl<'g> Net<'g> {
    pub(super) fn new(g: &'g Geometry) -> Self {
        // Only edges within r of a centre can fail it: bucketed once.
        Net {
            g,
            product: crate::geom::EdgeGrid::new(&g.product_offset, g.r),
            keep_out: crate::geom::EdgeGrid::new(&g.keep_out, g.r),
            slopes: g
                .slope_check
                .iter()
                .map(|(rho, e)| crate::geom::EdgeGrid::new(e, *rho))
                .collect(),
        }
    }

    fn near(p: DVec2, edges: &[Edge2], grid: &crate::geom::EdgeGrid) -> f64 {
        grid.candidates(p)
            .iter()
            .map(|&k| edges[k as usize].distance(p))
            .fold(f64::INFINITY, f64::min)
    }

    /// Why a tool centre at `p` of a `kind` move would touch product, if
    /// it would: closer than the radius to a product edge or free-space
    /// boundary, or than the section radius to a sloped face.
    pub(super) fn touches(&self, p: DVec3, kind: Kind) -> Option<String> {
        let g = self.g;
        for ((rho, edges), grid) in g.slope_check.iter().zip(&self.slopes) {
            let dist = Self::near(p.truncate(), edges, grid);
            if dist < rho - EPS_SLOPE {
                return Some(format!(
                    "a move would touch a sloped product face: tool centre ({:.3}, {:.3}, \
                     {:.3}) is {dist:.6} mm from it where the tool's section radius is \
                     {rho:.6}",
                    p.x, p.y, p.z
                ));
            }
        }
        let own = Self::near(p.truncate(), &g.product_offset, &self.product);
        let other = Self::near(p.truncate(), &g.keep_out, &self.keep_out);
        let dist = own.min(other);
        if dist < g.r - EPS {
            let which = if own <= other {
                "product edge"
            } else {
                "free-space boundary (other product)"
            };
            return Some(format!(
                "a move would touch product: tool centre ({:.3}, {:.3}) of a {kind:?} move is \
                 {dist:.4} mm from a {which}, tool radius {:.3}",
                p.x, p.y, g.r
            ));
        }
        None
    }
}

/// The safety net: every feed move's tool centre at least r from every
/// product edge and never below the feature's floor; rapids above its top.
pub(super) fn check(
    b: &Builder,
    g: &Geometry,
    z_min: f64,
    z_top: f64,
    f: &MachiningFeature,
) -> Result<(), String> {
    let net = Net::new(g);
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
            if p.z < z_min - 1e-9 {
                return Err(format!("a move goes below the floor at z {:.4}", p.z));
            }
            if let Some(why) = net.touches(p, mv.kind) {
                return Err(why);
            }
        }
        from = mv.to;
    }
    Ok(())
}
