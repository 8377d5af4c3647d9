//! Test tool paths as point lists (mm) in the plane z = 0, with a given point spacing: every
//! straight piece and arc is cut into equal steps no longer than `spacing`. Consecutive
//! pieces share their joining point (no duplicates).

use glam::DVec3;
use std::f64::consts::{PI, TAU};

fn steps(len: f64, spacing: f64) -> usize {
    assert!(spacing > 0.0, "paths: spacing must be > 0");
    ((len / spacing).ceil() as usize).max(1)
}

/// Append the straight line to `b` (the start is the last point of `out`, or `a`).
fn push_line(out: &mut Vec<DVec3>, a: DVec3, b: DVec3, spacing: f64) {
    let n = steps(a.distance(b), spacing);
    let first = if out.is_empty() { 0 } else { 1 };
    for i in first..=n {
        out.push(a.lerp(b, i as f64 / n as f64));
    }
}

/// Append an arc around `center` from angle `start` through `sweep` (radians, positive = CCW).
fn push_arc(
    out: &mut Vec<DVec3>,
    center: DVec3,
    radius: f64,
    start: f64,
    sweep: f64,
    spacing: f64,
) {
    let n = steps(radius * sweep.abs(), spacing);
    let first = if out.is_empty() { 0 } else { 1 };
    for i in first..=n {
        let a = start + sweep * i as f64 / n as f64;
        out.push(center + DVec3::new(radius * a.cos(), radius * a.sin(), 0.0));
    }
}

/// A straight line from `a` to `b`.
pub fn line(a: DVec3, b: DVec3, spacing: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    push_line(&mut out, a, b, spacing);
    out
}

/// Zigzag over the rectangle `[0, width] × [0, height]`: passes along x, `stepover` apart in
/// y, joined by straight stepover moves with sharp 90° corners (the classic direction-parallel
/// pattern). The last pass lies on y = height.
pub fn zigzag(width: f64, height: f64, stepover: f64, spacing: f64) -> Vec<DVec3> {
    let passes = steps(height, stepover);
    let dy = height / passes as f64;
    let mut out = Vec::new();
    for p in 0..=passes {
        let y = p as f64 * dy;
        let (x0, x1) = if p % 2 == 0 {
            (0.0, width)
        } else {
            (width, 0.0)
        };
        push_line(
            &mut out,
            DVec3::new(x0, y, 0.0),
            DVec3::new(x1, y, 0.0),
            spacing,
        );
        if p < passes {
            push_line(
                &mut out,
                DVec3::new(x1, y, 0.0),
                DVec3::new(x1, y + dy, 0.0),
                spacing,
            );
        }
    }
    out
}

/// Zigzag over `[0, width] × [0, height]` with rounded turns: passes along x joined by
/// semicircles of diameter `stepover` outside the rectangle (tangent-continuous, no corners).
pub fn zigzag_rounded(width: f64, height: f64, stepover: f64, spacing: f64) -> Vec<DVec3> {
    let passes = steps(height, stepover);
    let dy = height / passes as f64;
    let r = dy / 2.0;
    let mut out = Vec::new();
    for p in 0..=passes {
        let y = p as f64 * dy;
        let forward = p % 2 == 0;
        let (x0, x1) = if forward { (0.0, width) } else { (width, 0.0) };
        push_line(
            &mut out,
            DVec3::new(x0, y, 0.0),
            DVec3::new(x1, y, 0.0),
            spacing,
        );
        if p < passes {
            let c = DVec3::new(x1, y + r, 0.0);
            if forward {
                push_arc(&mut out, c, r, -PI / 2.0, PI, spacing); // right end, CCW
            } else {
                push_arc(&mut out, c, r, -PI / 2.0, -PI, spacing); // left end, CW
            }
        }
    }
    out
}

/// Closed circle of `radius` about the origin, starting and ending at (radius, 0), CCW.
pub fn circle(radius: f64, spacing: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    push_arc(&mut out, DVec3::ZERO, radius, 0.0, TAU, spacing);
    out
}

