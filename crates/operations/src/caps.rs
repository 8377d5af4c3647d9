//! Sloped product faces swept by the tool's profile, exactly at the ends of
//! their edges.
//!
//! One shift per product edge (`layers::slope_shifts`) is exact along the
//! edge but conservative around its ends, where a tool beside a thin flange
//! pivots about the edge's end and its lower, narrower sections meet the
//! face where it reaches furthest in. Here the product at every height of
//! the corner radius is kept its section radius away: between two sampled
//! heights the product's edges move linearly and the section radius grows
//! along a chord of the torus, so the convex hull of the four end discs
//! (radius raised by the chord's sagitta) holds every disc between. The
//! hulls are exact arcs and tangent lines, so the tool-centre region keeps
//! true arcs for its offsets.

use std::f64::consts::{PI, TAU};

use cavalier_contours::polyline::{
    BooleanOp, BooleanResultInfo, PlineSource, PlineSourceMut, PlineVertex, Polyline,
};
use glam::DVec2;

use crate::geom::{oriented, Area};

/// The convex hull of discs `(centre, radius)` as a closed
/// counter-clockwise polyline of arcs on the discs and their common outer
/// tangents. `None` for no disc, a radius that is not positive, or a hull
/// the wrap cannot close (numerically degenerate input).
pub(crate) fn disc_hull(discs: &[(DVec2, f64)]) -> Option<Polyline<f64>> {
    if discs.is_empty()
        || discs
            .iter()
            .any(|(c, r)| !r.is_finite() || *r <= 0.0 || !c.is_finite())
    {
        return None;
    }
    // Discs inside another one add nothing (of equal ones the first stays).
    let ds: Vec<(DVec2, f64)> = discs
        .iter()
        .enumerate()
        .filter(|&(i, &(c, r))| {
            !discs.iter().enumerate().any(|(j, &(c2, r2))| {
                let d = c.distance(c2);
                j != i && (d + r < r2 - 1e-12 || (d + (r - r2).abs() <= 1e-12 && j < i))
            })
        })
        .map(|(_, d)| *d)
        .collect();
    let mut out: Vec<(DVec2, f64)> = Vec::new();
    let on = |k: usize, beta: f64| ds[k].0 + DVec2::from_angle(beta) * ds[k].1;
    // A vertex at `p` starting a segment of `bulge`; a vertex on top of the
    // previous one replaces it (a zero-length segment).
    fn push(out: &mut Vec<(DVec2, f64)>, p: DVec2, bulge: f64) {
        if let Some(last) = out.last_mut() {
            if last.0.distance_squared(p) < 1e-20 {
                last.1 = bulge;
                return;
            }
        }
        out.push((p, bulge));
    }
    // An arc on disc k from outward normal angle b0, ccw by `sweep`.
    let arc = |out: &mut Vec<(DVec2, f64)>, k: usize, b0: f64, sweep: f64| {
        if sweep <= 1e-12 {
            return;
        }
        let n = if sweep > PI - 1e-9 { 2 } else { 1 };
        let part = sweep / n as f64;
        for m in 0..n {
            push(out, on(k, b0 + part * m as f64), (part / 4.0).tan());
        }
    };
    let start = (0..ds.len())
        .min_by(|&a, &b| {
            (ds[a].0.x - ds[a].1)
                .total_cmp(&(ds[b].0.x - ds[b].1))
                .then(ds[a].0.y.total_cmp(&ds[b].0.y))
        })
        .expect("not empty");
    let (mut i, mut beta, mut turned) = (start, PI, 0.0);
    for _ in 0..4 * ds.len() + 4 {
        // The next disc: the outer tangent from disc i the least turn ccw.
        let mut best: Option<(usize, f64, f64, f64)> = None; // (j, turn, beta_j, length)
        for (j, &(cj, rj)) in ds.iter().enumerate() {
            if j == i {
                continue;
            }
            let (ci, ri) = ds[i];
            let d = cj - ci;
            let l = d.length();
            if l <= (ri - rj).abs() + 1e-12 {
                continue;
            }
            let bj = d.to_angle() - ((ri - rj) / l).clamp(-1.0, 1.0).acos();
            let mut turn = (bj - beta).rem_euclid(TAU);
            if turn > TAU - 1e-9 {
                turn = 0.0;
            }
            let better = match best {
                None => true,
                Some((_, t, _, bl)) => turn < t - 1e-12 || (turn <= t + 1e-12 && l > bl),
            };
            if better {
                best = Some((j, turn, beta + turn, l));
            }
        }
        match best {
            // Back at the first disc: close when the wrap ends before the
            // next tangent.
            Some((j, turn, bj, _))
                if (i != start && turned + turn <= TAU + 1e-9)
                    || (i == start && turned + turn < TAU - 1e-9) =>
            {
                arc(&mut out, i, beta, turn);
                push(&mut out, on(i, bj), 0.0);
                turned += turn;
                beta = bj;
                i = j;
            }
            _ => {
                // Closing: back round the first disc to where the wrap began.
                if i != start {
                    return None;
                }
                arc(&mut out, i, beta, TAU - turned);
                if out.len() >= 2 && out[0].0.distance_squared(out[out.len() - 1].0) < 1e-20 {
                    out.pop();
                }
                let mut pl = Polyline::new_closed();
                for (p, b) in &out {
                    pl.add_vertex(PlineVertex::new(p.x, p.y, *b));
                }
                return (pl.vertex_count() >= 2).then_some(pl);
            }
        }
    }
    None
}

