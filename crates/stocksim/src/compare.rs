//! The part's top-height field on the Z-map grid, the ideal 3-axis result
//! (what the program's tools could reach without gouging), and the per-cell
//! classification of the simulated stock.

use std::collections::VecDeque;
use std::f64::consts::SQRT_2;

use glam::DVec2;
use serde::Serialize;
use thinplan_brep::{tessellate, Brep, Mesh, TessTolerance};

use crate::tools::ToolShape;
use crate::zmap::Grid;

/// The part's top height on the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct PartField {
    /// Top height at each cell centre (the highest hit of a vertical ray
    /// against the tessellation); the floor where no part lies above.
    pub top: Vec<f32>,
    /// The lowest of the tops at the centre and at the four points `near`
    /// mm away along ±X and ±Y: a wall that passes within `near` of a
    /// centre does not turn a cut at the wall into a gouge.
    pub lo: Vec<f32>,
    /// The highest of the tops at the centre and at the four points `far`
    /// mm away: a wall within `far` of a centre does not turn material at
    /// its foot into leftover.
    pub hi: Vec<f32>,
    /// Whether a part face passes within `near` of the centre: one of the
    /// tops `near` away differs from the centre's by more than `far`.
    pub face: Vec<bool>,
}

/// The part's height field by vertical rays (see [`PartField`]): `near` is
/// how near a wall may pass to a centre and a cut there not be a gouge,
/// `far` how near it may pass and material there not be leftover. Returns
/// the field and warnings (faces that failed to tessellate).
pub fn part_heights(
    brep: &Brep,
    grid: &Grid,
    floor: f64,
    near: f64,
    far: f64,
) -> (PartField, Vec<String>) {
    let tol = TessTolerance {
        chord: (near.min(far) / 5.0).clamp(1e-4, 0.01),
        angle: 0.2,
    };
    let mesh = tessellate(brep, &tol);
    let warnings = mesh
        .failed_faces
        .iter()
        .map(|(f, e)| {
            format!("part face {f} not tessellated ({e}); its top is missing from the comparison")
        })
        .collect();
    let top = raster(&mesh, grid, floor, DVec2::ZERO);
    let around = |lateral: f64, keep: fn(f32, f32) -> f32| {
        let mut out = top.clone();
        if lateral > 0.0 {
            for d in [DVec2::X, DVec2::NEG_X, DVec2::Y, DVec2::NEG_Y] {
                let f = raster(&mesh, grid, floor, d * lateral);
                for (o, v) in out.iter_mut().zip(f) {
                    *o = keep(*o, v);
                }
            }
        }
        out
    };
    let lo = around(near, f32::min);
    let hi = around(far, f32::max);
    let near_hi = around(near, f32::max);
    let face = top
        .iter()
        .zip(lo.iter().zip(&near_hi))
        .map(|(&t, (&l, &h))| (t - l) as f64 > far || (h - t) as f64 > far)
        .collect();
    (PartField { top, lo, hi, face }, warnings)
}

/// Highest ray hit per cell, rays at the cell centres shifted by `off`.
fn raster(mesh: &Mesh, grid: &Grid, floor: f64, off: DVec2) -> Vec<f32> {
    let mut top = vec![floor as f32; grid.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|k| mesh.positions[k as usize]);
        let (a2, b2, c2) = (a.truncate() - off, b.truncate() - off, c.truncate() - off);
        let area = (b2 - a2).perp_dot(c2 - a2);
        if area.abs() < 1e-12 {
            continue; // vertical: no ray hits its interior
        }
        let lo = a2.min(b2).min(c2);
        let hi = a2.max(b2).max(c2);
        let (Some((i0, i1)), Some((j0, j1))) = (grid.cols(lo.x, hi.x), grid.rows(lo.y, hi.y))
        else {
            continue;
        };
        // Inclusive edges (a ray on a shared edge hits both triangles, same z).
        let eps = -1e-9 * area.abs();
        for j in j0..=j1 {
            for i in i0..=i1 {
                let p = grid.center(i, j);
                let w0 = (b2 - p).perp_dot(c2 - p);
                let w1 = (c2 - p).perp_dot(a2 - p);
                let w2 = (a2 - p).perp_dot(b2 - p);
                let inside = if area > 0.0 {
                    w0 >= eps && w1 >= eps && w2 >= eps
                } else {
                    w0 <= -eps && w1 <= -eps && w2 <= -eps
                };
                if inside {
                    let z = (w0 * a.z + w1 * b.z + w2 * c.z) / area;
                    let k = j * grid.nx + i;
                    top[k] = top[k].max(z as f32);
                }
            }
        }
    }
    top
}

