//! Evaluation of curves and surfaces: points, derivatives, normals and
//! closest-parameter projection (exact for analytic kinds, Newton for the
//! free-form ones).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::DVec3;

use crate::geom::{Curve, Surface};

/// A closed parameter interval `(start, end)`.
pub type Range = (f64, f64);

/// Maximum Newton iterations of the free-form projections.
const NEWTON_ITERS: usize = 30;

// ---------------------------------------------------------------------------
// B-spline basis (The NURBS Book, A2.1 and A2.3)
// ---------------------------------------------------------------------------

/// The knot span index of `u` for `n_ctrl` control points of degree `p`.
fn find_span(n_ctrl: usize, p: usize, u: f64, knots: &[f64]) -> usize {
    let n = n_ctrl - 1;
    if u >= knots[n + 1] {
        // Last non-empty span.
        let mut s = n;
        while s > p && knots[s] >= knots[s + 1] {
            s -= 1;
        }
        return s;
    }
    if u <= knots[p] {
        let mut s = p;
        while s < n && knots[s + 1] <= knots[s] {
            s += 1;
        }
        return s;
    }
    let (mut lo, mut hi) = (p, n + 1);
    let mut mid = (lo + hi) / 2;
    while u < knots[mid] || u >= knots[mid + 1] {
        if u < knots[mid] {
            hi = mid;
        } else {
            lo = mid;
        }
        mid = (lo + hi) / 2;
    }
    mid
}

/// Non-zero basis functions and their first derivatives at `u`:
/// returns `(values, first_derivatives)`, each of length `p + 1`.
fn basis_ders(span: usize, u: f64, p: usize, knots: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut ndu = vec![vec![0.0; p + 1]; p + 1];
    let mut left = vec![0.0; p + 1];
    let mut right = vec![0.0; p + 1];
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = if ndu[j][r] != 0.0 {
                ndu[r][j - 1] / ndu[j][r]
            } else {
                0.0
            };
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    let vals: Vec<f64> = (0..=p).map(|j| ndu[j][p]).collect();
    let mut ders = vec![0.0; p + 1];
    if p > 0 {
        for (r, d) in ders.iter_mut().enumerate() {
            let mut v = 0.0;
            if r >= 1 && ndu[p][r - 1] != 0.0 {
                v += ndu[r - 1][p - 1] / ndu[p][r - 1];
            }
            if r < p && ndu[p][r] != 0.0 {
                v -= ndu[r][p - 1] / ndu[p][r];
            }
            *d = v * p as f64;
        }
    }
    (vals, ders)
}

fn bspline_valid(degree: usize, n_ctrl: usize, knots: &[f64]) -> bool {
    n_ctrl > degree && knots.len() == n_ctrl + degree + 1
}

/// Point and first derivative of a (rational) B-spline curve.
fn bspline_curve_d1(
    degree: usize,
    ctrl: &[DVec3],
    knots: &[f64],
    weights: &[f64],
    t: f64,
) -> (DVec3, DVec3) {
    if !bspline_valid(degree, ctrl.len(), knots) {
        return (ctrl.first().copied().unwrap_or(DVec3::ZERO), DVec3::ZERO);
    }
    let rational = weights.len() == ctrl.len();
    let span = find_span(ctrl.len(), degree, t, knots);
    let (n, dn) = basis_ders(span, t, degree, knots);
    let (mut a, mut da, mut w, mut dw) = (DVec3::ZERO, DVec3::ZERO, 0.0, 0.0);
    for j in 0..=degree {
        let i = span - degree + j;
        let wi = if rational { weights[i] } else { 1.0 };
        a += ctrl[i] * (n[j] * wi);
        da += ctrl[i] * (dn[j] * wi);
        w += n[j] * wi;
        dw += dn[j] * wi;
    }
    if w.abs() < 1e-300 {
        return (a, da);
    }
    let c = a / w;
    (c, (da - c * dw) / w)
}

// ---------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------

/// Rodrigues rotation of vector `v` about unit `axis` by `angle`.
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

/// `a` shifted by a multiple of `period` to be as close as possible to `reference`.
pub fn unwrap_near(a: f64, reference: f64, period: f64) -> f64 {
    a + ((reference - a) / period).round() * period
}

