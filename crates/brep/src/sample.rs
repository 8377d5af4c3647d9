//! Sampling edges and loops into polylines within a chord tolerance.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::geom::Curve;
use crate::tess::TessTolerance;
use crate::{Brep, Coedge, EdgeId, LoopId};

/// Number of segments so that an arc of `sweep` radians on radius `r`
/// stays within the chord and angle tolerances.
pub fn arc_segments(r: f64, sweep: f64, tol: &TessTolerance) -> usize {
    let sweep = sweep.abs();
    if sweep == 0.0 {
        return 1;
    }
    let chord_step = if r > tol.chord {
        2.0 * (1.0 - tol.chord / r).clamp(-1.0, 1.0).acos()
    } else {
        std::f64::consts::PI
    };
    let step = chord_step.min(tol.angle.max(1e-3)).max(1e-4);
    ((sweep / step).ceil() as usize).clamp(1, 100_000)
}

impl Brep {
    /// The parameters `(t_start, t_end)` of an edge on its curve: the edge
    /// runs from `t_start` to `t_end` (decreasing when the edge runs against
    /// the curve). For circles and ellipses the range is found from the
    /// vertex angles going in the curve direction (or against it when
    /// `same_sense` is false); a closed edge spans a full period.
    pub fn edge_param_range(&self, e: EdgeId) -> (f64, f64) {
        let edge = &self.edges[e];
        let ps = self.vertices[edge.start].point;
        let pe = self.vertices[edge.end].point;
        let curve = &edge.curve;
        let closed = edge.is_closed() || ps.distance(pe) < 1e-12 * (1.0 + ps.length());
        match curve {
            Curve::Circle { .. } | Curve::Ellipse { .. } => {
                let a = curve.project(ps);
                let b = curve.project(pe);
                let eps = 1e-12;
                if edge.same_sense {
                    let mut b = b;
                    if closed {
                        b = a + TAU;
                    } else {
                        while b <= a + eps {
                            b += TAU;
                        }
                        while b > a + TAU {
                            b -= TAU;
                        }
                    }
                    (a, b)
                } else {
                    let mut b = b;
                    if closed {
                        b = a - TAU;
                    } else {
                        while b >= a - eps {
                            b -= TAU;
                        }
                        while b < a - TAU {
                            b += TAU;
                        }
                    }
                    (a, b)
                }
            }
            Curve::BSpline { .. } | Curve::Polyline { .. } if closed => {
                let (a, b) = curve.domain().unwrap_or((0.0, 1.0));
                if edge.same_sense {
                    (a, b)
                } else {
                    (b, a)
                }
            }
            _ => (curve.project(ps), curve.project(pe)),
        }
    }

    /// The edge as a polyline from its start vertex to its end vertex
    /// (a closed edge returns its start point at both ends), within `tol`.
    pub fn edge_polyline(&self, e: EdgeId, tol: &TessTolerance) -> Vec<DVec3> {
        let edge = &self.edges[e];
        let ps = self.vertices[edge.start].point;
        let pe = self.vertices[edge.end].point;
        let (a, b) = self.edge_param_range(e);
        let mut pts = match &edge.curve {
            Curve::Line { .. } => vec![ps, pe],
            Curve::Circle { radius, .. } => {
                let n = arc_segments(*radius, b - a, tol).max(if edge.is_closed() { 3 } else { 1 });
                (0..=n)
                    .map(|i| edge.curve.point(a + (b - a) * i as f64 / n as f64))
                    .collect()
            }
            Curve::Ellipse {
                semi_axis_1,
                semi_axis_2,
                ..
            } => {
                // Chord error of a parametric step dt is at most dt²/8 max|C''|.
                let big = semi_axis_1.abs().max(semi_axis_2.abs());
                let small = semi_axis_1.abs().min(semi_axis_2.abs()).max(1e-9);
                let dt_chord = (8.0 * tol.chord / big.max(1e-9)).sqrt();
                // Tangent turns by at most dt * big/small per parameter step.
                let dt_angle = tol.angle * small / big;
                let step = dt_chord.min(dt_angle).max(1e-4);
                let n = (((b - a).abs() / step).ceil() as usize)
                    .clamp(if edge.is_closed() { 3 } else { 1 }, 100_000);
                (0..=n)
                    .map(|i| edge.curve.point(a + (b - a) * i as f64 / n as f64))
                    .collect()
            }
            Curve::BSpline { .. } => sample_adaptive(&edge.curve, a, b, tol),
            Curve::Polyline { points } => {
                let mut v = vec![edge.curve.point(a)];
                if a <= b {
                    for (i, p) in points.iter().enumerate() {
                        if (i as f64) > a && (i as f64) < b {
                            v.push(*p);
                        }
                    }
                } else {
                    for (i, p) in points.iter().enumerate().rev() {
                        if (i as f64) < a && (i as f64) > b {
                            v.push(*p);
                        }
                    }
                }
                v.push(edge.curve.point(b));
                v
            }
        };
        // Snap the ends onto the vertices so that neighbouring faces share them.
        if let Some(f) = pts.first_mut() {
            *f = ps;
        }
        if let Some(l) = pts.last_mut() {
            *l = pe;
        }
        if pts.len() < 2 {
            pts = vec![ps, pe];
        }
        pts
    }

