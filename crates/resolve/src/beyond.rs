//! Where a section's boundary lies beyond a feature's product edge: a ray
//! from the edge towards the product, cast against every loop of the
//! part's section at a height.
//!
//! An isogrid's section holds thousands of segments and each sloped slab
//! asks for every product edge at several heights, so the segments are
//! bucketed once per section: the ray visits only the cells it crosses
//! (nearest first, stopping past the nearest hit) and the inside test only
//! the edges of the row its point lies in. The answers are those of the
//! plain loops over every segment, which the tests compare.

use crate::section::Shapes;

/// One section: its loops, and their segments and its filled region's
/// bucketed.
pub(crate) struct Section {
    loops: Vec<Vec<[f64; 2]>>,
    grid: Grid,
    rows: Grid,
}

/// Segments bucketed on a uniform grid of square cells.
struct Grid {
    lo: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    segs: Vec<([f64; 2], [f64; 2])>,
    /// Segment indices per cell, row-major.
    cells: Vec<Vec<u32>>,
}

impl Grid {
    /// `columns`: false buckets by rows only (one cell across).
    fn new(segs: Vec<([f64; 2], [f64; 2])>, columns: bool) -> Grid {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (a, b) in &segs {
            for p in [a, b] {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if segs.is_empty() || !lo[0].is_finite() || !hi[0].is_finite() {
            return Grid {
                lo: [0.0; 2],
                cell: 1.0,
                nx: 0,
                ny: 0,
                segs,
                cells: Vec::new(),
            };
        }
        let (w, h) = ((hi[0] - lo[0]).max(1e-9), (hi[1] - lo[1]).max(1e-9));
        // About one segment per cell (per row: a few times its square
        // root), at most 4,096 cells a side.
        let n = segs.len() as f64;
        let cell = if columns {
            (w * h / n).sqrt()
        } else {
            h / (4.0 * n.sqrt()).ceil()
        }
        .max(w.max(h) / 4096.0)
        .max(1e-6);
        let nx = if columns {
            (w / cell).floor() as usize + 1
        } else {
            1
        };
        let ny = (h / cell).floor() as usize + 1;
        let mut g = Grid {
            lo,
            cell,
            nx,
            ny,
            segs,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, (a, b)) in g.segs.iter().enumerate() {
            let (x0, x1) = if columns {
                (g.col(a[0].min(b[0])), g.col(a[0].max(b[0])))
            } else {
                (0, 0)
            };
            let (y0, y1) = (g.row(a[1].min(b[1])), g.row(a[1].max(b[1])));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.cells[y * g.nx + x].push(i as u32);
                }
            }
        }
        g
    }

    /// The column of `x`, clamped to the grid, taken a hair wide so a
    /// coordinate on a cell's border lands in both (the segment too).
    fn col(&self, x: f64) -> usize {
        (((x - self.lo[0]) / self.cell).floor().max(0.0) as usize).min(self.nx - 1)
    }

    fn row(&self, y: f64) -> usize {
        (((y - self.lo[1]) / self.cell).floor().max(0.0) as usize).min(self.ny - 1)
    }
}

impl Section {
    pub(crate) fn new(loops: Vec<Vec<[f64; 2]>>, part: Shapes) -> Section {
        let ring = |c: &Vec<[f64; 2]>| {
            let n = c.len();
            (0..n).map(|i| (c[i], c[(i + 1) % n])).collect::<Vec<_>>()
        };
        let grid = Grid::new(loops.iter().flat_map(ring).collect(), true);
        let rows = Grid::new(part.iter().flatten().flat_map(ring).collect(), false);
        Section { loops, grid, rows }
    }

