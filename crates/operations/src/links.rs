//! Stage 8, second step: links at the lowest safe height the in-process
//! stock allows (thesis §5.4.3).
//!
//! Stage 7 takes every link that leaves a feature's cleared space over the
//! top of the whole stock: it cannot know what the operations before leave
//! behind (corners no tool reaches, features refused or not yet cut). Once
//! the order is known, this step replays the operations on a height map of
//! the in-process stock and lowers each such link (rapid up, across, down),
//! and the link between consecutive operations of one tool, to
//! `methods.safe_clearance` above the highest stock under the tool, its
//! shank and its holder along the link (`methods.links: InProcessStock`).
//!
//! The height map errs towards material: it starts at the top of the part's
//! box and of every machining feature's box, and a cell is lowered only where
//! the tool's flat bottom covers all of it (to the tip's height) or its
//! corner radius does (to the tip plus that radius), and only if its stock
//! did not stand above the flutes. So no cell is ever lower than the real
//! stock in it, whatever the tool paths leave — leftovers need no model of
//! their own. Links only ever move down from where stage 7 and the post
//! put them, and the independent stock simulation checks that no rapid
//! enters stock.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_knowledge::{Knowledge, LinkHeight, Tool};
use thinplan_plan::{Operation, OperationId, PathMove, Plan, Region3};

use crate::path::{move_points, LMove};
use crate::{length_and_time, resources, Kind, OperationsError};
use thinplan_feeds::MachineLimits;

/// Side of a height-map cell, mm. Any size is safe (cells err towards
/// material); finer cells let links run lower beside walls.
const CELL: f64 = 1.0;
/// Most cells of a map: a larger part gets larger cells (4 M cells: 32 MB).
const MAX_CELLS: f64 = 4.0e6;
/// Arcs are followed by chords at most this long, mm; a chord strays at most
/// half of it from its arc, which the cut radius gives up.
const CHORD: f64 = 0.5;
/// Longest piece a segment is cut into for the map, mm (bounds the box of
/// cells each piece visits).
const PIECE: f64 = 4.0;
/// A link lowered by less than this (mm) is left where it was.
const MIN_GAIN: f64 = 1e-3;

/// What lowering did, for the report.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinkReport {
    /// Links inside operations (rapid up, across, down) that were lowered.
    pub inside: usize,
    /// Links between operations of one tool that were lowered.
    pub between: usize,
    /// Straight feed descents into stock turned into ramp entries.
    pub ramped: usize,
    /// Operations the map could not follow (tool axis not the set-up's up,
    /// tool not in the set): their links stay, and the stock they cut is
    /// taken as still there.
    pub skipped: Vec<OperationId>,
}

/// Plan view along the set-up's up: x, y across it, z along it.
#[derive(Clone, Copy)]
pub(crate) struct View {
    ex: DVec3,
    ey: DVec3,
    up: DVec3,
}

impl View {
    pub(crate) fn new(up: DVec3) -> Self {
        let up = up.normalize_or_zero();
        let seed = if up.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let ex = (seed - up * seed.dot(up)).normalize_or_zero();
        View {
            ex,
            ey: up.cross(ex),
            up,
        }
    }
    pub(crate) fn xy(&self, p: DVec3) -> DVec2 {
        DVec2::new(p.dot(self.ex), p.dot(self.ey))
    }
    pub(crate) fn z(&self, p: DVec3) -> f64 {
        p.dot(self.up)
    }
    pub(crate) fn up(&self) -> DVec3 {
        self.up
    }
}

/// Highest point of the stock in each cell, along up; outside the map: air.
struct HeightMap {
    lo: DVec2,
    /// Side of a cell, mm: [`CELL`], or more on parts over [`MAX_CELLS`].
    cell: f64,
    nx: usize,
    ny: usize,
    h: Vec<f64>,
}

impl HeightMap {
    fn new(lo: DVec2, hi: DVec2) -> Self {
        let size = (hi - lo).max(DVec2::ZERO);
        let cell = CELL.max((size.x * size.y / MAX_CELLS).sqrt());
        let nx = ((size.x / cell).ceil().max(1.0)) as usize;
        let ny = ((size.y / cell).ceil().max(1.0)) as usize;
        HeightMap {
            lo,
            cell,
            nx,
            ny,
            h: vec![f64::NEG_INFINITY; nx * ny],
        }
    }

    fn centre(&self, i: usize, j: usize) -> DVec2 {
        self.lo + DVec2::new((i as f64 + 0.5) * self.cell, (j as f64 + 0.5) * self.cell)
    }

