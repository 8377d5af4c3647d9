//! Machine motion model and time-optimal feed schedule.
//!
//! This is the time model with which every tool path of the project is measured: give it a
//! path (points in mm) and the commanded cutting-feed cap per segment, get back the speed at
//! every point and the time at which the tool gets there.
//!
//! # Algorithm
//!
//! A two-pass scheme (Bieterman & Sandstrom's setting, with TOPP-RA's backward controllable-set
//! and greedy forward passes), with arc length `s` as the independent variable and `u = v²`
//! as the state, so that constant tangential acceleration `a` is a straight line `du/ds = 2a`:
//!
//! 1. **Geometry.** Segment `i` runs from `points[i]` to `points[i+1]`; its unit direction
//!    `d_i` is the tangent along it. At every interior point the curvature vector
//!    `c_j = κ_j·n_j` is that of the circle through the point and its two neighbours
//!    (`κ = 1/R`, equal to the Menger curvature `2 sin θ / |p_{j+1} − p_{j−1}|` with θ the
//!    turning angle; `n` the unit vector from the point to the circle's centre). This is exact
//!    for points on a circle. A point whose turning angle
//!    exceeds [`MachineLimits::corner_angle_deg`] is a **corner**: the speed there is 0 and
//!    its curvature is not used (the kink is not a circle). The two path ends copy the
//!    curvature of their neighbour (a sampled curve continues), and have speed 0.
//! 2. **Speed caps.** Every point gets a cap on `u`: the feed caps and the per-axis velocity
//!    limits `min_k V_k/|d_k|` of the segments that meet there, the centripetal cap
//!    `A_c/κ_j`, and 0 at the ends and corners.
//! 3. **Segment constraints.** Between two points `u` is linear in `s` (constant tangential
//!    acceleration `a = (u_{i+1} − u_i)/2Δs`) and so is the curvature vector (from `c_i` to
//!    `c_{i+1}`, the sampled curve's curvature between its samples). The segment requires
//!    `|a| ≤ min_k A_k/|d_k|` and, on every axis and at every point of the segment,
//!    `|d_k·a + c_k(σ)·u(σ)| ≤ A_k`. `c_k(σ)·u(σ)` is a quadratic in σ whose Bernstein
//!    coefficients are `c_ik·u_i`, `(c_ik·u_{i+1} + c_{i+1,k}·u_i)/2` and `c_{i+1,k}·u_{i+1}`;
//!    requiring the bound on all three (convex hull property) is linear in `(u_i, u_{i+1})`
//!    and sufficient, exact at the end points and within O(spacing²) inside. `(0, 0)` is
//!    always feasible. A constraint whose two coefficients have the same sign (a higher
//!    `u_i` forces a lower `u_{i+1}`: the curvature term outweighs the discretised tangential
//!    one, on an axis nearly normal to the path or next to a long segment) is replaced by the
//!    separable pair `u_i, u_{i+1} ≤ A_k/|α + β|` (its constant-speed point, conservative).
//!    The feasible set is then a lattice: the greedy passes below give its greatest element,
//!    time-optimal for the discretisation and monotone in the limits (a slower machine is
//!    never faster). Each end speed sees its own end's curvature only (applying either
//!    end's at both is conservative by O(spacing), 2–3 % on the pocket spirals).
//! 4. **Backward pass** (controllable sets, as TOPP-RA): from `u_{n−1} = 0`, the largest `u_i`
//!    for which some `u_{i+1}` in `[0, hi_{i+1}]` satisfies segment i's constraints — a
//!    two-variable LP, solved in closed form by eliminating `u_{i+1}` (Fourier–Motzkin over
//!    the ≤ 14 lower and upper bounds). Every controllable set is `[0, hi_i]`.
//! 5. **Forward pass** (greedy): `u_0 = 0`, and `u_{i+1}` the largest value in
//!    `[0, hi_{i+1}]` allowed by segment i's constraints at `u_i` (non-empty because
//!    `u_i ≤ hi_i`). There is no cruise-feasible cap: the speed may exceed the speed at which
//!    zero tangential acceleration is possible wherever accelerating (braking) unloads the
//!    saturated axis, e.g. at arc exits and entries — the maximum-velocity curve is implied by
//!    the constraints.
//! 6. **Time.** Per segment, the least of the ramp time `2Δs/(v_i + v_{i+1})` and the fastest
//!    profile inside the segment between the two end speeds: on a straight segment
//!    accelerate–cruise–decelerate at `±min_k A_k/|d_k|`; on a curved one the exact optimum
//!    `u(σ) = min(F(σ), B(σ), vc_i²)` under the conservative in-segment model (curvature of
//!    either end at every speed; `vc_i²` the segment's cap lowered to the cruise-feasible
//!    normal cap `min_k A_k/|c_jk|` and `A_c/κ_j` of both ends), where `F` accelerates from
//!    `u_i` at the largest acceleration `a⁺(u)` (a concave piecewise-linear function of `u`)
//!    and `B` decelerates into `u_{i+1}`: closed form per linear piece, the meeting level by
//!    safeguarded Newton; where that model cannot connect the end speeds, `max(ramp, F)`.
//!    An end speed above `vc_i²` is lowered to it for this profile (the machine can follow
//!    `max(ramp, profile)`, faster than either, so the time is an upper bound that falls with
//!    the limits). A constant acceleration up to the cap would be a heuristic whose rate
//!    falls as the cap rises, so a faster machine could come out slower.
//!    Long straight segments are thus timed exactly, however coarse the point spacing.
//!
//! **Tangential acceleration (the choice the design leaves open).** The available tangential
//! acceleration is *reduced by the normal acceleration already in use*, axis by axis, as in
//! TOPP-RA's per-axis `JointAccelerationConstraint`; without it curved paths would break the
//! axis limits. The tangential acceleration also never exceeds `min_k A_k/|d_k|` even where the
//! normal acceleration on an axis points against it and the coupled bound alone would allow
//! more (the curvature is a three-point estimate; this keeps "tangential ≤ min_k A_k/|d_k|"
//! true on its own, at a cost of about 0.4 % on a circle against TOPP-RA, which does exploit
//! it). The centripetal cap `A_c` caps only the normal acceleration and does not take from the
//! tangential budget.
//!
//! Known approximations (measured against TOPP-RA, see the README): that tangential cap
//! (conservative), and the three-point curvature: exact on circles, but at
//! a curvature jump (a line meeting an arc) the junction sample gets a curvature between the
//! two, so the schedule is slightly *optimistic* there (rounded pentagon R60 r10 at 1 mm
//! spacing: 0.2 % faster than its fine-sampling limit). The time converges about linearly
//! under refinement (`tests/optimality.rs`).
//!
//! Cost: five linear passes over the points (two of them solving a small LP per segment) and
//! one scratch allocation besides the three output vectors; over a million points per second
//! in release (see the README).
//!
//! # Conventions
//!
//! Units: mm, s, mm/s, mm/s². Segments shorter than [`DEGENERATE_LEN`] are treated as
//! repeated points: they take no time, impose no direction, and are skipped when the turning
//! angle and curvature of their neighbours are computed (so a corner with a duplicated point
//! is still a corner).

