//! Shank and holder against the in-process stock.
//!
//! For every operation in the plan's order, the stock at that point is the
//! part plus every machining feature not yet removed. Everything here is a
//! prism along the set-up's up: resolved machining features are exact
//! prisms, and the part is cut into slabs at every height of its mesh
//! vertices (thinner where faces slope) with its section at each slab's
//! middle. The tool's shank and holder are vertical cylinders, so a
//! collision test is a 2D distance test (tool axis path against the
//! section's loops) plus a z-overlap test — exact for vertical walls, no
//! mesh-vs-mesh library needed (none is in the lock file, and this is
//! simpler to reason about than a convex decomposition of the stock).
//!
//! Moves are checked as swept pieces, not as sampled points: each piece is a
//! straight segment of the tool tip (arcs first become chords within
//! [`ARC_TOLERANCE`]), split so that its rise is at most [`MAX_RISE`]; the
//! cylinder swept along a piece is bounded exactly in plan view (the
//! segment's distance to the stock's loops against the radius) and by the
//! piece's z interval (conservative by at most its rise).

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use serde_json::{json, Value};
use thinplan_brep::{Brep, Frame};
use thinplan_knowledge::{Knowledge, Tool};
use thinplan_plan::{
    MachiningFeature, MachiningFeatureId, OperationId, Plan, ProfileLoop, Region3,
};
use thinplan_resolve::section::LocalMesh;

/// Chord tolerance for arcs of moves and profile bulges, mm.
pub const ARC_TOLERANCE: f64 = 1e-3;
/// Largest rise of one swept piece of a move, mm: bounds how much the
/// piece's z interval over-states the swept cylinder on ramps and helices.
pub const MAX_RISE: f64 = 0.25;
/// Overlaps below this (mm, radial and axial) are contact, not collision:
/// boundary passes run at exactly the tool radius from the product.
pub const CONTACT: f64 = 1e-3;
/// Largest thickness of a part slab where faces slope, mm.
pub const SLOPED_SLAB: f64 = 0.5;

/// Which part of the tool assembly hits the stock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ToolPart {
    /// The shank (and a long-reach tool's neck): from the flute length up
    /// to the stickout.
    Shank,
    /// The holder: from the stickout up, `holder_length` tall.
    Holder,
}

impl ToolPart {
    pub fn name(self) -> &'static str {
        match self {
            ToolPart::Shank => "shank",
            ToolPart::Holder => "holder",
        }
    }
}

/// What a stock body is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Against {
    /// The finished part.
    Part,
    /// A machining feature not (fully) removed yet.
    Feature(MachiningFeatureId),
}

impl std::fmt::Display for Against {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Against::Part => write!(f, "part"),
            Against::Feature(id) => write!(f, "{id}"),
        }
    }
}

/// One collision: the worst overlap of one tool part with one stock body
/// during one move.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    pub operation: OperationId,
    /// Index into the operation's `moves` (0 for the link).
    pub move_index: usize,
    /// The move is the link stage 8 planned from the previous operation
    /// (`Operation::link_z`), not one of the operation's own moves.
    pub link: bool,
    pub what: ToolPart,
    /// Tool tip (part coordinates) where the overlap is deepest.
    pub position: DVec3,
    /// Radial penetration, mm: the cylinder's radius minus the distance
    /// from the tool axis to the stock (more than the radius when the axis
    /// itself is inside the stock).
    pub penetration: f64,
    /// How far the tool would have to rise to clear that body, mm.
    pub lift: f64,
    pub against: Against,
}

/// The result with what could not be checked.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Report {
    pub collisions: Vec<Collision>,
    /// Operations or features the vertical-prism model cannot check, with why.
    pub unchecked: Vec<String>,
    /// Swept pieces tested (for reports and benchmarks).
    pub pieces: usize,
}

