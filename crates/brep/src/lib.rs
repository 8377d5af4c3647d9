//! Index-based boundary representation (B-rep) shared by every importer and stage.
//!
//! Entities live in flat vectors and refer to one another by index, so the
//! structure is trivially serialisable, cheap to clone and deterministic.
//! Surfaces and curves keep their analytic parameters (planes, cylinders,
//! radii, axes) because recognition reasons on them directly.
//!
//! Units: millimetres, always. Importers convert.

use glam::DVec3;
use serde::{Deserialize, Serialize};

pub mod adjacency;
pub mod eval;
pub mod geom;
pub mod mass;
#[cfg(test)]
mod proptests;
pub mod sample;
pub mod tess;
#[cfg(any(test, feature = "test-shapes"))]
pub mod test_shapes;

pub use adjacency::{edge_adjacency, face_neighbours, Convexity, EdgeAdjacency};
pub use geom::{Curve, Frame, Surface};
pub use mass::MassProperties;
pub use tess::{tessellate, tessellate_face, Mesh, TessError, TessTolerance};

/// Index of a vertex in [`Brep::vertices`].
pub type VertexId = usize;
/// Index of an edge in [`Brep::edges`].
pub type EdgeId = usize;
/// Index of a loop in [`Brep::loops`].
pub type LoopId = usize;
/// Index of a face in [`Brep::faces`].
pub type FaceId = usize;
/// Index of a shell in [`Brep::shells`].
pub type ShellId = usize;
/// Index of a solid in [`Brep::solids`].
pub type SolidId = usize;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Vertex {
    pub point: DVec3,
}

/// A bounded piece of a curve from `start` to `end`.
///
/// When `same_sense` is true the edge runs along the curve's own direction
/// from `start` to `end`; otherwise against it. A closed edge (a full circle
/// bounding a round hole) has `start == end`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    pub start: VertexId,
    pub end: VertexId,
    pub curve: Curve,
    pub same_sense: bool,
}

impl Edge {
    pub fn is_closed(&self) -> bool {
        self.start == self.end
    }
}

/// A use of an edge by a loop, in the loop's direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Coedge {
    pub edge: EdgeId,
    /// True when the loop traverses the edge from its start to its end.
    pub forward: bool,
}

/// A closed chain of coedges bounding a face. A loop made of a single vertex
/// (`VERTEX_LOOP`, the apex of a cone) has no coedges and `vertex` set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Loop {
    pub coedges: Vec<Coedge>,
    pub vertex: Option<VertexId>,
    /// False when the file marked the bound as reversed (`FACE_BOUND(.F.)`);
    /// coedges are stored as the file gave them.
    pub orientation: bool,
    /// True for a `FACE_OUTER_BOUND`, false for an inner or unspecified bound.
    pub outer: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Face {
    pub surface: Surface,
    /// True when the face's outward normal is the surface's own normal.
    pub same_sense: bool,
    pub loops: Vec<LoopId>,
    /// The name the source gave the face (STEP `ADVANCED_FACE('name', …)`), or empty.
    pub name: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Shell {
    pub faces: Vec<FaceId>,
    /// Closed shells bound a volume; open shells do not.
    pub closed: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Solid {
    /// The first shell is the outer boundary; the rest are voids.
    pub shells: Vec<ShellId>,
    pub name: String,
}

/// A whole part: one or more solids sharing nothing but the index space.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Brep {
    pub vertices: Vec<Vertex>,
    pub edges: Vec<Edge>,
    pub loops: Vec<Loop>,
    pub faces: Vec<Face>,
    pub shells: Vec<Shell>,
    pub solids: Vec<Solid>,
}

/// Axis-aligned bounding box in millimetres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn include(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    pub fn extent(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }
}

/// Counts of faces by surface kind, in the order of the `inspect` contract.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FaceKindCounts {
    pub plane: usize,
    pub cylinder: usize,
    pub cone: usize,
    pub sphere: usize,
    pub torus: usize,
    pub bspline: usize,
    pub other: usize,
}

impl Brep {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn add_vertex(&mut self, point: DVec3) -> VertexId {
        self.vertices.push(Vertex { point });
        self.vertices.len() - 1
    }

