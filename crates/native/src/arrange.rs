//! A 2D arrangement boolean on regions bounded by lines and true arcs.
//!
//! All boundary segments of all input regions are split at every mutual
//! intersection and at every vertex lying on another segment; coincident
//! pieces are merged. For each piece the number of regions of each class
//! covering its left and right sides is counted exactly (the regions whose
//! boundary runs along the piece are known; every other region is tested at
//! the piece's midpoint). A predicate on those counts says what is inside
//! the result; pieces with inside on exactly one side are kept, oriented
//! with the inside on the left, and chained into loops (taking the sharpest
//! left turn where several continue). This does union, difference and
//! intersection of many operands with holes in one pass, keeps arcs exact,
//! and lets the caller reject overlaps (a count above one).

use std::collections::HashMap;

use cavalier_contours::polyline::{pline_seg_intr, PlineSegIntr, PlineVertex, Polyline};
use glam::DVec2;

use crate::geom2::{loop_area, loop_bounds, to_pline, winding, Seg};

/// One operand: loops with the region on their left (outer counter-clockwise,
/// holes clockwise), a class (the counts are per class) and a caller tag.
#[derive(Debug, Clone)]
pub struct ARegion {
    pub loops: Vec<Vec<Seg>>,
    pub class: usize,
}

/// A connected result face: outer loop counter-clockwise, holes clockwise.
#[derive(Debug, Clone)]
pub struct AFace {
    pub outer: Vec<Seg>,
    pub holes: Vec<Vec<Seg>>,
    /// Input regions covering the inside next to the face's boundary.
    pub cover: Vec<usize>,
}

impl AFace {
    pub fn area(&self) -> f64 {
        loop_area(&self.outer) + self.holes.iter().map(|h| loop_area(h)).sum::<f64>()
    }
}

#[derive(Debug, Clone)]
pub enum ArrangeError {
    /// The counts at some place fail the caller's validity test; the regions
    /// covering that place.
    Invalid { regions: Vec<usize>, at: DVec2 },
    /// The kept pieces do not chain into loops (numerical trouble).
    Topology(String),
}

/// Points merged within a tolerance, on a hash grid.
pub struct PointIndex2 {
    pub pts: Vec<DVec2>,
    grid: HashMap<(i64, i64), Vec<usize>>,
    cell: f64,
    tol: f64,
}

impl PointIndex2 {
    pub fn new(tol: f64) -> Self {
        PointIndex2 {
            pts: Vec::new(),
            grid: HashMap::new(),
            cell: tol * 4.0,
            tol,
        }
    }

    fn key(&self, p: DVec2) -> (i64, i64) {
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    pub fn id(&mut self, p: DVec2) -> usize {
        let (kx, ky) = self.key(p);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(list) = self.grid.get(&(kx + dx, ky + dy)) {
                    for &i in list {
                        let d = self.pts[i].distance(p);
                        if d <= self.tol && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, i));
                        }
                    }
                }
            }
        }
        if let Some((_, i)) = best {
            return i;
        }
        self.pts.push(p);
        let i = self.pts.len() - 1;
        self.grid.entry((kx, ky)).or_default().push(i);
        i
    }
}

fn boxes_overlap(a: &(DVec2, DVec2), b: &(DVec2, DVec2), tol: f64) -> bool {
    a.0.x <= b.1.x + tol && b.0.x <= a.1.x + tol && a.0.y <= b.1.y + tol && b.0.y <= a.1.y + tol
}

fn pv(s: &Seg) -> (PlineVertex<f64>, PlineVertex<f64>) {
    (s.vertex_a(), PlineVertex::new(s.b.x, s.b.y, 0.0))
}

struct Piece {
    va: usize,
    vb: usize,
    seg: Seg,
    /// (region, runs in the piece's direction)
    contrib: Vec<(usize, bool)>,
}

struct Kept {
    va: usize,
    vb: usize,
    seg: Seg,
    cover: Vec<usize>,
}

