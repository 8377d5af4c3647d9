//! Tool engagement measured on the material, independent of how a path was made.
//!
//! A path (tool-centre points in order; arcs already sampled) is replayed over stock that
//! starts uncut everywhere (a closed pocket: the walls are stock too, so a path that strays
//! past the offset boundary is charged for the wall it cuts). The material removed so far is
//! the union of the capsules of radius R = D/2 about the path's segments (the exact swept
//! area of a disc moving along a polyline), held in a uniform grid of buckets of side R/2 (a
//! raster over the floor region; each bucket lists the capsules that reach into it).
//!
//! At each tool position `p` (every vertex of the path and points in between, at most
//! `step × D` apart), with `t` the direction of motion into `p` and `n` its left normal:
//!
//! * **engagement angle** φ: the length (as an angle) of the part of the tool's circumference
//!   that borders uncut material and advances into it: the circumference points
//!   `p + R·(cos θ·t + sin θ·n)`, θ ∈ (−90°, 90°) (the front half: the back half recedes and
//!   cannot meet material a continuously moving tool has not already removed), that lie
//!   outside the material removed up to the previous position. A slot through uncut stock
//!   gives 180°; a straight pass at radial width a beside a straight wall, acos(1 − 2a/D).
//!   Measured with `probes` points on the front half: resolution 180°/`probes`.
//! * **radial engagement** a_e: the width across the motion of the engaged part of the
//!   circumference, `max n·(q − p) − min n·(q − p)` over its engaged points q (D for a slot, a
//!   for the pass beside a wall; 0 where nothing is engaged).
//!
//! The swept area is exact for a polyline, so thin chips are resolved: a boolean raster of
//! cell h cannot see a chip thinner than h, which at the arc ends of a slot (chip thickness
//! step·cos θ) would cut off the arc where it thins below h.
//!
//! **Entry.** Where the tool enters, the whole disc is uncut (a plunge, helix or ramp: 360°,
//! not informative). The entry is excluded by clearing it before the replay: a disc of radius
//! R at the first point (a plunge) or, for a path that starts with a helix (FreeCAD
//! Adaptive; our spirals as stage 7 enters them), the exact disc of radius r_helix + R about
//! the helix centre; positions are measured from the first move out of it.

use glam::DVec2;

use crate::geom::dist2_point_seg;
use serde::{Deserialize, Serialize};

/// Resolution of the measure.
#[derive(Debug, Clone, Copy)]
pub struct EngagementParams {
    /// Largest distance between measured positions, in tool diameters.
    pub step: f64,
    /// Probe points on the front half of the circumference (angle resolution 180°/probes).
    pub probes: usize,
}

impl Default for EngagementParams {
    /// Positions every D/40, 0.5° angle resolution.
    fn default() -> Self {
        EngagementParams {
            step: 1.0 / 40.0,
            probes: 360,
        }
    }
}

/// The material cleared before the path starts (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Entry {
    /// Plunge at the first point: a disc of radius R.
    Plunge,
    /// Helix of radius `radius` (tool-centre path) about `center`: a disc of radius
    /// `radius + R`.
    Helix { center: DVec2, radius: f64 },
}

/// Engagement at one measured position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngagementSample {
    /// Arc length along the path (mm).
    pub s: f64,
    pub position: DVec2,
    /// Engagement angle (degrees).
    pub angle_deg: f64,
    /// Radial engagement (mm).
    pub radial_mm: f64,
}

/// Summary over a path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EngagementStats {
    pub max_engagement_deg: f64,
    /// 99th percentile of the engagement angle over the measured positions (equally spaced
    /// along the path, so it is weighted by path length).
    pub p99_engagement_deg: f64,
    pub max_radial_mm: f64,
    /// Where the maximum angle occurs, as a fraction of the path length.
    pub max_at_fraction: f64,
}

struct Buckets {
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    lists: Vec<Vec<u32>>,
    segs: Vec<(DVec2, DVec2)>,
}

impl Buckets {
    fn new(lo: DVec2, hi: DVec2, cell: f64) -> Self {
        let ext = (hi - lo).max(DVec2::splat(cell));
        // cap the raster size for degenerate inputs (a huge path with a tiny tool)
        let cell = cell.max(ext.max_element() / 4096.0);
        let nx = (ext.x / cell).ceil() as usize + 1;
        let ny = (ext.y / cell).ceil() as usize + 1;
        Buckets {
            origin: lo,
            cell,
            nx,
            ny,
            lists: vec![Vec::new(); nx * ny],
            segs: Vec::new(),
        }
    }

    fn index(&self, p: DVec2) -> (isize, isize) {
        let q = (p - self.origin) / self.cell;
        (q.x.floor() as isize, q.y.floor() as isize)
    }

    /// Add the capsule of radius `r` about `a`–`b`: listed in every bucket it reaches (the
    /// bucket's centre within r + half a diagonal of the segment).
    fn add(&mut self, a: DVec2, b: DVec2, r: f64) {
        let k = self.segs.len() as u32;
        self.segs.push((a, b));
        let (i0, j0) = self.index(a.min(b) - DVec2::splat(r));
        let (i1, j1) = self.index(a.max(b) + DVec2::splat(r));
        let reach = r + self.cell * std::f64::consts::FRAC_1_SQRT_2;
        let reach2 = reach * reach * (1.0 + 1e-9);
        for j in j0.max(0)..=j1.min(self.ny as isize - 1) {
            for i in i0.max(0)..=i1.min(self.nx as isize - 1) {
                let c = self.origin + (DVec2::new(i as f64, j as f64) + 0.5) * self.cell;
                if dist2_point_seg(c, a, b) <= reach2 {
                    self.lists[j as usize * self.nx + i as usize].push(k);
                }
            }
        }
    }

