//! Analytic and free-form curves and surfaces, with parameters kept.

use glam::{DMat4, DVec3};
use serde::{Deserialize, Serialize};

/// A right-handed orthonormal frame (STEP `AXIS2_PLACEMENT_3D`).
/// `z` is the axis (of a cylinder, cone, circle …) or the plane normal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub origin: DVec3,
    pub x: DVec3,
    pub y: DVec3,
    pub z: DVec3,
}

impl Frame {
    pub const WORLD: Frame = Frame {
        origin: DVec3::ZERO,
        x: DVec3::X,
        y: DVec3::Y,
        z: DVec3::Z,
    };

    /// Builds an orthonormal frame from an axis and a reference direction
    /// (which need not be perpendicular to the axis, as in STEP).
    pub fn from_axis_ref(origin: DVec3, axis: DVec3, ref_dir: Option<DVec3>) -> Frame {
        let z = axis.try_normalize().unwrap_or(DVec3::Z);
        let candidate = ref_dir.unwrap_or(if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y });
        let mut x = candidate - z * candidate.dot(z);
        if x.length_squared() < 1e-20 {
            let alt = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
            x = alt - z * alt.dot(z);
        }
        let x = x.normalize();
        let y = z.cross(x);
        Frame { origin, x, y, z }
    }

    /// Local coordinates → world.
    pub fn to_world(&self, local: DVec3) -> DVec3 {
        self.origin + self.x * local.x + self.y * local.y + self.z * local.z
    }

    /// World → local coordinates.
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.x), d.dot(self.y), d.dot(self.z))
    }

    /// The homogeneous matrix taking local coordinates to world.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_cols(
            self.x.extend(0.0),
            self.y.extend(0.0),
            self.z.extend(0.0),
            self.origin.extend(1.0),
        )
    }

    pub fn transform(&mut self, m: &DMat4) {
        self.origin = m.transform_point3(self.origin);
        self.x = m.transform_vector3(self.x).normalize();
        self.y = m.transform_vector3(self.y).normalize();
        self.z = m.transform_vector3(self.z).normalize();
    }
}

/// Curves carried by edges. Parameters as in ISO 10303-42.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Curve {
    /// Point and unit direction; parameter is arc length.
    Line { origin: DVec3, dir: DVec3 },
    /// Parameter is the angle in radians from `frame.x` towards `frame.y`.
    Circle { frame: Frame, radius: f64 },
    Ellipse {
        frame: Frame,
        semi_axis_1: f64,
        semi_axis_2: f64,
    },
    /// Non-uniform (optionally rational) B-spline; `knots` fully expanded
    /// (multiplicities applied), `weights` empty when not rational.
    BSpline {
        degree: usize,
        control_points: Vec<DVec3>,
        knots: Vec<f64>,
        weights: Vec<f64>,
    },
    /// A polyline through the given points (from tessellated or unsupported
    /// curves, e.g. a hyperbola sampled between its vertices).
    Polyline { points: Vec<DVec3> },
}

/// Surfaces carried by faces. The surface normal for `Plane` is `frame.z`;
/// for cylinders, cones, spheres and tori it points away from the axis/centre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Surface {
    Plane {
        frame: Frame,
    },
    Cylinder {
        frame: Frame,
        radius: f64,
    },
    /// `radius` is the radius at the frame origin; `semi_angle` in radians.
    Cone {
        frame: Frame,
        radius: f64,
        semi_angle: f64,
    },
    Sphere {
        frame: Frame,
        radius: f64,
    },
    Torus {
        frame: Frame,
        major_radius: f64,
        minor_radius: f64,
    },
    /// Tensor-product (optionally rational) B-spline surface; control points
    /// row-major `[u][v]`, knots expanded, weights empty when not rational.
    BSpline {
        u_degree: usize,
        v_degree: usize,
        control_points: Vec<Vec<DVec3>>,
        u_knots: Vec<f64>,
        v_knots: Vec<f64>,
        weights: Vec<Vec<f64>>,
    },
    /// A curve swept along a direction (`SURFACE_OF_LINEAR_EXTRUSION`).
    Extrusion {
        curve: Box<Curve>,
        dir: DVec3,
    },
    /// A curve revolved about an axis (`SURFACE_OF_REVOLUTION`).
    Revolution {
        curve: Box<Curve>,
        axis_origin: DVec3,
        axis_dir: DVec3,
    },
    /// A surface kind the reader keeps only by name (offset surfaces …).
    Other {
        kind: String,
    },
}

impl Curve {
    pub fn transform(&mut self, m: &DMat4) {
        match self {
            Curve::Line { origin, dir } => {
                *origin = m.transform_point3(*origin);
                *dir = m.transform_vector3(*dir).normalize();
            }
            Curve::Circle { frame, .. } | Curve::Ellipse { frame, .. } => frame.transform(m),
            Curve::BSpline { control_points, .. } => {
                for p in control_points {
                    *p = m.transform_point3(*p);
                }
            }
            Curve::Polyline { points } => {
                for p in points {
                    *p = m.transform_point3(*p);
                }
            }
        }
    }
}

impl Surface {
    pub fn transform(&mut self, m: &DMat4) {
        match self {
            Surface::Plane { frame }
            | Surface::Cylinder { frame, .. }
            | Surface::Cone { frame, .. }
            | Surface::Sphere { frame, .. }
            | Surface::Torus { frame, .. } => frame.transform(m),
            Surface::BSpline { control_points, .. } => {
                for row in control_points {
                    for p in row {
                        *p = m.transform_point3(*p);
                    }
                }
            }
            Surface::Extrusion { curve, dir } => {
                curve.transform(m);
                *dir = m.transform_vector3(*dir);
            }
            Surface::Revolution {
                curve,
                axis_origin,
                axis_dir,
            } => {
                curve.transform(m);
                *axis_origin = m.transform_point3(*axis_origin);
                *axis_dir = m.transform_vector3(*axis_dir).normalize();
            }
            Surface::Other { .. } => {}
        }
    }

    /// A short name of the kind, as used in the `inspect` contract.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Surface::Plane { .. } => "plane",
            Surface::Cylinder { .. } => "cylinder",
            Surface::Cone { .. } => "cone",
            Surface::Sphere { .. } => "sphere",
            Surface::Torus { .. } => "torus",
            Surface::BSpline { .. } => "bspline",
            _ => "other",
        }
    }
}