    /// Cells whose centre may lie within `reach` of segment a–b.
    fn cells(&self, a: DVec2, b: DVec2, reach: f64) -> (usize, usize, usize, usize) {
        let lo = (a.min(b) - DVec2::splat(reach) - self.lo) / self.cell;
        let hi = (a.max(b) + DVec2::splat(reach) - self.lo) / self.cell;
        let clamp = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n);
        (
            clamp(lo.x, self.nx),
            clamp(hi.x + 1.0, self.nx),
            clamp(lo.y, self.ny),
            clamp(hi.y + 1.0, self.ny),
        )
    }

    /// Stock up to `top` over the box `lo`–`hi` (plan view).
    fn raise_box(&mut self, lo: DVec2, hi: DVec2, top: f64) {
        let half = 0.5 * self.cell;
        let (i0, i1, j0, j1) = self.cells(lo, hi, half);
        for j in j0..j1 {
            for i in i0..i1 {
                let c = self.centre(i, j);
                // Every cell the box touches.
                if c.x + half >= lo.x
                    && c.x - half <= hi.x
                    && c.y + half >= lo.y
                    && c.y - half <= hi.y
                {
                    let k = j * self.nx + i;
                    self.h[k] = self.h[k].max(top);
                }
            }
        }
    }

    /// The tool tip moved from `a` to `b` at heights up to `z`: cells wholly
    /// under its flat bottom drop to `z`, cells wholly under its corner to
    /// `z + rc`, unless their stock stood above the flutes.
    fn cut(&mut self, a: DVec2, b: DVec2, z: f64, tool: &Tool) {
        let r = 0.5 * tool.diameter;
        let rc = tool.corner_radius.clamp(0.0, r);
        let slack = self.cell * std::f64::consts::FRAC_1_SQRT_2 + 0.5 * CHORD;
        let r_all = r - slack;
        if r_all <= 0.0 {
            return;
        }
        let r_flat = r - rc - slack;
        for (p, q) in pieces(a, b) {
            let (i0, i1, j0, j1) = self.cells(p, q, r_all);
            for j in j0..j1 {
                for i in i0..i1 {
                    let d = crate::geom::dist_point_seg(self.centre(i, j), p, q);
                    let new = if d <= r_flat {
                        z
                    } else if d <= r_all {
                        z + rc
                    } else {
                        continue;
                    };
                    let k = j * self.nx + i;
                    if self.h[k] <= z + tool.flute_length {
                        self.h[k] = self.h[k].min(new);
                    }
                }
            }
        }
    }

    /// Stock above the lower surface of `tool` with its tip at `p` at
    /// height `z`, mm³: what a straight descent to there removes, as the
    /// map knows it (never less than the real stock's).
    fn volume_under(&self, p: DVec2, z: f64, tool: &Tool) -> f64 {
        let r = 0.5 * tool.diameter;
        let rc = tool.corner_radius.clamp(0.0, r);
        // Cells wholly under the tool: a wall the tool's rim only touches
        // (a boundary pass beside it) is not stock under a descent.
        let inside = r - self.cell * std::f64::consts::FRAC_1_SQRT_2;
        let (i0, i1, j0, j1) = self.cells(p, p, r);
        let mut v = 0.0;
        for j in j0..j1 {
            for i in i0..i1 {
                let rho = self.centre(i, j).distance(p);
                if rho > inside {
                    continue;
                }
                let u = rho - (r - rc);
                let lift = if u <= 0.0 {
                    0.0
                } else {
                    rc - (rc * rc - u * u).max(0.0).sqrt()
                };
                let h = self.h[j * self.nx + i];
                if h.is_finite() {
                    v += (h - z - lift).max(0.0);
                }
            }
        }
        v * self.cell * self.cell
    }

    /// Highest stock in any cell that a disc of radius `rho` swept from `a`
    /// to `b` may touch.
    fn highest(&self, a: DVec2, b: DVec2, rho: f64) -> f64 {
        let reach = rho + self.cell * std::f64::consts::FRAC_1_SQRT_2;
        let mut top = f64::NEG_INFINITY;
        for (p, q) in pieces(a, b) {
            let (i0, i1, j0, j1) = self.cells(p, q, reach);
            for j in j0..j1 {
                for i in i0..i1 {
                    let k = j * self.nx + i;
                    if self.h[k] > top
                        && crate::geom::dist_point_seg(self.centre(i, j), p, q) <= reach
                    {
                        top = self.h[k];
                    }
                }
            }
        }
        top
    }
}

/// A segment in pieces no longer than [`PIECE`].
fn pieces(a: DVec2, b: DVec2) -> impl Iterator<Item = (DVec2, DVec2)> {
    let n = ((a.distance(b) / PIECE).ceil() as usize).max(1);
    (0..n).map(move |k| {
        (
            a.lerp(b, k as f64 / n as f64),
            a.lerp(b, (k + 1) as f64 / n as f64),
        )
    })
}

/// The tool's parts as vertical cylinders: (radius, height of their lower
/// end above the tip).
fn cylinders(t: &Tool) -> Vec<(f64, f64)> {
    let mut c = vec![(0.5 * t.diameter, 0.0)];
    if t.stickout > t.flute_length && t.shank_diameter > 0.0 {
        c.push((0.5 * t.shank_diameter, t.flute_length));
    }
    if t.holder_diameter > 0.0 && t.holder_length > 0.0 {
        c.push((0.5 * t.holder_diameter, t.stickout));
    }
    c
}

/// The lowest tip height (along up) at which the tool, its shank and its
/// holder clear the stock by `clearance` moving straight from `a` to `b`.
fn lowest(map: &HeightMap, a: DVec2, b: DVec2, cyl: &[(f64, f64)], clearance: f64) -> f64 {
    cyl.iter()
        .map(|&(rho, above)| map.highest(a, b, rho) - above)
        .fold(f64::NEG_INFINITY, f64::max)
        + clearance
}

