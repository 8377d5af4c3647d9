//! 2D helpers in a prism's frame: arcs flattened, half-plane clipping,
//! orientation, and the 3D points of a prism.

use glam::{DVec2, DVec3};
use thinplan_plan::{Prism, ProfileLoop};

/// Largest angle (rad) one flattened arc segment spans.
const ARC_STEP: f64 = std::f64::consts::PI / 16.0;

/// The loop's points with arcs replaced by chords of at most [`ARC_STEP`].
pub fn flatten(lp: &ProfileLoop) -> Vec<DVec2> {
    let n = lp.vertices.len();
    let mut out = Vec::new();
    for i in 0..n {
        let a = &lp.vertices[i];
        let b = &lp.vertices[(i + 1) % n];
        let p0 = DVec2::new(a.x, a.y);
        let p1 = DVec2::new(b.x, b.y);
        out.push(p0);
        if a.bulge.abs() > 1e-12 {
            let theta = 4.0 * a.bulge.atan();
            let c = p1 - p0;
            let d = c.length();
            if d < 1e-12 {
                continue;
            }
            let left = DVec2::new(-c.y, c.x) / d;
            let centre =
                (p0 + p1) * 0.5 + left * (d * 0.5) * (1.0 - a.bulge * a.bulge) / (2.0 * a.bulge);
            let r0 = p0 - centre;
            let a0 = r0.y.atan2(r0.x);
            let r = r0.length();
            let steps = (theta.abs() / ARC_STEP).ceil().max(1.0) as usize;
            for k in 1..steps {
                let ang = a0 + theta * k as f64 / steps as f64;
                out.push(centre + DVec2::new(ang.cos(), ang.sin()) * r);
            }
        }
    }
    out
}

/// Sutherland–Hodgman: the part of `poly` where `dir · p ≥ at`.
pub fn clip(poly: &[DVec2], dir: DVec2, at: f64) -> Vec<DVec2> {
    let n = poly.len();
    let mut out = Vec::with_capacity(n + 2);
    for i in 0..n {
        let p = poly[i];
        let q = poly[(i + 1) % n];
        let fp = dir.dot(p) - at;
        let fq = dir.dot(q) - at;
        if fp >= 0.0 {
            out.push(p);
        }
        if (fp >= 0.0) != (fq >= 0.0) {
            let s = fp / (fp - fq);
            out.push(p + (q - p) * s);
        }
    }
    dedup(out)
}

fn dedup(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.dedup_by(|a, b| a.distance(*b) < 1e-9);
    while pts.len() > 1 && pts[0].distance(pts[pts.len() - 1]) < 1e-9 {
        pts.pop();
    }
    pts
}

/// Twice the signed area (positive: counter-clockwise).
pub fn area2(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum()
}

/// The 3D points of a prism: its (flattened) outer loop at both z ends.
pub fn prism_points(p: &Prism) -> Vec<DVec3> {
    let fx = p.frame.x.normalize_or_zero();
    let fz = p.frame.z.normalize_or_zero();
    let fy = fz.cross(fx);
    let mut out = Vec::new();
    for q in flatten(&p.region.outer) {
        for z in [p.z_min, p.z_max] {
            out.push(p.frame.origin + fx * q.x + fy * q.y + fz * z);
        }
    }
    out
}

/// The interval of `pts` projected on `dir`.
pub fn span(pts: &[DVec3], dir: DVec3) -> (f64, f64) {
    pts.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = p.dot(dir);
            (lo.min(s), hi.max(s))
        })
}