/// Runs the arrangement. `inside(counts)` decides membership in the result;
/// `valid(counts)` rejects impossible covers (overlaps).
pub fn arrange(
    regions: &[ARegion],
    nclass: usize,
    tol: f64,
    inside: &dyn Fn(&[u32]) -> bool,
    valid: &dyn Fn(&[u32]) -> bool,
) -> Result<Vec<AFace>, ArrangeError> {
    // 1. All segments.
    let mut segs: Vec<(Seg, usize)> = Vec::new();
    for (ri, r) in regions.iter().enumerate() {
        for l in &r.loops {
            for s in l {
                segs.push((*s, ri));
            }
        }
    }
    let bounds: Vec<(DVec2, DVec2)> = segs.iter().map(|(s, _)| s.bounds()).collect();

    // 2. Split points.
    let mut splits: Vec<Vec<DVec2>> = segs.iter().map(|(s, _)| vec![s.a, s.b]).collect();
    // Sweep over x to find candidate pairs.
    let mut order: Vec<usize> = (0..segs.len()).collect();
    order.sort_by(|&i, &j| bounds[i].0.x.total_cmp(&bounds[j].0.x));
    for (oi, &i) in order.iter().enumerate() {
        for &j in &order[oi + 1..] {
            if bounds[j].0.x > bounds[i].1.x + tol {
                break;
            }
            if !boxes_overlap(&bounds[i], &bounds[j], tol) {
                continue;
            }
            let (si, sj) = (segs[i].0, segs[j].0);
            let (v1, v2) = pv(&si);
            let (u1, u2) = pv(&sj);
            match pline_seg_intr(v1, v2, u1, u2, tol) {
                PlineSegIntr::NoIntersect => {}
                PlineSegIntr::TangentIntersect { point } | PlineSegIntr::OneIntersect { point } => {
                    let p = DVec2::new(point.x, point.y);
                    splits[i].push(p);
                    splits[j].push(p);
                }
                PlineSegIntr::TwoIntersects { point1, point2 }
                | PlineSegIntr::OverlappingLines { point1, point2 }
                | PlineSegIntr::OverlappingArcs { point1, point2 } => {
                    for point in [point1, point2] {
                        let p = DVec2::new(point.x, point.y);
                        splits[i].push(p);
                        splits[j].push(p);
                    }
                }
            }
            for e in [sj.a, sj.b] {
                if si.distance_to(e) <= tol {
                    splits[i].push(e);
                }
            }
            for e in [si.a, si.b] {
                if sj.distance_to(e) <= tol {
                    splits[j].push(e);
                }
            }
        }
    }

    // 3. Vertices and pieces.
    let mut index = PointIndex2::new(tol);
    let mut pieces: Vec<Piece> = Vec::new();
    let mut by_ends: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (si, (seg, region)) in segs.iter().enumerate() {
        let va = index.id(seg.a);
        let vb = index.id(seg.b);
        let mut pts: Vec<(f64, usize)> = vec![(0.0, va), (1.0, vb)];
        for p in &splits[si][2..] {
            let id = index.id(*p);
            if id == va || id == vb {
                continue;
            }
            let t = seg.param_of(*p).clamp(0.0, 1.0);
            pts.push((t, id));
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts.dedup_by_key(|p| p.1);
        let sweep = seg.sweep();
        for w in pts.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            if a == b {
                continue;
            }
            let piece = Seg {
                a: index.pts[a],
                b: index.pts[b],
                bulge: if seg.is_line() {
                    0.0
                } else {
                    (sweep * (t1 - t0) / 4.0).tan()
                },
            };
            let key = (a.min(b), a.max(b));
            let mid = piece.midpoint();
            let list = by_ends.entry(key).or_default();
            let found = list
                .iter()
                .copied()
                .find(|&k| pieces[k].seg.midpoint().distance(mid) <= tol * 10.0);
            match found {
                Some(k) => {
                    let same = pieces[k].va == a;
                    pieces[k].contrib.push((*region, same));
                }
                None => {
                    list.push(pieces.len());
                    pieces.push(Piece {
                        va: a,
                        vb: b,
                        seg: piece,
                        contrib: vec![(*region, true)],
                    });
                }
            }
        }
    }

    // 4. Counts on both sides of every piece.
    let plines: Vec<Vec<Polyline<f64>>> = regions
        .iter()
        .map(|r| r.loops.iter().map(|l| to_pline(l)).collect())
        .collect();
    let rbounds: Vec<(DVec2, DVec2)> = regions
        .iter()
        .map(|r| {
            r.loops.iter().fold(
                (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                |acc, l| {
                    let (lo, hi) = loop_bounds(l);
                    (acc.0.min(lo), acc.1.max(hi))
                },
            )
        })
        .collect();
    let mut kept: Vec<Kept> = Vec::new();
    for p in &pieces {
        let m = p.seg.midpoint();
        let mut base = vec![0u32; nclass];
        let mut base_list = Vec::new();
        for (ri, r) in regions.iter().enumerate() {
            if p.contrib.iter().any(|c| c.0 == ri) {
                continue;
            }
            if !boxes_overlap(&rbounds[ri], &(m, m), 0.0) {
                continue;
            }
            let w: i32 = plines[ri].iter().map(|pl| winding(pl, m)).sum();
            if w != 0 {
                base[r.class] += 1;
                base_list.push(ri);
            }
        }
        let mut left = base.clone();
        let mut right = base;
        let mut left_list = base_list.clone();
        let mut right_list = base_list;
        for &(ri, same) in &p.contrib {
            if same {
                left[regions[ri].class] += 1;
                left_list.push(ri);
            } else {
                right[regions[ri].class] += 1;
                right_list.push(ri);
            }
        }
        for (counts, list) in [(&left, &left_list), (&right, &right_list)] {
            if !valid(counts) {
                let mut regions = list.clone();
                regions.sort_unstable();
                regions.dedup();
                return Err(ArrangeError::Invalid { regions, at: m });
            }
        }
        let (il, ir) = (inside(&left), inside(&right));
        if il == ir {
            continue;
        }
        if il {
            kept.push(Kept {
                va: p.va,
                vb: p.vb,
                seg: p.seg,
                cover: left_list,
            });
        } else {
            kept.push(Kept {
                va: p.vb,
                vb: p.va,
                seg: p.seg.reversed(),
                cover: right_list,
            });
        }
    }

    // 5. Chain into loops: at each vertex take the sharpest left turn.
    let mut outgoing: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, e) in kept.iter().enumerate() {
        outgoing.entry(e.va).or_default().push(k);
    }
    let next = |k: usize| -> Option<usize> {
        let cands = outgoing.get(&kept[k].vb)?;
        if cands.len() == 1 {
            return Some(cands[0]);
        }
        let t_in = kept[k].seg.end_tangent();
        cands.iter().copied().max_by(|&a, &b| {
            let key = |c: usize| {
                let t = kept[c].seg.start_tangent();
                let ang = t_in.perp_dot(t).atan2(t_in.dot(t));
                (ang, kept[c].seg.curvature())
            };
            let (ka, kb) = (key(a), key(b));
            if (ka.0 - kb.0).abs() > 1e-9 {
                ka.0.total_cmp(&kb.0)
            } else {
                ka.1.total_cmp(&kb.1)
            }
        })
    };
    let mut used = vec![false; kept.len()];
    let mut loops: Vec<(Vec<Seg>, Vec<usize>)> = Vec::new();
    for start in 0..kept.len() {
        if used[start] {
            continue;
        }
        let mut segs_l = Vec::new();
        let mut cover = Vec::new();
        let mut cur = start;
        loop {
            if used[cur] {
                return Err(ArrangeError::Topology(format!(
                    "boundary pieces do not close near ({:.6}, {:.6})",
                    kept[cur].seg.a.x, kept[cur].seg.a.y
                )));
            }
            used[cur] = true;
            segs_l.push(kept[cur].seg);
            cover.extend_from_slice(&kept[cur].cover);
            match next(cur) {
                Some(n) if n == start => break,
                Some(n) => cur = n,
                None => {
                    return Err(ArrangeError::Topology(format!(
                        "open boundary at ({:.6}, {:.6})",
                        kept[cur].seg.b.x, kept[cur].seg.b.y
                    )))
                }
            }
        }
        cover.sort_unstable();
        cover.dedup();
        loops.push((simplify(segs_l, tol), cover));
    }

    // 6. Outer loops and their holes.
    let mut outers: Vec<(f64, AFace)> = Vec::new();
    let mut holes: Vec<(Vec<Seg>, Vec<usize>)> = Vec::new();
    for (l, cover) in loops {
        let a = loop_area(&l);
        if a.abs() <= tol * tol {
            continue;
        }
        if a > 0.0 {
            outers.push((
                a,
                AFace {
                    outer: l,
                    holes: Vec::new(),
                    cover,
                },
            ));
        } else {
            holes.push((l, cover));
        }
    }
    let outer_pl: Vec<Polyline<f64>> = outers.iter().map(|(_, f)| to_pline(&f.outer)).collect();
    for (h, cover) in holes {
        let probe = h[0].midpoint();
        let best = outers
            .iter()
            .enumerate()
            .filter(|(i, _)| winding(&outer_pl[*i], probe) != 0)
            .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
            .map(|(i, _)| i);
        match best {
            Some(i) => {
                outers[i].1.holes.push(h);
                outers[i].1.cover.extend(cover);
            }
            None => {
                return Err(ArrangeError::Topology(format!(
                    "a hole loop near ({:.6}, {:.6}) lies in no outer loop",
                    probe.x, probe.y
                )))
            }
        }
    }
    Ok(outers
        .into_iter()
        .map(|(_, mut f)| {
            f.cover.sort_unstable();
            f.cover.dedup();
            f
        })
        .collect())
}

