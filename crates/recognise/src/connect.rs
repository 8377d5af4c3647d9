//! Stage 3: the connection graph (base–leaf and crossing) in the set-up frame
//! (thesis §5.4.1 "Connection determination", §6.1.2, figure 5.10).
//!
//! Two features are candidates when they touch: a face of one shares an edge
//! with a face of the other, or they share a face. Then:
//!
//! - **wall–wall** (walls not parallel), with each wall's volume (its
//!   mid-surface prism) placed against the other's slab:
//!   - both continue past both sides of the other's slab → `crossing`
//!     (rule `connect.crossing`; symmetric, the smaller id is written as
//!     the base);
//!   - one lies wholly on one side of the other's slab, ending at its face
//!     (a rib standing on a web, a stiffener ending at a flange) → that one
//!     is the leaf (`connect.stands_on`);
//!   - otherwise (an L corner, flush, or both ending at each other) the
//!     set-up decides (`connect.setup_height`, figure 5.10): the wall whose
//!     top along `up` is lower is the base; on equal tops a web is the base
//!     of a non-web, then the longer wall is the base of the shorter, then
//!     the smaller id.
//!   - parallel touching walls (a step in a web): the lower one is the base.
//! - **wall–depression**: the depression is a leaf of every wall it touches
//!   (`connect.depression_in_wall`): a hole through a rib has the rib as base.
//!   Depressions never are bases (thesis §5.4.1).
//! - **wall–detail**: a chamfer or fillet across a standing wall's corner
//!   (recognition gave it a wedge in the wall's frame) is a leaf of that
//!   wall (`connect.detail_on_wall`, figure 4.10: the detail is machined in
//!   the wall's sequence). Other details (corner blends between walls) shape
//!   the features they blend and get no connection.
//!
//! Output sorted by (base, leaf, kind), one connection per pair.

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use thinplan_brep::{Brep, EdgeAdjacency, FaceId};
use thinplan_knowledge::WallRecognition;
use thinplan_plan::{
    Connection, ConnectionKind, Provenance, ProvenanceSource, StiffnessFeature, StiffnessKind,
};

use crate::walls::{touching_pairs, SlabSide, WallVolume};

pub fn connect(
    _brep: &Brep,
    adjacency: &[EdgeAdjacency],
    up: DVec3,
    features: &[StiffnessFeature],
    k: &WallRecognition,
) -> Vec<Connection> {
    let up = up.try_normalize().unwrap_or(DVec3::Z);
    let cos_tol = k.angle_tolerance_deg.to_radians().cos();
    let tol = k.distance_tolerance.max(1e-3);
    let mut face_owner: BTreeMap<FaceId, Vec<usize>> = BTreeMap::new();
    for (i, f) in features.iter().enumerate() {
        for &fc in &f.faces {
            face_owner.entry(fc).or_default().push(i);
        }
    }
    let vols: Vec<Option<WallVolume>> = features
        .iter()
        .map(|f| {
            if f.kind == StiffnessKind::Wall {
                WallVolume::of(f, up, cos_tol)
            } else {
                None
            }
        })
        .collect();
    let mut out: BTreeMap<(u32, u32), Connection> = BTreeMap::new();
    let mut seen: BTreeSet<(usize, usize)> = BTreeSet::new();
    for (i, j) in touching_pairs(adjacency, &face_owner) {
        if !seen.insert((i, j)) {
            continue;
        }
        let (fi, fj) = (&features[i], &features[j]);
        let conn = match (fi.kind, fj.kind) {
            (StiffnessKind::Wall, StiffnessKind::Wall) => {
                match (vols[i].as_ref(), vols[j].as_ref()) {
                    (Some(a), Some(b)) => wall_wall(fi, a, fj, b, up, cos_tol, tol),
                    _ => None,
                }
            }
            (StiffnessKind::Wall, d) if is_depression(d) => Some(leaf_in(fi, fj)),
            (d, StiffnessKind::Wall) if is_depression(d) => Some(leaf_in(fj, fi)),
            (StiffnessKind::Wall, _) if on_wall(fi, fj, tol) => Some(detail_on(fi, fj)),
            (_, StiffnessKind::Wall) if on_wall(fj, fi, tol) => Some(detail_on(fj, fi)),
            _ => None,
        };
        if let Some(c) = conn {
            let key = (c.base.0.min(c.leaf.0), c.base.0.max(c.leaf.0));
            out.entry(key).or_insert(c);
        }
    }
    let mut v: Vec<Connection> = out.into_values().collect();
    v.sort_by_key(|c| (c.base, c.leaf, c.kind as u8));
    v
}

