//! Small exact helpers for 2D line/arc segments in bulge form
//! (bulge = tan(sweep/4), positive counter-clockwise), as cavalier_contours uses.

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, PlineVertex, Polyline};
use glam::DVec2;

/// A line (bulge 0) or circular arc from `a` to `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seg {
    pub a: DVec2,
    pub b: DVec2,
    pub bulge: f64,
}

impl Seg {
    pub fn line(a: DVec2, b: DVec2) -> Seg {
        Seg { a, b, bulge: 0.0 }
    }

    pub fn is_line(&self) -> bool {
        self.bulge.abs() < 1e-12
    }

    pub fn reversed(&self) -> Seg {
        Seg {
            a: self.b,
            b: self.a,
            bulge: -self.bulge,
        }
    }

    /// Signed sweep angle (0 for lines).
    pub fn sweep(&self) -> f64 {
        4.0 * self.bulge.atan()
    }

    /// Centre and radius of an arc.
    pub fn centre_radius(&self) -> (DVec2, f64) {
        let chord = self.b - self.a;
        let half = chord.length() * 0.5;
        let mid = (self.a + self.b) * 0.5;
        // Distance from the chord midpoint to the centre, signed to the left.
        let b = self.bulge;
        let sagitta_ratio = (1.0 - b * b) / (2.0 * b); // = d / half
        let left = DVec2::new(-chord.y, chord.x) / chord.length().max(1e-300);
        let centre = mid + left * (sagitta_ratio * half);
        let radius = half * (1.0 + b * b) / (2.0 * b.abs());
        (centre, radius)
    }

    pub fn midpoint(&self) -> DVec2 {
        if self.is_line() {
            return (self.a + self.b) * 0.5;
        }
        let chord = self.b - self.a;
        let mid = (self.a + self.b) * 0.5;
        // Sagitta s = bulge * half chord, to the right of the chord for positive bulge.
        let right = DVec2::new(chord.y, -chord.x) * 0.5;
        mid + right * self.bulge
    }

    /// Unit tangent at the start, in travel direction.
    pub fn start_tangent(&self) -> DVec2 {
        let d = (self.b - self.a).normalize_or_zero();
        if self.is_line() {
            d
        } else {
            DVec2::from_angle(-self.sweep() * 0.5).rotate(d)
        }
    }

    /// Unit tangent at the end, in travel direction.
    pub fn end_tangent(&self) -> DVec2 {
        let d = (self.b - self.a).normalize_or_zero();
        if self.is_line() {
            d
        } else {
            DVec2::from_angle(self.sweep() * 0.5).rotate(d)
        }
    }

    /// Signed curvature (positive when turning left).
    pub fn curvature(&self) -> f64 {
        if self.is_line() {
            0.0
        } else {
            let (_, r) = self.centre_radius();
            self.bulge.signum() / r
        }
    }

    /// ½∮(x dy − y dx) over the segment: summed over a closed loop this is
    /// the signed area (positive counter-clockwise).
    pub fn area_term(&self) -> f64 {
        let chord = 0.5 * self.a.perp_dot(self.b);
        if self.is_line() {
            return chord;
        }
        let (_, r) = self.centre_radius();
        let theta = self.sweep();
        // Circular segment between chord and arc, signed with the sweep.
        chord + 0.5 * r * r * (theta - theta.sin())
    }

    /// Point at parameter `t` in [0, 1] (fraction of the sweep for arcs).
    #[allow(dead_code)]
    pub fn point_at(&self, t: f64) -> DVec2 {
        if self.is_line() {
            return self.a.lerp(self.b, t);
        }
        let (c, _) = self.centre_radius();
        c + DVec2::from_angle(self.sweep() * t).rotate(self.a - c)
    }

    /// Parameter in [0, 1] of a point assumed to lie on the segment.
    pub fn param_of(&self, p: DVec2) -> f64 {
        if self.is_line() {
            let d = self.b - self.a;
            return (p - self.a).dot(d) / d.length_squared();
        }
        let (c, _) = self.centre_radius();
        let sweep = self.sweep();
        let ang = (self.a - c).angle_to(p - c); // (-π, π]
        let mut ang = if sweep > 0.0 {
            ang.rem_euclid(std::f64::consts::TAU)
        } else {
            -(-ang).rem_euclid(std::f64::consts::TAU)
        };
        // Points at the start may come out as a full turn.
        if (ang.abs() - std::f64::consts::TAU).abs() < 1e-9 {
            ang = 0.0;
        }
        ang / sweep
    }

    /// Distance from a point to the segment.
    pub fn distance_to(&self, p: DVec2) -> f64 {
        if self.is_line() {
            let d = self.b - self.a;
            let t = ((p - self.a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
            return (self.a + d * t).distance(p);
        }
        let (c, r) = self.centre_radius();
        let t = self.param_of(p);
        if (0.0..=1.0).contains(&t) {
            ((p - c).length() - r).abs()
        } else {
            p.distance(self.a).min(p.distance(self.b))
        }
    }

    /// Axis-aligned bounds (exact for arcs).
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let mut lo = self.a.min(self.b);
        let mut hi = self.a.max(self.b);
        if !self.is_line() {
            let (c, r) = self.centre_radius();
            for dir in [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y] {
                let p = c + dir * r;
                let t = self.param_of(p);
                if t > 0.0 && t < 1.0 {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
        (lo, hi)
    }

    pub fn vertex_a(&self) -> PlineVertex<f64> {
        PlineVertex::new(self.a.x, self.a.y, self.bulge)
    }
}

/// Signed area of a closed loop of segments.
pub fn loop_area(segs: &[Seg]) -> f64 {
    segs.iter().map(Seg::area_term).sum()
}

/// Reverses a loop (order and direction of every segment).
pub fn reverse_loop(segs: &[Seg]) -> Vec<Seg> {
    segs.iter().rev().map(Seg::reversed).collect()
}

/// A closed cavalier polyline of a loop.
pub fn to_pline(segs: &[Seg]) -> Polyline<f64> {
    let mut p = Polyline::new_closed();
    for s in segs {
        p.add(s.a.x, s.a.y, s.bulge);
    }
    p
}

/// Winding number of a point about a loop (cavalier_contours).
pub fn winding(pline: &Polyline<f64>, p: DVec2) -> i32 {
    pline.winding_number(cavalier_contours::core::math::Vector2::new(p.x, p.y))
}

/// Bounds of a loop.
pub fn loop_bounds(segs: &[Seg]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for s in segs {
        let (a, b) = s.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn half_circle_geometry() {
        let s = Seg {
            a: DVec2::new(1.0, 0.0),
            b: DVec2::new(-1.0, 0.0),
            bulge: 1.0,
        };
        let (c, r) = s.centre_radius();
        assert!(c.length() < 1e-12 && (r - 1.0).abs() < 1e-12);
        assert!((s.midpoint() - DVec2::new(0.0, 1.0)).length() < 1e-12);
        assert!((s.start_tangent() - DVec2::Y).length() < 1e-12);
        assert!((s.end_tangent() + DVec2::Y).length() < 1e-12);
        let other = Seg {
            a: s.b,
            b: s.a,
            bulge: 1.0,
        };
        let full = [s, other];
        assert!((loop_area(&full) - PI).abs() < 1e-12);
        assert!((s.param_of(DVec2::new(0.0, 1.0)) - 0.5).abs() < 1e-12);
        let (lo, hi) = s.bounds();
        assert!((hi.y - 1.0).abs() < 1e-12 && lo.y.abs() < 1e-12);
    }
}
