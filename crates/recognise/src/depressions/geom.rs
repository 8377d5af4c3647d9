//! Face geometry the depression recogniser reasons on: outward normals,
//! sampled boundaries, hull tests, 2D profiles in a feature frame.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_brep::{
    Brep, Convexity, EdgeAdjacency, EdgeId, FaceId, Frame, Surface, TessTolerance,
};

/// What the recogniser needs to know of one face's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaceGeom {
    /// A plane with its outward normal and a point on it.
    Plane { normal: DVec3, origin: DVec3 },
    /// A cylinder; `hole` when the material is outside it (outward normal
    /// towards the axis: a hole wall or a concave blend).
    Cylinder {
        axis: DVec3,
        origin: DVec3,
        radius: f64,
        hole: bool,
    },
    /// A cone (countersink, drill point); `hole` as for cylinders.
    Cone { axis: DVec3, hole: bool },
    /// Anything else (tori, free-form).
    Other,
}

/// One neighbour of a face across an edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    pub face: FaceId,
    pub edge: EdgeId,
    pub convexity: Convexity,
}

/// Per-face facts, computed once per part.
#[derive(Debug, Clone)]
pub struct FaceFacts {
    pub geom: FaceGeom,
    /// Boundary sample points of all loops.
    pub points: Vec<DVec3>,
    /// The sampled outer loop (the loop enclosing the largest area).
    pub outer: Vec<DVec3>,
    pub neighbours: Vec<Neighbour>,
    /// A planar face with the whole part behind it (on the convex hull):
    /// a face of the stock envelope.
    pub hull: bool,
}

impl FaceGeom {
    pub fn of(brep: &Brep, f: FaceId) -> FaceGeom {
        let face = &brep.faces[f];
        let s = if face.same_sense { 1.0 } else { -1.0 };
        match &face.surface {
            Surface::Plane { frame } => FaceGeom::Plane {
                normal: frame.z * s,
                origin: frame.origin,
            },
            Surface::Cylinder { frame, radius } => FaceGeom::Cylinder {
                axis: frame.z,
                origin: frame.origin,
                radius: *radius,
                hole: !face.same_sense,
            },
            Surface::Cone { frame, .. } => FaceGeom::Cone {
                axis: frame.z,
                hole: !face.same_sense,
            },
            _ => FaceGeom::Other,
        }
    }

    pub fn normal(&self) -> Option<DVec3> {
        match self {
            FaceGeom::Plane { normal, .. } => Some(*normal),
            _ => None,
        }
    }

    /// The axis of a cylinder or cone.
    #[allow(dead_code)]
    pub fn axis(&self) -> Option<DVec3> {
        match self {
            FaceGeom::Cylinder { axis, .. } | FaceGeom::Cone { axis, .. } => Some(*axis),
            _ => None,
        }
    }
}

/// Computes the facts of every face.
pub fn face_facts(brep: &Brep, adjacency: &[EdgeAdjacency], tol: f64) -> Vec<FaceFacts> {
    let diag = brep.rough_bbox().extent().length().max(1.0);
    let ttol = TessTolerance {
        chord: (diag * 1e-3).clamp(1e-4, 0.5),
        angle: 0.3,
    };
    let mut neighbours: Vec<Vec<Neighbour>> = vec![Vec::new(); brep.faces.len()];
    for (e, a) in adjacency.iter().enumerate() {
        if let [fa, fb] = a.faces[..] {
            neighbours[fa].push(Neighbour {
                face: fb,
                edge: e,
                convexity: a.convexity,
            });
            neighbours[fb].push(Neighbour {
                face: fa,
                edge: e,
                convexity: a.convexity,
            });
        }
    }
    let mut facts: Vec<FaceFacts> = Vec::with_capacity(brep.faces.len());
    for (f, face) in brep.faces.iter().enumerate() {
        let geom = FaceGeom::of(brep, f);
        let mut points = Vec::new();
        let mut outer = Vec::new();
        let mut best = -1.0;
        for &l in &face.loops {
            let poly = brep.loop_polyline(l, &ttol);
            let area = loop_area(&poly);
            if area > best {
                best = area;
                outer = poly.clone();
            }
            points.extend(poly);
        }
        facts.push(FaceFacts {
            geom,
            points,
            outer,
            neighbours: std::mem::take(&mut neighbours[f]),
            hull: false,
        });
    }
    // Hull test against every boundary point of the part: the support
    // value max p·n over all points, computed once per distinct normal
    // (parts share few plane directions; the web bottoms of a panel are one).
    let all: Vec<DVec3> = facts
        .iter()
        .flat_map(|x| x.points.iter().copied())
        .collect();
    let mut support: BTreeMap<[i64; 3], f64> = BTreeMap::new();
    for fx in facts.iter_mut() {
        if let FaceGeom::Plane { normal, origin } = fx.geom {
            let h = *support
                .entry(direction_key(normal))
                .or_insert_with(|| all.iter().map(|p| p.dot(normal)).fold(f64::MIN, f64::max));
            fx.hull = h - origin.dot(normal) <= tol;
        }
    }
    facts
}

/// A key for a unit direction, equal for directions within about 1e-9.
pub fn direction_key(n: DVec3) -> [i64; 3] {
    let q = |x: f64| (x * 1e9).round() as i64;
    [q(n.x), q(n.y), q(n.z)]
}

/// Area magnitude of a closed 3D polyline (vector area).
pub fn loop_area(poly: &[DVec3]) -> f64 {
    let mut a = DVec3::ZERO;
    for i in 0..poly.len() {
        a += poly[i].cross(poly[(i + 1) % poly.len()]);
    }
    0.5 * a.length()
}

/// A frame with z along `axis`.
pub fn frame_for(axis: DVec3, origin: DVec3) -> Frame {
    Frame::from_axis_ref(origin, axis, None)
}

/// 2D convex hull (Andrew's monotone chain), counter-clockwise.
pub fn convex_hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup_by(|a, b| a.distance_squared(*b) < 1e-18);
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut lower: Vec<DVec2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<DVec2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Removes consecutive duplicate and collinear points of a closed 2D polygon
/// (within `tol` mm), giving its corners.
pub fn polygon_corners(poly: &[DVec2], tol: f64) -> Vec<DVec2> {
    let mut pts: Vec<DVec2> = Vec::new();
    for &p in poly {
        if pts.last().is_none_or(|q: &DVec2| q.distance(p) > tol) {
            pts.push(p);
        }
    }
    while pts.len() > 1 && pts[0].distance(pts[pts.len() - 1]) <= tol {
        pts.pop();
    }
    let mut changed = true;
    while changed && pts.len() > 3 {
        changed = false;
        for i in 0..pts.len() {
            let n = pts.len();
            let a = pts[(i + n - 1) % n];
            let b = pts[i];
            let c = pts[(i + 1) % n];
            let ab = b - a;
            let d = if ab.length() > 0.0 {
                ab.perp_dot(c - a).abs() / (c - a).length().max(1e-300)
            } else {
                0.0
            };
            if d <= tol {
                pts.remove(i);
                changed = true;
                break;
            }
        }
    }
    pts
}

/// Signed area of a 2D polygon (positive counter-clockwise).
pub fn signed_area(poly: &[DVec2]) -> f64 {
    let mut a = 0.0;
    for i in 0..poly.len() {
        a += poly[i].perp_dot(poly[(i + 1) % poly.len()]);
    }
    0.5 * a
}
