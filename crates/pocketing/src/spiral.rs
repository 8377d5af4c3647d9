//! Bieterman & Sandstrom's curvilinear spiral from contours of a PDE solution.

use glam::DVec2;
use std::f64::consts::TAU;

use crate::contour::EdgeTopology;
use crate::fem::{self, Mesh, Solution};
use crate::geom::{loop_gap, perimeter, signed_area, SegIndex};
use crate::offset::{append_loop_from_nearest, offset_loops, offset_path, sample_level};
use crate::{Method, Pocket, PocketError, PocketParams, PocketPath};

/// A closed loop, star-shaped about `c`, as a function of the winding angle.
struct Polar {
    c: DVec2,
    /// angles relative to θ0, strictly increasing, in [0, 2π)
    ang: Vec<f64>,
    pts: Vec<DVec2>,
}

impl Polar {
    /// `None` if the loop is not star-shaped about `c` (winding angle not strictly monotone or
    /// winding number ≠ 1).
    fn new(lp: &[DVec2], c: DVec2, theta0: f64) -> Option<Polar> {
        let mut lp: Vec<DVec2> = lp.to_vec();
        if signed_area(&lp) < 0.0 {
            lp.reverse();
        }
        let n = lp.len();
        if n < 3 {
            return None;
        }
        let mut total = 0.0;
        for i in 0..n {
            let a = lp[i] - c;
            let b = lp[(i + 1) % n] - c;
            if a.length_squared() < 1e-24 || b.length_squared() < 1e-24 {
                return None;
            }
            let d = a.perp_dot(b).atan2(a.dot(b));
            if d <= 1e-12 {
                return None;
            }
            total += d;
        }
        if (total - TAU).abs() > 1e-6 {
            return None;
        }
        let rel = |p: DVec2| ((p - c).to_angle() - theta0).rem_euclid(TAU);
        let start = (0..n)
            .min_by(|&i, &j| rel(lp[i]).total_cmp(&rel(lp[j])))
            .unwrap();
        let pts: Vec<DVec2> = (0..n).map(|k| lp[(start + k) % n]).collect();
        let mut ang = Vec::with_capacity(n);
        let mut acc = rel(pts[0]);
        ang.push(acc);
        for k in 1..n {
            let a = pts[k - 1] - c;
            let b = pts[k] - c;
            acc += a.perp_dot(b).atan2(a.dot(b));
            ang.push(acc);
        }
        Some(Polar { c, ang, pts })
    }

    /// Radius along the ray at relative angle `t` ∈ [0, 2π] (θ0 + t absolute).
    fn radius(&self, t: f64, theta0: f64) -> f64 {
        let n = self.pts.len();
        let t = t.rem_euclid(TAU);
        // segment i: from pts[i] (ang[i]) to pts[i+1] (ang[i+1]), cyclic with +2π
        let i = match self.ang.partition_point(|&a| a <= t) {
            0 => n - 1,
            k => k - 1,
        };
        let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
        let dir = DVec2::from_angle(theta0 + t);
        // c + r dir = a + s (b - a)
        let ab = b - a;
        let ca = a - self.c;
        let den = dir.perp_dot(ab);
        if den.abs() < 1e-300 {
            return ca.length();
        }
        let r = ca.perp_dot(ab) / den;
        r.max(0.0)
    }

    fn max_radius(&self) -> f64 {
        self.pts
            .iter()
            .map(|p| p.distance(self.c))
            .fold(0.0, f64::max)
    }
}

/// Internal outcome of one spiral attempt.
enum Attempt {
    Ok(Box<PocketPath>),
    Fallback(String),
}

