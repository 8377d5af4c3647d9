//! The modular pattern of one machining feature: method and tool choice,
//! the tool-centre region, z-levels, rest passes, boundary passes, entries.

use std::collections::BTreeMap;

use cavalier_contours::polyline::PlineSource;
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};
use glam::{DVec2, DVec3};
use thinplan_knowledge::{
    FullCut, Knowledge, LevelEntry, Machine, Material, Method, MethodKnowledge, MirrorLayers,
    Pattern, RestPass, RunUp, SidesMatch, SlopedFaces, SpindleDirection, Tool, ToolChoice, ToolSet,
    WallRest,
};
use thinplan_plan::{Adjacency, EdgeSlopes, MachiningFeature, Provenance, ProvenanceSource};

use crate::geom::{
    adjacency_edges, boundary_distance, edges_of_pline, inside, move_edges, move_edges_tagged,
    oriented, pline_from_edges, segment_inside, Area, Edge2,
};
use crate::path::{helix, ramp, rounded, seg_points, Builder, Kind, LMove, Seg2, Space};

pub(crate) struct Env<'a> {
    pub k: &'a Knowledge,
    pub tools: &'a ToolSet,
    pub material: &'a Material,
    pub machine: &'a Machine,
    pub limits: thinplan_feeds::MachineLimits,
    pub global_top: f64,
    /// Set for stage 7's second pass: plan only the feature's orphan wall
    /// stretches, those no operation of the first pass cut
    /// ([`Rest::Orphan`]).
    pub orphans: Option<&'a crate::coverage::Coverage>,
}

impl<'a> Env<'a> {
    /// The same environment with another tool set.
    pub fn clone_with_tools<'b>(&self, tools: &'b ToolSet) -> Env<'b>
    where
        'a: 'b,
    {
        Env {
            k: self.k,
            tools,
            material: self.material,
            machine: self.machine,
            limits: self.limits.clone(),
            global_top: self.global_top,
            orphans: self.orphans,
        }
    }
}

/// An operation in the feature's local frame.
pub(crate) struct LocalOp {
    pub method: String,
    pub tool: String,
    pub rpm: f64,
    pub feed_rough: f64,
    pub feed_finish: f64,
    pub feed_boundary: f64,
    pub feed_link: f64,
    pub start: DVec3,
    pub moves: Vec<LMove>,
    pub provenance: Provenance,
}

pub(crate) struct Made {
    pub ops: Vec<LocalOp>,
    pub warnings: Vec<String>,
    /// Material of this feature no tool of the tool set can reach (product
    /// corners tighter than the smallest tool), with the reason and an
    /// estimate of its volume (mm³).
    pub unreachable: Vec<(String, f64)>,
    /// Where the tool centre may go (sampled polygons of the tool-centre region).
    pub reach: Vec<Vec<DVec2>>,
}

/// How a refusal for lack of any tool that fits starts (stage 7 reports it
/// as unreachable material, rule `operations.unreachable`).
pub(crate) const NO_TOOL_FITS: &str = "unreachable: no tool of the set-up's tool set fits";
/// The start of a refusal for material below every fitting tool's reach.
pub(crate) const NO_TOOL_REACHES: &str = "unreachable: no tool of the set-up's tool set reaches";

/// Whether a refusal leaves material no tool of the set can cut (not a
/// planning failure).
pub(crate) fn is_unreachable(reason: &str) -> bool {
    reason.starts_with(NO_TOOL_FITS) || reason.starts_with(NO_TOOL_REACHES)
}

/// How far below the top of the stock `t` may cut: its stickout less the
/// holder clearance, so its holder's face stays above the highest stock
/// it could meet (the top of the stock bounds it everywhere).
pub(crate) fn tool_reach(env: &Env, t: &Tool) -> f64 {
    t.stickout - env.k.methods.holder_clearance
}

/// The depth of local height `z` of `f` below the top of the stock.
pub(crate) fn depth_below_top(env: &Env, f: &MachiningFeature, z: f64) -> f64 {
    let up_off = f
        .shape
        .frame
        .origin
        .dot(f.shape.frame.z.normalize_or_zero());
    env.global_top - up_off - z
}

/// Sampling step (mm) for containment checks and polygons.
const STEP: f64 = 0.25;
/// Rest blocks shorter than this (mm) are points where a zigzag line only
/// touches the tool-centre region.
const MIN_BLOCK: f64 = 1e-3;

/// A block the zigzag only touches (a rest region pinched to a point): it
/// has no length to ramp along and cuts no more than the disc a
/// neighbouring pass takes, so a level skips it where no entry fits.
fn pinched(block: &[DVec2]) -> bool {
    block.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>() < MIN_BLOCK
}
/// Distance slack for "on the product offset" (mm).
const EPS: f64 = 1e-6;
/// Distance slack of the sloped-face safety net (mm): the tool's profile
/// is tangent to the face there, and the torus's sagitta between the
/// net's sample heights is smaller still.
const EPS_SLOPE: f64 = 1e-5;

/// Extra radius of every swept cut (mm): the passes built along the cut
/// region come up to about 1.2e-4 nearer than its boundary (the booleans'
/// intersections, the passes' joins), and the safety net allows only
/// `EPS_SLOPE`.
const SWEPT_MARGIN: f64 = 1e-3;

/// How clearly a swept cut crosses the relaxed region's boundary where the
/// two would run along each other (mm, `swept_cuts`).
const TOUCH: f64 = 2e-3;

/// The geometry of a feature for one tool.
#[derive(Clone)]
struct Geometry {
    r: f64,
    /// Tool-centre region and its sampled polygons.
    centre: Area,
    centre_polys: Vec<Vec<DVec2>>,
    /// The feature region itself, sampled.
    region_polys: Vec<Vec<DVec2>>,
    /// Product edges the tool's radius is measured from: which stretches
    /// of the region run along product, bands, entries. With `Swept`,
    /// where one shift per edge put them (conservative at the edges' ends,
    /// where the swept region reaches further).
    product: Vec<Edge2>,
    /// Product edges the region was offset from, which the safety net
    /// holds every tool centre `r` away from (`product` but with `Swept`).
    product_offset: Vec<Edge2>,
    /// Boundaries of the free space around the feature (other product the
    /// tool must keep r from, see `free.rs`).
    keep_out: Vec<Edge2>,
    /// The region was clipped to the free space (straight edges only).
    clipped: bool,
    /// How sloped product faces (`MachiningFeature::slopes`) were
    /// followed: the product edges above are moved to where the tool's
    /// profile touches the face.
    slopes: Slopes,
    /// The product's edges at heights over the tool's profile, each with
    /// the tool's section radius there: the safety net for sloped faces
    /// (every tool centre at least that far from them). Empty when not
    /// `Slopes::AsVertical`.
    slope_check: Vec<(f64, Vec<Edge2>)>,
}

fn sides_class(edges: &[(Vec<Edge2>, Vec<Adjacency>)]) -> SidesMatch {
    let all: Vec<Adjacency> = edges.iter().flat_map(|(_, a)| a.iter().copied()).collect();
    let p = all.iter().filter(|a| **a == Adjacency::Product).count();
    if p == 0 {
        SidesMatch::Open
    } else if p == all.len() {
        SidesMatch::Closed
    } else {
        SidesMatch::PartiallyOpen
    }
}

/// Smallest concave product corner radius: product arcs whose centre lies on
/// the region's side, and sharp convex vertices between two product edges.
fn smallest_product_corner(edges: &[(Vec<Edge2>, Vec<Adjacency>)]) -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut note = |v: f64| best = Some(best.map_or(v, |b: f64| b.min(v)));
    for (es, adj) in edges {
        let n = es.len();
        // The region lies left of every edge (ccw outer, cw holes): a left
        // turn between two product edges is a concave corner of the part.
        // Negative: a right turn, or an edge that is not product (either
        // ends a run of chords).
        let turn = |i: usize| {
            let j = (i + 1) % n;
            if adj[i] != Adjacency::Product || adj[j] != Adjacency::Product {
                return -1.0;
            }
            let (t1, t2) = (es[i].tangents().1, es[j].tangents().0);
            t1.perp_dot(t2).atan2(t1.dot(t2))
        };
        for i in 0..n {
            if adj[i] == Adjacency::Product {
                if let Some((r, _)) = es[i].arc() {
                    if es[i].bulge > 0.0 {
                        note(r);
                    }
                }
            }
        }
        let turns: Vec<f64> = (0..n).map(turn).collect();
        let lengths: Vec<f64> = es.iter().map(Edge2::length).collect();
        for r in corner_radii(&turns, &lengths) {
            note(r);
        }
    }
    best
}

/// The largest turn between two chords of one tessellated arc: twice the
/// sections' mesh turn per segment (`thinplan_brep::TessParams::angle`,
/// 0.2 rad). A steeper left turn is a sharp corner of the part.
const CHORD_TURN_MAX: f64 = 0.4;

/// A chord run ends at a link this many times longer than the link beside
/// it: a fillet's chords are alike, the wall tangent to two fillets is not.
const CHORD_LINK_RATIO: f64 = 3.0;

/// The concave corners' radii along a closed chain: `turns[i]` is the turn
/// from edge i to edge i + 1 (left positive; negative also where an edge
/// is not product), `lengths[i]` edge i's length. A left turn steeper than
/// [`CHORD_TURN_MAX`] is a sharp corner (0). Gentler left turns, with
/// straight junctions between them, are the chords of a tessellated fillet,
/// split where one link between turns is [`CHORD_LINK_RATIO`] times longer
/// than a link beside it; each fillet of two turns or more gives its
/// radius: its chords' length over the turns (the first and last, at the
/// tangent points, are half a chord's), a little under the true radius as
/// chords are shorter than their arcs. A lone gentle turn is sharp (0).
fn corner_radii(turns: &[f64], lengths: &[f64]) -> Vec<f64> {
    let n = turns.len();
    let straight = |t: f64| t.abs() <= 1e-6;
    let chordal = |t: f64| t > 1e-6 && t <= CHORD_TURN_MAX;
    let mut out: Vec<f64> = turns
        .iter()
        .filter(|t| **t > CHORD_TURN_MAX)
        .map(|_| 0.0)
        .collect();
    // Runs start after a junction that is neither chordal nor straight.
    let Some(start) = (0..n).find(|&i| !chordal(turns[i]) && !straight(turns[i])) else {
        // Every junction chordal or straight: a round hole's wall.
        let total: f64 = turns.iter().filter(|t| **t > 0.0).sum();
        if total > 1e-9 {
            out.push(lengths.iter().sum::<f64>() / total);
        }
        return out;
    };
    // (turns, links between consecutive turns) of each run.
    let mut runs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let (mut cur, mut links) = (Vec::new(), Vec::new());
    let mut since = 0.0;
    for s in 1..=n {
        let i = (start + s) % n;
        let t = turns[i];
        if chordal(t) {
            if !cur.is_empty() {
                links.push(since + lengths[i]);
            }
            since = 0.0;
            cur.push(t);
        } else if straight(t) && !cur.is_empty() {
            since += lengths[i];
        } else if !cur.is_empty() {
            runs.push((std::mem::take(&mut cur), std::mem::take(&mut links)));
            since = 0.0;
        }
    }
    if !cur.is_empty() {
        runs.push((cur, links));
    }
    for (turns, links) in runs {
        // A link much longer than a link beside it is a wall between two
        // fillets: the run splits there.
        let wall = |j: usize| {
            let longer = |k: Option<&f64>| k.is_some_and(|l| links[j] > CHORD_LINK_RATIO * l);
            longer(j.checked_sub(1).and_then(|k| links.get(k))) || longer(links.get(j + 1))
        };
        let mut from = 0;
        for k in 0..turns.len() {
            if k + 1 < turns.len() && !wall(k) {
                continue;
            }
            // Turns from..=k, joined by links from..k: one fillet; a lone
            // turn is read as sharp, as any turn between two product
            // edges always was (a boolean's polyline kink, a noisy vertex).
            if k == from {
                out.push(0.0);
            } else {
                // The end turns are at the tangent points (half a chord's
                // turn each): the chords subtend all the turns.
                let total: f64 = turns[from..=k].iter().sum();
                if total > 1e-9 {
                    out.push(links[from..k].iter().sum::<f64>() / total);
                }
            }
            from = k + 1;
        }
    }
    out
}

/// How a feature's sampled sloped faces shape its tool-centre region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slopes {
    /// Product edges stay where the region's section has them.
    AsVertical,
    /// Each product edge moves by one distance: exact along the edge,
    /// conservative around its ends.
    Shifted,
    /// Each product edge moves as far as the tool's full radius allows,
    /// and the product at every height of the corner radius is cut from
    /// the region (`caps`): exact at the edges' ends too.
    Swept,
}