use glam::DVec3;
use serde::{Deserialize, Serialize};

pub mod paths;

/// Segments shorter than this (mm) are repeated points: no direction, no time.
pub const DEGENERATE_LEN: f64 = 1e-9;

/// Per-axis limits of the machine (mm/s, mm/s²), plus a centripetal acceleration cap and the
/// angle above which a path junction is a corner where the feed must drop to zero.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MachineLimits {
    /// Maximum axis velocity X, Y, Z (mm/s), each > 0.
    pub v_max: [f64; 3],
    /// Maximum axis acceleration (and deceleration) X, Y, Z (mm/s²), each > 0.
    pub a_max: [f64; 3],
    /// Cap on the centripetal (normal) acceleration v²κ (mm/s²), > 0; `f64::INFINITY` disables it.
    pub a_centripetal: f64,
    /// Turning angle (degrees) above which a junction is a corner with v = 0.
    pub corner_angle_deg: f64,
}

impl MachineLimits {
    /// A typical high-speed milling machine: 500 mm/s (30 m/min) and 5000 mm/s² (0.5 g) per
    /// axis, centripetal cap 5000 mm/s², corners above 30°. `D = V²/(2A) = 25 mm`.
    pub fn typical_hsm() -> Self {
        Self {
            v_max: [500.0; 3],
            a_max: [5000.0; 3],
            a_centripetal: 5000.0,
            corner_angle_deg: 30.0,
        }
    }

    /// Bieterman's `D = V²/(2A)`: the distance to reach full speed from rest, here for the
    /// slowest-to-accelerate of the X and Y axes.
    pub fn accel_distance(&self) -> f64 {
        (0..2)
            .map(|k| self.v_max[k] * self.v_max[k] / (2.0 * self.a_max[k]))
            .fold(0.0, f64::max)
    }

    fn assert_valid(&self) {
        for k in 0..3 {
            assert!(
                self.v_max[k] > 0.0 && self.a_max[k] > 0.0,
                "MachineLimits: v_max and a_max must be > 0 (axis {k}: {} mm/s, {} mm/s²)",
                self.v_max[k],
                self.a_max[k]
            );
        }
        assert!(
            self.a_centripetal > 0.0,
            "MachineLimits: a_centripetal must be > 0 (use f64::INFINITY to disable)"
        );
        assert!(
            self.corner_angle_deg.is_finite() && self.corner_angle_deg >= 0.0,
            "MachineLimits: corner_angle_deg must be finite and >= 0"
        );
    }
}

