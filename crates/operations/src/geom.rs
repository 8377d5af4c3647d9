//! 2D geometry in a feature's frame: edges with their adjacency, the
//! tool-centre region (cavalier_contours offsets, true arcs kept), sampling
//! and distances.

use cavalier_contours::polyline::{
    seg_arc_radius_and_center, PlineCreation, PlineSource, PlineSourceMut, PlineVertex, Polyline,
};
use cavalier_contours::shape_algorithms::Shape;
use glam::DVec2;
use thinplan_plan::{Adjacency, ProfileLoop};

/// One profile edge: from `a` to `b`, straight (`bulge` 0) or a true arc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge2 {
    pub a: DVec2,
    pub b: DVec2,
    pub bulge: f64,
}

impl Edge2 {
    /// Arc radius and centre, `None` for a straight edge.
    pub fn arc(&self) -> Option<(f64, DVec2)> {
        if self.bulge.abs() < 1e-12 {
            return None;
        }
        let (r, c) = seg_arc_radius_and_center(
            PlineVertex::new(self.a.x, self.a.y, self.bulge),
            PlineVertex::new(self.b.x, self.b.y, 0.0),
        );
        Some((r, DVec2::new(c.x, c.y)))
    }

    pub fn length(&self) -> f64 {
        match self.arc() {
            None => self.a.distance(self.b),
            Some((r, _)) => r * (4.0 * self.bulge.atan()).abs(),
        }
    }

    /// Distance from `p` to the edge.
    pub fn distance(&self, p: DVec2) -> f64 {
        match self.arc() {
            None => dist_point_seg(p, self.a, self.b),
            Some((r, c)) => {
                let sweep = 4.0 * self.bulge.atan();
                let a0 = (self.a - c).to_angle();
                let ang = (p - c).to_angle();
                // Angle of p measured from a0 in the sweep's sense.
                let mut t = (ang - a0) * sweep.signum();
                t = t.rem_euclid(std::f64::consts::TAU);
                if t <= sweep.abs() {
                    ((p - c).length() - r).abs()
                } else {
                    p.distance(self.a).min(p.distance(self.b))
                }
            }
        }
    }

    /// The edge cut into pieces no longer than `max_len` (arcs into arcs of
    /// equal sweep), end to end.
    pub fn split(&self, max_len: f64) -> Vec<Edge2> {
        let k = (self.length() / max_len).ceil().max(1.0) as usize;
        if k == 1 {
            return vec![*self];
        }
        match self.arc() {
            None => (0..k)
                .map(|j| Edge2 {
                    a: self.a.lerp(self.b, j as f64 / k as f64),
                    b: self.a.lerp(self.b, (j + 1) as f64 / k as f64),
                    bulge: 0.0,
                })
                .collect(),
            Some((r, c)) => {
                let sweep = 4.0 * self.bulge.atan();
                let a0 = (self.a - c).to_angle();
                let at = |j: usize| {
                    if j == 0 {
                        self.a
                    } else if j == k {
                        self.b
                    } else {
                        c + r * DVec2::from_angle(a0 + sweep * j as f64 / k as f64)
                    }
                };
                let bulge = (sweep / (4.0 * k as f64)).tan();
                (0..k)
                    .map(|j| Edge2 {
                        a: at(j),
                        b: at(j + 1),
                        bulge,
                    })
                    .collect()
            }
        }
    }

    /// The edge as chords between its samples every `step` (see
    /// [`Edge2::sample`]).
    pub fn chords(&self, step: f64) -> Vec<(DVec2, DVec2)> {
        self.sample(step).windows(2).map(|w| (w[0], w[1])).collect()
    }

    /// Points along the edge, no chord longer than `step` (end points included).
    pub fn sample(&self, step: f64) -> Vec<DVec2> {
        match self.arc() {
            None => {
                let k = (self.a.distance(self.b) / step).ceil().max(1.0) as usize;
                (0..=k)
                    .map(|j| self.a.lerp(self.b, j as f64 / k as f64))
                    .collect()
            }
            Some((r, c)) => {
                let sweep = 4.0 * self.bulge.atan();
                let a0 = (self.a - c).to_angle();
                let k = (r * sweep.abs() / step).ceil().max(2.0) as usize;
                (0..=k)
                    .map(|j| c + r * DVec2::from_angle(a0 + sweep * j as f64 / k as f64))
                    .collect()
            }
        }
    }