    /// Whether `q` lies within `r` of a listed segment (removed material).
    fn cut(&self, q: DVec2, r2: f64) -> bool {
        let (i, j) = self.index(q);
        if i < 0 || j < 0 || i >= self.nx as isize || j >= self.ny as isize {
            return false;
        }
        self.lists[j as usize * self.nx + i as usize]
            .iter()
            .rev() // recent cuts first: the likeliest to contain q
            .any(|&k| {
                let (a, b) = self.segs[k as usize];
                dist2_point_seg(q, a, b) <= r2
            })
    }
}

/// Engagement at every measured position of `points` (see the module doc). Empty for a path
/// of fewer than two distinct points or a non-positive tool.
pub fn engagement_profile(
    points: &[DVec2],
    tool_diameter: f64,
    entry: Entry,
    params: &EngagementParams,
) -> Vec<EngagementSample> {
    let pts: Vec<DVec2> = points.iter().copied().filter(|p| p.is_finite()).collect();
    if pts.len() < 2 || !(tool_diameter.is_finite() && tool_diameter > 0.0) {
        return Vec::new();
    }
    let r = tool_diameter / 2.0;
    let step = (params.step.max(1e-4) * tool_diameter).max(1e-9);
    let probes = params.probes.max(2);
    let lo = pts
        .iter()
        .fold(DVec2::splat(f64::INFINITY), |a, p| a.min(*p));
    let hi = pts
        .iter()
        .fold(DVec2::splat(f64::NEG_INFINITY), |a, p| a.max(*p));
    // the plunge's disc is a capsule of the tool's radius; a helix hole is held as an exact
    // disc (a ring of chords would leave a sagitta of stock at its edge, which a tool running
    // inside the hole along its rim would read as a few degrees of engagement)
    let hole = match entry {
        Entry::Helix { center, radius } if radius.is_finite() && radius > 0.0 => {
            Some((center, (radius + r) * (radius + r) * (1.0 + 1e-9)))
        }
        _ => None,
    };
    let pad = DVec2::splat(2.0 * r);
    let mut grid = Buckets::new(lo - pad, hi + pad, 0.5 * r);
    if hole.is_none() {
        grid.add(pts[0], pts[0], r);
    }
    let in_hole = |q: DVec2| hole.is_some_and(|(c, h2)| q.distance_squared(c) <= h2);
    let r2 = r * r * (1.0 + 1e-9);
    let dth = std::f64::consts::PI / probes as f64;
    let mut out = Vec::new();
    let mut s = 0.0;
    let mut prev = pts[0];
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = a.distance(b);
        if len < 1e-12 {
            continue;
        }
        let t = (b - a) / len;
        let nrm = t.perp();
        let k = (len / step).ceil().max(1.0) as usize;
        for j in 1..=k {
            let p = a.lerp(b, j as f64 / k as f64);
            let mut count = 0usize;
            let (mut lo_n, mut hi_n) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..probes {
                let th = -std::f64::consts::FRAC_PI_2 + (i as f64 + 0.5) * dth;
                let (sn, cs) = th.sin_cos();
                let q = p + r * (cs * t + sn * nrm);
                if !in_hole(q) && !grid.cut(q, r2) {
                    count += 1;
                    let across = r * sn;
                    lo_n = lo_n.min(across);
                    hi_n = hi_n.max(across);
                }
            }
            s += len / k as f64;
            out.push(EngagementSample {
                s,
                position: p,
                angle_deg: count as f64 * 180.0 / probes as f64,
                radial_mm: if count > 0 { hi_n - lo_n } else { 0.0 },
            });
            grid.add(prev, p, r);
            prev = p;
        }
    }
    out
}

/// Max and 99th percentile engagement angle and max radial engagement of a path; `None` when
/// nothing could be measured.
pub fn engagement_stats(
    points: &[DVec2],
    tool_diameter: f64,
    entry: Entry,
    params: &EngagementParams,
) -> Option<EngagementStats> {
    summarize(&engagement_profile(points, tool_diameter, entry, params))
}

/// The summary of a profile.
pub fn summarize(samples: &[EngagementSample]) -> Option<EngagementStats> {
    let last = samples.last()?;
    let mut angles: Vec<f64> = samples.iter().map(|e| e.angle_deg).collect();
    angles.sort_by(f64::total_cmp);
    // nearest-rank percentile
    let rank = ((0.99 * angles.len() as f64).ceil() as usize).clamp(1, angles.len());
    let (mut imax, mut amax) = (0, f64::NEG_INFINITY);
    for (i, e) in samples.iter().enumerate() {
        if e.angle_deg > amax {
            amax = e.angle_deg;
            imax = i;
        }
    }
    Some(EngagementStats {
        max_engagement_deg: amax,
        p99_engagement_deg: angles[rank - 1],
        max_radial_mm: samples.iter().map(|e| e.radial_mm).fold(0.0, f64::max),
        max_at_fraction: if last.s > 0.0 {
            samples[imax].s / last.s
        } else {
            0.0
        },
    })
}