impl Default for MachineLimits {
    fn default() -> Self {
        Self::typical_hsm()
    }
}

/// A feed schedule: speed and time at every path point.
///
/// Between two points the speed follows the accelerate–cruise–decelerate profile described in
/// the crate documentation, so it may exceed both end-point speeds inside a long segment; the
/// times are exact for that profile. For an NC program use [`Schedule::segment_feed`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// Arc length at each point (mm), `s[0] = 0`.
    pub s: Vec<f64>,
    /// Speed at each point (mm/s).
    pub v: Vec<f64>,
    /// Time at each point (s), `t[0] = 0`.
    pub t: Vec<f64>,
    /// Time to run the whole path (s), `t.last()`.
    pub total_time: f64,
    /// Path length (mm), `s.last()`.
    pub length: f64,
}

impl Schedule {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.s.len()
    }

    /// True for an empty path.
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Mean feed over segment `i` (mm/s): `Δs/Δt`, the F word that gives the same time.
    /// 0 for a segment of zero length.
    pub fn segment_feed(&self, i: usize) -> f64 {
        let ds = self.s[i + 1] - self.s[i];
        let dt = self.t[i + 1] - self.t[i];
        if dt > 0.0 {
            ds / dt
        } else {
            0.0
        }
    }
}

/// Schedule a path with one feed cap for all segments.
///
/// # Panics
/// As [`schedule_polyline`].
pub fn schedule_polyline_uniform(points: &[DVec3], feed: f64, limits: &MachineLimits) -> Schedule {
    let caps = vec![feed; points.len().saturating_sub(1)];
    schedule_polyline(points, &caps, limits)
}

/// Per-point scratch: the outgoing segment and the point's curvature.
#[derive(Clone, Copy)]
struct Work {
    /// Unit direction of segment i (zero when degenerate).
    d: DVec3,
    /// Length of segment i.
    len: f64,
    /// Cruise cap² of segment i.
    vc2: f64,
    /// Curvature vector at point i (first pass: the incoming segment vector).
    c: DVec3,
    /// Speed cap² at point i.
    cap2: f64,
    /// Tangential acceleration limit of segment i alone, `min_k A_k/|d_ik|`.
    a_tan: f64,
}

