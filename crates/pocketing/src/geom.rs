//! Small 2D helpers: sampling cavalier polylines (arcs as bulges) into points,
//! point–segment distances and a uniform-grid segment index for nearest-distance queries.

use cavalier_contours::polyline::{seg_arc_radius_and_center, PlineSource, Polyline};
use glam::DVec2;

/// Sample a closed polyline into points (no repeated end point). Lines keep their end points;
/// arcs are split so that no chord is longer than `max_seg` and no arc step exceeds `max_angle`
/// radians.
pub fn sample_pline(pl: &Polyline<f64>, max_seg: f64, max_angle: f64) -> Vec<DVec2> {
    let mut out = Vec::new();
    let n = pl.vertex_count();
    let seg_count = if pl.is_closed() {
        n
    } else {
        n.saturating_sub(1)
    };
    for i in 0..seg_count {
        let v1 = pl.at(i);
        let v2 = pl.at((i + 1) % n);
        let p1 = DVec2::new(v1.x, v1.y);
        let p2 = DVec2::new(v2.x, v2.y);
        out.push(p1);
        if v1.bulge.abs() < 1e-12 {
            let len = p1.distance(p2);
            let k = (len / max_seg).ceil().max(1.0) as usize;
            for j in 1..k {
                out.push(p1.lerp(p2, j as f64 / k as f64));
            }
        } else {
            let (r, c) = seg_arc_radius_and_center(v1, v2);
            let c = DVec2::new(c.x, c.y);
            let sweep = 4.0 * v1.bulge.atan(); // signed
            let a0 = (p1 - c).to_angle();
            let by_len = (r * sweep.abs() / max_seg).ceil();
            let by_ang = (sweep.abs() / max_angle).ceil();
            let k = by_len.max(by_ang).max(1.0) as usize;
            for j in 1..k {
                let a = a0 + sweep * j as f64 / k as f64;
                out.push(c + r * DVec2::from_angle(a));
            }
        }
    }
    if !pl.is_closed() && n > 0 {
        let v = pl.at(n - 1);
        out.push(DVec2::new(v.x, v.y));
    }
    dedup_closed(out)
}

/// Remove consecutive duplicates (and a duplicated closing point).
pub fn dedup_closed(pts: Vec<DVec2>) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = Vec::with_capacity(pts.len());
    for p in pts {
        if out.last().is_none_or(|q| q.distance_squared(p) > 1e-20) {
            out.push(p);
        }
    }
    while out.len() > 1 && out[0].distance_squared(*out.last().unwrap()) <= 1e-20 {
        out.pop();
    }
    out
}

/// Signed area of a closed point loop (positive = counter-clockwise).
pub fn signed_area(pts: &[DVec2]) -> f64 {
    let n = pts.len();
    let mut a = 0.0;
    for i in 0..n {
        a += pts[i].perp_dot(pts[(i + 1) % n]);
    }
    0.5 * a
}

/// Perimeter of a closed loop.
pub fn perimeter(pts: &[DVec2]) -> f64 {
    let n = pts.len();
    (0..n).map(|i| pts[i].distance(pts[(i + 1) % n])).sum()
}

/// Distance from `p` to segment `a`–`b`.
#[inline]
pub fn dist_point_seg(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    dist2_point_seg(p, a, b).sqrt()
}

/// Squared distance from `p` to segment `a`–`b`.
#[inline]
pub fn dist2_point_seg(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance_squared(a + ab * t)
}

