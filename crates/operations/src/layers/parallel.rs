//! Parallel blocks of the tool region: the rest region's lines along the
//! longest product edge, progressing towards the product, joined into
//! zigzag blocks where a straight step-over stays inside the region, or
//! one-way lines. The first and last lines engage at most the stepover.

use glam::DVec2;
use thinplan_knowledge::SpindleDirection;
use thinplan_plan::Adjacency;

use super::plan_view::centroid;
use super::region::Geometry;
use super::STEP;
use crate::geom::{segment_inside, Edge2};

/// Parallel lines across the tool-centre region `polys`: along `dir`,
/// progressing along `progress` (±dir.perp()), at most `spacing` apart,
/// reaching both extremes, joined into zigzag blocks where a straight
/// step-over stays inside (or one block per line for one-way, travelling
/// `oneway`); with the number of lines. `cover` is the feature region and
/// the tool radius: past an open edge the centre region reaches a radius
/// beyond the feature, where a line's disc only grazes what the line
/// before it cut, so the first and last lines engage at most `spacing`
/// (one line down the middle of a feature no wider than the stepover and
/// the tool). A slab whose every edge is open (the layers above it gone
/// first) would otherwise take three times the lines.
#[allow(clippy::too_many_arguments)]
pub(super) fn parallel_blocks(
    polys: &[Vec<DVec2>],
    cover: (&[Vec<DVec2>], f64),
    dir: DVec2,
    progress: DVec2,
    spacing: f64,
    extra_line: bool,
    start_high: bool,
    oneway: Option<DVec2>,
) -> (Vec<Vec<DVec2>>, usize) {
    let frame = Frame::new(dir, progress);
    let uv: Vec<Vec<DVec2>> = polys
        .iter()
        .map(|p| p.iter().map(|q| frame.uv_of(*q)).collect())
        .collect();
    let Some((lo, hi)) = line_span(&uv, cover, spacing, frame) else {
        return (Vec::new(), 0);
    };
    let vs = line_offsets(lo, hi, spacing, extra_line);
    let n = vs.len();
    let intervals = crossings(&uv, &vs);
    let blocks = match oneway {
        Some(t) => one_way_blocks(&intervals, &vs, frame, t.dot(dir) >= 0.0),
        None => zigzag_blocks(&intervals, &vs, frame, polys, start_high),
    };
    (blocks, n)
}

/// Plan-view coordinates of the lines: u along them, v across them,
/// growing the way the passes progress.
#[derive(Clone, Copy)]
struct Frame {
    dir: DVec2,
    nrm: DVec2,
    sign: f64,
}

impl Frame {
    fn new(dir: DVec2, progress: DVec2) -> Frame {
        let nrm = dir.perp();
        let sign = progress.dot(nrm).signum();
        Frame { dir, nrm, sign }
    }

    fn uv_of(self, p: DVec2) -> DVec2 {
        DVec2::new(p.dot(self.dir), p.dot(self.nrm) * self.sign)
    }

    fn point_at(self, q: DVec2) -> DVec2 {
        self.dir * q.x + self.nrm * (q.y * self.sign)
    }
}

