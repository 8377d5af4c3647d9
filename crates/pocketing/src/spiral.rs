//! Bieterman & Sandstrom's curvilinear spiral from contours of a PDE solution.

use glam::DVec2;
use std::f64::consts::TAU;

use crate::contour::EdgeTopology;
use crate::fem::{self, Mesh, Solution};
use crate::geom::{directed_within, loop_within, perimeter, signed_area, SegIndex, NO_HINT};
use crate::offset::{append_loop_from_nearest, offset_loops, offset_path, sample_level};
use crate::{Method, Pocket, PocketError, PocketParams, PocketPath};

/// Where the contour loops of a level come from.
#[derive(Clone, Copy)]
enum Contours<'a> {
    /// Level sets of the field, linear on the mesh (the PDE's contours).
    Mesh(&'a EdgeTopology),
    /// The exact contours of the distance to the roughing boundary: the pocket's parallel
    /// offsets by `base` + level·`dmax` (cavalier_contours), sampled at `step`. Linear
    /// interpolation of the distance cuts notches into its contours where they cross the
    /// distance's ridge (the field has a kink there), which made the triangle's contours not
    /// star-shaped about their centre.
    Offsets {
        pocket: &'a Pocket,
        base: f64,
        dmax: f64,
        step: f64,
    },
}

impl Contours<'_> {
    fn loops(&self, mesh: &Mesh, u: &[f64], level: f64) -> Vec<Vec<DVec2>> {
        match *self {
            Contours::Mesh(topo) => topo.loops(mesh, u, level),
            Contours::Offsets {
                pocket,
                base,
                dmax,
                step,
            } => sample_level(&offset_loops(pocket, base + level * dmax), step),
        }
    }
}

/// The core the orbits wind about: a point (Bieterman's centre, `len` = 0) or a segment (the
/// ridge of an elongated pocket). Rays leave the core as the normals of a thin stadium around
/// it, so the "winding angle" generalises to a parameter τ ∈ [0, T), T = 2·len + 2π: along the
/// right side a → b, round the cap at b, back along the left side, round the cap at a
/// (counter-clockwise). With `len` = 0, τ is the polar angle measured from −perp(u).
#[derive(Clone, Copy)]
struct Core {
    a: DVec2,
    u: DVec2,
    len: f64,
}

impl Core {
    fn point(c: DVec2) -> Core {
        Core {
            a: c,
            u: DVec2::X,
            len: 0.0,
        }
    }

    fn period(&self) -> f64 {
        2.0 * self.len + TAU
    }

    fn mid(&self) -> DVec2 {
        self.a + 0.5 * self.len * self.u
    }

    /// Sample points of the core (for gap measurements).
    fn samples(&self, step: f64) -> Vec<DVec2> {
        let k = (self.len / step.max(1e-12)).ceil() as usize;
        (0..=k)
            .map(|j| self.a + self.u * (self.len * j as f64 / k.max(1) as f64))
            .collect()
    }

    /// τ of a point off the core; `None` on the core.
    fn tau(&self, p: DVec2) -> Option<f64> {
        let perp = self.u.perp();
        let s = (p - self.a).dot(self.u);
        let q = self.a + self.u * s.clamp(0.0, self.len);
        let v = p - q;
        if v.length_squared() < 1e-24 {
            return None;
        }
        let (l, pi) = (self.len, std::f64::consts::PI);
        Some(if s > 0.0 && s < l {
            if v.dot(perp) < 0.0 {
                s
            } else {
                l + pi + (l - s)
            }
        } else if s >= l && l > 0.0 {
            // in a cap |v·u| is the axial component; abs() also makes −0.0 (read by atan2 as
            // −π) +0.0
            l + v.dot(self.u).abs().atan2(-v.dot(perp))
        } else if l > 0.0 {
            2.0 * l + pi + v.dot(self.u).abs().atan2(v.dot(perp))
        } else {
            // a point core: the polar angle from −perp
            v.dot(self.u).atan2(-v.dot(perp)).rem_euclid(TAU)
        })
    }

