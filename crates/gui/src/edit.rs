//! Machining-feature edits as plain functions on a plan:
//! split at a height, split by a line in plan, merge two adjacent features
//! of one owner, and a new feature from a drawn profile. [`AppState`]
//! wraps each in one undoable history entry; here nothing is drawn and
//! nothing is undone, so the geometry is testable on its own. On `Err` a
//! function may have changed the plan part-way (a cycle is found after the
//! change): callers edit a copy, as `AppState::edit` does.
//!
//! Profiles keep their arcs: the boolean work is cavalier_contours' (the
//! library the operations and pocketing crates use), so a split's pieces
//! add up to the original's area exactly, not to a chord approximation.
//!
//! [`AppState`]: crate::AppState

use cavalier_contours::polyline::{
    BooleanOp, BooleanResultInfo, PlineCreation, PlineOrientation, PlineSource, PlineSourceMut,
    Polyline,
};
use glam::{DVec2, DVec3};
use thinplan_plan::{
    Adjacency, Constraint, ConstraintKind, MachiningFeature, MachiningFeatureId, Plan, Prism,
    PrismFrame, ProfileLoop, ProfileVertex, Provenance, ProvenanceSource, Region, Stage,
};

/// Lengths below this (mm) are one point: vertices, z levels, gaps.
const EPS: f64 = 1e-6;
/// Coordinates a user may give (mm): a kilometre is beyond any part, and
/// larger numbers would overflow the boolean work's bounds.
const FAR: f64 = 1e6;

fn reasonable(v: f64) -> bool {
    v.is_finite() && v.abs() < FAR
}
/// Areas below this (mm²) are slivers: a shared edge or a grazing cut.
/// (A two-vertex loop with an arc is a real piece: a lens.)
const AREA_EPS: f64 = 1e-9;

type Pline = Polyline<f64>;

/// The stage an edit of machining features invalidates from: features
/// already resolved keep the edit and only operations and order recompute;
/// before resolving, resolve itself takes the edited stage-5 features.
pub fn invalidated_from(plan: &Plan) -> Stage {
    if plan.stages_done.contains(&Stage::Resolve) {
        Stage::Operations
    } else {
        Stage::Resolve
    }
}

fn pline(l: &ProfileLoop) -> Pline {
    let mut p = Pline::with_capacity(l.vertices.len(), true);
    for v in &l.vertices {
        p.add(v.x, v.y, v.bulge);
    }
    p
}

fn profile(p: &Pline) -> ProfileLoop {
    ProfileLoop {
        vertices: p
            .iter_vertexes()
            .map(|v| ProfileVertex {
                x: v.x,
                y: v.y,
                bulge: v.bulge,
            })
            .collect(),
    }
}

fn oriented(mut p: Pline, ccw: bool) -> Pline {
    let is_ccw = p.orientation() == PlineOrientation::CounterClockwise;
    if is_ccw != ccw {
        p.invert_direction_mut();
    }
    p
}

/// The area of a loop, arcs exact (unsigned).
pub fn loop_area(l: &ProfileLoop) -> f64 {
    if l.vertices.len() < 2 {
        return 0.0;
    }
    pline(l).area().abs()
}

/// The area of a region: outer minus holes.
pub fn region_area(r: &Region) -> f64 {
    loop_area(&r.outer) - r.holes.iter().map(loop_area).sum::<f64>()
}

/// The volume a machining feature removes.
pub fn prism_volume(p: &Prism) -> f64 {
    region_area(&p.region) * (p.z_max - p.z_min).max(0.0)
}

fn next_id(plan: &Plan) -> u32 {
    plan.machining_features
        .iter()
        .map(|f| f.id.0 + 1)
        .max()
        .unwrap_or(0)
}

fn find(plan: &Plan, id: MachiningFeatureId) -> Result<usize, String> {
    plan.machining_features
        .iter()
        .position(|f| f.id == id)
        .ok_or_else(|| format!("no {id}"))
}

/// The provenance of a hand edit, naming what the feature was made by.
fn edited(rule: &str, old: &Provenance, note: String) -> Provenance {
    let mut p = Provenance::new(ProvenanceSource::User, rule);
    p.note = if old.source == ProvenanceSource::User {
        format!("{note}; {}", old.note)
    } else {
        format!("{note}; made by {}", old.rule)
    };
    p
}

/// Replaces `old` in the machining constraints: its predecessors go before
/// each of `firsts`, each of `lasts` goes before its successors, and what
/// was simultaneous with it is simultaneous with each of `together`.
/// Self-loops and repeats are dropped; the order stays the plan's.
fn redirect(
    plan: &mut Plan,
    old: MachiningFeatureId,
    firsts: &[MachiningFeatureId],
    lasts: &[MachiningFeatureId],
    together: &[MachiningFeatureId],
) {
    let mut out: Vec<Constraint<MachiningFeatureId>> = Vec::new();
    for c in std::mem::take(&mut plan.machining_constraints) {
        let expanded: Vec<Constraint<MachiningFeatureId>> = if c.first == old || c.second == old {
            let (ids, first_side) = match (c.kind, c.first == old) {
                (ConstraintKind::Simultaneous, f) => (together, f),
                (ConstraintKind::Before, true) => (lasts, true),
                (ConstraintKind::Before, false) => (firsts, false),
            };
            ids.iter()
                .map(|&n| {
                    let mut d = c.clone();
                    if first_side {
                        d.first = n;
                    } else {
                        d.second = n;
                    }
                    if d.first == old {
                        d.first = n;
                    }
                    if d.second == old {
                        d.second = n;
                    }
                    d
                })
                .collect()
        } else {
            vec![c]
        };
        for d in expanded {
            let repeat = out
                .iter()
                .any(|e| e.first == d.first && e.second == d.second && e.kind == d.kind);
            if d.first != d.second && !repeat {
                out.push(d);
            }
        }
    }
    plan.machining_constraints = out;
}