/// A feature's frame, to map an operation's moves to the local moves stage 7
/// made them from (and time them the same way).
struct Local {
    origin: DVec3,
    x: DVec3,
    y: DVec3,
    z: DVec3,
}

impl Local {
    fn new(f: &thinplan_plan::MachiningFeature) -> Self {
        let fr = &f.shape.frame;
        let z = fr.z.normalize_or_zero();
        let x = (fr.x - z * fr.x.dot(z)).normalize_or_zero();
        Local {
            origin: fr.origin,
            x,
            y: z.cross(x),
            z,
        }
    }
    fn point(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.x), d.dot(self.y), d.dot(self.z))
    }
    fn part(&self, p: DVec3) -> DVec3 {
        self.origin + self.x * p.x + self.y * p.y + self.z * p.z
    }
    fn lmove(&self, m: &PathMove) -> LMove {
        LMove {
            to: self.point(m.to),
            arc: m.arc.map(|a| {
                let c = self.point(a.centre).truncate();
                let ccw = if a.axis.dot(self.z) >= 0.0 {
                    !a.clockwise
                } else {
                    a.clockwise
                };
                (c, ccw)
            }),
            kind: if m.region == Region3::Rapid {
                Kind::Rapid
            } else {
                Kind::Link
            },
        }
    }
}

fn is_vertical(a: DVec3, b: DVec3, v: &View) -> bool {
    v.xy(a).distance(v.xy(b)) < 1e-9
}

