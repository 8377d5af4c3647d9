//! Face tessellation: loops are sampled in 3D, mapped to the surface's
//! parameter space (unwrapping periodic parameters and closing seam-less
//! bands across the seam), triangulated there by a constrained Delaunay
//! triangulation (`spade`), kept inside by even-odd parity over the loop
//! constraints (never by the `outer` flag), refined until the chord and angle
//! tolerances hold on curved surfaces, and mapped back to 3D.

use std::collections::VecDeque;
use std::fmt;

use glam::{DVec2, DVec3};
use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, HasPosition, Point2, Triangulation};

use crate::eval::unwrap_near;
use crate::geom::Surface;
use crate::{Aabb, Brep, FaceId};

/// Tessellation tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TessTolerance {
    /// Maximum distance between the mesh and the true surface/edges, mm.
    pub chord: f64,
    /// Maximum turn of the normal/tangent across one triangle/segment, rad.
    pub angle: f64,
}

impl Default for TessTolerance {
    fn default() -> Self {
        TessTolerance {
            chord: 0.01,
            angle: 0.2,
        }
    }
}

impl TessTolerance {
    /// A tolerance relative to a part size (bounding-box diagonal): the chord
    /// is `rel * diagonal`, clamped to a sane millimetre range.
    pub fn relative(diagonal: f64, rel: f64) -> Self {
        TessTolerance {
            chord: (diagonal * rel).clamp(1e-5, 1.0),
            angle: 0.2,
        }
    }
}

/// Why a face could not be tessellated.
#[derive(Debug, Clone, PartialEq)]
pub enum TessError {
    /// The surface kind cannot be evaluated (`Surface::Other`).
    Unsupported(String),
    /// The face has no usable loop and its surface is not closed.
    NoLoops,
    /// The loops do not bound a region in parameter space.
    BadLoops(String),
    /// The triangulator refused the input.
    Triangulation(String),
}

impl fmt::Display for TessError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TessError::Unsupported(k) => write!(f, "unsupported surface kind {k}"),
            TessError::NoLoops => write!(f, "face has no usable loops"),
            TessError::BadLoops(m) => write!(f, "bad loops: {m}"),
            TessError::Triangulation(m) => write!(f, "triangulation failed: {m}"),
        }
    }
}

impl std::error::Error for TessError {}

/// A triangle mesh of faces; triangles are counter-clockwise seen from
/// outside (along the face's outward normal, `Face.same_sense` applied).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    /// Unit outward normals of the faces at the positions.
    pub normals: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    pub face_of_triangle: Vec<FaceId>,
    /// Faces that could not be tessellated, with the reason (only filled by
    /// [`tessellate`]).
    pub failed_faces: Vec<(FaceId, TessError)>,
}

impl Mesh {
    /// Appends another mesh (indices shifted).
    pub fn append(&mut self, other: &Mesh) {
        let off = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
        );
        self.face_of_triangle
            .extend_from_slice(&other.face_of_triangle);
        self.failed_faces.extend(other.failed_faces.iter().cloned());
    }

    fn tri(&self, t: &[u32; 3]) -> [DVec3; 3] {
        [
            self.positions[t[0] as usize],
            self.positions[t[1] as usize],
            self.positions[t[2] as usize],
        ]
    }

    /// Total triangle area.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.tri(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Signed volume enclosed (divergence theorem), over the triangles whose
    /// face passes `keep`. Positive for closed outward-oriented meshes.
    pub fn signed_volume_where(&self, keep: impl Fn(FaceId) -> bool) -> f64 {
        // Relative to a reference point near the mesh to limit cancellation.
        let r = self.positions.first().copied().unwrap_or(DVec3::ZERO);
        self.triangles
            .iter()
            .zip(&self.face_of_triangle)
            .filter(|(_, f)| keep(**f))
            .map(|(t, _)| {
                let [a, b, c] = self.tri(t);
                (a - r).dot((b - r).cross(c - r)) / 6.0
            })
            .sum()
    }

    /// Signed volume enclosed by all triangles.
    pub fn signed_volume(&self) -> f64 {
        self.signed_volume_where(|_| true)
    }

    /// Axis-aligned box of the positions.
    pub fn bbox(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in &self.positions {
            b.include(*p);
        }
        b
    }
}

