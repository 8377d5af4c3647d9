//! Remaining material no tool fits into on its own: a corner of a pocket
//! between the walls' machining features, narrower than the smallest tool.
//!
//! Stage 6 leaves such a corner as its own feature once the walls' steps
//! are cut, so its open edges face space already cut. A tool that sits in
//! that space reaches into the corner as far as its radius allows; the
//! feature is therefore planned as its region grown into the space cut
//! before it (at most `reach` from the region) and the operations clear the
//! corner from there. Stage 8 orders the features the tool passes through
//! first (`precedence::cutting_pairs`).

use glam::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use thinplan_plan::{Adjacency, MachiningFeature, ProfileLoop};

use crate::free::Shapes;

fn signed_area(c: &[[f64; 2]]) -> f64 {
    let n = c.len();
    (0..n)
        .map(|i| c[i][0] * c[(i + 1) % n][1] - c[(i + 1) % n][0] * c[i][1])
        .sum::<f64>()
        / 2.0
}

/// Each shape's loops as points, for containment tests.
fn polygons(shapes: &Shapes) -> Vec<Vec<Vec<DVec2>>> {
    shapes
        .iter()
        .map(|s| {
            s.iter()
                .map(|c| c.iter().map(|p| DVec2::new(p[0], p[1])).collect())
                .collect()
        })
        .collect()
}

fn contains(shapes: &[Vec<Vec<DVec2>>], q: DVec2) -> bool {
    shapes.iter().any(|polys| crate::geom::inside(q, polys))
}

/// `f` grown by at most `reach` into `removed` (space cut before it, which
/// includes `f`), kept inside `free`, as a feature of its own: the pieces
/// that overlap `f`, every edge classified the way stage 6 does (product
/// beyond the free space, open where already cut, a feature otherwise).
/// `None` when nothing grows (no open edge, or no room beside them).
pub(crate) fn reached_from_beside(
    f: &MachiningFeature,
    free: &Shapes,
    removed: &Shapes,
    reach: f64,
) -> Option<MachiningFeature> {
    if reach.is_nan() || reach <= 0.0 || !f.side_adjacency.contains(&Adjacency::Open) {
        return None;
    }
    let own = crate::free::region(f);
    let segs: Vec<(DVec2, DVec2)> = own
        .iter()
        .flat_map(|c| {
            let n = c.len();
            (0..n).map(move |i| {
                (
                    DVec2::new(c[i][0], c[i][1]),
                    DVec2::new(c[(i + 1) % n][0], c[(i + 1) % n][1]),
                )
            })
        })
        .collect();
    let near: Shapes = crate::geom::capsules(segs.into_iter(), reach).overlay_as::<i64>(
        &Vec::<Vec<[f64; 2]>>::new(),
        OverlayRule::Subject,
        FillRule::NonZero,
    );
    let cut: Shapes = near.overlay_as::<i64>(removed, OverlayRule::Intersect, FillRule::NonZero);
    let cut: Shapes = cut.overlay_as::<i64>(free, OverlayRule::Intersect, FillRule::NonZero);
    let grown: Shapes = cut.overlay_as::<i64>(&own, OverlayRule::Union, FillRule::NonZero);
    // Only the pieces the feature is in: a piece past a wall is no way in.
    let own_area = signed_area(&own[0]).abs();
    let grown: Shapes = crate::free::without_slits(grown)
        .into_iter()
        .filter(|s| {
            let common: Shapes =
                own.overlay_as::<i64>(s, OverlayRule::Intersect, FillRule::NonZero);
            common
                .iter()
                .map(|c| crate::free::shape_area(c))
                .sum::<f64>()
                > 1e-3 * own_area
        })
        .collect();
    let [shape] = grown.as_slice() else {
        return None;
    };
    let total = crate::free::shape_area(shape);
    if total <= own_area * (1.0 + 1e-6) {
        return None;
    }
    Some(rebuilt(f, shape, free, removed))
}

/// `f` with its region replaced by `shape` (an outer contour then holes),
/// every edge classified the way stage 6 does: product beyond `free`, open
/// where `removed` (already cut), a feature otherwise; sloped product faces
/// carried to the edges that lie on `f`'s own.
pub(crate) fn rebuilt(
    f: &MachiningFeature,
    shape: &[Vec<[f64; 2]>],
    free: &Shapes,
    removed: &Shapes,
) -> MachiningFeature {
    let (free_polys, removed_polys) = (polygons(free), polygons(removed));
    let classify = |c: &[[f64; 2]]| -> Vec<Adjacency> {
        let n = c.len();
        (0..n)
            .map(|i| {
                let (a, b) = (
                    DVec2::new(c[i][0], c[i][1]),
                    DVec2::new(c[(i + 1) % n][0], c[(i + 1) % n][1]),
                );
                let t = (b - a).normalize_or_zero();
                // Outward: right of the edge (outer ccw, holes cw).
                let q = (a + b) * 0.5 + DVec2::new(t.y, -t.x) * 1e-3;
                if !contains(&free_polys, q) {
                    Adjacency::Product
                } else if contains(&removed_polys, q) {
                    Adjacency::Open
                } else {
                    Adjacency::Feature
                }
            })
            .collect()
    };
    let to_loop = |c: &[[f64; 2]], ccw: bool| -> Vec<[f64; 2]> {
        let mut c = c.to_vec();
        if (signed_area(&c) > 0.0) != ccw {
            c.reverse();
        }
        c
    };
    let mut g = f.clone();
    let outer = to_loop(&shape[0], true);
    g.side_adjacency = classify(&outer);
    g.shape.region.outer = ProfileLoop::polygon(&outer);
    g.shape.region.holes.clear();
    g.hole_adjacency.clear();
    for h in &shape[1..] {
        let h = to_loop(h, false);
        g.hole_adjacency.push(classify(&h));
        g.shape.region.holes.push(ProfileLoop::polygon(&h));
    }
    g.slopes = carried_slopes(f, &g);
    g
}