/// Curvilinear pocketing. See the crate documentation; falls back to [`offset_path`] (method
/// `offset-fallback`) where the winding-angle parameterisation is impossible.
pub fn curvilinear_path(pocket: &Pocket, params: &PocketParams) -> Result<PocketPath, PocketError> {
    params.validate()?;
    pocket.validate()?;
    let fallback = |reason: String| -> Result<PocketPath, PocketError> {
        let mut p = offset_path(pocket, params)?;
        p.method = Method::OffsetFallback;
        p.fallback_reason = Some(reason);
        Ok(p)
    };
    if !pocket.islands.is_empty() {
        return fallback("pocket has islands".into());
    }
    let r = params.tool_diameter / 2.0;
    let f = params.finish_stepover;
    let step = params.sample_step();
    let finish = offset_loops(pocket, r);
    if finish.is_empty() {
        return Err(PocketError::ToolDoesNotFit);
    }
    if finish.len() > 1 {
        return fallback("tool-offset region splits into several parts".into());
    }
    let rough = if f > 1e-9 {
        offset_loops(pocket, r + f)
    } else {
        finish.clone()
    };
    if rough.len() != 1 {
        return fallback("roughing region is empty or splits".into());
    }
    let boundary = sample_level(&finish, step).remove(0);
    let rough_loop = sample_level(&rough, step).remove(0);
    let h = params
        .mesh_size
        .unwrap_or(params.stepover / 3.0)
        .min(perimeter(&rough_loop) / 24.0);
    let mesh = Mesh::of_loop(&rough_loop, h)?;
    let mut sol = fem::solve(&mesh, params.field)?;
    if params.distance_blend > 0.0 {
        blend_with_distance(&mesh, &mut sol, &rough_loop, params.distance_blend);
    }
    let topo = EdgeTopology::new(&mesh);
    let mut factor = 1.0;
    let mut worst = 0.0;
    for _ in 0..10 {
        match attempt(params, &mesh, &topo, &sol, &rough_loop, &boundary, factor) {
            Attempt::Fallback(reason) => return fallback(reason),
            Attempt::Ok(p) => {
                if p.max_gap <= params.stepover {
                    return Ok(*p);
                }
                worst = p.max_gap;
                factor *= 0.93;
            }
        }
    }
    // never return a spiral whose measured gap exceeds the stepover
    fallback(format!(
        "spiral gap {worst:.4} stays above the stepover {:.4} after 10 attempts",
        params.stepover
    ))
}

/// Replace the normalised field u by w = (1 − α)·u + α·d/max d (d: distance of each mesh
/// vertex to the roughing boundary, 0 on it), renormalised to max 1.
fn blend_with_distance(mesh: &Mesh, sol: &mut Solution, rough_loop: &[DVec2], alpha: f64) {
    let idx = SegIndex::new(&[rough_loop], true);
    let d: Vec<f64> = mesh
        .vertices
        .iter()
        .zip(&mesh.on_boundary)
        .map(|(p, &b)| if b { 0.0 } else { idx.nearest(*p) })
        .collect();
    let dmax = d.iter().copied().fold(0.0, f64::max).max(1e-300);
    let mut w: Vec<f64> = sol
        .u
        .iter()
        .zip(&d)
        .map(|(u, d)| (1.0 - alpha) * u + alpha * d / dmax)
        .collect();
    let wmax = w.iter().copied().fold(0.0, f64::max).max(1e-300);
    w.iter_mut().for_each(|x| *x /= wmax);
    sol.u = w;
}

/// Sample `f` on t ∈ [0, 1] at `n` even steps, bisecting any step longer than `step`.
fn sample_turn(f: impl Fn(f64) -> DVec2, n: usize, step: f64) -> Vec<DVec2> {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        f: &dyn Fn(f64) -> DVec2,
        t0: f64,
        p0: DVec2,
        t1: f64,
        p1: DVec2,
        step: f64,
        depth: u32,
        out: &mut Vec<DVec2>,
    ) {
        if depth < 20 && p0.distance(p1) > step {
            let tm = 0.5 * (t0 + t1);
            let pm = f(tm);
            rec(f, t0, p0, tm, pm, step, depth + 1, out);
            rec(f, tm, pm, t1, p1, step, depth + 1, out);
        } else {
            out.push(p1);
        }
    }
    let mut out = vec![f(0.0)];
    let mut prev = out[0];
    for j in 1..=n {
        let t = j as f64 / n as f64;
        let p = f(t);
        rec(&f, (j - 1) as f64 / n as f64, prev, t, p, step, 0, &mut out);
        prev = p;
    }
    out
}

