//! Conventional parallel-offset pocketing (the baseline).

use cavalier_contours::polyline::{PlineSource, Polyline};
use glam::DVec2;

use crate::geom::{directed_gap, dist_point_seg, sample_pline, SegIndex};
use crate::{Method, Pocket, PocketError, PocketParams, PocketPath};

/// Inward offset loops of the pocket (outer shrunk, islands grown) by distance `d`.
pub fn offset_loops(pocket: &Pocket, d: f64) -> Vec<Polyline<f64>> {
    let keep = |p: &Polyline<f64>| p.is_closed() && p.vertex_count() >= 2 && p.area().abs() > 1e-12;
    if pocket.islands.is_empty() {
        let plain = std::panic::catch_unwind(|| pocket.outer.parallel_offset(d)).ok();
        if let Some(plain) = plain.filter(|l| !l.is_empty() && l.iter().all(keep)) {
            return plain;
        }
    }
    // With islands, or where the plain offset failed (sections of fillets).
    let mut all = vec![pocket.outer.clone()];
    all.extend(pocket.islands.iter().cloned());
    let off = crate::inset::inset(&all, d);
    off.ccw_plines
        .into_iter()
        .chain(off.cw_plines)
        .map(|ip| ip.polyline)
        .filter(keep)
        .collect()
}

/// Sample loops of one offset level.
pub(crate) fn sample_level(loops: &[Polyline<f64>], step: f64) -> Vec<Vec<DVec2>> {
    loops
        .iter()
        .map(|p| sample_pline(p, step, 3f64.to_radians()))
        .filter(|p| p.len() >= 3)
        .collect()
}

