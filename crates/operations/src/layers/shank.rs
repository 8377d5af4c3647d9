//! Bands over obstacles: a feature's levels split where the shank above
//! the flutes would reach a taller feature still standing beside it, and
//! each such band planned with that feature as a wall and out of the free
//! space, so only the cutter touches it. The area a band then leaves is
//! measured against the whole feature's plan, and a band that cannot be
//! planned on its own falls back to the whole plan, said.

use glam::DVec2;
use thinplan_knowledge::Tool;
use thinplan_plan::{Adjacency, MachiningFeature};

use super::band::plan_band;
use super::plan_view::seg_seg_distance;
use super::{Env, LocalOp, Made};
use crate::geom::inside;
use crate::path::{seg_points, Kind, Seg2};

/// Overlaps below this (mm) are contact, not collision (as in the holder
/// and shank check): a pass tangent to a neighbour's side touches it.
const CONTACT: f64 = 1e-3;

/// A feature's operations, kept clear of the shank.
///
/// A tool cuts no deeper than its flute length per level, but beside a
/// machining feature that still stands, a level more than a flute length
/// below that feature's top puts the shank into it wherever the path
/// overhangs the shared edge. Such levels are planned as their own band
/// with that feature taken out of the free space, so the cutter only
/// touches it; the bands above keep the overhang. A band that finds no
/// room that way (a step narrower than the tool beside it) keeps the
/// overhang and says so: the holder and shank check then reports it.
pub(crate) fn feature_operations(
    f: &MachiningFeature,
    env: &Env,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    obstacles: &[crate::free::Obstacle],
) -> Result<Made, String> {
    let whole = plan_band(f, env, free, removed)?;
    if env.orphans.is_some() {
        // Run last, when every other feature is gone: no shank bands.
        return Ok(whole);
    }
    let Some(free) = free else {
        return Ok(whole);
    };
    let Some(tool) = whole
        .ops
        .first()
        .and_then(|o| env.tools.tools.iter().find(|t| t.id == o.tool))
    else {
        return Ok(whole);
    };
    let (flute, r) = (tool.flute_length, tool.diameter / 2.0);
    // Each obstacle the tool's reach meets, with the height below which the
    // shank would be in it.
    let deep: Vec<(f64, &crate::free::Obstacle)> = obstacles
        .iter()
        .map(|o| (o.top - flute, o))
        .filter(|(z, o)| *z > f.shape.z_min + CONTACT && reaches(&whole.reach, o, r))
        .collect();
    if deep.is_empty() {
        return Ok(whole);
    }
    let mut cuts: Vec<f64> = deep
        .iter()
        .map(|(z, _)| *z)
        .filter(|z| *z < f.shape.z_max - CONTACT)
        .collect();
    cuts.extend([f.shape.z_max, f.shape.z_min]);
    cuts.sort_by(|a, b| b.total_cmp(a));
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let mut out = Made {
        ops: Vec::new(),
        warnings: whole.warnings.clone(),
        unreachable: Vec::new(),
        reach: whole.reach.clone(),
    };
    for w in cuts.windows(2) {
        let (hi, lo) = (w[0], w[1]);
        let mut band = f.clone();
        band.shape.z_max = hi;
        band.shape.z_min = lo;
        if lo > f.shape.z_min + 1e-9 {
            // Below this band stands the rest of the same feature.
            band.bottom_adjacency = Adjacency::Feature;
        }
        let active: Vec<&crate::free::Obstacle> = deep
            .iter()
            .filter(|(z, _)| *z >= hi - 1e-6)
            .map(|(_, o)| *o)
            .collect();
        let made = match shank_clear_band(&band, &active, &whole.ops, env, free, removed, tool) {
            Ok(m) => m,
            Err(e) => return Ok(unbanded(whole, f, lo, hi, &e)),
        };
        out.ops.extend(made.ops);
        for w in made.warnings {
            if !out.warnings.contains(&w) {
                out.warnings.push(w);
            }
        }
        out.unreachable.extend(made.unreachable);
    }
    Ok(out)
}