/// Time-optimal feed schedule along a polyline (two passes, O(n); see the crate
/// documentation for the exact motion model).
///
/// `feed_cap[i]` caps the speed on the segment from `points[i]` to `points[i+1]` (mm/s).
///
/// # Panics
/// If `feed_cap.len() != points.len() - 1` (for a non-empty path), if a feed cap is not > 0
/// (NaN included), or if `limits` are not positive.
pub fn schedule_polyline(points: &[DVec3], feed_cap: &[f64], limits: &MachineLimits) -> Schedule {
    limits.assert_valid();
    let n = points.len();
    if n == 0 {
        return Schedule::default();
    }
    assert_eq!(
        feed_cap.len(),
        n - 1,
        "schedule_polyline: need one feed cap per segment ({} points, {} caps)",
        n,
        feed_cap.len()
    );
    let mut s = Vec::with_capacity(n);
    let mut u = Vec::with_capacity(n);
    let mut t = Vec::with_capacity(n);
    if n == 1 {
        return Schedule {
            s: vec![0.0],
            v: vec![0.0],
            t: vec![0.0],
            total_time: 0.0,
            length: 0.0,
        };
    }

    let zero = Work {
        d: DVec3::ZERO,
        len: 0.0,
        vc2: f64::INFINITY,
        c: DVec3::ZERO,
        cap2: f64::INFINITY,
        a_tan: f64::INFINITY,
    };
    let mut w = vec![zero; n];

    // Pass 1 (forward): segments, arc length, and for each point the incoming segment vector
    // (skipping degenerate segments) stored provisionally in `c`.
    let mut acc = 0.0;
    let mut incoming = DVec3::ZERO;
    s.push(0.0);
    for i in 0..n - 1 {
        let f = feed_cap[i];
        assert!(
            f > 0.0,
            "schedule_polyline: feed cap of segment {i} must be > 0, got {f}"
        );
        let delta = points[i + 1] - points[i];
        let len = delta.length();
        acc += len;
        s.push(acc);
        let wi = &mut w[i];
        wi.c = incoming;
        if len > DEGENERATE_LEN {
            wi.d = delta / len;
            wi.len = len;
            incoming = delta;
        }
        wi.vc2 = f * f;
    }
    w[n - 1].c = incoming;

    // Pass 2 (backward): curvature vector and corners, with the outgoing segment vector carried.
    let cos_corner = limits.corner_angle_deg.to_radians().cos();
    let mut outgoing = DVec3::ZERO;
    for j in (0..n).rev() {
        if j + 1 < n && w[j].len > 0.0 {
            outgoing = w[j].d * w[j].len;
        }
        let a = w[j].c;
        let mut c = DVec3::ZERO;
        if j > 0 && j + 1 < n && a != DVec3::ZERO && outgoing != DVec3::ZERO {
            let (la, lb) = (a.length(), outgoing.length());
            let (da, db) = (a / la, outgoing / lb);
            let cos = da.dot(db);
            if cos < cos_corner {
                w[j].cap2 = 0.0;
            } else {
                // Circle through the three points: its centre relative to the previous
                // point, from the two chords `a` and `a + outgoing`.
                let chord = a + outgoing;
                let cr = a.cross(outgoing);
                let cr2 = cr.length_squared();
                if cr2 > 1e-30 * (la * lb).powi(2) {
                    let centre = (chord.length_squared() * cr.cross(a) + la * la * chord.cross(cr))
                        / (2.0 * cr2);
                    let to_centre = centre - a;
                    c = to_centre / to_centre.length_squared();
                }
            }
        }
        w[j].c = c;
    }
    w[0].cap2 = 0.0;
    w[n - 1].cap2 = 0.0;
    if n >= 3 {
        // The ends continue the curve of their neighbour (not across a corner: c = 0 there).
        w[0].c = w[1].c;
        w[n - 1].c = w[n - 2].c;
    }

    // Pass 3: segment caps and point caps. `seg2` (feed and per-axis velocity) caps the speed
    // at both end points; `vc2` adds the cruise-feasible normal cap and is used only for the
    // accelerate–cruise–decelerate profile inside a segment.
    let inv_v: [f64; 3] = std::array::from_fn(|k| 1.0 / limits.v_max[k]);
    for i in 0..n - 1 {
        let wi = w[i];
        let mut seg2 = wi.vc2;
        if wi.len > 0.0 {
            // Per-axis velocity along the segment: v·|d_k| ≤ V_k.
            let r = (wi.d.x.abs() * inv_v[0])
                .max(wi.d.y.abs() * inv_v[1])
                .max(wi.d.z.abs() * inv_v[2]);
            seg2 = seg2.min(1.0 / (r * r));
            let mut vc2 = seg2;
            for c in [wi.c, w[i + 1].c] {
                vc2 = vc2.min(normal_cap2(c, limits));
            }
            w[i].vc2 = vc2;
            w[i].a_tan = (0..3)
                .filter(|&k| wi.d[k].abs() >= 1e-12)
                .map(|k| limits.a_max[k] / wi.d[k].abs())
                .fold(f64::INFINITY, f64::min);
        }
        w[i].cap2 = w[i].cap2.min(seg2);
        w[i + 1].cap2 = w[i + 1].cap2.min(seg2);
    }
    for wj in w.iter_mut() {
        let kappa = wj.c.length();
        if kappa > 0.0 {
            wj.cap2 = wj.cap2.min(limits.a_centripetal / kappa);
        }
    }

    // Pass 4 (backward): controllable sets. `u[i]` holds the largest u_i from which the end
    // can still be reached at rest; every such set is [0, u_i] since (0, 0) is feasible on
    // every segment.
    u.resize(n, 0.0);
    u[n - 1] = 0.0;
    for i in (0..n - 1).rev() {
        let hi = u[i + 1];
        let x = if w[i].len > 0.0 {
            let (cons, m) = segment_constraints(&w[i], &w[i + 1].c, limits);
            max_start(&cons[..m], hi, w[i].cap2)
        } else {
            hi
        };
        u[i] = x.min(w[i].cap2).max(0.0);
    }
    // Pass 5 (forward): greedy, the largest u_{i+1} in its controllable set reachable from u_i.
    u[0] = 0.0;
    for i in 0..n - 1 {
        let hi = u[i + 1];
        let y = if w[i].len > 0.0 {
            let (cons, m) = segment_constraints(&w[i], &w[i + 1].c, limits);
            max_end(&cons[..m], u[i], hi)
        } else {
            u[i].min(hi)
        };
        u[i + 1] = y.max(0.0);
    }

    // Pass 6: time, speeds.
    let mut time = 0.0;
    t.push(0.0);
    for i in 0..n - 1 {
        let wi = &w[i];
        if wi.len > 0.0 {
            time += segment_time_any(u[i], u[i + 1], wi, &w[i + 1].c, limits);
        }
        t.push(time);
        u[i] = u[i].max(0.0).sqrt();
    }
    u[n - 1] = u[n - 1].max(0.0).sqrt();
    Schedule {
        s,
        v: u,
        t,
        total_time: time,
        length: acc,
    }
}

