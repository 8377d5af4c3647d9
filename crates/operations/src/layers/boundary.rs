//! The boundary region: passes along the product at exactly the tool's
//! radius, down milling, each with a run-up and run-off that stay in
//! cleared space. The boundary stepover splits the tool-centre region into
//! these passes and the rest region the zigzag or spiral clears first.

use glam::DVec2;
use thinplan_knowledge::{BoundaryRegion, MethodKnowledge, RunUp, SpindleDirection};
use thinplan_plan::MachiningFeature;

use super::plan_view::product_distance;
use super::region::{away_from_product, Geometry};
use super::{EPS, STEP};
use crate::geom::{edges_of_pline, inside, Edge2};
use crate::path::{seg_points, Seg2};

/// A band's boundary passes and the rest region they leave.
pub(super) struct Boundary {
    /// The boundary passes' width of cut (mm; 0 without boundary passes).
    pub(super) s_b: f64,
    /// The rest region: the tool-centre region kept `s_b` from the
    /// boundary passes, sampled.
    pub(super) rest_polys: Vec<Vec<DVec2>>,
    pub(super) passes: Vec<BoundaryPass>,
}

/// The boundary passes of the method's boundary region (`None`: the
/// feature has none, or no product) and the rest region beside them; a
/// pass with no room for a run-up is said.
pub(super) fn boundary_region(
    f: &MachiningFeature,
    g: &Geometry,
    boundary: Option<&BoundaryRegion>,
    d: f64,
    mk: &MethodKnowledge,
    warnings: &mut Vec<String>,
) -> Boundary {
    let s_b = boundary.map_or(0.0, |b| b.stepover * d);
    // The rest region keeps s_b from the boundary passes only: shrinking
    // it from every side would leave a band along non-product sides that
    // no pass visits (a narrow step beside a wall would lose its far side).
    let rest_polys = if s_b > 0.0 && g.clipped {
        away_from_product(&g.centre_polys, &g.product, g.r + s_b)
    } else if s_b > 0.0 {
        g.centre.offset(s_b).polygons(STEP)
    } else {
        g.centre_polys.clone()
    };
    let chains = match boundary {
        Some(_) => boundary_chains(g, 0.5 * s_b.max(1e-3), mk.spindle),
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
            .map(|(c, _)| boundary_pass(c, g, b.run_up, d, cleared_for_runup, mk))
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
    Boundary {
        s_b,
        rest_polys,
        passes,
    }
}

/// The boundary passes: the product-adjacent stretches of the tool-centre
/// region's loops, in down-milling direction.
pub(super) fn boundary_chains(
    g: &Geometry,
    band: f64,
    spindle: SpindleDirection,
) -> Vec<(Vec<Edge2>, bool)> {
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
pub(super) struct BoundaryPass {
    pub(super) start: DVec2,
    pub(super) segs: Vec<Seg2>,
    pub(super) lead_in: &'static str,
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
pub(super) fn entered_from_room(
    mut p: BoundaryPass,
    g: &Geometry,
    room: &[Vec<DVec2>],
) -> BoundaryPass {
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

/// The boundary pass along `chain`: a run-up (circular or tangential, the
/// largest of the fit scales that stays in `cleared` and keeps `r` from the
/// product) where the chain starts inside the region, the chain, and a
/// run-off where it ends inside.
pub(super) fn boundary_pass(
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

/// Where a boundary pass ends.
pub(super) fn end_of(p: &BoundaryPass) -> DVec2 {
    p.segs.last().map_or(p.start, |s| s.to)
}
