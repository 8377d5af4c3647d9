//! B-spline curves and surfaces, simple or complex (rational) entities:
//! degrees, control points, weights and knots expanded from their
//! multiplicities.

use glam::DVec3;
use thinplan_brep::{Curve, Surface};

use crate::p21::Value;

use super::args::{resolve_from, A};
use super::walk::Ctx;
use super::R;

impl<'x, 'a> Ctx<'x, 'a> {
    fn expand_knots(
        &mut self,
        a: &A<'x, 'a>,
        mults: usize,
        knots: usize,
        n_expected: usize,
    ) -> R<Vec<f64>> {
        let m = a.list(mults)?;
        let k = a.list(knots)?;
        if m.len() != k.len() {
            return Err(a.wrong(format!(
                "{} knot multiplicities for {} knots",
                m.len(),
                k.len()
            )));
        }
        let bound = n_expected.saturating_mul(4).saturating_add(64);
        let mut out = Vec::with_capacity(n_expected.min(1 << 20));
        for (mv, kv) in m.iter().zip(k) {
            let mult = match mv {
                Value::Int(i) if *i >= 0 => *i as usize,
                _ => return Err(a.wrong("knot multiplicity must be a non-negative integer")),
            };
            let knot = a.value_num(kv, "knot")?;
            if out.len().saturating_add(mult) > bound {
                return Err(a.wrong(format!(
                    "knot multiplicities add up to more than {bound} for {n_expected} expected knots"
                )));
            }
            out.extend(std::iter::repeat_n(knot, mult));
        }
        self.tick(out.len() as u64, a.idx)?;
        // Evaluation searches the knots by bisection, which decreasing knots
        // would send round for ever.
        if out.windows(2).any(|w| w[1] < w[0]) {
            return Err(a.wrong("knots decrease"));
        }
        if out.len() != n_expected {
            let id = self.ent(a.idx).map(|e| e.id).unwrap_or(0);
            self.warn(
                &format!("knots#{id}"),
                format!(
                    "#{id}: {} knots after expansion, {n_expected} expected (control points + degree + 1)",
                    out.len()
                ),
            );
        }
        Ok(out)
    }

    fn degree(&self, a: &A<'x, 'a>, i: usize) -> R<usize> {
        let d = a.int(i)?;
        if !(0..=64).contains(&d) {
            return Err(a.wrong(format!("B-spline degree {d} out of range")));
        }
        Ok(d as usize)
    }

    pub(super) fn points(&mut self, a: &A<'x, 'a>, i: usize) -> R<Vec<DVec3>> {
        let refs = a.refs(i)?;
        refs.into_iter().map(|r| self.point(r)).collect()
    }

    pub(super) fn bspline_curve(&mut self, idx: usize) -> R<Curve> {
        // Simple: B_SPLINE_CURVE_WITH_KNOTS(name, degree, cps, form, closed, si, mults, knots, spec)
        // Complex: B_SPLINE_CURVE(degree, cps, form, closed, si)
        //          B_SPLINE_CURVE_WITH_KNOTS(mults, knots, spec)
        //          RATIONAL_B_SPLINE_CURVE(weights)
        let (base, base_off, knots, knots_off) = if self.head(idx) == "B_SPLINE_CURVE_WITH_KNOTS" {
            let a = self.args(idx);
            (a, 1, a, 6)
        } else {
            match (
                self.part_args(idx, "B_SPLINE_CURVE"),
                self.part_args(idx, "B_SPLINE_CURVE_WITH_KNOTS"),
            ) {
                (Some(b), Some(k)) => (b, 0, k, 0),
                _ => {
                    return Err(self.unsupported(idx, "B-spline curve without knots"));
                }
            }
        };
        let degree = self.degree(&base, base_off)?;
        let control_points = self.points(&base, base_off + 1)?;
        let n = control_points.len() + degree + 1;
        let knots = self.expand_knots(&knots, knots_off, knots_off + 1, n)?;
        let weights = match self.part_args(idx, "RATIONAL_B_SPLINE_CURVE") {
            Some(w) => {
                let l = w.list(0)?;
                let ws = l
                    .iter()
                    .map(|v| w.value_num(v, "weight"))
                    .collect::<R<Vec<f64>>>()?;
                if ws.len() != control_points.len() {
                    return Err(w.wrong(format!(
                        "{} weights for {} control points",
                        ws.len(),
                        control_points.len()
                    )));
                }
                ws
            }
            None => Vec::new(),
        };
        Ok(Curve::BSpline {
            degree,
            control_points,
            knots,
            weights,
        })
    }

    pub(super) fn bspline_surface(&mut self, idx: usize) -> R<Surface> {
        // Simple: (name, ud, vd, cps, form, uc, vc, si, umults, vmults, uknots, vknots, spec)
        let (base, bo, knots, ko) = if self.head(idx) == "B_SPLINE_SURFACE_WITH_KNOTS" {
            let a = self.args(idx);
            (a, 1, a, 8)
        } else {
            match (
                self.part_args(idx, "B_SPLINE_SURFACE"),
                self.part_args(idx, "B_SPLINE_SURFACE_WITH_KNOTS"),
            ) {
                (Some(b), Some(k)) => (b, 0, k, 0),
                _ => {
                    return Ok(Surface::Other {
                        kind: self.type_label(idx),
                    })
                }
            }
        };
        let u_degree = self.degree(&base, bo)?;
        let v_degree = self.degree(&base, bo + 1)?;
        let rows = base.list(bo + 2)?;
        let mut control_points = Vec::with_capacity(rows.len());
        let mut width = None;
        for row in rows {
            let l = match row {
                Value::List(l) => self.ex.list(*l),
                _ => return Err(base.wrong("control points: expected a list of lists")),
            };
            if *width.get_or_insert(l.len()) != l.len() {
                return Err(base.wrong("control point rows of different lengths"));
            }
            let mut pts = Vec::with_capacity(l.len());
            for v in l {
                let r = resolve_from(self.ex, idx, v)?;
                pts.push(self.point(r)?);
            }
            control_points.push(pts);
        }
        let nu = control_points.len();
        let nv = width.unwrap_or(0);
        let u_knots = self.expand_knots(&knots, ko, ko + 2, nu + u_degree + 1)?;
        let v_knots = self.expand_knots(&knots, ko + 1, ko + 3, nv + v_degree + 1)?;
        let weights = match self.part_args(idx, "RATIONAL_B_SPLINE_SURFACE") {
            Some(w) => {
                let mut out = Vec::new();
                for row in w.list(0)? {
                    let l = match row {
                        Value::List(l) => self.ex.list(*l),
                        _ => return Err(w.wrong("weights: expected a list of lists")),
                    };
                    let r = l
                        .iter()
                        .map(|v| w.value_num(v, "weight"))
                        .collect::<R<Vec<f64>>>()?;
                    if r.len() != nv {
                        return Err(w.wrong("weights do not match the control points"));
                    }
                    out.push(r);
                }
                if out.len() != nu {
                    return Err(w.wrong("weights do not match the control points"));
                }
                out
            }
            None => Vec::new(),
        };
        Ok(Surface::BSpline {
            u_degree,
            v_degree,
            control_points,
            u_knots,
            v_knots,
            weights,
        })
    }
}