/// The lowest stock a tool can leave without cutting below `part` anywhere:
/// the grey-scale closing of the part's height field by the tool's lower
/// surface (dilate: the lowest safe tip height at each tool position; erode:
/// the lowest surface those positions sweep). Tool positions are the cell
/// centres, the grid padded by the tool radius on every side. The bull-nose
/// profile is the flat disc of radius `R − r` combined with the sphere cap of
/// radius `r`, each applied in turn (Minkowski sum), so the flat part uses a
/// fast row decomposition and only the rounded part is applied cell by cell.
pub fn ideal_field(part: &[f32], grid: &Grid, tool: &ToolShape, floor: f32) -> Vec<f32> {
    let c = grid.cell;
    let pad = (tool.radius() / c).ceil() as usize + 2;
    let (w, h) = (grid.nx + 2 * pad, grid.ny + 2 * pad);
    let mut f = vec![floor; w * h];
    for j in 0..grid.ny {
        let row = &part[j * grid.nx..(j + 1) * grid.nx];
        f[(j + pad) * w + pad..(j + pad) * w + pad + grid.nx].copy_from_slice(row);
    }
    let core = (tool.radius() - tool.corner_radius) / c;
    let cap = sphere_offsets(tool.corner_radius, c);
    // Where a tool may stand is decided against part cells by their centres,
    // but part may lie anywhere in a cell, up to half its diagonal from the
    // centre: a position may then stand that much nearer a wall than any
    // real tool, and its reach spill past the true limit (by that, divided
    // by sin(θ/2) along the bisector of a corner of angle θ). Standing
    // positions keep the half-diagonal more (the reach is at most that
    // short, near walls only); what they sweep is the true tool's.
    let mut g = disc_filter(&f, w, h, core + SQRT_2 / 2.0, true);
    if !cap.is_empty() {
        g = offsets_filter(&g, w, h, &cap, true);
        g = offsets_filter(&g, w, h, &cap, false);
    }
    g = disc_filter(&g, w, h, core, false);
    let mut out = vec![floor; grid.len()];
    for j in 0..grid.ny {
        out[j * grid.nx..(j + 1) * grid.nx]
            .copy_from_slice(&g[(j + pad) * w + pad..(j + pad) * w + pad + grid.nx]);
    }
    out
}

/// Offsets `(di, dj, height)` of a sphere cap of radius `r` (height above its
/// lowest point), in cells.
fn sphere_offsets(r: f64, cell: f64) -> Vec<(isize, isize, f32)> {
    if r <= 0.0 {
        return vec![];
    }
    let m = (r / cell).floor() as isize;
    let mut v = Vec::new();
    for dj in -m..=m {
        for di in -m..=m {
            let d = ((di * di + dj * dj) as f64).sqrt() * cell;
            if d <= r * (1.0 + 1e-9) {
                v.push((di, dj, (r - (r * r - d * d).max(0.0).sqrt()) as f32));
            }
        }
    }
    v
}

/// max (`dilate`) of `f(q+δ) − h(δ)`, or min of `f(q+δ) + h(δ)`, over the offsets.
fn offsets_filter(
    f: &[f32],
    w: usize,
    h: usize,
    offs: &[(isize, isize, f32)],
    dilate: bool,
) -> Vec<f32> {
    let mut out = f.to_vec();
    for j in 0..h {
        for i in 0..w {
            let mut best = f[j * w + i];
            for &(di, dj, hh) in offs {
                let (x, y) = (i as isize + di, j as isize + dj);
                if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                    continue;
                }
                let v = f[y as usize * w + x as usize];
                if dilate {
                    best = best.max(v - hh);
                } else {
                    best = best.min(v + hh);
                }
            }
            out[j * w + i] = best;
        }
    }
    out
}

/// Flat max/min filter over the disc of `radius` cells (cell centres within
/// it), by rows: the disc is a stack of row segments, each a sliding window.
fn disc_filter(f: &[f32], w: usize, h: usize, radius: f64, max: bool) -> Vec<f32> {
    let m = (radius + 1e-9).floor().max(0.0) as usize;
    let half = |dj: usize| {
        ((radius * radius - (dj * dj) as f64).max(0.0) + 1e-9)
            .sqrt()
            .floor() as usize
    };
    let mut out = f.to_vec();
    let mut widths: Vec<usize> = (0..=m).map(half).collect();
    widths.sort_unstable();
    widths.dedup();
    let mut rowbuf = vec![0f32; w];
    let mut slid = vec![0f32; w * h];
    for &k in &widths {
        for j in 0..h {
            sliding(&f[j * w..(j + 1) * w], k, &mut rowbuf, max);
            slid[j * w..(j + 1) * w].copy_from_slice(&rowbuf);
        }
        for dj in 0..=m {
            if half(dj) != k {
                continue;
            }
            for sgn in [-1isize, 1] {
                if dj == 0 && sgn < 0 {
                    continue;
                }
                let d = sgn * dj as isize;
                for j in 0..h {
                    let y = j as isize + d;
                    if y < 0 || y >= h as isize {
                        continue;
                    }
                    let src = &slid[y as usize * w..(y as usize + 1) * w];
                    let dst = &mut out[j * w..(j + 1) * w];
                    for (o, &s) in dst.iter_mut().zip(src) {
                        *o = if max { o.max(s) } else { o.min(s) };
                    }
                }
            }
        }
    }
    out
}