/// One band's plan with the shank of `tool` kept out of the obstacles it
/// would reach (`active`): their edges are walls for the band and they
/// leave the free space. Where that finds no plan, the band keeps the
/// overhang, and says so. `Err`: the band cannot be planned on its own.
fn shank_clear_band(
    band: &MachiningFeature,
    active: &[&crate::free::Obstacle],
    whole: &[LocalOp],
    env: &Env,
    free: &crate::free::Shapes,
    removed: Option<&crate::free::Shapes>,
    tool: &Tool,
) -> Result<Made, String> {
    if active.is_empty() {
        return plan_band(band, env, Some(free), removed);
    }
    let (flute, r) = (tool.flute_length, tool.diameter / 2.0);
    let (lo, hi) = (band.shape.z_min, band.shape.z_max);
    let names: Vec<String> = active
        .iter()
        .map(|o| format!("{}(top {:.3})", o.id, o.top))
        .collect();
    let clear = crate::free::without(free, active);
    // Its edges towards them are walls for this band: a pass runs
    // along them (the rest pattern alone would leave a strip where
    // the overhang would have reached).
    let mut walled = band.clone();
    walls_towards(&mut walled, active);
    // Kept even where it reaches less than the overhanging plan in
    // this band: a shank in standing material is a collision the
    // verification would take the whole operation out for, while
    // what the band leaves is beside features cut later (their
    // passes, open towards this one, and stage 7's second pass).
    match plan_band(&walled, env, Some(&clear), removed) {
        Ok(mut m) => {
            let lost = lost_area(whole, &m.ops, band, r);
            if lost > LOST_AREA {
                m.warnings.push(format!(
                    "{}: levels {lo:.3}..{hi:.3} keep the shank out of {}: {lost:.1} mm² \
                     the overhang would reach is left to the features cut after it",
                    band.id,
                    names.join(", ")
                ));
            }
            for op in &mut m.ops {
                op.provenance.note.push_str(&format!(
                    "; shank_clear_of={} (flute {flute:.3} mm, band {lo:.3}..{hi:.3})",
                    names.join(",")
                ));
                op.provenance.values.insert("shank_band_top_mm".into(), hi);
                if lost > LOST_AREA {
                    op.provenance
                        .values
                        .insert("shank_band_lost_mm2".into(), lost);
                }
            }
            Ok(m)
        }
        Err(e) => {
            let mut m = plan_band(band, env, Some(free), removed)?;
            m.warnings.push(format!(
                "{}: levels {lo:.3}..{hi:.3} cannot keep the shank out of {} ({e}); \
                 planned with the overhang, the shank rubs there",
                band.id,
                names.join(", ")
            ));
            Ok(m)
        }
    }
}

/// The whole feature's plan, kept where a band of it cannot be planned on
/// its own (its shank clearance is then given up, and said).
fn unbanded(mut whole: Made, f: &MachiningFeature, lo: f64, hi: f64, e: &str) -> Made {
    whole.warnings.push(format!(
        "{}: levels {lo:.3}..{hi:.3} cannot be planned as a band of their own ({e}); \
         the feature is planned whole and its shank may rub taller features beside it",
        f.id
    ));
    whole
}

/// Marks as product the edges of `f` whose outward side lies in one of the
/// obstacles (only `feature` edges: the others face product or air).
fn walls_towards(f: &mut MachiningFeature, obstacles: &[&crate::free::Obstacle]) {
    let polys: Vec<Vec<Vec<DVec2>>> = obstacles
        .iter()
        .map(|o| {
            o.region
                .iter()
                .map(|c| c.iter().map(|q| DVec2::new(q[0], q[1])).collect())
                .collect()
        })
        .collect();
    let as_poly = |l: &thinplan_plan::ProfileLoop| -> Vec<DVec2> {
        l.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect()
    };
    let mut own_loops = vec![as_poly(&f.shape.region.outer)];
    own_loops.extend(f.shape.region.holes.iter().map(as_poly));
    let own = &own_loops;
    let mark = |l: &thinplan_plan::ProfileLoop, adj: &mut [Adjacency]| {
        let n = l.vertices.len();
        for (i, a) in adj.iter_mut().enumerate().take(n) {
            if *a != Adjacency::Feature {
                continue;
            }
            let (p, q) = (&l.vertices[i], &l.vertices[(i + 1) % n]);
            let (p, q) = (DVec2::new(p.x, p.y), DVec2::new(q.x, q.y));
            let t = (q - p).normalize_or_zero();
            // Outward: the side of the edge off the feature's own region.
            let m = (p + q) * 0.5;
            let nrm = DVec2::new(t.y, -t.x) * 1e-3;
            let probe = if inside(m + nrm, own) {
                m - nrm
            } else {
                m + nrm
            };
            if polys.iter().any(|o| inside(probe, o)) {
                *a = Adjacency::Product;
            }
        }
    };
    let outer = f.shape.region.outer.clone();
    mark(&outer, &mut f.side_adjacency);
    for (h, adj) in f
        .shape
        .region
        .holes
        .clone()
        .iter()
        .zip(f.hole_adjacency.iter_mut())
    {
        mark(h, adj);
    }
}