fn boxes_meet(a: &Polyline<f64>, b: &Polyline<f64>) -> bool {
    match (a.extents(), b.extents()) {
        (Some(p), Some(q)) => {
            p.min_x <= q.max_x && q.min_x <= p.max_x && p.min_y <= q.max_y && q.min_y <= p.max_y
        }
        _ => false,
    }
}

fn inside(p: &Polyline<f64>, of: &Polyline<f64>) -> bool {
    let v = p.at(0);
    of.winding_number(cavalier_contours::core::math::Vector2::new(v.x, v.y)) != 0
}

/// Distance within which a point counts as on a loop (mm).
const ON: f64 = 1e-6;

/// A loop with its edges and box, for many point tests.
struct Probe<'a> {
    pl: &'a Polyline<f64>,
    edges: Vec<crate::geom::Edge2>,
    lo: DVec2,
    hi: DVec2,
}

impl<'a> Probe<'a> {
    fn new(pl: &'a Polyline<f64>) -> Self {
        let (lo, hi) = pl.extents().map_or((DVec2::ZERO, DVec2::ZERO), |e| {
            (
                DVec2::new(e.min_x - ON, e.min_y - ON),
                DVec2::new(e.max_x + ON, e.max_y + ON),
            )
        });
        Probe {
            pl,
            edges: crate::geom::edges_of_pline(pl),
            lo,
            hi,
        }
    }

    fn in_box(&self, p: DVec2) -> bool {
        p.x >= self.lo.x && p.y >= self.lo.y && p.x <= self.hi.x && p.y <= self.hi.y
    }

    fn on(&self, p: DVec2) -> bool {
        self.in_box(p) && self.edges.iter().any(|e| e.distance(p) < ON)
    }

    /// Inside or on the loop.
    fn covers(&self, p: DVec2) -> bool {
        self.in_box(p)
            && (self
                .pl
                .winding_number(cavalier_contours::core::math::Vector2::new(p.x, p.y))
                != 0
                || self.on(p))
    }

    fn strictly_inside(&self, p: DVec2) -> bool {
        self.covers(p) && !self.on(p)
    }
}

/// Whether `pos` can be `o` less `x`: no larger than `o`, every vertex of
/// `o` outside `x` kept (inside or on a result), and no result vertex
/// strictly inside `x` or outside `o`. The failures this is there for are
/// gross (a region gone, or the cut's outline taken for the region's).
fn plausible(o: &Polyline<f64>, x: &Polyline<f64>, pos: &[Polyline<f64>]) -> bool {
    let area: f64 = pos.iter().map(|p| p.area().abs()).sum();
    if area > o.area().abs() + 1e-9 {
        return false;
    }
    let (po, px) = (Probe::new(o), Probe::new(x));
    let pp: Vec<Probe> = pos.iter().map(Probe::new).collect();
    let vertex = |v: PlineVertex<f64>| DVec2::new(v.x, v.y);
    // Every vertex near the cut, and a sample of the others: a region of
    // thousands of vertices (sections through fillets) met by hundreds of
    // cuts made this check quadratic, and its failures are gross.
    let tested = |pts: Vec<DVec2>| -> Vec<DVec2> {
        let stride = (pts.len() / PLAUSIBLE_SAMPLE).max(1);
        pts.iter()
            .enumerate()
            .filter(|(i, p)| px.in_box(**p) || i % stride == 0)
            .map(|(_, p)| *p)
            .collect()
    };
    // A vertex both loops share is on both: only the others are tested
    // against the whole loop.
    let key = |p: &DVec2| (p.x.to_bits(), p.y.to_bits());
    let of_o: std::collections::HashSet<(u64, u64)> =
        o.iter_vertexes().map(|v| key(&vertex(v))).collect();
    let of_pos: std::collections::HashSet<(u64, u64)> = pos
        .iter()
        .flat_map(|q| q.iter_vertexes())
        .map(|v| key(&vertex(v)))
        .collect();
    let kept = tested(o.iter_vertexes().map(vertex).collect())
        .into_iter()
        .all(|p| of_pos.contains(&key(&p)) || px.covers(p) || pp.iter().any(|q| q.covers(p)));
    kept && tested(
        pos.iter()
            .flat_map(|q| q.iter_vertexes())
            .map(vertex)
            .collect(),
    )
    .into_iter()
    .all(|p| !px.strictly_inside(p) && (of_o.contains(&key(&p)) || po.covers(p)))
}

