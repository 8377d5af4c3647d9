//! Rest passes: boundary passes with a smaller tool along the product
//! walls, where the feature's tool leaves material. The floor rest pass
//! finishes the fillet its corner radius leaves at a product floor; the
//! wall rest passes finish wall stretches it could not come beside
//! (corners and fillets narrower than it), each smaller tool after the
//! last; stage 7's second pass finishes the orphan stretches no operation
//! came beside, run last with every other feature gone.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_knowledge::{Method, RestPass, Tool, WallRest};
use thinplan_plan::{Adjacency, MachiningFeature, Provenance, ProvenanceSource, Schedule};

use super::boundary::{boundary_chains, boundary_pass, entered_from_room};
use super::entries::{go_to, retract};
use super::plan_view::intersect_polys;
use super::region::{geometry, Geometry};
use super::safety_net::{check, Net};
use super::slopes::{slope_values, Slopes};
use super::tool_choice::conditions;
use super::{depth_below_top, tool_reach, Env, LocalOp, STEP};
use crate::geom::{inside, Edge2};
use crate::path::{Builder, Kind, Space};

/// What a band's rest passes share: the feature, its method, tool and
/// geometry, what its own operations cut, and the heights.
pub(super) struct RestCtx<'a> {
    pub(super) f: &'a MachiningFeature,
    pub(super) m: &'a Method,
    pub(super) env: &'a Env<'a>,
    pub(super) free: Option<&'a crate::free::Shapes>,
    pub(super) removed: Option<&'a crate::free::Shapes>,
    /// The cutting moves of the feature's own operations (local frame).
    pub(super) own_cuts: &'a crate::coverage::Coverage,
    /// The feature's tool and its geometry.
    pub(super) tool: &'a Tool,
    pub(super) g: &'a Geometry,
    /// The tool of the last wall rest pass and its geometry: the next one
    /// finishes what it left, with a smaller tool.
    pub(super) after: Option<(&'a Tool, &'a Geometry)>,
    pub(super) z_min: f64,
    pub(super) z_top: f64,
    /// The levels of the feature's passes, top down, the floor last.
    pub(super) levels: &'a [f64],
    pub(super) safe_z: f64,
    pub(super) rapid_floor: f64,
    /// Each candidate tool's geometry of the feature, once for both rest
    /// passes (by tool id; `None`: no room).
    pub(super) geometries: std::cell::RefCell<BTreeMap<String, Option<Geometry>>>,
}

impl<'a> RestCtx<'a> {
    /// The same context without the geometry cache.
    fn clone_shallow(&self) -> RestCtx<'a> {
        RestCtx {
            geometries: Default::default(),
            ..*self
        }
    }

    /// `t`'s geometry of the feature, computed once per tool.
    fn geometry(&self, t: &Tool) -> Option<Geometry> {
        self.geometries
            .borrow_mut()
            .entry(t.id.clone())
            .or_insert_with(|| geometry(self.f, self.m, t, self.free, self.removed, self.g.slopes))
            .clone()
    }
}

/// Points of the disc of radius `r` about `p`: its centre and rings at a
/// quarter, half, three quarters and (a hair inside) all of `r`, 24 each.
fn disc_samples(p: DVec2, r: f64) -> impl Iterator<Item = DVec2> {
    std::iter::once(p).chain((1..=4).flat_map(move |k| {
        let rho = (0.25 * k as f64 * r - if k == 4 { 1e-3 } else { 0.0 }).max(0.0);
        (0..24).map(move |j| {
            let a = std::f64::consts::TAU * j as f64 / 24.0;
            p + rho * DVec2::new(a.cos(), a.sin())
        })
    }))
}

/// How far inside what a larger tool swept the smaller tool's disc may
/// still count as inside it (mm): chains at exactly the smaller radius from
/// the walls are inside.
const HAIR: f64 = 1e-2;

/// Provenance value (1) of a wall rest pass for orphan stretches
/// ([`Rest::Orphan`]).
const ORPHAN: &str = "orphan_stretches";

