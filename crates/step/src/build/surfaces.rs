//! Surfaces: elementary, B-spline, extrusion and revolution surfaces;
//! other kinds are kept by name with a warning.

use thinplan_brep::Surface;

use super::curves::CurveOut;
use super::walk::Ctx;
use super::R;

impl<'x, 'a> Ctx<'x, 'a> {
    pub(super) fn surface(&mut self, idx: usize, from: usize) -> R<Surface> {
        self.tick(1, idx)?;
        self.enter(idx, from)?;
        let r = self.surface_inner(idx);
        self.leave(idx);
        r
    }

    fn surface_inner(&mut self, idx: usize) -> R<Surface> {
        let a = self.args(idx);
        Ok(match self.head(idx) {
            "PLANE" => Surface::Plane {
                frame: self.placement(a.r(1)?)?,
            },
            "CYLINDRICAL_SURFACE" => Surface::Cylinder {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
            },
            "CONICAL_SURFACE" => Surface::Cone {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
                semi_angle: a.num(3)? * self.geo.angle,
            },
            "SPHERICAL_SURFACE" => Surface::Sphere {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
            },
            "TOROIDAL_SURFACE" | "DEGENERATE_TOROIDAL_SURFACE" => Surface::Torus {
                frame: self.placement(a.r(1)?)?,
                major_radius: self.length(&a, 2)?,
                minor_radius: self.length(&a, 3)?,
            },
            "B_SPLINE_SURFACE_WITH_KNOTS" => self.bspline_surface(idx)?,
            "SURFACE_OF_LINEAR_EXTRUSION" => match self.curve(a.r(1)?, idx)? {
                CurveOut::Known { curve, .. } => {
                    let (d, m) = self.vector(a.r(2)?)?;
                    Surface::Extrusion {
                        curve: Box::new(curve),
                        dir: d * m,
                    }
                }
                CurveOut::Unknown(k) => Surface::Other {
                    kind: format!("SURFACE_OF_LINEAR_EXTRUSION of {k}"),
                },
            },
            "SURFACE_OF_REVOLUTION" => match self.curve(a.r(1)?, idx)? {
                CurveOut::Known { curve, .. } => {
                    let (axis_origin, axis_dir) = self.axis1(a.r(2)?)?;
                    Surface::Revolution {
                        curve: Box::new(curve),
                        axis_origin,
                        axis_dir,
                    }
                }
                CurveOut::Unknown(k) => Surface::Other {
                    kind: format!("SURFACE_OF_REVOLUTION of {k}"),
                },
            },
            "" if self.has_part(idx, "B_SPLINE_SURFACE") => self.bspline_surface(idx)?,
            _ => {
                let kind = self.type_label(idx);
                self.warn(
                    &format!("surface:{kind}"),
                    format!("surface kind {kind} kept by name only"),
                );
                Surface::Other { kind }
            }
        })
    }
}