    /// Origin and unit direction of the ray at τ.
    fn ray(&self, tau: f64) -> (DVec2, DVec2) {
        let (l, pi) = (self.len, std::f64::consts::PI);
        let t = tau.rem_euclid(self.period());
        let perp = self.u.perp();
        if t < l {
            (self.a + self.u * t, -perp)
        } else if t < l + pi {
            let ph = t - l;
            (self.a + self.u * l, -perp * ph.cos() + self.u * ph.sin())
        } else if t < 2.0 * l + pi {
            (self.a + self.u * (2.0 * l + pi - t), perp)
        } else {
            let ph = t - 2.0 * l - pi;
            (self.a, perp * ph.cos() - self.u * ph.sin())
        }
    }
}

/// A closed loop, star-shaped about the core, as a function of τ (see [`Core`]).
struct Polar {
    core: Core,
    /// τ relative to τ0, strictly increasing, in [0, T)
    ang: Vec<f64>,
    pts: Vec<DVec2>,
}

impl Polar {
    /// `None` if the loop is not star-shaped about the core (τ not strictly monotone along it
    /// or winding ≠ 1).
    fn new(lp: &[DVec2], core: Core, tau0: f64) -> Option<Polar> {
        let mut lp: Vec<DVec2> = lp.to_vec();
        if signed_area(&lp) < 0.0 {
            lp.reverse();
        }
        let n = lp.len();
        if n < 3 {
            return None;
        }
        let per = core.period();
        let taus: Vec<f64> = lp.iter().map(|&p| core.tau(p)).collect::<Option<_>>()?;
        let mut total = 0.0;
        for i in 0..n {
            let d = (taus[(i + 1) % n] - taus[i] + 0.5 * per).rem_euclid(per) - 0.5 * per;
            if d <= 1e-12 {
                return None;
            }
            total += d;
        }
        if (total - per).abs() > 1e-6 {
            return None;
        }
        let rel = |t: f64| (t - tau0).rem_euclid(per);
        let start = (0..n)
            .min_by(|&i, &j| rel(taus[i]).total_cmp(&rel(taus[j])))
            .unwrap();
        let pts: Vec<DVec2> = (0..n).map(|k| lp[(start + k) % n]).collect();
        let mut ang = Vec::with_capacity(n);
        let mut acc = rel(taus[start]);
        ang.push(acc);
        for k in 1..n {
            let (t0, t1) = (taus[(start + k - 1) % n], taus[(start + k) % n]);
            acc += (t1 - t0 + 0.5 * per).rem_euclid(per) - 0.5 * per;
            ang.push(acc);
        }
        Some(Polar { core, ang, pts })
    }

    /// Distance along the ray at relative parameter `t` ∈ [0, T] (τ0 + t absolute).
    fn radius(&self, t: f64, tau0: f64) -> f64 {
        let n = self.pts.len();
        let t = t.rem_euclid(self.core.period());
        // segment i: from pts[i] (ang[i]) to pts[i+1] (ang[i+1]), cyclic with +T
        let i = match self.ang.partition_point(|&a| a <= t) {
            0 => n - 1,
            k => k - 1,
        };
        let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
        let (o, dir) = self.core.ray(tau0 + t);
        // o + r dir = a + s (b - a)
        let ab = b - a;
        let ca = a - o;
        let den = dir.perp_dot(ab);
        if den.abs() < 1e-300 {
            return ca.length();
        }
        let r = ca.perp_dot(ab) / den;
        r.max(0.0)
    }