/// Which rest pass: the fillet at a product floor, or stretches of product
/// walls the feature's tool could not come beside.
#[derive(Clone, Copy)]
enum Rest<'k> {
    Floor(&'k RestPass),
    Wall(&'k WallRest),
    /// Stretches of the feature's product walls that no operation of stage
    /// 7's first pass came beside within `min_left` (the coverage of all of
    /// them), at any of the feature's levels: planned with the smallest
    /// tool that has room, every other feature gone, run last.
    Orphan(&'k WallRest, &'k crate::coverage::Coverage),
}

/// A rest pass along the product walls with a smaller tool of the set.
///
/// `Floor` (`methods.<id>.rest_pass`): boundary passes at the floor with the
/// tool that has the smallest corner radius (then the largest diameter),
/// where that radius is smaller than the feature tool's by
/// `min_corner_gain`, only along stretches where the feature's tool has been
/// beside the wall (its centre region grown by the difference of the
/// radii) or a wall rest pass cut at the floor round the smaller disc, so
/// the pass cuts the fillets their corner radii leave and nothing more.
///
/// `Wall` (`methods.<id>.wall_rest`): boundary passes at every level with
/// the largest tool smaller than the feature's, only along stretches where
/// the feature's tool left more than `min_left` on the wall (its disc never
/// came that close: corners and fillets at the wall's ends narrower than
/// it). With no smaller tool in the set and `run_last`, the feature's own
/// tool, every edge that is not product taken as open (all other features
/// are gone by then): a neighbour that stood during the feature's passes
/// no longer limits the reach. Stage 7 drops such a pass where other
/// operations already cut all of it (`drop_covered_rest`).
///
/// Links stay in the space the feature's tool cleared. `None`: no tool
/// gains, or nothing is left.
fn rest_pass(c: &RestCtx, rest: Rest) -> Result<Option<LocalOp>, String> {
    let mk = &c.env.k.methods;
    let cands = rest_candidates(c, rest);
    let Some(rt) = rest_tool(c, rest, &cands) else {
        return Ok(None);
    };
    let (small, g2) = (rt.tool, &rt.g);
    let d2 = small.diameter;
    // Where the small tool's disc lies inside a disc the feature's tool
    // swept down to the floor: its centre region grown by r − r₂ (a hair
    // more, so the chains at exactly r₂ from the walls are inside). Orphan
    // stretches are cut last: the whole free space is cleared by then.
    let cleared = match rest {
        Rest::Orphan(..) => g2.centre_polys.clone(),
        _ => c.g.centre.offset(-(c.g.r - g2.r + HAIR)).polygons(STEP),
    };
    if cleared.is_empty() {
        return Ok(None);
    }
    // Run-ups and links stay where the feature's tool cut and where the
    // smaller tool has room: beside sloped faces the first does not imply
    // the second (the tools' corner radii meet the face differently).
    let room = if g2.slopes == Slopes::AsVertical {
        cleared.clone()
    } else {
        intersect_polys(&cleared, &g2.centre_polys)
    };
    // The floor pass runs where the feature's tool (or a wall rest pass,
    // `wanted`) was beside the wall; the wall pass where it stayed more
    // than `min_left` away.
    let (beside, want_inside, run_up) = match rest {
        Rest::Floor(rp) => (cleared.clone(), true, rp.run_up),
        Rest::Wall(w) => (
            c.after
                .map_or(c.g, |a| a.1)
                .centre
                .offset(-(c.after.map_or(c.g, |a| a.1).r - g2.r + w.min_left))
                .polygons(STEP),
            false,
            w.run_up,
        ),
        Rest::Orphan(w, _) => (Vec::new(), false, w.run_up),
    };
    // Which loop stretches run along product: within the boundary band
    // (half the boundary stepover), as for the feature's own passes.
    let Some(bd) = c.m.boundary.as_ref() else {
        return Ok(None);
    };
    let band = 0.5 * bd.stepover * d2;
    let mut passes = Vec::new();
    for (chain, _) in boundary_chains(g2, band, mk.spindle) {
        let ok = |e: &Edge2| wanted(c, rest, g2, &beside, want_inside, e);
        for part in accepted_parts(&chain, ok) {
            let len: f64 = part.iter().map(|e| e.length()).sum();
            if len < STEP {
                continue;
            }
            let pass = boundary_pass(&part, g2, run_up, d2, &room, mk);
            passes.push(entered_from_room(pass, g2, &room));
        }
    }
    if passes.is_empty() {
        return Ok(None);
    }
    let net = Net::new(g2);
    let clear = |p: DVec3| net.touches(p, Kind::Link).is_none();
    let space = Space {
        centre_region: &room,
        z_top: c.rapid_floor,
        safe_z: c.safe_z,
        step: STEP,
        clear: Some(&clear),
    };
    let levels: Vec<f64> = match rest {
        Rest::Floor(_) => vec![c.z_min],
        Rest::Wall(_) | Rest::Orphan(..) => c.levels.to_vec(),
    };
    let mut b = Builder::new(DVec3::ZERO);
    let mut started = false;
    for &z in &levels {
        for p in &passes {
            go_to(&mut b, &mut started, &space, p.start, z);
            b.follow(&p.segs, z, Kind::Boundary);
        }
    }
    retract(&mut b, c.safe_z);
    check(&b, g2, c.z_min, c.z_top, c.f)?;
    let (rpm, feed_rough, feed_finish) = conditions(c.env, small);
    let prov = rest_provenance(c, rest, &rt, passes.len(), &levels, rpm, feed_finish);
    Ok(Some(LocalOp {
        method: c.m.id.clone(),
        tool: small.id.clone(),
        rpm,
        feed_rough,
        feed_finish,
        feed_boundary: feed_finish,
        feed_link: feed_rough * mk.link_feed_factor,
        start: b.start,
        moves: b.moves,
        schedule: rest_schedule(rest, rt.own),
        provenance: prov,
    }))
}

/// When stage 8 runs a rest pass: one planned with every other feature
/// gone at the end (a pass with the feature's own tool dropped where other
/// operations cut its boundary already), a deferred wall rest or a floor
/// rest pass after its feature, any other wall rest with its feature.
fn rest_schedule(rest: Rest, own: bool) -> Schedule {
    match rest {
        Rest::Orphan(..) => Schedule::AtEnd {
            covered_within_mm: None,
        },
        Rest::Wall(w) if own => Schedule::AtEnd {
            covered_within_mm: Some(w.min_left),
        },
        Rest::Wall(w) if !w.run_last => Schedule::WithFeature,
        Rest::Wall(_) | Rest::Floor(_) => Schedule::AfterFeature,
    }
}

/// The tools a rest pass may use, best first: for the floor those whose
/// corner radius gains enough (the smallest radius, then the largest
/// diameter), for the walls those smaller than the last tool (the
/// largest), for orphan stretches any (the smallest, the most reach); all
/// of a kind the method allows, reaching the floor.
fn rest_candidates<'a>(c: &RestCtx<'a>, rest: Rest) -> Vec<&'a Tool> {
    let main = c.tool;
    let need = depth_below_top(c.env, c.f, c.z_min);
    let mut cands: Vec<&Tool> = c
        .env
        .tools
        .tools
        .iter()
        .filter(|t| c.m.tool.kinds.contains(&t.kind) && tool_reach(c.env, t) >= need - 1e-9)
        .filter(|t| match rest {
            Rest::Floor(rp) => {
                t.corner_radius <= main.corner_radius - rp.min_corner_gain + 1e-12
                    && t.diameter <= main.diameter
            }
            Rest::Wall(_) => t.diameter < c.after.map_or(main, |a| a.0).diameter - 1e-9,
            Rest::Orphan(..) => true,
        })
        .collect();
    cands.sort_by(|a, b| match rest {
        Rest::Floor(_) => a
            .corner_radius
            .total_cmp(&b.corner_radius)
            .then_with(|| b.diameter.total_cmp(&a.diameter))
            .then_with(|| a.id.cmp(&b.id)),
        Rest::Wall(_) => b
            .diameter
            .total_cmp(&a.diameter)
            .then_with(|| a.id.cmp(&b.id)),
        // the most reach
        Rest::Orphan(..) => a
            .diameter
            .total_cmp(&b.diameter)
            .then_with(|| a.id.cmp(&b.id)),
    });
    cands
}

