//! Independent checks of a schedule against the limits, by finite differences on the
//! scheduled (s, v, t) and on the positions. The geometry (directions, three-point curvature,
//! corners) is recomputed here from the points, not taken from the crate.

#![allow(dead_code)]

use glam::DVec3;
use thinplan_feeds::{MachineLimits, Schedule, DEGENERATE_LEN};

/// Relative tolerance for "no limit violated".
pub const TOL: f64 = 1e-9;

pub struct Geometry {
    /// Unit direction per segment (zero when degenerate).
    pub dir: Vec<DVec3>,
    pub len: Vec<f64>,
    /// Curvature vector per point as the model defines it (zero at corners; ends copy the
    /// neighbour).
    pub curv: Vec<DVec3>,
    pub corner: Vec<bool>,
}

pub fn geometry(p: &[DVec3], limits: &MachineLimits) -> Geometry {
    let n = p.len();
    let mut dir = vec![DVec3::ZERO; n.saturating_sub(1)];
    let mut len = vec![0.0; n.saturating_sub(1)];
    for i in 0..n.saturating_sub(1) {
        let d = p[i + 1] - p[i];
        if d.length() > DEGENERATE_LEN {
            dir[i] = d.normalize();
            len[i] = d.length();
        }
    }
    let mut curv = vec![DVec3::ZERO; n];
    let mut corner = vec![false; n];
    for j in 1..n.saturating_sub(1) {
        // Nearest non-degenerate segments before and after j.
        let before = (0..j).rev().find(|&i| len[i] > 0.0);
        let after = (j..n - 1).find(|&i| len[i] > 0.0);
        let (Some(b), Some(a)) = (before, after) else {
            continue;
        };
        let (u, w) = (dir[b] * len[b], dir[a] * len[a]);
        let angle = u.angle_between(w).to_degrees();
        if angle > limits.corner_angle_deg {
            corner[j] = true;
            continue;
        }
        // Circumscribed circle of the triangle (q0, q1, q2) with q1 - q0 = u, q2 - q1 = w.
        let (ab, ac) = (u, u + w);
        let cr = ab.cross(ac);
        if cr.length() < 1e-15 * ab.length() * ac.length() {
            continue;
        }
        // Circumcentre relative to q0.
        let cc = (ac.length_squared() * cr.cross(ab) + ab.length_squared() * ac.cross(cr))
            / (2.0 * cr.length_squared());
        let to_centre = cc - ab; // from q1
        let r = to_centre.length();
        curv[j] = to_centre / (r * r);
    }
    if n >= 3 {
        curv[0] = curv[1];
        curv[n - 1] = curv[n - 2];
    }
    Geometry {
        dir,
        len,
        curv,
        corner,
    }
}

/// Largest violation ratio found (≤ 1 + TOL means fine), with a description.
pub struct Report {
    pub worst: f64,
    pub what: String,
}

impl Report {
    fn see(&mut self, ratio: f64, what: impl FnOnce() -> String) {
        if ratio > self.worst {
            self.worst = ratio;
            self.what = what();
        }
    }
}

/// Check a schedule against the limits; panics with the worst violation.
pub fn check(p: &[DVec3], caps: &[f64], limits: &MachineLimits, s: &Schedule) {
    let r = violations(p, caps, limits, s);
    assert!(
        r.worst <= 1.0 + TOL,
        "limit violated: ratio {} at {}",
        r.worst,
        r.what
    );
}

