//! Sloped product faces: how the tool's bull-nose profile meets the faces
//! stage 6 sampled beyond each edge, and so how far the product edges of
//! the tool-centre region may move towards them (one shift per edge, or
//! the relaxed shift with the swept cuts that keep every height of the
//! corner radius off the product at the edges' ends), and the product's
//! edges over the profile's heights the safety net holds passes to.

use glam::DVec2;
use thinplan_knowledge::Tool;
use thinplan_plan::{Adjacency, EdgeSlopes, MachiningFeature, Provenance};

use super::region::Geometry;
use crate::geom::{move_edges_tagged, Edge2};

/// Extra radius of every swept cut (mm): the passes built along the cut
/// region come up to about 1.2e-4 nearer than its boundary (the booleans'
/// intersections, the passes' joins), and the safety net allows only
/// `EPS_SLOPE`.
const SWEPT_MARGIN: f64 = 1e-3;

/// How clearly a swept cut crosses the relaxed region's boundary where the
/// two would run along each other (mm, `swept_cuts`).
const TOUCH: f64 = 2e-3;

/// How a feature's sampled sloped faces shape its tool-centre region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Slopes {
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
pub(super) fn slope_shifts(f: &MachiningFeature, tool: &Tool) -> Option<Vec<Vec<f64>>> {
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
pub(super) fn relaxed_shifts(f: &MachiningFeature, tool: &Tool) -> Option<Vec<Vec<f64>>> {
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
pub(super) fn swept_cuts(
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
    let hs = corner_heights(s, tip, rc);
    let at = |out: Vec<Vec<f64>>| -> Keyed { moved_edges_keyed(plain, &out) };
    let outs = |h: f64| face_offsets(s, plain, tip + h);
    let base = at(relaxed.to_vec());
    let same = |a: &Edge2, b: &Edge2| {
        a.a.distance_squared(b.a) < 1e-18 && a.b.distance_squared(b.b) < 1e-18
    };
    let full = tool.diameter / 2.0;
    let mut cuts = Vec::new();
    let mut prev = at(outs(hs[0]));
    for w in hs.windows(2) {
        let next = at(outs(w[1]));
        let (low, top) = disc_radii(tool, w[0], w[1], rc);
        let radii = (clear_of_boundary(low, full), clear_of_boundary(top, full));
        for ((e0, e1), relaxed_edge) in paired_segments(&prev, &next, &base)? {
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

/// Loops of moved edges, each with its adjacency and the index of the edge
/// it moves (`moved_edges_keyed`).
type Keyed = Vec<Vec<(Edge2, Adjacency, Option<usize>)>>;

/// A product segment at two neighbouring heights, with its edge in the
/// relaxed region (`None` for a join).
type Pair = ((Edge2, Edge2), Option<Edge2>);

/// The heights above the tip the swept cuts are taken between: the corner
/// radius in 32 steps of angle, and every sampled height within it.
fn corner_heights(s: &EdgeSlopes, tip: f64, rc: f64) -> Vec<f64> {
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
    hs
}

/// The discs' radii at heights `h0` and `h1` above the tip: they must run
/// linearly between the two heights (as the edges move) and never below
/// the section radius, so they follow the tangent to the (concave) profile
/// parallel to the chord between the two heights, which lies above it, by
/// the least over all tangents.
fn disc_radii(tool: &Tool, h0: f64, h1: f64, rc: f64) -> (f64, f64) {
    let full = tool.diameter / 2.0;
    let (r0, r1) = (section_radius(tool, h0), section_radius(tool, h1));
    let chord = (r1 - r0) / (h1 - h0);
    if h1 <= rc && chord > 0.0 {
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
    }
}

/// A disc's radius with the swept cuts' margin. A disc all but as large as
/// the full radius would run a hair inside the relaxed region's boundary,
/// along it: the polyline booleans fail on such near-coincident edges, so
/// it is made to cross clearly (a thousandth of a millimetre more room is
/// lost).
fn clear_of_boundary(r: f64, full: f64) -> f64 {
    let r = r + SWEPT_MARGIN;
    if r > full - TOUCH {
        r.max(full + TOUCH)
    } else {
        r
    }
}

/// The product's segments at two neighbouring heights (`prev`, `next`),
/// paired, each with its edge in the relaxed region (`base`): the moved
/// edges by the edge they move, and the joins between two of them (a join
/// is there at one height and not at another where the two edges'
/// distances part: its ends are the two edges' ends, which move linearly
/// too). `None` where the loops' edges do not pair up or a product edge
/// is an arc.
fn paired_segments(prev: &Keyed, next: &Keyed, base: &Keyed) -> Option<Vec<Pair>> {
    let mut pairs: Vec<Pair> = Vec::new();
    for (k, (l0, l1)) in prev.iter().zip(next).enumerate() {
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
    Some(pairs)
}

/// The product edges of the loops moved by `out` (`moved_edges`).
pub(super) fn moved_product(
    plain: &[(Vec<Edge2>, Vec<Adjacency>)],
    out: &[Vec<f64>],
) -> Vec<Edge2> {
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
pub(super) fn moved_edges(
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
pub(super) fn slope_check(
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

/// Provenance of how sloped faces shaped the operation's region:
/// `slope_ends_swept` 1 where the product was swept at every height of the
/// corner radius (`Slopes::Swept`), 0 where each edge moved by one shift.
pub(super) fn slope_values(prov: &mut Provenance, g: &Geometry) {
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

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use proptest::prelude::*;
    use thinplan_knowledge::SidesMatch;
    use thinplan_plan::ProvenanceSource;

    use super::super::region::geometry;
    use super::*;
    use crate::geom::{boundary_distance, inside};

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
                origin: Default::default(),
                access_blocked: false,
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
