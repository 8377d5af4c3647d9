//! Shank and holder against the in-process stock (issue 5, item 5).
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
    /// The shank: from the flute length up to the stickout.
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
    /// Index into the operation's `moves`.
    pub move_index: usize,
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
    /// (negative inside) and the segment parameter where it is reached.
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

    fn boundary_distance(&self, p: DVec2) -> f64 {
        self.loops
            .iter()
            .flat_map(|lp| (0..lp.len()).map(move |i| (lp[i], lp[(i + 1) % lp.len()])))
            .map(|(a, b)| point_seg(p, a, b).0)
            .fold(f64::INFINITY, f64::min)
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

/// The tool's cylinders above the tip: (part, radius, from, to) along up.
fn cylinders(t: &Tool) -> Vec<(ToolPart, f64, f64, f64)> {
    let mut c = Vec::new();
    if t.stickout > t.flute_length && t.shank_diameter > 0.0 {
        c.push((
            ToolPart::Shank,
            0.5 * t.shank_diameter,
            t.flute_length,
            t.stickout,
        ));
    }
    if t.holder_diameter > 0.0 && t.holder_length > 0.0 {
        c.push((
            ToolPart::Holder,
            0.5 * t.holder_diameter,
            t.stickout,
            t.stickout + t.holder_length,
        ));
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
    let mut features: BTreeMap<MachiningFeatureId, (Body, f64, usize)> = BTreeMap::new();
    for f in &plan.machining_features {
        match feature_body(f, frame) {
            Ok(b) => {
                let top = b.z_hi;
                features.insert(f.id, (b, top, 0));
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
        let mut prev = frame.to_local(op.start);
        for (mi, mv) in op.moves.iter().enumerate() {
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
                    let bodies = part.iter().chain(
                        features
                            .iter()
                            .filter_map(|(_, (b, _, left))| (*left > 0).then_some(b)),
                    );
                    for body in bodies {
                        // What is left of a feature being cut lies below its top.
                        let z_hi = match body.against {
                            Against::Feature(fid) => features.get(&fid).map_or(body.z_hi, |f| f.1),
                            Against::Part => body.z_hi,
                        };
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
                            let (d, t) = body.segment_distance(p2, q2);
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
                                        move_index: mi,
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
                json!({
                    "operation": c.operation.to_string(),
                    "move": c.move_index,
                    "what": c.what.name(),
                    "position": [round6(c.position.x), round6(c.position.y), round6(c.position.z)],
                    "penetration": round6(c.penetration),
                    "lift": round6(c.lift),
                    "against": c.against.to_string(),
                })
            })
            .collect(),
    )
}