/// Lowers the links of `plan`'s operations in `plan.operation_order` on the
/// in-process stock; `part_box` is the part's box (part coordinates).
/// Records what it did in each changed operation's provenance
/// (`links_lowered`, `link_clearance_mm`) and retimes it.
pub fn lower_links(
    plan: &mut Plan,
    k: &Knowledge,
    part_box: (DVec3, DVec3),
) -> Result<LinkReport, OperationsError> {
    let mut report = LinkReport::default();
    let mk = &k.methods;
    if mk.links != LinkHeight::InProcessStock || plan.operation_order.is_empty() {
        return Ok(report);
    }
    let (_, tools, limits) = resources(plan, k)?;
    let rapid_cap = limits.v_max.iter().copied().fold(0.0, f64::max);
    let clearance = mk.safe_clearance;
    let view = View::new(plan.setup.up);

    // The map: the part's box and every feature's box at their tops, with
    // room for the widest holder around everything the tools visit.
    let corners = |lo: DVec3, hi: DVec3| {
        (0..8).map(move |c| {
            DVec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            )
        })
    };
    // Plan-view box and top of points, grown by `grow` across.
    let plan_box = |pts: &mut dyn Iterator<Item = DVec3>, grow: f64| {
        let (mut lo, mut hi, mut top) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
        for p in pts {
            lo = lo.min(view.xy(p));
            hi = hi.max(view.xy(p));
            top = top.max(view.z(p));
        }
        (lo.x <= hi.x && lo.y <= hi.y && top.is_finite())
            .then(|| (lo - DVec2::splat(grow), hi + DVec2::splat(grow), top))
    };
    let mut boxes: Vec<(DVec2, DVec2, f64)> = Vec::new();
    boxes.extend(plan_box(&mut corners(part_box.0, part_box.1), 0.0));
    for f in &plan.machining_features {
        let l = Local::new(f);
        let s = &f.shape;
        let mut pts = s
            .region
            .outer
            .vertices
            .iter()
            .flat_map(|v| [s.z_min, s.z_max].map(|z| l.part(DVec3::new(v.x, v.y, z))));
        // Arcs bulge past their vertices by at most half their chord.
        let grow = crate::geom::loop_edges(&s.region.outer)
            .iter()
            .filter(|e| e.bulge.abs() > 1e-12)
            .map(|e| 0.5 * e.a.distance(e.b) * e.bulge.abs().max(1.0))
            .fold(0.0, f64::max);
        boxes.extend(plan_box(&mut pts, grow));
    }
    let reach = tools
        .tools
        .iter()
        .flat_map(|t| cylinders(t).into_iter().map(|c| c.0))
        .fold(0.0, f64::max)
        + 2.0 * CELL;
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for (a, b, _) in &boxes {
        lo = lo.min(*a);
        hi = hi.max(*b);
    }
    for op in &plan.operations {
        for p in std::iter::once(op.start).chain(op.moves.iter().map(|m| m.to)) {
            lo = lo.min(view.xy(p));
            hi = hi.max(view.xy(p));
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return Ok(report);
    }
    let mut map = HeightMap::new(lo - DVec2::splat(reach), hi + DVec2::splat(reach));
    for (a, b, top) in &boxes {
        map.raise_box(*a, *b, *top);
    }

    let index: BTreeMap<OperationId, usize> = plan
        .operations
        .iter()
        .enumerate()
        .map(|(i, o)| (o.id, i))
        .collect();
    let features: BTreeMap<_, usize> = plan
        .machining_features
        .iter()
        .enumerate()
        .map(|(i, f)| (f.id, i))
        .collect();
    let order: Vec<usize> = plan
        .operation_order
        .iter()
        .filter_map(|id| index.get(id).copied())
        .collect();
    let mut changed = vec![false; plan.operations.len()];
    let mut prev: Option<usize> = None;
    // Operations whose method is not in the knowledge (hand-made) ramp at
    // the shallowest angle any method allows.
    let min_entry_angle = mk
        .methods
        .iter()
        .map(|m| m.entry.angle_deg())
        .fold(f64::INFINITY, f64::min)
        .min(45.0);
    // A straight descent may take what the verification lets a plunge
    // take; half of it, as this map is coarser than the replay.
    let max_plunge = 0.5 * k.verification.max_plunge_mm3;
    for &oi in &order {
        let op = &plan.operations[oi];
        let (op_tool, op_start) = (op.tool.clone(), op.start);
        let tool = tools.tools.iter().find(|t| t.id == op.tool);
        let local = features
            .get(&op.feature)
            .map(|&fi| Local::new(&plan.machining_features[fi]));
        let (Some(tool), Some(local)) = (tool, local) else {
            report.skipped.push(op.id);
            prev = None;
            continue;
        };
        if op.tool_axis.normalize_or_zero().dot(view.up) < 1.0 - 1e-9
            || local.z.dot(view.up) < 1.0 - 1e-9
        {
            report.skipped.push(op.id);
            prev = None;
            continue;
        }
        let cyl = cylinders(tool);
        let mut start = op_start;
        let mut link_z = None;

        // The link from the previous operation of the same tool: straight
        // across from the top of its retract to above this start.
        if let Some(pi) = prev.filter(|&p| plan.operations[p].tool == op_tool) {
            let p = &plan.operations[pi];
            let n = p.moves.len();
            let retract = p.moves.last().filter(|m| m.region == Region3::Rapid);
            let foot = match n {
                0 => None,
                1 => Some(p.start),
                _ => Some(p.moves[n - 2].to),
            };
            // This operation must begin by going straight down from its
            // start (stage 7's always do): nothing else was checked there.
            let descends = op.moves.first().is_some_and(|m| {
                m.region == Region3::Rapid
                    && m.arc.is_none()
                    && is_vertical(op_start, m.to, &view)
                    && view.z(m.to) <= view.z(op_start)
            });
            if let (Some(r), Some(foot), true) = (retract, foot, descends) {
                if is_vertical(foot, r.to, &view) && view.z(r.to) >= view.z(foot) {
                    let old = view.z(r.to).min(view.z(op_start));
                    let l = lowest(&map, view.xy(foot), view.xy(op_start), &cyl, clearance)
                        .max(view.z(foot))
                        .min(old);
                    // Planned even at stage 7's own height: the post's
                    // link would climb over its clearance height instead.
                    if l.is_finite() {
                        let l = if l > old - MIN_GAIN { old } else { l };
                        if view.z(r.to) > l + 1e-12 {
                            let end = r.to + view.up * (l - view.z(r.to));
                            let pm = plan.operations[pi].moves.last_mut().expect("a retract");
                            pm.to = end;
                            changed[pi] = true;
                        }
                        start = op_start + view.up * (l - view.z(op_start));
                        link_z = Some(l);
                        report.between += 1;
                    }
                }
            }
        }
        let op = &plan.operations[oi];
        let entry_angle = mk
            .methods
            .iter()
            .find(|m| m.id == op.method)
            .map_or(min_entry_angle, |m| m.entry.angle_deg());
        let mut ramps = 0;
        let (moves, inside) = lower_inside(
            op,
            start,
            tool,
            &cyl,
            &mut map,
            &local,
            &view,
            clearance,
            (entry_angle, max_plunge),
            &mut ramps,
        );
        report.inside += inside;
        report.ramped += ramps;
        if ramps > 0 {
            plan.operations[oi]
                .provenance
                .values
                .insert("entries_ramped".into(), ramps as f64);
        }
        if inside > 0 || link_z.is_some() || ramps > 0 {
            let op = &mut plan.operations[oi];
            op.start = start;
            op.moves = moves;
            op.link_z = link_z;
            op.provenance
                .values
                .insert("links_lowered".into(), inside as f64);
            op.provenance
                .values
                .insert("link_clearance_mm".into(), clearance);
            changed[oi] = true;
        }
        prev = Some(oi);
    }
    for (oi, c) in changed.iter().enumerate() {
        if *c {
            retime(plan, oi, rapid_cap, &limits);
        }
    }
    Ok(report)
}

/// Records the length and time of operation `oi` as its moves now stand.
fn retime(plan: &mut Plan, oi: usize, rapid_cap: f64, limits: &MachineLimits) {
    let op = &plan.operations[oi];
    let Some(f) = plan.machining_features.iter().find(|f| f.id == op.feature) else {
        return;
    };
    let local = Local::new(f);
    let lm: Vec<(LMove, f64)> = op
        .moves
        .iter()
        .map(|m| {
            let cap = if m.region == Region3::Rapid {
                rapid_cap
            } else {
                m.feed / 60.0
            };
            (local.lmove(m), cap)
        })
        .collect();
    let (length, time) = length_and_time(
        local.point(op.start),
        lm.iter().map(|(m, c)| (m, *c)),
        limits,
    );
    let op = &mut plan.operations[oi];
    op.provenance.values.insert("length_mm".into(), length);
    op.provenance.values.insert("time_s".into(), time);
}