fn geometry(
    f: &MachiningFeature,
    m: &Method,
    tool: &Tool,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    slopes: Slopes,
) -> Option<Geometry> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let d = tool.diameter;
    let r = d / 2.0;
    let plain = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    // Sloped product faces: the product edges move to where the tool's
    // profile touches the face, and the space between is free.
    let shifts = match slopes {
        Slopes::AsVertical => None,
        Slopes::Shifted => slope_shifts(f, tool),
        Slopes::Swept => match relaxed_shifts(f, tool) {
            Some(sh) => Some(sh),
            None => return geometry(f, m, tool, free, removed, Slopes::Shifted),
        },
    };
    let (edges, free_sloped) = match &shifts {
        None => (plain.clone(), None),
        Some(sh) => {
            let moved = moved_edges(&plain, sh);
            let grown = free.map(|free| {
                let region: Vec<Vec<[f64; 2]>> = moved
                    .iter()
                    .map(|(es, _)| es.iter().map(|e| [e.a.x, e.a.y]).collect())
                    .collect();
                let region: crate::free::Shapes = region.overlay_as::<i64>(
                    &Vec::<Vec<[f64; 2]>>::new(),
                    OverlayRule::Subject,
                    FillRule::NonZero,
                );
                let a: Vec<Vec<[f64; 2]>> = free.iter().flatten().cloned().collect();
                let b: Vec<Vec<[f64; 2]>> = region.into_iter().flatten().collect();
                a.overlay_as::<i64>(&b, OverlayRule::Union, FillRule::NonZero)
            });
            (moved, grown)
        }
    };
    let free = free_sloped.as_ref().or(free);
    let mut product = Vec::new();
    let keep_out: Vec<Edge2> = free
        .map(|free| {
            free.iter()
                .flat_map(|s| s.iter())
                .flat_map(|c| {
                    let n = c.len();
                    (0..n).map(move |i| Edge2 {
                        a: DVec2::new(c[i][0], c[i][1]),
                        b: DVec2::new(c[(i + 1) % n][0], c[(i + 1) % n][1]),
                        bulge: 0.0,
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    // Straight-edged features with a known free space (every resolved
    // feature): the moved region is clipped to the free space below, so the
    // overhang needs no per-edge clearance. Otherwise (arcs, synthetic
    // plans) each edge's overhang is capped by the room beyond it.
    let clip = free.filter(|_| {
        edges
            .iter()
            .all(|(es, _)| es.iter().all(|e| e.bulge == 0.0))
    });
    let mut loops = Vec::new();
    for (k, (es, adj)) in edges.iter().enumerate() {
        // Tool edge may pass `overhang·D` beyond a non-product edge: the
        // loop is moved out by that, then the whole offset in by r.
        let out: Vec<f64> = adj
            .iter()
            .zip(es)
            .map(|(a, e)| {
                let wanted = match a {
                    Adjacency::Product => 0.0,
                    Adjacency::Open => m.overhang.open * d,
                    Adjacency::Feature => m.overhang.feature * d,
                };
                // Never so far that the tool reaches product beyond the
                // edge (an open edge may face a narrow strip beside a wall).
                if clip.is_some() {
                    wanted
                } else {
                    wanted.min(clearance(e, &keep_out))
                }
            })
            .collect();
        for (e, a) in es.iter().zip(adj) {
            if *a == Adjacency::Product {
                product.push(*e);
            }
        }
        let moved = move_edges(es, &out);
        if moved.len() < 2 {
            continue;
        }
        let pl = pline_from_edges(&moved, true);
        if pl.area().abs() < 1e-9 {
            continue;
        }
        // A hole moved out past itself vanished (it was all non-product).
        let expect_ccw = k == 0;
        if (pl.area() > 0.0) != expect_ccw {
            if k == 0 {
                return None;
            }
            continue;
        }
        loops.push(oriented(pl, expect_ccw));
    }
    if loops.is_empty() {
        return None;
    }
    if let Some(free) = clip {
        let mut grown = grown_region(&edges, m, d, false);
        if let Some(removed) = removed {
            // An edge counts as open by its midpoint; past it the tool may
            // overhang a whole diameter only into space already cut, and
            // half of one into a feature still to come (where the far side
            // of an open edge is partly such a feature).
            let half = grown_region(&edges, m, d, true);
            let far: crate::free::Shapes =
                grown.overlay_as::<i64>(removed, OverlayRule::Intersect, FillRule::NonZero);
            let far: Vec<Vec<[f64; 2]>> = far.into_iter().flatten().collect();
            let both: crate::free::Shapes =
                half.overlay_as::<i64>(&far, OverlayRule::Union, FillRule::NonZero);
            grown = both.into_iter().flatten().collect();
        }
        loops = clipped_to_free(&grown, free, &product_strips(&edges), d);
        if loops.is_empty() {
            return None;
        }
    }
    let shape = Shape::from_plines(loops.clone());
    // The clipped loops carry the overlay's rounding (well under 1e-6 mm).
    let slack = if clip.is_some() { clip_slack(r) } else { 0.0 };
    // cavalier_contours asserts (debug builds) on some degenerate
    // intersections of the clipped loops; a hair more offset avoids them,
    // so debug and release builds make the same region.
    let centre = [0.0, 1e-6, 1e-5, 1e-4, 1e-3, 2e-3]
        .iter()
        .find_map(|extra| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                shape.parallel_offset(r + slack + extra, &ShapeOffsetOptions::default())
            }))
            .ok()
        });
    // Loops through fillets (hundreds of tiny, nearly collinear pieces) can
    // offset into pieces of no area: then within a simplification.
    let centre = match centre {
        Some(c) if thinplan_pocketing::inset::sound(&c) => c,
        _ => thinplan_pocketing::inset::inset(&loops, r + slack),
    };
    let mut centre = Area::from_shape(centre);
    if slopes == Slopes::Swept {
        let cut = swept_cuts(f, tool, &plain, shifts.as_deref().unwrap_or_default())
            .and_then(|cuts| crate::caps::subtract(&centre, &cuts));
        match cut {
            Some(c) => centre = c,
            None => return geometry(f, m, tool, free, removed, Slopes::Shifted),
        }
    }
    if centre.is_empty() {
        return None;
    }
    let centre_polys = centre.polygons(STEP);
    let mut region_loops = vec![pline_from_edges(&plain[0].0, true)];
    for (es, _) in &plain[1..] {
        region_loops.push(pline_from_edges(es, true));
    }
    let region_polys = Area {
        parts: vec![(region_loops[0].clone(), region_loops[1..].to_vec())],
    }
    .polygons(STEP);
    Some(Geometry {
        r,
        centre,
        centre_polys,
        region_polys,
        product_offset: product.clone(),
        product: match (slopes, &shifts) {
            (Slopes::Swept, Some(_)) => {
                moved_product(&plain, &slope_shifts(f, tool).unwrap_or_default())
            }
            _ => product,
        },
        keep_out,
        clipped: clip.is_some(),
        slopes: if shifts.is_some() {
            slopes
        } else {
            Slopes::AsVertical
        },
        slope_check: match shifts {
            Some(_) => slope_check(f, tool, &plain),
            None => Vec::new(),
        },
    })
}

/// The tool's section radius `h` above its tip (bull-nose profile).
fn section_radius(tool: &Tool, h: f64) -> f64 {
    let r = tool.diameter / 2.0;
    let rc = tool.corner_radius.clamp(0.0, r);
    if h >= rc {
        r
    } else if h <= 0.0 {
        r - rc
    } else {
        r - rc + (rc * rc - (rc - h) * (rc - h)).max(0.0).sqrt()
    }
}

/// The least distance from the tool's axis to a product edge at which no
/// height of the tool's profile (tip at `tip`) crosses the face beyond it:
/// the largest section radius less how far the face lies beyond the edge,
/// over every height. Exact for the piecewise-linear face: the maximum lies
/// at a sample height, at the corner radius's top, or where the torus is
/// tangent to a piece.
fn reach_needed(s: &EdgeSlopes, offsets: &[f64], tip: f64, tool: &Tool) -> f64 {
    let rc = tool.corner_radius.clamp(0.0, tool.diameter / 2.0);
    let mut hs = vec![0.0, rc];
    hs.extend(s.heights.iter().map(|z| z - tip).filter(|h| *h > 0.0));
    for w in s.heights.windows(2) {
        let (h0, h1) = ((w[0] - tip).max(0.0), (w[1] - tip).min(rc));
        if h1 <= h0 || w[1] - w[0] <= 1e-12 {
            continue;
        }
        let c = (s.beyond(offsets, w[1]) - s.beyond(offsets, w[0])) / (w[1] - w[0]);
        if c > 0.0 {
            let h = rc * (1.0 - c / (1.0 + c * c).sqrt());
            if h > h0 && h < h1 {
                hs.push(h);
            }
        }
    }
    hs.iter()
        .map(|&h| section_radius(tool, h) - s.beyond(offsets, tip + h))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// How far each edge of the feature's loops moves towards the product for
/// `tool`: r less the reach it needs there (0 for vertical faces and
/// non-product edges). `None` where nothing moves.
fn slope_shifts(f: &MachiningFeature, tool: &Tool) -> Option<Vec<Vec<f64>>> {
    let r = tool.diameter / 2.0;
    per_sloped_edge(f, |s, o| r - reach_needed(s, o, f.shape.z_min, tool))
}

/// `distance` of every edge with sampled faces (0 for the others, and for
/// one within 1e-9), per loop; `None` where the samples are unusable or
/// nothing moves.
fn per_sloped_edge(
    f: &MachiningFeature,
    distance: impl Fn(&EdgeSlopes, &Vec<f64>) -> f64,
) -> Option<Vec<Vec<f64>>> {
    let s = f.slopes.as_ref().filter(|s| s.unusable().is_none())?;
    let per = |o: &Vec<f64>| -> f64 {
        if o.is_empty() {
            return 0.0;
        }
        let v = distance(s, o);
        if v.abs() < 1e-9 {
            0.0
        } else {
            v
        }
    };
    let mut v: Vec<Vec<f64>> = vec![s.side.iter().map(per).collect()];
    v.extend(s.holes.iter().map(|h| h.iter().map(per).collect()));
    v.iter().flatten().any(|x| *x != 0.0).then_some(v)
}

/// How far each edge of the feature's loops can move towards the product
/// for `tool` when the product at the corner radius's heights is cut from
/// the region on its own (`swept_cuts`): to the face where the tool is at
/// its full radius, the nearest over those heights. Never less than
/// `slope_shifts`. `None` where nothing moves.
fn relaxed_shifts(f: &MachiningFeature, tool: &Tool) -> Option<Vec<Vec<f64>>> {
    let rc = tool.corner_radius.clamp(0.0, tool.diameter / 2.0);
    let full = f.shape.z_min + rc;
    // `beyond` is piecewise linear and constant past its samples.
    per_sloped_edge(f, |s, o| {
        s.heights
            .iter()
            .filter(|z| **z > full)
            .map(|z| s.beyond(o, *z))
            .fold(s.beyond(o, full), f64::min)
    })
}

/// What the region moved by `relaxed` (`relaxed_shifts`) must lose so that
/// no height of the tool's corner radius comes nearer the product than its
/// section radius: per pair of neighbouring heights and product edge, the
/// convex hull of the edge's end discs at both (`caps`). Above the corner
/// radius the relaxed region already keeps the full radius from the
/// product. `None` where the edges do not pair up between heights or a
/// product edge is an arc (the caller keeps one shift per edge).
fn swept_cuts(
    f: &MachiningFeature,
    tool: &Tool,
    plain: &[(Vec<Edge2>, Vec<Adjacency>)],
    relaxed: &[Vec<f64>],
) -> Option<Vec<cavalier_contours::polyline::Polyline<f64>>> {
    let s = f.slopes.as_ref().filter(|s| s.unusable().is_none())?;
    let tip = f.shape.z_min;
    let rc = tool.corner_radius.clamp(0.0, tool.diameter / 2.0);
    if rc <= 0.0 {
        return Some(Vec::new());
    }
    const STEPS: usize = 32;
    let mut hs: Vec<f64> = (0..=STEPS)
        .map(|k| rc * (1.0 - (k as f64 * std::f64::consts::FRAC_PI_2 / STEPS as f64).cos()))
        .collect();
    hs.extend(
        s.heights
            .iter()
            .map(|z| z - tip)
            .filter(|h| *h > 0.0 && *h < rc),
    );
    hs.sort_by(f64::total_cmp);
    hs.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let at = |out: Vec<Vec<f64>>| -> Vec<Vec<(Edge2, Adjacency, Option<usize>)>> {
        moved_edges_keyed(plain, &out)
    };
    let outs = |h: f64| face_offsets(s, plain, tip + h);
    let base = at(relaxed.to_vec());
    let same = |a: &Edge2, b: &Edge2| {
        a.a.distance_squared(b.a) < 1e-18 && a.b.distance_squared(b.b) < 1e-18
    };
    // A disc all but as large as the full radius would run a hair
    // inside the relaxed region's boundary, along it: the polyline
    // booleans fail on such near-coincident edges, so it is made to
    // cross clearly (a thousandth of a millimetre more room is lost).
    let full = tool.diameter / 2.0;
    let grown = |r: f64| {
        let r = r + SWEPT_MARGIN;
        if r > full - TOUCH {
            r.max(full + TOUCH)
        } else {
            r
        }
    };
    let mut cuts = Vec::new();
    let mut prev = at(outs(hs[0]));
    for w in hs.windows(2) {
        let next = at(outs(w[1]));
        // The discs' radius must run linearly between the two heights (as
        // the edges move) and never below the section radius: the tangent
        // to the (concave) profile parallel to the chord between the two
        // heights lies above it, by the least over all tangents.
        let (h0, h1) = (w[0], w[1]);
        let (r0, r1) = (section_radius(tool, h0), section_radius(tool, h1));
        let chord = (r1 - r0) / (h1 - h0);
        let (low, top) = if h1 <= rc && chord > 0.0 {
            // The corner radius's arc at angle t from the tip: height
            // rc(1 − cos t), radius r − rc + rc·sin t, slope cot t.
            let t = (1.0 / chord).atan();
            let (ht, rt) = (rc * (1.0 - t.cos()), full - rc + rc * t.sin());
            (
                (rt + chord * (h0 - ht)).max(r0),
                (rt + chord * (h1 - ht)).max(r1),
            )
        } else {
            (r0.max(r1), r0.max(r1))
        };
        let radii = (grown(low), grown(top));
        // The product's segments at both heights, paired: the moved edges
        // by the edge they move, and the joins between two of them (a join
        // is there at one height and not at another where the two edges'
        // distances part: its ends are the two edges' ends, which move
        // linearly too).
        let mut pairs: Vec<((Edge2, Edge2), Option<Edge2>)> = Vec::new();
        for (k, (l0, l1)) in prev.iter().zip(&next).enumerate() {
            let tagged =
                |l: &Vec<(Edge2, Adjacency, Option<usize>)>| -> Vec<(Edge2, Adjacency, usize)> {
                    l.iter()
                        .filter_map(|(e, a, t)| t.map(|t| (*e, *a, t)))
                        .collect()
                };
            let (t0, t1) = (tagged(l0), tagged(l1));
            if t0.len() != t1.len() || t0.iter().zip(&t1).any(|(a, b)| a.2 != b.2) {
                return None;
            }
            let n = t0.len();
            for j in 0..n {
                let (e0, e1) = (&t0[j], &t1[j]);
                if e0.0.bulge != 0.0 || e1.0.bulge != 0.0 {
                    if e0.1 == Adjacency::Product {
                        return None;
                    }
                    continue;
                }
                if e0.1 == Adjacency::Product {
                    let relaxed_edge = base
                        .get(k)
                        .and_then(|l| l.iter().find(|b| b.2 == Some(e0.2)))
                        .map(|b| b.0);
                    pairs.push(((e0.0, e1.0), relaxed_edge));
                }
                let (f0, f1) = (&t0[(j + 1) % n], &t1[(j + 1) % n]);
                let joined = |a: &Edge2, b: &Edge2| a.b.distance_squared(b.a) > 1e-18;
                if (e0.1 == Adjacency::Product || f0.1 == Adjacency::Product)
                    && (joined(&e0.0, &f0.0) || joined(&e1.0, &f1.0))
                {
                    let seg = |a: DVec2, b: DVec2| Edge2 { a, b, bulge: 0.0 };
                    pairs.push(((seg(e0.0.b, f0.0.a), seg(e1.0.b, f1.0.a)), None));
                }
            }
        }
        for ((e0, e1), relaxed_edge) in pairs {
            // Where it stands as in the relaxed region, the full radius
            // there keeps the smaller ones off already; so it does where
            // all four discs lie within the full radius of one relaxed
            // product edge (that capsule is convex, so their hull does).
            if relaxed_edge.is_some_and(|b| same(&b, &e0) && same(&b, &e1)) {
                continue;
            }
            let discs = [(e0.a, low), (e0.b, low), (e1.a, top), (e1.b, top)];
            let covered = base.iter().flatten().any(|(b, a, _)| {
                *a == Adjacency::Product
                    && discs
                        .iter()
                        .all(|(c, rho)| b.distance(*c) + rho + SWEPT_MARGIN <= full)
            });
            if covered {
                continue;
            }
            let hull = crate::caps::disc_hull(&[
                (e0.a, radii.0),
                (e0.b, radii.0),
                (e1.a, radii.1),
                (e1.b, radii.1),
            ])?;
            cuts.push(hull);
        }
        prev = next;
    }
    Some(cuts)
}

/// The product edges of the loops moved by `out` (`moved_edges`).
fn moved_product(plain: &[(Vec<Edge2>, Vec<Adjacency>)], out: &[Vec<f64>]) -> Vec<Edge2> {
    moved_edges_keyed(plain, out)
        .into_iter()
        .flatten()
        .filter(|(_, a, _)| *a == Adjacency::Product)
        .map(|(e, _, _)| e)
        .collect()
}

/// Where the face beyond each edge of the loops lies at height `z` (0 for
/// edges without samples), per loop.
fn face_offsets(s: &EdgeSlopes, plain: &[(Vec<Edge2>, Vec<Adjacency>)], z: f64) -> Vec<Vec<f64>> {
    plain
        .iter()
        .enumerate()
        .map(|(k, (es, _))| {
            let samples = if k == 0 {
                Some(&s.side)
            } else {
                s.holes.get(k - 1)
            };
            (0..es.len())
                .map(|i| {
                    samples
                        .and_then(|v| v.get(i))
                        .map_or(0.0, |o| s.beyond(o, z))
                })
                .collect()
        })
        .collect()
}

/// The loops with each edge moved out by its own distance (`move_edges`),
/// keeping each edge's adjacency (a join next to a product edge counts as
/// product).
fn moved_edges(
    loops: &[(Vec<Edge2>, Vec<Adjacency>)],
    out: &[Vec<f64>],
) -> Vec<(Vec<Edge2>, Vec<Adjacency>)> {
    moved_edges_keyed(loops, out)
        .into_iter()
        .map(|l| l.into_iter().map(|(e, a, _)| (e, a)).unzip())
        .collect()
}

/// `moved_edges`, each edge with the index of the edge it moves (`None`
/// for a join).
fn moved_edges_keyed(
    loops: &[(Vec<Edge2>, Vec<Adjacency>)],
    out: &[Vec<f64>],
) -> Vec<Vec<(Edge2, Adjacency, Option<usize>)>> {
    loops
        .iter()
        .enumerate()
        .map(|(k, (es, adj))| {
            let o: Vec<f64> = (0..es.len())
                .map(|i| out.get(k).and_then(|v| v.get(i)).copied().unwrap_or(0.0))
                .collect();
            let n = es.len();
            let tagged = move_edges_tagged(es, &o);
            let m = tagged.len();
            (0..m)
                .map(|j| {
                    let (e, tag) = tagged[j];
                    let a = match tag {
                        Some(i) => adj[i],
                        // A join sits before the next edge's moved copy.
                        None => match tagged[(j + 1) % m].1 {
                            Some(i)
                                if adj[i] != Adjacency::Product
                                    && adj[(i + n - 1) % n] != Adjacency::Product =>
                            {
                                adj[i]
                            }
                            _ => Adjacency::Product,
                        },
                    };
                    (e, a, tag)
                })
                .collect()
        })
        .collect()
}

/// The product's edges at heights over the tool's profile (its corner
/// radius in 32 steps of angle, and every height the faces were sampled
/// at), each with the tool's section radius there.
fn slope_check(
    f: &MachiningFeature,
    tool: &Tool,
    plain: &[(Vec<Edge2>, Vec<Adjacency>)],
) -> Vec<(f64, Vec<Edge2>)> {
    let Some(s) = f.slopes.as_ref().filter(|s| s.unusable().is_none()) else {
        return Vec::new();
    };
    let tip = f.shape.z_min;
    let rc = tool.corner_radius.clamp(0.0, tool.diameter / 2.0);
    let mut hs: Vec<f64> = (0..=32)
        .map(|k| rc * (1.0 - (k as f64 * std::f64::consts::FRAC_PI_2 / 32.0).cos()))
        .collect();
    hs.extend(s.heights.iter().map(|z| z - tip).filter(|h| *h > 0.0));
    hs.sort_by(f64::total_cmp);
    hs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    hs.iter()
        .map(|&h| {
            let product = moved_product(plain, &face_offsets(s, plain, tip + h));
            (section_radius(tool, h), product)
        })
        .collect()
}

/// The polygons less every point closer than `reach` to a product edge
/// (each edge's capsule, circumscribed so the cut is never too small).
fn away_from_product(polys: &[Vec<DVec2>], product: &[Edge2], reach: f64) -> Vec<Vec<DVec2>> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    if product.is_empty() {
        return polys.to_vec();
    }
    let subject: Vec<Vec<[f64; 2]>> = polys
        .iter()
        .map(|p| p.iter().map(|q| [q.x, q.y]).collect())
        .collect();
    let band = crate::geom::band_along(product.iter().map(|e| (e.a, e.b)), reach);
    let out: crate::free::Shapes =
        subject.overlay_as::<i64>(&band, OverlayRule::Difference, FillRule::NonZero);
    out.into_iter()
        .flatten()
        .filter(|c| c.len() >= 3)
        .map(|c| c.into_iter().map(|q| DVec2::new(q[0], q[1])).collect())
        .collect()
}

/// The feature region grown beyond its non-product edges (straight edges):
/// the region, a band `overhang·D` wide beyond each such edge, and a patch
/// at every vertex between two of them. An open edge's band also runs on
/// past an end where product meets it, so a tool can reach a slot narrower
/// than itself from the open side (clipping to the free space and the
/// product strips keep it off the product). Contours, all counter-clockwise
/// except the region's holes.
fn grown_region(
    edges: &[(Vec<Edge2>, Vec<Adjacency>)],
    m: &Method,
    d: f64,
    open_as_feature: bool,
) -> Vec<Vec<[f64; 2]>> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let ccw = |mut c: Vec<DVec2>| {
        let area: f64 = (0..c.len())
            .map(|i| c[i].perp_dot(c[(i + 1) % c.len()]))
            .sum();
        if area < 0.0 {
            c.reverse();
        }
        c.into_iter().map(|p| [p.x, p.y]).collect::<Vec<[f64; 2]>>()
    };
    let overhang = |a: Adjacency| match a {
        Adjacency::Product => 0.0,
        Adjacency::Open if !open_as_feature => m.overhang.open * d,
        Adjacency::Open | Adjacency::Feature => m.overhang.feature * d,
    };
    let region: Vec<Vec<[f64; 2]>> = edges
        .iter()
        .map(|(es, _)| es.iter().map(|e| [e.a.x, e.a.y]).collect())
        .collect();
    let mut bands: Vec<Vec<[f64; 2]>> = Vec::new();
    for (es, adj) in edges {
        let n = es.len();
        for i in 0..n {
            let o = overhang(adj[i]);
            let e = es[i];
            if o <= 0.0 || e.a.distance_squared(e.b) < 1e-18 {
                continue;
            }
            let t = (e.b - e.a).normalize();
            let nrm = DVec2::new(t.y, -t.x);
            // Running on past an end is for space already cut.
            let open = adj[i] == Adjacency::Open && !open_as_feature;
            let prev = adj[(i + n - 1) % n];
            let next = adj[(i + 1) % n];
            let a = if open && prev == Adjacency::Product {
                e.a - t * o
            } else {
                e.a
            };
            let b = if open && next == Adjacency::Product {
                e.b + t * o
            } else {
                e.b
            };
            bands.push(ccw(vec![a, b, b + nrm * o, a + nrm * o]));
            // The corner patch towards the next non-product edge.
            let o2 = overhang(next);
            let f = es[(i + 1) % n];
            if o2 > 0.0 && f.a.distance_squared(f.b) > 1e-18 {
                let t2 = (f.b - f.a).normalize();
                let n2 = DVec2::new(t2.y, -t2.x);
                let v = e.b;
                if (nrm * o).perp_dot(n2 * o2).abs() > 1e-12 {
                    bands.push(ccw(vec![
                        v,
                        v + nrm * o,
                        v + nrm * o + n2 * o2,
                        v + n2 * o2,
                    ]));
                }
            }
        }
    }
    let grown: crate::free::Shapes =
        region.overlay_as::<i64>(&bands, OverlayRule::Union, FillRule::NonZero);
    grown.into_iter().flatten().collect()
}

