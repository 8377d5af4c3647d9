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
    cells: Vec<Vec<u32>>,
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
        let mut cells = vec![Vec::new(); nx * ny];
        for (k, (a, b)) in segs.iter().enumerate() {
            let (i0, j0) = Self::cell_of(lo, cell, nx, ny, a.min(*b));
            let (i1, j1) = Self::cell_of(lo, cell, nx, ny, a.max(*b));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    cells[j * nx + i].push(k as u32);
                }
            }
        }
        SegIndex {
            segs,
            origin: lo,
            cell,
            nx,
            ny,
            cells,
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
        if self.segs.is_empty() {
            return f64::INFINITY;
        }
        let (ci, cj) = Self::cell_of(self.origin, self.cell, self.nx, self.ny, p);
        // distance from p to the grid box, to start rings sensibly when p lies outside
        let mut best = f64::INFINITY;
        let maxr = self.nx.max(self.ny);
        let visit = |i: isize, j: isize, best: &mut f64| {
            if i < 0 || j < 0 || i >= self.nx as isize || j >= self.ny as isize {
                return;
            }
            for &k in &self.cells[j as usize * self.nx + i as usize] {
                let (a, b) = self.segs[k as usize];
                let d = dist_point_seg(p, a, b);
                if d < *best {
                    *best = d;
                }
            }
        };
        for r in 0..=maxr {
            let (ci, cj, ri) = (ci as isize, cj as isize, r as isize);
            // The ring of cells at Chebyshev distance r only (the square's
            // inside was visited by the smaller rings).
            if r == 0 {
                visit(ci, cj, &mut best);
            } else {
                let (nx, ny) = (self.nx as isize, self.ny as isize);
                for i in (ci - ri).max(0)..=(ci + ri).min(nx - 1) {
                    visit(i, cj - ri, &mut best);
                    visit(i, cj + ri, &mut best);
                }
                for j in (cj - ri + 1).max(0)..(cj + ri).min(ny) {
                    visit(ci - ri, j, &mut best);
                    visit(ci + ri, j, &mut best);
                }
            }
            // every cell not yet visited is at least r*cell away from p, and every segment is at
            // least `outside` away when p lies outside the grid box
            let outside = {
                let q = p - self.origin;
                let ext = DVec2::new(self.nx as f64, self.ny as f64) * self.cell;
                let dx = (-q.x).max(q.x - ext.x).max(0.0);
                let dy = (-q.y).max(q.y - ext.y).max(0.0);
                dx.max(dy)
            };
            if best.is_finite() && best <= (r as f64 * self.cell).max(outside) {
                break;
            }
        }
        best
    }
}

/// Directed Hausdorff distance: max over points of `a` of the distance to the polyline(s) `b`.
pub fn directed_gap(a: &[DVec2], b: &SegIndex) -> f64 {
    a.iter().map(|&p| b.nearest(p)).fold(0.0, f64::max)
}

/// Symmetric Hausdorff distance between two closed loops (a single point is a degenerate loop).
pub fn loop_gap(a: &[DVec2], b: &[DVec2]) -> f64 {
    let ia = SegIndex::new(&[a], true);
    let ib = SegIndex::new(&[b], true);
    directed_gap(a, &ib).max(directed_gap(b, &ia))
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
    }
}