/// The sampled sloped faces of `f` carried to the edges of `g` that lie on
/// one of `f`'s product edges (the rest: vertical, nothing sampled).
fn carried_slopes(f: &MachiningFeature, g: &MachiningFeature) -> Option<thinplan_plan::EdgeSlopes> {
    let s = f.slopes.as_ref()?;
    let loops_of = |m: &MachiningFeature| -> Vec<Vec<DVec2>> {
        std::iter::once(&m.shape.region.outer)
            .chain(&m.shape.region.holes)
            .map(|l| l.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect())
            .collect()
    };
    let old = loops_of(f);
    let old_offsets: Vec<&Vec<Vec<f64>>> = std::iter::once(&s.side).chain(&s.holes).collect();
    let on = |p: DVec2, a: DVec2, b: DVec2| crate::geom::dist_point_seg(p, a, b) < 1e-6;
    let find = |a: DVec2, b: DVec2| -> Vec<f64> {
        for (k, l) in old.iter().enumerate() {
            let n = l.len();
            for i in 0..n {
                let (p, q) = (l[i], l[(i + 1) % n]);
                if on(a, p, q) && on(b, p, q) {
                    return old_offsets
                        .get(k)
                        .and_then(|o| o.get(i))
                        .cloned()
                        .unwrap_or_default();
                }
            }
        }
        Vec::new()
    };
    let per_loop = |l: &Vec<DVec2>, adj: &[Adjacency]| -> Vec<Vec<f64>> {
        let n = l.len();
        (0..n)
            .map(|i| {
                if adj.get(i) == Some(&Adjacency::Product) {
                    find(l[i], l[(i + 1) % n])
                } else {
                    Vec::new()
                }
            })
            .collect()
    };
    let new = loops_of(g);
    let side = per_loop(&new[0], &g.side_adjacency);
    let holes: Vec<Vec<Vec<f64>>> = new[1..]
        .iter()
        .zip(&g.hole_adjacency)
        .map(|(l, a)| per_loop(l, a))
        .collect();
    let any = side
        .iter()
        .chain(holes.iter().flatten())
        .any(|o| !o.is_empty());
    any.then(|| thinplan_plan::EdgeSlopes {
        heights: s.heights.clone(),
        side,
        holes,
    })
}