/// Thin strips just beyond every product edge (on its outward side, a
/// little longer than the edge): cut from the moved region, the offset then
/// keeps the tool centre r from each product edge even where a moved
/// neighbour shortened it or a narrow hole moved past itself.
fn product_strips(edges: &[(Vec<Edge2>, Vec<Adjacency>)]) -> Vec<Vec<[f64; 2]>> {
    let e = PRODUCT_STRIP;
    let mut v = Vec::new();
    for (es, adj) in edges {
        for (edge, a) in es.iter().zip(adj) {
            if *a != Adjacency::Product || edge.a.distance_squared(edge.b) < 1e-18 {
                continue;
            }
            let t = (edge.b - edge.a).normalize();
            let n = DVec2::new(t.y, -t.x);
            let (p, q) = (edge.a - t * e, edge.b + t * e);
            v.push(
                [p, q, q + n * e, p + n * e]
                    .iter()
                    .map(|c| [c.x, c.y])
                    .collect(),
            );
        }
    }
    v
}

/// Width (mm) of the strip cut beyond a product edge: the offset by r then
/// keeps the tool centre at least r from the edge and its ends.
const PRODUCT_STRIP: f64 = 1e-3;

/// Extra inward offset (mm) of a region clipped to the free space: the
/// overlay's integer rounding, and the chords of the sampled polygons the
/// passes are built on where the region bends round an obstacle (sagitta
/// of a 0.25 mm chord on a radius of at least r).
fn clip_slack(r: f64) -> f64 {
    1e-4 + STEP * STEP / (8.0 * r.max(STEP))
}

/// The moved region (straight loops, outer ccw, holes cw) intersected with
/// the free space, less the strips beyond product edges; as
/// cavalier loops with the same orientation convention.
fn clipped_to_free(
    subject: &[Vec<[f64; 2]>],
    free: &crate::free::Shapes,
    strips: &[Vec<[f64; 2]>],
    d: f64,
) -> Vec<cavalier_contours::polyline::Polyline<f64>> {
    use cavalier_contours::polyline::{PlineCreation, PlineSourceMut, Polyline};
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let subject: Vec<Vec<[f64; 2]>> = subject.to_vec();
    // Outer ccw and holes cw: non-zero winding is the region.
    let region: crate::free::Shapes = subject.overlay_as::<i64>(
        &Vec::<Vec<[f64; 2]>>::new(),
        OverlayRule::Subject,
        FillRule::NonZero,
    );
    let mut within: crate::free::Shapes =
        region.overlay_as::<i64>(free, OverlayRule::Intersect, FillRule::NonZero);
    if !strips.is_empty() {
        let strips: Vec<Vec<[f64; 2]>> = strips.to_vec();
        within = within.overlay_as::<i64>(&strips, OverlayRule::Difference, FillRule::NonZero);
    }
    let mut out = Vec::new();
    for shape in &within {
        for (k, c) in shape.iter().enumerate() {
            if c.len() < 3 {
                continue;
            }
            // Near-duplicate and collinear vertices (the overlay's seams)
            // upset the offset: drop them.
            let mut pts: Vec<DVec2> = c.iter().map(|q| DVec2::new(q[0], q[1])).collect();
            loop {
                let n = pts.len();
                if n < 3 {
                    break;
                }
                let drop = (0..n).find(|&i| {
                    let (a, b, q) = (pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
                    a.distance(b) < 1e-5
                        || ((b - a).perp_dot(q - b)).abs() < 1e-9 * (1.0 + a.distance(q))
                            && (b - a).dot(q - b) > 0.0
                });
                match drop {
                    Some(i) => {
                        pts.remove(i);
                    }
                    None => break,
                }
            }
            if pts.len() < 3 {
                continue;
            }
            let mut p = Polyline::with_capacity(pts.len(), true);
            for q in &pts {
                p.add(q.x, q.y, 0.0);
            }
            // Slivers far thinner than the tool vanish in the offset anyway.
            if p.area().abs() < 1e-9 * d * d {
                continue;
            }
            out.push(oriented(p, k == 0));
        }
    }
    out
}

/// Room beyond an edge (on its outward, right-hand side) before the free
/// space ends, mm: the smallest distance from the edge to a free-space
/// boundary segment that lies at least partly beyond it.
fn clearance(e: &Edge2, keep_out: &[Edge2]) -> f64 {
    let dir = (e.b - e.a).normalize_or_zero();
    let outward = DVec2::new(dir.y, -dir.x);
    let beyond = |p: DVec2| (p - e.a).dot(outward) > 1e-9;
    keep_out
        .iter()
        .filter(|s| beyond(s.a) || beyond(s.b))
        .map(|s| seg_seg_distance(e.a, e.b, s.a, s.b))
        .fold(f64::INFINITY, f64::min)
}

fn seg_seg_distance(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
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

fn product_distance(p: DVec2, product: &[Edge2]) -> f64 {
    product
        .iter()
        .map(|e| e.distance(p))
        .fold(f64::INFINITY, f64::min)
}

/// The boundary passes: the product-adjacent stretches of the tool-centre
/// region's loops, in down-milling direction.
fn boundary_chains(g: &Geometry, band: f64, spindle: SpindleDirection) -> Vec<(Vec<Edge2>, bool)> {
    let mut chains = Vec::new();
    for lp in g.centre.loops() {
        let es = edges_of_pline(lp);
        let n = es.len();
        if n == 0 {
            continue;
        }
        let adj: Vec<bool> = es
            .iter()
            .map(|e| product_distance(e.midpoint(), &g.product) <= g.r + band)
            .collect();
        let mut found: Vec<(Vec<Edge2>, bool)> = Vec::new();
        if adj.iter().all(|a| *a) {
            found.push((es.clone(), true));
        } else if adj.iter().any(|a| *a) {
            // Start after a non-adjacent edge so no chain wraps.
            let s = (0..n).find(|&i| !adj[i]).unwrap_or(0);
            let mut cur: Vec<Edge2> = Vec::new();
            for k in 1..=n {
                let i = (s + k) % n;
                if adj[i] {
                    cur.push(es[i]);
                } else if !cur.is_empty() {
                    found.push((std::mem::take(&mut cur), false));
                }
            }
            if !cur.is_empty() {
                found.push((cur, false));
            }
        }
        for (mut c, closed) in found {
            // Loops keep cavalier's orientation: product on the right, which
            // is down milling with a clockwise (M3) spindle.
            if spindle == SpindleDirection::CounterClockwise {
                c = c
                    .iter()
                    .rev()
                    .map(|e| Edge2 {
                        a: e.b,
                        b: e.a,
                        bulge: -e.bulge,
                    })
                    .collect();
            }
            if closed {
                c = start_mid_longest(c);
            }
            chains.push((c, closed));
        }
    }
    chains
}

/// A closed chain restarted in the middle of its longest straight edge, so
/// the run-up meets it on a straight.
fn start_mid_longest(c: Vec<Edge2>) -> Vec<Edge2> {
    let Some((i, _)) = c
        .iter()
        .enumerate()
        .filter(|(_, e)| e.bulge == 0.0)
        .max_by(|a, b| a.1.length().total_cmp(&b.1.length()))
    else {
        return c;
    };
    let e = c[i];
    let m = (e.a + e.b) * 0.5;
    let mut out = vec![Edge2 {
        a: m,
        b: e.b,
        bulge: 0.0,
    }];
    for k in 1..c.len() {
        out.push(c[(i + k) % c.len()]);
    }
    out.push(Edge2 {
        a: e.a,
        b: m,
        bulge: 0.0,
    });
    out
}

fn chain_segs(c: &[Edge2]) -> Vec<Seg2> {
    c.iter()
        .map(|e| Seg2 {
            to: e.b,
            arc: e.arc().map(|(_, centre)| (centre, e.bulge > 0.0)),
        })
        .collect()
}

/// A boundary pass with its run-up and run-off: (start point, segments).
struct BoundaryPass {
    start: DVec2,
    segs: Vec<Seg2>,
    lead_in: &'static str,
}

fn arc_ok(from: DVec2, s: &Seg2, g: &Geometry, cleared: &[Vec<DVec2>]) -> bool {
    seg_points(from, s, STEP)
        .iter()
        .chain(std::iter::once(&from))
        .all(|p| inside(*p, cleared) && product_distance(*p, &g.product) >= g.r - EPS)
}

/// A pass with no room for a run-up whose start lies where the tool before
/// it did not cut (a rest pass starting in the corner that tool could not
/// reach): it goes down beside it, at the nearest point of `room`, and
/// comes in sideways along a straight line that keeps `r` from the
/// product, rather than plunging into the corner's material.
fn entered_from_room(mut p: BoundaryPass, g: &Geometry, room: &[Vec<DVec2>]) -> BoundaryPass {
    if p.lead_in != "none" || inside(p.start, room) {
        return p;
    }
    let Some(q) = nearest_inside(p.start, room) else {
        return p;
    };
    let seg = Seg2 {
        to: p.start,
        arc: None,
    };
    if seg_points(q, &seg, STEP / 4.0)
        .iter()
        .all(|x| product_distance(*x, &g.product) >= g.r - EPS)
    {
        p.segs.insert(0, seg);
        p.start = q;
        p.lead_in = "from-cleared-side";
    }
    p
}

/// The point of `polys` nearest `p` from outside, a hair inside them.
fn nearest_inside(p: DVec2, polys: &[Vec<DVec2>]) -> Option<DVec2> {
    const HAIR: f64 = 1e-3;
    let mut best: Option<(f64, DVec2)> = None;
    for pts in polys {
        let n = pts.len();
        for i in 0..n {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let c = a + ab * t;
            let d = c.distance(p);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, c));
            }
        }
    }
    let (_, c) = best?;
    let q = c + (c - p).normalize_or_zero() * HAIR;
    inside(q, polys).then_some(q)
}