/// Vertices away from a cut that `plausible` tests, at most about.
const PLAUSIBLE_SAMPLE: usize = 64;

/// `o` less `x` by the polyline boolean, each result checked
/// (`plausible`): the boolean fails now and then where the loops graze
/// each other, so the cut is then grown a hair (the region loses as much)
/// and tried again.
fn checked_not(
    o: &Polyline<f64>,
    x: &Polyline<f64>,
) -> Option<cavalier_contours::polyline::BooleanResult<Polyline<f64>>> {
    use cavalier_contours::polyline::PlineOffsetOptions;
    for grow in [0.0, 1e-4, 1e-3, 4e-3] {
        let x = if grow == 0.0 {
            x.clone()
        } else {
            // Counter-clockwise: a negative offset grows it.
            let mut v = std::panic::catch_unwind(|| {
                x.parallel_offset_opt(-grow, &PlineOffsetOptions::default())
            })
            .ok()?;
            if v.len() != 1 {
                return None;
            }
            v.remove(0)
        };
        let Ok(r) = std::panic::catch_unwind(|| o.boolean(&x, BooleanOp::Not)) else {
            continue;
        };
        match r.result_info {
            BooleanResultInfo::InvalidInput => continue,
            BooleanResultInfo::Disjoint | BooleanResultInfo::Pline2InsidePline1 => return Some(r),
            _ => {}
        }
        let pos: Vec<Polyline<f64>> = r.pos_plines.iter().map(|p| p.pline.clone()).collect();
        if plausible(o, &x, &pos) {
            return Some(r);
        }
    }
    None
}

