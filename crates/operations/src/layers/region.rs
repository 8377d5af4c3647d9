//! The tool-centre region: where the centre of a given tool may go in a
//! feature. The region moves out beyond its non-product edges by the
//! overhang the method allows, is clipped to the free space around the
//! feature (other product the tool must keep clear of), follows sloped
//! product faces, and is offset in by the tool's radius. Every pass of a
//! band is built inside it, and the safety net holds passes to the edges
//! it was made from.

use cavalier_contours::polyline::{PlineSource, Polyline};
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};
use glam::DVec2;
use thinplan_knowledge::{Method, Tool};
use thinplan_plan::{Adjacency, MachiningFeature};

use super::plan_view::{contours_area, seg_seg_distance};
use super::slopes::{
    moved_edges, moved_product, relaxed_shifts, slope_check, slope_shifts, swept_cuts, Slopes,
};
use super::{Loops, STEP};
use crate::geom::{adjacency_edges, move_edges, oriented, pline_from_edges, Area, Edge2};

/// The geometry of a feature for one tool.
#[derive(Clone)]
pub(super) struct Geometry {
    pub(super) r: f64,
    /// Tool-centre region and its sampled polygons.
    pub(super) centre: Area,
    pub(super) centre_polys: Vec<Vec<DVec2>>,
    /// The feature region itself, sampled.
    pub(super) region_polys: Vec<Vec<DVec2>>,
    /// Product edges the tool's radius is measured from: which stretches
    /// of the region run along product, bands, entries. With `Swept`,
    /// where one shift per edge put them (conservative at the edges' ends,
    /// where the swept region reaches further).
    pub(super) product: Vec<Edge2>,
    /// Product edges the region was offset from, which the safety net
    /// holds every tool centre `r` away from (`product` but with `Swept`).
    pub(super) product_offset: Vec<Edge2>,
    /// Boundaries of the free space around the feature (other product the
    /// tool must keep r from, see `free.rs`).
    pub(super) keep_out: Vec<Edge2>,
    /// The region was clipped to the free space (straight edges only).
    pub(super) clipped: bool,
    /// How sloped product faces (`MachiningFeature::slopes`) were
    /// followed: the product edges above are moved to where the tool's
    /// profile touches the face.
    pub(super) slopes: Slopes,
    /// The product's edges at heights over the tool's profile, each with
    /// the tool's section radius there: the safety net for sloped faces
    /// (every tool centre at least that far from them). Empty when not
    /// `Slopes::AsVertical`.
    pub(super) slope_check: Vec<(f64, Vec<Edge2>)>,
}

/// The geometry of feature `f` for `tool` under method `m`: its
/// tool-centre region (the region moved out by the overhang the method
/// allows beyond non-product edges, clipped to the free space where the
/// edges are straight, offset in by the tool's radius), with the product
/// edges and free-space boundaries it keeps the radius from. `None` where
/// the tool has no room.
pub(super) fn geometry(
    f: &MachiningFeature,
    m: &Method,
    tool: &Tool,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    slopes: Slopes,
) -> Option<Geometry> {
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
        Some(sh) => moved_to_slopes(&plain, sh, free),
    };
    let free = free_sloped.as_ref().or(free);
    let keep_out = keep_out_edges(free);
    // Straight-edged features with a known free space (every resolved
    // feature): the moved region is clipped to the free space below, so the
    // overhang needs no per-edge clearance. Otherwise (arcs, synthetic
    // plans) each edge's overhang is capped by the room beyond it.
    let clip = free.filter(|_| {
        edges
            .iter()
            .all(|(es, _)| es.iter().all(|e| e.bulge == 0.0))
    });
    let (mut loops, product) = overhung_loops(&edges, m, d, clip.is_some(), &keep_out)?;
    if loops.is_empty() {
        return None;
    }
    if let Some(free) = clip {
        loops = clipped_loops(&edges, m, d, free, removed);
        if loops.is_empty() {
            return None;
        }
    }
    // The clipped loops carry the overlay's rounding (well under 1e-6 mm).
    let slack = if clip.is_some() { clip_slack(r) } else { 0.0 };
    let mut centre = offset_in(loops, r, slack);
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
    let region_polys = region_polygons(&plain);
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