fn boundary_pass(
    chain: &[Edge2],
    g: &Geometry,
    run_up: RunUp,
    d: f64,
    cleared: &[Vec<DVec2>],
    mk: &MethodKnowledge,
) -> BoundaryPass {
    let p0 = chain[0].a;
    let t0 = chain[0].tangents().0;
    let pe = chain[chain.len() - 1].b;
    let te = chain[chain.len() - 1].tangents().1;
    let mut segs = Vec::new();
    let mut start = p0;
    let mut lead_in = "from-open-side";
    // A pass starting outside the region starts in air beyond an open edge:
    // its own first stretch is the tangential run-up.
    if inside(p0, &g.region_polys) {
        lead_in = "none";
        let mut tries: Vec<(f64, bool)> = Vec::new();
        match run_up {
            RunUp::Circular { radius } => {
                for s in &mk.fit_scales {
                    tries.push((radius * d * s, true));
                }
                tries.push((radius * d, false));
            }
            RunUp::Tangential { length } => {
                for s in &mk.fit_scales {
                    tries.push((length * d * s, false));
                }
            }
        }
        for (rho, circular) in tries {
            let (s, seg) = if circular {
                // Quarter circle from the cleared side (left), tangent at p0.
                let c = p0 + t0.perp() * rho;
                (
                    c - t0 * rho,
                    Seg2 {
                        to: p0,
                        arc: Some((c, true)),
                    },
                )
            } else {
                (p0 - t0 * rho, Seg2 { to: p0, arc: None })
            };
            if arc_ok(s, &seg, g, cleared) {
                start = s;
                segs.push(seg);
                lead_in = if circular { "circular" } else { "tangential" };
                break;
            }
        }
    }
    segs.extend(chain_segs(chain));
    if inside(pe, &g.region_polys) {
        for s in &mk.fit_scales {
            let rho = mk.run_off_radius * d * s;
            let c = pe + te.perp() * rho;
            let seg = Seg2 {
                to: c + te * rho,
                arc: Some((c, true)),
            };
            if arc_ok(pe, &seg, g, cleared) {
                segs.push(seg);
                break;
            }
        }
    }
    BoundaryPass {
        start,
        segs,
        lead_in,
    }
}

/// Parallel passes over `polys`: lines along `dir`, progressing along
/// `progress` (±dir.perp()), at most `spacing` apart, reaching both extremes.
/// Zigzag blocks (connected where a straight step-over stays inside), or one
/// pass per block for one-way (travel `oneway_dir`).
/// Parallel lines across the tool-centre region `polys`, `spacing` apart at
/// most, joined into zigzag blocks (or one-way lines). `cover` is the
/// feature region and the tool radius: past an open edge the centre region
/// reaches a radius beyond the feature, where a line's disc only grazes
/// what the line before it cut, so the first and last lines engage at most
/// `spacing` (one line down the middle of a feature no wider than the
/// stepover and the tool). Issue 5: with the web layers above gone first, the
/// flange's cut-out slabs had every edge open and three times the lines.
#[allow(clippy::too_many_arguments)]
fn parallel_blocks(
    polys: &[Vec<DVec2>],
    cover: (&[Vec<DVec2>], f64),
    dir: DVec2,
    progress: DVec2,
    spacing: f64,
    extra_line: bool,
    start_high: bool,
    oneway: Option<DVec2>,
) -> (Vec<Vec<DVec2>>, usize) {
    let nrm = dir.perp();
    let sign = progress.dot(nrm).signum();
    let to_uv = |p: DVec2| DVec2::new(p.dot(dir), p.dot(nrm) * sign);
    let from_uv = |q: DVec2| dir * q.x + nrm * (q.y * sign);
    let uv: Vec<Vec<DVec2>> = polys
        .iter()
        .map(|p| p.iter().map(|q| to_uv(*q)).collect())
        .collect();
    let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &uv {
        for q in p {
            vmin = vmin.min(q.y);
            vmax = vmax.max(q.y);
        }
    }
    if !vmin.is_finite() {
        return (Vec::new(), 0);
    }
    let eps = 1e-4;
    let (mut lo, mut hi) = (vmin + eps, vmax - eps);
    let (region, r) = cover;
    let (mut cmin, mut cmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for q in region.iter().flatten() {
        let v = to_uv(*q).y;
        cmin = cmin.min(v);
        cmax = cmax.max(v);
    }
    if cmin.is_finite() {
        // One line covers a feature no wider than the stepover and the
        // tool; else the first line (either way: layers may be mirrored)
        // engages at most the stepover.
        let (a, b) = if cmax - cmin <= spacing.min(2.0 * r) {
            let mid = 0.5 * (cmin + cmax);
            (mid, mid)
        } else {
            (cmin - r + spacing, cmax + r - spacing)
        };
        let (a, b) = (lo.max(a), hi.min(b));
        if a <= b {
            (lo, hi) = (a, b);
        } else {
            let mid = (0.5 * (cmin + cmax)).max(lo).min(hi);
            (lo, hi) = (mid, mid);
        }
    }
    let span = (hi - lo).max(0.0);
    let mut n = if span < 1e-9 {
        1
    } else {
        (span / spacing).ceil() as usize + 1
    };
    if extra_line {
        n += 1;
    }
    let vs: Vec<f64> = (0..n)
        .map(|i| {
            if n == 1 {
                (lo + hi) / 2.0
            } else {
                lo + span * i as f64 / (n - 1) as f64
            }
        })
        .collect();
    let intervals: Vec<Vec<(f64, f64)>> = vs
        .iter()
        .map(|&v| {
            let mut xs = Vec::new();
            for p in &uv {
                let m = p.len();
                for i in 0..m {
                    let (a, b) = (p[i], p[(i + 1) % m]);
                    if (a.y > v) != (b.y > v) {
                        xs.push(a.x + (v - a.y) * (b.x - a.x) / (b.y - a.y));
                    }
                }
            }
            xs.sort_by(f64::total_cmp);
            xs.chunks_exact(2)
                .map(|c| (c[0], c[1]))
                .filter(|c| c.1 - c.0 > 1e-6)
                .collect()
        })
        .collect();
    let mut used: Vec<Vec<bool>> = intervals.iter().map(|l| vec![false; l.len()]).collect();
    let mut blocks: Vec<Vec<DVec2>> = Vec::new();
    if let Some(t) = oneway {
        let forward = t.dot(dir) >= 0.0;
        for (li, ivs) in intervals.iter().enumerate() {
            for iv in ivs {
                let (a, b) = if forward { (iv.0, iv.1) } else { (iv.1, iv.0) };
                blocks.push(vec![
                    from_uv(DVec2::new(a, vs[li])),
                    from_uv(DVec2::new(b, vs[li])),
                ]);
            }
        }
        return (blocks, n);
    }
    let mut last_end: Option<f64> = None;
    while let Some(li) = (0..intervals.len()).find(|&l| used[l].iter().any(|u| !u)) {
        // The interval whose end is nearest to where the last block ended.
        let ii = (0..intervals[li].len())
            .filter(|&i| !used[li][i])
            .min_by(|&a, &b| {
                let key = |i: usize| {
                    let iv = intervals[li][i];
                    match last_end {
                        Some(u) => (iv.0 - u).abs().min((iv.1 - u).abs()),
                        None => iv.0,
                    }
                };
                key(a).total_cmp(&key(b))
            })
            .unwrap_or(0);
        used[li][ii] = true;
        let iv = intervals[li][ii];
        let high_first = match last_end {
            Some(u) => (iv.1 - u).abs() < (iv.0 - u).abs(),
            None => start_high,
        };
        let (a, b) = if high_first {
            (iv.1, iv.0)
        } else {
            (iv.0, iv.1)
        };
        let mut block = vec![
            from_uv(DVec2::new(a, vs[li])),
            from_uv(DVec2::new(b, vs[li])),
        ];
        let mut cur_u = b;
        let mut cur_iv = iv;
        let mut l = li;
        while l + 1 < intervals.len() {
            let nl = l + 1;
            let cand = (0..intervals[nl].len())
                .filter(|&i| !used[nl][i])
                .filter(|&i| {
                    let c = intervals[nl][i];
                    c.0 <= cur_iv.1 + 1e-6 && c.1 >= cur_iv.0 - 1e-6
                })
                .min_by(|&x, &y| {
                    let dx = |i: usize| {
                        let c = intervals[nl][i];
                        (c.0 - cur_u).abs().min((c.1 - cur_u).abs())
                    };
                    dx(x).total_cmp(&dx(y))
                });
            let Some(ci) = cand else { break };
            let c = intervals[nl][ci];
            let (na, nb) = if (c.0 - cur_u).abs() <= (c.1 - cur_u).abs() {
                (c.0, c.1)
            } else {
                (c.1, c.0)
            };
            let from = from_uv(DVec2::new(cur_u, vs[l]));
            let to = from_uv(DVec2::new(na, vs[nl]));
            if !segment_inside(from, to, polys, STEP / 2.0) {
                break;
            }
            used[nl][ci] = true;
            block.push(to);
            block.push(from_uv(DVec2::new(nb, vs[nl])));
            cur_u = nb;
            cur_iv = c;
            l = nl;
        }
        last_end = Some(cur_u);
        blocks.push(block);
    }
    (blocks, n)
}

/// Cutting conditions: spindle speed and feeds (mm/min) for a tool.
fn conditions(env: &Env, tool: &Tool) -> (f64, f64, f64) {
    let c = &env.material.cutting;
    let rpm = (1000.0 * c.cutting_speed / (std::f64::consts::PI * tool.diameter))
        .min(env.machine.spindle_max_rpm);
    let vmax = 60.0 * env.machine.x.v_max.min(env.machine.y.v_max);
    let z = tool.flutes as f64;
    (
        rpm,
        (c.feed_per_tooth_roughing * z * rpm).min(vmax),
        (c.feed_per_tooth_finishing * z * rpm).min(vmax),
    )
}

/// The z-levels of a range from the top: `n` levels `dz` apart.
fn levels(top: f64, bottom: f64, depth: f64) -> Vec<f64> {
    let h = top - bottom;
    if h <= 1e-9 {
        return Vec::new();
    }
    let n = (h / depth - 1e-9).ceil().max(1.0) as usize;
    (1..=n)
        .map(|i| {
            if i == n {
                bottom
            } else {
                top - h * i as f64 / n as f64
            }
        })
        .collect()
}

/// Overlaps below this (mm) are contact, not collision (as in the holder
/// and shank check): a pass tangent to a neighbour's side touches it.
const CONTACT: f64 = 1e-3;

/// A feature's operations, kept clear of the shank (issue 5, item 5).
///
/// A tool cuts no deeper than its flute length per level, but beside a
/// machining feature that still stands, a level more than a flute length
/// below that feature's top puts the shank into it wherever the path
/// overhangs the shared edge. Such levels are planned as their own band
/// with that feature taken out of the free space, so the cutter only
/// touches it; the bands above are planned as before. A band that finds no
/// room that way (a step narrower than the tool beside it) keeps the
/// overhang and says so: the holder and shank check then reports it.
pub(crate) fn feature_operations(
    f: &MachiningFeature,
    env: &Env,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    obstacles: &[crate::free::Obstacle],
) -> Result<Made, String> {
    let whole = plan_band(f, env, free, removed)?;
    if env.orphans.is_some() {
        // Run last, when every other feature is gone: no shank bands.
        return Ok(whole);
    }
    let Some(free) = free else {
        return Ok(whole);
    };
    let Some(tool) = whole
        .ops
        .first()
        .and_then(|o| env.tools.tools.iter().find(|t| t.id == o.tool))
    else {
        return Ok(whole);
    };
    let (flute, r) = (tool.flute_length, tool.diameter / 2.0);
    // Each obstacle the tool's reach meets, with the height below which the
    // shank would be in it.
    let deep: Vec<(f64, &crate::free::Obstacle)> = obstacles
        .iter()
        .map(|o| (o.top - flute, o))
        .filter(|(z, o)| *z > f.shape.z_min + CONTACT && reaches(&whole.reach, o, r))
        .collect();
    if deep.is_empty() {
        return Ok(whole);
    }
    let mut cuts: Vec<f64> = deep
        .iter()
        .map(|(z, _)| *z)
        .filter(|z| *z < f.shape.z_max - CONTACT)
        .collect();
    cuts.extend([f.shape.z_max, f.shape.z_min]);
    cuts.sort_by(|a, b| b.total_cmp(a));
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let mut out = Made {
        ops: Vec::new(),
        warnings: whole.warnings.clone(),
        unreachable: Vec::new(),
        reach: whole.reach.clone(),
    };
    for w in cuts.windows(2) {
        let (hi, lo) = (w[0], w[1]);
        let mut band = f.clone();
        band.shape.z_max = hi;
        band.shape.z_min = lo;
        if lo > f.shape.z_min + 1e-9 {
            // Below this band stands the rest of the same feature.
            band.bottom_adjacency = Adjacency::Feature;
        }
        let active: Vec<&crate::free::Obstacle> = deep
            .iter()
            .filter(|(z, _)| *z >= hi - 1e-6)
            .map(|(_, o)| *o)
            .collect();
        let made = if active.is_empty() {
            match plan_band(&band, env, Some(free), removed) {
                Ok(m) => m,
                Err(e) => return Ok(unbanded(whole, f, lo, hi, &e)),
            }
        } else {
            let names: Vec<String> = active
                .iter()
                .map(|o| format!("{}(top {:.3})", o.id, o.top))
                .collect();
            let clear = crate::free::without(free, &active);
            // Its edges towards them are walls for this band: a pass runs
            // along them (the rest pattern alone would leave a strip where
            // the overhang used to reach).
            let mut walled = band.clone();
            walls_towards(&mut walled, &active);
            // Kept even where it reaches less than the overhanging plan in
            // this band: a shank in standing material is a collision the
            // verification would take the whole operation out for, while
            // what the band leaves is beside features cut later (their
            // passes, open towards this one, and stage 7's second pass).
            match plan_band(&walled, env, Some(&clear), removed) {
                Ok(mut m) => {
                    let lost = lost_area(&whole.ops, &m.ops, &band, r);
                    if lost > LOST_AREA {
                        m.warnings.push(format!(
                            "{}: levels {lo:.3}..{hi:.3} keep the shank out of {}: {lost:.1} mm² \
                             the overhang would reach is left to the features cut after it",
                            f.id,
                            names.join(", ")
                        ));
                    }
                    for op in &mut m.ops {
                        op.provenance.note.push_str(&format!(
                            "; shank_clear_of={} (flute {flute:.3} mm, band {lo:.3}..{hi:.3})",
                            names.join(",")
                        ));
                        op.provenance.values.insert("shank_band_top_mm".into(), hi);
                        if lost > LOST_AREA {
                            op.provenance
                                .values
                                .insert("shank_band_lost_mm2".into(), lost);
                        }
                    }
                    m
                }
                Err(e) => {
                    let mut m = match plan_band(&band, env, Some(free), removed) {
                        Ok(m) => m,
                        Err(e) => return Ok(unbanded(whole, f, lo, hi, &e)),
                    };
                    m.warnings.push(format!(
                        "{}: levels {lo:.3}..{hi:.3} cannot keep the shank out of {} ({e}); \
                         planned with the overhang, the shank rubs there",
                        f.id,
                        names.join(", ")
                    ));
                    m
                }
            }
        };
        out.ops.extend(made.ops);
        for w in made.warnings {
            if !out.warnings.contains(&w) {
                out.warnings.push(w);
            }
        }
        out.unreachable.extend(made.unreachable);
    }
    Ok(out)
}

/// The whole feature's plan, kept where a band of it cannot be planned on
/// its own (its shank clearance is then given up, and said).
fn unbanded(mut whole: Made, f: &MachiningFeature, lo: f64, hi: f64, e: &str) -> Made {
    whole.warnings.push(format!(
        "{}: levels {lo:.3}..{hi:.3} cannot be planned as a band of their own ({e}); \
         the feature is planned whole and its shank may rub taller features beside it",
        f.id
    ));
    whole
}

/// Marks as product the edges of `f` whose outward side lies in one of the
/// obstacles (only `feature` edges: the others face product or air).
fn walls_towards(f: &mut MachiningFeature, obstacles: &[&crate::free::Obstacle]) {
    let polys: Vec<Vec<Vec<DVec2>>> = obstacles
        .iter()
        .map(|o| {
            o.region
                .iter()
                .map(|c| c.iter().map(|q| DVec2::new(q[0], q[1])).collect())
                .collect()
        })
        .collect();
    let as_poly = |l: &thinplan_plan::ProfileLoop| -> Vec<DVec2> {
        l.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect()
    };
    let mut own_loops = vec![as_poly(&f.shape.region.outer)];
    own_loops.extend(f.shape.region.holes.iter().map(as_poly));
    let own = &own_loops;
    let mark = |l: &thinplan_plan::ProfileLoop, adj: &mut [Adjacency]| {
        let n = l.vertices.len();
        for (i, a) in adj.iter_mut().enumerate().take(n) {
            if *a != Adjacency::Feature {
                continue;
            }
            let (p, q) = (&l.vertices[i], &l.vertices[(i + 1) % n]);
            let (p, q) = (DVec2::new(p.x, p.y), DVec2::new(q.x, q.y));
            let t = (q - p).normalize_or_zero();
            // Outward: the side of the edge off the feature's own region.
            let m = (p + q) * 0.5;
            let nrm = DVec2::new(t.y, -t.x) * 1e-3;
            let probe = if inside(m + nrm, own) {
                m - nrm
            } else {
                m + nrm
            };
            if polys.iter().any(|o| inside(probe, o)) {
                *a = Adjacency::Product;
            }
        }
    };
    let outer = f.shape.region.outer.clone();
    mark(&outer, &mut f.side_adjacency);
    for (h, adj) in f
        .shape
        .region
        .holes
        .clone()
        .iter()
        .zip(f.hole_adjacency.iter_mut())
    {
        mark(h, adj);
    }
}

/// Plan-view area (mm²) a band may reach less than the whole feature's
/// plan before its shank clearance is given up: a few grid cells of noise.
const LOST_AREA: f64 = 1.0;
/// Grid step (mm) of the coverage comparison.
const COVER_STEP: f64 = 0.5;

/// Plan-view area of the band's region that the level passes of `whole`
/// at the band's heights reach and those of `band_ops` do not (mm²).
fn lost_area(whole: &[LocalOp], band_ops: &[LocalOp], band: &MachiningFeature, r: f64) -> f64 {
    let region: Vec<Vec<DVec2>> = {
        let mut v = vec![band
            .shape
            .region
            .outer
            .vertices
            .iter()
            .map(|q| DVec2::new(q.x, q.y))
            .collect::<Vec<_>>()];
        v.extend(
            band.shape
                .region
                .holes
                .iter()
                .map(|h| h.vertices.iter().map(|q| DVec2::new(q.x, q.y)).collect()),
        );
        v
    };
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for q in region.iter().flatten() {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    if !(lo.x.is_finite() && hi.x.is_finite()) {
        return 0.0;
    }
    let nx = ((hi.x - lo.x) / COVER_STEP).ceil() as usize + 1;
    let ny = ((hi.y - lo.y) / COVER_STEP).ceil() as usize + 1;
    let at = |i: usize, j: usize| lo + DVec2::new(i as f64, j as f64) * COVER_STEP;
    let (z_lo, z_hi) = (band.shape.z_min - 1e-6, band.shape.z_max + 1e-6);
    // The whole plan counts a cell only where its disc covers it with room
    // to spare, the band wherever its disc touches it: grazing is no loss.
    let cover = |ops: &[LocalOp], zs: bool| -> Vec<bool> {
        let mut hit = vec![false; nx * ny];
        let reach = if zs { (r - 0.05).max(0.0) } else { r + 1e-3 };
        for op in ops {
            let mut from = op.start;
            for m in &op.moves {
                // Level passes only: a ramp's first stretch may graze what
                // a later feature's overhang takes anyway.
                let cutting =
                    !matches!(m.kind, Kind::Rapid | Kind::Link) && (m.to.z - from.z).abs() < 1e-9;
                let in_band = !zs || (m.to.z >= z_lo && m.to.z <= z_hi);
                if cutting && in_band {
                    let s = Seg2 {
                        to: m.to.truncate(),
                        arc: m.arc,
                    };
                    let mut a = from.truncate();
                    for b in seg_points(a, &s, 1.0) {
                        let (p, q) = (a.min(b) - reach, a.max(b) + reach);
                        let i0 = ((p.x - lo.x) / COVER_STEP).floor().max(0.0) as usize;
                        let j0 = ((p.y - lo.y) / COVER_STEP).floor().max(0.0) as usize;
                        let i1 = (((q.x - lo.x) / COVER_STEP).ceil().max(0.0) as usize).min(nx - 1);
                        let j1 = (((q.y - lo.y) / COVER_STEP).ceil().max(0.0) as usize).min(ny - 1);
                        for j in j0..=j1 {
                            for i in i0..=i1 {
                                let k = j * nx + i;
                                if !hit[k] && crate::geom::dist_point_seg(at(i, j), a, b) <= reach {
                                    hit[k] = true;
                                }
                            }
                        }
                        a = b;
                    }
                }
                from = m.to;
            }
        }
        hit
    };
    let before = cover(whole, true);
    let after = cover(band_ops, false);
    let mut lost = 0usize;
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            if before[k] && !after[k] && inside(at(i, j), &region) {
                lost += 1;
            }
        }
    }
    lost as f64 * COVER_STEP * COVER_STEP
}