    /// Length of the loop (sets the sampling density of the orbit ending on it).
    fn perimeter(&self) -> f64 {
        perimeter(&self.pts)
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
    let imax = (0..sol.u.len())
        .max_by(|&a, &b| sol.u[a].total_cmp(&sol.u[b]))
        .unwrap();
    let pde = spiral_with(
        params,
        &mesh,
        Contours::Mesh(&topo),
        &sol,
        Core::point(mesh.vertices[imax]),
        Method::Curvilinear,
        &rough_loop,
        &boundary,
    );
    // the offset spiral: contours of the distance to ∂Ω' (parallel offsets, evenly spaced
    // where the PDE's crowd) wound about the distance's ridge, a segment in an elongated pocket
    let mut dist = sol.clone();
    blend_with_distance(&mesh, &mut dist, &rough_loop, 1.0);
    let dmax = {
        let idx = SegIndex::new(&[&rough_loop], true);
        mesh.vertices
            .iter()
            .map(|p| idx.nearest(*p))
            .fold(0.0, f64::max)
    };
    let ridge = ridge_core(&mesh, &dist.u, dmax, h);
    // the distance's contours on the mesh first: linear interpolation softens the offsets'
    // corners, which the feed schedule rewards (slot: 4.6 % vs 9.4 % saving over `gapm` at
    // L/D 1 with the exact offsets); where they are notched at the ridge and so not
    // star-shaped (the triangle), the exact offsets
    let mut offsets_note = "";
    let off = spiral_with(
        params,
        &mesh,
        Contours::Mesh(&topo),
        &dist,
        ridge,
        Method::OffsetSpiral,
        &rough_loop,
        &boundary,
    )
    .or_else(|on_mesh| {
        offsets_note = " on the exact offsets";
        let exact = Contours::Offsets {
            pocket,
            base: r + f,
            dmax,
            step,
        };
        spiral_with(
            params,
            &mesh,
            exact,
            &dist,
            ridge,
            Method::OffsetSpiral,
            &rough_loop,
            &boundary,
        )
        .map_err(|e| format!("{e} (on the mesh: {on_mesh})"))
    });
    match (pde, off) {
        (Ok(a), Ok(b)) => {
            // the offset spiral only where it needs fewer turns (an elongated pocket, where the
            // PDE's contours crowd at the ends); at equal turns the PDE spiral's rounder orbits
            // are faster even when a few millimetres longer (rounded square: offset spiral
            // 0.2 % shorter, 13 % slower at L/D 10)
            let (ta, tb) = (a.roughing_turns(), b.roughing_turns());
            let (la, lb) = (a.length(), b.length());
            let mut win = if tb < ta { b } else { a };
            win.choice = Some(format!(
                "{}: curvilinear {ta} turns {la:.1} mm, offset-spiral{offsets_note} {tb} turns \
                 {lb:.1} mm (the offset spiral only with fewer turns)",
                win.method.as_str()
            ));
            Ok(win)
        }
        (Ok(mut a), Err(rb)) | (Err(rb), Ok(mut a)) => {
            a.choice = Some(format!("the other field failed: {rb}"));
            Ok(a)
        }
        (Err(ra), Err(rb)) => fallback(format!("{ra}; offset spiral: {rb}")),
    }
}

/// The ridge of a normalised field as the spiral's core: the principal axis of the vertices
/// within `h`·(gradient scale) of the maximum, shortened by `h` at both ends; a point when that
/// leaves nothing.
fn ridge_core(mesh: &Mesh, w: &[f64], dmax: f64, h: f64) -> Core {
    let imax = (0..w.len()).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap();
    let c = mesh.vertices[imax];
    // w = d / max d: a step h in distance is h / max d in w
    let tol = h / dmax.max(1e-12);
    let ridge: Vec<DVec2> = mesh
        .vertices
        .iter()
        .zip(w)
        .filter(|(_, &x)| x >= 1.0 - tol)
        .map(|(p, _)| *p)
        .collect();
    if ridge.len() < 3 {
        return Core::point(c);
    }
    let m = ridge.iter().fold(DVec2::ZERO, |a, p| a + *p) / ridge.len() as f64;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in &ridge {
        let d = *p - m;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let ang = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let u = DVec2::from_angle(ang);
    let (lo, hi) = ridge
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = (*p - m).dot(u);
            (lo.min(s), hi.max(s))
        });
    // a sharp corner's ridge (slope ≥ ½ away from a 60° incentre) spans up to 4h: not a segment
    let len = hi - lo - 4.0 * h;
    if len <= h {
        return Core::point(c);
    }
    Core {
        a: m + u * (lo + 2.0 * h),
        u,
        len,
    }
}