/// A straight-edged feature in the plan frame, `z` its heights (tests).
#[cfg(test)]
pub(crate) fn test_feature(
    id: u32,
    outer: &[[f64; 2]],
    side_adjacency: Vec<Adjacency>,
    (z_min, z_max): (f64, f64),
) -> MachiningFeature {
    use thinplan_plan::*;
    MachiningFeature {
        id: MachiningFeatureId(id),
        owner: StiffnessFeatureId(0),
        shape: Prism {
            frame: PrismFrame {
                origin: glam::DVec3::ZERO,
                x: glam::DVec3::X,
                z: glam::DVec3::Z,
            },
            region: Region {
                outer: ProfileLoop::polygon(outer),
                holes: vec![],
            },
            z_min,
            z_max,
        },
        side_adjacency,
        hole_adjacency: vec![],
        bottom_adjacency: Adjacency::Product,
        slopes: None,
        origin: Default::default(),
        access_blocked: false,
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    /// A 4 × 4 corner (x 0–4, y 0–4) of a pocket whose walls are x < 0 and
    /// y < 0; its edges x = 4 and y = 4 open onto strips cut before it
    /// along both walls (x 0–30 × y 0–10 and x 0–10 × y 0–30). Beyond
    /// y = 30 and x = 30 stands a feature still to come.
    fn corner() -> (MachiningFeature, Shapes, Shapes) {
        let f = test_feature(
            7,
            &rect(0.0, 0.0, 4.0, 4.0),
            vec![
                Adjacency::Product,
                Adjacency::Open,
                Adjacency::Open,
                Adjacency::Product,
            ],
            (0.0, 10.0),
        );
        let free = vec![vec![rect(0.0, 0.0, 60.0, 60.0)]];
        let removed: Shapes = vec![rect(0.0, 0.0, 30.0, 10.0), rect(0.0, 0.0, 10.0, 30.0)]
            .overlay_as::<i64>(
                &Vec::<Vec<[f64; 2]>>::new(),
                OverlayRule::Subject,
                FillRule::NonZero,
            );
        (f, free, removed)
    }

    fn area(c: &[ProfileVertex]) -> f64 {
        let pts: Vec<[f64; 2]> = c.iter().map(|p| [p.x, p.y]).collect();
        signed_area(&pts)
    }

    #[test]
    fn grows_into_the_space_cut_before_it_and_classifies_every_edge() {
        let (f, free, removed) = corner();
        let g = reached_from_beside(&f, &free, &removed, 12.0).expect("it grows");
        let outer = &g.shape.region.outer.vertices;
        // Inside the cut strips, within 12 of the corner: the L of the two
        // strips cut at x, y ≤ 16 (4 + 12), less the two bits beyond the
        // circle of radius 12 about (4, 4): ∫₀⁶ (12 − √(144 − w²)) dw each.
        let k = 600;
        let bit: f64 = (0..k)
            .map(|i| {
                let w = 6.0 * (i as f64 + 0.5) / k as f64;
                (12.0 - (144.0 - w * w).sqrt()) * 6.0 / k as f64
            })
            .sum();
        let expected = 16.0 * 10.0 + 10.0 * 16.0 - 10.0 * 10.0 - 2.0 * bit;
        assert!(area(outer) > 0.0, "outer loop counter-clockwise");
        assert!(
            (area(outer) - expected).abs() < 1.0,
            "area {} vs {expected}",
            area(outer)
        );
        // The capsules are circumscribed polygons: 12 / cos(π/32) at most.
        for p in outer {
            assert!(
                p.x >= -1e-6 && p.y >= -1e-6 && p.x <= 16.06 && p.y <= 16.06,
                "{p:?}"
            );
        }
        let n = outer.len();
        assert_eq!(g.side_adjacency.len(), n);
        for i in 0..n {
            let (a, b) = (outer[i], outer[(i + 1) % n]);
            let mid = DVec2::new((a.x + b.x) / 2.0, (a.y + b.y) / 2.0);
            // On a wall (x = 0 or y = 0) it is product; on a strip's long
            // side (beyond it the feature still to come) a feature; on the
            // arcs 12 from the corner, cut space.
            let on_wall = mid.x.abs() < 1e-6 || mid.y.abs() < 1e-6;
            let on_strip = (mid.y - 10.0).abs() < 1e-6 && mid.x > 10.0
                || (mid.x - 10.0).abs() < 1e-6 && mid.y > 10.0;
            let want = if on_wall {
                Adjacency::Product
            } else if on_strip {
                Adjacency::Feature
            } else {
                Adjacency::Open
            };
            assert_eq!(g.side_adjacency[i], want, "edge {i} at {mid}");
        }
    }

    #[test]
    fn does_not_grow_into_a_feature_still_to_come_nor_without_an_open_edge() {
        let (f, free, _) = corner();
        // Nothing cut before it but itself: no growth.
        let own: Shapes = vec![vec![rect(0.0, 0.0, 4.0, 4.0)]];
        assert!(reached_from_beside(&f, &free, &own, 12.0).is_none());
        let mut closed = f.clone();
        closed.side_adjacency = vec![Adjacency::Feature; 4];
        let (_, _, removed) = corner();
        assert!(reached_from_beside(&closed, &free, &removed, 12.0).is_none());
    }

    /// Sampled slopes stay with the edges that lie within one of the old
    /// product edges (an edge split in two keeps them on both halves); a
    /// wall that grows past its old edge is planned as vertical (nothing
    /// was sampled there).
    #[test]
    fn sloped_faces_stay_only_on_the_edges_they_were_sampled_on() {
        let (mut f, free, removed) = corner();
        let offsets = vec![-0.5, 0.0, 0.5];
        f.slopes = Some(EdgeSlopes {
            heights: vec![0.0, 5.0, 10.0],
            side: vec![offsets.clone(), vec![], vec![], vec![]],
            holes: vec![],
        });
        let mut g = f.clone();
        let v = |x: f64, y: f64| ProfileVertex { x, y, bulge: 0.0 };
        g.shape.region.outer.vertices = vec![
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(4.0, 0.0),
            v(4.0, 4.0),
            v(0.0, 4.0),
        ];
        g.side_adjacency = vec![
            Adjacency::Product,
            Adjacency::Product,
            Adjacency::Open,
            Adjacency::Open,
            Adjacency::Product,
        ];
        let s = carried_slopes(&f, &g).expect("carried");
        assert_eq!(
            s.side,
            vec![offsets.clone(), offsets, vec![], vec![], vec![]]
        );
        // Grown along both walls past their old edges.
        let grown = reached_from_beside(&f, &free, &removed, 12.0).expect("it grows");
        assert!(grown.slopes.is_none());
    }
}