fn clamp_opt(x: f64, dom: Option<(f64, f64)>) -> f64 {
    match dom {
        Some((a, b)) => x.clamp(a.min(b), a.max(b)),
        None => x,
    }
}

// ---------------------------------------------------------------------------
// Curves
// ---------------------------------------------------------------------------

impl Curve {
    /// The point at parameter `t`.
    pub fn point(&self, t: f64) -> DVec3 {
        self.point_d1(t).0
    }

    /// The first derivative with respect to the parameter at `t`.
    pub fn derivative(&self, t: f64) -> DVec3 {
        self.point_d1(t).1
    }

    /// The unit tangent (curve direction) at `t`; zero where undefined.
    pub fn tangent(&self, t: f64) -> DVec3 {
        self.derivative(t).normalize_or_zero()
    }

    /// Point and first derivative at `t`.
    pub fn point_d1(&self, t: f64) -> (DVec3, DVec3) {
        match self {
            Curve::Line { origin, dir } => (*origin + *dir * t, *dir),
            Curve::Circle { frame, radius } => {
                let (s, c) = t.sin_cos();
                (
                    frame.origin + (frame.x * c + frame.y * s) * *radius,
                    (frame.y * c - frame.x * s) * *radius,
                )
            }
            Curve::Ellipse {
                frame,
                semi_axis_1,
                semi_axis_2,
            } => {
                let (s, c) = t.sin_cos();
                (
                    frame.origin + frame.x * (semi_axis_1 * c) + frame.y * (semi_axis_2 * s),
                    frame.y * (semi_axis_2 * c) - frame.x * (semi_axis_1 * s),
                )
            }
            Curve::BSpline {
                degree,
                control_points,
                knots,
                weights,
            } => bspline_curve_d1(*degree, control_points, knots, weights, t),
            Curve::Polyline { points } => {
                if points.is_empty() {
                    return (DVec3::ZERO, DVec3::ZERO);
                }
                if points.len() == 1 {
                    return (points[0], DVec3::ZERO);
                }
                let last = (points.len() - 2) as f64;
                let tt = t.clamp(0.0, last + 1.0);
                let i = (tt.floor() as usize).min(points.len() - 2);
                let f = tt - i as f64;
                let d = points[i + 1] - points[i];
                (points[i] + d * f, d)
            }
        }
    }

    /// The period of a periodic parameterisation (circles and ellipses).
    pub fn period(&self) -> Option<f64> {
        match self {
            Curve::Circle { .. } | Curve::Ellipse { .. } => Some(TAU),
            _ => None,
        }
    }

    /// The parameter domain of bounded curves (`None` for lines).
    pub fn domain(&self) -> Option<(f64, f64)> {
        match self {
            Curve::Line { .. } => None,
            Curve::Circle { .. } | Curve::Ellipse { .. } => Some((0.0, TAU)),
            Curve::BSpline {
                degree,
                control_points,
                knots,
                ..
            } => {
                if bspline_valid(*degree, control_points.len(), knots) {
                    Some((knots[*degree], knots[control_points.len()]))
                } else {
                    Some((0.0, 0.0))
                }
            }
            Curve::Polyline { points } => Some((0.0, points.len().saturating_sub(1) as f64)),
        }
    }

