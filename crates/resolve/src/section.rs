//! Planar sections of the part's mesh and the 2D booleans of the slabs.
//!
//! The part is sliced by horizontal planes (in the set-up frame) through
//! its triangle mesh. Intersection points on a mesh edge are computed from
//! the edge's endpoints in a canonical order, so the two triangles sharing
//! an edge give bit-identical points and the segments chain into closed
//! loops without tolerances. Booleans are `i_overlay`'s (integer-snapped,
//! robust); see docs/ARCHITECTURE.md.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use i_overlay::mesh::float::outline::offset::OutlineOffset;
use i_overlay::mesh::float::style::OutlineStyle;

/// A set of polygons with holes: each shape is an outer contour
/// (counter-clockwise) followed by its holes (clockwise).
pub type Shapes = Vec<Vec<Vec<[f64; 2]>>>;

/// A triangle mesh in the set-up frame (z = up).
pub struct LocalMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl LocalMesh {
    /// The closed loops where the plane `z` cuts the mesh, oriented with the
    /// material on their left (outer boundaries counter-clockwise). A loop
    /// that does not close (a mesh that is not watertight) is closed by a
    /// straight gap and counted in the returned number.
    pub fn section(&self, z: f64) -> (Vec<Vec<[f64; 2]>>, usize) {
        // Segment start → end, keyed by the bits of the points.
        let mut next: BTreeMap<[u64; 2], [f64; 2]> = BTreeMap::new();
        let key = |p: [f64; 2]| [p[0].to_bits(), p[1].to_bits()];
        for t in &self.triangles {
            let v = t.map(|i| self.positions[i as usize]);
            // Strictly below vs on-or-above: no vertex lies on the plane.
            let above = v.map(|p| p.z >= z);
            let n_above = above.iter().filter(|a| **a).count();
            if n_above == 0 || n_above == 3 {
                continue;
            }
            let mut pts = Vec::with_capacity(2);
            for i in 0..3 {
                let j = (i + 1) % 3;
                if above[i] != above[j] {
                    pts.push(cut_edge(v[i], v[j], z));
                }
            }
            let (a, b) = (pts[0], pts[1]);
            // Outward normal of the triangle (counter-clockwise from outside);
            // the section runs along up × n so the material is on its left.
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            let dir = DVec3::Z.cross(n);
            let ab = DVec2::new(b[0] - a[0], b[1] - a[1]);
            let (a, b) = if ab.x * dir.x + ab.y * dir.y >= 0.0 {
                (a, b)
            } else {
                (b, a)
            };
            if a == b {
                continue;
            }
            next.insert(key(a), b);
        }
        let mut loops = Vec::new();
        let mut gaps = 0;
        while let Some((&k0, &first)) = next.iter().next() {
            next.remove(&k0);
            let start = [f64::from_bits(k0[0]), f64::from_bits(k0[1])];
            let mut lp = vec![start];
            let mut cur = first;
            loop {
                if key(cur) == k0 {
                    break;
                }
                lp.push(cur);
                match next.remove(&key(cur)) {
                    Some(n) => cur = n,
                    None => {
                        gaps += 1;
                        break;
                    }
                }
            }
            if lp.len() >= 3 {
                loops.push(lp);
            }
        }
        (loops, gaps)
    }
}

/// The point where the plane `z` cuts the edge `p`–`q`, computed from the
/// endpoints in a fixed order so both triangles of the edge agree exactly.
fn cut_edge(p: DVec3, q: DVec3, z: f64) -> [f64; 2] {
    let (a, b) = if (p.x, p.y, p.z) <= (q.x, q.y, q.z) {
        (p, q)
    } else {
        (q, p)
    };
    let t = (z - a.z) / (b.z - a.z);
    let r = a + (b - a) * t;
    [r.x, r.y]
}

/// The region inside `contours` by the non-zero rule (the section's
/// material), normalised into shapes.
pub fn fill(contours: &[Vec<[f64; 2]>]) -> Shapes {
    if contours.is_empty() {
        return Vec::new();
    }
    let empty: Vec<Vec<[f64; 2]>> = Vec::new();
    contours.overlay_as::<i64>(&empty, OverlayRule::Subject, FillRule::NonZero)
}

pub fn difference(a: &Shapes, b: &Shapes) -> Shapes {
    if a.is_empty() {
        return Vec::new();
    }
    if b.is_empty() {
        return a.clone();
    }
    a.overlay_as::<i64>(b, OverlayRule::Difference, FillRule::NonZero)
}

pub fn intersection(a: &Shapes, b: &Shapes) -> Shapes {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    a.overlay_as::<i64>(b, OverlayRule::Intersect, FillRule::NonZero)
}

pub fn union(a: &Shapes, b: &Shapes) -> Shapes {
    if a.is_empty() {
        return b.clone();
    }
    if b.is_empty() {
        return a.clone();
    }
    a.overlay_as::<i64>(b, OverlayRule::Union, FillRule::NonZero)
}