/// Greedy contour levels outward from the maximum at `c`: each next level is the lowest whose
/// single contour loop is within `target` (symmetric Hausdorff) of the previous one; the first
/// contour must have every mesh vertex inside it within `target` of it. Stops when the
/// roughing boundary is within `target` of the last contour. `Err` when no single loop fits.
fn choose_levels(
    mesh: &Mesh,
    topo: &EdgeTopology,
    sol: &Solution,
    rough_loop: &[DVec2],
    c: DVec2,
    target: f64,
) -> Result<Vec<(f64, Vec<DVec2>)>, ()> {
    let mut out: Vec<(f64, Vec<DVec2>)> = Vec::new();
    let mut prev_level = 1.0;
    let interior_gap = |lvl: f64, lp: &[DVec2]| -> f64 {
        let idx = SegIndex::new(&[lp], true);
        let mut g = idx.nearest(c);
        for (p, &u) in mesh.vertices.iter().zip(&sol.u) {
            if u > lvl {
                g = g.max(idx.nearest(*p));
            }
        }
        g
    };
    loop {
        let done = match out.last() {
            None => interior_gap(0.0, rough_loop) <= target,
            Some((_, prev)) => loop_gap(prev, rough_loop) <= target,
        };
        if done {
            return Ok(out);
        }
        let (mut lo, mut hi) = (0.0, prev_level);
        let mut best: Option<(f64, Vec<DVec2>)> = None;
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            let mut l = topo.loops(mesh, &sol.u, mid);
            let ok = if l.len() == 1 {
                let lp = l.pop().unwrap();
                let g = match out.last() {
                    None => interior_gap(mid, &lp),
                    Some((_, prev)) => loop_gap(prev, &lp),
                };
                if g <= target {
                    best = Some((mid, lp));
                    true
                } else {
                    false
                }
            } else {
                false
            };
            if ok {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo < 1e-6 {
                break;
            }
        }
        let Some((lvl, lp)) = best else {
            return Err(());
        };
        if prev_level - lvl < 1e-9 {
            return Err(());
        }
        prev_level = lvl;
        out.push((lvl, lp));
    }
}