    /// The parameter of the point of the curve closest to `p`. Exact for
    /// lines and circles, exact for points on an ellipse, sampled + Newton
    /// for B-splines, exact for polylines.
    pub fn project(&self, p: DVec3) -> f64 {
        match self {
            Curve::Line { origin, dir } => {
                (p - *origin).dot(*dir) / dir.length_squared().max(1e-300)
            }
            Curve::Circle { frame, .. } => {
                let l = frame.to_local(p);
                l.y.atan2(l.x)
            }
            Curve::Ellipse {
                frame,
                semi_axis_1,
                semi_axis_2,
            } => {
                let l = frame.to_local(p);
                let t0 = (l.y / semi_axis_2).atan2(l.x / semi_axis_1);
                self.newton_curve(p, t0, None)
            }
            Curve::BSpline { control_points, .. } => {
                let (a, b) = self.domain().unwrap_or((0.0, 1.0));
                let n = (control_points.len() * 4).clamp(16, 400);
                let mut best = (f64::INFINITY, a);
                for i in 0..=n {
                    let t = a + (b - a) * i as f64 / n as f64;
                    let d = self.point(t).distance_squared(p);
                    if d < best.0 {
                        best = (d, t);
                    }
                }
                self.newton_curve(p, best.1, Some((a, b)))
            }
            Curve::Polyline { points } => {
                let mut best = (f64::INFINITY, 0.0);
                for (i, w) in points.windows(2).enumerate() {
                    let d = w[1] - w[0];
                    let f = if d.length_squared() > 0.0 {
                        ((p - w[0]).dot(d) / d.length_squared()).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let dist = (w[0] + d * f).distance_squared(p);
                    if dist < best.0 {
                        best = (dist, i as f64 + f);
                    }
                }
                best.1
            }
        }
    }

    fn newton_curve(&self, p: DVec3, t0: f64, dom: Option<(f64, f64)>) -> f64 {
        let mut t = t0;
        for _ in 0..NEWTON_ITERS {
            let (c, d) = self.point_d1(t);
            // Second derivative by central difference (only for the step size).
            let h = 1e-6 * (1.0 + t.abs());
            let dd = (self.derivative(t + h) - self.derivative(t - h)) / (2.0 * h);
            let r = c - p;
            let f = r.dot(d);
            let fp = d.length_squared() + r.dot(dd);
            if fp.abs() < 1e-300 {
                break;
            }
            let step = f / if fp > 0.0 {
                fp
            } else {
                d.length_squared().max(1e-300)
            };
            let nt = clamp_opt(t - step, dom);
            if (nt - t).abs() < 1e-14 * (1.0 + t.abs()) {
                t = nt;
                break;
            }
            t = nt;
        }
        t
    }
}

// ---------------------------------------------------------------------------
// Surfaces
// ---------------------------------------------------------------------------

impl Surface {
    /// The point at parameters `(u, v)`.
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.point_d1(u, v).0
    }

    /// The unit surface normal at `(u, v)` by the surface convention (plane:
    /// `frame.z`; cylinder, cone, sphere, torus: away from the axis/centre;
    /// free-form: `Su × Sv`). Zero where undefined.
    pub fn normal(&self, u: f64, v: f64) -> DVec3 {
        match self {
            Surface::Plane { frame } => frame.z,
            Surface::Cylinder { frame, .. } => {
                let (s, c) = u.sin_cos();
                frame.x * c + frame.y * s
            }
            Surface::Cone {
                frame, semi_angle, ..
            } => {
                let (s, c) = u.sin_cos();
                let (sa, ca) = semi_angle.sin_cos();
                (frame.x * c + frame.y * s) * ca - frame.z * sa
            }
            Surface::Sphere { frame, .. } => {
                let (s, c) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                (frame.x * c + frame.y * s) * cv + frame.z * sv
            }
            Surface::Torus { frame, .. } => {
                let (s, c) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                (frame.x * c + frame.y * s) * cv + frame.z * sv
            }
            _ => {
                let (_, su, sv) = self.point_d1(u, v);
                su.cross(sv).normalize_or_zero()
            }
        }
    }

    /// Point and first partial derivatives `(S, Su, Sv)` at `(u, v)`.
    pub fn point_d1(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        match self {
            Surface::Plane { frame } => {
                (frame.origin + frame.x * u + frame.y * v, frame.x, frame.y)
            }
            Surface::Cylinder { frame, radius } => {
                let (s, c) = u.sin_cos();
                let radial = frame.x * c + frame.y * s;
                let tang = frame.y * c - frame.x * s;
                (
                    frame.origin + radial * *radius + frame.z * v,
                    tang * *radius,
                    frame.z,
                )
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                let (s, c) = u.sin_cos();
                let radial = frame.x * c + frame.y * s;
                let tang = frame.y * c - frame.x * s;
                let ta = semi_angle.tan();
                let rho = radius + v * ta;
                (
                    frame.origin + radial * rho + frame.z * v,
                    tang * rho,
                    radial * ta + frame.z,
                )
            }
            Surface::Sphere { frame, radius } => {
                let (s, c) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                let radial = frame.x * c + frame.y * s;
                let tang = frame.y * c - frame.x * s;
                (
                    frame.origin + (radial * cv + frame.z * sv) * *radius,
                    tang * (radius * cv),
                    (frame.z * cv - radial * sv) * *radius,
                )
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                let (s, c) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                let radial = frame.x * c + frame.y * s;
                let tang = frame.y * c - frame.x * s;
                let rho = major_radius + minor_radius * cv;
                (
                    frame.origin + radial * rho + frame.z * (minor_radius * sv),
                    tang * rho,
                    (frame.z * cv - radial * sv) * *minor_radius,
                )
            }
            Surface::BSpline {
                u_degree,
                v_degree,
                control_points,
                u_knots,
                v_knots,
                weights,
            } => bspline_surface_d1(
                *u_degree,
                *v_degree,
                control_points,
                u_knots,
                v_knots,
                weights,
                u,
                v,
            ),
            Surface::Extrusion { curve, dir } => {
                let (c, d) = curve.point_d1(u);
                (c + *dir * v, d, *dir)
            }
            Surface::Revolution {
                curve,
                axis_origin,
                axis_dir,
            } => {
                let axis = axis_dir.normalize_or_zero();
                let (c, d) = curve.point_d1(v);
                let q = rotate(c - *axis_origin, axis, u);
                (*axis_origin + q, axis.cross(q), rotate(d, axis, u))
            }
            Surface::Other { .. } => (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO),
        }
    }

