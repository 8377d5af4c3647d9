//! Face adjacency across edges, with the convexity of each edge.

use serde::{Deserialize, Serialize};

use glam::DVec3;

use crate::{Brep, EdgeId, FaceId};

/// How the material meets at an edge between two faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Convexity {
    /// The solid angle inside the material is below 180° (an outside corner).
    Convex,
    /// Above 180° (an inside corner, e.g. the foot of a wall).
    Concave,
    /// Tangent continuous faces (e.g. a fillet running into a plane).
    Smooth,
    /// Fewer or more than two faces, or undecidable geometry.
    Unknown,
}

/// The faces that use an edge and how they meet there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdgeAdjacency {
    pub faces: Vec<FaceId>,
    pub convexity: Convexity,
}

/// The faces using each edge, in face order (deterministic).
pub fn edge_faces(brep: &Brep) -> Vec<Vec<FaceId>> {
    let mut out = vec![Vec::new(); brep.edges.len()];
    for (fi, f) in brep.faces.iter().enumerate() {
        for &l in &f.loops {
            for ce in &brep.loops[l].coedges {
                let v: &mut Vec<FaceId> = &mut out[ce.edge];
                if v.last() != Some(&fi) {
                    v.push(fi);
                }
            }
        }
    }
    out
}

/// Normals closer than this (sine of the angle) meet smoothly.
pub const SMOOTH_SIN: f64 = 0.0175; // 1°

/// The faces using each edge and the convexity at each edge.
///
/// For the coedge of face A traversing the edge with tangent `T` (loop
/// direction, `Loop.orientation` applied), with outward normals `nA`, `nB`
/// of the two faces at the edge midpoint: `(nA × nB)·T > 0` is convex,
/// `< 0` concave, `|nA × nB|` small (and normals alike) smooth. A seam edge
/// (used twice by one face) is smooth; edges with one or more than two uses
/// are unknown.
pub fn edge_adjacency(brep: &Brep) -> Vec<EdgeAdjacency> {
    let uses = edge_uses(brep);
    uses.iter()
        .enumerate()
        .map(|(e, u)| {
            let mut faces: Vec<FaceId> = Vec::new();
            for &(f, _) in u {
                if !faces.contains(&f) {
                    faces.push(f);
                }
            }
            let convexity = match u.as_slice() {
                [(fa, da), (fb, _)] if fa != fb => convexity_at(brep, e, *fa, *da, *fb),
                [(fa, _), (fb, _)] if fa == fb => Convexity::Smooth,
                _ => Convexity::Unknown,
            };
            EdgeAdjacency { faces, convexity }
        })
        .collect()
}

/// The convexity of one edge (see [`edge_adjacency`]).
pub fn edge_convexity(brep: &Brep, edge: EdgeId) -> Convexity {
    let mut u = Vec::new();
    for (fi, f) in brep.faces.iter().enumerate() {
        for &l in &f.loops {
            let lp = &brep.loops[l];
            for ce in &lp.coedges {
                if ce.edge == edge {
                    u.push((fi, ce.forward == lp.orientation));
                }
            }
        }
    }
    match u.as_slice() {
        [(fa, da), (fb, _)] if fa != fb => convexity_at(brep, edge, *fa, *da, *fb),
        [(fa, _), (fb, _)] if fa == fb => Convexity::Smooth,
        _ => Convexity::Unknown,
    }
}

/// For every edge, its uses `(face, runs start→end in loop direction)`.
fn edge_uses(brep: &Brep) -> Vec<Vec<(FaceId, bool)>> {
    let mut out = vec![Vec::new(); brep.edges.len()];
    for (fi, f) in brep.faces.iter().enumerate() {
        for &l in &f.loops {
            let lp = &brep.loops[l];
            for ce in &lp.coedges {
                out[ce.edge].push((fi, ce.forward == lp.orientation));
            }
        }
    }
    out
}

/// Outward normal of a face at (near) a point.
pub fn face_normal_at(brep: &Brep, face: FaceId, p: DVec3) -> DVec3 {
    let f = &brep.faces[face];
    let (u, v) = f.surface.project(p);
    let n = f.surface.normal(u, v);
    if f.same_sense {
        n
    } else {
        -n
    }
}

fn convexity_at(brep: &Brep, e: EdgeId, fa: FaceId, a_forward: bool, fb: FaceId) -> Convexity {
    let edge = &brep.edges[e];
    let (t0, t1) = brep.edge_param_range(e);
    let (p, t) = if t0 == t1 {
        let a = brep.vertices[edge.start].point;
        let b = brep.vertices[edge.end].point;
        (0.5 * (a + b), (b - a).normalize_or_zero())
    } else {
        let tm = 0.5 * (t0 + t1);
        let (p, d) = edge.curve.point_d1(tm);
        (p, d.normalize_or_zero() * (t1 - t0).signum())
    };
    let ta = if a_forward { t } else { -t };
    let na = face_normal_at(brep, fa, p);
    let nb = face_normal_at(brep, fb, p);
    if ta == DVec3::ZERO || na == DVec3::ZERO || nb == DVec3::ZERO {
        return Convexity::Unknown;
    }
    let c = na.cross(nb);
    if c.length() < SMOOTH_SIN {
        return if na.dot(nb) > 0.0 {
            Convexity::Smooth
        } else {
            Convexity::Unknown
        };
    }
    let s = c.dot(ta);
    if s.abs() < 0.5 * c.length() {
        Convexity::Unknown
    } else if s > 0.0 {
        Convexity::Convex
    } else {
        Convexity::Concave
    }
}

/// Faces sharing at least one edge with `face`, ascending, without `face`.
pub fn face_neighbours(brep: &Brep, face: FaceId) -> Vec<FaceId> {
    let mut mine: Vec<EdgeId> = brep.faces[face]
        .loops
        .iter()
        .flat_map(|&l| brep.loops[l].coedges.iter().map(|c| c.edge))
        .collect();
    mine.sort_unstable();
    mine.dedup();
    let mut out = Vec::new();
    for (fi, f) in brep.faces.iter().enumerate() {
        if fi == face {
            continue;
        }
        let touches = f.loops.iter().any(|&l| {
            brep.loops[l]
                .coedges
                .iter()
                .any(|c| mine.binary_search(&c.edge).is_ok())
        });
        if touches {
            out.push(fi);
        }
    }
    out
}