/// Speed² cap from a curvature vector: centripetal cap and per-axis normal acceleration.
#[inline]
fn normal_cap2(c: DVec3, limits: &MachineLimits) -> f64 {
    let kappa = c.length();
    if kappa == 0.0 {
        return f64::INFINITY;
    }
    let mut cap = limits.a_centripetal / kappa;
    for k in 0..3 {
        let ck = c[k].abs();
        if ck > 0.0 {
            cap = cap.min(limits.a_max[k] / ck);
        }
    }
    cap
}

/// Linear constraints `α·u_i + β·u_{i+1} ≤ γ` on segment `w` (from point i to i+1) for a
/// constant tangential acceleration `a = (u_{i+1} − u_i)/2Δs` (`u` linear in `s`):
/// `|a| ≤ min_k A_k/|d_k|`, and on every axis `|d_k·a + c_k(σ)·u(σ)| ≤ A_k` along the
/// segment with the curvature linear between its end points (Bernstein coefficients).
#[inline]
fn segment_constraints(
    w: &Work,
    c_far: &DVec3,
    limits: &MachineLimits,
) -> ([(f64, f64, f64); 26], usize) {
    let mut out = [(0.0, 0.0, 0.0); 26];
    let mut m = 0;
    let l2 = 2.0 * w.len;
    if w.a_tan.is_finite() {
        out[0] = (-1.0, 1.0, l2 * w.a_tan);
        out[1] = (1.0, -1.0, l2 * w.a_tan);
        m = 2;
    }
    for k in 0..3 {
        let ak = limits.a_max[k];
        let q = w.d[k] / l2;
        let (c0, c1) = (w.c[k], c_far[k]);
        // d_k·a + c_k(σ)·u(σ) with c and u linear in σ is a quadratic whose Bernstein
        // coefficients are d_k·a plus c0·x, (c0·y + c1·x)/2 and c1·y: keeping all three
        // within ±A_k keeps the whole segment within (convex hull property).
        let mut push = |ax: f64, by: f64| {
            if (ax > 0.0 && by > 0.0) || (ax < 0.0 && by < 0.0) {
                // Coupled: a higher u_i would force a lower u_{i+1}, and the greedy forward
                // pass is then neither optimal nor monotone in the limits. Replace
                // |ax·x + by·y| ≤ A_k by the separable x, y ≤ A_k/|ax + by| (the constant-speed
                // point of the line, so conservative): the feasible set stays a lattice.
                let g = ak / (ax + by).abs();
                out[m] = (1.0, 0.0, g);
                out[m + 1] = (0.0, 1.0, g);
            } else {
                out[m] = (ax, by, ak);
                out[m + 1] = (-ax, -by, ak);
            }
            m += 2;
        };
        if c0 != 0.0 {
            push(c0 - q, q); // at u_i, own curvature
        }
        if c1 != 0.0 {
            push(-q, q + c1); // at u_{i+1}, own curvature
        }
        if c0 != c1 {
            push(0.5 * c1 - q, q + 0.5 * c0); // middle coefficient (implied when c0 = c1)
        }
    }
    (out, m)
}

/// Largest `x ≤ x_cap` for which some `y` in `[0, y_hi]` satisfies all the constraints
/// (Fourier–Motzkin elimination of `y`). `(0, 0)` is always feasible, so the feasible `x`
/// form the interval `[0, result]`.
#[inline]
fn max_start(cons: &[(f64, f64, f64)], y_hi: f64, x_cap: f64) -> f64 {
    let mut x_max = x_cap;
    let mut up = [(0.0, 1.0, y_hi); 27];
    let mut lo = [(0.0, -1.0, 0.0); 27];
    let (mut nu, mut nl) = (1, 1);
    for &(a, b, g) in cons {
        if b > 0.0 {
            up[nu] = (a, b, g);
            nu += 1;
        } else if b < 0.0 {
            lo[nl] = (a, b, g);
            nl += 1;
        } else if a > 0.0 {
            x_max = x_max.min(g / a);
        }
    }
    for &(ap, bp, gp) in &lo[..nl] {
        for &(aq, bq, gq) in &up[..nu] {
            // bq·(p) − bp·(q): (ap·bq − aq·bp)·x ≤ gp·bq − gq·bp.
            let d = ap * bq - aq * bp;
            if d > 0.0 {
                x_max = x_max.min((gp * bq - gq * bp) / d);
            }
        }
    }
    x_max.max(0.0)
}

/// Largest `y ≤ y_hi` allowed by the constraints at `x` (the greedy forward step).
#[inline]
fn max_end(cons: &[(f64, f64, f64)], x: f64, y_hi: f64) -> f64 {
    let mut y = y_hi;
    for &(a, b, g) in cons {
        if b > 0.0 {
            y = y.min((g - a * x) / b);
        }
    }
    y
}