    /// Periods in `u` and `v` of periodic parameterisations.
    pub fn periods(&self) -> (Option<f64>, Option<f64>) {
        match self {
            Surface::Cylinder { .. } | Surface::Cone { .. } | Surface::Sphere { .. } => {
                (Some(TAU), None)
            }
            Surface::Torus { .. } => (Some(TAU), Some(TAU)),
            Surface::Revolution { curve, .. } => (Some(TAU), curve.period()),
            Surface::Extrusion { curve, .. } => (curve.period(), None),
            _ => (None, None),
        }
    }

    /// Bounded parameter ranges (`None` where unbounded or periodic).
    pub fn domain(&self) -> (Option<Range>, Option<Range>) {
        match self {
            Surface::Sphere { .. } => (None, Some((-FRAC_PI_2, FRAC_PI_2))),
            Surface::BSpline {
                u_degree,
                v_degree,
                control_points,
                u_knots,
                v_knots,
                ..
            } => {
                let nu = control_points.len();
                let nv = control_points.first().map_or(0, |r| r.len());
                let du = (nu > *u_degree && u_knots.len() == nu + u_degree + 1)
                    .then(|| (u_knots[*u_degree], u_knots[nu]));
                let dv = (nv > *v_degree && v_knots.len() == nv + v_degree + 1)
                    .then(|| (v_knots[*v_degree], v_knots[nv]));
                (du, dv)
            }
            Surface::Extrusion { curve, .. } => match curve.period() {
                Some(_) => (None, None),
                None => (curve.domain(), None),
            },
            Surface::Revolution { curve, .. } => match curve.period() {
                Some(_) => (None, None),
                None => (None, curve.domain()),
            },
            _ => (None, None),
        }
    }

    /// Parameters `v` where the `u` parameter degenerates (sphere poles,
    /// cone apex), where a whole `u` range maps to one point.
    pub fn singular_v(&self) -> Vec<f64> {
        match self {
            Surface::Sphere { .. } => vec![-FRAC_PI_2, FRAC_PI_2],
            Surface::Cone {
                radius, semi_angle, ..
            } => {
                let t = semi_angle.tan();
                if t.abs() > 1e-12 {
                    vec![-radius / t]
                } else {
                    vec![]
                }
            }
            _ => vec![],
        }
    }

    /// Whether `(u, v)` lies on a degenerate line of the parameterisation
    /// (its `u` is then arbitrary).
    pub fn is_singular(&self, p: DVec3) -> bool {
        match self {
            Surface::Sphere { frame, radius } => {
                let l = frame.to_local(p);
                l.x.hypot(l.y) < 1e-9 * radius.max(1.0)
            }
            Surface::Cone { frame, radius, .. } => {
                let l = frame.to_local(p);
                l.x.hypot(l.y) < 1e-9 * radius.abs().max(1.0)
            }
            Surface::Revolution {
                axis_origin,
                axis_dir,
                ..
            } => {
                let a = axis_dir.normalize_or_zero();
                let d = p - *axis_origin;
                (d - a * d.dot(a)).length() < 1e-9
            }
            _ => false,
        }
    }