/// A rest pass's tool and its geometry of the feature.
struct RestTool<'a> {
    tool: &'a Tool,
    g: Geometry,
    /// The feature's own tool, run last with every other feature gone.
    own: bool,
}

/// The first candidate with room in the feature; with none and a wall
/// rest pass run last, the feature's own tool with every other feature
/// gone.
fn rest_tool<'a>(c: &RestCtx<'a>, rest: Rest, cands: &[&'a Tool]) -> Option<RestTool<'a>> {
    let main = c.tool;
    // No smaller tool: a wall rest pass run last may use the feature's own
    // tool, with every other feature gone.
    let found = match rest {
        Rest::Orphan(..) => cands
            .iter()
            .find_map(|t| opened_geometry(c, t).map(|g| (*t, g, false))),
        _ => cands
            .iter()
            .find_map(|t| c.geometry(t).map(|g| (*t, g, false)))
            .or_else(|| match rest {
                Rest::Wall(w) if w.run_last && cands.is_empty() && c.after.is_none() => {
                    opened_geometry(c, main).map(|g| (main, g, true))
                }
                _ => None,
            }),
    };
    found.map(|(tool, g, own)| RestTool { tool, g, own })
}

/// `t`'s geometry of the feature run last, when every other feature is
/// gone: every edge that is not product is open, and the removed space is
/// the whole free space.
fn opened_geometry(c: &RestCtx, t: &Tool) -> Option<Geometry> {
    let mut f = c.f.clone();
    let open = |a: &mut Adjacency| {
        if *a == Adjacency::Feature {
            *a = Adjacency::Open;
        }
    };
    f.side_adjacency.iter_mut().for_each(open);
    f.hole_adjacency
        .iter_mut()
        .flat_map(|h| h.iter_mut())
        .for_each(open);
    geometry(&f, c.m, t, c.free, c.free, c.g.slopes)
}

/// Whether the rest pass wants stretch `e` of a chain of the small tool's
/// region `g2`: where the feature's tool was `beside` the wall (floor,
/// `want_inside`), where it never came near or its passes left some of
/// the wall (walls), where no operation came beside it (orphans).
fn wanted(
    c: &RestCtx,
    rest: Rest,
    g2: &Geometry,
    beside: &[Vec<DVec2>],
    want_inside: bool,
    e: &Edge2,
) -> bool {
    match rest {
        // wanted where some sample was not cut round at some level
        Rest::Orphan(w, cov) if g2.slopes == Slopes::AsVertical => e.sample(STEP).iter().any(|p| {
            c.levels
                .iter()
                .any(|&z| !cov.covers(crate::to_part(c.f, *p, z), g2.r, w.min_left))
        }),
        // Beside sloped faces the disc reaches past open edges, into
        // air or space other features cleared at their own heights:
        // only the feature's own material in it counts.
        Rest::Orphan(w, cov) => e.sample(STEP).iter().any(|p| {
            disc_samples(*p, g2.r)
                .filter(|q| inside(*q, &c.g.region_polys))
                .any(|q| {
                    c.levels
                        .iter()
                        .any(|&z| !cov.covers(crate::to_part(c.f, q, z), 0.0, w.min_left))
                })
        }),
        // the feature's tool never came near, or the passes it made
        // left some of it (a centre region too narrow for a pass)
        Rest::Wall(w) => {
            let pts = e.sample(STEP);
            pts.iter().all(|p| !inside(*p, beside))
                || pts.iter().any(|p| {
                    c.levels
                        .iter()
                        .any(|&z| !c.own_cuts.covers(p.extend(z), g2.r, w.min_left))
                })
        }
        // where the feature's tool or a wall rest pass at the floor came
        // beside the wall and left its corner radius's fillet
        Rest::Floor(_) => e.sample(STEP).iter().all(|p| {
            inside(*p, beside) == want_inside || c.own_cuts.covers(p.extend(c.z_min), g2.r, HAIR)
        }),
    }
}

/// The stretches of `chain` the rest pass wants (`ok`). A stretch ends
/// where the feature's tool stopped being beside the wall (floor) or came
/// close enough (wall): decided piece by piece along each edge (a whole
/// edge would be refused for its last millimetres, and the fillet along
/// the rest left standing); the accepted pieces of an edge are joined
/// again (an edge kept whole is kept as it was).
fn accepted_parts(chain: &[Edge2], ok: impl Fn(&Edge2) -> bool) -> Vec<Vec<Edge2>> {
    let mut cur: Vec<Edge2> = Vec::new();
    let mut parts = Vec::new();
    for e in chain {
        let pieces = e.split(4.0 * STEP);
        if pieces.iter().all(&ok) {
            cur.push(*e);
            continue;
        }
        // (start, end, Σ atan(bulge)): the joined arc's bulge is the
        // tangent of the sum.
        let mut run: Option<(DVec2, DVec2, f64)> = None;
        for piece in pieces {
            if ok(&piece) {
                run = Some(match run {
                    None => (piece.a, piece.b, piece.bulge.atan()),
                    Some((a, _, q)) => (a, piece.b, q + piece.bulge.atan()),
                });
            } else {
                if let Some((a, b, q)) = run.take() {
                    cur.push(Edge2 {
                        a,
                        b,
                        bulge: q.tan(),
                    });
                }
                if !cur.is_empty() {
                    parts.push(std::mem::take(&mut cur));
                }
            }
        }
        if let Some((a, b, q)) = run.take() {
            cur.push(Edge2 {
                a,
                b,
                bulge: q.tan(),
            });
        }
    }
    if !cur.is_empty() {
        parts.push(cur);
    }
    parts
}

/// The rest pass's provenance: its tool against the feature's, its
/// conditions, passes and levels, and what it finishes.
fn rest_provenance(
    c: &RestCtx,
    rest: Rest,
    rt: &RestTool,
    passes: usize,
    levels: &[f64],
    rpm: f64,
    feed_finish: f64,
) -> Provenance {
    let (main, small, own) = (c.tool, rt.tool, rt.own);
    let suffix = match rest {
        Rest::Floor(_) => "rest_pass",
        Rest::Wall(_) | Rest::Orphan(..) => "wall_rest",
    };
    let mut prov = Provenance::new(
        ProvenanceSource::Knowledge,
        format!("methods.{}.{suffix}", c.m.id),
    );
    slope_values(&mut prov, &rt.g);
    let v = &mut prov.values;
    v.insert("tool_diameter_mm".into(), small.diameter);
    v.insert("tool_corner_radius_mm".into(), small.corner_radius);
    v.insert("feature_tool_diameter_mm".into(), main.diameter);
    v.insert("feature_tool_corner_radius_mm".into(), main.corner_radius);
    v.insert("spindle_rpm".into(), rpm);
    v.insert("feed_finish_mm_min".into(), feed_finish);
    v.insert("feed_boundary_mm_min".into(), feed_finish);
    v.insert("passes".into(), passes as f64);
    v.insert("layers".into(), levels.len() as f64);
    // the deepest cut of a wall pass: between levels, or the first below
    // the top
    let wall_depth = levels
        .windows(2)
        .map(|p| p[0] - p[1])
        .chain(std::iter::once(c.z_top - levels[0]))
        .fold(0.0, f64::max);
    match rest {
        Rest::Floor(rp) => {
            v.insert("min_corner_gain_mm".into(), rp.min_corner_gain);
            v.insert("depth_of_cut_mm".into(), main.corner_radius);
            prov.note = format!(
                "pattern=RestPass; layer=floor; fillet of {} (corner radius {:.2} mm) finished \
                 by {} (corner radius {:.2} mm)",
                main.id, main.corner_radius, small.id, small.corner_radius
            );
        }
        Rest::Wall(w) => {
            v.insert("min_left_mm".into(), w.min_left);
            if own {
                v.insert("after_every_feature".into(), 1.0);
            }
            if w.run_last {
                v.insert("run_last".into(), 1.0);
            }
            v.insert("depth_of_cut_mm".into(), wall_depth);
            prov.note = format!(
                "pattern=RestPass; layer=walls; wall stretches {} (D {:.1} mm) left more than \
                 {:.2} mm on, finished by {} (D {:.1} mm) at {} levels",
                c.after.map_or(main, |a| a.0).id,
                c.after.map_or(main, |a| a.0).diameter,
                w.min_left,
                small.id,
                small.diameter,
                levels.len()
            );
        }
        Rest::Orphan(w, _) => {
            v.insert("min_left_mm".into(), w.min_left);
            v.insert("run_last".into(), 1.0);
            v.insert(ORPHAN.into(), 1.0);
            v.insert("depth_of_cut_mm".into(), wall_depth);
            prov.note = format!(
                "pattern=RestPass; layer=walls; orphan stretches: product wall no operation \
                 came within {:.2} mm of, finished by {} (D {:.1} mm) at {} levels, run last \
                 with every other feature gone",
                w.min_left,
                small.id,
                small.diameter,
                levels.len()
            );
        }
    }
    prov
}

/// What the feature's operations `ops` cut (local frame), to find the
/// wall stretches they left (the centre region alone overstates it where
/// it is too narrow for a pass).
pub(super) fn cuts_of(env: &Env, ops: &[LocalOp]) -> crate::coverage::Coverage {
    crate::coverage::Coverage::local(ops.iter().map(|o| {
        let t = env.tools.tools.iter().find(|t| t.id == o.tool);
        (
            o.moves.as_slice(),
            o.start,
            t.map_or(0.0, |t| 0.5 * t.diameter),
            t.map_or(0.0, |t| t.flute_length),
        )
    }))
}

/// Stage 7's second pass: the wall rest pass of the orphan stretches only
/// (none where it fails, said).
pub(super) fn orphan_passes(
    ctx: &RestCtx,
    cov: &crate::coverage::Coverage,
    warnings: &mut Vec<String>,
) -> Vec<LocalOp> {
    let mut orphan = Vec::new();
    if let Some(w) = ctx
        .m
        .wall_rest
        .as_ref()
        .filter(|_| !ctx.g.product.is_empty())
    {
        match rest_pass(ctx, Rest::Orphan(w, cov)) {
            Ok(Some(op)) => orphan.push(op),
            Ok(None) => {}
            Err(e) => warnings.push(format!("{}: no orphan wall rest pass: {e}", ctx.f.id)),
        }
    }
    orphan
}

/// The rest passes after the feature's own operations `ops`, added to
/// them; a pass that fails is said and left out.
///
/// The wall rest passes: stretches of product wall this tool could not
/// come beside, finished by the next smaller tool right after it, and
/// what that one left by the next smaller again (a corner between two
/// walls stops each tool at its own radius from the crossing wall).
///
/// The floor rest pass (`bottom_product`): the fillet this tool's corner
/// radius leaves along the product walls' feet, finished by a smaller
/// corner radius.
pub(super) fn rest_passes(
    ctx: &RestCtx,
    bottom_product: bool,
    ops: &mut Vec<LocalOp>,
    warnings: &mut Vec<String>,
) {
    let (f, env, g, tool) = (ctx.f, ctx.env, ctx.g, ctx.tool);
    if let Some(w) = ctx
        .m
        .wall_rest
        .as_ref()
        .filter(|_| !ops.is_empty() && !g.product.is_empty())
    {
        let mut after: Option<(&Tool, Geometry)> = None;
        loop {
            let own_cuts = cuts_of(env, ops);
            let c = RestCtx {
                own_cuts: &own_cuts,
                after: after.as_ref().map(|(t, g)| (*t, g)),
                ..ctx.clone_shallow()
            };
            match rest_pass(&c, Rest::Wall(w)) {
                Ok(Some(op)) => {
                    let small = env.tools.tools.iter().find(|t| t.id == op.tool);
                    let next = small
                        .filter(|t| t.diameter < after.as_ref().map_or(tool, |a| a.0).diameter)
                        .and_then(|t| c.geometry(t).map(|g2| (t, g2)));
                    ops.push(op);
                    match next {
                        Some(n) => after = Some(n),
                        None => break,
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    warnings.push(format!("{}: no wall rest pass: {e}", f.id));
                    break;
                }
            }
        }
    }
    if let Some(rp) = ctx
        .m
        .rest_pass
        .as_ref()
        .filter(|_| bottom_product && !ops.is_empty() && !g.product.is_empty())
    {
        // The wall rest passes' floor fillets too.
        let own_cuts = cuts_of(env, ops);
        let c = RestCtx {
            own_cuts: &own_cuts,
            ..ctx.clone_shallow()
        };
        match rest_pass(&c, Rest::Floor(rp)) {
            Ok(Some(op)) => ops.push(op),
            Ok(None) => {}
            Err(e) => warnings.push(format!("{}: no rest pass: {e}", f.id)),
        }
    }
}