/// Merges consecutive collinear lines and consecutive arcs of one circle.
pub fn simplify(mut segs: Vec<Seg>, tol: f64) -> Vec<Seg> {
    let mergeable = |s: &Seg, t: &Seg| -> Option<Seg> {
        if s.is_line() && t.is_line() {
            let d1 = (s.b - s.a).normalize();
            let d2 = (t.b - t.a).normalize();
            if d1.perp_dot(d2).abs() < 1e-9 && d1.dot(d2) > 0.0 {
                return Some(Seg::line(s.a, t.b));
            }
            return None;
        }
        if s.is_line() || t.is_line() || s.bulge.signum() != t.bulge.signum() {
            return None;
        }
        let (c1, r1) = s.centre_radius();
        let (c2, r2) = t.centre_radius();
        if c1.distance(c2) > tol || (r1 - r2).abs() > tol {
            return None;
        }
        let sweep = s.sweep() + t.sweep();
        if sweep.abs() >= std::f64::consts::TAU - 1e-6 {
            return None;
        }
        Some(Seg {
            a: s.a,
            b: t.b,
            bulge: (sweep / 4.0).tan(),
        })
    };
    let mut changed = true;
    while changed && segs.len() > 2 {
        changed = false;
        let n = segs.len();
        for i in 0..n {
            let j = (i + 1) % n;
            if let Some(m) = mergeable(&segs[i], &segs[j]) {
                segs[i] = m;
                segs.remove(j);
                changed = true;
                break;
            }
        }
    }
    segs
}

/// True when a loop is one full circle (arcs of one circle, same sense).
pub fn is_full_circle(segs: &[Seg], tol: f64) -> Option<(DVec2, f64, bool)> {
    if segs.iter().any(Seg::is_line) {
        return None;
    }
    let (c, r) = segs[0].centre_radius();
    let ccw = segs[0].bulge > 0.0;
    for s in segs {
        let (c2, r2) = s.centre_radius();
        if c2.distance(c) > tol || (r2 - r).abs() > tol || (s.bulge > 0.0) != ccw {
            return None;
        }
    }
    let total: f64 = segs.iter().map(Seg::sweep).sum();
    if (total.abs() - std::f64::consts::TAU).abs() < 1e-6 {
        Some((c, r, ccw))
    } else {
        None
    }
}
