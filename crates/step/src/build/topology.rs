//! Vertices, edges, loops and faces of one representation, each built
//! once per entity, with the entity each B-rep edge and face came from.

use std::collections::HashMap;

use glam::DVec3;
use thinplan_brep::{Brep, Coedge, Curve, Edge, EdgeId, Face, Loop};

use super::curves::CurveOut;
use super::units::Units;
use super::walk::Ctx;
use super::R;

/// Per-representation geometry state: scale and the deduplication maps.
pub(super) struct Geo {
    pub(super) scale: f64,
    pub(super) angle: f64,
    pub(super) brep: Brep,
    vertices: HashMap<usize, usize>,
    edges: HashMap<usize, EdgeId>,
    poly_vertices: HashMap<usize, usize>,
    poly_edges: HashMap<(usize, usize), EdgeId>,
    /// Per B-rep edge, the entity ids it was read from (for messages).
    pub(super) edge_src: Vec<EdgeSrc>,
    /// Per B-rep face, the id of its `ADVANCED_FACE` / `FACE_SURFACE`.
    pub(super) face_src: Vec<u64>,
}

/// Where a B-rep edge came from.
#[derive(Debug, Clone, Copy)]
pub(super) enum EdgeSrc {
    Curve(u64),
    /// A `POLY_LOOP` side between two points.
    Poly(u64, u64),
}

impl Geo {
    pub(super) fn new(u: &Units) -> Geo {
        Geo {
            scale: u.length,
            angle: u.angle,
            brep: Brep::new(),
            vertices: HashMap::new(),
            edges: HashMap::new(),
            poly_vertices: HashMap::new(),
            poly_edges: HashMap::new(),
            edge_src: Vec::new(),
            face_src: Vec::new(),
        }
    }
}