/// Point-in-polygon (even-odd) for a closed loop.
pub fn point_in_loop(p: DVec2, pts: &[DVec2]) -> bool {
    let n = pts.len();
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (pts[i], pts[j]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// A uniform grid over segments for nearest-distance queries.
pub struct SegIndex {
    segs: Vec<(DVec2, DVec2)>,
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// cell c holds `items[start[c]..start[c + 1]]`, segment numbers ascending
    start: Vec<u32>,
    items: Vec<u32>,
}

impl SegIndex {
    /// Index the segments of closed loops (`closed = true`) or open polylines.
    pub fn new(polys: &[&[DVec2]], closed: bool) -> Self {
        let mut segs = Vec::new();
        for pts in polys {
            let n = pts.len();
            if n == 1 {
                segs.push((pts[0], pts[0]));
                continue;
            }
            let m = if closed { n } else { n.saturating_sub(1) };
            for i in 0..m {
                segs.push((pts[i], pts[(i + 1) % n]));
            }
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        let mut total = 0.0;
        for (a, b) in &segs {
            lo = lo.min(a.min(*b));
            hi = hi.max(a.max(*b));
            total += a.distance(*b);
        }
        if segs.is_empty() {
            lo = DVec2::ZERO;
            hi = DVec2::ONE;
        }
        let ext = (hi - lo).max(DVec2::splat(1e-9));
        let avg = if segs.is_empty() {
            1.0
        } else {
            (total / segs.len() as f64).max(1e-9)
        };
        // cells about 2 average segment lengths, at most ~256 per side
        let cell = (avg * 2.0).max(ext.max_element() / 256.0);
        let nx = ((ext.x / cell).floor() as usize + 1).max(1);
        let ny = ((ext.y / cell).floor() as usize + 1).max(1);
        // each segment in every cell its box touches: counted, then filled in segment order
        let boxes: Vec<((usize, usize), (usize, usize))> = segs
            .iter()
            .map(|(a, b)| {
                (
                    Self::cell_of(lo, cell, nx, ny, a.min(*b)),
                    Self::cell_of(lo, cell, nx, ny, a.max(*b)),
                )
            })
            .collect();
        let mut start = vec![0u32; nx * ny + 1];
        for &((i0, j0), (i1, j1)) in &boxes {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    start[j * nx + i + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            start[c + 1] += start[c];
        }
        let mut fill: Vec<u32> = start[..nx * ny].to_vec();
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (k, &((i0, j0), (i1, j1))) in boxes.iter().enumerate() {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let f = &mut fill[j * nx + i];
                    items[*f as usize] = k as u32;
                    *f += 1;
                }
            }
        }
        SegIndex {
            segs,
            origin: lo,
            cell,
            nx,
            ny,
            start,
            items,
        }
    }

    fn cell_of(lo: DVec2, cell: f64, nx: usize, ny: usize, p: DVec2) -> (usize, usize) {
        let q = (p - lo) / cell;
        (
            (q.x.floor().max(0.0) as usize).min(nx - 1),
            (q.y.floor().max(0.0) as usize).min(ny - 1),
        )
    }

    /// Distance from `p` to the nearest indexed segment (infinite if empty).
    pub fn nearest(&self, p: DVec2) -> f64 {
        self.nearest_above(p, f64::NEG_INFINITY)
    }

    /// Whether the nearest indexed segment is within `bound` of `p`: exactly
    /// `self.nearest(p) <= bound`, but the search stops at the first segment within `bound`.
    pub fn within(&self, p: DVec2, bound: f64) -> bool {
        self.search(p, bound, true).0 <= bound
    }

    /// [`SegIndex::within`] for a run of nearby points: `hint` (start with [`NO_HINT`]) is the
    /// segment that answered the previous point and is tried first. The same answer: the
    /// search returns the least distance to any segment (the property test against brute
    /// force), so one segment within `bound` means the nearest is.
    pub fn within_hinted(&self, p: DVec2, bound: f64, hint: &mut u32) -> bool {
        if let Some(&(a, b)) = self.segs.get(*hint as usize) {
            if dist_point_seg(p, a, b) <= bound {
                return true;
            }
        }
        let (d, k) = self.search(p, bound, true);
        *hint = k;
        d <= bound
    }

    /// [`SegIndex::nearest_above`] with a hint as in [`SegIndex::within_hinted`]: when the
    /// hinted segment is within `floor`, so is the nearest, and its distance is returned.
    pub fn nearest_above_hinted(&self, p: DVec2, floor: f64, hint: &mut u32) -> f64 {
        if let Some(&(a, b)) = self.segs.get(*hint as usize) {
            let d = dist_point_seg(p, a, b);
            if d <= floor {
                return d;
            }
        }
        let (d, k) = self.search(p, floor, false);
        *hint = k;
        d
    }

    /// [`SegIndex::nearest`] where it exceeds `floor`; otherwise some distance ≤ `floor` (the
    /// search stops at the first segment within `floor`). So `g.max(nearest_above(p, g))`
    /// equals `g.max(nearest(p))` exactly, which lets a maximum over many points skip most of
    /// each search. The cells are visited in the same order as the full search and the same
    /// stopping rule ends it, so a result above `floor` is the full search's, bit for bit.
    pub fn nearest_above(&self, p: DVec2, floor: f64) -> f64 {
        self.search(p, floor, false).0
    }

    /// [`SegIndex::nearest_above`] and the segment it measured ([`NO_HINT`] if none). With
    /// `only_within`, only whether the result is ≤ `floor` matters: the search also stops once
    /// every segment not yet measured is farther than `floor` (then the result is > `floor`,
    /// though maybe not the least distance).
    fn search(&self, p: DVec2, floor: f64, only_within: bool) -> (f64, u32) {
        if self.segs.is_empty() {
            return (f64::INFINITY, NO_HINT);
        }
        let (ci, cj) = Self::cell_of(self.origin, self.cell, self.nx, self.ny, p);
        let mut best = f64::INFINITY;
        // the squared distance `best` is the root of: a segment with d² ≥ best2 has
        // d = √d² ≥ best (the rounded root is monotone), so its root is not needed
        let mut best2 = f64::INFINITY;
        let mut best_k = NO_HINT;
        let maxr = self.nx.max(self.ny);
        // `true` once `best` ≤ `floor`
        let mut visit = |i: isize, j: isize, best: &mut f64| -> bool {
            if i < 0 || j < 0 || i >= self.nx as isize || j >= self.ny as isize {
                return false;
            }
            let c = j as usize * self.nx + i as usize;
            for &k in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                let (a, b) = self.segs[k as usize];
                let d2 = dist2_point_seg(p, a, b);
                if d2 < best2 {
                    // dist_point_seg(p, a, b), as the full search computes it
                    let d = d2.sqrt();
                    if d < *best {
                        *best = d;
                        best2 = d2;
                        best_k = k;
                        if d <= floor {
                            return true;
                        }
                    }
                }
            }
            false
        };
        // every segment is at least `outside` away when p lies outside the grid box
        let outside = {
            let q = p - self.origin;
            let ext = DVec2::new(self.nx as f64, self.ny as f64) * self.cell;
            let dx = (-q.x).max(q.x - ext.x).max(0.0);
            let dy = (-q.y).max(q.y - ext.y).max(0.0);
            dx.max(dy)
        };
        for r in 0..=maxr {
            let (ci, cj, ri) = (ci as isize, cj as isize, r as isize);
            // The ring of cells at Chebyshev distance r only (the square's
            // inside was visited by the smaller rings).
            if r == 0 {
                if visit(ci, cj, &mut best) {
                    return (best, best_k);
                }
            } else {
                let (nx, ny) = (self.nx as isize, self.ny as isize);
                for i in (ci - ri).max(0)..=(ci + ri).min(nx - 1) {
                    if visit(i, cj - ri, &mut best) || visit(i, cj + ri, &mut best) {
                        return (best, best_k);
                    }
                }
                for j in (cj - ri + 1).max(0)..(cj + ri).min(ny) {
                    if visit(ci - ri, j, &mut best) || visit(ci + ri, j, &mut best) {
                        return (best, best_k);
                    }
                }
            }
            // every cell not yet visited is at least r*cell away from p
            let unvisited = (r as f64 * self.cell).max(outside);
            if best.is_finite() && best <= unvisited {
                break;
            }
            if only_within && unvisited > floor {
                break;
            }
        }
        (best, best_k)
    }
}

/// The hint of a first query ([`SegIndex::within_hinted`]).
pub const NO_HINT: u32 = u32::MAX;

/// Directed Hausdorff distance: max over points of `a` of the distance to the polyline(s) `b`.
pub fn directed_gap(a: &[DVec2], b: &SegIndex) -> f64 {
    // g.max(nearest_above(p, g)) == g.max(nearest(p)): the same fold as over `nearest`
    let mut hint = NO_HINT;
    a.iter().fold(0.0, |g: f64, &p| {
        g.max(b.nearest_above_hinted(p, g, &mut hint))
    })
}

/// Whether every point of `a` is within `bound` of the polyline(s) `b`: exactly
/// `directed_gap(a, b) <= bound`, stopping at the first point that is not.
pub fn directed_within(a: &[DVec2], b: &SegIndex, bound: f64) -> bool {
    // the fold starts at 0.0
    let mut hint = NO_HINT;
    0.0 <= bound && a.iter().all(|&p| b.within_hinted(p, bound, &mut hint))
}

/// Symmetric Hausdorff distance between two closed loops (a single point is a degenerate loop).
pub fn loop_gap(a: &[DVec2], b: &[DVec2]) -> f64 {
    let ia = SegIndex::new(&[a], true);
    let ib = SegIndex::new(&[b], true);
    directed_gap(a, &ib).max(directed_gap(b, &ia))
}

/// Whether `loop_gap(a, b) <= bound`, exactly; `ib` indexes `b` (closed). `b`'s points are
/// tested against `a`'s index only when all of `a`'s are within `bound`.
pub fn loop_within(a: &[DVec2], b: &[DVec2], ib: &SegIndex, bound: f64) -> bool {
    directed_within(a, ib, bound) && directed_within(b, &SegIndex::new(&[a], true), bound)
}

/// Convert sampled points to a cavalier polyline (lines only).
pub fn pline_from_points(pts: &[DVec2], closed: bool) -> Polyline<f64> {
    use cavalier_contours::polyline::{PlineCreation, PlineSourceMut};
    let mut pl = Polyline::with_capacity(pts.len(), closed);
    for p in pts {
        pl.add(p.x, p.y, 0.0);
    }
    pl
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The grid's ring search finds the same distance as trying every
        /// segment, for points inside and outside the indexed box.
        #[test]
        fn nearest_equals_brute_force(
            pts in prop::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 2..40),
            queries in prop::collection::vec((-120.0f64..120.0, -120.0f64..120.0), 1..20),
            closed in any::<bool>(),
        ) {
            let poly: Vec<DVec2> = pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            let idx = SegIndex::new(&[&poly], closed);
            let n = poly.len();
            let m = if closed { n } else { n - 1 };
            for &(x, y) in &queries {
                let p = DVec2::new(x, y);
                let brute = (0..m)
                    .map(|i| dist_point_seg(p, poly[i], poly[(i + 1) % n]))
                    .fold(f64::INFINITY, f64::min);
                prop_assert_eq!(idx.nearest(p), brute);
            }
        }

        /// The bounded and hinted queries answer as brute force does: `within` is
        /// `brute <= bound`, `nearest_above` is the brute-force distance where that exceeds the
        /// floor and at most the floor otherwise (with or without a hint, whatever segment the
        /// hint names), and the directed gaps built on them equal the brute-force fold.
        #[test]
        fn bounded_queries_equal_brute_force(
            pts in prop::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 2..40),
            queries in prop::collection::vec((-120.0f64..120.0, -120.0f64..120.0), 1..20),
            walk in prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 1..40),
            bound in 0.0f64..60.0,
            start_hint in 0u32..50,
            closed in any::<bool>(),
        ) {
            let poly: Vec<DVec2> = pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            let idx = SegIndex::new(&[&poly], closed);
            let n = poly.len();
            let m = if closed { n } else { n - 1 };
            let brute = |p: DVec2| {
                (0..m)
                    .map(|i| dist_point_seg(p, poly[i], poly[(i + 1) % n]))
                    .fold(f64::INFINITY, f64::min)
            };
            // scattered points, then a walk of nearby points (as along a loop)
            let mut all: Vec<DVec2> = queries.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            let mut q = all[0];
            for &(dx, dy) in &walk {
                q += DVec2::new(dx, dy);
                all.push(q);
            }
            let (mut h1, mut h2) = (start_hint, start_hint);
            for &p in &all {
                let b = brute(p);
                prop_assert_eq!(idx.within(p, bound), b <= bound);
                prop_assert_eq!(idx.within_hinted(p, bound, &mut h1), b <= bound);
                for floor in [f64::NEG_INFINITY, 0.0, bound] {
                    let x = idx.nearest_above(p, floor);
                    let y = idx.nearest_above_hinted(p, floor, &mut h2);
                    if b > floor {
                        prop_assert_eq!(x, b);
                        prop_assert_eq!(y, b);
                    } else {
                        prop_assert!(x <= floor && y <= floor);
                    }
                }
            }
            let gap = all.iter().map(|&p| brute(p)).fold(0.0, f64::max);
            prop_assert_eq!(directed_gap(&all, &idx), gap);
            prop_assert_eq!(directed_within(&all, &idx, bound), gap <= bound);
            if closed {
                let ia = SegIndex::new(&[&all], true);
                let ib = SegIndex::new(&[&poly], true);
                let full = directed_gap(&all, &ib).max(directed_gap(&poly, &ia));
                prop_assert_eq!(loop_gap(&all, &poly), full);
                prop_assert_eq!(loop_within(&all, &poly, &ib, bound), full <= bound);
            }
        }
    }
}