/// Closed outline of a regular pentagon with circumradius `circumradius` (of the sharp
/// pentagon) whose corners are rounded with `corner_radius` (tangent arcs), CCW, starting at
/// the middle of the bottom edge.
pub fn rounded_pentagon(circumradius: f64, corner_radius: f64, spacing: f64) -> Vec<DVec3> {
    let inradius = circumradius * (PI / 5.0).cos();
    assert!(
        corner_radius >= 0.0 && corner_radius < inradius,
        "rounded_pentagon: corner radius must be in [0, inradius)"
    );
    // The outline is the offset by `corner_radius` of a smaller pentagon with inradius
    // `inradius - corner_radius`: straight edges joined by arcs about its vertices.
    let r_in = (inradius - corner_radius) / (PI / 5.0).cos();
    // Vertices of the small pentagon; edge m goes from vertex m to m+1, the bottom edge first.
    let vert = |m: usize| {
        let a = -PI / 2.0 - PI / 5.0 + m as f64 * TAU / 5.0;
        DVec3::new(r_in * a.cos(), r_in * a.sin(), 0.0)
    };
    let mut out = Vec::new();
    for m in 0..5 {
        let (p, q) = (vert(m), vert(m + 1));
        let normal_angle = -PI / 2.0 + m as f64 * TAU / 5.0; // outward normal of edge m
        let off = DVec3::new(normal_angle.cos(), normal_angle.sin(), 0.0) * corner_radius;
        let mid = (p + q) / 2.0 + off;
        if m == 0 {
            push_line(&mut out, mid, q + off, spacing);
        } else {
            push_line(&mut out, p + off, q + off, spacing);
        }
        if corner_radius > 0.0 {
            push_arc(&mut out, q, corner_radius, normal_angle, TAU / 5.0, spacing);
        }
    }
    let (start, last) = (out[0], out[out.len() - 1]);
    push_line(&mut out, last, start, spacing);
    out
}

/// Archimedean spiral about the origin, `r = r_start + pitch·θ/2π`, from `r_start` out to
/// `r_end` (both > 0), with steps of arc length close to `spacing`.
pub fn spiral(r_start: f64, r_end: f64, pitch: f64, spacing: f64) -> Vec<DVec3> {
    assert!(
        r_start > 0.0 && r_end > r_start && pitch > 0.0,
        "spiral: need 0 < r_start < r_end, pitch > 0"
    );
    let b = pitch / TAU;
    let theta_end = (r_end - r_start) / b;
    let at = |th: f64| {
        let r = r_start + b * th;
        DVec3::new(r * th.cos(), r * th.sin(), 0.0)
    };
    let mut out = vec![at(0.0)];
    let mut th = 0.0;
    loop {
        let r = r_start + b * th;
        // Midpoint step: dθ = ds / |dP/dθ| evaluated half a step ahead.
        let d0 = spacing / (r * r + b * b).sqrt();
        let rm = r + b * d0 / 2.0;
        th += spacing / (rm * rm + b * b).sqrt();
        if th >= theta_end - 1e-9 * theta_end {
            break;
        }
        out.push(at(th));
    }
    out.push(at(theta_end));
    out
}

/// Helix about the z axis (a helical ramp entry): `turns` turns of `radius`, descending
/// `pitch` per turn from z = 0, starting at (radius, 0, 0), CCW.
pub fn helix(radius: f64, pitch: f64, turns: f64, spacing: f64) -> Vec<DVec3> {
    let sweep = TAU * turns;
    let len = (radius * sweep).hypot(pitch * turns);
    let n = steps(len, spacing);
    (0..=n)
        .map(|i| {
            let a = sweep * i as f64 / n as f64;
            DVec3::new(radius * a.cos(), radius * a.sin(), -pitch * a / TAU)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_step(p: &[DVec3]) -> f64 {
        p.windows(2)
            .map(|w| w[0].distance(w[1]))
            .fold(0.0, f64::max)
    }

    #[test]
    fn shapes() {
        let c = circle(50.0, 1.0);
        assert!(c[0].distance(*c.last().unwrap()) < 1e-9);
        assert!(c.iter().all(|p| (p.length() - 50.0).abs() < 1e-9));
        assert!(max_step(&c) <= 1.0);

        let z = zigzag(100.0, 40.0, 10.0, 2.0);
        assert_eq!(z[0], DVec3::ZERO);
        assert!((z.last().unwrap().y - 40.0).abs() < 1e-9);
        assert!(max_step(&z) <= 2.0 + 1e-12);

        let zr = zigzag_rounded(100.0, 40.0, 10.0, 1.0);
        assert!(zr.iter().all(|p| p.x >= -5.0 - 1e-9 && p.x <= 105.0 + 1e-9));
        assert!(max_step(&zr) <= 1.0 + 1e-12);

        let p = rounded_pentagon(50.0, 10.0, 1.0);
        assert!(p[0].distance(*p.last().unwrap()) < 1e-9);
        // All points at least the corner radius inside the sharp pentagon's circumcircle.
        assert!(p.iter().all(|q| q.length() <= 50.0 + 1e-9));
        assert!(max_step(&p) <= 1.0 + 1e-12);
        // No duplicate points.
        assert!(p.windows(2).all(|w| w[0].distance(w[1]) > 0.1));

        let s = spiral(2.0, 40.0, 5.0, 0.5);
        assert!((s.last().unwrap().length() - 40.0).abs() < 1e-9);
        assert!(max_step(&s) <= 0.5 * 1.01);
    }
}
