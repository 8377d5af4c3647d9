//! Entries and links within a band: getting to a pass's start (the first
//! move down from the safe height, then transits through cleared space),
//! getting down into a level without plunging (helix or ramp, and the
//! ramp along a boundary pass's own straight start), and retracting.

use glam::DVec2;
use thinplan_knowledge::{LevelEntry, MethodKnowledge, SpindleDirection};

use super::boundary::BoundaryPass;
use super::plan_view::product_distance;
use super::region::Geometry;
use super::STEP;
use crate::geom::{boundary_distance, inside, segment_inside};
use crate::path::{helix, ramp, Builder, Kind, Space};

/// Moves to `to` at the cleared height `z_clear`: the operation's first
/// move comes down from the safe height, rapid to the top of the stock and
/// fed below it; later ones are transits (`Space::transit`).
pub(super) fn go_to(b: &mut Builder, started: &mut bool, space: &Space, to: DVec2, z_clear: f64) {
    if !*started {
        *b = Builder::new(to.extend(space.safe_z));
        b.line(to.extend(space.z_top), Kind::Rapid);
        b.line(to.extend(z_clear), Kind::Link);
        *started = true;
    } else {
        space.transit(b, to, z_clear);
    }
}

/// Straight up to the safe height.
pub(super) fn retract(b: &mut Builder, safe_z: f64) {
    let p = b.pos;
    b.line(p.truncate().extend(safe_z), Kind::Rapid);
}

/// Gets from `z_from` down to `z` at the block's start: a helix where the
/// method asks and it fits, else a ramp along the block; `None` if neither.
#[allow(clippy::too_many_arguments)]
pub(super) fn enter(
    b: &mut Builder,
    entry: LevelEntry,
    block: &[DVec2],
    z_from: f64,
    z: f64,
    angle: f64,
    d: f64,
    g: &Geometry,
    centred: Option<(DVec2, f64)>,
    mk: &MethodKnowledge,
    kind: Kind,
) -> Option<()> {
    let spindle = mk.spindle;
    if z_from - z <= 1e-12 {
        return Some(());
    }
    // Down milling around the helix: counter-clockwise for M3.
    let ccw = spindle == SpindleDirection::Clockwise;
    if let Some((c, rho)) = centred {
        // A spiral started where it leaves this helix's circle: only this
        // helix clears the middle, so there is no other way in.
        let fits = inside(c, &g.centre_polys)
            && boundary_distance(c, &g.centre_polys) >= rho + 1e-6
            && product_distance(c, &g.product) >= g.r + rho;
        if !fits {
            return None;
        }
        let a0 = (block[0] - c).to_angle();
        helix(b, c, rho, a0, z_from, z, angle, ccw, kind);
        return Some(());
    }
    if let LevelEntry::Helix { radius, .. } = entry {
        let p0 = block[0];
        for s in &mk.fit_scales {
            let rho = radius * d * s;
            let c = p0 - DVec2::new(rho, 0.0);
            let fits = inside(c, &g.centre_polys)
                && boundary_distance(c, &g.centre_polys) >= rho + 1e-6
                && product_distance(c, &g.product) >= g.r + rho;
            if fits {
                helix(b, c, rho, 0.0, z_from, z, angle, ccw, kind);
                return Some(());
            }
        }
    }
    let min_len = 0.02 * d;
    if ramp(b, block, z_from, z, angle, min_len, kind).is_some() {
        return Some(());
    }
    // The block is too short to ramp along (a small rest region): ramp back
    // and forth along the longest straight run from its start that stays in
    // the tool-centre region, the direction found among 24.
    let p0 = block[0];
    let need = (z_from - z) / angle.tan();
    let (mut best, mut best_len) = (p0, 0.0);
    let limit = need.max(min_len);
    let h = STEP / 2.0;
    let ok = |p: DVec2| inside(p, &g.centre_polys) || boundary_distance(p, &g.centre_polys) < 1e-6;
    for k in 0..24 {
        let u = DVec2::from_angle(std::f64::consts::TAU * k as f64 / 24.0);
        // Walk out in half-steps until the run leaves the region.
        let mut len = 0.0;
        while len < limit {
            let next = (len + h).min(limit);
            if !ok(p0 + u * next) {
                break;
            }
            len = next;
        }
        if len > best_len + 1e-9 {
            best_len = len;
            best = p0 + u * len;
        }
        if best_len >= limit {
            break;
        }
    }
    ramp(b, &[p0, best], z_from, z, angle, min_len, kind)
}

/// The boundary passes of one z-level, stacked where the z-level is deeper
/// than the boundary depth of cut.
#[allow(clippy::too_many_arguments)]
pub(super) fn boundary_level(
    b: &mut Builder,
    started: &mut bool,
    space: &Space,
    passes: &[BoundaryPass],
    rest_polys: &[Vec<DVec2>],
    z_prev: f64,
    z: f64,
    a_b: f64,
    angle: f64,
) {
    if passes.is_empty() {
        return;
    }
    let m = ((z_prev - z) / a_b - 1e-9).ceil().max(1.0) as usize;
    for j in 1..=m {
        let zj = if j == m {
            z
        } else {
            z_prev - (z_prev - z) * j as f64 / m as f64
        };
        for p in passes {
            let here = b.pos.truncate();
            if *started
                && !rest_polys.is_empty()
                && inside(here, rest_polys)
                && segment_inside(here, p.start, rest_polys, STEP)
                && space.line_clear(here, p.start, b.pos.z)
            {
                // Through the rest region just cleared at this level.
                b.line(p.start.extend(b.pos.z), Kind::Link);
                b.line(p.start.extend(zj), Kind::Link);
            } else {
                // Down to the height cleared so far, then ramp along the
                // pass itself (its centre keeps r from the product) rather
                // than plunging; a pass that starts beyond an open edge
                // starts in air.
                let z_hi = if j == 1 {
                    z_prev
                } else {
                    z_prev - (z_prev - z) * (j - 1) as f64 / m as f64
                };
                go_to(b, started, space, p.start, z_hi);
                if z_hi > zj + 1e-12 {
                    // The straight stretch the pass starts with (a chord of
                    // one of its arcs would come closer than r); an entry,
                    // so its legs back are roughing, not boundary, moves.
                    let mut prefix = vec![p.start];
                    for sg in p.segs.iter().take_while(|sg| sg.arc.is_none()) {
                        prefix.push(sg.to);
                    }
                    let ramped = p.lead_in != "from-open-side"
                        && ramp(b, &prefix, z_hi, zj, angle, STEP, Kind::Rest).is_some();
                    if !ramped {
                        b.line(p.start.extend(zj), Kind::Link);
                    }
                }
            }
            b.follow(&p.segs, zj, Kind::Boundary);
        }
    }
}