/// A piece of stock: loops in the set-up frame's plan view (inside by the
/// even-odd rule) swept over `z_lo..z_hi` along up.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    pub against: Against,
    pub loops: Vec<Vec<DVec2>>,
    pub z_lo: f64,
    pub z_hi: f64,
    pub lo: DVec2,
    pub hi: DVec2,
}

impl Body {
    fn new(against: Against, loops: Vec<Vec<DVec2>>, z_lo: f64, z_hi: f64) -> Option<Body> {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in loops.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo.x <= hi.x && z_lo < z_hi && lo.is_finite() && hi.is_finite()).then_some(Body {
            against,
            loops,
            z_lo,
            z_hi,
            lo,
            hi,
        })
    }

    /// Whether `p` is inside (even-odd over all loops).
    pub fn contains(&self, p: DVec2) -> bool {
        let mut inside = false;
        for lp in &self.loops {
            for i in 0..lp.len() {
                let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
                if (a.y > p.y) != (b.y > p.y) {
                    let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                    if p.x < x {
                        inside = !inside;
                    }
                }
            }
        }
        inside
    }

    /// Signed distance in plan view from the segment `a`–`b` to the body
    /// (negative inside) and the segment parameter where it is reached. The
    /// reference for [`EdgeIndex::segment_distance`], which the check uses.
    #[cfg(test)]
    fn segment_distance(&self, a: DVec2, b: DVec2) -> (f64, f64) {
        let mut best = (f64::INFINITY, 0.0);
        for lp in &self.loops {
            for i in 0..lp.len() {
                let (d, t) = seg_seg(a, b, lp[i], lp[(i + 1) % lp.len()]);
                if d < best.0 {
                    best = (d, t);
                }
            }
        }
        let mut deepest: Option<(f64, f64)> = None;
        for (p, t) in [(a, 0.0), (b, 1.0)] {
            if self.contains(p) {
                let d = self.boundary_distance(p);
                if deepest.is_none_or(|(dd, _)| d > dd) {
                    deepest = Some((d, t));
                }
            }
        }
        match deepest {
            Some((d, t)) => (-d, t),
            None => best,
        }
    }

    #[cfg(test)]
    fn boundary_distance(&self, p: DVec2) -> f64 {
        self.loops
            .iter()
            .flat_map(|lp| (0..lp.len()).map(move |i| (lp[i], lp[(i + 1) % lp.len()])))
            .map(|(a, b)| point_seg(p, a, b).0)
            .fold(f64::INFINITY, f64::min)
    }
}

/// Margin, mm, by which [`EdgeIndex`] over-reaches: an edge whose box lies farther than the
/// reach plus this from a piece's box is farther than the reach, rounding included (its
/// error is some 1e-13 mm at part sizes).
const INDEX_MARGIN: f64 = 1e-6;

/// A body's edges on a uniform grid, for [`Body::segment_distance`] and [`Body::contains`]
/// asked only about edges near a piece: exact, as only edges that cannot matter are skipped
/// (see [`EdgeIndex::segment_distance`]).
struct EdgeIndex {
    /// The body's edges in its order: loop by loop, `(lp[i], lp[i + 1])`.
    edges: Vec<(DVec2, DVec2)>,
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// cell `j * nx + i` holds `cell_items[cell_start[c]..cell_start[c + 1]]`, ascending
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
    /// row `j` (y from `lo.y + j·cell`) holds the edges whose y range meets it, ascending
    row_start: Vec<u32>,
    row_items: Vec<u32>,
    /// the first cell (column, row) of each edge's box
    first_cell: Vec<(u32, u32)>,
}

/// Buckets as compressed lists: `ranges[k]` are the buckets of item `k`.
fn buckets(n: usize, ranges: impl Fn(usize) -> Vec<usize>, items: usize) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; n + 1];
    for k in 0..items {
        for c in ranges(k) {
            start[c + 1] += 1;
        }
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    let mut fill: Vec<u32> = start[..n].to_vec();
    let mut out = vec![0u32; start[n] as usize];
    for k in 0..items {
        for c in ranges(k) {
            out[fill[c] as usize] = k as u32;
            fill[c] += 1;
        }
    }
    (start, out)
}