/// The first and last lines' offsets across (v): the region's extent less
/// a hair, narrowed by `cover` (`parallel_blocks`). `None` for an empty
/// region.
fn line_span(
    uv: &[Vec<DVec2>],
    cover: (&[Vec<DVec2>], f64),
    spacing: f64,
    frame: Frame,
) -> Option<(f64, f64)> {
    let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in uv {
        for q in p {
            vmin = vmin.min(q.y);
            vmax = vmax.max(q.y);
        }
    }
    if !vmin.is_finite() {
        return None;
    }
    let eps = 1e-4;
    let (mut lo, mut hi) = (vmin + eps, vmax - eps);
    let (region, r) = cover;
    let (mut cmin, mut cmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for q in region.iter().flatten() {
        let v = frame.uv_of(*q).y;
        cmin = cmin.min(v);
        cmax = cmax.max(v);
    }
    if cmin.is_finite() {
        // One line covers a feature no wider than the stepover and the
        // tool; else the first line (either way: layers may be mirrored)
        // engages at most the stepover.
        let (a, b) = if cmax - cmin <= spacing.min(2.0 * r) {
            let mid = 0.5 * (cmin + cmax);
            (mid, mid)
        } else {
            (cmin - r + spacing, cmax + r - spacing)
        };
        let (a, b) = (lo.max(a), hi.min(b));
        if a <= b {
            (lo, hi) = (a, b);
        } else {
            let mid = (0.5 * (cmin + cmax)).max(lo).min(hi);
            (lo, hi) = (mid, mid);
        }
    }
    Some((lo, hi))
}

/// The lines' offsets across, evenly from `lo` to `hi` at most `spacing`
/// apart (one line midway where they meet), with one line more where
/// `extra_line`.
fn line_offsets(lo: f64, hi: f64, spacing: f64, extra_line: bool) -> Vec<f64> {
    let span = (hi - lo).max(0.0);
    let mut n = if span < 1e-9 {
        1
    } else {
        (span / spacing).ceil() as usize + 1
    };
    if extra_line {
        n += 1;
    }
    (0..n)
        .map(|i| {
            if n == 1 {
                (lo + hi) / 2.0
            } else {
                lo + span * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

/// Where each line runs inside the region: its intervals along u.
fn crossings(uv: &[Vec<DVec2>], vs: &[f64]) -> Vec<Vec<(f64, f64)>> {
    vs.iter()
        .map(|&v| {
            let mut xs = Vec::new();
            for p in uv {
                let m = p.len();
                for i in 0..m {
                    let (a, b) = (p[i], p[(i + 1) % m]);
                    if (a.y > v) != (b.y > v) {
                        xs.push(a.x + (v - a.y) * (b.x - a.x) / (b.y - a.y));
                    }
                }
            }
            xs.sort_by(f64::total_cmp);
            xs.chunks_exact(2)
                .map(|c| (c[0], c[1]))
                .filter(|c| c.1 - c.0 > 1e-6)
                .collect()
        })
        .collect()
}

/// One block per interval, every one travelling the same way.
fn one_way_blocks(
    intervals: &[Vec<(f64, f64)>],
    vs: &[f64],
    frame: Frame,
    forward: bool,
) -> Vec<Vec<DVec2>> {
    let mut blocks: Vec<Vec<DVec2>> = Vec::new();
    for (li, ivs) in intervals.iter().enumerate() {
        for iv in ivs {
            let (a, b) = if forward { (iv.0, iv.1) } else { (iv.1, iv.0) };
            blocks.push(vec![
                frame.point_at(DVec2::new(a, vs[li])),
                frame.point_at(DVec2::new(b, vs[li])),
            ]);
        }
    }
    blocks
}

/// Zigzag blocks: each starts at the first line with an interval left
/// (the one whose end is nearest where the last block ended) and steps
/// over to the next line's nearest overlapping interval while the
/// straight step-over stays inside `polys`.
fn zigzag_blocks(
    intervals: &[Vec<(f64, f64)>],
    vs: &[f64],
    frame: Frame,
    polys: &[Vec<DVec2>],
    start_high: bool,
) -> Vec<Vec<DVec2>> {
    let mut used: Vec<Vec<bool>> = intervals.iter().map(|l| vec![false; l.len()]).collect();
    let mut blocks: Vec<Vec<DVec2>> = Vec::new();
    let mut last_end: Option<f64> = None;
    while let Some(li) = (0..intervals.len()).find(|&l| used[l].iter().any(|u| !u)) {
        // The interval whose end is nearest to where the last block ended.
        let ii = (0..intervals[li].len())
            .filter(|&i| !used[li][i])
            .min_by(|&a, &b| {
                let key = |i: usize| {
                    let iv = intervals[li][i];
                    match last_end {
                        Some(u) => (iv.0 - u).abs().min((iv.1 - u).abs()),
                        None => iv.0,
                    }
                };
                key(a).total_cmp(&key(b))
            })
            .unwrap_or(0);
        used[li][ii] = true;
        let iv = intervals[li][ii];
        let high_first = match last_end {
            Some(u) => (iv.1 - u).abs() < (iv.0 - u).abs(),
            None => start_high,
        };
        let (a, b) = if high_first {
            (iv.1, iv.0)
        } else {
            (iv.0, iv.1)
        };
        let mut block = vec![
            frame.point_at(DVec2::new(a, vs[li])),
            frame.point_at(DVec2::new(b, vs[li])),
        ];
        let mut cur_u = b;
        let mut cur_iv = iv;
        let mut l = li;
        while l + 1 < intervals.len() {
            let nl = l + 1;
            let cand = (0..intervals[nl].len())
                .filter(|&i| !used[nl][i])
                .filter(|&i| {
                    let c = intervals[nl][i];
                    c.0 <= cur_iv.1 + 1e-6 && c.1 >= cur_iv.0 - 1e-6
                })
                .min_by(|&x, &y| {
                    let dx = |i: usize| {
                        let c = intervals[nl][i];
                        (c.0 - cur_u).abs().min((c.1 - cur_u).abs())
                    };
                    dx(x).total_cmp(&dx(y))
                });
            let Some(ci) = cand else { break };
            let c = intervals[nl][ci];
            let (na, nb) = if (c.0 - cur_u).abs() <= (c.1 - cur_u).abs() {
                (c.0, c.1)
            } else {
                (c.1, c.0)
            };
            let from = frame.point_at(DVec2::new(cur_u, vs[l]));
            let to = frame.point_at(DVec2::new(na, vs[nl]));
            if !segment_inside(from, to, polys, STEP / 2.0) {
                break;
            }
            used[nl][ci] = true;
            block.push(to);
            block.push(frame.point_at(DVec2::new(nb, vs[nl])));
            cur_u = nb;
            cur_iv = c;
            l = nl;
        }
        last_end = Some(cur_u);
        blocks.push(block);
    }
    blocks
}

/// The lines' direction, along the longest product edge (else the longest
/// edge), and the way they progress: towards the product, so the boundary
/// region is cut last.
pub(super) fn pass_direction(
    edges: &[(Vec<Edge2>, Vec<Adjacency>)],
    g: &Geometry,
) -> Result<(DVec2, DVec2), String> {
    let longest = |pred: &dyn Fn(Adjacency) -> bool| {
        edges
            .iter()
            .flat_map(|(es, adj)| es.iter().zip(adj.iter()))
            .filter(|(_, a)| pred(**a))
            .max_by(|a, b| a.0.length().total_cmp(&b.0.length()))
            .map(|(e, _)| *e)
    };
    let ref_edge = longest(&|a| a == Adjacency::Product)
        .or_else(|| longest(&|_| true))
        .ok_or("no edges")?;
    let dir = {
        let t = (ref_edge.b - ref_edge.a).normalize_or_zero();
        if t == DVec2::ZERO {
            DVec2::X
        } else {
            t
        }
    };
    // Passes progress towards the product (the boundary region is last).
    let progress = if g.product.is_empty() {
        dir.perp()
    } else {
        let pm: DVec2 =
            g.product.iter().map(|e| e.midpoint()).sum::<DVec2>() / g.product.len() as f64;
        let cm = centroid(&g.centre_polys);
        if (pm - cm).dot(dir.perp()) >= 0.0 {
            dir.perp()
        } else {
            -dir.perp()
        }
    };
    Ok((dir, progress))
}

/// The sign of the spindle's turn (clockwise, M3, positive): one-way lines
/// travel so that they cut down milling.
pub(super) fn spin_sign(s: SpindleDirection) -> f64 {
    match s {
        SpindleDirection::Clockwise => 1.0,
        SpindleDirection::CounterClockwise => -1.0,
    }
}