/// One spiral about `core` on the field `sol`, retried with a smaller target gap until the
/// measured gap is ≤ the stepover; `Err(reason)` when the field's contours do not allow one.
#[allow(clippy::too_many_arguments)]
fn spiral_with(
    params: &PocketParams,
    mesh: &Mesh,
    source: Contours,
    sol: &Solution,
    core: Core,
    method: Method,
    rough_loop: &[DVec2],
    boundary: &[DVec2],
) -> Result<PocketPath, String> {
    let mut factor = 1.0;
    let mut worst = 0.0;
    for _ in 0..10 {
        match attempt(
            params, mesh, source, sol, core, method, rough_loop, boundary, factor,
        ) {
            Attempt::Fallback(reason) => return Err(reason),
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
    Err(format!(
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
    source: Contours,
    sol: &Solution,
    rough_loop: &[DVec2],
    core: &[DVec2],
    target: f64,
) -> Result<Vec<(f64, Vec<DVec2>)>, ()> {
    let mut out: Vec<(f64, Vec<DVec2>)> = Vec::new();
    let mut prev_level = 1.0;
    // Only whether a gap is within `target` is asked, so the measurements stop at the first
    // point farther than `target` (exactly the comparison of the maximum with `target`).
    // Whether the core and every mesh vertex above `lvl` lie within `target` of `lp`.
    let interior_within = |lvl: f64, idx: &SegIndex| -> bool {
        let mut hint = NO_HINT;
        0.0 <= target
            && core
                .iter()
                .all(|&c| idx.within_hinted(c, target, &mut hint))
            && mesh
                .vertices
                .iter()
                .zip(&sol.u)
                .all(|(p, &u)| u <= lvl || idx.within_hinted(*p, target, &mut hint))
    };
    let rough_idx = SegIndex::new(&[rough_loop], true);
    loop {
        // the previous contour's index, for the roughing boundary and every candidate
        let prev_idx = out
            .last()
            .map(|(_, prev)| SegIndex::new(&[prev.as_slice()], true));
        let done = match (out.last(), &prev_idx) {
            (Some((_, prev)), Some(prev_idx)) => {
                // loop_gap(prev, rough_loop) <= target
                directed_within(prev, &rough_idx, target)
                    && directed_within(rough_loop, prev_idx, target)
            }
            _ => interior_within(0.0, &rough_idx),
        };
        if done {
            return Ok(out);
        }
        let (mut lo, mut hi) = (0.0, prev_level);
        let mut best: Option<(f64, Vec<DVec2>)> = None;
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            let l = source.loops(mesh, &sol.u, mid);
            let ok = if l.len() == 1 {
                let lp = &l[0];
                let lp_idx = || SegIndex::new(&[lp.as_slice()], true);
                let fits = match (out.last(), &prev_idx) {
                    (Some((_, prev)), Some(prev_idx)) => {
                        // loop_gap(prev, lp) <= target, the cached index's half first
                        directed_within(lp, prev_idx, target)
                            && directed_within(prev, &lp_idx(), target)
                    }
                    _ => interior_within(mid, &lp_idx()),
                };
                if fits {
                    best = Some((mid, lp.clone()));
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

#[allow(clippy::too_many_arguments)]
fn attempt(
    params: &PocketParams,
    mesh: &Mesh,
    source: Contours,
    sol: &Solution,
    core: Core,
    method: Method,
    rough_loop: &[DVec2],
    boundary: &[DVec2],
    factor: f64,
) -> Attempt {
    let s = params.stepover;
    let target = factor * s;
    let step = params.sample_step();
    let c = core.mid();
    let core_pts = core.samples(step);
    let per = core.period();
    // start the orbits on the ray towards the nearest point of the roughing boundary
    let theta0 = {
        let idx = SegIndex::new(&[&core_pts], false);
        // each point's distance once (min_by keeps the first of equal minima either way)
        let (p, _) = rough_loop
            .iter()
            .map(|p| (p, idx.nearest(*p)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        core.tau(*p).unwrap_or(0.0)
    };
    let Some(terminal) = Polar::new(rough_loop, core, theta0) else {
        return Attempt::Fallback(
            "tool-offset boundary is not star-shaped about the centre".into(),
        );
    };
    // --- levels, outward from the maximum: greedy with the target gap, then the smallest
    // target that needs no more contours (so the gaps come out even instead of leaving a thin
    // last orbit)
    let Ok(first) = choose_levels(mesh, source, sol, rough_loop, &core_pts, target) else {
        return Attempt::Fallback("no single contour within the stepover below the maximum".into());
    };
    let n0 = first.len();
    let (mut lo, mut hi) = (0.5 * target, target);
    let mut chosen = first;
    for _ in 0..6 {
        let mid = 0.5 * (lo + hi);
        match choose_levels(mesh, source, sol, rough_loop, &core_pts, mid) {
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
        let Some(pol) = Polar::new(&lp, core, theta0) else {
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
        .is_none_or(|c1| loop_within(&core_pts, c1, &SegIndex::new(&[c1], true), target));
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
    let perims: Vec<f64> = polars
        .iter()
        .map(|p| p.perimeter())
        .chain(std::iter::once(terminal.perimeter()))
        .collect();
    let at = |r: f64, t: f64| {
        let (o, dir) = core.ray(theta0 + t);
        o + r * dir
    };
    let mut turns: Vec<Vec<DVec2>> = Vec::new();
    if !from_centre {
        // straight entry along the start ray, then the first contour in full
        let p = &polars[0];
        let n = ((p.perimeter() / step).ceil() as usize).max(24);
        let c0 = at(0.0, 0.0);
        let mut t0 = vec![c0];
        let first = sample_turn(|t| at(p.radius(per * t, theta0), per * t), n, step);
        // straight entry from the centre, subdivided
        let k = (c0.distance(first[0]) / step).ceil().max(1.0) as usize;
        for j in 1..k {
            t0.push(c0.lerp(first[0], j as f64 / k as f64));
        }
        t0.extend(first);
        turns.push(t0);
    }
    let roff = usize::from(from_centre);
    for k in 0..radii.len() - 1 {
        let n = ((perims[k + 1 - roff] / step).ceil() as usize).max(24);
        let (ra, rb) = (&radii[k], &radii[k + 1]);
        let turn = sample_turn(
            |t| {
                let th = per * t;
                at((1.0 - t) * ra(th) + t * rb(th), th)
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
        method,
        points,
        finish_start,
        max_gap,
        contours,
        center: Some(c),
        fallback_reason: None,
        choice: None,
        boundary: boundary.to_vec(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// τ and the ray agree: every point off the core lies on the ray at its own τ, for a point
    /// core and a segment core, on both sides and round both caps.
    #[test]
    fn core_tau_and_ray_agree() {
        let cores = [
            Core::point(DVec2::new(1.0, 2.0)),
            Core {
                a: DVec2::new(-3.0, 1.0),
                u: DVec2::from_angle(0.3),
                len: 6.0,
            },
        ];
        for core in cores {
            for i in 0..40 {
                for j in 1..6 {
                    let p =
                        core.mid() + DVec2::from_angle(i as f64 * 0.157 + 0.01) * (j as f64 * 1.7);
                    let Some(t) = core.tau(p) else { continue };
                    assert!((0.0..core.period() + 1e-12).contains(&t));
                    let (o, dir) = core.ray(t);
                    let v = p - o;
                    assert!(v.perp_dot(dir).abs() < 1e-9, "{p} off the ray at τ {t}");
                    assert!(v.dot(dir) > 0.0);
                }
            }
        }
    }

    /// A stadium around a segment core is star-shaped about it, its radius is its half-width.
    #[test]
    fn stadium_is_star_shaped_about_its_segment() {
        let core = Core {
            a: DVec2::new(0.0, 0.0),
            u: DVec2::X,
            len: 10.0,
        };
        let w = 2.0;
        let mut lp = Vec::new();
        for k in 0..=20 {
            lp.push(DVec2::new(k as f64 * 0.5, -w));
        }
        for k in 1..20 {
            lp.push(
                DVec2::new(10.0, 0.0) + w * DVec2::from_angle(-FRAC_PI_2 + k as f64 * PI / 20.0),
            );
        }
        for k in 0..=20 {
            lp.push(DVec2::new(10.0 - k as f64 * 0.5, w));
        }
        for k in 1..20 {
            lp.push(w * DVec2::from_angle(FRAC_PI_2 + k as f64 * PI / 20.0));
        }
        let pol = Polar::new(&lp, core, 0.0).expect("star-shaped");
        for k in 0..200 {
            let t = core.period() * k as f64 / 200.0;
            let r = pol.radius(t, 0.0);
            assert!((r - w).abs() < 0.02, "τ {t}: r {r}");
        }
    }
}