impl EdgeIndex {
    /// At most this many cells along a side.
    const CELLS: f64 = 32.0;

    fn new(body: &Body) -> EdgeIndex {
        let edges: Vec<(DVec2, DVec2)> = body
            .loops
            .iter()
            .flat_map(|lp| (0..lp.len()).map(move |i| (lp[i], lp[(i + 1) % lp.len()])))
            .collect();
        let (lo, hi) = (body.lo, body.hi);
        let ext = (hi - lo).max(DVec2::splat(1e-9));
        let cell = (ext.max_element() / Self::CELLS).max(1e-9);
        let nx = ((ext.x / cell).floor() as usize + 1).max(1);
        let ny = ((ext.y / cell).floor() as usize + 1).max(1);
        let mut g = EdgeIndex {
            edges,
            lo,
            cell,
            nx,
            ny,
            cell_start: Vec::new(),
            cell_items: Vec::new(),
            row_start: Vec::new(),
            row_items: Vec::new(),
            first_cell: Vec::new(),
        };
        let boxes: Vec<((usize, usize), (usize, usize))> = g
            .edges
            .iter()
            .map(|(a, b)| (g.cell_of(a.min(*b)), g.cell_of(a.max(*b))))
            .collect();
        g.first_cell = boxes
            .iter()
            .map(|&((i0, j0), _)| (i0 as u32, j0 as u32))
            .collect();
        (g.cell_start, g.cell_items) = buckets(
            nx * ny,
            |k| {
                let ((i0, j0), (i1, j1)) = boxes[k];
                (j0..=j1)
                    .flat_map(|j| (i0..=i1).map(move |i| j * nx + i))
                    .collect()
            },
            boxes.len(),
        );
        (g.row_start, g.row_items) = buckets(
            ny,
            |k| {
                let ((_, j0), (_, j1)) = boxes[k];
                (j0..=j1).collect()
            },
            boxes.len(),
        );
        g
    }

    /// The cell of `p`, clamped to the grid; monotone in each coordinate.
    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.lo) / self.cell;
        (
            (q.x.floor().max(0.0) as usize).min(self.nx - 1),
            (q.y.floor().max(0.0) as usize).min(self.ny - 1),
        )
    }

    /// [`Body::contains`]: only the edges whose y range meets `p`'s row can change the count
    /// (an edge crosses `p`'s horizontal only if `p.y` lies in its y range, and the row of
    /// every y in that range is among the edge's rows); even-odd does not depend on the
    /// order.
    fn contains(&self, p: DVec2) -> bool {
        let j = self.cell_of(p).1;
        let mut inside = false;
        for &k in &self.row_items[self.row_start[j] as usize..self.row_start[j + 1] as usize] {
            let (a, b) = self.edges[k as usize];
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// [`Body::boundary_distance`], every edge in the same order.
    fn boundary_distance(&self, p: DVec2) -> f64 {
        self.edges
            .iter()
            .map(|&(a, b)| point_seg(p, a, b).0)
            .fold(f64::INFINITY, f64::min)
    }

    /// [`Body::segment_distance`] wherever its distance is below `reach`; otherwise a
    /// distance ≥ `reach` (maybe not the least). Only edges whose boxes lie within `reach`
    /// (plus [`INDEX_MARGIN`]) of the segment's box are measured, in the body's order: every
    /// edge nearer than `reach` is among them, so when the least distance is below `reach`
    /// the same first nearest edge gives the same distance and parameter. Inside the body
    /// the boundary distance over all edges, as there. A query covering half the grid or more
    /// scans every edge in order.
    fn segment_distance(&self, a: DVec2, b: DVec2, reach: f64) -> (f64, f64) {
        let mut best = (f64::INFINITY, 0.0);
        let grow = reach + INDEX_MARGIN;
        let (i0, j0) = self.cell_of(a.min(b) - DVec2::splat(grow));
        let (i1, j1) = self.cell_of(a.max(b) + DVec2::splat(grow));
        if grow.is_finite() && 2 * (i1 - i0 + 1) * (j1 - j0 + 1) <= self.nx * self.ny {
            // each edge once (in the first cell of its box within the query's), and of equal
            // distances the first edge in the body's order, as the scan in order keeps
            let mut best_k = u32::MAX;
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = j * self.nx + i;
                    for &k in &self.cell_items
                        [self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
                    {
                        let (bi, bj) = self.first_cell[k as usize];
                        if bi.max(i0 as u32) != i as u32 || bj.max(j0 as u32) != j as u32 {
                            continue;
                        }
                        let (c, d) = self.edges[k as usize];
                        let (dist, t) = seg_seg(a, b, c, d);
                        if dist < best.0 || (dist == best.0 && k < best_k) {
                            best = (dist, t);
                            best_k = k;
                        }
                    }
                }
            }
        } else {
            for &(c, d) in &self.edges {
                let (dist, t) = seg_seg(a, b, c, d);
                if dist < best.0 {
                    best = (dist, t);
                }
            }
        }
        let mut deepest: Option<(f64, f64)> = None;
        for (p, t) in [(a, 0.0), (b, 1.0)] {
            if self.contains(p) {
                let d = self.boundary_distance(p);
                if deepest.is_none_or(|(dd, _)| d > dd) {
                    deepest = Some((d, t));
                }
            }
        }
        match deepest {
            Some((d, t)) => (-d, t),
            None => best,
        }
    }
}

