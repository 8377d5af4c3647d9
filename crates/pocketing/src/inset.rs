//! The inward offset of a region's loops, robust to sections of fillets.
//!
//! A region cut through a filleted corner has its fillet as hundreds of
//! straight pieces, some a few micrometres long and nearly collinear.
//! `cavalier_contours` offsets such loops into pieces of zero area (or
//! asserts, in debug builds), and a pocket 58 mm wide is taken for one no
//! tool fits. Where that happens the loops are simplified within `t`
//! (Douglas–Peucker over the straight runs; arcs are kept) and offset by
//! `d + t`: the simplified boundary lies within `t` of the true one, so
//! the result is still at least `d` from it, and gives up only `t`.

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};

/// How far the loops may be simplified, in turn, when the plain offset
/// fails, mm: each well below the verification's tolerance.
pub const SIMPLIFY: [f64; 3] = [1e-4, 1e-3, 1e-2];

/// `shape.parallel_offset(d)` of `loops` (outer counter-clockwise, islands
/// clockwise), or, where it fails (a panic, a loop of no area, nothing at
/// all), the offset by `d + t` of the loops simplified within `t`, for the
/// first `t` of [`SIMPLIFY`] that gives a result. An empty shape when none
/// does: the region has no point `d` from its boundary.
pub fn inset(loops: &[Polyline<f64>], d: f64) -> Shape<f64> {
    let attempt = |loops: Vec<Polyline<f64>>, d: f64| -> Option<Shape<f64>> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            Shape::from_plines(loops).parallel_offset(d, &ShapeOffsetOptions::default())
        }))
        .ok()
    };
    let plain = attempt(loops.to_vec(), d);
    if let Some(s) = plain.as_ref().filter(|s| sound(s)) {
        return s.clone();
    }
    for t in SIMPLIFY {
        let simple: Vec<Polyline<f64>> = loops.iter().map(|l| simplified(l, t)).collect();
        if let Some(s) = attempt(simple, d + t).filter(sound) {
            return s;
        }
    }
    Shape::empty()
}

/// A result to keep: some loop, and none without area (the pieces a failed
/// join leaves).
pub fn sound(s: &Shape<f64>) -> bool {
    let all = || s.ccw_plines.iter().chain(&s.cw_plines);
    all().next().is_some() && all().all(|p| p.polyline.area().abs() > 1e-12)
}

/// `p` with the vertices of its straight runs that lie within `t` of the
/// chord of their run dropped (Douglas–Peucker); arcs and their ends kept.
pub fn simplified(p: &Polyline<f64>, t: f64) -> Polyline<f64> {
    let n = p.vertex_count();
    if n < 4 || !p.is_closed() {
        return p.clone();
    }
    let v = |i: usize| p.at(i % n);
    // Anchors: both ends of every arc; else the first vertex and the one
    // farthest from it.
    let mut keep = vec![false; n];
    for i in 0..n {
        if v(i).bulge != 0.0 {
            keep[i] = true;
            keep[(i + 1) % n] = true;
        }
    }
    if !keep.iter().any(|k| *k) {
        let far = (1..n)
            .max_by(|&a, &b| {
                let d = |i: usize| (v(i).x - v(0).x).hypot(v(i).y - v(0).y);
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(n / 2);
        keep[0] = true;
        keep[far] = true;
    }
    let anchors: Vec<usize> = (0..n).filter(|&i| keep[i]).collect();
    for (k, &a) in anchors.iter().enumerate() {
        let b = anchors[(k + 1) % anchors.len()];
        let b = if b <= a { b + n } else { b };
        if v(a).bulge == 0.0 {
            douglas_peucker(&v, a, b, t, &mut keep, n);
        }
    }
    let mut out = Polyline::new_closed();
    for i in (0..n).filter(|&i| keep[i]) {
        let q = v(i);
        out.add(q.x, q.y, q.bulge);
    }
    if out.vertex_count() < 3 {
        return p.clone();
    }
    out
}

/// Marks in `keep` the vertices strictly between `a` and `b` (indices mod
/// `n`) that the straight run from `a` to `b` needs within `t`.
fn douglas_peucker(
    v: &dyn Fn(usize) -> cavalier_contours::polyline::PlineVertex<f64>,
    a: usize,
    b: usize,
    t: f64,
    keep: &mut [bool],
    n: usize,
) {
    // An explicit stack: runs may hold thousands of vertices.
    let mut stack = vec![(a, b)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (pa, pb) = (v(a), v(b));
        let (dx, dy) = (pb.x - pa.x, pb.y - pa.y);
        let len = dx.hypot(dy);
        let mut worst = (0.0, a);
        for i in a + 1..b {
            let q = v(i);
            // To the chord as a segment, not its line: a vertex beyond
            // its ends is kept.
            let s = if len < 1e-12 {
                0.0
            } else {
                (((q.x - pa.x) * dx + (q.y - pa.y) * dy) / (len * len)).clamp(0.0, 1.0)
            };
            let d = (q.x - pa.x - s * dx).hypot(q.y - pa.y - s * dy);
            if d > worst.0 {
                worst = (d, i);
            }
        }
        if worst.0 > t {
            keep[worst.1 % n] = true;
            stack.push((a, worst.1));
            stack.push((worst.1, b));
        }
    }
}