/// Plan-view area (mm²) a band may reach less than the whole feature's
/// plan before its shank clearance is given up: a few grid cells of noise.
const LOST_AREA: f64 = 1.0;
/// Grid step (mm) of the coverage comparison.
const COVER_STEP: f64 = 0.5;

/// Plan-view area of the band's region that the level passes of `whole`
/// at the band's heights reach and those of `band_ops` do not (mm²).
fn lost_area(whole: &[LocalOp], band_ops: &[LocalOp], band: &MachiningFeature, r: f64) -> f64 {
    let region: Vec<Vec<DVec2>> = {
        let mut v = vec![band
            .shape
            .region
            .outer
            .vertices
            .iter()
            .map(|q| DVec2::new(q.x, q.y))
            .collect::<Vec<_>>()];
        v.extend(
            band.shape
                .region
                .holes
                .iter()
                .map(|h| h.vertices.iter().map(|q| DVec2::new(q.x, q.y)).collect()),
        );
        v
    };
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for q in region.iter().flatten() {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    if !(lo.x.is_finite() && hi.x.is_finite()) {
        return 0.0;
    }
    let nx = ((hi.x - lo.x) / COVER_STEP).ceil() as usize + 1;
    let ny = ((hi.y - lo.y) / COVER_STEP).ceil() as usize + 1;
    let at = |i: usize, j: usize| lo + DVec2::new(i as f64, j as f64) * COVER_STEP;
    let (z_lo, z_hi) = (band.shape.z_min - 1e-6, band.shape.z_max + 1e-6);
    // The whole plan counts a cell only where its disc covers it with room
    // to spare, the band wherever its disc touches it: grazing is no loss.
    let cover = |ops: &[LocalOp], zs: bool| -> Vec<bool> {
        let mut hit = vec![false; nx * ny];
        let reach = if zs { (r - 0.05).max(0.0) } else { r + 1e-3 };
        for op in ops {
            let mut from = op.start;
            for m in &op.moves {
                // Level passes only: a ramp's first stretch may graze what
                // a later feature's overhang takes anyway.
                let cutting =
                    !matches!(m.kind, Kind::Rapid | Kind::Link) && (m.to.z - from.z).abs() < 1e-9;
                let in_band = !zs || (m.to.z >= z_lo && m.to.z <= z_hi);
                if cutting && in_band {
                    let s = Seg2 {
                        to: m.to.truncate(),
                        arc: m.arc,
                    };
                    let mut a = from.truncate();
                    for b in seg_points(a, &s, 1.0) {
                        let (p, q) = (a.min(b) - reach, a.max(b) + reach);
                        let i0 = ((p.x - lo.x) / COVER_STEP).floor().max(0.0) as usize;
                        let j0 = ((p.y - lo.y) / COVER_STEP).floor().max(0.0) as usize;
                        let i1 = (((q.x - lo.x) / COVER_STEP).ceil().max(0.0) as usize).min(nx - 1);
                        let j1 = (((q.y - lo.y) / COVER_STEP).ceil().max(0.0) as usize).min(ny - 1);
                        for j in j0..=j1 {
                            for i in i0..=i1 {
                                let k = j * nx + i;
                                if !hit[k] && crate::geom::dist_point_seg(at(i, j), a, b) <= reach {
                                    hit[k] = true;
                                }
                            }
                        }
                        a = b;
                    }
                }
                from = m.to;
            }
        }
        hit
    };
    let before = cover(whole, true);
    let after = cover(band_ops, false);
    let mut lost = 0usize;
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            if before[k] && !after[k] && inside(at(i, j), &region) {
                lost += 1;
            }
        }
    }
    lost as f64 * COVER_STEP * COVER_STEP
}

/// Whether a tool of radius `r` whose centre stays in `reach` comes closer
/// than contact to the obstacle's region.
fn reaches(reach: &[Vec<DVec2>], o: &crate::free::Obstacle, r: f64) -> bool {
    let obstacle: Vec<Vec<DVec2>> = o
        .region
        .iter()
        .map(|c| c.iter().map(|q| DVec2::new(q[0], q[1])).collect())
        .collect();
    let near = r - CONTACT;
    for poly in reach {
        for (k, &p) in poly.iter().enumerate() {
            if inside(p, &obstacle) {
                return true;
            }
            let q = poly[(k + 1) % poly.len()];
            for c in &obstacle {
                for i in 0..c.len() {
                    let (a, b) = (c[i], c[(i + 1) % c.len()]);
                    if seg_seg_distance(p, q, a, b) < near {
                        return true;
                    }
                }
            }
        }
    }
    false
}
