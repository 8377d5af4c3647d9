//! Mass properties on the tessellation: volume (divergence theorem), area,
//! and an axis-aligned box tightened by the analytic extremes of arcs.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::geom::Curve;
use crate::tess::{tessellate, tessellate_face, Mesh, TessTolerance};
use crate::{Aabb, Brep, FaceId, SolidId};

/// Chord tolerance of mass properties, relative to the bounding-box diagonal.
pub const MASS_REL_CHORD: f64 = 2e-5;

/// Volume, area and box computed from one tessellation.
#[derive(Debug, Clone, PartialEq)]
pub struct MassProperties {
    /// Sum of the solids' signed volumes, mm³ (voids subtract).
    pub volume: f64,
    /// Sum of all faces' areas, mm².
    pub area: f64,
    pub bbox: Aabb,
    /// The tolerance the tessellation used.
    pub tolerance: TessTolerance,
    /// Faces that could not be tessellated (their contribution is missing).
    pub failed_faces: Vec<FaceId>,
}

impl Brep {
    /// A quick box from the vertices and the analytic extremes of the circle
    /// and ellipse edges (no tessellation); used to size tolerances.
    pub fn rough_bbox(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for v in &self.vertices {
            b.include(v.point);
        }
        for e in 0..self.edges.len() {
            for p in self.edge_extremes(e) {
                b.include(p);
            }
        }
        b
    }

    /// The points of a circle or ellipse edge where a world coordinate is
    /// extreme (within the edge's range); empty for other curves.
    pub fn edge_extremes(&self, e: crate::EdgeId) -> Vec<DVec3> {
        let edge = &self.edges[e];
        let (frame, a, b) = match &edge.curve {
            Curve::Circle { frame, radius } => (frame, *radius, *radius),
            Curve::Ellipse {
                frame,
                semi_axis_1,
                semi_axis_2,
            } => (frame, *semi_axis_1, *semi_axis_2),
            _ => return Vec::new(),
        };
        let (t0, t1) = self.edge_param_range(e);
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let mut out = Vec::new();
        for k in 0..3 {
            let t_star = (b * frame.y[k]).atan2(a * frame.x[k]);
            for t in [t_star, t_star + std::f64::consts::PI] {
                let t = lo + (t - lo).rem_euclid(TAU);
                if t <= hi + 1e-12 {
                    out.push(edge.curve.point(t));
                }
            }
        }
        out
    }

    /// The tolerance used by the mass-property methods: a chord of
    /// [`MASS_REL_CHORD`] times the bounding-box diagonal, angle 0.1 rad.
    pub fn mass_tolerance(&self) -> TessTolerance {
        let d = self.rough_bbox().extent().length();
        let mut t = TessTolerance::relative(if d > 0.0 { d } else { 1.0 }, MASS_REL_CHORD);
        t.angle = 0.1;
        t
    }

    /// Volume, area and box from one tessellation at [`Brep::mass_tolerance`].
    pub fn mass_properties(&self) -> MassProperties {
        self.mass_properties_with(&self.mass_tolerance())
    }

    /// Volume, area and box from one tessellation at `tol`.
    pub fn mass_properties_with(&self, tol: &TessTolerance) -> MassProperties {
        let mesh = tessellate(self, tol);
        MassProperties {
            volume: self.volume_of_mesh(&mesh),
            area: mesh.area(),
            bbox: self.bbox_of_mesh(&mesh),
            tolerance: *tol,
            failed_faces: mesh.failed_faces.iter().map(|(f, _)| *f).collect(),
        }
    }

    fn volume_of_mesh(&self, mesh: &Mesh) -> f64 {
        if self.solids.is_empty() {
            let mut in_closed = vec![false; self.faces.len()];
            for s in self.shells.iter().filter(|s| s.closed) {
                for &f in &s.faces {
                    in_closed[f] = true;
                }
            }
            if self.shells.is_empty() {
                return mesh.signed_volume();
            }
            return mesh.signed_volume_where(|f| in_closed[f]);
        }
        // A face counts once per solid that uses it.
        let mut uses = vec![0u32; self.faces.len()];
        for s in 0..self.solids.len() {
            for f in self.solid_faces(s) {
                uses[f] += 1;
            }
        }
        let mut total = 0.0;
        let max_uses = uses.iter().copied().max().unwrap_or(0);
        for k in 1..=max_uses {
            total += mesh.signed_volume_where(|f| uses[f] >= k);
        }
        total
    }

    fn bbox_of_mesh(&self, mesh: &Mesh) -> Aabb {
        let mut b = mesh.bbox();
        for v in &self.vertices {
            b.include(v.point);
        }
        for e in 0..self.edges.len() {
            for p in self.edge_extremes(e) {
                b.include(p);
            }
        }
        b
    }

    /// Enclosed volume in mm³: the sum over solids (void shells subtract
    /// through their inward-facing orientation); without solids, the closed
    /// shells.
    pub fn volume(&self) -> f64 {
        self.mass_properties().volume
    }

    /// Volume of one solid, mm³.
    pub fn solid_volume(&self, solid: SolidId) -> f64 {
        let tol = self.mass_tolerance();
        let mut mesh = Mesh::default();
        for f in self.solid_faces(solid) {
            if let Ok(m) = tessellate_face(self, f, &tol) {
                mesh.append(&m);
            }
        }
        mesh.signed_volume()
    }

    /// Axis-aligned box of the part (tessellation points within the chord
    /// tolerance, arcs' extremes exact).
    pub fn bbox(&self) -> Aabb {
        self.mass_properties().bbox
    }

    /// Total face area in mm².
    pub fn surface_area(&self) -> f64 {
        self.mass_properties().area
    }
}
