//! Sloped product faces beside a resolved feature: how far the face beyond
//! each product edge lies beyond it at heights through and above the slab,
//! so that stage 7 can keep a tool's profile off a face that is not
//! vertical.

use std::collections::BTreeMap;

use thinplan_plan::{Adjacency, EdgeSlopes};

use crate::section::{self, LocalMesh};
use crate::{beyond, Geo};

/// How far the product face beyond each product edge of a one-slab feature
/// lies beyond the edge (its region is the section at the slab's middle),
/// sampled at the slab's bottom, middle and top and on up by the slab's
/// thickness until `above` over its top (where a tool's corner radius
/// reaches) or past the part's `top`. `None` where every face is vertical.
pub(crate) fn edge_slopes(
    local: &LocalMesh,
    g: &Geo,
    (hi, top): (f64, f64),
    adjacency: (&[Adjacency], &[Vec<Adjacency>]),
    (above, reach): (f64, f64),
    sections: &mut SectionCache,
) -> Option<EdgeSlopes> {
    let (lo, at) = (g.lo, 0.5 * (g.lo + hi));
    let t = hi - lo;
    let mut heights = vec![lo, at, hi];
    let mut z = hi;
    // Above the part's top the sections are empty: nothing stands there.
    while z < hi + above - 1e-9 && z < top + t && t > 1e-9 {
        z += t;
        heights.push(z);
    }
    // Just inside: the slab bounds are vertex heights, where a section is
    // degenerate (the face moves `EPS_SECTION`·slope there: nothing).
    let probe: Vec<f64> = heights
        .iter()
        .enumerate()
        .map(|(i, &z)| {
            if i == 0 {
                z + EPS_SECTION
            } else {
                z - EPS_SECTION
            }
        })
        .collect();
    for (i, z) in probe.iter().enumerate() {
        if i != 1 {
            sections.entry(z.to_bits()).or_insert_with(|| {
                let (loops, _) = local.section(*z);
                let part = section::fill(&loops);
                beyond::Section::new(loops, part)
            });
        }
    }
    let mut any = false;
    let mut per_loop = |contour: &Vec<[f64; 2]>, adj: &[Adjacency]| -> Vec<Vec<f64>> {
        let n = contour.len();
        (0..n)
            .map(|i| {
                if adj.get(i) != Some(&Adjacency::Product) {
                    return Vec::new();
                }
                let (a, b) = (contour[i], contour[(i + 1) % n]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let len = (dx * dx + dy * dy).sqrt();
                if len < 1e-9 {
                    return Vec::new();
                }
                let p = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                // Outward (towards the product): right of the edge.
                let nrm = [dy / len, -dx / len];
                let e: Vec<f64> = probe
                    .iter()
                    .enumerate()
                    .map(|(k, z)| {
                        if k == 1 {
                            return 0.0;
                        }
                        let v = beyond::face_beyond(&sections[&z.to_bits()], p, nrm, reach);
                        // Rounded: the plan file stays readable.
                        let v = (v * 1e9).round() / 1e9;
                        if v.abs() < 1e-6 {
                            0.0
                        } else {
                            v
                        }
                    })
                    .collect();
                if e.iter().all(|v| *v == 0.0) {
                    return Vec::new();
                }
                any = true;
                e
            })
            .collect()
    };
    let side = per_loop(&g.region[0][0], adjacency.0);
    let holes: Vec<Vec<Vec<f64>>> = g.region[0][1..]
        .iter()
        .zip(adjacency.1)
        .map(|(c, a)| per_loop(c, a))
        .collect();
    any.then_some(EdgeSlopes {
        heights,
        side,
        holes,
    })
}

/// The part's sections by height (bits): the loops and their region.
pub(crate) type SectionCache = BTreeMap<u64, beyond::Section>;

/// How far inside a slab its bounds' sections are taken (mm).
const EPS_SECTION: f64 = 1e-4;