/// `area` less every cut (closed counter-clockwise polylines). `None`
/// where a boolean fails, or a cut meets one of the area's holes (the holes
/// would have to be merged with it; the caller then keeps its conservative
/// region).
pub(crate) fn subtract(area: &Area, cuts: &[Polyline<f64>]) -> Option<Area> {
    let mut parts = area.parts.clone();
    for x in cuts {
        let mut next = Vec::with_capacity(parts.len());
        for (o, hs) in parts {
            if !boxes_meet(&o, x) {
                next.push((o, hs));
                continue;
            }
            for h in &hs {
                if boxes_meet(h, x) {
                    let ccw = oriented(h.clone(), true);
                    let r = std::panic::catch_unwind(|| ccw.boolean(x, BooleanOp::And)).ok()?;
                    if !matches!(r.result_info, BooleanResultInfo::Disjoint) {
                        return None;
                    }
                }
            }
            let r = checked_not(&o, x)?;
            match r.result_info {
                BooleanResultInfo::InvalidInput => return None,
                BooleanResultInfo::Disjoint => next.push((o, hs)),
                BooleanResultInfo::Pline2InsidePline1 => {
                    let mut hs = hs;
                    // The cut as the boolean took it (maybe grown).
                    hs.extend(r.neg_plines.into_iter().map(|p| oriented(p.pline, false)));
                    next.push((o, hs));
                }
                _ => {
                    for p in r.pos_plines {
                        let p = oriented(p.pline, true);
                        if p.vertex_count() < 2 || p.area().abs() < 1e-9 {
                            continue;
                        }
                        let own: Vec<Polyline<f64>> =
                            hs.iter().filter(|h| inside(h, &p)).cloned().collect();
                        next.push((p, own));
                    }
                }
            }
        }
        parts = next;
    }
    Some(Area { parts })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn dist_to_pline(p: DVec2, pl: &Polyline<f64>) -> f64 {
        crate::geom::edges_of_pline(pl)
            .iter()
            .map(|e| e.distance(p))
            .fold(f64::INFINITY, f64::min)
    }

    fn winding(p: DVec2, pl: &Polyline<f64>) -> i32 {
        pl.winding_number(cavalier_contours::core::math::Vector2::new(p.x, p.y))
    }

    #[test]
    fn one_disc_is_its_circle() {
        let h = disc_hull(&[(DVec2::new(1.0, 2.0), 3.0)]).unwrap();
        assert!((h.area() - PI * 9.0).abs() < 1e-9, "{}", h.area());
    }

    #[test]
    fn two_equal_discs_make_a_stadium() {
        let h = disc_hull(&[(DVec2::ZERO, 1.0), (DVec2::new(4.0, 0.0), 1.0)]).unwrap();
        assert!((h.area() - (PI + 8.0)).abs() < 1e-9, "{}", h.area());
        assert!(h.area() > 0.0, "counter-clockwise");
    }

    proptest! {
        // The hull against a dense sampling of its discs: every disc inside
        // it, every hull vertex on some disc's circle, and its area that of
        // the sampled points' hull to within the sampling's sagitta.
        #[test]
        fn hull_holds_the_discs_and_nothing_more(
            discs in proptest::collection::vec(
                ((-5.0f64..5.0, -5.0f64..5.0), 0.05f64..4.0), 1..6)
        ) {
            let discs: Vec<(DVec2, f64)> =
                discs.iter().map(|((x, y), r)| (DVec2::new(*x, *y), *r)).collect();
            let h = disc_hull(&discs).expect("a hull");
            prop_assert!(h.area() > 0.0);
            const N: usize = 720;
            let mut pts = Vec::new();
            for (c, r) in &discs {
                for k in 0..N {
                    let q = *c + DVec2::from_angle(TAU * k as f64 / N as f64) * *r;
                    prop_assert!(
                        winding(q, &h) != 0 || dist_to_pline(q, &h) < 1e-7,
                        "({}, {}) outside", q.x, q.y
                    );
                    pts.push(q);
                }
            }
            for v in h.iter_vertexes() {
                let p = DVec2::new(v.x, v.y);
                let off = discs
                    .iter()
                    .map(|(c, r)| (p.distance(*c) - r).abs())
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(off < 1e-7, "vertex ({}, {}) off every circle by {off}", p.x, p.y);
            }
            // Area of the points' hull (monotone chain).
            pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
            let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
            let mut lower: Vec<DVec2> = Vec::new();
            for p in &pts {
                while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], *p) <= 0.0 {
                    lower.pop();
                }
                lower.push(*p);
            }
            let mut upper: Vec<DVec2> = Vec::new();
            for p in pts.iter().rev() {
                while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], *p) <= 0.0 {
                    upper.pop();
                }
                upper.push(*p);
            }
            lower.pop();
            upper.pop();
            lower.extend(upper);
            let a: f64 = (0..lower.len())
                .map(|k| lower[k].perp_dot(lower[(k + 1) % lower.len()]))
                .sum::<f64>()
                / 2.0;
            let perim: f64 = (0..lower.len()).map(|k| lower[k].distance(lower[(k + 1) % lower.len()])).sum();
            let rmax = discs.iter().map(|d| d.1).fold(0.0, f64::max);
            let sag = rmax * (1.0 - (PI / N as f64).cos());
            prop_assert!(h.area() >= a - 1e-9, "{} < {a}", h.area());
            prop_assert!(h.area() <= a + perim * sag + 1e-9, "{} > {a}", h.area());
        }
    }

    #[test]
    fn a_cut_across_a_square_leaves_two_parts() {
        let sq = |x0: f64, y0: f64, x1: f64, y1: f64| {
            let mut p = Polyline::new_closed();
            for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
                p.add_vertex(PlineVertex::new(x, y, 0.0));
            }
            p
        };
        let area = Area {
            parts: vec![(sq(0.0, 0.0, 10.0, 10.0), vec![])],
        };
        let cut = disc_hull(&[(DVec2::new(5.0, -1.0), 1.0), (DVec2::new(5.0, 11.0), 1.0)]).unwrap();
        let out = subtract(&area, &[cut]).unwrap();
        assert_eq!(out.parts.len(), 2);
        let total: f64 = out.parts.iter().map(|(o, _)| o.area()).sum();
        assert!((total - 80.0).abs() < 1e-9, "{total}");
        // A cut inside becomes a hole; one meeting that hole is refused.
        let inner = disc_hull(&[(DVec2::new(2.0, 5.0), 1.0)]).unwrap();
        let out = subtract(&out, &[inner]).unwrap();
        assert_eq!(out.parts.iter().map(|p| p.1.len()).sum::<usize>(), 1);
        let across = disc_hull(&[(DVec2::new(3.0, 5.0), 1.0)]).unwrap();
        assert!(subtract(&out, &[across]).is_none());
    }
}