/// Distance from `p` to segment `a`–`b` and the parameter of the nearest point.
fn point_seg(p: DVec2, a: DVec2, b: DVec2) -> (f64, f64) {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((a + ab * t).distance(p), t)
}

/// Distance between segments `a`–`b` and `c`–`d`, with the parameter on
/// `a`–`b` of the closest point (0 when they cross).
fn seg_seg(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> (f64, f64) {
    let cross = |u: DVec2, v: DVec2| u.x * v.y - u.y * v.x;
    let (r, s) = (b - a, d - c);
    let den = cross(r, s);
    if den.abs() > 1e-300 {
        let t = cross(c - a, s) / den;
        let u = cross(c - a, r) / den;
        if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
            return (0.0, t);
        }
    }
    let mut best = point_seg(a, c, d);
    best.1 = 0.0;
    let e = point_seg(b, c, d);
    if e.0 < best.0 {
        best = (e.0, 1.0);
    }
    for q in [c, d] {
        let (dist, t) = point_seg(q, a, b);
        if dist < best.0 {
            best = (dist, t);
        }
    }
    best
}

/// The set-up frame: z = up, the same x for every picture and test.
pub fn setup_frame(up: DVec3) -> Frame {
    Frame::from_axis_ref(DVec3::ZERO, up, None)
}