    /// The polyline of a coedge in loop direction.
    pub fn coedge_polyline(&self, ce: Coedge, tol: &TessTolerance) -> Vec<DVec3> {
        let mut p = self.edge_polyline(ce.edge, tol);
        if !ce.forward {
            p.reverse();
        }
        p
    }

    /// The closed polyline of a loop in its traversal direction (with
    /// `Loop.orientation` applied), without repeating the first point at the
    /// end. A vertex loop gives its single point.
    pub fn loop_polyline(&self, l: LoopId, tol: &TessTolerance) -> Vec<DVec3> {
        let lp = &self.loops[l];
        if lp.coedges.is_empty() {
            return lp
                .vertex
                .map(|v| vec![self.vertices[v].point])
                .unwrap_or_default();
        }
        let mut out: Vec<DVec3> = Vec::new();
        for ce in &lp.coedges {
            let poly = self.coedge_polyline(*ce, tol);
            for p in poly {
                if out.last().is_none_or(|q| q.distance_squared(p) > 1e-24) {
                    out.push(p);
                }
            }
        }
        while out.len() > 1 && out[0].distance_squared(*out.last().unwrap()) <= 1e-24 {
            out.pop();
        }
        if !lp.orientation {
            out.reverse();
        }
        out
    }
}

/// Adaptive sampling of a curve between parameters `a` and `b`: starts from
/// a few samples per unit of parameter span and bisects where the midpoint
/// leaves the chord by more than the tolerance or the tangent turns too much.
fn sample_adaptive(c: &Curve, a: f64, b: f64, tol: &TessTolerance) -> Vec<DVec3> {
    // Initial subdivision: at the knots inside the range, each span in 4.
    let mut ts = vec![a];
    if let Curve::BSpline { degree, knots, .. } = c {
        let (lo, hi) = (a.min(b), a.max(b));
        let mut inner: Vec<f64> = knots
            .iter()
            .copied()
            .filter(|k| *k > lo && *k < hi)
            .collect();
        inner.dedup();
        if a > b {
            inner.reverse();
        }
        let per = (*degree).max(1) + 1;
        let mut prev = a;
        for k in inner.into_iter().chain(std::iter::once(b)) {
            for i in 1..=per {
                ts.push(prev + (k - prev) * i as f64 / per as f64);
            }
            prev = k;
        }
    } else {
        for i in 1..=8 {
            ts.push(a + (b - a) * i as f64 / 8.0);
        }
    }
    let mut out = vec![c.point(a)];
    for w in ts.windows(2) {
        refine(
            c,
            w[0],
            w[1],
            c.point(w[0]),
            c.point(w[1]),
            tol,
            0,
            &mut out,
        );
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn refine(
    c: &Curve,
    t0: f64,
    t1: f64,
    p0: DVec3,
    p1: DVec3,
    tol: &TessTolerance,
    depth: u32,
    out: &mut Vec<DVec3>,
) {
    if t0 == t1 {
        return;
    }
    let tm = 0.5 * (t0 + t1);
    let pm = c.point(tm);
    let dev = pm.distance(0.5 * (p0 + p1));
    let ta = c.tangent(t0);
    let tb = c.tangent(t1);
    let turn = ta.dot(tb).clamp(-1.0, 1.0).acos();
    if depth < 16 && (dev > tol.chord * 0.5 || turn > tol.angle) {
        refine(c, t0, tm, p0, pm, tol, depth + 1, out);
        refine(c, tm, t1, pm, p1, tol, depth + 1, out);
    } else {
        out.push(p1);
    }
}