impl<'x, 'a> Ctx<'x, 'a> {
    fn vertex(&mut self, idx: usize) -> R<usize> {
        if let Some(&v) = self.geo.vertices.get(&idx) {
            return Ok(v);
        }
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["VERTEX_POINT"], "a vertex")?;
        let p = self.point(a.r(1)?)?;
        let v = self.geo.brep.add_vertex(p);
        self.geo.vertices.insert(idx, v);
        Ok(v)
    }

    fn edge(&mut self, idx: usize) -> R<EdgeId> {
        if let Some(&e) = self.geo.edges.get(&idx) {
            return Ok(e);
        }
        self.tick(1, idx)?;
        if self.head(idx) != "EDGE_CURVE" {
            return Err(self.bad_kind(idx, &["EDGE_CURVE"], "an edge"));
        }
        let a = self.args(idx);
        let start = self.vertex(a.r(1)?)?;
        let end = self.vertex(a.r(2)?)?;
        let same_sense = a.logical(4)?;
        let (curve, reversed) = match self.curve(a.r(3)?, idx)? {
            CurveOut::Known { curve, reversed } => (curve, reversed),
            CurveOut::Unknown(kind) => {
                self.warn(
                    &format!("curve:{kind}"),
                    format!("curve kind {kind} replaced by a polyline through its edge's vertices"),
                );
                let b = &self.geo.brep;
                let pts = match (b.vertices.get(start), b.vertices.get(end)) {
                    (Some(s), Some(e)) => vec![s.point, e.point],
                    _ => Vec::new(),
                };
                (Curve::Polyline { points: pts }, false)
            }
        };
        let e = self.geo.brep.add_edge(Edge {
            start,
            end,
            curve,
            same_sense: same_sense ^ reversed,
        });
        let id = self.ent(idx).map(|x| x.id).unwrap_or(0);
        self.geo.edge_src.push(EdgeSrc::Curve(id));
        self.geo.edges.insert(idx, e);
        Ok(e)
    }

    fn oriented_edge(&mut self, idx: usize, from: usize) -> R<Coedge> {
        self.tick(1, idx)?;
        match self.head(idx) {
            "ORIENTED_EDGE" => {
                let a = self.args(idx);
                let element = a.r(3)?;
                let orientation = a.logical(4)?;
                self.enter(idx, from)?;
                let inner = if self.head(element) == "ORIENTED_EDGE" {
                    self.oriented_edge(element, idx)
                } else {
                    self.edge(element).map(|edge| Coedge {
                        edge,
                        forward: true,
                    })
                };
                self.leave(idx);
                let c = inner?;
                Ok(Coedge {
                    edge: c.edge,
                    forward: c.forward == orientation,
                })
            }
            "EDGE_CURVE" => Ok(Coedge {
                edge: self.edge(idx)?,
                forward: true,
            }),
            _ => Err(self.bad_kind(idx, &["ORIENTED_EDGE"], "an oriented edge")),
        }
    }

    fn poly_vertex(&mut self, pidx: usize) -> R<usize> {
        if let Some(&v) = self.geo.poly_vertices.get(&pidx) {
            return Ok(v);
        }
        let p = self.point(pidx)?;
        let v = self.geo.brep.add_vertex(p);
        self.geo.poly_vertices.insert(pidx, v);
        Ok(v)
    }

    fn lp(&mut self, idx: usize, outer: bool, orientation: bool) -> R<Loop> {
        self.tick(1, idx)?;
        let a = self.args(idx);
        let mut l = Loop {
            coedges: Vec::new(),
            vertex: None,
            orientation,
            outer,
        };
        match self.head(idx) {
            "EDGE_LOOP" => {
                for r in a.refs(1)? {
                    let c = self.oriented_edge(r, idx)?;
                    l.coedges.push(c);
                }
            }
            "VERTEX_LOOP" => l.vertex = Some(self.vertex(a.r(1)?)?),
            "POLY_LOOP" => {
                let pts = a.refs(1)?;
                let n = pts.len();
                for i in 0..n {
                    let (pa, pb) = (pts[i], pts[(i + 1) % n]);
                    let key = (pa.min(pb), pa.max(pb));
                    let forward = pa <= pb;
                    let edge = match self.geo.poly_edges.get(&key) {
                        Some(&e) => e,
                        None => {
                            let start = self.poly_vertex(key.0)?;
                            let end = self.poly_vertex(key.1)?;
                            let (ps, pe) = (
                                self.geo.brep.vertices[start].point,
                                self.geo.brep.vertices[end].point,
                            );
                            let dir = (pe - ps).try_normalize().unwrap_or(DVec3::X);
                            let e = self.geo.brep.add_edge(Edge {
                                start,
                                end,
                                curve: Curve::Line { origin: ps, dir },
                                same_sense: true,
                            });
                            let id = |i: usize| self.ent(i).map(|x| x.id).unwrap_or(0);
                            let src = EdgeSrc::Poly(id(key.0), id(key.1));
                            self.geo.edge_src.push(src);
                            self.geo.poly_edges.insert(key, e);
                            e
                        }
                    };
                    l.coedges.push(Coedge { edge, forward });
                }
            }
            _ => {
                return Err(self.bad_kind(
                    idx,
                    &["EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP"],
                    "a loop",
                ))
            }
        }
        Ok(l)
    }

    pub(super) fn face(&mut self, idx: usize, from: usize) -> R<usize> {
        self.tick(1, idx)?;
        let a = self.args(idx);
        match self.head(idx) {
            "ADVANCED_FACE" | "FACE_SURFACE" => {
                let name = a.string(0);
                let bounds = a.refs(1)?;
                let surface = self.surface(a.r(2)?, idx)?;
                let same_sense = a.logical(3)?;
                let mut loops = Vec::with_capacity(bounds.len());
                for b in bounds {
                    let ba =
                        self.expect_type(b, &["FACE_OUTER_BOUND", "FACE_BOUND"], "a face bound")?;
                    let outer = ba.ty == "FACE_OUTER_BOUND";
                    let orientation = ba.logical(2)?;
                    let l = self.lp(ba.r(1)?, outer, orientation)?;
                    loops.push(self.geo.brep.add_loop(l));
                }
                let id = self.ent(idx).map(|x| x.id).unwrap_or(0);
                self.geo.face_src.push(id);
                Ok(self.geo.brep.add_face(Face {
                    surface,
                    same_sense,
                    loops,
                    name,
                }))
            }
            "ORIENTED_FACE" => {
                let element = a.r(2)?;
                let orientation = a.logical(3)?;
                self.enter(idx, from)?;
                let f = self.face(element, idx);
                self.leave(idx);
                let f = f?;
                if !orientation {
                    self.reverse_face(f);
                }
                Ok(f)
            }
            _ => Err(self.bad_kind(idx, &["ADVANCED_FACE", "FACE_SURFACE"], "a face")),
        }
    }

    /// Turns a face over: its normal and its bounds (`ORIENTED_FACE(.F.)`).
    pub(super) fn reverse_face(&mut self, f: usize) {
        let b = &mut self.geo.brep;
        if let Some(face) = b.faces.get_mut(f) {
            face.same_sense = !face.same_sense;
            for &l in &face.loops {
                if let Some(lp) = b.loops.get_mut(l) {
                    lp.orientation = !lp.orientation;
                }
            }
        }
    }
}
