//! Shank access: a tool cutting a feature F reaches beyond F's
//! open edges (its overhang, ½D, plus the shank's radius, ½D), and above
//! its flutes (`flute_length`) the shank does not cut. A neighbour N that
//! still stands there more than a flute length above F's bottom would rub
//! the shank: N is machined before F.
//!
//! The reach zone of F is the band of width D outward of every side edge
//! whose neighbour is not the product, cut back by the product and kept only
//! where it is connected to those edges: it never grows across a wall, so the
//! two sides of a thin wall stay apart.

use thinplan_knowledge::Tool;
use thinplan_plan::{ConstraintKind, MachiningFeatureId, Provenance, ProvenanceSource};

use super::{overlaps, section, Geo, Graph, Resolution, Shapes, Slab, EPS_Z};

/// Provenance rule of shank-access constraints.
pub const RULE_SHANK: &str = "interference.shank_access";

/// Outward sample points lie this far beyond an edge, mm (as adjacency's).
const OFF: f64 = 1e-3;

/// Adds `N before F` for every feature N that stands in F's reach zone above
/// F's bottom plus a flute length, for some tool of the set.
///
/// Shallow features ask first (bottom highest, then id): in a top-down
/// sequence they are cut first, and when two neighbours each stand in the
/// other's way, the deeper one's request closes a cycle and is refused
/// (recorded); its tool is then kept away from the neighbour by the
/// operations.
pub(crate) fn shank_access(
    geo: &[Geo],
    slabs: &[Slab],
    tools: &[Tool],
    sliver: f64,
    graph: &mut Graph,
    out: &mut Resolution,
) {
    let top = |g: &Geo| slabs[g.top_slab].hi;
    let mut asking: Vec<usize> = (0..geo.len()).collect();
    asking.sort_by(|&a, &b| geo[b].lo.total_cmp(&geo[a].lo).then(a.cmp(&b)));
    for f in asking {
        let gf = &geo[f];
        let open = open_edges(gf, slabs);
        if open.is_empty() {
            continue;
        }
        let zones: Vec<Shapes> = tools
            .iter()
            .map(|t| reach_zone(gf, &open, slabs, t.diameter))
            .collect();
        for (n, gn) in geo.iter().enumerate() {
            if n == f {
                continue;
            }
            let found = tools.iter().zip(&zones).find_map(|(t, zone)| {
                if zone.is_empty()
                    || top(gn) <= gf.lo + t.flute_length + EPS_Z
                    || gn.lo >= top(gf) + t.stickout
                    || !overlaps(&gn.bbox, &bbox(zone))
                {
                    return None;
                }
                let common = section::area(&section::intersection(&gn.region, zone));
                (common > sliver).then_some((t, common))
            });
            let Some((t, common)) = found else {
                continue;
            };
            // Already ordered by other rules: nothing to add.
            if graph.reaches(n, f) {
                continue;
            }
            // F already comes first by this rule's own earlier constraints
            // only (a shallower neighbour asked first): the reverse request
            // is no news, and the operations keep the deeper feature's tool
            // out of F instead. A refusal is recorded only where another
            // rule stands in the way.
            if graph.reaches(f, n) && !reaches_without(out, RULE_SHANK, f, n) {
                continue;
            }
            let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_SHANK)
                .with_value("flute_length", t.flute_length)
                .with_value("top_of_first", top(gn))
                .with_value("bottom_of_second", gf.lo)
                .with_value("overlap_area", common);
            p.note = format!(
                "MF{n} stands {:.2} mm above MF{f}'s bottom within {}'s reach (Ø{} overhang \
                 plus shank), higher than its flute length {}: the shank would rub it",
                top(gn) - gf.lo,
                t.id,
                t.diameter,
                t.flute_length
            );
            graph.add(
                out,
                MachiningFeatureId(n as u32),
                MachiningFeatureId(f as u32),
                ConstraintKind::Before,
                0,
                p,
            );
        }
    }
}