fn attempt(
    params: &PocketParams,
    mesh: &Mesh,
    topo: &EdgeTopology,
    sol: &Solution,
    rough_loop: &[DVec2],
    boundary: &[DVec2],
    factor: f64,
) -> Attempt {
    let s = params.stepover;
    let target = factor * s;
    let step = params.sample_step();
    let imax = (0..sol.u.len())
        .max_by(|&a, &b| sol.u[a].total_cmp(&sol.u[b]))
        .unwrap();
    let c = mesh.vertices[imax];
    // start the orbits on the ray towards the nearest point of the roughing boundary
    let theta0 = {
        let p = rough_loop
            .iter()
            .min_by(|a, b| a.distance_squared(c).total_cmp(&b.distance_squared(c)))
            .unwrap();
        (*p - c).to_angle()
    };
    let Some(terminal) = Polar::new(rough_loop, c, theta0) else {
        return Attempt::Fallback(
            "tool-offset boundary is not star-shaped about the centre".into(),
        );
    };
    // --- levels, outward from the maximum: greedy with the target gap, then the smallest
    // target that needs no more contours (so the gaps come out even instead of leaving a thin
    // last orbit)
    let Ok(first) = choose_levels(mesh, topo, sol, rough_loop, c, target) else {
        return Attempt::Fallback("no single contour within the stepover below the maximum".into());
    };
    let n0 = first.len();
    let (mut lo, mut hi) = (0.5 * target, target);
    let mut chosen = first;
    for _ in 0..6 {
        let mid = 0.5 * (lo + hi);
        match choose_levels(mesh, topo, sol, rough_loop, c, mid) {
            Ok(l) if l.len() <= n0 => {
                hi = mid;
                chosen = l;
            }
            _ => lo = mid,
        }
    }
    let mut contours: Vec<Vec<DVec2>> = Vec::new();
    let mut polars: Vec<Polar> = Vec::new();
    for (lvl, lp) in chosen {
        let Some(pol) = Polar::new(&lp, c, theta0) else {
            return Attempt::Fallback(format!(
                "contour at level {lvl:.4} is not star-shaped about the centre"
            ));
        };
        polars.push(pol);
        contours.push(lp);
    }
    // the first orbit spirals out of the centre when the first contour is within the stepover
    // of it; for elongated pockets (a ridge-like maximum) it enters the first contour on the
    // start ray and runs it in full instead
    let from_centre = contours
        .first()
        .is_none_or(|c1| loop_gap(&[c], c1) <= target);
    // --- orbits: centre → C1 → … → Cm → ∂Ω' (roughing boundary)
    let mut radii: Vec<Box<dyn Fn(f64) -> f64 + '_>> = Vec::new();
    if from_centre {
        radii.push(Box::new(|_| 0.0));
    }
    for p in &polars {
        radii.push(Box::new(move |t| p.radius(t, theta0)));
    }
    let term = &terminal;
    radii.push(Box::new(move |t| term.radius(t, theta0)));
    let rmax: Vec<f64> = polars
        .iter()
        .map(|p| p.max_radius())
        .chain(std::iter::once(terminal.max_radius()))
        .collect();
    let mut turns: Vec<Vec<DVec2>> = Vec::new();
    if !from_centre {
        // straight entry along the start ray, then the first contour in full
        let p = &polars[0];
        let n = ((TAU * p.max_radius() / step).ceil() as usize).max(24);
        let mut t0 = vec![c];
        let first = sample_turn(
            |t| c + p.radius(TAU * t, theta0) * DVec2::from_angle(theta0 + TAU * t),
            n,
            step,
        );
        // straight entry from the centre, subdivided
        let k = (c.distance(first[0]) / step).ceil().max(1.0) as usize;
        for j in 1..k {
            t0.push(c.lerp(first[0], j as f64 / k as f64));
        }
        t0.extend(first);
        turns.push(t0);
    }
    let roff = usize::from(from_centre);
    for k in 0..radii.len() - 1 {
        let n = ((TAU * rmax[k + 1 - roff] / step).ceil() as usize).max(24);
        let (ra, rb) = (&radii[k], &radii[k + 1]);
        let turn = sample_turn(
            |t| {
                let th = TAU * t;
                c + ((1.0 - t) * ra(th) + t * rb(th)) * DVec2::from_angle(theta0 + th)
            },
            n,
            step,
        );
        turns.push(turn);
    }
    // full orbit on the roughing boundary, starting where the spiral ends
    let mut rough_turn = Vec::new();
    rough_turn.push(*turns.last().unwrap().last().unwrap());
    append_loop_from_nearest(&mut rough_turn, rough_loop);
    // smoothing of the spiral orbits (end points fixed), kept only if the gap stays in bound
    let raw_turns = turns.clone();
    let gap_of = |turns: &[Vec<DVec2>]| -> f64 {
        let mut g: f64 = 0.0;
        let mut all: Vec<&[DVec2]> = turns.iter().map(|t| t.as_slice()).collect();
        all.push(&rough_turn);
        for w in all.windows(2) {
            let ia = SegIndex::new(&[w[0]], false);
            let ib = SegIndex::new(&[w[1]], false);
            g = g.max(crate::geom::directed_gap(w[0], &ib));
            g = g.max(crate::geom::directed_gap(w[1], &ia));
        }
        g
    };
    let raw_gap = gap_of(&raw_turns);
    if params.smoothing_passes > 0 {
        let mut flat: Vec<DVec2> = Vec::new();
        let mut bounds = Vec::new();
        for t in &turns {
            let s0 = flat.len();
            if s0 > 0 {
                flat.pop(); // shared point between orbits
            }
            let s0 = flat.len();
            flat.extend_from_slice(t);
            bounds.push((s0, flat.len()));
        }
        for _ in 0..params.smoothing_passes {
            let old = flat.clone();
            // keep the last orbit's final tenth untouched so the spiral meets ∂Ω' exactly
            let last_fixed = bounds.last().map(|&(a, b)| b - (b - a) / 10).unwrap_or(0);
            for i in 1..flat.len() - 1 {
                if i >= last_fixed {
                    break;
                }
                let avg = 0.5 * (old[i - 1] + old[i + 1]);
                flat[i] = old[i] + 0.5 * (avg - old[i]);
            }
        }
        let smoothed: Vec<Vec<DVec2>> = bounds.iter().map(|&(a, b)| flat[a..b].to_vec()).collect();
        let sg = gap_of(&smoothed);
        if sg <= s || sg <= raw_gap {
            turns = smoothed;
        }
    }
    let max_gap = gap_of(&turns).max(params.finish_stepover);
    // --- assemble: spiral, roughing boundary orbit, link, finishing pass on ∂Ω
    let mut points: Vec<DVec2> = Vec::new();
    for t in &turns {
        for &p in t {
            if points
                .last()
                .is_none_or(|q: &DVec2| q.distance_squared(p) > 1e-18)
            {
                points.push(p);
            }
        }
    }
    for &p in &rough_turn[1..] {
        if points
            .last()
            .is_none_or(|q: &DVec2| q.distance_squared(p) > 1e-18)
        {
            points.push(p);
        }
    }
    let finish_start = points.len();
    append_loop_from_nearest(&mut points, boundary);
    contours.push(rough_loop.to_vec());
    Attempt::Ok(Box::new(PocketPath {
        method: Method::Curvilinear,
        points,
        finish_start,
        max_gap,
        contours,
        center: Some(c),
        fallback_reason: None,
        boundary: boundary.to_vec(),
    }))
}