/// Stage 9's repair of an operation whose replay found a feed plunge
/// `plunge_depth` deep into stock that stage 8's map took for air (it is
/// coarser than the replay): every straight feed descent of operation `id`
/// becomes a ramp at its method's entry angle (the shallowest any method
/// allows for one not in the knowledge), and the operation is retimed.
/// A ramp starts just above the highest stock the descent can meet: the
/// top of the operation's feature (what stands above it was cut before, as
/// stage 6 ordered it), or the plunge's depth above the highest descent's
/// end if that is higher; the replay judges the result. Records
/// `entries_ramped_on_replay`; returns how many descents it ramped (0:
/// none could be, the operation is as it was).
pub fn ramp_every_descent(
    plan: &mut Plan,
    k: &Knowledge,
    id: OperationId,
    plunge_depth: f64,
) -> Result<usize, OperationsError> {
    let (_, tools, limits) = resources(plan, k)?;
    let rapid_cap = limits.v_max.iter().copied().fold(0.0, f64::max);
    let view = View::new(plan.setup.up);
    let Some(oi) = plan.operations.iter().position(|o| o.id == id) else {
        return Ok(0);
    };
    let op = &plan.operations[oi];
    let Some(tool) = tools.tools.iter().find(|t| t.id == op.tool) else {
        return Ok(0);
    };
    let angle = k
        .methods
        .methods
        .iter()
        .find(|m| m.id == op.method)
        .map(|m| m.entry.angle_deg())
        .unwrap_or_else(|| {
            k.methods
                .methods
                .iter()
                .map(|m| m.entry.angle_deg())
                .fold(45.0, f64::min)
        });
    let down = |from: DVec3, m: &PathMove| {
        m.arc.is_none() && is_vertical(from, m.to, &view) && view.z(m.to) < view.z(from) - 1e-6
    };
    let stock_top = stock_top(plan, op, plunge_depth, &view, down);
    let mut out = Vec::with_capacity(op.moves.len());
    let mut pos = op.start;
    let mut ramped = 0;
    let mut i = 0;
    while i < op.moves.len() {
        let m = &op.moves[i];
        // Fed (G1) straight descents, whatever region they belong to.
        if m.feed == 0.0 || !down(pos, m) {
            out.push(m.clone());
            pos = m.to;
            i += 1;
            continue;
        }
        // The fed descent and the straight descents right after it (the
        // descent to the top of a ramp stage 8 planned) are one descent.
        let mut j = i + 1;
        while j < op.moves.len() && down(op.moves[j - 1].to, &op.moves[j]) {
            j += 1;
        }
        let to = op.moves[j - 1].to;
        let ramp = crate::ramps::ramp_entry(
            pos,
            to,
            stock_top,
            &op.moves[j..],
            angle,
            RAMP_RUN_DIAMETERS * tool.diameter,
            &view,
        );
        match ramp {
            Some(r) => {
                out.extend(r);
                ramped += 1;
                i = j;
            }
            None => {
                out.push(m.clone());
                i += 1;
            }
        }
        pos = out.last().map_or(pos, |m| m.to);
    }
    if ramped > 0 {
        let op = &mut plan.operations[oi];
        op.moves = out;
        op.provenance
            .values
            .insert("entries_ramped_on_replay".into(), ramped as f64);
        retime(plan, oi, rapid_cap, &limits);
    }
    Ok(ramped)
}

/// The highest stock (set-up height) a descent of `op` can meet, as
/// [`ramp_every_descent`] bounds it: its feature's top, or `plunge_depth`
/// above the highest end of its fed descents (`down`) if that is higher.
fn stock_top(
    plan: &Plan,
    op: &Operation,
    plunge_depth: f64,
    view: &View,
    down: impl Fn(DVec3, &PathMove) -> bool,
) -> f64 {
    let feature_top = plan
        .machining_features
        .iter()
        .find(|f| f.id == op.feature)
        .map_or(f64::NEG_INFINITY, |f| {
            let l = Local::new(f);
            f.shape
                .region
                .outer
                .vertices
                .iter()
                .map(|v| view.z(l.part(DVec3::new(v.x, v.y, f.shape.z_max))))
                .fold(f64::NEG_INFINITY, f64::max)
        });
    let mut pos = op.start;
    let mut highest_end = f64::NEG_INFINITY;
    for m in &op.moves {
        if m.feed > 0.0 && down(pos, m) {
            highest_end = highest_end.max(view.z(m.to));
        }
        pos = m.to;
    }
    let top = feature_top.max(highest_end + plunge_depth);
    // No feature and no descent: every descent starts where it is.
    if top.is_finite() {
        top
    } else {
        f64::INFINITY
    }
}