/// Tessellates every face; faces that fail are skipped and listed in
/// [`Mesh::failed_faces`].
pub fn tessellate(brep: &Brep, tol: &TessTolerance) -> Mesh {
    let mut mesh = Mesh::default();
    for f in 0..brep.faces.len() {
        match tessellate_face(brep, f, tol) {
            Ok(m) => mesh.append(&m),
            Err(e) => mesh.failed_faces.push((f, e)),
        }
    }
    mesh
}

/// A loop point: working parameters and its exact 3D position.
#[derive(Debug, Clone, Copy)]
struct Rp {
    uv: DVec2,
    p: DVec3,
}

/// Vertex stored in the triangulation: scaled parameter position, real
/// parameters and 3D point.
#[derive(Debug, Clone, Copy)]
struct Tv {
    pos: Point2<f64>,
    uv: DVec2,
    p: DVec3,
}

impl HasPosition for Tv {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

type Cdt = ConstrainedDelaunayTriangulation<Tv>;

const MAX_REFINE_ITERS: usize = 14;
const MAX_VERTICES: usize = 400_000;

/// Tessellates one face into a mesh with outward, counter-clockwise triangles.
pub fn tessellate_face(brep: &Brep, face: FaceId, tol: &TessTolerance) -> Result<Mesh, TessError> {
    let f = brep
        .faces
        .get(face)
        .ok_or_else(|| TessError::BadLoops(format!("no face {face}")))?;
    let surf = &f.surface;
    if let Surface::Other { kind } = surf {
        return Err(TessError::Unsupported(kind.clone()));
    }
    let loops3: Vec<Vec<DVec3>> = f
        .loops
        .iter()
        .map(|&l| brep.loop_polyline(l, tol))
        .collect();
    let mut rings = param_rings(surf, f.same_sense, &loops3)?;
    if !matches!(surf, Surface::Plane { .. }) {
        for r in rings.iter_mut() {
            densify(surf, r, tol);
        }
    }
    triangulate(surf, f.same_sense, &rings, tol, face)
}

/// Maps loops to closed rings in parameter space that bound the face region
/// by even-odd parity.
fn param_rings(
    surf: &Surface,
    sense: bool,
    loops3: &[Vec<DVec3>],
) -> Result<Vec<Vec<Rp>>, TessError> {
    let (pu, pv) = surf.periods();
    let mut ordinary: Vec<Vec<Rp>> = Vec::new();
    let mut ubands: Vec<(Vec<Rp>, i64)> = Vec::new();
    let mut vbands: Vec<(Vec<Rp>, i64)> = Vec::new();
    for pts in loops3 {
        if pts.len() < 3 {
            // Vertex loops (cone apex) and degenerate loops add no boundary:
            // apexes are closed through the singular parameter line below.
            continue;
        }
        let (ring, ku, kv) = map_loop(surf, pts, pu, pv);
        match (ku, kv) {
            (0, 0) => ordinary.push(ring),
            (k, 0) => ubands.push((ring, k)),
            (0, k) => vbands.push((ring, k)),
            _ => {
                return Err(TessError::BadLoops(
                    "a loop winds around both periodic directions".into(),
                ))
            }
        }
    }

    if ordinary.is_empty() && ubands.is_empty() && vbands.is_empty() {
        // A closed surface without bounds: the whole sphere or torus.
        return match surf {
            Surface::Sphere { .. } => Ok(vec![full_rect(
                surf,
                (0.0, std::f64::consts::TAU),
                (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2),
            )]),
            Surface::Torus { .. } => Ok(vec![full_rect(
                surf,
                (0.0, std::f64::consts::TAU),
                (0.0, std::f64::consts::TAU),
            )]),
            _ => Err(TessError::NoLoops),
        };
    }

    // A loop that collapses onto a seam (a sphere bounded only by its seam
    // edge) is the full period between its parameter extremes.
    if let (Some(pu), true) = (pu, ubands.is_empty() && vbands.is_empty()) {
        for r in ordinary.iter_mut() {
            let (lo, hi) = extent(r);
            if (hi.x - lo.x) < 1e-9 && hi.y > lo.y {
                *r = full_rect(surf, (lo.x, lo.x + pu), (lo.y, hi.y));
            }
        }
    }

    let swapped = ubands.is_empty() && !vbands.is_empty();
    if !ubands.is_empty() && !vbands.is_empty() {
        return Err(TessError::BadLoops(
            "loops wind around both periodic directions".into(),
        ));
    }
    let (mut bands, per_cut, per_other) = if swapped {
        let sw = |r: &mut Vec<Rp>| r.iter_mut().for_each(|q| q.uv = DVec2::new(q.uv.y, q.uv.x));
        ordinary.iter_mut().for_each(sw);
        let mut vb = vbands;
        vb.iter_mut().for_each(|(r, _)| sw(r));
        (vb, pv, pu)
    } else {
        (ubands, pu, pv)
    };

    // Bring the rings together along the non-cut periodic direction (and
    // along the cut direction when there is no band): nearest to the ring of
    // largest extent.
    {
        let no_bands = bands.is_empty();
        let mut all: Vec<&mut Vec<Rp>> = ordinary
            .iter_mut()
            .chain(bands.iter_mut().map(|(r, _)| r))
            .collect();
        let reference = all
            .iter()
            .enumerate()
            .max_by(|a, b| {
                let ea = extent(a.1);
                let eb = extent(b.1);
                let sa = (ea.1 - ea.0).length();
                let sb = (eb.1 - eb.0).length();
                sa.total_cmp(&sb)
            })
            .map(|(i, _)| i)
            .unwrap_or(0);
        let refc = centre(all[reference]);
        for r in all.iter_mut() {
            let c = centre(r);
            let mut shift = DVec2::ZERO;
            if let Some(p) = per_other {
                shift.y = unwrap_near(c.y, refc.y, p) - c.y;
            }
            if no_bands {
                if let Some(p) = per_cut {
                    shift.x = unwrap_near(c.x, refc.x, p) - c.x;
                }
            }
            if shift != DVec2::ZERO {
                r.iter_mut().for_each(|q| q.uv += shift);
            }
        }
    }

    let mut rings = ordinary;
    if !bands.is_empty() {
        let period = per_cut.unwrap_or(std::f64::consts::TAU);
        let uc = choose_cut(&rings, period);
        for r in rings.iter_mut() {
            let (lo, _) = extent(r);
            let k = ((lo.x - uc) / period).floor();
            if k != 0.0 {
                r.iter_mut().for_each(|q| q.uv.x -= k * period);
            }
        }
        // Cut every band at uc, running from uc to uc + period.
        let mut cut: Vec<(Vec<Rp>, i64)> = bands
            .drain(..)
            .map(|(r, k)| (cut_band(surf, swapped, r, k, uc, period), k))
            .collect();
        cut.sort_by(|a, b| mean_v(&a.0).total_cmp(&mean_v(&b.0)));
        // Param orientation: CCW in (u, v) is along the surface normal.
        let s = (if sense { 1 } else { -1 }) * (if swapped { -1 } else { 1 });
        if cut.len() % 2 == 1 {
            // One band is closed through a singular line (pole, apex). The
            // face lies left of a loop's original direction: above it in v
            // when its winding agrees with the parameter orientation.
            if swapped {
                return Err(TessError::BadLoops("an unpaired band loop".into()));
            }
            let last = cut.len() - 1;
            let up = cut[last].1 * s > 0;
            let (band, _) = cut.remove(if up { last } else { 0 });
            let v0 = mean_v(&band);
            let pole = surf
                .singular_v()
                .into_iter()
                .filter(|&v| if up { v > v0 } else { v < v0 })
                .min_by(|a, b| (a - v0).abs().total_cmp(&(b - v0).abs()))
                .ok_or_else(|| {
                    TessError::BadLoops(
                        "an unpaired band loop with no singular line to close it".into(),
                    )
                })?;
            rings.push(close_to_pole(surf, band, pole));
        }
        let mut i = 0;
        while i + 1 < cut.len() {
            let mut ring = cut[i].0.clone();
            ring.extend(cut[i + 1].0.iter().rev().copied());
            rings.push(ring);
            i += 2;
        }
    }

    if swapped {
        for r in rings.iter_mut() {
            r.iter_mut().for_each(|q| q.uv = DVec2::new(q.uv.y, q.uv.x));
        }
    }
    // Drop consecutive duplicates.
    for r in rings.iter_mut() {
        r.dedup_by(|a, b| a.uv.distance_squared(b.uv) < 1e-28);
        while r.len() > 1 && r[0].uv.distance_squared(r[r.len() - 1].uv) < 1e-28 {
            r.pop();
        }
    }
    rings.retain(|r| r.len() >= 3);
    if rings.is_empty() {
        return Err(TessError::BadLoops("no ring with area".into()));
    }
    Ok(rings)
}

fn extent(r: &[Rp]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for q in r {
        lo = lo.min(q.uv);
        hi = hi.max(q.uv);
    }
    (lo, hi)
}

fn centre(r: &[Rp]) -> DVec2 {
    let (lo, hi) = extent(r);
    0.5 * (lo + hi)
}

fn mean_v(r: &[Rp]) -> f64 {
    r.iter().map(|q| q.uv.y).sum::<f64>() / r.len().max(1) as f64
}

/// A rectangle in parameter space sampled along its sides.
fn full_rect(surf: &Surface, (u0, u1): (f64, f64), (v0, v1): (f64, f64)) -> Vec<Rp> {
    let n = 16;
    let mut out = Vec::with_capacity(4 * n);
    let corners = [
        DVec2::new(u0, v0),
        DVec2::new(u1, v0),
        DVec2::new(u1, v1),
        DVec2::new(u0, v1),
    ];
    for k in 0..4 {
        let a = corners[k];
        let b = corners[(k + 1) % 4];
        for i in 0..n {
            let uv = a.lerp(b, i as f64 / n as f64);
            out.push(Rp {
                uv,
                p: surf.point(uv.x, uv.y),
            });
        }
    }
    out
}

/// Projects a loop, unwraps periodic parameters along it, and opens
/// singular points (poles, apexes) into segments along the singular line.
/// Returns the ring and its winding numbers in u and v.
fn map_loop(
    surf: &Surface,
    pts: &[DVec3],
    pu: Option<f64>,
    pv: Option<f64>,
) -> (Vec<Rp>, i64, i64) {
    let n = pts.len();
    let mut uv = Vec::with_capacity(n);
    let mut sing = Vec::with_capacity(n);
    let mut guess = None;
    for &p in pts {
        let (u, v) = surf.project_near(p, guess);
        guess = Some((u, v));
        uv.push(DVec2::new(u, v));
        sing.push(surf.is_singular(p));
    }
    let regular: Vec<usize> = (0..n).filter(|&i| !sing[i]).collect();
    if regular.is_empty() {
        return (Vec::new(), 0, 0);
    }
    let mut ku = 0;
    let mut kv = 0;
    if let Some(p) = pu {
        let mut prev = uv[regular[0]].x;
        for &i in &regular {
            uv[i].x = unwrap_near(uv[i].x, prev, p);
            prev = uv[i].x;
        }
        let first = uv[regular[0]].x;
        ku = ((unwrap_near(first, prev, p) - first) / p).round() as i64;
    }
    if let Some(p) = pv {
        let mut prev = uv[regular[0]].y;
        for &i in &regular {
            uv[i].y = unwrap_near(uv[i].y, prev, p);
            prev = uv[i].y;
        }
        let first = uv[regular[0]].y;
        kv = ((unwrap_near(first, prev, p) - first) / p).round() as i64;
    }
    let has_sing = regular.len() < n;
    let mut ring = Vec::with_capacity(n + 4);
    for i in 0..n {
        if !sing[i] {
            ring.push(Rp {
                uv: uv[i],
                p: pts[i],
            });
            continue;
        }
        // Neighbouring regular points, cyclically.
        let prev = (1..n).map(|k| (i + n - k) % n).find(|&j| !sing[j]).unwrap();
        let next = (1..n).map(|k| (i + k) % n).find(|&j| !sing[j]).unwrap();
        let (up, un) = (uv[prev].x, uv[next].x);
        ring.push(Rp {
            uv: DVec2::new(up, uv[i].y),
            p: pts[i],
        });
        if (un - up).abs() > 1e-12 {
            ring.push(Rp {
                uv: DVec2::new(un, uv[i].y),
                p: pts[i],
            });
        }
    }
    if has_sing {
        // The singular line closes the ring, whatever its u winding.
        ku = 0;
    }
    (ring, ku, kv)
}

/// A cut position in [0, period) lying in the widest gap between the
/// u-extents of the ordinary rings (which must not cross the cut).
fn choose_cut(rings: &[Vec<Rp>], period: f64) -> f64 {
    let mut iv: Vec<(f64, f64)> = rings
        .iter()
        .map(|r| {
            let (lo, hi) = extent(r);
            let s = lo.x.rem_euclid(period);
            (s, s + (hi.x - lo.x))
        })
        .collect();
    if iv.is_empty() {
        return 0.0;
    }
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = (f64::NEG_INFINITY, 0.0);
    let mut end = iv[0].1;
    for w in iv.iter().skip(1) {
        if w.0 > end && w.0 - end > best.0 {
            best = (w.0 - end, 0.5 * (w.0 + end));
        }
        end = end.max(w.1);
    }
    let wrap_gap = iv[0].0 + period - end;
    if wrap_gap > best.0 {
        best = (wrap_gap, 0.5 * (end + iv[0].0 + period));
    }
    best.1.rem_euclid(period)
}

/// Opens a band loop (winding once around u) at `u = uc (mod period)` into a
/// polyline increasing from `uc` to `uc + period`.
fn cut_band(
    surf: &Surface,
    swapped: bool,
    mut ring: Vec<Rp>,
    k: i64,
    uc: f64,
    period: f64,
) -> Vec<Rp> {
    if k < 0 {
        ring.reverse();
    }
    let n = ring.len();
    let mut ext: Vec<Rp> = ring.clone();
    ext.push(Rp {
        uv: ring[0].uv + DVec2::new(period, 0.0),
        p: ring[0].p,
    });
    for q in ring.iter().skip(1) {
        ext.push(Rp {
            uv: q.uv + DVec2::new(period, 0.0),
            p: q.p,
        });
    }
    let u0 = ring[0].uv.x;
    let m = ((u0 - uc) / period).ceil();
    let level = uc + m * period;
    let j = (0..n).find(|&j| ext[j + 1].uv.x >= level).unwrap_or(n - 1);
    let (a, b) = (ext[j], ext[j + 1]);
    let du = b.uv.x - a.uv.x;
    let t = if du.abs() > 0.0 {
        ((level - a.uv.x) / du).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let eval = |uv: DVec2| {
        if swapped {
            surf.point(uv.y, uv.x)
        } else {
            surf.point(uv.x, uv.y)
        }
    };
    let cuv = DVec2::new(level, a.uv.y + (b.uv.y - a.uv.y) * t);
    let cp = if t == 0.0 {
        a.p
    } else if t == 1.0 {
        b.p
    } else {
        eval(cuv)
    };
    let mut out = Vec::with_capacity(n + 2);
    out.push(Rp { uv: cuv, p: cp });
    out.extend_from_slice(&ext[j + 1..=j + n]);
    out.push(Rp {
        uv: cuv + DVec2::new(period, 0.0),
        p: cp,
    });
    let shift = DVec2::new(m * period, 0.0);
    for q in out.iter_mut() {
        q.uv -= shift;
    }
    out.dedup_by(|a, b| a.uv.distance_squared(b.uv) < 1e-28);
    out
}

/// Closes an opened band through the singular line `v = vp` (u from
/// `uc + period` back to `uc`, all at the singular point).
fn close_to_pole(surf: &Surface, mut band: Vec<Rp>, vp: f64) -> Vec<Rp> {
    let back: Vec<Rp> = band
        .iter()
        .rev()
        .map(|q| Rp {
            uv: DVec2::new(q.uv.x, vp),
            p: surf.point(q.uv.x, vp),
        })
        .collect();
    band.extend(back);
    band
}

fn param_scale(surf: &Surface, rings: &[Vec<Rp>]) -> (f64, f64) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for r in rings {
        let (a, b) = extent(r);
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let mid = 0.5 * (lo + hi);
    let (su, sv) = match surf {
        Surface::Plane { .. } => (1.0, 1.0),
        Surface::Cylinder { radius, .. } => (radius.abs(), 1.0),
        Surface::Cone {
            radius, semi_angle, ..
        } => {
            let t = semi_angle.tan();
            let r0 = (radius + lo.y * t).abs();
            let r1 = (radius + hi.y * t).abs();
            (0.5 * (r0 + r1), 1.0 / semi_angle.cos().abs().max(1e-6))
        }
        Surface::Sphere { radius, .. } => (radius * mid.y.cos().abs().max(0.2), *radius),
        Surface::Torus {
            major_radius,
            minor_radius,
            ..
        } => (
            (major_radius + minor_radius * mid.y.cos())
                .abs()
                .max(0.2 * minor_radius),
            *minor_radius,
        ),
        _ => {
            let (mut a, mut b, mut n) = (0.0, 0.0, 0.0);
            for i in 0..=4 {
                for j in 0..=4 {
                    let u = lo.x + (hi.x - lo.x) * i as f64 / 4.0;
                    let v = lo.y + (hi.y - lo.y) * j as f64 / 4.0;
                    let (_, du, dv) = surf.point_d1(u, v);
                    a += du.length();
                    b += dv.length();
                    n += 1.0;
                }
            }
            (a / n, b / n)
        }
    };
    let fix = |s: f64| if s.is_finite() && s > 1e-12 { s } else { 1.0 };
    (fix(su), fix(sv))
}

/// Splits ring segments whose parameter-space midpoint leaves the 3D chord
/// by more than the tolerance (seam cut lines, whole-surface rectangles;
/// properly sampled loop edges on analytic surfaces are left alone).
fn densify(surf: &Surface, ring: &mut Vec<Rp>, tol: &TessTolerance) {
    fn split(surf: &Surface, a: Rp, b: Rp, tol: f64, depth: u32, out: &mut Vec<Rp>) {
        let muv = 0.5 * (a.uv + b.uv);
        let mp = surf.point(muv.x, muv.y);
        if depth < 16 && mp.distance(0.5 * (a.p + b.p)) > tol {
            let m = Rp { uv: muv, p: mp };
            split(surf, a, m, tol, depth + 1, out);
            out.push(m);
            split(surf, m, b, tol, depth + 1, out);
        }
    }
    let n = ring.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        out.push(a);
        split(surf, a, b, tol.chord * (1.0 + 1e-6), 0, &mut out);
    }
    *ring = out;
}

/// Even-odd classification of the inner faces: crossing a constraint edge
/// toggles inside/outside, starting from outside the convex hull.
fn classify(cdt: &Cdt) -> Vec<bool> {
    let mut state: Vec<i8> = vec![-1; cdt.num_all_faces()];
    let mut queue = VecDeque::new();
    for e in cdt.convex_hull() {
        let f = if e.face().is_outer() {
            e.rev().face()
        } else {
            e.face()
        };
        if let Some(inner) = f.as_inner() {
            let idx = inner.fix().index();
            if state[idx] == -1 {
                state[idx] = e.is_constraint_edge() as i8;
                queue.push_back(inner.fix());
            }
        }
    }
    while let Some(fh) = queue.pop_front() {
        let face = cdt.face(fh);
        let here = state[fh.index()];
        for e in face.adjacent_edges() {
            if let Some(nb) = e.rev().face().as_inner() {
                let idx = nb.fix().index();
                if state[idx] == -1 {
                    state[idx] = here ^ (e.is_constraint_edge() as i8);
                    queue.push_back(nb.fix());
                }
            }
        }
    }
    state.into_iter().map(|s| s == 1).collect()
}

fn triangulate(
    surf: &Surface,
    sense: bool,
    rings: &[Vec<Rp>],
    tol: &TessTolerance,
    face: FaceId,
) -> Result<Mesh, TessError> {
    let (su, sv) = param_scale(surf, rings);
    let mk = |uv: DVec2, p: DVec3| Tv {
        pos: Point2::new(uv.x * su, uv.y * sv),
        uv,
        p,
    };
    // Loop samples of circles are exactly cocircular, which sends every
    // in-circle test down the slow exact-arithmetic path. A deterministic
    // jitter of 1e-10 of the extent, applied to the triangulation position
    // only (parameters and 3D points stay exact), avoids that.
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for r in rings {
        let (a, b) = extent(r);
        lo = lo.min(a * DVec2::new(su, sv));
        hi = hi.max(b * DVec2::new(su, sv));
    }
    let jit = 1e-10 * (hi - lo).max_element().max(1e-300);
    let mut counter: u64 = 0;
    let mut jitter = move || {
        counter = counter.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = counter;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        let a = (z & 0xFFFF_FFFF) as f64 / u32::MAX as f64 - 0.5;
        let b = (z >> 32) as f64 / u32::MAX as f64 - 0.5;
        Point2::new(a * jit, b * jit)
    };
    let mut cdt = Cdt::new();
    for ring in rings {
        let mut hs: Vec<FixedVertexHandle> = Vec::with_capacity(ring.len());
        for q in ring {
            if !(q.uv.is_finite() && q.p.is_finite()) {
                return Err(TessError::BadLoops("non-finite parameters".into()));
            }
            let mut v = mk(q.uv, q.p);
            let j = jitter();
            v.pos = Point2::new(v.pos.x + j.x, v.pos.y + j.y);
            let h = cdt
                .insert(v)
                .map_err(|e| TessError::Triangulation(format!("{e:?}")))?;
            hs.push(h);
        }
        for i in 0..hs.len() {
            let (a, b) = (hs[i], hs[(i + 1) % hs.len()]);
            if a != b {
                cdt.add_constraint_and_split(a, b, |pt: Point2<f64>| {
                    let uv = DVec2::new(pt.x / su, pt.y / sv);
                    Tv {
                        pos: pt,
                        uv,
                        p: surf.point(uv.x, uv.y),
                    }
                });
            }
        }
    }

    let planar = matches!(surf, Surface::Plane { .. });
    if !planar {
        refine(&mut cdt, surf, tol, &mut |uv, p| {
            let mut v = mk(uv, p);
            let j = jitter();
            v.pos = Point2::new(v.pos.x + j.x, v.pos.y + j.y);
            v
        });
    }

    let inside = classify(&cdt);
    let sign = if sense { 1.0 } else { -1.0 };
    let mut map = vec![u32::MAX; cdt.num_vertices()];
    let mut mesh = Mesh::default();
    for fh in cdt.inner_faces() {
        if !inside[fh.fix().index()] {
            continue;
        }
        let vs = fh.vertices();
        let ps = vs.map(|v| v.data().p);
        let e0 = ps[1] - ps[0];
        let e1 = ps[2] - ps[0];
        let longest = e0
            .length_squared()
            .max(e1.length_squared())
            .max((ps[2] - ps[1]).length_squared());
        if e0.cross(e1).length_squared() <= 1e-24 * longest * longest || longest == 0.0 {
            continue; // degenerate (pole fans, collinear slivers)
        }
        let mut t = [0u32; 3];
        for (k, v) in vs.iter().enumerate() {
            let i = v.fix().index();
            if map[i] == u32::MAX {
                map[i] = mesh.positions.len() as u32;
                let d = v.data();
                mesh.positions.push(d.p);
                mesh.normals.push(surf.normal(d.uv.x, d.uv.y) * sign);
            }
            t[k] = map[i];
        }
        mesh.triangles.push(t);
        mesh.face_of_triangle.push(face);
    }
    // Orientation: CCW in parameter space is along Su x Sv; make triangles
    // CCW about the outward normal whatever the parameterisation does.
    let mut vote = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = mesh.tri(t);
        let n =
            mesh.normals[t[0] as usize] + mesh.normals[t[1] as usize] + mesh.normals[t[2] as usize];
        vote += (b - a).cross(c - a).dot(n);
    }
    if vote < 0.0 {
        for t in mesh.triangles.iter_mut() {
            t.swap(1, 2);
        }
    }
    // Fill undefined normals (degenerate free-form points) from triangles.
    if mesh.normals.iter().any(|n| n.length_squared() < 0.5) {
        let mut acc = vec![DVec3::ZERO; mesh.positions.len()];
        for t in &mesh.triangles {
            let [a, b, c] = mesh.tri(t);
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        for (n, a) in mesh.normals.iter_mut().zip(acc) {
            if n.length_squared() < 0.5 {
                *n = a.normalize_or_zero();
            }
        }
    }
    Ok(mesh)
}

/// Inserts edge midpoints and centroids where the flat triangles leave the
/// surface by more than the chord tolerance or the normal turns too much.
fn refine(
    cdt: &mut Cdt,
    surf: &Surface,
    tol: &TessTolerance,
    mk: &mut impl FnMut(DVec2, DVec3) -> Tv,
) {
    let cos_angle = tol.angle.cos();
    let chord = tol.chord * (1.0 + 1e-9);
    for _ in 0..MAX_REFINE_ITERS {
        let inside = classify(cdt);
        let mut seen = vec![false; cdt.num_undirected_edges()];
        let mut new_pts: Vec<DVec2> = Vec::new();
        for fh in cdt.inner_faces() {
            if !inside[fh.fix().index()] {
                continue;
            }
            for e in fh.adjacent_edges() {
                let ue = e.as_undirected();
                let idx = ue.fix().index();
                if seen[idx] || e.is_constraint_edge() {
                    continue;
                }
                seen[idx] = true;
                let (a, b) = (*e.from().data(), *e.to().data());
                let len = a.p.distance(b.p);
                if len < 1e-9 {
                    continue;
                }
                let muv = 0.5 * (a.uv + b.uv);
                let sp = surf.point(muv.x, muv.y);
                let err = sp.distance(0.5 * (a.p + b.p));
                // The angle criterion only on edges long against the chord:
                // near singular points (cone apex) normals turn on any scale.
                let turns = len > 10.0 * tol.chord && {
                    let na = surf.normal(a.uv.x, a.uv.y);
                    let nb = surf.normal(b.uv.x, b.uv.y);
                    na.dot(nb) < cos_angle
                };
                if err > chord || turns {
                    new_pts.push(muv);
                }
            }
            let vs = fh.vertices().map(|v| *v.data());
            let cuv = (vs[0].uv + vs[1].uv + vs[2].uv) / 3.0;
            let cp = (vs[0].p + vs[1].p + vs[2].p) / 3.0;
            if surf.point(cuv.x, cuv.y).distance(cp) > chord {
                new_pts.push(cuv);
            }
        }
        if new_pts.is_empty() || cdt.num_vertices() + new_pts.len() > MAX_VERTICES {
            break;
        }
        for uv in new_pts {
            let p = surf.point(uv.x, uv.y);
            let _ = cdt.insert(mk(uv, p));
        }
    }
}