/// The part as slabs along up in `frame`: at every mesh-vertex height,
/// subdivided to at most [`SLOPED_SLAB`] where faces slope; each slab's
/// section is taken at its middle.
pub fn part_bodies(brep: &Brep, frame: &Frame) -> Vec<Body> {
    let mesh = thinplan_brep::tess::tessellate(brep, &brep.mass_tolerance());
    let local = LocalMesh {
        positions: mesh.positions.iter().map(|p| frame.to_local(*p)).collect(),
        triangles: mesh.triangles.clone(),
    };
    let mut zs: Vec<f64> = local
        .positions
        .iter()
        .map(|p| p.z)
        .filter(|z| z.is_finite())
        .collect();
    zs.sort_by(f64::total_cmp);
    let mut levels: Vec<f64> = Vec::new();
    for z in zs {
        if levels.last().is_none_or(|l| z - l > 1e-6) {
            levels.push(z);
        }
    }
    let mut sloped: Vec<(f64, f64)> = Vec::new();
    for t in &local.triangles {
        let v = t.map(|i| local.positions[i as usize]);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = n.length();
        if len > 1e-300 {
            let nz = (n.z / len).abs();
            if nz > 1e-7 && nz < 1.0 - 1e-7 {
                let lo = v[0].z.min(v[1].z).min(v[2].z);
                let hi = v[0].z.max(v[1].z).max(v[2].z);
                sloped.push((lo, hi));
            }
        }
    }
    let mut out = Vec::new();
    for w in levels.windows(2) {
        let (a, b) = (w[0], w[1]);
        let slopes = sloped.iter().any(|s| s.0 < b - 1e-6 && s.1 > a + 1e-6);
        let n = if slopes {
            ((b - a) / SLOPED_SLAB).ceil().clamp(1.0, 10_000.0) as usize
        } else {
            1
        };
        for i in 0..n {
            let lo = a + (b - a) * i as f64 / n as f64;
            let hi = a + (b - a) * (i + 1) as f64 / n as f64;
            let (loops, _gaps) = local.section(0.5 * (lo + hi));
            let loops: Vec<Vec<DVec2>> = loops
                .into_iter()
                .map(|l| l.into_iter().map(|p| DVec2::new(p[0], p[1])).collect())
                .collect();
            if let Some(body) = Body::new(Against::Part, loops, lo, hi) {
                out.push(body);
            }
        }
    }
    out
}

/// Points of a profile loop with its bulges (true arcs) as chords within
/// [`ARC_TOLERANCE`].
pub fn loop_points(lp: &ProfileLoop) -> Vec<DVec2> {
    let n = lp.vertices.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let v = lp.vertices[i];
        let w = lp.vertices[(i + 1) % n];
        let (p, q) = (DVec2::new(v.x, v.y), DVec2::new(w.x, w.y));
        out.push(p);
        if v.bulge.abs() < 1e-12 || !v.bulge.is_finite() || p.distance(q) < 1e-12 {
            continue;
        }
        let b = v.bulge;
        let d = q - p;
        let centre = (p + q) * 0.5 + DVec2::new(-d.y, d.x) * ((1.0 - b * b) / (4.0 * b));
        let r = centre.distance(p);
        let sweep = 4.0 * b.atan();
        let step = if ARC_TOLERANCE >= r {
            std::f64::consts::PI
        } else {
            2.0 * (1.0 - ARC_TOLERANCE / r).acos()
        };
        let k = ((sweep.abs() / step).ceil() as usize).clamp(1, 10_000);
        let a0 = (p - centre).to_angle();
        for j in 1..k {
            let a = a0 + sweep * j as f64 / k as f64;
            out.push(centre + DVec2::from_angle(a) * r);
        }
    }
    out
}

/// A machining feature as a stock body in `frame`, or why not.
pub fn feature_body(f: &MachiningFeature, frame: &Frame) -> Result<Body, String> {
    let s = &f.shape;
    let fz = s.frame.z.normalize_or_zero();
    if fz.dot(frame.z).abs() < 1.0 - 1e-9 {
        return Err(format!(
            "{}: its axis is not the set-up's up; not checked",
            f.id
        ));
    }
    let pf = Frame::from_axis_ref(s.frame.origin, fz, Some(s.frame.x));
    let to_plan = |p: DVec2| {
        let w = pf.to_world(DVec3::new(p.x, p.y, 0.0));
        let l = frame.to_local(w);
        DVec2::new(l.x, l.y)
    };
    let loops: Vec<Vec<DVec2>> = std::iter::once(&s.region.outer)
        .chain(s.region.holes.iter())
        .map(|lp| loop_points(lp).into_iter().map(to_plan).collect())
        .collect();
    let za = frame.to_local(pf.to_world(DVec3::new(0.0, 0.0, s.z_min))).z;
    let zb = frame.to_local(pf.to_world(DVec3::new(0.0, 0.0, s.z_max))).z;
    Body::new(Against::Feature(f.id), loops, za.min(zb), za.max(zb))
        .ok_or_else(|| format!("{}: empty shape; not checked", f.id))
}