/// Sliding-window max/min of half-width `k` (monotone deque, O(n)).
fn sliding(src: &[f32], k: usize, out: &mut [f32], max: bool) {
    let n = src.len();
    let mut dq: VecDeque<usize> = VecDeque::new();
    let better = |a: f32, b: f32| if max { a >= b } else { a <= b };
    for i in 0..n + k {
        if i < n {
            while let Some(&b) = dq.back() {
                if better(src[i], src[b]) {
                    dq.pop_back();
                } else {
                    break;
                }
            }
            dq.push_back(i);
        }
        if i >= k {
            let o = i - k;
            while let Some(&f) = dq.front() {
                if f + k < o {
                    dq.pop_front();
                } else {
                    break;
                }
            }
            out[o] = src[dq[0]];
        }
    }
}

/// What a cell of the final stock is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum CellClass {
    /// Within tolerance of the part.
    Ok,
    /// Stock below the part by more than the tolerance.
    Gouge,
    /// Stock above the part that one of the program's tools could have
    /// removed down to the part.
    Missed,
    /// Stock above the part that none of the program's tools can reach.
    Unreachable,
    /// Stock above what the program's tools could leave, where none of them
    /// reaches the part: the part is unreachable there, and a tool could
    /// only have taken some off the top (the rim of a column in a corner no
    /// tool fits, a ridge on a face no flat bottom follows).
    AboveReach,
}

/// Classifies every cell: a gouge below the part's `lo` − tol, leftover
/// above its `hi` + tol (see [`PartField`]); leftover above the ideal + tol
/// is missed where the ideal comes within tol of the part, else above
/// reach.
pub fn classify(stock: &[f32], part: &PartField, ideal: &[f32], tol: f64) -> Vec<CellClass> {
    stock
        .iter()
        .zip(part.lo.iter().zip(&part.hi))
        .zip(ideal)
        .map(|((&s, (&lo, &hi)), &id)| {
            let (s, lo, hi, id) = (s as f64, lo as f64, hi as f64, id as f64);
            if s < lo - tol {
                CellClass::Gouge
            } else if s > hi + tol {
                if s <= id + tol {
                    CellClass::Unreachable
                } else if id <= hi + tol {
                    CellClass::Missed
                } else {
                    CellClass::AboveReach
                }
            } else {
                CellClass::Ok
            }
        })
        .collect()
}

/// A 4-connected patch of cells of one class.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Region {
    pub cells: usize,
    /// Σ |stock − part| · cell area, mm³.
    pub volume_mm3: f64,
    /// Largest |stock − part| in the patch, mm.
    pub worst_mm: f64,
    /// Cell centre of the worst cell.
    pub at: [f64; 2],
    /// The program line that last cut the worst cell (gouges), if any.
    pub line: Option<usize>,
    /// `[xmin, ymin, xmax, ymax]` of the patch's cell centres.
    pub bbox: [f64; 4],
}

/// Finds the patches of `class`, largest volume first.
pub fn regions(
    classes: &[CellClass],
    class: CellClass,
    stock: &[f32],
    part: &[f32],
    last_line: &[u32],
    grid: &Grid,
) -> Vec<Region> {
    let mut seen = vec![false; classes.len()];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for start in 0..classes.len() {
        if seen[start] || classes[start] != class {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut reg = Region {
            cells: 0,
            volume_mm3: 0.0,
            worst_mm: -1.0,
            at: [0.0; 2],
            line: None,
            bbox: [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
        };
        while let Some(k) = stack.pop() {
            let (i, j) = (k % grid.nx, k / grid.nx);
            let c = grid.center(i, j);
            let d = (stock[k] as f64 - part[k] as f64).abs();
            reg.cells += 1;
            reg.volume_mm3 += d * grid.cell_area();
            // Ties go to the lowest index, so the result does not depend on the fill order.
            if d > reg.worst_mm || (d == reg.worst_mm && k < idx_of(&reg.at, grid)) {
                reg.worst_mm = d;
                reg.at = [c.x, c.y];
                reg.line = (last_line[k] > 0).then_some(last_line[k] as usize);
            }
            reg.bbox = [
                reg.bbox[0].min(c.x),
                reg.bbox[1].min(c.y),
                reg.bbox[2].max(c.x),
                reg.bbox[3].max(c.y),
            ];
            let mut push = |n: usize| {
                if !seen[n] && classes[n] == class {
                    seen[n] = true;
                    stack.push(n);
                }
            };
            if i > 0 {
                push(k - 1);
            }
            if i + 1 < grid.nx {
                push(k + 1);
            }
            if j > 0 {
                push(k - grid.nx);
            }
            if j + 1 < grid.ny {
                push(k + grid.nx);
            }
        }
        if class != CellClass::Gouge {
            reg.line = None;
        }
        out.push(reg);
    }
    out.sort_by(|a, b| {
        b.volume_mm3
            .total_cmp(&a.volume_mm3)
            .then(a.at[1].total_cmp(&b.at[1]))
            .then(a.at[0].total_cmp(&b.at[0]))
    });
    out
}

fn idx_of(at: &[f64; 2], grid: &Grid) -> usize {
    let i = ((at[0] - grid.x0) / grid.cell).floor().max(0.0) as usize;
    let j = ((at[1] - grid.y0) / grid.cell).floor().max(0.0) as usize;
    j * grid.nx + i
}