    /// Whether `p` lies in the filled section (even-odd, as
    /// `section::contains`).
    pub(crate) fn contains(&self, p: [f64; 2]) -> bool {
        let g = &self.rows;
        if g.ny == 0 || !p[1].is_finite() {
            return false;
        }
        let r = ((p[1] - g.lo[1]) / g.cell).floor();
        if r < 0.0 || r >= g.ny as f64 {
            return false;
        }
        let mut inside = false;
        for &i in &g.cells[r as usize] {
            let (a, b) = g.segs[i as usize];
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > p[0] {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// The smallest parameter `t ≥ 0` at which the ray `p + t·dir` meets a
    /// segment of the loops, if some `t ≤ reach` does (else infinity).
    fn ray(&self, p: [f64; 2], dir: [f64; 2], reach: f64) -> f64 {
        let g = &self.grid;
        let mut best = f64::INFINITY;
        if g.nx == 0 {
            return best;
        }
        let hit = |best: &mut f64, i: u32| {
            let (a, b) = g.segs[i as usize];
            let e = [b[0] - a[0], b[1] - a[1]];
            let den = dir[0] * e[1] - dir[1] * e[0];
            if den.abs() < 1e-15 {
                return;
            }
            let w = [a[0] - p[0], a[1] - p[1]];
            let t = (w[0] * e[1] - w[1] * e[0]) / den;
            let u = (w[0] * dir[1] - w[1] * dir[0]) / den;
            if t >= 0.0 && (0.0..=1.0).contains(&u) && t < *best {
                *best = t;
            }
        };
        // The stretch of the ray inside the grid's box, a cell wider all
        // round (segments on the box's border).
        let m = g.cell;
        let hi = [
            g.lo[0] + g.nx as f64 * g.cell + m,
            g.lo[1] + g.ny as f64 * g.cell + m,
        ];
        let lo = [g.lo[0] - m, g.lo[1] - m];
        let (mut t0, mut t1) = (0.0f64, reach.max(0.0));
        for k in 0..2 {
            if dir[k].abs() < 1e-300 {
                if p[k] < lo[k] || p[k] > hi[k] {
                    return best;
                }
            } else {
                let (a, b) = ((lo[k] - p[k]) / dir[k], (hi[k] - p[k]) / dir[k]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        if t0 > t1 {
            return best;
        }
        // Cells along the ray (Amanatides & Woo), nearest first; a hit
        // inside a cell entered later than the best so far cannot be nearer.
        let at = |t: f64, k: usize| p[k] + dir[k] * t;
        let clamp = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
        let mut ix = clamp((at(t0, 0) - g.lo[0]) / g.cell, g.nx);
        let mut iy = clamp((at(t0, 1) - g.lo[1]) / g.cell, g.ny);
        let next = |i: usize, k: usize| {
            if dir[k] > 0.0 {
                (g.lo[k] + (i + 1) as f64 * g.cell - p[k]) / dir[k]
            } else if dir[k] < 0.0 {
                (g.lo[k] + i as f64 * g.cell - p[k]) / dir[k]
            } else {
                f64::INFINITY
            }
        };
        let delta = |k: usize| {
            if dir[k] != 0.0 {
                g.cell / dir[k].abs()
            } else {
                f64::INFINITY
            }
        };
        let (mut tx, mut ty) = (next(ix, 0), next(iy, 1));
        let (dx, dy) = (delta(0), delta(1));
        let mut entry = t0;
        loop {
            if entry > best || entry > t1 {
                break;
            }
            for &i in &g.cells[iy * g.nx + ix] {
                hit(&mut best, i);
            }
            if tx < ty {
                entry = tx;
                tx += dx;
                if dir[0] > 0.0 {
                    ix += 1;
                    if ix >= g.nx {
                        break;
                    }
                } else {
                    if ix == 0 {
                        break;
                    }
                    ix -= 1;
                }
            } else {
                entry = ty;
                ty += dy;
                if dir[1] > 0.0 {
                    iy += 1;
                    if iy >= g.ny {
                        break;
                    }
                } else {
                    if iy == 0 {
                        break;
                    }
                    iy -= 1;
                }
            }
        }
        best
    }
}

/// Where the part's section boundary crosses the line through `p` along
/// the unit normal `n` (towards the product): the signed distance along
/// `n` of the crossing nearest `p` on the side the face lies (towards the
/// region where `p` is in the product, else towards the product). Where
/// the line meets none: the product covers the whole reach (`-reach`), or
/// the nearest product in any direction (`reach` where there is none).
pub(crate) fn face_beyond(s: &Section, p: [f64; 2], n: [f64; 2], reach: f64) -> f64 {
    // A point on the boundary (an edge on a vertical face, sampled at
    // another height) is inside or not by rounding, and a ray from it may
    // miss the face it starts on and meet the product's far side: the face
    // through it is asked for first, both ways.
    let ahead = s.ray(p, n, ON_FACE);
    let behind = s.ray(p, [-n[0], -n[1]], ON_FACE);
    if ahead <= ON_FACE || behind <= ON_FACE {
        return if ahead <= behind { ahead } else { -behind };
    }
    let inside = s.contains(p);
    let dir = if inside { [-n[0], -n[1]] } else { n };
    let best = s.ray(p, dir, reach);
    match (best <= reach, inside) {
        (true, true) => -best,
        (true, false) => best,
        (false, true) => -reach,
        (false, false) => s
            .loops
            .iter()
            .flat_map(|c| (0..c.len()).map(move |i| seg_distance(p, c[i], c[(i + 1) % c.len()])))
            .fold(reach, f64::min),
    }
}

/// How near a face a point is taken to lie on it (mm): far below any
/// machining tolerance, far above the rounding of sections and booleans.
const ON_FACE: f64 = 1e-6;

fn seg_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let l2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if l2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - ab[0] * t, ap[1] - ab[1] * t];
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The plain answer: every segment tried.
    fn ray_plain(loops: &[Vec<[f64; 2]>], p: [f64; 2], dir: [f64; 2]) -> f64 {
        let mut best = f64::INFINITY;
        for c in loops {
            let m = c.len();
            for i in 0..m {
                let (a, b) = (c[i], c[(i + 1) % m]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let den = dir[0] * e[1] - dir[1] * e[0];
                if den.abs() < 1e-15 {
                    continue;
                }
                let w = [a[0] - p[0], a[1] - p[1]];
                let t = (w[0] * e[1] - w[1] * e[0]) / den;
                let u = (w[0] * dir[1] - w[1] * dir[0]) / den;
                if t >= 0.0 && (0.0..=1.0).contains(&u) && t < best {
                    best = t;
                }
            }
        }
        best
    }

    /// Star-shaped loops (rings of pockets, as a grid's section has).
    fn loops_strategy() -> impl Strategy<Value = Vec<Vec<[f64; 2]>>> {
        prop::collection::vec(
            (
                -50.0f64..50.0,
                -50.0f64..50.0,
                prop::collection::vec(0.5f64..8.0, 3..24),
            ),
            1..12,
        )
        .prop_map(|rings| {
            rings
                .into_iter()
                .map(|(cx, cy, radii)| {
                    let n = radii.len();
                    radii
                        .iter()
                        .enumerate()
                        .map(|(i, r)| {
                            let a = std::f64::consts::TAU * i as f64 / n as f64;
                            [cx + r * a.cos(), cy + r * a.sin()]
                        })
                        .collect()
                })
                .collect()
        })
    }

    proptest! {
        #[test]
        fn the_bucketed_ray_and_inside_test_answer_as_the_plain_loops(
            loops in loops_strategy(),
            px in -70.0f64..70.0,
            py in -70.0f64..70.0,
            ang in 0.0f64..std::f64::consts::TAU,
            reach in 0.1f64..200.0,
        ) {
            let part: Shapes = vec![loops.clone()];
            let s = Section::new(loops.clone(), part.clone());
            let p = [px, py];
            prop_assert_eq!(s.contains(p), crate::section::contains(&part, p));
            let dir = [ang.cos(), ang.sin()];
            let plain = ray_plain(&loops, p, dir);
            let fast = s.ray(p, dir, reach);
            if plain <= reach {
                prop_assert_eq!(fast, plain);
            } else {
                prop_assert!(fast > reach);
            }
        }

        /// A point on a wall's face, as rounding puts it (a hair inside or
        /// outside), reads the face through it, never the wall's far side.
        #[test]
        fn a_point_on_a_face_reads_that_face_not_the_far_side(
            ang in 0.0f64..std::f64::consts::TAU,
            thick in 0.5f64..5.0,
            t in 0.01f64..0.99,
            ox in -100.0f64..100.0,
            oy in -100.0f64..100.0,
        ) {
            let (c, s_) = (ang.cos(), ang.sin());
            let at = |x: f64, y: f64| [ox + c * x - s_ * y, oy + s_ * x + c * y];
            // The wall [0, 80] × [0, thick], counter-clockwise: its face
            // towards +y runs from (80, thick) to (0, thick).
            let wall = vec![at(0.0, 0.0), at(80.0, 0.0), at(80.0, thick), at(0.0, thick)];
            let sec = Section::new(vec![wall.clone()], vec![vec![wall.clone()]]);
            let (a, b) = (wall[2], wall[3]);
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            // Towards the product: -y in the wall's frame.
            let n = [s_, -c];
            let v = face_beyond(&sec, p, n, 50.0);
            prop_assert!(v.abs() <= ON_FACE, "{v} (wall {thick} thick)");
        }

        #[test]
        fn axis_rays_along_cell_borders_find_the_same_crossing(
            loops in loops_strategy(),
            k in -60i32..60,
            sign in prop::bool::ANY,
            vertical in prop::bool::ANY,
        ) {
            let s = Section::new(loops.clone(), vec![loops.clone()]);
            let d = if sign { 1.0 } else { -1.0 };
            let (p, dir) = if vertical {
                ([k as f64, -80.0 * d], [0.0, d])
            } else {
                ([-80.0 * d, k as f64], [d, 0.0])
            };
            let plain = ray_plain(&loops, p, dir);
            let fast = s.ray(p, dir, 500.0);
            if plain <= 500.0 {
                prop_assert_eq!(fast, plain);
            } else {
                prop_assert!(fast > 500.0);
            }
        }
    }
}