/// The tool's cylinders above the flutes: (part, radius, from, to) along
/// up, from [`Tool::radius_profile`]: a long-reach tool's neck up to its
/// reach, then the shank up to the stickout (both [`ToolPart::Shank`]),
/// then the holder.
fn cylinders(t: &Tool) -> Vec<(ToolPart, f64, f64, f64)> {
    let mut c = Vec::new();
    let mut from = 0.0;
    for (k, (top, r)) in t.radius_profile().into_iter().enumerate() {
        let part = if top > t.stickout + 1e-9 {
            ToolPart::Holder
        } else {
            ToolPart::Shank
        };
        // The first step is the cutter: it cuts, it does not collide.
        if k > 0 && r > 0.0 && top > from {
            c.push((part, r, from, top));
        }
        from = top;
    }
    c
}

/// Every collision of shank and holder with the in-process stock.
pub fn check_holders(plan: &Plan, k: &Knowledge, brep: &Brep) -> Vec<Collision> {
    check(plan, k, brep).collisions
}

/// [`check_holders`] with what could not be checked.
pub fn check(plan: &Plan, k: &Knowledge, brep: &Brep) -> Report {
    let mut report = Report::default();
    let up = plan.setup.up;
    if !(up.is_finite() && up.length() > 1e-9) {
        report
            .unchecked
            .push("the set-up's up is not a direction".into());
        return report;
    }
    let frame = setup_frame(up);
    let part = part_bodies(brep, &frame);
    check_with_part(plan, k, &frame, &part, &mut report);
    report
}

