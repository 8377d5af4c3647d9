//! Curves: lines, conics, B-splines, polylines and the curves that wrap
//! another (surface, seam and trimmed curves); kinds not modelled are
//! returned by name for the edge to replace.

use thinplan_brep::Curve;

use super::walk::Ctx;
use super::R;

/// A curve as read, or the name of a kind we do not model.
pub(super) enum CurveOut {
    Known { curve: Curve, reversed: bool },
    Unknown(String),
}

impl<'x, 'a> Ctx<'x, 'a> {
    pub(super) fn curve(&mut self, idx: usize, from: usize) -> R<CurveOut> {
        self.tick(1, idx)?;
        self.enter(idx, from)?;
        let r = self.curve_inner(idx);
        self.leave(idx);
        r
    }

    fn curve_inner(&mut self, idx: usize) -> R<CurveOut> {
        let a = self.args(idx);
        let known = |curve| {
            Ok(CurveOut::Known {
                curve,
                reversed: false,
            })
        };
        match self.head(idx) {
            "LINE" => {
                let origin = self.point(a.r(1)?)?;
                let (dir, _) = self.vector(a.r(2)?)?;
                known(Curve::Line { origin, dir })
            }
            "CIRCLE" => {
                let p = a.r(1)?;
                if self.head(p) != "AXIS2_PLACEMENT_3D" {
                    return Ok(CurveOut::Unknown("CIRCLE (2D)".into()));
                }
                let frame = self.placement(p)?;
                let radius = self.length(&a, 2)?;
                known(Curve::Circle { frame, radius })
            }
            "ELLIPSE" => {
                let p = a.r(1)?;
                if self.head(p) != "AXIS2_PLACEMENT_3D" {
                    return Ok(CurveOut::Unknown("ELLIPSE (2D)".into()));
                }
                let frame = self.placement(p)?;
                let semi_axis_1 = self.length(&a, 2)?;
                let semi_axis_2 = self.length(&a, 3)?;
                known(Curve::Ellipse {
                    frame,
                    semi_axis_1,
                    semi_axis_2,
                })
            }
            "B_SPLINE_CURVE_WITH_KNOTS" => known(self.bspline_curve(idx)?),
            "POLYLINE" => {
                let points = self.points(&a, 1)?;
                known(Curve::Polyline { points })
            }
            "SURFACE_CURVE" | "SEAM_CURVE" | "INTERSECTION_CURVE" | "BOUNDED_SURFACE_CURVE" => {
                self.curve(a.r(1)?, idx)
            }
            "TRIMMED_CURVE" => {
                let basis = a.r(1)?;
                let sense = a.logical(4).unwrap_or(true);
                Ok(match self.curve(basis, idx)? {
                    CurveOut::Known { curve, reversed } => CurveOut::Known {
                        curve,
                        reversed: reversed ^ !sense,
                    },
                    u => u,
                })
            }
            "" => {
                if self.has_part(idx, "B_SPLINE_CURVE") {
                    known(self.bspline_curve(idx)?)
                } else {
                    Ok(CurveOut::Unknown(self.type_label(idx)))
                }
            }
            other => Ok(CurveOut::Unknown(other.to_string())),
        }
    }
}