/// Whether a tool of radius `r` whose centre stays in `reach` comes closer
/// than contact to the obstacle's region.
fn reaches(reach: &[Vec<DVec2>], o: &crate::free::Obstacle, r: f64) -> bool {
    let obstacle: Vec<Vec<DVec2>> = o
        .region
        .iter()
        .map(|c| c.iter().map(|q| DVec2::new(q[0], q[1])).collect())
        .collect();
    let near = r - CONTACT;
    for poly in reach {
        for (k, &p) in poly.iter().enumerate() {
            if inside(p, &obstacle) {
                return true;
            }
            let q = poly[(k + 1) % poly.len()];
            for c in &obstacle {
                for i in 0..c.len() {
                    let (a, b) = (c[i], c[(i + 1) % c.len()]);
                    if seg_seg_distance(p, q, a, b) < near {
                        return true;
                    }
                }
            }
        }
    }
    false
}

fn plan_band(
    f: &MachiningFeature,
    env: &Env,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
) -> Result<Made, String> {
    if f.slopes.is_none() || env.k.methods.sloped_faces == SlopedFaces::AsVertical {
        return plan_band_with(f, env, free, removed, Slopes::AsVertical);
    }
    if let Some(why) = f.slopes.as_ref().and_then(|s| s.unusable()) {
        let mut m = plan_band_with(f, env, free, removed, Slopes::AsVertical)?;
        m.warnings.push(format!(
            "{}: its sampled sloped faces cannot be used ({why}); planned as vertical, \
             material stays on them",
            f.id
        ));
        return Ok(m);
    }
    // Sloped product faces: followed where the safety net holds (swept at
    // the edges' ends, else one shift per edge), else planned as vertical
    // at the region's section (material stays, none is cut beyond it),
    // and said.
    let followed = plan_band_with(f, env, free, removed, Slopes::Swept)
        .or_else(|_| plan_band_with(f, env, free, removed, Slopes::Shifted));
    match followed {
        Ok(mut m) => {
            // Provenance: how far the product edges moved for each tool.
            for op in &mut m.ops {
                let Some(tool) = env.tools.tools.iter().find(|t| t.id == op.tool) else {
                    continue;
                };
                if let Some(sh) = slope_shifts(f, tool) {
                    let most =
                        sh.into_iter()
                            .flatten()
                            .fold(0.0, |a: f64, b| if b.abs() > a.abs() { b } else { a });
                    op.provenance.values.insert("slope_shift_mm".into(), most);
                    op.provenance.note.push_str("; sloped_faces=Follow");
                }
            }
            Ok(m)
        }
        Err(e) => {
            let mut m = plan_band_with(f, env, free, removed, Slopes::AsVertical)?;
            m.warnings.push(format!(
                "{}: its sloped product faces cannot be followed ({e}); planned as vertical, \
                 material stays on them",
                f.id
            ));
            Ok(m)
        }
    }
}

/// Provenance of how sloped faces shaped the operation's region:
/// `slope_ends_swept` 1 where the product was swept at every height of the
/// corner radius (`Slopes::Swept`), 0 where each edge moved by one shift.
fn slope_values(prov: &mut Provenance, g: &Geometry) {
    match g.slopes {
        Slopes::AsVertical => {}
        Slopes::Shifted => {
            prov.values.insert("slope_ends_swept".into(), 0.0);
        }
        Slopes::Swept => {
            prov.values.insert("slope_ends_swept".into(), 1.0);
        }
    }
}