/// Time over segment `w` between end speeds² `u0` and `u1`: the constant-acceleration ramp
/// (`u` linear in `s`, which the segment constraints make feasible), or the fastest profile
/// inside the segment when it is faster (straight: accelerate–cruise–decelerate; curved: see
/// [`curved_segment_time`]).
#[inline]
fn segment_time_any(u0: f64, u1: f64, w: &Work, c_far: &DVec3, limits: &MachineLimits) -> f64 {
    let (v0, v1) = (u0.sqrt(), u1.sqrt());
    let ramp = if v0 + v1 > 0.0 {
        2.0 * w.len / (v0 + v1)
    } else {
        f64::INFINITY
    };
    // An end above the in-segment cap (possible where accelerating unloads the saturated
    // axis): the in-segment profile is computed from the end speed lowered to the cap. The
    // machine can follow max(ramp, that profile), which is faster than either, so the time
    // stays an upper bound, and it falls with the limits.
    let (u0, u1) = (u0.min(w.vc2), u1.min(w.vc2));
    // No profile is faster than the segment at the highest speed it can reach: skip the
    // search where the ramp already achieves that bound.
    let peak = w
        .vc2
        .min(u0.min(u1) + 2.0 * w.a_tan * w.len)
        .max(u0.max(u1));
    if ramp <= w.len / peak.sqrt() {
        return ramp;
    }
    if w.c == DVec3::ZERO && *c_far == DVec3::ZERO {
        // Straight: ±a_tan whatever the speed, accelerate–cruise–decelerate in closed form.
        let a = w.a_tan;
        let slack = 1.0 + 1e-12;
        if u1 <= (u0 + 2.0 * a * w.len) * slack && u0 <= (u1 + 2.0 * a * w.len) * slack {
            return ramp.min(segment_time(u0, u1, w.vc2, a, a, w.len));
        }
        return ramp;
    }
    ramp.min(curved_segment_time(u0, u1, w, c_far, limits))
}

/// The lines `(α, β)` whose lower envelope `a⁺(u) = min(α − β·u)` is the largest tangential
/// acceleration (`dir = 1`; deceleration towards the end for `dir = -1`) at speed² `u` on a
/// curved segment: `a_tan`, and on every axis `|d_k|·a + σ·u ≤ A_k` with the curvature of
/// either end point (lines with σ ≤ 0 never go below `a_tan` and are left out).
#[inline]
fn accel_lines(
    w: &Work,
    c_far: &DVec3,
    dir: f64,
    limits: &MachineLimits,
) -> ([(f64, f64); 7], usize) {
    let mut out = [(w.a_tan, 0.0); 7];
    let mut n = 1;
    for k in 0..3 {
        let dk = w.d[k];
        let adk = dk.abs();
        if adk < 1e-12 {
            continue; // no tangential share on this axis: a speed cap, in vc²
        }
        for ck in [w.c[k], c_far[k]] {
            let sigma = dir * dk.signum() * ck;
            if sigma > 0.0 {
                out[n] = (limits.a_max[k] / adk, sigma / adk);
                n += 1;
            }
        }
    }
    (out, n)
}

/// Distance and time to go from speed² `us` up to `ut` accelerating at `a⁺(u)` (the lower
/// envelope of `lines`), in closed form per line: `ds = du/2a`, `dt = dw/a` with `w = √u`.
#[inline]
fn climb(lines: &[(f64, f64)], us: f64, ut: f64) -> (f64, f64) {
    if ut <= us {
        return (0.0, 0.0);
    }
    let val = |l: (f64, f64), u: f64| l.0 - l.1 * u;
    let mut cur = lines[0];
    for &l in &lines[1..] {
        let (a, b) = (val(l, us), val(cur, us));
        if a < b || (a == b && l.1 > cur.1) {
            cur = l;
        }
    }
    let (mut u, mut dist, mut time) = (us, 0.0, 0.0);
    loop {
        // the envelope is concave: the next line to take over is steeper
        let mut end = ut;
        let mut next = None;
        for &l in lines {
            if l.1 > cur.1 {
                let x = (l.0 - cur.0) / (l.1 - cur.1);
                if x > u && x < end {
                    end = x;
                    next = Some(l);
                }
            }
        }
        let (d, t) = climb_line(cur, u, end);
        dist += d;
        time += t;
        match next {
            Some(l) => {
                cur = l;
                u = end;
            }
            None => return (dist, time),
        }
    }
}

