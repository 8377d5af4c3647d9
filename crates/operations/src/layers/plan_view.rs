//! Small plan-view (2D) helpers shared by several of the band's steps:
//! distances between segments and to the product, the overlap of two sets
//! of loops, centroids and areas of sampled contours.

use glam::DVec2;

use crate::geom::Edge2;

/// The least distance between segments `ab` and `cd` (0 where they cross).
pub(super) fn seg_seg_distance(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    let cross = |o: DVec2, p: DVec2, q: DVec2| (p - o).perp_dot(q - o);
    let (d1, d2, d3, d4) = (
        cross(c, d, a),
        cross(c, d, b),
        cross(a, b, c),
        cross(a, b, d),
    );
    if (d1 > 0.0) != (d2 > 0.0) && (d3 > 0.0) != (d4 > 0.0) {
        return 0.0;
    }
    [
        crate::geom::dist_point_seg(a, c, d),
        crate::geom::dist_point_seg(b, c, d),
        crate::geom::dist_point_seg(c, a, b),
        crate::geom::dist_point_seg(d, a, b),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// The least distance from `p` to any product edge.
pub(super) fn product_distance(p: DVec2, product: &[Edge2]) -> f64 {
    product
        .iter()
        .map(|e| e.distance(p))
        .fold(f64::INFINITY, f64::min)
}

/// The part of one set of loops (outer loops and holes, even-odd) inside
/// another.
pub(super) fn intersect_polys(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> Vec<Vec<DVec2>> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let paths = |p: &[Vec<DVec2>]| -> Vec<Vec<[f64; 2]>> {
        p.iter()
            .map(|l| l.iter().map(|q| [q.x, q.y]).collect())
            .collect()
    };
    let out: crate::free::Shapes =
        paths(a).overlay_as::<i64>(&paths(b), OverlayRule::Intersect, FillRule::EvenOdd);
    out.into_iter()
        .flatten()
        .map(|l| l.into_iter().map(|q| DVec2::new(q[0], q[1])).collect())
        .collect()
}

/// The mean of the polygons' vertices.
pub(super) fn centroid(polys: &[Vec<DVec2>]) -> DVec2 {
    let mut s = DVec2::ZERO;
    let mut n = 0.0;
    for p in polys {
        for q in p {
            s += *q;
            n += 1.0;
        }
    }
    if n > 0.0 {
        s / n
    } else {
        s
    }
}

/// Signed-area sum of sampled contours (outer loops ccw, holes cw).
pub(super) fn contours_area(cs: &[Vec<[f64; 2]>]) -> f64 {
    cs.iter()
        .map(|c| {
            let n = c.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (c[i], c[(i + 1) % n]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
                * 0.5
        })
        .sum()
}