    /// The parameters of the surface point closest to `p`. Exact for planes,
    /// cylinders, cones, spheres and tori (with `u` in `(-π, π]`); sampled
    /// start + bounded Newton iterations for the other kinds.
    pub fn project(&self, p: DVec3) -> (f64, f64) {
        self.project_near(p, None)
    }

    /// As [`Surface::project`], starting free-form Newton iterations from
    /// `guess` when given (loops project point after point this way).
    pub fn project_near(&self, p: DVec3, guess: Option<(f64, f64)>) -> (f64, f64) {
        match self {
            Surface::Plane { frame } => {
                let l = frame.to_local(p);
                (l.x, l.y)
            }
            Surface::Cylinder { frame, .. } => {
                let l = frame.to_local(p);
                (l.y.atan2(l.x), l.z)
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                let l = frame.to_local(p);
                let r = l.x.hypot(l.y);
                let t = semi_angle.tan();
                let v = ((r - radius) * t + l.z) / (1.0 + t * t);
                (l.y.atan2(l.x), v)
            }
            Surface::Sphere { frame, .. } => {
                let l = frame.to_local(p);
                (l.y.atan2(l.x), l.z.atan2(l.x.hypot(l.y)))
            }
            Surface::Torus {
                frame,
                major_radius,
                ..
            } => {
                let l = frame.to_local(p);
                let rho = l.x.hypot(l.y);
                (l.y.atan2(l.x), l.z.atan2(rho - major_radius))
            }
            Surface::Other { .. } => (0.0, 0.0),
            Surface::BSpline { .. } => {
                let start = match guess {
                    Some(g) => {
                        let r = self.newton_surface(p, g);
                        // Accept the warm start only if it landed on a true
                        // local minimum close to the previous parameters.
                        if self.point(r.0, r.1).distance(p) < 1e-6 * (1.0 + p.length()) {
                            return r;
                        }
                        self.grid_start(p)
                    }
                    None => self.grid_start(p),
                };
                self.newton_surface(p, start)
            }
            Surface::Extrusion { curve, dir } => {
                let dd = dir.length_squared().max(1e-300);
                let mut u = match guess {
                    Some(g) => g.0,
                    None => curve.project(p),
                };
                let mut v = 0.0;
                for _ in 0..4 {
                    v = (p - curve.point(u)).dot(*dir) / dd;
                    u = curve.project(p - *dir * v);
                }
                self.newton_surface(p, (u, v))
            }
            Surface::Revolution {
                curve,
                axis_origin,
                axis_dir,
            } => {
                let axis = axis_dir.normalize_or_zero();
                let angle_of = |q: DVec3| -> f64 {
                    let d = q - *axis_origin;
                    let r = d - axis * d.dot(axis);
                    // Angle measured in a frame fixed to the axis.
                    let f = crate::geom::Frame::from_axis_ref(*axis_origin, axis, None);
                    r.dot(f.y).atan2(r.dot(f.x))
                };
                let ap = angle_of(p);
                let mut v = match guess {
                    Some(g) => g.1,
                    None => curve.project(p),
                };
                let mut u = 0.0;
                for _ in 0..4 {
                    let c = curve.point(v);
                    u = ap - angle_of(c);
                    // Rotate p back into the half-plane of the curve point.
                    let q = *axis_origin + rotate(p - *axis_origin, axis, -u);
                    v = curve.project(q);
                }
                if let Some(g) = guess {
                    u = unwrap_near(u, g.0, TAU);
                }
                self.newton_surface(p, (u, v))
            }
        }
    }

    fn grid_start(&self, p: DVec3) -> (f64, f64) {
        let (du, dv) = self.domain();
        let (ua, ub) = du.unwrap_or((0.0, 1.0));
        let (va, vb) = dv.unwrap_or((0.0, 1.0));
        let n = match self {
            Surface::BSpline { control_points, .. } => {
                let nu = control_points.len();
                let nv = control_points.first().map_or(1, |r| r.len());
                ((nu.max(nv)) * 3).clamp(8, 40)
            }
            _ => 16,
        };
        let mut best = (f64::INFINITY, (ua, va));
        for i in 0..=n {
            let u = ua + (ub - ua) * i as f64 / n as f64;
            for j in 0..=n {
                let v = va + (vb - va) * j as f64 / n as f64;
                let d = self.point(u, v).distance_squared(p);
                if d < best.0 {
                    best = (d, (u, v));
                }
            }
        }
        best.1
    }