/// `s` with each vertex that lies within `tol` of a vertex of `to` moved
/// onto it: shapes from different overlays that share an edge then share
/// it bit for bit, and their union has no crack along it.
pub fn snap_to(s: &Shapes, to: &Shapes, tol: f64) -> Shapes {
    let mut pts: Vec<[f64; 2]> = to.iter().flatten().flatten().copied().collect();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let snap = |p: [f64; 2]| {
        let from = pts.partition_point(|q| q[0] < p[0] - tol);
        pts[from..]
            .iter()
            .take_while(|q| q[0] <= p[0] + tol)
            .filter(|q| (q[0] - p[0]).hypot(q[1] - p[1]) <= tol)
            .min_by(|a, b| {
                let d = |q: &&[f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]);
                d(a).total_cmp(&d(b))
            })
            .copied()
            .unwrap_or(p)
    };
    s.iter()
        .map(|shape| {
            shape
                .iter()
                .map(|c| c.iter().map(|&p| snap(p)).collect())
                .collect()
        })
        .collect()
}

/// The region grown (`d > 0`) or shrunk (`d < 0`) by `|d|`.
pub fn offset(s: &Shapes, d: f64) -> Shapes {
    if s.is_empty() {
        return Vec::new();
    }
    s.outline(&OutlineStyle::new(d))
}

/// Signed area of a contour (positive counter-clockwise).
pub fn contour_area(c: &[[f64; 2]]) -> f64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        * 0.5
}

/// Area of one shape (outer minus holes), whatever the contours' orientation.
pub fn shape_area(s: &[Vec<[f64; 2]>]) -> f64 {
    let mut it = s.iter();
    let outer = it.next().map_or(0.0, |c| contour_area(c).abs());
    outer - it.map(|c| contour_area(c).abs()).sum::<f64>()
}

pub fn area(s: &Shapes) -> f64 {
    s.iter().map(|x| shape_area(x)).sum()
}

/// Puts a shape's outer contour counter-clockwise and its holes clockwise.
pub fn normalise(mut s: Vec<Vec<[f64; 2]>>) -> Vec<Vec<[f64; 2]>> {
    for (i, c) in s.iter_mut().enumerate() {
        let ccw = contour_area(c) > 0.0;
        if (i == 0) != ccw {
            c.reverse();
        }
    }
    s
}

/// Whether `p` lies inside the region (even-odd over all contours).
pub fn contains(s: &Shapes, p: [f64; 2]) -> bool {
    let mut inside = false;
    for shape in s {
        for c in shape {
            let n = c.len();
            for i in 0..n {
                let (a, b) = (c[i], c[(i + 1) % n]);
                if (a[1] > p[1]) != (b[1] > p[1]) {
                    let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                    if x > p[0] {
                        inside = !inside;
                    }
                }
            }
        }
    }
    inside
}

/// The shapes of a region as one-shape regions (each connected piece).
pub fn pieces(s: Shapes) -> Vec<Shapes> {
    s.into_iter().map(|x| vec![normalise(x)]).collect()
}

/// An axis-aligned rectangle as a region.
pub fn rect(lo: [f64; 2], hi: [f64; 2]) -> Shapes {
    vec![vec![vec![
        [lo[0], lo[1]],
        [hi[0], lo[1]],
        [hi[0], hi[1]],
        [lo[0], hi[1]],
    ]]]
}

/// Same region up to tolerance (used to merge identical slab pieces): the
/// symmetric difference's area is negligible.
pub fn same_region(a: &Shapes, b: &Shapes, tol_area: f64) -> bool {
    let (aa, ab) = (area(a), area(b));
    if (aa - ab).abs() > tol_area {
        return false;
    }
    area(&difference(a, b)) + area(&difference(b, a)) <= tol_area
}

/// A point strictly inside a one-shape region: the middle of the longest
/// chord of a horizontal line through the shape's middle height band.
pub fn interior_point(s: &[Vec<[f64; 2]>]) -> Option<[f64; 2]> {
    let outer = s.first()?;
    let (ylo, yhi) = outer
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p[1]), h.max(p[1]))
        });
    let mut best: Option<([f64; 2], f64)> = None;
    for k in 1..8 {
        let y = ylo + (yhi - ylo) * (k as f64 / 8.0 + 0.013);
        let mut xs: Vec<f64> = Vec::new();
        for c in s {
            let n = c.len();
            for i in 0..n {
                let (a, b) = (c[i], c[(i + 1) % n]);
                if (a[1] > y) != (b[1] > y) {
                    xs.push(a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        for w in xs.chunks(2) {
            if let [x0, x1] = w {
                let len = x1 - x0;
                if best.is_none_or(|(_, l)| len > l) {
                    best = Some(([0.5 * (x0 + x1), y], len));
                }
            }
        }
    }
    best.map(|(p, _)| p)
}