/// F's side edges (outer contour and holes) whose outward neighbour is not
/// the product in any of F's slabs, with their outward unit normals.
fn open_edges(g: &Geo, slabs: &[Slab]) -> Vec<([f64; 2], [f64; 2], [f64; 2])> {
    let mut out = Vec::new();
    for c in &g.region[0] {
        let n = c.len();
        for i in 0..n {
            let (a, b) = (c[i], c[(i + 1) % n]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = (dx * dx + dy * dy).sqrt();
            if len < 1e-9 {
                continue;
            }
            // Outward: right of the edge (outer contours are counter-clockwise,
            // holes clockwise).
            let nrm = [dy / len, -dx / len];
            let q = [
                0.5 * (a[0] + b[0]) + nrm[0] * OFF,
                0.5 * (a[1] + b[1]) + nrm[1] * OFF,
            ];
            let product = slabs[g.bottom_slab..=g.top_slab]
                .iter()
                .any(|s| section::contains(&s.part, q));
            if !product {
                out.push((a, b, nrm));
            }
        }
    }
    out
}

/// The band of width `w` outward of the open edges (with the corners
/// between consecutive open edges filled), less the product at F's top, kept
/// where it touches an open edge.
fn reach_zone(g: &Geo, open: &[([f64; 2], [f64; 2], [f64; 2])], slabs: &[Slab], w: f64) -> Shapes {
    let ccw = |mut c: Vec<[f64; 2]>| {
        if section::contour_area(&c) < 0.0 {
            c.reverse();
        }
        c
    };
    let mut contours: Vec<Vec<[f64; 2]>> = Vec::new();
    for (i, &(a, b, n)) in open.iter().enumerate() {
        let off = |p: [f64; 2], n: [f64; 2]| [p[0] + n[0] * w, p[1] + n[1] * w];
        contours.push(ccw(vec![a, b, off(b, n), off(a, n)]));
        // The next open edge starting where this one ends: fill the corner.
        let next = open[(i + 1) % open.len()];
        if next.0 == b {
            let m = [n[0] + next.2[0], n[1] + next.2[1]];
            let ml = (m[0] * m[0] + m[1] * m[1]).sqrt();
            if ml > 1e-9 {
                let mid = [m[0] / ml, m[1] / ml];
                contours.push(ccw(vec![b, off(b, n), off(b, mid), off(b, next.2)]));
            }
        }
    }
    let band = section::fill(&contours);
    let band = section::difference(&band, &g.region);
    let free = section::difference(&band, &slabs[g.top_slab].part);
    let probes: Vec<[f64; 2]> = open
        .iter()
        .flat_map(|&(a, b, n)| {
            [0.25, 0.5, 0.75].map(|t| {
                [
                    a[0] + (b[0] - a[0]) * t + n[0] * OFF,
                    a[1] + (b[1] - a[1]) * t + n[1] * OFF,
                ]
            })
        })
        .collect();
    free.into_iter()
        .filter(|s| {
            let one = vec![s.clone()];
            probes.iter().any(|&q| section::contains(&one, q))
        })
        .collect()
}

fn bbox(s: &Shapes) -> [f64; 4] {
    super::bbox_of(s)
}

/// Whether `from` comes before `to` through constraints of rules other
/// than `rule`.
fn reaches_without(out: &Resolution, rule: &str, from: usize, to: usize) -> bool {
    let mut next: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for c in out.constraints.iter().filter(|c| c.provenance.rule != rule) {
        next.entry(c.first.0 as usize)
            .or_default()
            .push(c.second.0 as usize);
    }
    let mut seen = std::collections::BTreeSet::new();
    let mut stack = vec![from];
    while let Some(v) = stack.pop() {
        if v == to {
            return true;
        }
        if seen.insert(v) {
            stack.extend(next.get(&v).into_iter().flatten().copied());
        }
    }
    false
}