    /// Unit tangent at the start and at the end.
    pub fn tangents(&self) -> (DVec2, DVec2) {
        match self.arc() {
            None => {
                let t = (self.b - self.a).normalize_or_zero();
                (t, t)
            }
            Some((_, c)) => {
                let s = self.bulge.signum();
                let ta = (self.a - c).perp() * s;
                let tb = (self.b - c).perp() * s;
                (ta.normalize_or_zero(), tb.normalize_or_zero())
            }
        }
    }

    pub fn midpoint(&self) -> DVec2 {
        match self.arc() {
            None => (self.a + self.b) * 0.5,
            Some((r, c)) => {
                let sweep = 4.0 * self.bulge.atan();
                c + r * DVec2::from_angle((self.a - c).to_angle() + sweep * 0.5)
            }
        }
    }
}

/// Polygons covering every point within `reach` of each segment (capsules,
/// circumscribed so that nothing within `reach` is left out).
pub fn capsules(segments: impl Iterator<Item = (DVec2, DVec2)>, reach: f64) -> Vec<Vec<[f64; 2]>> {
    const HALF: usize = 16;
    let rho = reach / (std::f64::consts::PI / (2.0 * HALF as f64)).cos();
    segments
        .filter(|(a, b)| a.distance_squared(*b) > 1e-18)
        .map(|(a, b)| {
            let t = (b - a).normalize();
            let a0 = t.perp().to_angle();
            let mut c = Vec::with_capacity(2 * HALF + 2);
            // Around b from +perp to -perp (clockwise side first), then a.
            for (centre, start) in [(b, a0 - std::f64::consts::PI), (a, a0)] {
                for k in 0..=HALF {
                    let ang = start + std::f64::consts::PI * k as f64 / HALF as f64;
                    let q = centre + DVec2::from_angle(ang) * rho;
                    c.push([q.x, q.y]);
                }
            }
            c
        })
        .collect()
}

/// The points within `reach` of the segments (at least: the round joins and
/// caps are polygons around their arcs), as shapes: the segments chained
/// where one ends at the next one's start and stroked with round joins and
/// caps. One stroke per chain, not one capsule per segment: the capsules of
/// a tessellated fillet's hundreds of short chords overlap dozens deep, and
/// their union cost grew with that overlap.
pub fn band_along(
    segments: impl Iterator<Item = (DVec2, DVec2)>,
    reach: f64,
) -> Vec<Vec<Vec<[f64; 2]>>> {
    use i_overlay::mesh::float::stroke::offset::StrokeOffset;
    use i_overlay::mesh::float::style::{LineCap, LineJoin, StrokeStyle};
    const ANGLE: f64 = 0.05;
    let mut chains: Vec<Vec<[f64; 2]>> = Vec::new();
    for (a, b) in segments.filter(|(a, b)| a.distance_squared(*b) > 1e-18) {
        match chains.last_mut() {
            Some(c)
                if c.last()
                    .is_some_and(|p| DVec2::from(*p).distance_squared(a) < 1e-18) =>
            {
                c.push([b.x, b.y]);
            }
            _ => chains.push(vec![[a.x, a.y], [b.x, b.y]]),
        }
    }
    if chains.is_empty() || reach.is_nan() || reach <= 0.0 {
        return Vec::new();
    }
    // Chords of the round pieces turn ANGLE/2 at most either side of a
    // vertex on the circle: widened so the chords lie outside the circle.
    let width = 2.0 * reach / (0.5 * ANGLE).cos();
    let style = StrokeStyle::new(width)
        .line_join(LineJoin::Round(ANGLE))
        .start_cap(LineCap::Round(ANGLE))
        .end_cap(LineCap::Round(ANGLE));
    chains.stroke(style, false)
}