fn plan_band_with<'a>(
    f: &MachiningFeature,
    env: &Env<'a>,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    slopes: Slopes,
) -> Result<Made, String> {
    let mk = &env.k.methods;
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    if edges[0].0.len() < 2 {
        return Err("its profile has fewer than two vertices".into());
    }
    if f.shape.z_max.partial_cmp(&f.shape.z_min) != Some(std::cmp::Ordering::Greater) {
        return Err(format!(
            "empty depth range [{}, {}]",
            f.shape.z_min, f.shape.z_max
        ));
    }
    let sides = sides_class(&edges);
    let bottom_product = f.bottom_adjacency == Adjacency::Product;
    let m = mk
        .for_feature(bottom_product, sides)
        .ok_or_else(|| format!("no method applies (sides {sides:?})"))?;
    let mut warnings = Vec::new();
    let mut unreachable: Vec<String> = Vec::new();
    let mut reach_left: Vec<(String, f64)> = Vec::new();
    let mut corners_unreached = false;

    // Tool: by the method's rule, of a kind it allows, smaller than the
    // smallest product corner, and reaching the feature's floor.
    let mut cands: Vec<&'a Tool> = env
        .tools
        .tools
        .iter()
        .filter(|t| m.tool.kinds.contains(&t.kind))
        .collect();
    if cands.is_empty() {
        return Err(format!(
            "{NO_TOOL_FITS} (none of the kinds {:?} the method allows)",
            m.tool.kinds
        ));
    }
    // By the method's rule on the diameter; among tools of one diameter
    // the shortest stickout first (the stiffest that reaches: a long-reach
    // tool only where a standard one does not reach).
    let by_size = |a: &&Tool, b: &&Tool| {
        a.diameter
            .total_cmp(&b.diameter)
            .then_with(|| b.stickout.total_cmp(&a.stickout))
            .then_with(|| b.id.cmp(&a.id))
    };
    cands.sort_by(by_size);
    if m.tool.choice == ToolChoice::LargestThatFits {
        cands.reverse();
    } else {
        cands.sort_by(|a, b| {
            a.diameter
                .total_cmp(&b.diameter)
                .then_with(|| a.stickout.total_cmp(&b.stickout))
                .then_with(|| a.id.cmp(&b.id))
        });
    }
    let corner = smallest_product_corner(&edges);
    if let (Some(ratio), Some(rho)) = (m.tool.corner_ratio, corner) {
        let small: Vec<&Tool> = cands
            .iter()
            .copied()
            .filter(|t| t.diameter / 2.0 <= ratio * rho)
            .collect();
        if small.is_empty() {
            // The smallest tool leaves the least in those corners.
            cands.sort_by(|a, b| {
                a.diameter
                    .total_cmp(&b.diameter)
                    .then_with(|| a.stickout.total_cmp(&b.stickout))
                    .then_with(|| a.id.cmp(&b.id))
            });
            warnings.push(format!(
                "{}: no tool is smaller than its smallest product corner (radius {rho:.3} mm); \
                 the smallest that fits is used and material stays in those corners",
                f.id
            ));
            let needs = if rho > 0.0 {
                format!("; needs D <= {:.3} mm", 2.0 * ratio * rho)
            } else {
                "; a sharp corner: no end mill reaches it".into()
            };
            unreachable.push(format!(
                "unreachable: product corners of {} tighter than any tool (smallest corner \
                 radius {rho:.3} mm, smallest tool radius {:.3} mm): the material in them \
                 stays{needs}",
                f.id,
                cands[0].diameter / 2.0
            ));
            corners_unreached = true;
        } else {
            cands = small;
        }
    }
    let need = depth_below_top(env, f, f.shape.z_min);
    let (reaching, short): (Vec<&Tool>, Vec<&Tool>) = cands
        .iter()
        .copied()
        .partition(|t| tool_reach(env, t) >= need - 1e-9);
    let fits = |t: &'a Tool| geometry(f, m, t, free, removed, slopes).map(|g| (t, g));
    let mut short = short;
    // Deepest reach first: the most of the feature is cut.
    short.sort_by(|a, b| tool_reach(env, b).total_cmp(&tool_reach(env, a)));
    let (tool, g) = reaching
        .iter()
        .find_map(|t| fits(t))
        .or_else(|| short.iter().find_map(|t| fits(t)))
        .ok_or_else(|| {
            let smallest = cands
                .iter()
                .map(|t| t.diameter)
                .fold(f64::INFINITY, f64::min);
            format!(
                "{NO_TOOL_FITS} (the smallest, D {smallest:.3} mm, has no room at its radius \
                 from the product and the free space)"
            )
        })?;
    // A tool that fits but does not reach the floor cuts the levels it
    // reaches; below them the feature is refused, naming the tool it needs.
    let reach = tool_reach(env, tool);
    let clamped;
    let mut bottom_product = bottom_product;
    let f = if reach < need - 1e-9 {
        let z_reach = f.shape.z_min + (need - reach);
        let why = format!(
            "{NO_TOOL_REACHES}: {} below {z_reach:.3}, {need:.1} mm below the top of the stock: \
             the tool of the set that fits and reaches deepest, {} (D {:.3} mm), reaches \
             {reach:.1} mm; needs D <= {:.3} mm with {need:.1} mm reach (stickout {:.1} mm)",
            f.id,
            tool.id,
            tool.diameter,
            tool.diameter,
            need + env.k.methods.holder_clearance
        );
        if z_reach >= f.shape.z_max - 1e-6 {
            return Err(why);
        }
        let area = region_area(f);
        let mut c = f.clone();
        c.shape.z_min = z_reach;
        c.bottom_adjacency = Adjacency::Feature;
        warnings.push(format!("{}: {why}", f.id));
        reach_left.push((why, area * (z_reach - f.shape.z_min)));
        bottom_product = false;
        clamped = c;
        &clamped
    } else {
        f
    };
    // The corners' volume: the region less what the tool's disc sweeps,
    // over the feature's depth.
    let depth = f.shape.z_max - f.shape.z_min;
    let unreachable: Vec<(String, f64)> = unreachable
        .into_iter()
        .map(|r| {
            let v = if corners_unreached {
                unreached_area(&g) * depth
            } else {
                0.0
            };
            (r, v)
        })
        .chain(reach_left)
        .collect();
    let d = tool.diameter;
    let (rpm, feed_rough, feed_finish) = conditions(env, tool);
    let boundary = m.boundary.as_ref().filter(|_| !g.product.is_empty());
    let feed_boundary = match boundary {
        Some(b) if b.finishing => feed_finish,
        _ => feed_rough,
    };
    let s_b = boundary.map_or(0.0, |b| b.stepover * d);
    // The rest region keeps s_b from the boundary passes only: shrinking
    // it from every side would leave a band along non-product sides that
    // no pass visits (a narrow step beside a wall lost its far side).
    let rest_polys = if s_b > 0.0 && g.clipped {
        away_from_product(&g.centre_polys, &g.product, g.r + s_b)
    } else if s_b > 0.0 {
        g.centre.offset(s_b).polygons(STEP)
    } else {
        g.centre_polys.clone()
    };
    let chains = match boundary {
        Some(_) => boundary_chains(&g, 0.5 * s_b.max(1e-3), mk.spindle),
        None => Vec::new(),
    };
    let cleared_for_runup = if rest_polys.is_empty() {
        &g.centre_polys
    } else {
        &rest_polys
    };
    let passes: Vec<BoundaryPass> = match boundary {
        Some(b) => chains
            .iter()
            .map(|(c, _)| boundary_pass(c, &g, b.run_up, d, cleared_for_runup, mk))
            .collect(),
        None => Vec::new(),
    };
    for p in &passes {
        if p.lead_in == "none" {
            warnings.push(format!(
                "{}: a boundary pass starting at ({:.2}, {:.2}) has no room for a run-up",
                f.id, p.start.x, p.start.y
            ));
        }
    }

    // Pass direction: along the longest product edge, else the longest edge.
    let longest = |pred: &dyn Fn(Adjacency) -> bool| {
        edges
            .iter()
            .flat_map(|(es, adj)| es.iter().zip(adj.iter()))
            .filter(|(_, a)| pred(**a))
            .max_by(|a, b| a.0.length().total_cmp(&b.0.length()))
            .map(|(e, _)| *e)
    };
    let ref_edge = longest(&|a| a == Adjacency::Product)
        .or_else(|| longest(&|_| true))
        .ok_or("no edges")?;
    let dir = {
        let t = (ref_edge.b - ref_edge.a).normalize_or_zero();
        if t == DVec2::ZERO {
            DVec2::X
        } else {
            t
        }
    };
    // Passes progress towards the product (the boundary region is last).
    let progress = if g.product.is_empty() {
        dir.perp()
    } else {
        let pm: DVec2 =
            g.product.iter().map(|e| e.midpoint()).sum::<DVec2>() / g.product.len() as f64;
        let cm = centroid(&g.centre_polys);
        if (pm - cm).dot(dir.perp()) >= 0.0 {
            dir.perp()
        } else {
            -dir.perp()
        }
    };

    let angle = m.entry.angle_deg().to_radians();
    let flute = tool.flute_length;
    let z_top = f.shape.z_max;
    let z_min = f.shape.z_min;
    let bottom_layer = m.bottom_layer.as_ref().filter(|_| bottom_product);
    let z_main_bottom = match bottom_layer {
        Some(b) => (z_min + b.thickness).min(z_top),
        None => z_min,
    };
    let mut a_rest = (m.rest.depth * d).min(flute);
    let full_cut_always = matches!(m.full_cut, FullCut::Always { .. });
    if let FullCut::Always { depth_factor } = m.full_cut {
        a_rest *= depth_factor;
    }
    let a_b = boundary.map_or(f64::INFINITY, |b| (b.depth * d).min(flute));
    let zs = levels(z_top, z_main_bottom, a_rest);
    let safe_z = env.global_top.max(z_top) + mk.safe_clearance;
    // Local heights: the global top is along `up`; the feature's frame
    // origin sits on that axis at origin·up.
    let up_off = f
        .shape
        .frame
        .origin
        .dot(f.shape.frame.z.normalize_or_zero());
    let safe_z = (safe_z - up_off).max(z_top + mk.safe_clearance);
    // Rapids stop at the top of the stock, not of the feature: material
    // that features above leave (corners no tool reaches, refused
    // features) may stand over this one; the rest of the way down is fed.
    let rapid_floor = (env.global_top - up_off).clamp(z_top, safe_z);
    let space = Space {
        centre_region: &g.centre_polys,
        z_top: rapid_floor,
        safe_z,
        step: STEP,
    };

    // The rest pattern of one z-level, chosen once for all levels.
    let spacing = m.rest.stepover * d;
    let oneway_dir = -progress.perp() * spin_sign(mk.spindle);
    let mut rest_plan = RestPlan::default();
    let mut prov_values: Vec<(&str, f64)> = Vec::new();
    let mut notes = vec![
        format!("pattern={:?}", m.pattern),
        format!("sides={sides:?}"),
    ];
    let mut mirror = false;
    if m.pattern.is_spiral() {
        rest_plan = spiral_rest(f, m, &g, d, spacing, s_b, true, &mk.fit_scales, &mut notes)?;
    } else if !rest_polys.is_empty() {
        let oneway = (m.pattern == Pattern::OneWay).then_some(oneway_dir);
        // Parity (§4.3.3, figure 4.22): choose the line count and the first
        // pass's end so one z-level flows into the boundary pass and the
        // next z-level starts where this one ended.
        let mut best: Option<(f64, usize, RestPlan)> = None;
        for extra in [false, true] {
            for high in [false, true] {
                let (blocks, n) = parallel_blocks(
                    &rest_polys,
                    (&g.region_polys, g.r),
                    dir,
                    progress,
                    spacing,
                    extra,
                    high,
                    oneway,
                );
                if blocks.is_empty() {
                    continue;
                }
                let first = blocks[0][0];
                let last = *blocks.last().and_then(|b| b.last()).unwrap_or(&first);
                let cost = match (passes.first(), passes.last()) {
                    (Some(p), Some(q)) => last.distance(p.start) + end_of(q).distance(first),
                    _ => 0.0,
                } + if extra { spacing * 0.5 } else { 0.0 };
                let better = best.as_ref().is_none_or(|b| cost < b.0 - 1e-9);
                if better {
                    best = Some((
                        cost,
                        n,
                        RestPlan {
                            blocks,
                            lines: n,
                            helix: None,
                        },
                    ));
                }
                if passes.is_empty() {
                    break;
                }
            }
            if passes.is_empty() {
                break;
            }
        }
        if let Some((_, _, p)) = best {
            rest_plan = p;
        }
        let side_passes = rest_plan.lines + usize::from(!passes.is_empty());
        prov_values.push(("side_passes", side_passes as f64));
        // Mirrored alternating z-levels where a level ends away from its start.
        let first = rest_plan.blocks.first().map(|b| b[0]);
        let last = rest_plan.blocks.last().and_then(|b| b.last().copied());
        let ends_away = match (first, last) {
            (Some(a), Some(b)) => a.distance(b) > d,
            _ => false,
        };
        mirror = match m.mirror_layers {
            MirrorLayers::Never => false,
            MirrorLayers::Always => true,
            MirrorLayers::WhenOddPasses => ends_away,
        } && passes.is_empty()
            && oneway.is_none();
        if !passes.is_empty() && m.mirror_layers != MirrorLayers::Never && ends_away {
            notes.push(
                "mirror=refused-product-sides(down milling fixes the boundary direction)".into(),
            );
        }
        // §6.3.3 full-cut criterion: alternating layers with a full cut in
        // every second one vs. the parity-matched pattern used here.
        if let FullCut::WhenFewerSidePasses { depth_factor } = m.full_cut {
            if !passes.is_empty() {
                let l = zs.len();
                let pair = a_rest * (1.0 + depth_factor);
                let l_fc = 2 * ((z_top - z_main_bottom) / pair - 1e-9).ceil().max(1.0) as usize;
                let base = rest_plan.lines.saturating_sub(1).max(1) + 1;
                let alt = l_fc * base + l_fc / 2;
                let used = l * side_passes;
                prov_values.push(("full_cut_alternating_passes", alt as f64));
                prov_values.push(("parity_matched_passes", used as f64));
                if alt < used {
                    warnings.push(format!(
                        "{}: alternating layers with a full cut would take fewer side passes \
                         ({alt} < {used}); not built, the parity-matched pattern is used",
                        f.id
                    ));
                }
            }
        }
    }
    if mirror {
        notes.push("mirror=alternate".into());
    }

    let entry_kind = if full_cut_always {
        Kind::FullCut
    } else {
        Kind::Rest
    };
    let rho_c = m.corner_rounding * d;
    let mut ops = Vec::new();
    let mut main = Builder::new(DVec3::ZERO);
    let mut started = false;
    let mut z_prev = z_top;
    let mut layer_count = 0;
    for (li, &z) in zs.iter().enumerate() {
        let reversed = mirror && li % 2 == 1;
        let blocks: Vec<Vec<DVec2>> = if reversed {
            rest_plan
                .blocks
                .iter()
                .rev()
                .map(|b| b.iter().rev().copied().collect())
                .collect()
        } else {
            rest_plan.blocks.clone()
        };
        for (bi, block) in blocks.iter().enumerate() {
            if block.len() < 2 {
                continue;
            }
            go_to(&mut main, &mut started, &space, block[0], z_prev);
            let kind = if full_cut_always && bi == 0 {
                Kind::FullCut
            } else {
                Kind::Rest
            };
            let mark = (main.moves.len(), main.pos);
            if enter(
                &mut main,
                m.entry,
                block,
                z_prev,
                z,
                angle,
                d,
                &g,
                if bi == 0 { rest_plan.helix } else { None },
                mk,
                entry_kind,
            )
            .is_none()
            {
                if pinched(block) {
                    main.moves.truncate(mark.0);
                    main.pos = mark.1;
                    continue;
                }
                return Err(format!("no room to ramp into z-level {z:.3}"));
            }
            let segs = rounded(block, rho_c);
            if full_cut_always && bi == 0 && m.pattern.is_spiral() {
                // The first orbit of a spiral cuts the full width.
                let p0 = block[0];
                for s in &segs {
                    let k = if s.to.distance(p0) <= spacing {
                        Kind::FullCut
                    } else {
                        Kind::Rest
                    };
                    main.follow(std::slice::from_ref(s), z, k);
                }
            } else {
                main.follow(&segs, z, kind);
            }
        }
        boundary_level(
            &mut main,
            &mut started,
            &space,
            &passes,
            &rest_polys,
            z_prev,
            z,
            a_b,
            angle,
        );
        z_prev = z;
        layer_count += 1;
    }
    let base_values = |prov: &mut Provenance, stepover: f64, depth: f64, layers: usize| {
        prov.values.insert("tool_diameter_mm".into(), d);
        prov.values.insert("spindle_rpm".into(), rpm);
        prov.values.insert("feed_rough_mm_min".into(), feed_rough);
        prov.values.insert("feed_finish_mm_min".into(), feed_finish);
        prov.values
            .insert("feed_boundary_mm_min".into(), feed_boundary);
        prov.values.insert("stepover_rest_mm".into(), stepover);
        prov.values.insert("stepover_boundary_mm".into(), s_b);
        prov.values.insert("depth_of_cut_mm".into(), depth);
        prov.values.insert("layers".into(), layers as f64);
        if let Some(c) = corner {
            prov.values.insert("smallest_product_corner_mm".into(), c);
        }
    };
    let rule = format!("methods.{}", m.id);
    let lop = |moves: Builder, prov: Provenance| LocalOp {
        method: m.id.clone(),
        tool: tool.id.clone(),
        rpm,
        feed_rough,
        feed_finish,
        feed_boundary,
        feed_link: feed_rough * mk.link_feed_factor,
        start: moves.start,
        moves: moves.moves,
        provenance: prov,
    };
    if !main.moves.is_empty() {
        retract(&mut main, safe_z);
        let mut prov = Provenance::new(ProvenanceSource::Knowledge, rule.clone());
        base_values(
            &mut prov,
            spacing,
            (z_top - z_main_bottom) / layer_count.max(1) as f64,
            layer_count,
        );
        slope_values(&mut prov, &g);
        for (k, v) in &prov_values {
            prov.values.insert((*k).into(), *v);
        }
        prov.note = notes.join("; ");
        check(&main, &g, z_min, z_top, f)?;
        ops.push(lop(main, prov));
    }

    // The product-adjacent bottom layer: its own operation, finishing
    // conditions on all of it (§4.3.4, §6.3.1).
    if let Some(bl) = bottom_layer {
        let so = bl.stepover * d;
        let mut b = Builder::new(DVec3::ZERO);
        let mut started = false;
        let top = z_main_bottom;
        let mut bnotes = vec![
            format!("pattern={:?}", bl.pattern),
            "layer=bottom".to_string(),
        ];
        let blocks: Vec<Vec<DVec2>> = if bl.pattern.is_spiral() {
            let mut mm = m.clone();
            mm.pattern = bl.pattern;
            spiral_rest(f, &mm, &g, d, so, s_b, false, &mk.fit_scales, &mut bnotes)?.blocks
        } else {
            let oneway = (bl.pattern == Pattern::OneWay).then_some(oneway_dir);
            parallel_blocks(
                &rest_polys,
                (&g.region_polys, g.r),
                dir,
                progress,
                so,
                false,
                false,
                oneway,
            )
            .0
        };
        for block in &blocks {
            if block.len() < 2 {
                continue;
            }
            go_to(&mut b, &mut started, &space, block[0], top);
            let mark = (b.moves.len(), b.pos);
            if enter(
                &mut b,
                m.entry,
                block,
                top,
                z_min,
                angle,
                d,
                &g,
                None,
                mk,
                Kind::BottomFinish,
            )
            .is_none()
            {
                if pinched(block) {
                    b.moves.truncate(mark.0);
                    b.pos = mark.1;
                    continue;
                }
                return Err("no room to ramp into the bottom layer".into());
            }
            b.follow(&rounded(block, rho_c), z_min, Kind::BottomFinish);
        }
        boundary_level(
            &mut b,
            &mut started,
            &space,
            &passes,
            &rest_polys,
            top,
            z_min,
            a_b,
            angle,
        );
        if !b.moves.is_empty() {
            retract(&mut b, safe_z);
            let mut prov =
                Provenance::new(ProvenanceSource::Knowledge, format!("{rule}.bottom_layer"));
            base_values(&mut prov, so, top - z_min, 1);
            slope_values(&mut prov, &g);
            prov.note = bnotes.join("; ");
            check(&b, &g, z_min, z_top, f)?;
            ops.push(lop(b, prov));
        }
    }
    let mut wall_levels: Vec<f64> = zs.clone();
    if wall_levels.last().is_none_or(|z| *z > z_min + 1e-9) {
        wall_levels.push(z_min);
    }
    // What this feature's own passes cut, to find the wall stretches they
    // left (the centre region alone overstates it where it is too narrow
    // for a pass).
    let cuts_of = |ops: &[LocalOp]| {
        crate::coverage::Coverage::local(ops.iter().map(|o| {
            let t = env.tools.tools.iter().find(|t| t.id == o.tool);
            (
                o.moves.as_slice(),
                o.start,
                t.map_or(0.0, |t| 0.5 * t.diameter),
                t.map_or(0.0, |t| t.flute_length),
            )
        }))
    };
    let own_cuts = cuts_of(&ops);
    let ctx = RestCtx {
        f,
        m,
        env,
        free,
        removed,
        own_cuts: &own_cuts,
        tool,
        g: &g,
        after: None,
        z_min,
        z_top,
        levels: &wall_levels,
        safe_z,
        rapid_floor,
        geometries: Default::default(),
    };
    // Stage 7's second pass: only the orphan stretches.
    if let Some(cov) = env.orphans {
        let mut orphan = Vec::new();
        if let Some(w) = m.wall_rest.as_ref().filter(|_| !g.product.is_empty()) {
            match rest_pass(&ctx, Rest::Orphan(w, cov)) {
                Ok(Some(op)) => orphan.push(op),
                Ok(None) => {}
                Err(e) => warnings.push(format!("{}: no orphan wall rest pass: {e}", f.id)),
            }
        }
        return Ok(Made {
            ops: orphan,
            warnings,
            unreachable: Vec::new(),
            reach: g.centre_polys.clone(),
        });
    }
    // The wall rest passes: stretches of product wall this tool could not
    // come beside, finished by the next smaller tool right after it, and
    // what that one left by the next smaller again (a corner between two
    // walls stops each tool at its own radius from the crossing wall).
    if let Some(w) = m
        .wall_rest
        .as_ref()
        .filter(|_| !ops.is_empty() && !g.product.is_empty())
    {
        let mut after: Option<(&Tool, Geometry)> = None;
        loop {
            let own_cuts = cuts_of(&ops);
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
    // The rest pass: the fillet this tool's corner radius leaves along the
    // product walls' feet, finished by a smaller corner radius.
    if let Some(rp) = m
        .rest_pass
        .as_ref()
        .filter(|_| bottom_product && !ops.is_empty() && !g.product.is_empty())
    {
        match rest_pass(&ctx, Rest::Floor(rp)) {
            Ok(Some(op)) => ops.push(op),
            Ok(None) => {}
            Err(e) => warnings.push(format!("{}: no rest pass: {e}", f.id)),
        }
    }
    if ops.is_empty() {
        return Err("the tool-centre region is empty at every z-level".into());
    }
    Ok(Made {
        ops,
        warnings,
        unreachable,
        reach: g.centre_polys.clone(),
    })
}

/// Signed-area sum of sampled contours (outer loops ccw, holes cw).
fn contours_area(cs: &[Vec<[f64; 2]>]) -> f64 {
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

/// The feature's region area (mm²): outer loop less holes.
pub(crate) fn region_area(f: &MachiningFeature) -> f64 {
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let mut a = 0.0;
    for (k, (es, _)) in edges.iter().enumerate() {
        if es.len() < 2 {
            continue;
        }
        let s = pline_from_edges(es, true).area().abs();
        a += if k == 0 { s } else { -s };
    }
    a.max(0.0)
}

/// Area (mm²) of the region the tool's disc never covers, its centre
/// anywhere in the tool-centre region (corners tighter than the tool, room
/// the free space denies). Sampled polygons: an estimate, good to the
/// chords' sagitta along the boundary.
fn unreached_area(g: &Geometry) -> f64 {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let reach = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        g.centre.offset(-g.r).polygons(STEP)
    }))
    .unwrap_or_default();
    let conv = |ps: &[Vec<DVec2>]| -> Vec<Vec<[f64; 2]>> {
        ps.iter()
            .map(|p| p.iter().map(|q| [q.x, q.y]).collect())
            .collect()
    };
    let region = conv(&g.region_polys);
    let total = contours_area(&region).abs();
    let hit: crate::free::Shapes =
        region.overlay_as::<i64>(&conv(&reach), OverlayRule::Intersect, FillRule::EvenOdd);
    // Each shape: its outer contour, then its holes.
    let hit: f64 = hit
        .iter()
        .map(|sh| {
            sh.iter()
                .enumerate()
                .map(|(k, c)| {
                    let a = contours_area(std::slice::from_ref(c)).abs();
                    if k == 0 {
                        a
                    } else {
                        -a
                    }
                })
                .sum::<f64>()
        })
        .sum();
    (total - hit).max(0.0)
}