/// A cycle of `before` constraints between machining features (with
/// simultaneous groups taken as one), as the features along it; `None`
/// when the constraints can be ordered.
pub fn find_cycle(plan: &Plan) -> Option<Vec<MachiningFeatureId>> {
    let ids: Vec<MachiningFeatureId> = plan.machining_features.iter().map(|f| f.id).collect();
    let index = |id: MachiningFeatureId| ids.binary_search(&id).ok();
    let mut sorted = ids.clone();
    sorted.sort();
    if sorted != ids {
        // Not in id order: search a sorted copy instead.
        let mut p = plan.clone();
        p.machining_features.sort_by_key(|f| f.id);
        return find_cycle(&p);
    }
    let n = ids.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for c in &plan.machining_constraints {
        if let (ConstraintKind::Simultaneous, Some(a), Some(b)) =
            (c.kind, index(c.first), index(c.second))
        {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut succ: Vec<Vec<(usize, usize, usize)>> = vec![Vec::new(); n];
    for c in &plan.machining_constraints {
        if let (ConstraintKind::Before, Some(a), Some(b)) =
            (c.kind, index(c.first), index(c.second))
        {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            succ[ra].push((rb, a, b));
        }
    }
    // Depth-first search with colours; the grey path is the cycle.
    let mut colour = vec![0u8; n];
    for start in 0..n {
        if colour[start] != 0 || root(&mut parent, start) != start {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
        let mut via: Vec<usize> = Vec::new();
        colour[start] = 1;
        while let Some(&mut (u, ref mut k)) = stack.last_mut() {
            if *k < succ[u].len() {
                let (v, a, b) = succ[u][*k];
                *k += 1;
                if colour[v] == 1 {
                    // The path from v to u, closed by a → b.
                    let pos = stack.iter().position(|&(w, _)| w == v).unwrap_or(0);
                    let mut cyc: Vec<MachiningFeatureId> =
                        via[pos..].iter().map(|&i| ids[i]).collect();
                    cyc.push(ids[a]);
                    cyc.push(ids[b]);
                    cyc.dedup();
                    return Some(cyc);
                }
                if colour[v] == 0 {
                    colour[v] = 1;
                    via.push(b);
                    stack.push((v, 0));
                }
            } else {
                colour[u] = 2;
                stack.pop();
                via.pop();
            }
        }
    }
    None
}

fn refuse_cycle(plan: &Plan, what: &str) -> Result<(), String> {
    match find_cycle(plan) {
        Some(c) => {
            let names: Vec<String> = c.iter().map(|i| i.to_string()).collect();
            Err(format!(
                "refused: {what} would close the cycle {}",
                names.join(" → ")
            ))
        }
        None => Ok(()),
    }
}

/// Splits machining feature `id` at height `z` (along its own sweep axis)
/// into an upper and a lower feature; the upper one keeps the id, is cut
/// first (`before` the lower one) and takes what was simultaneous with the
/// original. Returns the ids, upper first.
pub fn split_at_height(
    plan: &mut Plan,
    id: MachiningFeatureId,
    z: f64,
) -> Result<Vec<MachiningFeatureId>, String> {
    let i = find(plan, id)?;
    let f = plan.machining_features[i].clone();
    if !(reasonable(z) && z > f.shape.z_min + EPS && z < f.shape.z_max - EPS) {
        return Err(format!(
            "{id}: split height {z} is not inside its z range {:.3}–{:.3}",
            f.shape.z_min, f.shape.z_max
        ));
    }
    let lower_id = MachiningFeatureId(next_id(plan));
    let note = format!("split of {id} at z {z}");
    let mut upper = f.clone();
    upper.shape.z_min = z;
    // The lower part lies under it and is removed after it.
    upper.bottom_adjacency = Adjacency::Feature;
    upper.provenance = edited("gui.edit.split_height", &f.provenance, note.clone());
    let mut lower = f.clone();
    lower.id = lower_id;
    lower.shape.z_max = z;
    lower.provenance = edited("gui.edit.split_height", &f.provenance, note);
    plan.machining_features[i] = upper;
    plan.machining_features.push(lower);
    redirect(plan, id, &[id], &[lower_id], &[id]);
    plan.machining_constraints.push(Constraint {
        first: id,
        second: lower_id,
        kind: ConstraintKind::Before,
        priority: 0,
        provenance: Provenance::new(ProvenanceSource::User, "gui.edit.split_height")
            .with_value("z", z),
    });
    refuse_cycle(plan, "the split")?;
    Ok(vec![id, lower_id])
}

fn bbox(r: &Region) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    // Arcs bulge out by at most half their chord: pad by the longest chord.
    let mut pad: f64 = 0.0;
    let vs = &r.outer.vertices;
    for (k, v) in vs.iter().enumerate() {
        let p = DVec2::new(v.x, v.y);
        lo = lo.min(p);
        hi = hi.max(p);
        let w = &vs[(k + 1) % vs.len()];
        if v.bulge != 0.0 {
            pad = pad.max((DVec2::new(w.x, w.y) - p).length());
        }
    }
    (lo - DVec2::splat(pad), hi + DVec2::splat(pad))
}

/// The part of `region` in the closed polygon `clip` (counter-clockwise),
/// as regions, holes kept.
fn clip_region(region: &Region, clip: &Pline) -> Result<Vec<(Pline, Vec<Pline>)>, String> {
    let outer = oriented(pline(&region.outer), true);
    let r = outer.boolean(clip, BooleanOp::And);
    if matches!(r.result_info, BooleanResultInfo::InvalidInput) {
        return Err("the profile is not a valid closed loop".into());
    }
    let mut pieces: Vec<(Pline, Vec<Pline>)> = r
        .pos_plines
        .into_iter()
        .filter(|p| p.pline.area().abs() > AREA_EPS)
        .map(|p| (oriented(p.pline, true), Vec::new()))
        .collect();
    for h in &region.holes {
        let h = oriented(pline(h), true);
        let mut next = Vec::new();
        for (o, holes) in pieces {
            let r = o.boolean(&h, BooleanOp::Not);
            match r.result_info {
                BooleanResultInfo::Disjoint => next.push((o, holes)),
                BooleanResultInfo::Pline2InsidePline1 => {
                    let mut holes = holes;
                    holes.push(h.clone());
                    next.push((o, holes));
                }
                BooleanResultInfo::Pline1InsidePline2 | BooleanResultInfo::Overlapping => {}
                BooleanResultInfo::InvalidInput => {
                    return Err("a hole of the profile is not a valid closed loop".into())
                }
                BooleanResultInfo::Intersected => {
                    let outs: Vec<Pline> = r
                        .pos_plines
                        .into_iter()
                        .filter(|p| p.pline.area().abs() > AREA_EPS)
                        .map(|p| oriented(p.pline, true))
                        .collect();
                    for po in outs {
                        let kept = holes
                            .iter()
                            .filter(|q| {
                                let v = q.at(0);
                                po.winding_number(v.pos()) != 0
                            })
                            .cloned()
                            .collect();
                        next.push((po, kept));
                    }
                }
            }
        }
        pieces = next;
    }
    Ok(pieces)
}

fn region_of(outer: &Pline, holes: &[Pline]) -> Region {
    Region {
        outer: profile(&oriented(outer.clone(), true)),
        holes: holes
            .iter()
            .map(|h| profile(&oriented(h.clone(), false)))
            .collect(),
    }
}

/// The point halfway along edge `k` of a loop (on the arc for a bulge).
fn edge_midpoint(l: &ProfileLoop, k: usize) -> DVec2 {
    let v = &l.vertices;
    let a = DVec2::new(v[k].x, v[k].y);
    let b = DVec2::new(v[(k + 1) % v.len()].x, v[(k + 1) % v.len()].y);
    let c = b - a;
    // The arc's midpoint is off the chord by the sagitta, to the right of
    // the chord for a counter-clockwise (positive) bulge.
    let right = DVec2::new(c.y, -c.x);
    (a + b) * 0.5 + right * (v[k].bulge * 0.5)
}

/// The adjacency of each edge of `new`: that of the source edge it lies
/// on, or `otherwise` for an edge the edit made (a cut).
fn adjacency_of_edges(
    new: &ProfileLoop,
    sources: &[(&ProfileLoop, &[Adjacency])],
    otherwise: Adjacency,
) -> Vec<Adjacency> {
    let plines: Vec<Pline> = sources.iter().map(|(l, _)| pline(l)).collect();
    (0..new.vertices.len())
        .map(|k| {
            let m = edge_midpoint(new, k);
            let p = cavalier_contours::core::math::Vector2::new(m.x, m.y);
            let mut best: Option<(f64, Adjacency)> = None;
            for (s, (_, adj)) in plines.iter().zip(sources) {
                if let Some(c) = s.closest_point(p, EPS) {
                    let a = adj.get(c.seg_start_index).copied().unwrap_or(otherwise);
                    if c.distance < 1e-5 && best.is_none_or(|(d, _)| c.distance < d) {
                        best = Some((c.distance, a));
                    }
                }
            }
            best.map_or(otherwise, |(_, a)| a)
        })
        .collect()
}

fn with_region(f: &MachiningFeature, region: Region, cut: Adjacency) -> MachiningFeature {
    let mut sources: Vec<(&ProfileLoop, &[Adjacency])> =
        vec![(&f.shape.region.outer, f.side_adjacency.as_slice())];
    for (h, adj) in f.shape.region.holes.iter().zip(&f.hole_adjacency) {
        sources.push((h, adj.as_slice()));
    }
    let side = adjacency_of_edges(&region.outer, &sources, cut);
    let holes = region
        .holes
        .iter()
        .map(|h| adjacency_of_edges(h, &sources, cut))
        .collect();
    let mut g = f.clone();
    g.shape.region = region;
    g.side_adjacency = side;
    g.hole_adjacency = holes;
    // The sampled sloped faces belong to the old edges: the edited feature
    // is planned as if its faces were vertical.
    g.slopes = None;
    g
}

/// Splits machining feature `id` by the line through `p` and `q` (in the
/// feature's own profile coordinates, i.e. its frame's x and y) into the
/// pieces on either side; a concave profile may give more than two. The
/// first piece keeps the id; every piece takes the original's constraints;
/// the cut edges border a feature. Returns the ids.
pub fn split_by_line(
    plan: &mut Plan,
    id: MachiningFeatureId,
    p: DVec2,
    q: DVec2,
) -> Result<Vec<MachiningFeatureId>, String> {
    let i = find(plan, id)?;
    let f = plan.machining_features[i].clone();
    let d = q - p;
    if ![p.x, p.y, q.x, q.y].into_iter().all(reasonable) || d.length() <= EPS {
        return Err(format!(
            "{id}: the split line needs two distinct points within {FAR} mm"
        ));
    }
    let d = d.normalize();
    let n = DVec2::new(-d.y, d.x);
    let (lo, hi) = bbox(&f.shape.region);
    let big = 4.0 * ((hi - lo).length() + (p - (lo + hi) * 0.5).length()) + 1.0;
    let rect = |side: f64| {
        let n = n * side;
        let mut r = Pline::with_capacity(4, true);
        for c in [
            p - d * big,
            p + d * big,
            p + d * big + n * big,
            p - d * big + n * big,
        ] {
            r.add(c.x, c.y, 0.0);
        }
        oriented(r, true)
    };
    let total = region_area(&f.shape.region);
    let mut pieces = Vec::new();
    for side in [1.0, -1.0] {
        for (o, holes) in clip_region(&f.shape.region, &rect(side))? {
            let r = region_of(&o, &holes);
            // Slivers from the line grazing a vertex are not features.
            if region_area(&r) > total * 1e-9 {
                pieces.push(r);
            }
        }
    }
    if pieces.len() < 2 {
        return Err(format!("{id}: the line does not cross its profile"));
    }
    let first = pieces.len();
    let base = next_id(plan);
    let ids: Vec<MachiningFeatureId> = (0..first)
        .map(|k| {
            if k == 0 {
                id
            } else {
                MachiningFeatureId(base + k as u32 - 1)
            }
        })
        .collect();
    let note = format!(
        "split of {id} by the line ({:.3}, {:.3})–({:.3}, {:.3})",
        p.x, p.y, q.x, q.y
    );
    for (k, r) in pieces.into_iter().enumerate() {
        let mut g = with_region(&f, r, Adjacency::Feature);
        g.id = ids[k];
        g.provenance = edited("gui.edit.split_line", &f.provenance, note.clone());
        if k == 0 {
            plan.machining_features[i] = g;
        } else {
            plan.machining_features.push(g);
        }
    }
    redirect(plan, id, &ids, &ids, &ids);
    refuse_cycle(plan, "the split")?;
    Ok(ids)
}

/// `b`'s shape in `a`'s frame (same sweep axis required).
fn into_frame(a: &PrismFrame, b: &Prism) -> Result<Prism, String> {
    let (za, zb) = (a.z.normalize_or_zero(), b.frame.z.normalize_or_zero());
    if (za - zb).length() > 1e-9 {
        return Err("they are not swept along the same axis".into());
    }
    let ya = za.cross(a.x.normalize_or_zero());
    let xb = b.frame.x.normalize_or_zero();
    let yb = zb.cross(xb);
    let map = |l: &ProfileLoop| ProfileLoop {
        vertices: l
            .vertices
            .iter()
            .map(|v| {
                let w: DVec3 = b.frame.origin + xb * v.x + yb * v.y;
                let r = w - a.origin;
                ProfileVertex {
                    x: r.dot(a.x.normalize_or_zero()),
                    y: r.dot(ya),
                    bulge: v.bulge,
                }
            })
            .collect(),
    };
    let dz = (b.frame.origin - a.origin).dot(za);
    Ok(Prism {
        frame: *a,
        region: Region {
            outer: map(&b.region.outer),
            holes: b.region.holes.iter().map(map).collect(),
        },
        z_min: b.z_min + dz,
        z_max: b.z_max + dz,
    })
}

fn same_loop(a: &ProfileLoop, b: &ProfileLoop) -> bool {
    let n = a.vertices.len();
    if n != b.vertices.len() || n == 0 {
        return false;
    }
    // The same cyclic sequence, from any start.
    (0..n).any(|s| {
        (0..n).all(|k| {
            let (u, v) = (&a.vertices[k], &b.vertices[(k + s) % n]);
            (u.x - v.x).abs() < EPS && (u.y - v.y).abs() < EPS && (u.bulge - v.bulge).abs() < 1e-9
        })
    })
}

fn worst(a: Adjacency, b: Adjacency) -> Adjacency {
    // What the tool must respect wins: product over feature over open.
    match (a, b) {
        (Adjacency::Product, _) | (_, Adjacency::Product) => Adjacency::Product,
        (Adjacency::Feature, _) | (_, Adjacency::Feature) => Adjacency::Feature,
        _ => Adjacency::Open,
    }
}

/// Merges machining features `a` and `b` of one owner when they are
/// adjacent: stacked on the same profile (one's bottom the other's top) or
/// side by side over the same heights (profiles touching, not
/// overlapping). The merged feature keeps the smaller id and both
/// features' constraints; a merge that would close a cycle is refused.
pub fn merge(
    plan: &mut Plan,
    a: MachiningFeatureId,
    b: MachiningFeatureId,
) -> Result<MachiningFeatureId, String> {
    if a == b {
        return Err(format!("{a} cannot be merged with itself"));
    }
    let (a, b) = (a.min(b), a.max(b));
    let (ia, ib) = (find(plan, a)?, find(plan, b)?);
    let (fa, fb) = (
        plan.machining_features[ia].clone(),
        plan.machining_features[ib].clone(),
    );
    if fa.owner != fb.owner {
        return Err(format!(
            "{a} and {b} have different owners ({} and {})",
            fa.owner, fb.owner
        ));
    }
    let sb = into_frame(&fa.shape.frame, &fb.shape).map_err(|e| format!("{a} and {b}: {e}"))?;
    let sa = &fa.shape;
    let same_profile = same_loop(&sa.region.outer, &sb.region.outer)
        && sa.region.holes.len() == sb.region.holes.len()
        && sa
            .region
            .holes
            .iter()
            .all(|h| sb.region.holes.iter().any(|k| same_loop(h, k)));
    let stacked = (sa.z_max - sb.z_min).abs() < EPS || (sb.z_max - sa.z_min).abs() < EPS;
    let same_heights = (sa.z_min - sb.z_min).abs() < EPS && (sa.z_max - sb.z_max).abs() < EPS;
    let note = format!("merge of {a} and {b}");
    let mut m = if same_profile && stacked {
        let mut m = fa.clone();
        m.shape.z_min = sa.z_min.min(sb.z_min);
        m.shape.z_max = sa.z_max.max(sb.z_max);
        // Sampled for one slab's edges: planned as vertical once merged.
        m.slopes = None;
        if sb.z_min < sa.z_min {
            m.bottom_adjacency = fb.bottom_adjacency;
        }
        // b's edges in a's order: the same loop, so each a edge lies on a b edge.
        let b_side = adjacency_of_edges(
            &sa.region.outer,
            &[(&sb.region.outer, fb.side_adjacency.as_slice())],
            Adjacency::Open,
        );
        m.side_adjacency = fa
            .side_adjacency
            .iter()
            .zip(b_side)
            .map(|(x, y)| worst(*x, y))
            .collect();
        m
    } else if same_heights {
        let (pa, pb) = (
            oriented(pline(&sa.region.outer), true),
            oriented(pline(&sb.region.outer), true),
        );
        let u = pa.boolean(&pb, BooleanOp::Or);
        // A shared edge comes back as a zero-area sliver: not a piece.
        let keep = |p: &cavalier_contours::polyline::BooleanResultPline<Pline>| {
            p.pline.area().abs() > AREA_EPS
        };
        let outers: Vec<Pline> = u
            .pos_plines
            .iter()
            .filter(|p| keep(p))
            .map(|p| p.pline.clone())
            .collect();
        let joined = matches!(u.result_info, BooleanResultInfo::Intersected) && outers.len() == 1;
        let (aa, ab) = (region_area(&sa.region), region_area(&sb.region));
        if !joined {
            return Err(format!(
                "{a} and {b} are not adjacent: their profiles do not touch"
            ));
        }
        let outer = oriented(outers[0].clone(), true);
        let mut holes: Vec<Pline> = u
            .neg_plines
            .iter()
            .filter(|p| keep(p))
            .map(|p| p.pline.clone())
            .collect();
        holes.extend(sa.region.holes.iter().map(pline));
        holes.extend(sb.region.holes.iter().map(pline));
        let region = region_of(&outer, &holes);
        let area = region_area(&region);
        if (area - (aa + ab)).abs() > 1e-6 * (aa + ab).max(1.0) {
            return Err(format!(
                "{a} and {b} overlap ({:.3} mm² in both): only adjacent features merge",
                aa + ab - area
            ));
        }
        let mut sources: Vec<(&ProfileLoop, &[Adjacency])> = vec![
            (&sa.region.outer, fa.side_adjacency.as_slice()),
            (&sb.region.outer, fb.side_adjacency.as_slice()),
        ];
        for (h, adj) in sa.region.holes.iter().zip(&fa.hole_adjacency) {
            sources.push((h, adj.as_slice()));
        }
        for (h, adj) in sb.region.holes.iter().zip(&fb.hole_adjacency) {
            sources.push((h, adj.as_slice()));
        }
        let mut m = fa.clone();
        m.slopes = None;
        m.side_adjacency = adjacency_of_edges(&region.outer, &sources, Adjacency::Open);
        m.hole_adjacency = region
            .holes
            .iter()
            .map(|h| adjacency_of_edges(h, &sources, Adjacency::Open))
            .collect();
        m.shape.region = region;
        m.bottom_adjacency = worst(fa.bottom_adjacency, fb.bottom_adjacency);
        m
    } else {
        return Err(format!(
            "{a} and {b} are not adjacent: neither stacked on the same profile nor side by side over the same heights"
        ));
    };
    m.provenance = edited("gui.edit.merge", &fa.provenance, note);
    plan.machining_features[ia] = m;
    plan.machining_features.remove(ib);
    redirect(plan, b, &[a], &[a], &[a]);
    refuse_cycle(plan, &format!("merging {a} and {b}"))?;
    Ok(a)
}

/// A new machining feature of `owner` from a profile drawn in the set-up's
/// plan view (`points` in the set-up frame: x, y across the up axis),
/// swept from `z_min` to `z_max` along up. Its edges and bottom are taken
/// as bordering the product, so the tool stays inside what was drawn.
pub fn add_drawn(
    plan: &mut Plan,
    owner: thinplan_plan::StiffnessFeatureId,
    points: &[DVec2],
    z_min: f64,
    z_max: f64,
) -> Result<MachiningFeatureId, String> {
    if !plan.stiffness_features.iter().any(|f| f.id == owner) {
        return Err(format!("no {owner}"));
    }
    if !(reasonable(z_min) && reasonable(z_max) && z_max > z_min + EPS) {
        return Err(format!(
            "z range {z_min}–{z_max} is empty or beyond {FAR} mm"
        ));
    }
    let mut pts: Vec<DVec2> = points.to_vec();
    pts.dedup_by(|p, q| (*p - *q).length() < EPS);
    while pts.len() > 1 && (pts[0] - pts[pts.len() - 1]).length() < EPS {
        pts.pop();
    }
    if pts.iter().any(|p| !(reasonable(p.x) && reasonable(p.y))) {
        return Err(format!("profile points must lie within {FAR} mm"));
    }
    if pts.len() < 3 {
        return Err("a profile needs at least three distinct points".into());
    }
    let mut p = Pline::with_capacity(pts.len(), true);
    for q in &pts {
        p.add(q.x, q.y, 0.0);
    }
    if p.scan_for_self_intersect() {
        return Err("the profile crosses itself".into());
    }
    if p.area().abs() < EPS {
        return Err("the profile encloses no area".into());
    }
    let p = oriented(p, true);
    let up = plan.setup.up;
    let f = thinplan_brep::Frame::from_axis_ref(DVec3::ZERO, up, None);
    let outer = profile(&p);
    let n = outer.vertices.len();
    let id = MachiningFeatureId(next_id(plan));
    let mut prov = Provenance::new(ProvenanceSource::User, "gui.edit.draw");
    prov.note = "drawn by hand; edges and bottom taken as bordering the product".into();
    plan.machining_features.push(MachiningFeature {
        id,
        owner,
        shape: Prism {
            frame: PrismFrame {
                origin: DVec3::ZERO,
                x: f.x,
                z: f.z,
            },
            region: Region {
                outer,
                holes: Vec::new(),
            },
            z_min,
            z_max,
        },
        side_adjacency: vec![Adjacency::Product; n],
        hole_adjacency: Vec::new(),
        bottom_adjacency: Adjacency::Product,
        slopes: None,
        origin: Default::default(),
        access_blocked: false,
        provenance: prov,
    });
    Ok(id)
}

/// Parses a profile typed as `x, y; x, y; …` (mm).
pub fn parse_points(text: &str) -> Result<Vec<DVec2>, String> {
    text.split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            let v: Vec<&str> = s.split(',').map(str::trim).collect();
            match v.as_slice() {
                [x, y] => match (x.parse::<f64>(), y.parse::<f64>()) {
                    (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => Ok(DVec2::new(x, y)),
                    _ => Err(format!("`{s}` is not two numbers")),
                },
                _ => Err(format!("`{s}` is not `x, y`")),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loop_points;
    use proptest::prelude::*;
    use thinplan_plan::{MachiningFeatureId as M, StiffnessFeatureId};

    /// Shoelace of the loop with every arc divided into 512 chords: an
    /// estimate independent of cavalier_contours' arc areas.
    fn chord_area(l: &ProfileLoop) -> f64 {
        let v = &l.vertices;
        let mut p = Vec::new();
        for i in 0..v.len() {
            let a = DVec2::new(v[i].x, v[i].y);
            let b = DVec2::new(v[(i + 1) % v.len()].x, v[(i + 1) % v.len()].y);
            p.push(a);
            if v[i].bulge != 0.0 {
                // Centre from the bulge: the swept angle is 4·atan(bulge).
                let theta = 4.0 * v[i].bulge.atan();
                let d = b - a;
                let n = DVec2::new(-d.y, d.x) / d.length();
                let centre = (a + b) * 0.5 + n * (d.length() * 0.5 / (theta * 0.5).tan());
                let r = (a - centre).length();
                let a0 = (a - centre).y.atan2((a - centre).x);
                for k in 1..512 {
                    let t = a0 + theta * k as f64 / 512.0;
                    p.push(centre + DVec2::new(t.cos(), t.sin()) * r);
                }
            }
        }
        let mut s = 0.0;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            s += a.x * b.y - b.x * a.y;
        }
        (s * 0.5).abs()
    }

    fn v(x: f64, y: f64, bulge: f64) -> ProfileVertex {
        ProfileVertex { x, y, bulge }
    }

    fn feature(
        id: u32,
        outer: Vec<ProfileVertex>,
        holes: Vec<Vec<ProfileVertex>>,
    ) -> MachiningFeature {
        let n = outer.len();
        let hole_adjacency = holes
            .iter()
            .map(|h| vec![Adjacency::Product; h.len()])
            .collect();
        MachiningFeature {
            id: M(id),
            owner: StiffnessFeatureId(0),
            shape: Prism {
                frame: PrismFrame {
                    origin: DVec3::new(1.0, 2.0, 3.0),
                    x: DVec3::X,
                    z: DVec3::Z,
                },
                region: Region {
                    outer: ProfileLoop { vertices: outer },
                    holes: holes
                        .into_iter()
                        .map(|vertices| ProfileLoop { vertices })
                        .collect(),
                },
                z_min: 0.0,
                z_max: 5.0,
            },
            side_adjacency: (0..n)
                .map(|k| {
                    if k == 0 {
                        Adjacency::Product
                    } else {
                        Adjacency::Open
                    }
                })
                .collect(),
            hole_adjacency,
            bottom_adjacency: Adjacency::Product,
            slopes: None,
            origin: Default::default(),
            access_blocked: false,
            provenance: Provenance::new(ProvenanceSource::Recogniser, "test"),
        }
    }

    fn plan_with(features: Vec<MachiningFeature>) -> Plan {
        use thinplan_plan::*;
        let part = PartRef {
            source: "builtin:test".into(),
            format: PartFormat::Native,
            sha256: "ab".repeat(32),
            declared_units: "mm".into(),
            summary: PartSummary {
                solids: 1,
                faces: 6,
                bbox: [10.0, 10.0, 10.0],
                volume: 1000.0,
            },
        };
        let setup = Setup {
            up: DVec3::Z,
            machine: "m".into(),
            tool_set: "t".into(),
            material: "al".into(),
            provenance: Provenance::new(ProvenanceSource::Default, "test"),
        };
        let mut p = Plan::new(part, setup);
        p.stiffness_features.push(StiffnessFeature {
            id: StiffnessFeatureId(0),
            kind: StiffnessKind::Wall,
            role: None,
            faces: vec![],
            axis: DVec3::X,
            thickness: Some(2.0),
            height: 10.0,
            length: 10.0,
            diameter: None,
            shape: None,
            access: vec![DVec3::Z],
            provenance: Provenance::new(ProvenanceSource::Recogniser, "test"),
        });
        p.machining_features = features;
        p
    }

    fn volumes(plan: &Plan, ids: &[M]) -> f64 {
        ids.iter()
            .map(|i| prism_volume(&plan.machining_features[find(plan, *i).unwrap()].shape))
            .sum()
    }

    #[test]
    fn area_with_an_arc_and_a_hole() {
        // A 10 × 10 square with a half-disc (r = 5) on top and a 2 × 2 hole.
        let outer = vec![
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            v(10.0, 10.0, 1.0),
            v(0.0, 10.0, 0.0),
        ];
        let hole = vec![
            v(4.0, 4.0, 0.0),
            v(4.0, 6.0, 0.0),
            v(6.0, 6.0, 0.0),
            v(6.0, 4.0, 0.0),
        ];
        let f = feature(0, outer, vec![hole]);
        let want = 100.0 + std::f64::consts::PI * 12.5 - 4.0;
        assert!((region_area(&f.shape.region) - want).abs() < 1e-9);
        let chords = chord_area(&f.shape.region.outer) - chord_area(&f.shape.region.holes[0]);
        assert!((chords - want).abs() < 0.5, "{chords} vs {want}");
    }

    #[test]
    fn split_at_height_stacks_two_and_orders_them() {
        let sq = vec![
            v(0.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
            v(4.0, 4.0, 0.0),
            v(0.0, 4.0, 0.0),
        ];
        let mut plan = plan_with(vec![feature(0, sq.clone(), vec![]), feature(1, sq, vec![])]);
        plan.machining_constraints.push(Constraint {
            first: M(1),
            second: M(0),
            kind: ConstraintKind::Before,
            priority: 0,
            provenance: Provenance::new(ProvenanceSource::Knowledge, "k"),
        });
        let v0 = volumes(&plan, &[M(0)]);
        let ids = split_at_height(&mut plan, M(0), 2.0).unwrap();
        assert_eq!(ids, vec![M(0), M(2)]);
        assert!((volumes(&plan, &ids) - v0).abs() < 1e-9);
        let c: Vec<(M, M)> = plan
            .machining_constraints
            .iter()
            .map(|c| (c.first, c.second))
            .collect();
        // M1 still before the upper part; upper before lower.
        assert_eq!(c, vec![(M(1), M(0)), (M(0), M(2))]);
        assert!(split_at_height(&mut plan, M(0), 9.0).is_err());
        assert!(split_at_height(&mut plan, M(0), f64::NAN).is_err());
        // And merge puts it back (volume and z range).
        assert_eq!(merge(&mut plan, M(0), M(2)).unwrap(), M(0));
        let f = &plan.machining_features[0];
        assert_eq!((f.shape.z_min, f.shape.z_max), (0.0, 5.0));
        assert!((volumes(&plan, &[M(0)]) - v0).abs() < 1e-9);
    }

    #[test]
    fn split_by_line_keeps_arcs_holes_and_adjacency() {
        let outer = vec![
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            v(10.0, 10.0, 1.0),
            v(0.0, 10.0, 0.0),
        ];
        let hole = vec![
            v(4.0, 4.0, 0.0),
            v(4.0, 6.0, 0.0),
            v(6.0, 6.0, 0.0),
            v(6.0, 4.0, 0.0),
        ];
        let mut plan = plan_with(vec![feature(0, outer, vec![hole])]);
        let v0 = volumes(&plan, &[M(0)]);
        // Through the hole and the arc.
        let ids =
            split_by_line(&mut plan, M(0), DVec2::new(5.0, -1.0), DVec2::new(5.0, 1.0)).unwrap();
        assert_eq!(ids.len(), 2);
        assert!((volumes(&plan, &ids) - v0).abs() < 1e-9 * v0);
        for f in &plan.machining_features {
            assert_eq!(f.side_adjacency.len(), f.shape.region.outer.vertices.len());
            // The cut edge borders the other piece; the bottom edge stays product.
            assert!(f.side_adjacency.contains(&Adjacency::Feature));
            assert!(f.side_adjacency.contains(&Adjacency::Product));
            assert!(f.shape.region.outer.vertices.iter().any(|v| v.bulge != 0.0));
        }
        // Merging the halves back gives the original area (hole included).
        merge(&mut plan, ids[0], ids[1]).unwrap();
        assert!((volumes(&plan, &[M(0)]) - v0).abs() < 1e-6 * v0);
        assert_eq!(plan.machining_features.len(), 1);
    }

    #[test]
    fn a_line_missing_the_profile_and_non_adjacent_merges_are_refused() {
        let sq = |x: f64| {
            vec![
                v(x, 0.0, 0.0),
                v(x + 4.0, 0.0, 0.0),
                v(x + 4.0, 4.0, 0.0),
                v(x, 4.0, 0.0),
            ]
        };
        let mut plan = plan_with(vec![
            feature(0, sq(0.0), vec![]),
            feature(1, sq(10.0), vec![]),
            feature(2, sq(2.0), vec![]),
        ]);
        let before = plan.clone();
        assert!(split_by_line(
            &mut plan,
            M(0),
            DVec2::new(20.0, 0.0),
            DVec2::new(20.0, 1.0)
        )
        .is_err());
        let mut p = before.clone();
        assert!(merge(&mut p, M(0), M(1))
            .unwrap_err()
            .contains("not adjacent"));
        let mut p = before.clone();
        assert!(merge(&mut p, M(0), M(2)).unwrap_err().contains("overlap"));
        let mut p = before.clone();
        p.machining_features[1].owner = StiffnessFeatureId(7);
        assert!(merge(&mut p, M(0), M(1)).unwrap_err().contains("owners"));
    }

    #[test]
    fn a_merge_that_closes_a_cycle_is_refused_with_it() {
        let sq = |x: f64| {
            vec![
                v(x, 0.0, 0.0),
                v(x + 4.0, 0.0, 0.0),
                v(x + 4.0, 4.0, 0.0),
                v(x, 4.0, 0.0),
            ]
        };
        let mut plan = plan_with(vec![
            feature(0, sq(0.0), vec![]),
            feature(1, sq(4.0), vec![]),
            feature(2, sq(20.0), vec![]),
        ]);
        for (a, b) in [(0, 2), (2, 1)] {
            plan.machining_constraints.push(Constraint {
                first: M(a),
                second: M(b),
                kind: ConstraintKind::Before,
                priority: 0,
                provenance: Provenance::new(ProvenanceSource::Knowledge, "k"),
            });
        }
        let e = merge(&mut plan, M(0), M(1)).unwrap_err();
        assert!(
            e.contains("cycle") && e.contains("MF0") && e.contains("MF2"),
            "{e}"
        );
    }

    #[test]
    fn drawn_profiles_are_checked() {
        let mut plan = plan_with(vec![]);
        let owner = StiffnessFeatureId(0);
        let pts = parse_points("0,0; 5,0; 5,5; 0,5").unwrap();
        // Drawn clockwise or counter-clockwise, it comes out counter-clockwise.
        let mut rev = pts.clone();
        rev.reverse();
        let id = add_drawn(&mut plan, owner, &rev, 1.0, 3.0).unwrap();
        let f = &plan.machining_features[find(&plan, id).unwrap()];
        assert!((prism_volume(&f.shape) - 50.0).abs() < 1e-9);
        assert!(pline(&f.shape.region.outer).area() > 0.0);
        let bow = parse_points("0,0; 5,5; 5,0; 0,5").unwrap();
        assert!(add_drawn(&mut plan, owner, &bow, 1.0, 3.0)
            .unwrap_err()
            .contains("crosses"));
        assert!(add_drawn(&mut plan, owner, &pts[..2], 1.0, 3.0).is_err());
        assert!(add_drawn(&mut plan, owner, &pts, 3.0, 1.0).is_err());
        assert!(parse_points("1, x").is_err());
        assert!(parse_points("1, 2, 3").is_err());
    }

    #[test]
    fn wild_numbers_are_refused_not_panicked_on() {
        let sq = vec![
            v(0.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
            v(4.0, 4.0, 0.0),
            v(0.0, 4.0, 0.0),
        ];
        let wild = [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e308, -1e300, 1e7];
        for &w in &wild {
            let mut plan = plan_with(vec![feature(0, sq.clone(), vec![])]);
            let before = plan.clone();
            assert!(split_at_height(&mut plan, M(0), w).is_err());
            assert!(
                split_by_line(&mut plan, M(0), DVec2::new(w, 0.0), DVec2::new(2.0, 1.0)).is_err()
            );
            assert!(
                split_by_line(&mut plan, M(0), DVec2::new(2.0, 0.0), DVec2::new(2.0, w)).is_err()
            );
            let pts = [DVec2::ZERO, DVec2::new(w, 0.0), DVec2::new(1.0, 1.0)];
            assert!(add_drawn(&mut plan, StiffnessFeatureId(0), &pts, 0.0, 1.0).is_err());
            assert!(add_drawn(&mut plan, StiffnessFeatureId(0), &pts[..], 0.0, w).is_err());
            assert_eq!(plan, before, "a refused edit changes nothing");
        }
    }

    proptest! {
        /// Any line across a random star-shaped profile (arcs on some
        /// edges): the pieces' volumes add up to the original's, checked
        /// with cavalier's exact areas and with a chord estimate.
        #[test]
        fn split_pieces_add_up(
            radii in proptest::collection::vec(2.0f64..10.0, 5..12),
            bulges in proptest::collection::vec(-0.3f64..0.3, 12),
            angle in 0.0f64..std::f64::consts::PI,
            offset in -1.5f64..1.5, // inside the circle every edge stays out of
        ) {
            let n = radii.len();
            let outer: Vec<ProfileVertex> = (0..n).map(|k| {
                let t = k as f64 / n as f64 * std::f64::consts::TAU;
                // Small bulges on every other edge keep the loop simple.
                v(radii[k] * t.cos(), radii[k] * t.sin(), if k % 2 == 0 { bulges[k] * 0.3 } else { 0.0 })
            }).collect();
            let mut plan = plan_with(vec![feature(0, outer, vec![])]);
            prop_assume!(!pline(&plan.machining_features[0].shape.region.outer).scan_for_self_intersect());
            let v0 = volumes(&plan, &[M(0)]);
            let chord0: f64 = chord_area(&plan.machining_features[0].shape.region.outer);
            let d = DVec2::new(angle.cos(), angle.sin());
            let p = DVec2::new(-d.y, d.x) * offset;
            let ids = split_by_line(&mut plan, M(0), p, p + d).unwrap();
            prop_assert!(ids.len() >= 2);
            prop_assert!((volumes(&plan, &ids) - v0).abs() < 1e-9 * v0);
            let chords: f64 = plan.machining_features.iter().map(|f| chord_area(&f.shape.region.outer)).sum();
            prop_assert!((chords - chord0).abs() < 1e-3 * chord0, "{} vs {}", chords, chord0);
            // Every piece on one side of the line.
            for f in &plan.machining_features {
                let s: Vec<f64> = loop_points(&f.shape.region.outer).iter().map(|q| (*q - p).perp_dot(d)).collect();
                let lo = s.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                prop_assert!(lo > -1e-6 || hi < 1e-6, "piece on both sides: {} {}", lo, hi);
            }
        }
    }
}