pub fn dist_point_seg(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// The edges of a closed profile loop.
pub fn loop_edges(l: &ProfileLoop) -> Vec<Edge2> {
    let n = l.vertices.len();
    (0..n)
        .map(|i| {
            let v = &l.vertices[i];
            let w = &l.vertices[(i + 1) % n];
            Edge2 {
                a: DVec2::new(v.x, v.y),
                b: DVec2::new(w.x, w.y),
                bulge: v.bulge,
            }
        })
        .collect()
}

pub fn pline_from_edges(edges: &[Edge2], closed: bool) -> Polyline<f64> {
    let mut p = Polyline::with_capacity(edges.len() + 1, closed);
    for e in edges {
        p.add(e.a.x, e.a.y, e.bulge);
    }
    if !closed {
        if let Some(e) = edges.last() {
            p.add(e.b.x, e.b.y, 0.0);
        }
    }
    p
}

pub fn edges_of_pline(p: &Polyline<f64>) -> Vec<Edge2> {
    let n = p.vertex_count();
    let m = if p.is_closed() {
        n
    } else {
        n.saturating_sub(1)
    };
    (0..m)
        .map(|i| {
            let v = p.at(i);
            let w = p.at((i + 1) % n);
            Edge2 {
                a: DVec2::new(v.x, v.y),
                b: DVec2::new(w.x, w.y),
                bulge: v.bulge,
            }
        })
        .filter(|e| e.a.distance_squared(e.b) > 1e-18)
        .collect()
}

/// A loop with every edge moved outward (to the right of travel: away from
/// the region for a counter-clockwise outer loop and a clockwise hole) by its
/// own distance. Straight neighbours meet at their lines' intersection (so a
/// product edge is extended along its own line); elsewhere a straight join.
pub fn move_edges(edges: &[Edge2], out: &[f64]) -> Vec<Edge2> {
    move_edges_tagged(edges, out)
        .into_iter()
        .map(|(e, _)| e)
        .collect()
}

/// `move_edges`, each result edge with the index of the edge it moves
/// (`None` for a join between two).
pub fn move_edges_tagged(edges: &[Edge2], out: &[f64]) -> Vec<(Edge2, Option<usize>)> {
    let n = edges.len();
    let moved: Vec<Edge2> = edges
        .iter()
        .zip(out)
        .map(|(e, &d)| {
            if d == 0.0 {
                return *e;
            }
            match e.arc() {
                None => {
                    let nrm = -(e.b - e.a).normalize_or_zero().perp();
                    Edge2 {
                        a: e.a + nrm * d,
                        b: e.b + nrm * d,
                        bulge: 0.0,
                    }
                }
                Some((r, c)) => {
                    // Counter-clockwise arc: centre on the left, outward grows it.
                    let nr = if e.bulge > 0.0 { r + d } else { r - d };
                    if nr <= 1e-6 {
                        let nrm = -(e.b - e.a).normalize_or_zero().perp();
                        return Edge2 {
                            a: e.a + nrm * d,
                            b: e.b + nrm * d,
                            bulge: 0.0,
                        };
                    }
                    Edge2 {
                        a: c + (e.a - c) * (nr / r),
                        b: c + (e.b - c) * (nr / r),
                        bulge: e.bulge,
                    }
                }
            }
        })
        .collect();
    let mut res: Vec<(Edge2, Option<usize>)> = Vec::with_capacity(2 * n);
    // Start point of each moved edge after joining with its predecessor,
    // and an optional join segment before it.
    let mut starts = vec![DVec2::ZERO; n];
    let mut joins: Vec<Option<DVec2>> = vec![None; n];
    for i in 0..n {
        let p = &moved[(i + n - 1) % n];
        let q = &moved[i];
        let (op, oq) = (out[(i + n - 1) % n], out[i]);
        if op == 0.0 && oq == 0.0 {
            starts[i] = q.a;
            continue;
        }
        let straight = p.bulge == 0.0 && q.bulge == 0.0;
        let d1 = p.b - p.a;
        let d2 = q.b - q.a;
        let cr = d1.perp_dot(d2);
        // Edges move in (negative) as well as out.
        let reach = op.abs().max(oq.abs());
        if straight && cr.abs() > 1e-9 * d1.length() * d2.length() {
            let t = (q.a - p.a).perp_dot(d2) / cr;
            let x = p.a + d1 * t;
            // A mitre reaching far beyond the corner is replaced by a join.
            if x.distance(edges[i].a) <= 4.0 * reach + 1e-9 {
                starts[i] = x;
                continue;
            }
        }
        starts[i] = q.a;
        if p.b.distance_squared(q.a) > 1e-18 {
            joins[i] = Some(p.b);
        }
    }
    for i in 0..n {
        if let Some(j) = joins[i] {
            res.push((
                Edge2 {
                    a: j,
                    b: starts[i],
                    bulge: 0.0,
                },
                None,
            ));
        }
        let end = match joins[(i + 1) % n] {
            Some(j) => j,
            None => starts[(i + 1) % n],
        };
        res.push((
            Edge2 {
                a: starts[i],
                b: end,
                bulge: moved[i].bulge,
            },
            Some(i),
        ));
    }
    res.retain(|(e, _)| e.a.distance_squared(e.b) > 1e-18);
    res
}

/// A planar area: outer loops (counter-clockwise) each with its holes (clockwise).
#[derive(Debug, Clone, Default)]
pub struct Area {
    pub parts: Vec<(Polyline<f64>, Vec<Polyline<f64>>)>,
}

impl Area {
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    pub fn from_shape(shape: Shape<f64>) -> Area {
        let keep = |p: &Polyline<f64>| p.vertex_count() >= 2 && p.area().abs() > 1e-9;
        let mut parts: Vec<(Polyline<f64>, Vec<Polyline<f64>>)> = shape
            .ccw_plines
            .into_iter()
            .map(|ip| ip.polyline)
            .filter(keep)
            .map(|p| (p, Vec::new()))
            .collect();
        for h in shape
            .cw_plines
            .into_iter()
            .map(|ip| ip.polyline)
            .filter(keep)
        {
            let v = h.at(0);
            let pt = cavalier_contours::core::math::Vector2::new(v.x, v.y);
            // The smallest outer loop that contains the hole owns it.
            let owner = parts
                .iter()
                .enumerate()
                .filter(|(_, (o, _))| o.winding_number(pt) != 0)
                .min_by(|a, b| a.1 .0.area().abs().total_cmp(&b.1 .0.area().abs()))
                .map(|(i, _)| i);
            if let Some(i) = owner {
                parts[i].1.push(h);
            }
        }
        parts.sort_by(|a, b| {
            let ea =
                a.0.extents()
                    .map(|e| (e.min_x, e.min_y))
                    .unwrap_or_default();
            let eb =
                b.0.extents()
                    .map(|e| (e.min_x, e.min_y))
                    .unwrap_or_default();
            ea.partial_cmp(&eb).unwrap_or(std::cmp::Ordering::Equal)
        });
        Area { parts }
    }

    /// Inward offset by `d` (islands grow).
    pub fn offset(&self, d: f64) -> Area {
        let mut out = Area::default();
        for (o, hs) in &self.parts {
            let mut all = vec![o.clone()];
            all.extend(hs.iter().cloned());
            let off = thinplan_pocketing::inset::inset(&all, d);
            out.parts.extend(Area::from_shape(off).parts);
        }
        out
    }

    /// All loops with their orientation kept (outer ccw, holes cw).
    pub fn loops(&self) -> Vec<&Polyline<f64>> {
        let mut v = Vec::new();
        for (o, hs) in &self.parts {
            v.push(o);
            v.extend(hs.iter());
        }
        v
    }

    /// The loops sampled into polygons (for containment and scan lines).
    pub fn polygons(&self, step: f64) -> Vec<Vec<DVec2>> {
        self.loops()
            .into_iter()
            .map(|p| {
                let mut pts = Vec::new();
                for e in edges_of_pline(p) {
                    let s = e.sample(step);
                    pts.extend_from_slice(&s[..s.len() - 1]);
                }
                pts
            })
            .filter(|p| p.len() >= 3)
            .collect()
    }
}

/// Even-odd containment in a set of polygons (each loop tested by the
/// pocketing crate's point-in-loop).
pub fn inside(p: DVec2, polys: &[Vec<DVec2>]) -> bool {
    polys
        .iter()
        .filter(|pts| thinplan_pocketing::geom::point_in_loop(p, pts))
        .count()
        % 2
        == 1
}

/// Distance from `p` to the nearest polygon edge.
pub fn boundary_distance(p: DVec2, polys: &[Vec<DVec2>]) -> f64 {
    let mut d = f64::INFINITY;
    for pts in polys {
        let n = pts.len();
        for i in 0..n {
            d = d.min(dist_point_seg(p, pts[i], pts[(i + 1) % n]));
        }
    }
    d
}

/// Whether the segment a→b stays inside (sampled every `step`).
/// Points on the boundary (within 1e-6) count as inside: step-overs of
/// parallel passes run along it.
pub fn segment_inside(a: DVec2, b: DVec2, polys: &[Vec<DVec2>], step: f64) -> bool {
    let k = (a.distance(b) / step).ceil().max(1.0) as usize;
    (0..=k).all(|j| {
        let p = a.lerp(b, j as f64 / k as f64);
        inside(p, polys) || boundary_distance(p, polys) < 1e-6
    })
}

/// Edges of a feature's region with their adjacency: the outer loop's from
/// `side_adjacency`, the holes' from `hole_adjacency` (product where missing).
pub fn adjacency_edges(
    region: &thinplan_plan::Region,
    side: &[Adjacency],
    holes: &[Vec<Adjacency>],
) -> Vec<(Vec<Edge2>, Vec<Adjacency>)> {
    let mut v = Vec::new();
    let outer = loop_edges(&region.outer);
    let adj = (0..outer.len())
        .map(|i| side.get(i).copied().unwrap_or(Adjacency::Product))
        .collect();
    v.push((outer, adj));
    for (h, l) in region.holes.iter().enumerate() {
        let e = loop_edges(l);
        let adj = (0..e.len())
            .map(|i| {
                holes
                    .get(h)
                    .and_then(|a| a.get(i))
                    .copied()
                    .unwrap_or(Adjacency::Product)
            })
            .collect();
        v.push((e, adj));
    }
    v
}

/// Makes a loop's orientation counter-clockwise (`ccw`) or clockwise.
pub fn oriented(mut p: Polyline<f64>, ccw: bool) -> Polyline<f64> {
    let is_ccw = p.area() > 0.0;
    if is_ccw != ccw {
        p.invert_direction_mut();
    }
    p
}

/// Edges bucketed on a uniform grid by their box grown by `reach`: every
/// edge within `reach` of a point is among the point's cell's candidates
/// (the safety net asks that of every sampled tool centre, and a feature's
/// free-space boundary can have thousands of edges).
pub struct EdgeGrid {
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl EdgeGrid {
    pub fn new(edges: &[Edge2], reach: f64) -> Self {
        let boxes: Vec<(DVec2, DVec2)> = edges
            .iter()
            .map(|e| {
                let (mut lo, mut hi) = (e.a.min(e.b), e.a.max(e.b));
                if let Some((r, c)) = e.arc() {
                    // The whole circle: conservative and enough.
                    lo = lo.min(c - DVec2::splat(r));
                    hi = hi.max(c + DVec2::splat(r));
                }
                (lo - DVec2::splat(reach), hi + DVec2::splat(reach))
            })
            .collect();
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for (a, b) in &boxes {
            lo = lo.min(*a);
            hi = hi.max(*b);
        }
        if !lo.is_finite() || !hi.is_finite() {
            return EdgeGrid {
                origin: DVec2::ZERO,
                cell: 1.0,
                nx: 0,
                ny: 0,
                cells: Vec::new(),
            };
        }
        let ext = (hi - lo).max(DVec2::splat(1e-9));
        // About as many cells as edges, at most 256 a side.
        let target = (edges.len() as f64).sqrt().clamp(1.0, 256.0);
        let cell = (ext.x.max(ext.y) / target).max(1e-6);
        let nx = ((ext.x / cell).ceil() as usize).clamp(1, 256);
        let ny = ((ext.y / cell).ceil() as usize).clamp(1, 256);
        let cell = (ext.x / nx as f64).max(ext.y / ny as f64);
        let mut cells = vec![Vec::new(); nx * ny];
        let idx =
            |v: f64, o: f64, n: usize| (((v - o) / cell).floor().max(0.0) as usize).min(n - 1);
        for (k, (a, b)) in boxes.iter().enumerate() {
            for j in idx(a.y, lo.y, ny)..=idx(b.y, lo.y, ny) {
                for i in idx(a.x, lo.x, nx)..=idx(b.x, lo.x, nx) {
                    cells[j * nx + i].push(k as u32);
                }
            }
        }
        EdgeGrid {
            origin: lo,
            cell,
            nx,
            ny,
            cells,
        }
    }

    /// Indices of the edges whose grown box may hold `p` (none outside the
    /// grid).
    pub fn candidates(&self, p: DVec2) -> &[u32] {
        let q = (p - self.origin) / self.cell;
        if self.nx == 0 || !(q.x >= 0.0 && q.y >= 0.0) {
            return &[];
        }
        let (i, j) = (q.x.floor() as usize, q.y.floor() as usize);
        if i >= self.nx || j >= self.ny {
            return &[];
        }
        &self.cells[j * self.nx + i]
    }
}

#[cfg(test)]
mod edge_grid_tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every edge nearer than the reach to a point is among its
        /// candidates (lines and arcs, points inside and outside the grid).
        #[test]
        fn candidates_hold_every_edge_within_reach(
            es in prop::collection::vec(
                ((-50.0f64..50.0, -50.0f64..50.0), (-50.0f64..50.0, -50.0f64..50.0), -1.5f64..1.5),
                1..30,
            ),
            reach in 0.5f64..15.0,
            queries in prop::collection::vec((-80.0f64..80.0, -80.0f64..80.0), 1..40),
        ) {
            let edges: Vec<Edge2> = es
                .iter()
                .map(|&((ax, ay), (bx, by), bulge)| Edge2 {
                    a: DVec2::new(ax, ay),
                    b: DVec2::new(bx, by),
                    bulge: if bulge.abs() < 0.3 { 0.0 } else { bulge },
                })
                .filter(|e| e.a.distance(e.b) > 1e-3)
                .collect();
            let grid = EdgeGrid::new(&edges, reach);
            for &(x, y) in &queries {
                let p = DVec2::new(x, y);
                let cand = grid.candidates(p);
                for (k, e) in edges.iter().enumerate() {
                    if e.distance(p) < reach {
                        prop_assert!(cand.contains(&(k as u32)), "edge {k} at {} from {p}", e.distance(p));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod band_tests {
    use super::*;
    use proptest::prelude::*;

    /// Whether `p` lies in the shapes (non-zero winding over all contours).
    fn inside(shapes: &[Vec<Vec<[f64; 2]>>], p: DVec2) -> bool {
        let mut w = 0i32;
        for c in shapes.iter().flatten() {
            for i in 0..c.len() {
                let (a, b) = (c[i], c[(i + 1) % c.len()]);
                let (a, b) = (DVec2::new(a[0], a[1]), DVec2::new(b[0], b[1]));
                if (a.y <= p.y) != (b.y <= p.y) {
                    let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                    if x > p.x {
                        w += if b.y > a.y { 1 } else { -1 };
                    }
                }
            }
        }
        w != 0
    }

    proptest! {
        /// The band along chained and loose segments holds every point
        /// within the reach of one (never less), and nothing beyond the
        /// reach by more than 0.1 %.
        #[test]
        fn band_holds_the_reach_and_no_more(
            walk in prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 2..40),
            loose in prop::collection::vec(((-30.0f64..30.0, -30.0f64..30.0), (-30.0f64..30.0, -30.0f64..30.0)), 0..4),
            reach in 0.5f64..10.0,
            queries in prop::collection::vec((-45.0f64..45.0, -45.0f64..45.0), 1..60),
        ) {
            // A noisy chain (a tessellated fillet) and a few loose segments.
            let mut p = DVec2::ZERO;
            let mut segs = Vec::new();
            for &(dx, dy) in &walk {
                let q = p + DVec2::new(dx, dy);
                segs.push((p, q));
                p = q;
            }
            segs.extend(loose.iter().map(|&((ax, ay), (bx, by))| (DVec2::new(ax, ay), DVec2::new(bx, by))));
            let band = band_along(segs.iter().copied(), reach);
            for &(x, y) in &queries {
                let q = DVec2::new(x, y);
                let d = segs
                    .iter()
                    .filter(|(a, b)| a.distance_squared(*b) > 1e-18)
                    .map(|&(a, b)| dist_point_seg(q, a, b))
                    .fold(f64::INFINITY, f64::min);
                if d < reach * 0.999 {
                    prop_assert!(inside(&band, q), "{q} at {d} of {reach} is outside the band");
                }
                if d > reach * 1.001 {
                    prop_assert!(!inside(&band, q), "{q} at {d} of {reach} is inside the band");
                }
            }
        }
    }
}