/// Stage 9's remedy for a rapid that met stock: every rapid link inside
/// operation `id` that travels across below `top` (set-up frame height)
/// goes up to `top`, across, and straight down to where it ended, as
/// stage 7 planned links before stage 8 lowered them on its model of the
/// in-process stock. Records `links_raised_on_replay` and retimes the
/// operation; returns how many links it raised (0: the operation is as it
/// was).
pub fn raise_links(
    plan: &mut Plan,
    k: &Knowledge,
    id: OperationId,
    top: f64,
) -> Result<usize, OperationsError> {
    let (_, _, limits) = resources(plan, k)?;
    let rapid_cap = limits.v_max.iter().copied().fold(0.0, f64::max);
    let view = View::new(plan.setup.up);
    let Some(oi) = plan.operations.iter().position(|o| o.id == id) else {
        return Ok(0);
    };
    let op = &plan.operations[oi];
    let rapid = |m: &PathMove| m.region == Region3::Rapid && m.arc.is_none();
    let mut out: Vec<PathMove> = Vec::with_capacity(op.moves.len() + 2);
    let mut pos = op.start;
    let mut raised = 0;
    let mut i = 0;
    while i < op.moves.len() {
        if !rapid(&op.moves[i]) {
            out.push(op.moves[i].clone());
            pos = op.moves[i].to;
            i += 1;
            continue;
        }
        let mut j = i;
        while j < op.moves.len() && rapid(&op.moves[j]) {
            j += 1;
        }
        let run = &op.moves[i..j];
        let end = run[run.len() - 1].to;
        let across = view.xy(pos).distance(view.xy(end)) > 1e-9;
        let low = std::iter::once(pos)
            .chain(run.iter().map(|m| m.to))
            .any(|p| view.z(p) < top - 1e-9);
        if across && low {
            let template = run[0].clone();
            let at = |p: DVec3| p + view.up * (top - view.z(p));
            for to in [at(pos), at(end), end] {
                out.push(PathMove {
                    to,
                    ..template.clone()
                });
            }
            raised += 1;
        } else {
            out.extend(run.iter().cloned());
        }
        pos = end;
        i = j;
    }
    if raised > 0 {
        let op = &mut plan.operations[oi];
        op.moves = out;
        op.provenance
            .values
            .insert("links_raised_on_replay".into(), raised as f64);
        retime(plan, oi, rapid_cap, &limits);
    }
    Ok(raised)
}

/// One operation's moves from `start` with each rapid up–across–down link
/// lowered, the descent from `start` included; cuts the map as it goes.
/// Returns the moves and how many links it lowered.
#[allow(clippy::too_many_arguments)]
fn lower_inside(
    op: &Operation,
    start: DVec3,
    tool: &Tool,
    cyl: &[(f64, f64)],
    map: &mut HeightMap,
    local: &Local,
    view: &View,
    clearance: f64,
    entry: (f64, f64),
    ramps: &mut usize,
) -> (Vec<PathMove>, usize) {
    let mv = &op.moves;
    let mut out: Vec<PathMove> = Vec::with_capacity(mv.len());
    let mut pos = start;
    let mut lowered = 0;
    let rapid = |m: &PathMove| m.region == Region3::Rapid && m.arc.is_none();
    // Where a rapid descent at `q` may end: clear of the stock there, not
    // below the feed descent that follows, never below stage 7's end.
    let descent = |map: &HeightMap, q: DVec3, old: f64, next: Option<&PathMove>| {
        let below = next
            .filter(|n| n.region != Region3::Rapid && is_vertical(q, n.to, view))
            .map_or(old, |n| view.z(n.to));
        lowest(map, view.xy(q), view.xy(q), cyl, clearance)
            .max(below)
            .min(old)
    };
    let mut i = 0;
    // The first descent: from a lowered start, and in any case rapid down
    // to the clearance above the stock there (not only to the stock's top),
    // feeding the rest.
    if let Some(m) = mv
        .first()
        .filter(|m| rapid(m) && is_vertical(start, m.to, view) && view.z(m.to) <= view.z(op.start))
    {
        let d = descent(map, m.to, view.z(m.to), mv.get(1)).min(view.z(start));
        let moved = (start - op.start).length() > 1e-12;
        if moved || d < view.z(m.to) - MIN_GAIN {
            if d < view.z(start) - 1e-9 {
                let mut m = m.clone();
                m.to += view.up * (d - view.z(m.to));
                pos = m.to;
                out.push(m);
            }
            if d < view.z(m.to) - MIN_GAIN {
                lowered += 1;
            }
            i = 1;
        }
    }
    while i < mv.len() {
        if i + 2 < mv.len() && rapid(&mv[i]) && rapid(&mv[i + 1]) && rapid(&mv[i + 2]) {
            let (up, across, down) = (&mv[i], &mv[i + 1], &mv[i + 2]);
            let h_old = view.z(up.to);
            if is_vertical(pos, up.to, view)
                && h_old >= view.z(pos)
                && (view.z(across.to) - h_old).abs() < 1e-9
                && is_vertical(across.to, down.to, view)
                && view.z(down.to) <= h_old
            {
                let h = lowest(map, view.xy(pos), view.xy(across.to), cyl, clearance)
                    .max(view.z(pos))
                    .min(h_old);
                if h < h_old - MIN_GAIN {
                    let lift = |p: DVec3, z: f64| p + view.up * (z - view.z(p));
                    if h > view.z(pos) + 1e-9 {
                        out.push(PathMove {
                            to: lift(pos, h),
                            ..up.clone()
                        });
                    }
                    let over = lift(across.to, h);
                    out.push(PathMove {
                        to: over,
                        ..*across
                    });
                    let d = descent(map, down.to, view.z(down.to), mv.get(i + 3)).min(h);
                    let mut end = over;
                    if d < h - 1e-9 {
                        end = lift(down.to, d);
                        out.push(PathMove { to: end, ..*down });
                    }
                    pos = end;
                    lowered += 1;
                    i += 3;
                    continue;
                }
            }
        }
        let m = &mv[i];
        if let Some(ramp) = plunge_as_ramp(pos, m, &mv[i + 1..], map, tool, entry, view) {
            for r in ramp {
                cut_along(map, pos, &r, tool, local, view);
                pos = r.to;
                out.push(r);
            }
            *ramps += 1;
            i += 1;
            continue;
        }
        cut_along(map, pos, m, tool, local, view);
        pos = m.to;
        out.push(m.clone());
        i += 1;
    }
    (out, lowered)
}