/// [`climb`] along one line `a = α − β·u` (β ≥ 0) from `ua` to `ub`.
#[inline]
fn climb_line((alpha, beta): (f64, f64), ua: f64, ub: f64) -> (f64, f64) {
    let gb = alpha - beta * ub;
    if gb <= 0.0 {
        return (f64::INFINITY, f64::INFINITY); // the acceleration runs out before ub
    }
    let (wa, wb) = (ua.sqrt(), ub.sqrt());
    if beta == 0.0 {
        return ((ub - ua) / (2.0 * alpha), (wb - wa) / alpha);
    }
    let half_log = 0.5 * (beta * (ub - ua) / gb).ln_1p(); // ½·ln(g(ua)/g(ub))
    let dist = half_log / beta;
    // ∫ dw/(α − βw²) = (artanh(r·wb) − artanh(r·wa))/√(αβ) with r = √(β/α), written as
    // ln((1 + r·wb)/(1 + r·wa)) + ½·ln(g(ua)/g(ub)): no cancellation, no rounding past 1
    let r = (beta / alpha).sqrt();
    let time = ((r * (wb - wa) / (1.0 + r * wa)).ln_1p() + half_log) / (alpha * beta).sqrt();
    (dist, time)
}

/// Where the conservative in-segment model cannot connect the end speeds (the ramp between
/// them is feasible only under the segment constraints, with curvature linear along the
/// segment): the profile `max(ramp, F)` accelerating from the lower end speed at `a⁺(u)`
/// (`lines`) while that is above the ramp, then on the ramp — feasible piece by piece, and
/// higher than either for given end speeds, so still never slower for a faster machine.
/// For `u0 > u1` the same, mirrored (`lines` then the deceleration lines).
fn ramp_hybrid_time(u0: f64, u1: f64, lines: &[(f64, f64)], ds: f64) -> f64 {
    let (lo, hi) = (u0.min(u1), u0.max(u1));
    let ramp = |ua: f64, ub: f64, d: f64| {
        let v = ua.sqrt() + ub.sqrt();
        if v > 0.0 {
            2.0 * d / v
        } else {
            f64::INFINITY
        }
    };
    let a_at = |u: f64| {
        lines
            .iter()
            .map(|l| l.0 - l.1 * u)
            .fold(f64::INFINITY, f64::min)
    };
    let slope = (hi - lo) / ds; // du/dσ of the ramp
    if hi <= lo || 2.0 * a_at(lo) <= slope {
        return ramp(lo, hi, ds);
    }
    // g(u) = distance for F to reach u − distance for the ramp: convex, g(lo) = 0, g'(lo) < 0,
    // g(hi) > 0 (F cannot reach hi in ds): its other root by Newton from hi (from the right,
    // monotone), bisection as a safeguard.
    let g = |u: f64| climb(lines, lo, u).0 - (u - lo) / slope;
    let (mut a, mut b) = (lo, hi);
    let mut u = hi;
    let mut gu = f64::INFINITY;
    for _ in 0..200 {
        gu = g(u);
        if gu > 0.0 {
            b = u;
        } else {
            a = u;
        }
        // Stop on the residual or the bracket, never on a short step: near the level where
        // a⁺ runs out, g' is huge and Newton crawls (it stopped at hi there, timing F
        // itself, and a faster machine came out slower).
        if gu.abs() <= 1e-13 * ds || b - a <= 1e-14 * b {
            break;
        }
        let d = 0.5 / a_at(u) - 1.0 / slope;
        let mut un = if d > 0.0 { u - gu / d } else { 0.5 * (a + b) };
        if !(un > a && un < b) || (un - u).abs() < 1e-3 * (b - a) {
            un = 0.5 * (a + b);
        }
        u = un;
    }
    // The crossing, to rounding; else the bracket's lower end (F has reached it before the
    // ramp), not its upper end, which may be the level F reaches only asymptotically.
    let u = if gu.abs() <= 1e-13 * ds { u } else { a };
    let (dist, time) = climb(lines, lo, u);
    let dist = dist.min(ds);
    time + ramp(u, hi, ds - dist)
}