fn check_with_part(plan: &Plan, k: &Knowledge, frame: &Frame, part: &[Body], report: &mut Report) {
    let Some(tools) = k.tool_set(&plan.setup.tool_set) else {
        report.unchecked.push(format!(
            "the knowledge has no tool set `{}`",
            plan.setup.tool_set
        ));
        return;
    };
    // Features: body, top of what is left (lowered as their operations cut
    // top-down), operations still to run.
    // (and each body's edge grid, built once)
    #[allow(clippy::type_complexity)]
    let mut features: BTreeMap<MachiningFeatureId, (Body, f64, usize, EdgeIndex)> = BTreeMap::new();
    // each body's edge grid, built once
    let part_index: Vec<EdgeIndex> = part.iter().map(EdgeIndex::new).collect();
    for f in &plan.machining_features {
        match feature_body(f, frame) {
            Ok(b) => {
                let top = b.z_hi;
                let index = EdgeIndex::new(&b);
                features.insert(f.id, (b, top, 0, index));
            }
            Err(e) => report.unchecked.push(e),
        }
    }
    let ops: BTreeMap<OperationId, &thinplan_plan::Operation> =
        plan.operations.iter().map(|o| (o.id, o)).collect();
    for id in &plan.operation_order {
        if let Some(op) = ops.get(id) {
            if let Some(f) = features.get_mut(&op.feature) {
                f.2 += 1;
            }
        }
    }
    // A feature no operation removes (refused) stays in the stock for good.
    for f in features.values_mut() {
        if f.2 == 0 {
            f.2 = usize::MAX;
        }
    }
    // Where the previous operation ended, for links planned on the stock.
    let mut last_end: Option<DVec3> = None;
    for id in &plan.operation_order {
        let Some(op) = ops.get(id) else {
            report
                .unchecked
                .push(format!("{id}: in the order but not among the operations"));
            continue;
        };
        let Some(tool) = tools.tools.iter().find(|t| t.id == op.tool) else {
            report
                .unchecked
                .push(format!("{id}: tool `{}` is not in the tool set", op.tool));
            continue;
        };
        if op.tool_axis.normalize_or_zero().dot(frame.z) < 1.0 - 1e-9 {
            report.unchecked.push(format!(
                "{id}: its tool axis is not the set-up's up; not checked"
            ));
            continue;
        }
        let cyl = cylinders(tool);
        // The planned link from the previous operation's end, then the moves.
        let link = op.link_z.and(last_end).map(|_| thinplan_plan::PathMove {
            to: op.start,
            arc: None,
            feed: 0.0,
            region: Region3::Rapid,
        });
        let mut prev = match (&link, last_end) {
            (Some(_), Some(e)) => frame.to_local(e),
            _ => frame.to_local(op.start),
        };
        last_end = Some(op.moves.last().map_or(op.start, |m| m.to));
        let moves = link
            .iter()
            .map(|m| (None, m))
            .chain(op.moves.iter().enumerate().map(|(i, m)| (Some(i), m)));
        for (mi, mv) in moves {
            let to = frame.to_local(mv.to);
            let pts: Vec<DVec3> = match &mv.arc {
                Some(a) => thinplan_post::linearise_arc(
                    frame.to_world(prev),
                    mv.to,
                    a.centre,
                    a.axis,
                    a.clockwise,
                    ARC_TOLERANCE,
                )
                .into_iter()
                .map(|p| frame.to_local(p))
                .collect(),
                None => vec![to],
            };
            // Worst per tool part and stock body for this move.
            let mut worst: BTreeMap<(ToolPart, Against), Collision> = BTreeMap::new();
            let mut a = prev;
            let mut min_z = f64::INFINITY;
            for b in pts {
                let n = (((b.z - a.z).abs() / MAX_RISE).ceil() as usize).clamp(1, 100_000);
                for j in 0..n {
                    let p = a.lerp(b, j as f64 / n as f64);
                    let q = a.lerp(b, (j + 1) as f64 / n as f64);
                    report.pieces += 1;
                    // What is left of a feature being cut lies below its top (its entry's
                    // top: a feature body's `against` is its own id).
                    let bodies = part
                        .iter()
                        .zip(&part_index)
                        .map(|(b, index)| (b, index, b.z_hi))
                        .chain(
                            features
                                .values()
                                .filter(|(_, _, left, _)| *left > 0)
                                .map(|(b, top, _, index)| (b, index, *top)),
                        );
                    for (body, index, z_hi) in bodies {
                        for &(what, r, from, upto) in &cyl {
                            let c_lo = p.z.min(q.z) + from;
                            let c_hi = p.z.max(q.z) + upto;
                            // A feature cut down to its bottom has nothing
                            // left, though an operation of it (a rest pass
                            // run last) is still to come.
                            if z_hi - c_lo <= CONTACT
                                || c_hi - body.z_lo <= CONTACT
                                || z_hi - body.z_lo <= CONTACT
                            {
                                continue;
                            }
                            let (p2, q2) = (p.truncate(), q.truncate());
                            if p2.min(q2).x - r > body.hi.x
                                || p2.min(q2).y - r > body.hi.y
                                || p2.max(q2).x + r < body.lo.x
                                || p2.max(q2).y + r < body.lo.y
                            {
                                continue;
                            }
                            // exact where it matters: pen > CONTACT > 0 needs d < r
                            let (d, t) = index.segment_distance(p2, q2, r);
                            let pen = r - d;
                            if pen <= CONTACT {
                                continue;
                            }
                            let lift = z_hi - c_lo;
                            // Deepest radially, then the one needing most lift.
                            if worst.get(&(what, body.against)).is_none_or(|w| {
                                pen > w.penetration + 1e-9
                                    || (pen > w.penetration - 1e-9 && lift > w.lift)
                            }) {
                                // Closest in plan view, at the piece's lowest tip.
                                let mut at = p.lerp(q, t);
                                at.z = p.z.min(q.z);
                                worst.insert(
                                    (what, body.against),
                                    Collision {
                                        operation: *id,
                                        move_index: mi.unwrap_or(0),
                                        link: mi.is_none(),
                                        what,
                                        position: frame.to_world(at),
                                        penetration: pen,
                                        lift,
                                        against: body.against,
                                    },
                                );
                            }
                        }
                    }
                }
                min_z = min_z.min(a.z).min(b.z);
                a = b;
            }
            report.collisions.extend(worst.into_values());
            // Cutting moves lower what is left of the feature (top-down layers).
            if !matches!(mv.region, Region3::Rapid) {
                if let Some(f) = features.get_mut(&op.feature) {
                    f.1 = f.1.min(min_z);
                }
            }
            prev = to;
        }
        if let Some(f) = features.get_mut(&op.feature) {
            f.2 = f.2.saturating_sub(1);
        }
    }
}