struct RestCtx<'a> {
    f: &'a MachiningFeature,
    m: &'a Method,
    env: &'a Env<'a>,
    free: Option<&'a crate::free::Shapes>,
    removed: Option<&'a crate::free::Shapes>,
    /// The cutting moves of the feature's own operations (local frame).
    own_cuts: &'a crate::coverage::Coverage,
    /// The feature's tool and its geometry.
    tool: &'a Tool,
    g: &'a Geometry,
    /// The tool of the last wall rest pass and its geometry: the next one
    /// finishes what it left, with a smaller tool.
    after: Option<(&'a Tool, &'a Geometry)>,
    z_min: f64,
    z_top: f64,
    /// The levels of the feature's passes, top down, the floor last.
    levels: &'a [f64],
    safe_z: f64,
    rapid_floor: f64,
    /// Each candidate tool's geometry of the feature, once for both rest
    /// passes (by tool id; `None`: no room).
    geometries: std::cell::RefCell<BTreeMap<String, Option<Geometry>>>,
}

impl<'a> RestCtx<'a> {
    /// The same context without the geometry cache.
    fn clone_shallow(&self) -> RestCtx<'a> {
        RestCtx {
            geometries: Default::default(),
            ..*self
        }
    }

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

/// Provenance value (1) of a wall rest pass for orphan stretches
/// ([`Rest::Orphan`]).
pub(crate) const ORPHAN: &str = "orphan_stretches";

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
/// radii), so the pass cuts the fillet and nothing more.
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
    // Run last, every other feature is gone: every edge that is not
    // product is open, and the removed space is the whole free space.
    let opened = |t: &Tool| {
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
    };
    // No smaller tool: a wall rest pass run last may use the feature's own
    // tool, with every other feature gone.
    let found = match rest {
        Rest::Orphan(..) => cands.iter().find_map(|t| opened(t).map(|g| (*t, g, false))),
        _ => cands
            .iter()
            .find_map(|t| c.geometry(t).map(|g| (*t, g, false)))
            .or_else(|| match rest {
                Rest::Wall(w) if w.run_last && cands.is_empty() && c.after.is_none() => {
                    opened(main).map(|g| (main, g, true))
                }
                _ => None,
            }),
    };
    let Some((small, g2, own)) = found else {
        return Ok(None);
    };
    let d2 = small.diameter;
    // Where the small tool's disc lies inside a disc the feature's tool
    // swept down to the floor: its centre region grown by r − r₂ (a hair
    // more, so the chains at exactly r₂ from the walls are inside). Orphan
    // stretches are cut last: the whole free space is cleared by then.
    let cleared = match rest {
        Rest::Orphan(..) => g2.centre_polys.clone(),
        _ => c.g.centre.offset(-(c.g.r - g2.r + 1e-2)).polygons(STEP),
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
    // The floor pass runs where the feature's tool was beside the wall; the
    // wall pass where it stayed more than `min_left` away.
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
    for (chain, _) in boundary_chains(&g2, band, mk.spindle) {
        let ok = |e: &Edge2| match rest {
            // wanted where some sample was not cut round at some level
            Rest::Orphan(w, cov) if g2.slopes == Slopes::AsVertical => {
                e.sample(STEP).iter().any(|p| {
                    c.levels
                        .iter()
                        .any(|&z| !cov.covers(crate::to_part(c.f, *p, z), g2.r, w.min_left))
                })
            }
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
                pts.iter().all(|p| !inside(*p, &beside))
                    || pts.iter().any(|p| {
                        c.levels
                            .iter()
                            .any(|&z| !c.own_cuts.covers(p.extend(z), g2.r, w.min_left))
                    })
            }
            Rest::Floor(_) => e
                .sample(STEP)
                .iter()
                .all(|p| inside(*p, &beside) == want_inside),
        };
        // A stretch ends where the feature's tool stopped being beside the
        // wall (floor) or came close enough (wall): decided piece by piece
        // along each edge (a whole edge would be refused for its last
        // millimetres, and the fillet along the rest left standing); the
        // accepted pieces of an edge are joined again (an edge kept whole is
        // kept as it was).
        let mut cur: Vec<Edge2> = Vec::new();
        let mut parts = Vec::new();
        for e in &chain {
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
        for part in parts {
            let len: f64 = part.iter().map(|e| e.length()).sum();
            if len < STEP {
                continue;
            }
            let pass = boundary_pass(&part, &g2, run_up, d2, &room, mk);
            passes.push(entered_from_room(pass, &g2, &room));
        }
    }
    if passes.is_empty() {
        return Ok(None);
    }
    let space = Space {
        centre_region: &room,
        z_top: c.rapid_floor,
        safe_z: c.safe_z,
        step: STEP,
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
    check(&b, &g2, c.z_min, c.z_top, c.f)?;
    let (rpm, feed_rough, feed_finish) = conditions(c.env, small);
    let suffix = match rest {
        Rest::Floor(_) => "rest_pass",
        Rest::Wall(_) | Rest::Orphan(..) => "wall_rest",
    };
    let mut prov = Provenance::new(
        ProvenanceSource::Knowledge,
        format!("methods.{}.{suffix}", c.m.id),
    );
    slope_values(&mut prov, &g2);
    let v = &mut prov.values;
    v.insert("tool_diameter_mm".into(), d2);
    v.insert("tool_corner_radius_mm".into(), small.corner_radius);
    v.insert("feature_tool_diameter_mm".into(), main.diameter);
    v.insert("feature_tool_corner_radius_mm".into(), main.corner_radius);
    v.insert("spindle_rpm".into(), rpm);
    v.insert("feed_finish_mm_min".into(), feed_finish);
    v.insert("feed_boundary_mm_min".into(), feed_finish);
    v.insert("passes".into(), passes.len() as f64);
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
                v.insert(crate::RUN_LAST.into(), 1.0);
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
            v.insert(crate::RUN_LAST.into(), 1.0);
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
        provenance: prov,
    }))
}