/// Lowers the map where the feed move `m` from `pos` cuts (arcs as chords
/// within [`CHORD`]).
fn cut_along(
    map: &mut HeightMap,
    pos: DVec3,
    m: &PathMove,
    tool: &Tool,
    local: &Local,
    view: &View,
) {
    if m.region == Region3::Rapid {
        return;
    }
    let pts: Vec<DVec3> = if m.arc.is_none() {
        vec![m.to]
    } else {
        move_points(local.point(pos), &local.lmove(m), CHORD)
            .into_iter()
            .map(|p| local.part(p))
            .collect()
    };
    let mut a = pos;
    for b in pts {
        map.cut(view.xy(a), view.xy(b), view.z(a).max(view.z(b)), tool);
        a = b;
    }
}

/// `m` as a ramp entry ([`crate::ramps`]) when it is a straight feed
/// descent from `pos` and the map holds stock under the tool above its end.
fn plunge_as_ramp(
    pos: DVec3,
    m: &PathMove,
    next: &[PathMove],
    map: &HeightMap,
    tool: &Tool,
    (angle_deg, max_plunge_mm3): (f64, f64),
    view: &View,
) -> Option<Vec<PathMove>> {
    if m.region == Region3::Rapid
        || m.arc.is_some()
        || !is_vertical(pos, m.to, view)
        || view.z(m.to) >= view.z(pos) - 1e-9
    {
        return None;
    }
    if map.volume_under(view.xy(m.to), view.z(m.to), tool) <= max_plunge_mm3 {
        return None;
    }
    // The highest stock wholly under the tool, as `volume_under` counts it.
    let under = 0.5 * tool.diameter - map.cell * std::f64::consts::SQRT_2;
    let stock = map.highest(view.xy(m.to), view.xy(m.to), under.max(0.0));
    crate::ramps::ramp_entry(
        pos,
        m.to,
        stock,
        next,
        angle_deg,
        RAMP_RUN_DIAMETERS * tool.diameter,
        view,
    )
}

