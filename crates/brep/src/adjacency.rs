//! Face adjacency across edges, with the convexity of each edge.

use serde::{Deserialize, Serialize};

use crate::{Brep, FaceId};

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