/// The loops with their product edges moved by `shifts` towards the
/// sloped faces, and the free space grown by the moved region (the space
/// between the section and the faces is free).
fn moved_to_slopes(
    plain: &[(Vec<Edge2>, Vec<Adjacency>)],
    shifts: &[Vec<f64>],
    free: Option<&crate::free::Shapes>,
) -> (Loops, Option<crate::free::Shapes>) {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let moved = moved_edges(plain, shifts);
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

/// The free space's boundary as straight edges: other product the tool
/// must keep its radius from.
fn keep_out_edges(free: Option<&crate::free::Shapes>) -> Vec<Edge2> {
    free.map(|free| {
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
    .unwrap_or_default()
}

/// Each loop moved out beyond its non-product edges by the overhang the
/// method allows (capped by the room beyond each edge unless the region is
/// `clipped` to the free space after), as oriented cavalier loops, with
/// the product edges; a hole that moved out past itself is gone. `None`
/// where the outer loop turned inside out.
fn overhung_loops(
    edges: &[(Vec<Edge2>, Vec<Adjacency>)],
    m: &Method,
    d: f64,
    clipped: bool,
    keep_out: &[Edge2],
) -> Option<(Vec<Polyline<f64>>, Vec<Edge2>)> {
    let mut product = Vec::new();
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
                if clipped {
                    wanted
                } else {
                    wanted.min(clearance(e, keep_out))
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
    Some((loops, product))
}

/// The region grown beyond its non-product edges and clipped to the free
/// space, less the strips beyond product edges.
fn clipped_loops(
    edges: &[(Vec<Edge2>, Vec<Adjacency>)],
    m: &Method,
    d: f64,
    free: &crate::free::Shapes,
    removed: Option<&crate::free::Shapes>,
) -> Vec<Polyline<f64>> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let mut grown = grown_region(edges, m, d, false);
    if let Some(removed) = removed {
        // An edge counts as open by its midpoint; past it the tool may
        // overhang a whole diameter only into space already cut, and
        // half of one into a feature still to come (where the far side
        // of an open edge is partly such a feature).
        let half = grown_region(edges, m, d, true);
        let far: crate::free::Shapes =
            grown.overlay_as::<i64>(removed, OverlayRule::Intersect, FillRule::NonZero);
        let far: Vec<Vec<[f64; 2]>> = far.into_iter().flatten().collect();
        let both: crate::free::Shapes =
            half.overlay_as::<i64>(&far, OverlayRule::Union, FillRule::NonZero);
        grown = both.into_iter().flatten().collect();
    }
    clipped_to_free(&grown, free, &product_strips(edges), d)
}

/// The loops offset in by the tool's radius and `slack`: the tool-centre
/// region.
fn offset_in(loops: Vec<Polyline<f64>>, r: f64, slack: f64) -> Area {
    let shape = Shape::from_plines(loops.clone());
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
    Area::from_shape(centre)
}

/// The feature region itself (its loops as they are), sampled.
fn region_polygons(plain: &[(Vec<Edge2>, Vec<Adjacency>)]) -> Vec<Vec<DVec2>> {
    let mut region_loops = vec![pline_from_edges(&plain[0].0, true)];
    for (es, _) in &plain[1..] {
        region_loops.push(pline_from_edges(es, true));
    }
    Area {
        parts: vec![(region_loops[0].clone(), region_loops[1..].to_vec())],
    }
    .polygons(STEP)
}

/// The polygons less every point closer than `reach` to a product edge
/// (each edge's capsule, circumscribed so the cut is never too small).
pub(super) fn away_from_product(
    polys: &[Vec<DVec2>],
    product: &[Edge2],
    reach: f64,
) -> Vec<Vec<DVec2>> {
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

/// Area (mm²) of the region the tool's disc never covers, its centre
/// anywhere in the tool-centre region (corners tighter than the tool, room
/// the free space denies). Sampled polygons: an estimate, good to the
/// chords' sagitta along the boundary.
pub(super) fn unreached_area(g: &Geometry) -> f64 {
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