pub fn violations(p: &[DVec3], caps: &[f64], limits: &MachineLimits, s: &Schedule) -> Report {
    let n = p.len();
    let g = geometry(p, limits);
    let mut rep = Report {
        worst: 0.0,
        what: String::new(),
    };
    assert_eq!((s.s.len(), s.v.len(), s.t.len()), (n, n, n));
    if n == 0 {
        return rep;
    }
    // Bookkeeping.
    assert_eq!(s.s[0], 0.0);
    assert_eq!(s.t[0], 0.0);
    assert!(s.v.iter().all(|v| v.is_finite() && *v >= 0.0));
    for i in 0..n - 1 {
        let ds = p[i].distance(p[i + 1]);
        assert!(
            (s.s[i + 1] - s.s[i] - ds).abs() <= 1e-9 * (1.0 + s.s[i + 1]),
            "arc length at {i}"
        );
        assert!(s.t[i + 1] >= s.t[i], "time goes back at {i}");
    }
    assert_eq!(s.total_time, s.t[n - 1]);
    assert_eq!(s.length, s.s[n - 1]);
    // Ends and corners at rest.
    rep.see(if s.v[0] == 0.0 { 0.0 } else { f64::INFINITY }, || {
        "v at start".into()
    });
    rep.see(
        if s.v[n - 1] == 0.0 {
            0.0
        } else {
            f64::INFINITY
        },
        || "v at end".into(),
    );
    for j in 0..n {
        if g.corner[j] {
            rep.see(if s.v[j] == 0.0 { 0.0 } else { f64::INFINITY }, || {
                format!("v at corner {j}")
            });
        }
    }
    for i in 0..n - 1 {
        let len = g.len[i];
        if len == 0.0 {
            continue;
        }
        let d = g.dir[i];
        let (v0, v1) = (s.v[i], s.v[i + 1]);
        let dt = s.t[i + 1] - s.t[i];
        // Feed cap at both ends, and the mean feed over the segment.
        rep.see(v0.max(v1) / caps[i], || format!("feed cap on segment {i}"));
        rep.see(len / dt / caps[i], || format!("mean feed on segment {i}"));
        // Per-axis velocity: at both end points along the segment, and the mean by finite
        // differences of the positions.
        for k in 0..3 {
            let vk = limits.v_max[k];
            rep.see(v0.max(v1) * d[k].abs() / vk, || {
                format!("axis {k} velocity at segment {i}")
            });
            rep.see((p[i + 1][k] - p[i][k]).abs() / dt / vk, || {
                format!("axis {k} mean velocity, segment {i}")
            });
        }
        // Tangential acceleration: from v² over s, and from v over t.
        let a_lim = (0..3)
            .filter(|&k| d[k].abs() > 1e-12)
            .map(|k| limits.a_max[k] / d[k].abs())
            .fold(f64::INFINITY, f64::min);
        let a_s = (v1 * v1 - v0 * v0) / (2.0 * len);
        rep.see(a_s.abs() / a_lim, || {
            format!("tangential acceleration (v²/2s) on segment {i}")
        });
        if dt > 0.0 {
            let a_t = (v1 - v0) / dt;
            rep.see(a_t.abs() / a_lim, || {
                format!("tangential acceleration (dv/dt) on segment {i}")
            });
        }
        // Per-axis acceleration, tangential plus normal, at both end points and inside the
        // segment, where the model has the curvature vector and v² linear in s between the
        // end points' values.
        for sigma in [0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0] {
            let c = g.curv[i].lerp(g.curv[i + 1], sigma);
            let u = v0 * v0 + (v1 * v1 - v0 * v0) * sigma;
            for k in 0..3 {
                let acc = d[k] * a_s + c[k] * u;
                rep.see(acc.abs() / limits.a_max[k], || {
                    format!("axis {k} acceleration at σ = {sigma} of segment {i}: {acc}")
                });
            }
        }
    }
    // Centripetal acceleration.
    for j in 1..n - 1 {
        let k = g.curv[j].length();
        rep.see(s.v[j] * s.v[j] * k / limits.a_centripetal, || {
            format!("centripetal at point {j}")
        });
    }
    rep
}

/// Per-axis acceleration by second differences of the positions over the scheduled times,
/// divided by the axis limit; the largest over the interior points with distinct times.
pub fn max_axis_accel_ratio_from_positions(
    p: &[DVec3],
    s: &Schedule,
    limits: &MachineLimits,
) -> f64 {
    let mut worst: f64 = 0.0;
    for j in 1..p.len() - 1 {
        let (dt0, dt1) = (s.t[j] - s.t[j - 1], s.t[j + 1] - s.t[j]);
        if dt0 <= 0.0 || dt1 <= 0.0 {
            continue;
        }
        let acc = 2.0 * ((p[j + 1] - p[j]) / dt1 - (p[j] - p[j - 1]) / dt0) / (dt0 + dt1);
        for k in 0..3 {
            worst = worst.max(acc[k].abs() / limits.a_max[k]);
        }
    }
    worst
}