fn is_depression(k: StiffnessKind) -> bool {
    !matches!(
        k,
        StiffnessKind::Wall | StiffnessKind::Chamfer | StiffnessKind::Fillet
    )
}

/// A detail (chamfer, fillet) whose wedge lies in `wall`'s slab: recognition
/// gives a detail across a standing wall's corner the wall's frame.
fn on_wall(wall: &StiffnessFeature, detail: &StiffnessFeature, tol: f64) -> bool {
    if !matches!(detail.kind, StiffnessKind::Chamfer | StiffnessKind::Fillet) {
        return false;
    }
    let (Some(w), Some(d)) = (wall.shape.as_ref(), detail.shape.as_ref()) else {
        return false;
    };
    let n = w.frame.z.normalize_or_zero();
    n.dot(d.frame.z.normalize_or_zero()) > 1.0 - 1e-9
        && (d.frame.origin - w.frame.origin).dot(n).abs() <= tol
        && (d.z_min - w.z_min).abs() <= tol
        && (d.z_max - w.z_max).abs() <= tol
}

fn detail_on(wall: &StiffnessFeature, detail: &StiffnessFeature) -> Connection {
    Connection {
        base: wall.id,
        leaf: detail.id,
        kind: ConnectionKind::BaseLeaf,
        provenance: Provenance::new(ProvenanceSource::Recogniser, "connect.detail_on_wall"),
    }
}

fn leaf_in(wall: &StiffnessFeature, dep: &StiffnessFeature) -> Connection {
    Connection {
        base: wall.id,
        leaf: dep.id,
        kind: ConnectionKind::BaseLeaf,
        provenance: Provenance::new(ProvenanceSource::Recogniser, "connect.depression_in_wall"),
    }
}

fn wall_wall(
    fa: &StiffnessFeature,
    a: &WallVolume,
    fb: &StiffnessFeature,
    b: &WallVolume,
    up: DVec3,
    cos_tol: f64,
    tol: f64,
) -> Option<Connection> {
    let mk = |base: &StiffnessFeature, leaf: &StiffnessFeature, kind, rule: &str| Connection {
        base: base.id,
        leaf: leaf.id,
        kind,
        provenance: Provenance::new(ProvenanceSource::Recogniser, rule),
    };
    let top_a = a.range(up).1;
    let top_b = b.range(up).1;
    let with_tops = |mut c: Connection| {
        c.provenance = c
            .provenance
            .with_value("top_a", top_a)
            .with_value("top_b", top_b);
        c
    };
    if a.normal.dot(b.normal).abs() >= cos_tol {
        // Parallel walls touching: the lower one carries the higher.
        let (lo_a, lo_b) = (a.range(up).0, b.range(up).0);
        let (base, leaf) = if (lo_a, fa.id) <= (lo_b, fb.id) {
            (fa, fb)
        } else {
            (fb, fa)
        };
        return Some(with_tops(mk(
            base,
            leaf,
            ConnectionKind::BaseLeaf,
            "connect.parallel_lower",
        )));
    }
    let b_vs_a = a.side_of(b, tol);
    let a_vs_b = b.side_of(a, tol);
    let c = match (b_vs_a, a_vs_b) {
        (SlabSide::Through, SlabSide::Through) => {
            // Symmetric: the smaller id is written as the base.
            let (base, leaf) = if fa.id < fb.id { (fa, fb) } else { (fb, fa) };
            mk(base, leaf, ConnectionKind::Crossing, "connect.crossing")
        }
        (SlabSide::Outside, s) if s != SlabSide::Outside => {
            mk(fa, fb, ConnectionKind::BaseLeaf, "connect.stands_on")
        }
        (s, SlabSide::Outside) if s != SlabSide::Outside => {
            mk(fb, fa, ConnectionKind::BaseLeaf, "connect.stands_on")
        }
        _ => {
            let a_first = if (top_a - top_b).abs() > tol {
                top_a < top_b
            } else if a.web != b.web {
                a.web
            } else if (a.length - b.length).abs() > tol {
                a.length > b.length
            } else {
                fa.id < fb.id
            };
            let (base, leaf) = if a_first { (fa, fb) } else { (fb, fa) };
            mk(base, leaf, ConnectionKind::BaseLeaf, "connect.setup_height")
        }
    };
    Some(with_tops(c))
}