/// Longest stretch of a ramp entry, in tool diameters.
const RAMP_RUN_DIAMETERS: f64 = 4.0;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tool(d: f64, rc: f64) -> Tool {
        crate::test_tool(d, rc)
    }

    /// Height of a bull-nose tool's lower surface above its tip at
    /// horizontal distance `rho` from its axis; `None` beyond its radius.
    fn surface(t: &Tool, rho: f64) -> Option<f64> {
        let (r, rc) = (0.5 * t.diameter, t.corner_radius);
        if rho > r {
            None
        } else if rho <= r - rc {
            Some(0.0)
        } else {
            let u = rho - (r - rc);
            Some(rc - (rc * rc - u * u).max(0.0).sqrt())
        }
    }

    proptest! {
        /// No cell is ever lower than the true stock anywhere in it: the
        /// blank's top minus the exact swept bull-nose, sampled at random
        /// points.
        #[test]
        fn the_map_never_lies_below_the_stock(
            d in 2.0f64..20.0,
            rc_frac in 0.0f64..0.5,
            moves in prop::collection::vec((0.0f64..60.0, 0.0f64..60.0, 0.0f64..20.0), 2..8),
            probes in prop::collection::vec((0.0f64..60.0, 0.0f64..60.0), 50),
        ) {
            let t = tool(d, rc_frac * d);
            let top = 20.0;
            let mut map = HeightMap::new(DVec2::ZERO, DVec2::splat(60.0));
            map.raise_box(DVec2::ZERO, DVec2::splat(60.0), top);
            let segs: Vec<(DVec2, DVec2, f64)> = moves
                .windows(2)
                .map(|w| (DVec2::new(w[0].0, w[0].1), DVec2::new(w[1].0, w[1].1), w[1].2))
                .collect();
            for (a, b, z) in &segs {
                map.cut(*a, *b, *z, &t);
            }
            for (x, y) in probes {
                let p = DVec2::new(x, y);
                let truth = segs
                    .iter()
                    .filter_map(|(a, b, z)| {
                        surface(&t, crate::geom::dist_point_seg(p, *a, *b)).map(|s| z + s)
                    })
                    .fold(top, f64::min);
                let i = ((x / CELL) as usize).min(map.nx - 1);
                let j = ((y / CELL) as usize).min(map.ny - 1);
                prop_assert!(map.h[j * map.nx + i] >= truth - 1e-9,
                    "cell ({i}, {j}) at {} below the stock {truth} at {p}", map.h[j * map.nx + i]);
            }
        }
    }

    /// A link beside a column rises for the part of the tool that passes
    /// over it: the tool when it crosses the column, the holder when only
    /// the holder's radius reaches it.
    #[test]
    fn a_link_clears_the_stock_under_tool_and_holder() {
        let t = tool(10.0, 0.0);
        let cyl = cylinders(&t);
        let mut map = HeightMap::new(DVec2::ZERO, DVec2::splat(100.0));
        // A floor at 0 with a column 10 × 10 at (45..55, 45..55) up to 150.
        map.raise_box(DVec2::ZERO, DVec2::splat(100.0), 0.0);
        map.raise_box(DVec2::splat(45.0), DVec2::splat(55.0), 150.0);
        let clear = 5.0;
        // Far from the column: the floor plus the clearance.
        let far = lowest(
            &map,
            DVec2::new(5.0, 5.0),
            DVec2::new(95.0, 5.0),
            &cyl,
            clear,
        );
        assert!((far - 5.0).abs() < 1e-9, "{far}");
        // Across it: over its top.
        let over = lowest(
            &map,
            DVec2::new(5.0, 50.0),
            DVec2::new(95.0, 50.0),
            &cyl,
            clear,
        );
        assert!((over - 155.0).abs() < 1e-9, "{over}");
        // 15 mm beside it (beyond the tool's 5 and the shank's 5, within the
        // holder's 20): the holder, 120 above the tip, must clear 150.
        let beside = lowest(
            &map,
            DVec2::new(5.0, 70.0),
            DVec2::new(95.0, 70.0),
            &cyl,
            clear,
        );
        assert!((beside - 35.0).abs() < 1e-9, "{beside}");
        // Beyond the holder's reach of it, the floor again.
        let clear_of = lowest(
            &map,
            DVec2::new(5.0, 80.0),
            DVec2::new(95.0, 80.0),
            &cyl,
            clear,
        );
        assert!((clear_of - 5.0).abs() < 1e-9, "{clear_of}");
    }

    /// A part kilometres long gets coarser cells, never more than
    /// [`MAX_CELLS`], and the map still holds the stock under a cut.
    #[test]
    fn a_huge_part_gets_coarser_cells_not_more_of_them() {
        let mut map = HeightMap::new(DVec2::ZERO, DVec2::new(10_000.0, 2_000.0));
        assert!(map.cell > CELL && (map.nx * map.ny) as f64 <= MAX_CELLS * 1.01);
        map.raise_box(DVec2::ZERO, DVec2::new(10_000.0, 2_000.0), 20.0);
        let t = tool(20.0, 1.0);
        map.cut(DVec2::new(100.0, 100.0), DVec2::new(200.0, 100.0), 5.0, &t);
        // Right under the tool's path: down to the tip; 12 mm aside: untouched.
        assert_eq!(
            map.highest(DVec2::new(150.0, 100.0), DVec2::new(150.0, 100.0), 0.0),
            5.0
        );
        assert_eq!(
            map.highest(DVec2::new(150.0, 112.0), DVec2::new(150.0, 112.0), 0.0),
            20.0
        );
    }

    /// Cutting lowers only cells the tool covers whole, and not cells whose
    /// stock stood above the flutes.
    #[test]
    fn a_cut_lowers_the_cells_under_the_tool_only() {
        let mut t = tool(10.0, 2.0);
        let mut map = HeightMap::new(DVec2::ZERO, DVec2::splat(40.0));
        map.raise_box(DVec2::ZERO, DVec2::splat(40.0), 20.0);
        map.cut(DVec2::new(10.0, 20.0), DVec2::new(30.0, 20.0), 4.0, &t);
        let h = |map: &HeightMap, x: f64, y: f64| map.h[(y as usize) * map.nx + x as usize];
        assert_eq!(h(&map, 20.0, 20.0), 4.0, "under the flat bottom");
        assert_eq!(
            h(&map, 20.0, 23.5),
            6.0,
            "under the corner: tip plus its radius"
        );
        assert_eq!(h(&map, 20.0, 26.0), 20.0, "beyond the tool");
        // Short flutes: a cut 30 below the top does not reach the top.
        t.flute_length = 10.0;
        map.cut(DVec2::new(10.0, 5.0), DVec2::new(30.0, 5.0), -15.0, &t);
        assert_eq!(h(&map, 20.0, 5.0), 20.0);
    }
}