/// Append a full closed traversal of `lp` to `path`, starting at the point of `lp` nearest to
/// the current end of `path` (a straight link leads there). The loop keeps its orientation.
pub(crate) fn append_loop_from_nearest(path: &mut Vec<DVec2>, lp: &[DVec2]) {
    let n = lp.len();
    let Some(&cur) = path.last() else {
        path.extend_from_slice(lp);
        path.push(lp[0]);
        return;
    };
    let mut best = (f64::INFINITY, 0usize);
    for i in 0..n {
        let d = dist_point_seg(cur, lp[i], lp[(i + 1) % n]);
        if d < best.0 {
            best = (d, i);
        }
    }
    let i = best.1;
    let (a, b) = (lp[i], lp[(i + 1) % n]);
    let ab = b - a;
    let t = ((cur - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
    let start = a + ab * t;
    let push = |path: &mut Vec<DVec2>, p: DVec2| {
        if path.last().is_none_or(|q| q.distance_squared(p) > 1e-18) {
            path.push(p);
        }
    };
    push(path, start);
    for k in 1..=n {
        push(path, lp[(i + k) % n]);
    }
    push(path, start);
}

/// Symmetric gap between two sets of closed loops.
pub(crate) fn level_gap(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> f64 {
    let ra: Vec<&[DVec2]> = a.iter().map(|v| v.as_slice()).collect();
    let rb: Vec<&[DVec2]> = b.iter().map(|v| v.as_slice()).collect();
    let ia = SegIndex::new(&ra, true);
    let ib = SegIndex::new(&rb, true);
    let ab = a.iter().map(|l| directed_gap(l, &ib)).fold(0.0, f64::max);
    let ba = b.iter().map(|l| directed_gap(l, &ia)).fold(0.0, f64::max);
    ab.max(ba)
}

/// Parallel-offset pocketing: rings at offsets R (finishing), R + f, R + f + s, R + f + 2s, …
/// until empty (plus a ring half a stepover further in if the stepover exceeds the tool radius,
/// so the centre is not left uncut), linked innermost to outermost with short straight links.
/// Each ring is traversed in its cavalier orientation: counter-clockwise for the outer wall,
/// clockwise around islands — down milling with an M3 spindle in both cases.
pub fn offset_path(pocket: &Pocket, params: &PocketParams) -> Result<PocketPath, PocketError> {
    offset_path_styled(pocket, params, params.stepover, false)
}

/// The conventional "rectilinear" baseline Bieterman compared against (`shared/seeds/001_…`:
/// offsets that "inherit any corners", the tool decelerating "to rest, or near rest" at each):
/// the same rings and links as [`offset_path`], but every convex corner fillet of a roughing
/// ring (an arc of radius below the tool diameter on a ring with straight sides) is replaced by
/// its chord, so the rings are
/// polylines with sharp corners (the chord lies inside the arc: no gouge). Larger arcs (a
/// circular pocket) and concave arcs (around islands) are kept. The finishing pass keeps the
/// wall's arcs.
pub fn offset_path_sharp(
    pocket: &Pocket,
    params: &PocketParams,
) -> Result<PocketPath, PocketError> {
    offset_path_styled(pocket, params, params.stepover, true)
}

/// Parallel offsets held to the same maximum engagement as the curvilinear spiral: the ring
/// stepover s' is reduced from s in steps of 2 % until the measured gap between successive
/// rings (symmetric Hausdorff, corners included) is ≤ s. Returns the path and s'.
pub fn offset_path_gap_matched(
    pocket: &Pocket,
    params: &PocketParams,
) -> Result<(PocketPath, f64), PocketError> {
    let s = params.stepover;
    let mut last = None;
    for j in 0..=40 {
        let sj = s * (1.0 - 0.02 * j as f64);
        let p = offset_path_styled(pocket, params, sj, false)?;
        if p.max_gap <= s + 1e-9 {
            return Ok((p, sj));
        }
        last = Some((p, sj));
    }
    // not reached for the bench family (worst corner 60°: s' = s/2); return the finest tried
    Ok(last.expect("at least one attempt"))
}

/// Replace convex corner fillets (arcs turning with the loop, radius below `max_radius`, on a
/// loop that has straight sides) by their chords. Larger arcs, wide blends and all-arc loops (a
/// circular pocket's rings) are geometry, not corners, and are kept.
fn flatten_corner_arcs(pl: &Polyline<f64>, max_radius: f64) -> Polyline<f64> {
    use cavalier_contours::polyline::{
        seg_arc_radius_and_center, PlineCreation, PlineSourceMut, PlineVertex,
    };
    let sense = pl.area().signum();
    let n = pl.vertex_count();
    if pl.iter_vertexes().all(|v| v.bulge.abs() > 1e-12) {
        return pl.clone(); // no straight side (a circle): no fillet to sharpen
    }
    let mut out = Polyline::with_capacity(n, pl.is_closed());
    for i in 0..n {
        let v = pl.at(i);
        let corner = v.bulge * sense > 0.0
            && seg_arc_radius_and_center(v, pl.at((i + 1) % n)).0 < max_radius;
        out.add_vertex(PlineVertex::new(
            v.x,
            v.y,
            if corner { 0.0 } else { v.bulge },
        ));
    }
    out
}

fn offset_path_styled(
    pocket: &Pocket,
    params: &PocketParams,
    ring_step: f64,
    sharp: bool,
) -> Result<PocketPath, PocketError> {
    params.validate()?;
    pocket.validate()?;
    let r = params.tool_diameter / 2.0;
    let s = ring_step;
    let f = params.finish_stepover;
    let step = params.sample_step();
    let finish = offset_loops(pocket, r);
    if finish.is_empty() {
        return Err(PocketError::ToolDoesNotFit);
    }
    let mut levels: Vec<Vec<Vec<DVec2>>> = vec![sample_level(&finish, step)];
    let rough = |l: Vec<Polyline<f64>>| -> Vec<Vec<DVec2>> {
        if sharp {
            let flat: Vec<Polyline<f64>> = l
                .iter()
                .map(|p| flatten_corner_arcs(p, params.tool_diameter))
                .collect();
            sample_level(&flat, step)
        } else {
            sample_level(&l, step)
        }
    };
    let mut d = r + f;
    if f > 1e-9 {
        let l = offset_loops(pocket, d);
        if !l.is_empty() {
            levels.push(rough(l));
        } else {
            d = r;
        }
    }
    loop {
        let l = offset_loops(pocket, d + s);
        if l.is_empty() {
            if s > r {
                let l = offset_loops(pocket, d + s / 2.0);
                if !l.is_empty() {
                    levels.push(rough(l));
                }
            }
            break;
        }
        levels.push(rough(l));
        d += s;
    }
    let mut max_gap: f64 = 0.0;
    for w in levels.windows(2) {
        max_gap = max_gap.max(level_gap(&w[0], &w[1]));
    }
    // link innermost → outermost
    let mut points: Vec<DVec2> = Vec::new();
    let mut finish_start = 0;
    for (k, level) in levels.iter().enumerate().rev() {
        let mut remaining: Vec<&Vec<DVec2>> = level.iter().collect();
        while !remaining.is_empty() {
            // next loop: nearest to the current point
            let j = match points.last() {
                None => 0,
                Some(&cur) => {
                    let mut best = (f64::INFINITY, 0);
                    for (j, lp) in remaining.iter().enumerate() {
                        let dmin = lp
                            .iter()
                            .map(|p| p.distance_squared(cur))
                            .fold(f64::INFINITY, f64::min);
                        if dmin < best.0 {
                            best = (dmin, j);
                        }
                    }
                    best.1
                }
            };
            let lp = remaining.remove(j);
            if k == 0 && finish_start == 0 {
                finish_start = points.len();
            }
            append_loop_from_nearest(&mut points, lp);
        }
    }
    Ok(PocketPath {
        method: Method::Offset,
        points,
        finish_start,
        max_gap,
        contours: levels.iter().flatten().cloned().collect(),
        center: None,
        fallback_reason: None,
        choice: None,
        boundary: levels[0].first().cloned().unwrap_or_default(),
    })
}