    /// Gauss-Newton minimisation of |S(u,v) - p|² with bounded iterations,
    /// clamped to the bounded parameter ranges.
    fn newton_surface(&self, p: DVec3, start: (f64, f64)) -> (f64, f64) {
        let (du, dv) = self.domain();
        let (mut u, mut v) = start;
        for _ in 0..NEWTON_ITERS {
            let (s, su, sv) = self.point_d1(u, v);
            let r = p - s;
            let a11 = su.dot(su);
            let a12 = su.dot(sv);
            let a22 = sv.dot(sv);
            let b1 = su.dot(r);
            let b2 = sv.dot(r);
            let det = a11 * a22 - a12 * a12;
            if det.abs() < 1e-300 {
                break;
            }
            let du_ = (b1 * a22 - b2 * a12) / det;
            let dv_ = (a11 * b2 - a12 * b1) / det;
            let nu = clamp_opt(u + du_, du);
            let nv = clamp_opt(v + dv_, dv);
            let moved = (nu - u).abs() + (nv - v).abs();
            u = nu;
            v = nv;
            if moved < 1e-14 * (1.0 + u.abs() + v.abs()) {
                break;
            }
        }
        (u, v)
    }
}

#[allow(clippy::too_many_arguments)]
fn bspline_surface_d1(
    pu: usize,
    pv: usize,
    ctrl: &[Vec<DVec3>],
    uk: &[f64],
    vk: &[f64],
    weights: &[Vec<f64>],
    u: f64,
    v: f64,
) -> (DVec3, DVec3, DVec3) {
    let nu = ctrl.len();
    let nv = ctrl.first().map_or(0, |r| r.len());
    if !bspline_valid(pu, nu, uk) || !bspline_valid(pv, nv, vk) {
        let p = ctrl
            .first()
            .and_then(|r| r.first())
            .copied()
            .unwrap_or(DVec3::ZERO);
        return (p, DVec3::ZERO, DVec3::ZERO);
    }
    let rational = weights.len() == nu && weights.iter().all(|r| r.len() == nv);
    let su = find_span(nu, pu, u, uk);
    let sv = find_span(nv, pv, v, vk);
    let (nu_, dnu) = basis_ders(su, u, pu, uk);
    let (nv_, dnv) = basis_ders(sv, v, pv, vk);
    let (mut a, mut au, mut av) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    let (mut w, mut wu, mut wv) = (0.0, 0.0, 0.0);
    for i in 0..=pu {
        let ii = su - pu + i;
        for j in 0..=pv {
            let jj = sv - pv + j;
            let wij = if rational { weights[ii][jj] } else { 1.0 };
            let p = ctrl[ii][jj] * wij;
            a += p * (nu_[i] * nv_[j]);
            au += p * (dnu[i] * nv_[j]);
            av += p * (nu_[i] * dnv[j]);
            w += wij * nu_[i] * nv_[j];
            wu += wij * dnu[i] * nv_[j];
            wv += wij * nu_[i] * dnv[j];
        }
    }
    if w.abs() < 1e-300 {
        return (a, au, av);
    }
    let s = a / w;
    (s, (au - s * wu) / w, (av - s * wv) / w)
}