fn round6(v: f64) -> f64 {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// The `collisions` list of `plan --json`.
pub fn collisions_json(collisions: &[Collision]) -> Value {
    Value::Array(
        collisions
            .iter()
            .map(|c| {
                let mut v = json!({
                    "operation": c.operation.to_string(),
                    "move": if c.link { Value::Null } else { json!(c.move_index) },
                    "what": c.what.name(),
                    "position": [round6(c.position.x), round6(c.position.y), round6(c.position.z)],
                    "penetration": round6(c.penetration),
                    "lift": round6(c.lift),
                    "against": c.against.to_string(),
                });
                if c.link {
                    v["link"] = Value::Bool(true);
                }
                v
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (no extra dependency).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }

        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
    }

    /// The edge grid answers as the body does: `contains` everywhere, the boundary distance,
    /// and the segment distance with its parameter wherever that is below the reach (and a
    /// distance at least the reach otherwise), for bodies of star-shaped and zig-zag loops
    /// with holes, segments inside, across and outside, short and long, and reaches from 0
    /// to beyond the body.
    #[test]
    fn edge_index_equals_body() {
        let mut g = Lcg(7);
        for case in 0..300 {
            let mut loops = Vec::new();
            for _ in 0..1 + case % 3 {
                let c = DVec2::new(g.range(-40.0, 40.0), g.range(-40.0, 40.0));
                let n = 3 + (g.next() * 40.0) as usize;
                let lp: Vec<DVec2> = (0..n)
                    .map(|i| {
                        let a = std::f64::consts::TAU * i as f64 / n as f64;
                        c + DVec2::from_angle(a) * g.range(2.0, 30.0)
                    })
                    .collect();
                loops.push(lp);
            }
            if case % 7 == 0 {
                // an axis-aligned rectangle: edges exactly on cell rows
                loops.push(vec![
                    DVec2::new(-10.0, -10.0),
                    DVec2::new(10.0, -10.0),
                    DVec2::new(10.0, 10.0),
                    DVec2::new(-10.0, 10.0),
                ]);
            }
            let body = Body::new(Against::Part, loops, 0.0, 1.0).unwrap();
            let index = EdgeIndex::new(&body);
            for _ in 0..200 {
                let a = DVec2::new(g.range(-90.0, 90.0), g.range(-90.0, 90.0));
                let b = if g.next() < 0.5 {
                    a + DVec2::new(g.range(-2.0, 2.0), g.range(-2.0, 2.0))
                } else {
                    DVec2::new(g.range(-90.0, 90.0), g.range(-90.0, 90.0))
                };
                assert_eq!(index.contains(a), body.contains(a));
                assert_eq!(index.boundary_distance(a), body.boundary_distance(a));
                let reach = [0.0, 0.5, 3.0, 8.0, 25.0, 200.0][(g.next() * 6.0) as usize];
                let want = body.segment_distance(a, b);
                let got = index.segment_distance(a, b, reach);
                if want.0 < reach {
                    assert_eq!(got, want, "case {case}: {a} {b} reach {reach}");
                } else {
                    assert!(got.0 >= reach, "case {case}: {a} {b} reach {reach}");
                }
            }
        }
    }
}