/// Fastest time over a curved segment between end speeds² `u0` and `u1` under the
/// conservative in-segment model (both end curvatures at every speed, speed² ≤ vc²):
/// `u(σ) = min(F(σ), B(σ), vc²)` with `F` accelerating from `u0` at `a⁺(u)` and `B`
/// decelerating into `u1`, both solved in closed form, their meeting level by safeguarded
/// Newton (the distance to reach a level is convex in it). Where that model cannot connect the
/// end speeds, [`ramp_hybrid_time`]. The exact optimum of a problem whose constraints only
/// loosen with the limits, so a faster machine is never slower here for given end speeds.
fn curved_segment_time(u0: f64, u1: f64, w: &Work, c_far: &DVec3, limits: &MachineLimits) -> f64 {
    let (lf, nf) = accel_lines(w, c_far, 1.0, limits);
    let (lb, nb) = accel_lines(w, c_far, -1.0, limits);
    let (lf, lb) = (&lf[..nf], &lb[..nb]);
    let ds = w.len;
    let cap = w.vc2;
    let reach = |u: f64| {
        let (df, tf) = climb(lf, u0, u);
        let (db, tb) = climb(lb, u1, u);
        (df + db, tf + tb)
    };
    let lo = u0.max(u1);
    let (d_lo, t_lo) = reach(lo);
    if d_lo > ds * (1.0 + 1e-12) {
        return ramp_hybrid_time(u0, u1, if u1 >= u0 { lf } else { lb }, ds);
    }
    if d_lo >= ds {
        return t_lo;
    }
    if cap.is_finite() {
        let (d_cap, t_cap) = reach(cap);
        if d_cap <= ds {
            return t_cap + (ds - d_cap) / cap.sqrt(); // reaches the cap and cruises
        }
    }
    let a_at = |lines: &[(f64, f64)], u: f64| {
        lines
            .iter()
            .map(|l| l.0 - l.1 * u)
            .fold(f64::INFINITY, f64::min)
    };
    let (mut a, mut b) = (lo, cap); // reach(a) < ds < reach(b)
    let mut u = lo;
    let mut d = d_lo;
    let mut t = t_lo;
    for _ in 0..100 {
        let slope = 0.5 / a_at(lf, u) + 0.5 / a_at(lb, u);
        let mut un = u + (ds - d) / slope;
        if !(un > a && un < b) {
            un = 0.5 * (a + b);
        }
        if (un - u).abs() <= 1e-14 * u {
            break;
        }
        u = un;
        (d, t) = reach(u);
        if d <= ds {
            a = u;
        } else {
            b = u;
        }
    }
    // a cruise at u covers what is left (d ≤ ds) or the profile overshoots by rounding
    t + (ds - d).max(0.0) / u.sqrt()
}

/// Time over a segment of length `ds` with end speeds² `u0`, `u1`, cruise cap² `vc2`,
/// acceleration `a` from the start and deceleration `b` into the end:
/// `u(σ) = min(u0 + 2aσ, vc2, u1 + 2b(ds − σ))`.
#[inline]
fn segment_time(u0: f64, u1: f64, vc2: f64, a: f64, b: f64, ds: f64) -> f64 {
    let (v0, v1) = (u0.sqrt(), u1.sqrt());
    if a + b <= 0.0 {
        // No acceleration either way: u0 = u1, constant speed.
        let v = v0.max(v1);
        return if v > 0.0 { ds / v } else { f64::INFINITY };
    }
    // Where the acceleration and deceleration lines meet (distances are computed from the
    // sum a + b, never from one tiny rate alone, which would amplify rounding in u).
    let x = ((u1 - u0 + 2.0 * b * ds) / (2.0 * (a + b))).clamp(0.0, ds);
    let peak = u0 + 2.0 * a * x;
    if peak > vc2 && a > 0.0 && b > 0.0 {
        // Accelerate to the cruise cap, cruise, decelerate.
        let d1 = ((vc2 - u0) / (2.0 * a)).max(0.0);
        let d3 = ((vc2 - u1) / (2.0 * b)).max(0.0);
        if d1 + d3 <= ds {
            let vc = vc2.sqrt();
            return 2.0 * d1 / (v0 + vc) + (ds - d1 - d3) / vc + 2.0 * d3 / (vc + v1);
        }
    }
    let vp = peak.min(vc2.max(u0).max(u1)).max(u0).max(u1).sqrt();
    let mut t = 0.0;
    if x > 0.0 {
        t += 2.0 * x / (v0 + vp);
    }
    if ds - x > 0.0 {
        t += 2.0 * (ds - x) / (vp + v1);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_time_pieces() {
        // Pure acceleration from rest: t = 2d/v.
        let t = segment_time(0.0, 100.0, 1e9, 50.0, 50.0, 1.0);
        assert!((t - 0.2).abs() < 1e-12);
        // Rest to rest, a = b = 1, ds = 2: peak at 1 → u = 2, t = 2·sqrt(2).
        let t = segment_time(0.0, 0.0, 1e9, 1.0, 1.0, 2.0);
        assert!((t - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        // With a cruise cap of 1: accel 0.5, cruise 1, decel 0.5 → 1 + 1 + 1.
        let t = segment_time(0.0, 0.0, 1.0, 1.0, 1.0, 2.0);
        assert!((t - 3.0).abs() < 1e-12);
    }

    #[test]
    fn tiny_inputs() {
        let l = MachineLimits::typical_hsm();
        assert!(schedule_polyline_uniform(&[], 100.0, &l).is_empty());
        let one = schedule_polyline_uniform(&[DVec3::ONE], 100.0, &l);
        assert_eq!((one.len(), one.total_time), (1, 0.0));
        let same = schedule_polyline_uniform(&[DVec3::ONE, DVec3::ONE], 100.0, &l);
        assert_eq!(same.total_time, 0.0);
    }
}