/// Wraps an angle into `(-π, π]`.
pub fn wrap_pi(a: f64) -> f64 {
    let mut x = a % TAU;
    if x <= -PI {
        x += TAU;
    } else if x > PI {
        x -= TAU;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Frame;

    fn close(a: DVec3, b: DVec3) -> bool {
        a.distance(b) < 1e-9
    }

    #[test]
    fn circle_and_line() {
        let c = Curve::Circle {
            frame: Frame::WORLD,
            radius: 2.0,
        };
        assert!(close(c.point(FRAC_PI_2), DVec3::new(0.0, 2.0, 0.0)));
        assert!(close(c.tangent(0.0), DVec3::Y));
        assert!((c.project(DVec3::new(-3.0, 0.0, 5.0)) - PI).abs() < 1e-12);
        let l = Curve::Line {
            origin: DVec3::ONE,
            dir: DVec3::X,
        };
        assert!((l.project(DVec3::new(4.0, 0.0, 0.0)) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn bspline_curve_matches_quarter_circle() {
        // Rational quadratic quarter circle.
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let c = Curve::BSpline {
            degree: 2,
            control_points: vec![DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            weights: vec![1.0, w, 1.0],
        };
        for i in 0..=10 {
            let t = i as f64 / 10.0;
            assert!((c.point(t).length() - 1.0).abs() < 1e-12);
            // Derivative agrees with finite differences.
            let h = 1e-6;
            let fd = (c.point((t + h).min(1.0)) - c.point((t - h).max(0.0)))
                / ((t + h).min(1.0) - (t - h).max(0.0));
            assert!(c.derivative(t).distance(fd) < 1e-5);
        }
        let p = DVec3::new(0.6, 0.8, 0.0) * 3.0;
        let t = c.project(p);
        assert!(c.point(t).distance(DVec3::new(0.6, 0.8, 0.0)) < 1e-9);
    }

    #[test]
    fn analytic_surfaces_roundtrip() {
        let f = Frame::from_axis_ref(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(0.2, 0.3, 1.0),
            Some(DVec3::X),
        );
        let surfaces = [
            Surface::Plane { frame: f },
            Surface::Cylinder {
                frame: f,
                radius: 3.0,
            },
            Surface::Cone {
                frame: f,
                radius: 3.0,
                semi_angle: 0.3,
            },
            Surface::Sphere {
                frame: f,
                radius: 3.0,
            },
            Surface::Torus {
                frame: f,
                major_radius: 5.0,
                minor_radius: 1.5,
            },
        ];
        for s in &surfaces {
            for &(u, v) in &[(0.3, 0.4), (-2.0, 1.2), (2.9, -0.7)] {
                let p = s.point(u, v);
                let (pu, pv) = s.project(p);
                assert!(s.point(pu, pv).distance(p) < 1e-9, "{s:?}");
                // Projection of an offset point along the normal comes back.
                let n = s.normal(u, v);
                let (qu, qv) = s.project(p + n * 0.5);
                assert!(s.point(qu, qv).distance(p) < 1e-9, "{s:?} off");
                // The normal agrees with Su x Sv.
                let (_, su, sv) = s.point_d1(u, v);
                assert!(su.cross(sv).normalize().distance(n) < 1e-9, "{s:?} n");
            }
        }
    }

    #[test]
    fn bspline_surface_projection() {
        // A bilinear patch lifted to degree 2 in u with a bump.
        let ctrl = vec![
            vec![DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 10.0, 0.0)],
            vec![DVec3::new(5.0, 0.0, 3.0), DVec3::new(5.0, 10.0, 3.0)],
            vec![DVec3::new(10.0, 0.0, 0.0), DVec3::new(10.0, 10.0, 0.0)],
        ];
        let s = Surface::BSpline {
            u_degree: 2,
            v_degree: 1,
            control_points: ctrl,
            u_knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            v_knots: vec![0.0, 0.0, 1.0, 1.0],
            weights: vec![],
        };
        let p = s.point(0.37, 0.61);
        let (u, v) = s.project(p + s.normal(0.37, 0.61) * 0.2);
        assert!((u - 0.37).abs() < 1e-8 && (v - 0.61).abs() < 1e-8);
        // Extrusion and revolution evaluate through their curves.
        let e = Surface::Extrusion {
            curve: Box::new(Curve::Circle {
                frame: Frame::WORLD,
                radius: 2.0,
            }),
            dir: DVec3::Z,
        };
        let q = e.point(1.0, 4.0);
        let (u, v) = e.project(q);
        assert!(e.point(u, v).distance(q) < 1e-9);
        let r = Surface::Revolution {
            curve: Box::new(Curve::Line {
                origin: DVec3::new(3.0, 0.0, 0.0),
                dir: DVec3::Z,
            }),
            axis_origin: DVec3::ZERO,
            axis_dir: DVec3::Z,
        };
        let q = r.point(2.0, 5.0);
        assert!((q - DVec3::new(3.0 * 2f64.cos(), 3.0 * 2f64.sin(), 5.0)).length() < 1e-9);
        let (u, v) = r.project(q);
        assert!(r.point(u, v).distance(q) < 1e-9);
    }
}