    pub fn add_edge(&mut self, edge: Edge) -> EdgeId {
        self.edges.push(edge);
        self.edges.len() - 1
    }

    pub fn add_loop(&mut self, lp: Loop) -> LoopId {
        self.loops.push(lp);
        self.loops.len() - 1
    }

    pub fn add_face(&mut self, face: Face) -> FaceId {
        self.faces.push(face);
        self.faces.len() - 1
    }

    pub fn add_shell(&mut self, shell: Shell) -> ShellId {
        self.shells.push(shell);
        self.shells.len() - 1
    }

    pub fn add_solid(&mut self, solid: Solid) -> SolidId {
        self.solids.push(solid);
        self.solids.len() - 1
    }

    /// Faces of a solid, over all its shells, in shell order.
    pub fn solid_faces(&self, solid: SolidId) -> impl Iterator<Item = FaceId> + '_ {
        self.solids[solid]
            .shells
            .iter()
            .flat_map(move |&s| self.shells[s].faces.iter().copied())
    }

    pub fn face_kind_counts(&self) -> FaceKindCounts {
        let mut c = FaceKindCounts::default();
        for f in &self.faces {
            match f.surface {
                Surface::Plane { .. } => c.plane += 1,
                Surface::Cylinder { .. } => c.cylinder += 1,
                Surface::Cone { .. } => c.cone += 1,
                Surface::Sphere { .. } => c.sphere += 1,
                Surface::Torus { .. } => c.torus += 1,
                Surface::BSpline { .. } => c.bspline += 1,
                _ => c.other += 1,
            }
        }
        c
    }

    /// The vertex a coedge starts at, in loop direction.
    pub fn coedge_start(&self, ce: Coedge) -> VertexId {
        let e = &self.edges[ce.edge];
        if ce.forward {
            e.start
        } else {
            e.end
        }
    }

    /// The vertex a coedge ends at, in loop direction.
    pub fn coedge_end(&self, ce: Coedge) -> VertexId {
        let e = &self.edges[ce.edge];
        if ce.forward {
            e.end
        } else {
            e.start
        }
    }

    /// Applies a rigid transform (rotation + translation, homogeneous 4×4)
    /// to every point, direction and frame; used to place assembly instances.
    pub fn transform(&mut self, m: &glam::DMat4) {
        for v in &mut self.vertices {
            v.point = m.transform_point3(v.point);
        }
        for e in &mut self.edges {
            e.curve.transform(m);
        }
        for f in &mut self.faces {
            f.surface.transform(m);
        }
    }

    /// Appends another B-rep, shifting its indices; returns the new solid ids.
    pub fn append(&mut self, other: &Brep) -> Vec<SolidId> {
        let (v0, e0, l0, f0, s0, so0) = (
            self.vertices.len(),
            self.edges.len(),
            self.loops.len(),
            self.faces.len(),
            self.shells.len(),
            self.solids.len(),
        );
        self.vertices.extend(other.vertices.iter().cloned());
        self.edges.extend(other.edges.iter().map(|e| Edge {
            start: e.start + v0,
            end: e.end + v0,
            curve: e.curve.clone(),
            same_sense: e.same_sense,
        }));
        self.loops.extend(other.loops.iter().map(|l| {
            Loop {
                coedges: l
                    .coedges
                    .iter()
                    .map(|c| Coedge {
                        edge: c.edge + e0,
                        forward: c.forward,
                    })
                    .collect(),
                vertex: l.vertex.map(|v| v + v0),
                orientation: l.orientation,
                outer: l.outer,
            }
        }));
        self.faces.extend(other.faces.iter().map(|f| Face {
            surface: f.surface.clone(),
            same_sense: f.same_sense,
            loops: f.loops.iter().map(|l| l + l0).collect(),
            name: f.name.clone(),
        }));
        self.shells.extend(other.shells.iter().map(|s| Shell {
            faces: s.faces.iter().map(|f| f + f0).collect(),
            closed: s.closed,
        }));
        self.solids.extend(other.solids.iter().map(|s| Solid {
            shells: s.shells.iter().map(|x| x + s0).collect(),
            name: s.name.clone(),
        }));
        (so0..self.solids.len()).collect()
    }
}