/// The part of one set of loops (outer loops and holes, even-odd) inside
/// another.
fn intersect_polys(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> Vec<Vec<DVec2>> {
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

fn spin_sign(s: SpindleDirection) -> f64 {
    match s {
        SpindleDirection::Clockwise => 1.0,
        SpindleDirection::CounterClockwise => -1.0,
    }
}

fn end_of(p: &BoundaryPass) -> DVec2 {
    p.segs.last().map_or(p.start, |s| s.to)
}

fn centroid(polys: &[Vec<DVec2>]) -> DVec2 {
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

#[derive(Default)]
struct RestPlan {
    blocks: Vec<Vec<DVec2>>,
    lines: usize,
    /// A helix about the spiral's centre (centre, tool-centre radius) the
    /// first block starts on: the spiral inside its circle is left out.
    helix: Option<(DVec2, f64)>,
}

/// The rest region of a closed pocket: the pocketing crate's curvilinear
/// spiral (or offset rings), without its finishing ring (the boundary pass
/// replaces it with true arcs).
#[allow(clippy::too_many_arguments)]
fn spiral_rest(
    f: &MachiningFeature,
    m: &Method,
    g: &Geometry,
    d: f64,
    stepover: f64,
    s_b: f64,
    centred_helix: bool,
    fit_scales: &[f64],
    notes: &mut Vec<String>,
) -> Result<RestPlan, String> {
    use thinplan_pocketing::{curvilinear_path, offset_path, Pocket, PocketParams};
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let outer = oriented(pline_from_edges(&edges[0].0, true), true);
    let islands = edges[1..]
        .iter()
        .map(|(es, _)| oriented(pline_from_edges(es, true), false))
        .collect();
    let pocket = Pocket::with_islands(format!("{}", f.id), outer, islands);
    let mut params = PocketParams::for_tool(d);
    params.stepover = stepover.min(d);
    params.finish_stepover = s_b.min(params.stepover);
    let res = if m.pattern == Pattern::CurvilinearSpiral {
        curvilinear_path(&pocket, &params).or_else(|_| offset_path(&pocket, &params))
    } else {
        offset_path(&pocket, &params)
    }
    .map_err(|e| format!("pocket path: {e}"))?;
    notes.push(format!("spiral={}", res.method.as_str()));
    if let Some(r) = &res.fallback_reason {
        notes.push(format!("fallback={r}"));
    }
    // A spiral about a centre entered by a helix about that centre (the
    // method's radius, shrunk as stage 7's fit rule does): the helix clears
    // a hole of radius ρ + r, so the spiral starts where it leaves the
    // circle (issue 6: no slotting first turn around a plunge hole).
    let mut helix = None;
    let mut res = res;
    if let (true, LevelEntry::Helix { radius, .. }, Some(_)) = (centred_helix, m.entry, res.center)
    {
        let radii: Vec<f64> = fit_scales.iter().map(|s| radius * d * s).collect();
        if let Some((trimmed, h)) = res.after_centred_helix(&radii) {
            let fits = inside(h.center, &g.centre_polys)
                && boundary_distance(h.center, &g.centre_polys) >= h.radius + 1e-6
                && product_distance(h.center, &g.product) >= g.r + h.radius;
            if fits {
                notes.push(format!("entry=centred helix r={:.3}", h.radius));
                helix = Some((h.center, h.radius));
                res = trimmed;
            }
        }
    }
    let mut pts: Vec<DVec2> = res.points[..res.finish_start.min(res.points.len())].to_vec();
    // Keep only points the tool centre may reach (the pocket crate offsets
    // the same region; this guards against its sampling chords).
    pts.retain(|p| product_distance(*p, &g.product) >= g.r + 0.5 * s_b);
    if pts.len() < 2 {
        return Ok(RestPlan::default());
    }
    Ok(RestPlan {
        blocks: vec![pts],
        lines: 1,
        helix,
    })
}

fn go_to(b: &mut Builder, started: &mut bool, space: &Space, to: DVec2, z_clear: f64) {
    if !*started {
        *b = Builder::new(to.extend(space.safe_z));
        b.line(to.extend(space.z_top), Kind::Rapid);
        b.line(to.extend(z_clear), Kind::Link);
        *started = true;
    } else {
        space.transit(b, to, z_clear);
    }
}

fn retract(b: &mut Builder, safe_z: f64) {
    let p = b.pos;
    b.line(p.truncate().extend(safe_z), Kind::Rapid);
}

/// Gets from `z_from` down to `z` at the block's start: a helix where the
/// method asks and it fits, else a ramp along the block; `None` if neither.
#[allow(clippy::too_many_arguments)]
fn enter(
    b: &mut Builder,
    entry: LevelEntry,
    block: &[DVec2],
    z_from: f64,
    z: f64,
    angle: f64,
    d: f64,
    g: &Geometry,
    centred: Option<(DVec2, f64)>,
    mk: &MethodKnowledge,
    kind: Kind,
) -> Option<()> {
    let spindle = mk.spindle;
    if z_from - z <= 1e-12 {
        return Some(());
    }
    // Down milling around the helix: counter-clockwise for M3.
    let ccw = spindle == SpindleDirection::Clockwise;
    if let Some((c, rho)) = centred {
        // A spiral started where it leaves this helix's circle: only this
        // helix clears the middle, so there is no other way in.
        let fits = inside(c, &g.centre_polys)
            && boundary_distance(c, &g.centre_polys) >= rho + 1e-6
            && product_distance(c, &g.product) >= g.r + rho;
        if !fits {
            return None;
        }
        let a0 = (block[0] - c).to_angle();
        helix(b, c, rho, a0, z_from, z, angle, ccw, kind);
        return Some(());
    }
    if let LevelEntry::Helix { radius, .. } = entry {
        let p0 = block[0];
        for s in &mk.fit_scales {
            let rho = radius * d * s;
            let c = p0 - DVec2::new(rho, 0.0);
            let fits = inside(c, &g.centre_polys)
                && boundary_distance(c, &g.centre_polys) >= rho + 1e-6
                && product_distance(c, &g.product) >= g.r + rho;
            if fits {
                helix(b, c, rho, 0.0, z_from, z, angle, ccw, kind);
                return Some(());
            }
        }
    }
    let min_len = 0.02 * d;
    if ramp(b, block, z_from, z, angle, min_len, kind).is_some() {
        return Some(());
    }
    // The block is too short to ramp along (a small rest region): ramp back
    // and forth along the longest straight run from its start that stays in
    // the tool-centre region, the direction found among 24.
    let p0 = block[0];
    let need = (z_from - z) / angle.tan();
    let (mut best, mut best_len) = (p0, 0.0);
    let limit = need.max(min_len);
    let h = STEP / 2.0;
    let ok = |p: DVec2| inside(p, &g.centre_polys) || boundary_distance(p, &g.centre_polys) < 1e-6;
    for k in 0..24 {
        let u = DVec2::from_angle(std::f64::consts::TAU * k as f64 / 24.0);
        // Walk out in half-steps until the run leaves the region.
        let mut len = 0.0;
        while len < limit {
            let next = (len + h).min(limit);
            if !ok(p0 + u * next) {
                break;
            }
            len = next;
        }
        if len > best_len + 1e-9 {
            best_len = len;
            best = p0 + u * len;
        }
        if best_len >= limit {
            break;
        }
    }
    ramp(b, &[p0, best], z_from, z, angle, min_len, kind)
}

/// The boundary passes of one z-level, stacked where the z-level is deeper
/// than the boundary depth of cut.
#[allow(clippy::too_many_arguments)]
fn boundary_level(
    b: &mut Builder,
    started: &mut bool,
    space: &Space,
    passes: &[BoundaryPass],
    rest_polys: &[Vec<DVec2>],
    z_prev: f64,
    z: f64,
    a_b: f64,
    angle: f64,
) {
    if passes.is_empty() {
        return;
    }
    let m = ((z_prev - z) / a_b - 1e-9).ceil().max(1.0) as usize;
    for j in 1..=m {
        let zj = if j == m {
            z
        } else {
            z_prev - (z_prev - z) * j as f64 / m as f64
        };
        for p in passes {
            let here = b.pos.truncate();
            if *started
                && !rest_polys.is_empty()
                && inside(here, rest_polys)
                && segment_inside(here, p.start, rest_polys, STEP)
            {
                // Through the rest region just cleared at this level.
                b.line(p.start.extend(b.pos.z), Kind::Link);
                b.line(p.start.extend(zj), Kind::Link);
            } else {
                // Down to the height cleared so far, then ramp along the
                // pass itself (its centre keeps r from the product) rather
                // than plunging; a pass that starts beyond an open edge
                // starts in air.
                let z_hi = if j == 1 {
                    z_prev
                } else {
                    z_prev - (z_prev - z) * (j - 1) as f64 / m as f64
                };
                go_to(b, started, space, p.start, z_hi);
                if z_hi > zj + 1e-12 {
                    // The straight stretch the pass starts with (a chord of
                    // one of its arcs would come closer than r); an entry,
                    // so its legs back are roughing, not boundary, moves.
                    let mut prefix = vec![p.start];
                    for sg in p.segs.iter().take_while(|sg| sg.arc.is_none()) {
                        prefix.push(sg.to);
                    }
                    let ramped = p.lead_in != "from-open-side"
                        && ramp(b, &prefix, z_hi, zj, angle, STEP, Kind::Rest).is_some();
                    if !ramped {
                        b.line(p.start.extend(zj), Kind::Link);
                    }
                }
            }
            b.follow(&p.segs, zj, Kind::Boundary);
        }
    }
}

/// The safety net: every feed move's tool centre at least r from every
/// product edge and never below the feature's floor; rapids above its top.
fn check(
    b: &Builder,
    g: &Geometry,
    z_min: f64,
    z_top: f64,
    f: &MachiningFeature,
) -> Result<(), String> {
    // Only edges within r of a centre can fail it: bucketed once.
    let grids = (
        crate::geom::EdgeGrid::new(&g.product_offset, g.r),
        crate::geom::EdgeGrid::new(&g.keep_out, g.r),
    );
    let slope_grids: Vec<crate::geom::EdgeGrid> = g
        .slope_check
        .iter()
        .map(|(rho, e)| crate::geom::EdgeGrid::new(e, *rho))
        .collect();
    let near = |p: DVec2, edges: &[Edge2], grid: &crate::geom::EdgeGrid| {
        grid.candidates(p)
            .iter()
            .map(|&k| edges[k as usize].distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let mut from = b.start;
    for mv in &b.moves {
        if mv.kind == Kind::Rapid {
            // Rapids: straight up out of cleared space, or above the top.
            let vertical_up =
                from.truncate().distance(mv.to.truncate()) < 1e-9 && mv.to.z >= from.z;
            if !vertical_up && from.z.min(mv.to.z) < z_top - 1e-9 {
                let p = mv.to;
                return Err(format!(
                    "internal: a rapid move of {} runs below the feature top at ({:.3}, {:.3}, {:.3})",
                    f.id, p.x, p.y, p.z
                ));
            }
            from = mv.to;
            continue;
        }
        for p in crate::path::move_points(from, mv, STEP)
            .into_iter()
            .chain([from])
        {
            if mv.kind == Kind::Rapid {
                if p.z < z_top - 1e-9 {
                    return Err(format!(
                        "internal: a rapid move of {} runs below the feature top at ({:.3}, {:.3}, {:.3})",
                        f.id, p.x, p.y, p.z
                    ));
                }
                continue;
            }
            if p.z < z_min - 1e-9 {
                return Err(format!("a move goes below the floor at z {:.4}", p.z));
            }
            for ((rho, edges), grid) in g.slope_check.iter().zip(&slope_grids) {
                let dist = near(p.truncate(), edges, grid);
                if dist < rho - EPS_SLOPE {
                    return Err(format!(
                        "a move would touch a sloped product face: tool centre ({:.3}, {:.3}, \
                         {:.3}) is {dist:.6} mm from it where the tool's section radius is \
                         {rho:.6}",
                        p.x, p.y, p.z
                    ));
                }
            }
            let own = near(p.truncate(), &g.product_offset, &grids.0);
            let other = near(p.truncate(), &g.keep_out, &grids.1);
            let dist = own.min(other);
            if dist < g.r - EPS {
                let which = if own <= other {
                    "product edge"
                } else {
                    "free-space boundary (other product)"
                };
                return Err(format!(
                    "a move would touch product: tool centre ({:.3}, {:.3}) of a {:?} move is \
                     {:.4} mm from a {which}, tool radius {:.3}",
                    p.x, p.y, mv.kind, dist, g.r
                ));
            }
        }
        from = mv.to;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A pocket's corner chain as the mesh sections give it: a wall, a
    /// fillet of radius `r` in `k` chords (each optionally split in two by
    /// a collinear vertex), another wall turning 90° in all, and a sharp
    /// 90° corner closing nothing (turns and lengths only).
    fn filleted(r: f64, k: usize, wall: f64, split: bool) -> (Vec<f64>, Vec<f64>) {
        let step = std::f64::consts::FRAC_PI_2 / k as f64;
        let chord = 2.0 * r * (0.5 * step).sin();
        // Edge 0: the first wall; then the chords; then the second wall.
        let mut lengths = vec![wall];
        let mut turns = vec![0.5 * step];
        for c in 0..k {
            if split {
                lengths.extend([0.3 * chord, 0.7 * chord]);
                turns.push(0.0);
            } else {
                lengths.push(chord);
            }
            turns.push(if c + 1 == k { 0.5 * step } else { step });
        }
        lengths.push(wall);
        // The second wall meets the first one's start at a sharp corner.
        turns.push(std::f64::consts::FRAC_PI_2);
        (turns, lengths)
    }

    proptest! {
        /// A tessellated fillet reads as its radius (within 3 %), the sharp
        /// corner as 0, whatever the chord count, wall length and collinear
        /// splits.
        #[test]
        fn a_fillets_chords_give_its_radius_and_a_sharp_corner_zero(
            r in 1.0f64..20.0,
            k in 8usize..40,
            wall in 5.0f64..200.0,
            split in any::<bool>(),
        ) {
            let (turns, lengths) = filleted(r, k, wall, split);
            let mut radii = corner_radii(&turns, &lengths);
            radii.sort_by(f64::total_cmp);
            prop_assert_eq!(radii.len(), 2, "{:?}", radii);
            prop_assert_eq!(radii[0], 0.0);
            prop_assert!((radii[1] - r).abs() <= 0.03 * r, "{} for {}", radii[1], r);
        }

        /// Two fillets joined by a wall tangent to both stay two fillets:
        /// the wall is no chord.
        #[test]
        fn a_wall_between_two_fillets_is_not_a_chord(
            r in 1.0f64..20.0,
            k in 8usize..30,
            wall in 20.0f64..200.0,
        ) {
            let (mut turns, mut lengths) = filleted(r, k, wall, false);
            // Replace the sharp corner by a second fillet.
            turns.pop();
            let (t2, l2) = filleted(r, k, wall, false);
            turns.extend(&t2[..t2.len() - 1]);
            lengths.extend(&l2[1..]);
            turns.push(-1.0);
            let radii = corner_radii(&turns, &lengths);
            prop_assert_eq!(radii.len(), 2, "{:?}", radii);
            for x in radii {
                prop_assert!((x - r).abs() <= 0.03 * r, "{} for {}", x, r);
            }
        }
    }

    fn bull_nose(d: f64, rc: f64) -> Tool {
        crate::test_tool(d, rc)
    }

    /// A 45° chamfer sampled as stage 6 does (section at `at`, slabs 0.5
    /// thick, sampled 1.5 mm above): the face lies `z − at` beyond the edge.
    fn chamfer(at: f64) -> (EdgeSlopes, Vec<f64>) {
        let heights = vec![at - 0.25, at, at + 0.25, at + 0.75, at + 1.25, at + 1.75];
        let offsets = heights.iter().map(|z| z - at).collect();
        (
            EdgeSlopes {
                heights,
                side: Vec::new(),
                holes: Vec::new(),
            },
            offsets,
        )
    }

    /// The torus tangent to a 45° plane (the tangency worked out by hand):
    /// the tool's edge stands rc·(1 − tan 22.5°) inside the face's trace at
    /// the tip's height, so the axis is that much less than r from the
    /// trace, which lies `at − tip` inside the edge.
    #[test]
    fn the_torus_touches_a_chamfer_where_the_tangency_says() {
        for (d, rc) in [(20.0, 1.0), (12.0, 0.5), (10.0, 3.0), (8.0, 0.0)] {
            let tool = bull_nose(d, rc);
            let (s, o) = chamfer(50.0);
            let tip = 49.75;
            let want = d / 2.0 - rc * (1.0 - (std::f64::consts::PI / 8.0).tan()) + (50.0 - tip);
            let got = reach_needed(&s, &o, tip, &tool);
            assert!((got - want).abs() < 1e-9, "d {d} rc {rc}: {got} vs {want}");
        }
        // A vertical face needs the full radius, whatever the corner.
        let s = EdgeSlopes {
            heights: vec![0.0, 1.0],
            side: Vec::new(),
            holes: Vec::new(),
        };
        assert!((reach_needed(&s, &[0.0, 0.0], 0.0, &bull_nose(20.0, 1.0)) - 10.0).abs() < 1e-12);
    }

    proptest! {
        /// The exact maximum against a dense sampling of the tool's
        /// profile over a random piecewise-linear face: never below it
        /// (the tool would cut the face), and above it only by the
        /// sampling's own error.
        #[test]
        fn reach_needed_is_the_profiles_largest_overlap(
            steps in prop::collection::vec(0.05f64..1.0, 1..6),
            offsets in prop::collection::vec(-2.0f64..2.0, 6),
            tip_frac in 0.0f64..1.0,
            d in 2.0f64..25.0,
            rc_frac in 0.0f64..1.0,
        ) {
            let mut heights = vec![10.0];
            for s in &steps {
                heights.push(heights.last().unwrap() + s);
            }
            let n = heights.len();
            let offsets: Vec<f64> = offsets.into_iter().take(n).collect();
            prop_assume!(offsets.len() == n);
            let s = EdgeSlopes { heights: heights.clone(), side: Vec::new(), holes: Vec::new() };
            let tool = bull_nose(d, rc_frac * d / 2.0);
            let tip = heights[0] + tip_frac * (heights[n - 1] - heights[0]);
            let got = reach_needed(&s, &offsets, tip, &tool);
            let span = (heights[n - 1] - tip).max(0.0) + tool.corner_radius + 1.0;
            let dense = (0..=200_000)
                .map(|i| {
                    let h = span * i as f64 / 200_000.0;
                    section_radius(&tool, h) - s.beyond(&offsets, tip + h)
                })
                .fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(got >= dense - 1e-9, "{got} < {dense}");
            prop_assert!(got <= dense + 2e-3, "{got} > {dense}");
        }
    }

    /// A U-shaped cut-out's round bottom (R8) in a 2 mm flange: the slab's
    /// region is the gap between the flange's two ends, the tool (wider
    /// than the gap) reaches in from beside the flange and pivots about
    /// the ends. Checked here against the flange itself, independently of
    /// the plan's sampled faces: at 2000 heights over the tool's profile
    /// every point of the swept centre region keeps the section radius from
    /// both ends of the flange (rectangles whose gap narrows downward),
    /// and the swept region holds the one-shift region and reaches further
    /// in towards the flange. Once more with one end's edge in two pieces
    /// whose samples part, so their moved copies are joined at some heights
    /// only.
    #[test]
    fn swept_region_pivots_about_a_thin_flange_and_stays_off_it() {
        let k = thinplan_knowledge::Knowledge::builtin().unwrap();
        let m = k
            .methods
            .for_feature(false, SidesMatch::PartiallyOpen)
            .unwrap()
            .clone();
        let tool = bull_nose(20.0, 1.0);
        let (cx, zc, rb) = (50.0, 33.0, 8.0);
        let half = |z: f64| (rb * rb - (z.min(zc) - zc).powi(2)).max(0.0).sqrt();
        let (z0, z1) = (25.5, 25.75);
        let a = half(0.5 * (z0 + z1));
        let v = |x: f64, y: f64| thinplan_plan::ProfileVertex { x, y, bulge: 0.0 };
        let heights: Vec<f64> = (0..=60).map(|i| z0 + 0.05 * i as f64).collect();
        let beyond: Vec<f64> = heights.iter().map(|z| half(*z) - a).collect();
        // The right end's edge once whole and once in two pieces whose
        // samples part slightly (nearer the region: conservative), so the
        // moved pieces are joined at some heights and not at others.
        let near: Vec<f64> = beyond
            .iter()
            .enumerate()
            .map(|(i, b)| if i % 2 == 0 { b - 2e-3 } else { *b })
            .collect();
        for split in [false, true] {
            let mut outer = vec![
                v(cx - a, 0.0),
                v(cx + a, 0.0),
                v(cx + a, 2.0),
                v(cx - a, 2.0),
            ];
            let mut side_adjacency = vec![
                Adjacency::Open,
                Adjacency::Product,
                Adjacency::Open,
                Adjacency::Product,
            ];
            let mut side = vec![Vec::new(), beyond.clone(), Vec::new(), beyond.clone()];
            if split {
                outer.insert(2, v(cx + a, 1.2));
                side_adjacency.insert(2, Adjacency::Product);
                side.insert(2, near.clone());
            }
            let f = MachiningFeature {
                id: thinplan_plan::MachiningFeatureId(1),
                owner: thinplan_plan::StiffnessFeatureId(0),
                shape: thinplan_plan::Prism {
                    frame: thinplan_plan::PrismFrame {
                        origin: DVec3::ZERO,
                        x: DVec3::X,
                        z: DVec3::Z,
                    },
                    region: thinplan_plan::Region {
                        outer: thinplan_plan::ProfileLoop { vertices: outer },
                        holes: Vec::new(),
                    },
                    z_min: z0,
                    z_max: z1,
                },
                side_adjacency,
                hole_adjacency: Vec::new(),
                bottom_adjacency: Adjacency::Open,
                slopes: Some(EdgeSlopes {
                    heights: heights.clone(),
                    side,
                    holes: Vec::new(),
                }),
                provenance: Provenance::new(ProvenanceSource::Default, "test"),
            };
            // The free space at the slab's middle: a box less the flange.
            let free: crate::free::Shapes = vec![vec![vec![
                [30.0, -20.0],
                [70.0, -20.0],
                [70.0, 0.0],
                [cx + a, 0.0],
                [cx + a, 2.0],
                [70.0, 2.0],
                [70.0, 22.0],
                [30.0, 22.0],
                [30.0, 2.0],
                [cx - a, 2.0],
                [cx - a, 0.0],
                [30.0, 0.0],
            ]]];
            let swept = geometry(&f, &m, &tool, Some(&free), Some(&free), Slopes::Swept).unwrap();
            let shifted =
                geometry(&f, &m, &tool, Some(&free), Some(&free), Slopes::Shifted).unwrap();
            assert_eq!(swept.slopes, Slopes::Swept);
            assert_eq!(shifted.slopes, Slopes::Shifted);

            // Distance from p to the flange at height z (two rectangles).
            let flange = |p: DVec2, z: f64| -> f64 {
                let g = half(z);
                let dy = if p.y < 0.0 {
                    -p.y
                } else if p.y > 2.0 {
                    p.y - 2.0
                } else {
                    0.0
                };
                let dx = (p.x - cx).abs();
                let dx = if dx >= g { 0.0 } else { g - dx };
                dx.hypot(dy)
            };
            let r = 10.0;
            let rc = 1.0;
            let section = |h: f64| {
                if h >= rc {
                    r
                } else {
                    r - rc + (rc * rc - (rc - h) * (rc - h)).sqrt()
                }
            };
            let mut pts: Vec<DVec2> = swept.centre_polys.iter().flatten().copied().collect();
            let mut y = -12.0;
            while y < 14.0 {
                let mut x = 36.0;
                while x < 64.0 {
                    let p = DVec2::new(x, y);
                    if inside(p, &swept.centre_polys) {
                        pts.push(p);
                    }
                    x += 0.05;
                }
                y += 0.05;
            }
            assert!(pts.len() > 1000, "{}", pts.len());
            let mut worst = f64::INFINITY;
            for i in 0..=2000 {
                let h = 3.0 * i as f64 / 2000.0;
                let rho = section(h);
                for p in &pts {
                    worst = worst.min(flange(*p, z0 + h) - rho);
                }
            }
            assert!(
                worst >= -1e-6,
                "a tool centre is {worst} inside the flange's reach"
            );
            // The one-shift region lies within the swept one, which reaches
            // further in beside the flange's ends.
            for p in shifted.centre_polys.iter().flatten() {
                assert!(
                    inside(*p, &swept.centre_polys)
                        || boundary_distance(*p, &swept.centre_polys) < 1e-3,
                    "({}, {}) of the shifted region outside the swept one",
                    p.x,
                    p.y
                );
            }
            let deepest = |g: &Geometry| {
                g.centre_polys
                    .iter()
                    .flatten()
                    .filter(|p| (p.x - cx).abs() < 0.5 && p.y > 2.0)
                    .map(|p| p.y)
                    .fold(f64::INFINITY, f64::min)
            };
            let (ds, dh) = (deepest(&swept), deepest(&shifted));
            assert!(
                ds < dh - 0.2,
                "split {split}: swept reaches y {ds}, shifted {dh}"
            );
        }
    }
}
