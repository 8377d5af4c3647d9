//! Profiles: contours expanded into loops of lines and arcs, validated.

use cavalier_contours::polyline::{pline_seg_intr, PlineSegIntr, PlineSource};
use glam::DVec2;

use crate::geom2::{loop_area, loop_bounds, reverse_loop, to_pline, winding, Seg};
use crate::model::{Contour, Profile, Segment};

/// A closed loop with an optional name per segment.
#[derive(Debug, Clone)]
pub struct NamedLoop {
    pub segs: Vec<Seg>,
    pub names: Vec<Option<String>>,
    /// True when the loop is one full circle (made of arcs on one circle).
    pub circle: bool,
    /// `""` for the outer loop, `h{j}` for hole contour j (`h{j}.{k}` in a Repeat).
    pub label: String,
}

impl NamedLoop {
    fn reverse(&mut self) {
        self.segs = reverse_loop(&self.segs);
        self.names.reverse();
    }
}

/// A validated region: outer loop counter-clockwise, holes clockwise.
#[derive(Debug, Clone)]
pub struct Region2 {
    pub outer: NamedLoop,
    pub holes: Vec<NamedLoop>,
}

impl Region2 {
    pub fn area(&self) -> f64 {
        loop_area(&self.outer.segs) + self.holes.iter().map(|h| loop_area(&h.segs)).sum::<f64>()
    }

    pub fn loops(&self) -> impl Iterator<Item = &NamedLoop> {
        std::iter::once(&self.outer).chain(self.holes.iter())
    }

    pub fn bounds(&self) -> (DVec2, DVec2) {
        loop_bounds(&self.outer.segs)
    }
}

fn v(p: (f64, f64)) -> DVec2 {
    DVec2::new(p.0, p.1)
}

fn finite(p: DVec2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

/// Rounds the corners of a closed polygon with tangent arcs of radius `r`.
fn rounded_polygon(pts: &[DVec2], r: f64, tol: f64) -> Result<Vec<Seg>, String> {
    let n = pts.len();
    if n < 3 {
        return Err("a polygon needs at least 3 points".into());
    }
    if r == 0.0 {
        return Ok((0..n)
            .map(|i| Seg::line(pts[i], pts[(i + 1) % n]))
            .collect());
    }
    if !(r.is_finite() && r > 0.0) {
        return Err(format!("corner radius {r} must be ≥ 0"));
    }
    // Tangent points on each side: (after corner i, before corner i+1).
    let mut trims = vec![0.0; n];
    let mut corners = Vec::with_capacity(n);
    for i in 0..n {
        let p = pts[i];
        let prev = pts[(i + n - 1) % n];
        let next = pts[(i + 1) % n];
        let d1 = (p - prev).normalize_or_zero();
        let d2 = (next - p).normalize_or_zero();
        if d1 == DVec2::ZERO || d2 == DVec2::ZERO {
            return Err(format!("polygon point {i} repeats its neighbour"));
        }
        let turn = d1.perp_dot(d2).atan2(d1.dot(d2));
        if turn.abs() < 1e-12 {
            corners.push((p, p, 0.0));
            continue;
        }
        if (turn.abs() - std::f64::consts::PI).abs() < 1e-9 {
            return Err(format!("polygon turns back on itself at point {i}"));
        }
        let t = r * (turn.abs() * 0.5).tan();
        trims[i] = t;
        corners.push((p - d1 * t, p + d2 * t, (turn / 4.0).tan()));
    }
    let mut segs = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        let len = (pts[j] - pts[i]).length();
        if trims[i] + trims[j] > len + tol {
            return Err(format!(
                "corner radius {r} does not fit on polygon side {i} (length {len:.4})"
            ));
        }
        let (_, after_i, bulge_i) = corners[i];
        if bulge_i != 0.0 {
            segs.push(Seg {
                a: corners[i].0,
                b: after_i,
                bulge: bulge_i,
            });
        }
        let before_j = corners[j].0;
        if (before_j - after_i).length() > tol {
            segs.push(Seg::line(after_i, before_j));
        }
    }
    Ok(segs)
}

/// Expands one contour into loops (several for `Repeat`), not yet oriented.
fn expand(c: &Contour, tol: f64, out: &mut Vec<NamedLoop>) -> Result<(), String> {
    let plain = |segs: Vec<Seg>| NamedLoop {
        names: vec![None; segs.len()],
        segs,
        circle: false,
        label: String::new(),
    };
    match c {
        Contour::Rect { min, max } => {
            let (a, b) = (v(*min), v(*max));
            if !(finite(a) && finite(b)) || b.x - a.x <= tol || b.y - a.y <= tol {
                return Err("rectangle must have max > min in x and y".into());
            }
            let p = [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)];
            out.push(plain(rounded_polygon(&p, 0.0, tol)?));
        }
        Contour::RoundedRect { min, max, radius } => {
            let (a, b) = (v(*min), v(*max));
            if !(finite(a) && finite(b)) || b.x - a.x <= tol || b.y - a.y <= tol {
                return Err("rectangle must have max > min in x and y".into());
            }
            let p = [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)];
            out.push(plain(rounded_polygon(&p, *radius, tol)?));
        }
        Contour::Circle { centre, radius } => {
            let c = v(*centre);
            if !(finite(c) && radius.is_finite() && *radius > tol) {
                return Err(format!("circle radius {radius} must be > 0"));
            }
            let a = c + DVec2::X * *radius;
            let b = c - DVec2::X * *radius;
            let mut l = plain(vec![
                Seg { a, b, bulge: 1.0 },
                Seg {
                    a: b,
                    b: a,
                    bulge: 1.0,
                },
            ]);
            l.circle = true;
            out.push(l);
        }
        Contour::Slot { from, to, width } => {
            let (a, b) = (v(*from), v(*to));
            let d = (b - a).normalize_or_zero();
            if !(finite(a) && finite(b) && width.is_finite() && *width > tol) || d == DVec2::ZERO {
                return Err("slot needs two distinct centres and a width > 0".into());
            }
            let n = d.perp() * (*width * 0.5);
            out.push(plain(vec![
                Seg::line(a - n, b - n),
                Seg {
                    a: b - n,
                    b: b + n,
                    bulge: 1.0,
                },
                Seg::line(b + n, a + n),
                Seg {
                    a: a + n,
                    b: a - n,
                    bulge: 1.0,
                },
            ]));
        }
        Contour::Polygon { points, radius } => {
            let pts: Vec<DVec2> = points.iter().map(|p| v(*p)).collect();
            if !pts.iter().all(|p| finite(*p)) {
                return Err("polygon point is not finite".into());
            }
            out.push(plain(rounded_polygon(&pts, *radius, tol)?));
        }
        Contour::Path { start, segments } => {
            let mut cur = v(*start);
            let mut segs = Vec::new();
            let mut names = Vec::new();
            if segments.is_empty() {
                return Err("path has no segments".into());
            }
            for (i, s) in segments.iter().enumerate() {
                let (seg, name) = match s {
                    Segment::Line { to, name } => (Seg::line(cur, v(*to)), name),
                    Segment::Bulge { to, bulge, name } => {
                        if !bulge.is_finite() {
                            return Err(format!("path segment {i}: bulge is not finite"));
                        }
                        (
                            Seg {
                                a: cur,
                                b: v(*to),
                                bulge: *bulge,
                            },
                            name,
                        )
                    }
                    Segment::Arc {
                        to,
                        centre,
                        ccw,
                        name,
                    } => {
                        let (b, c) = (v(*to), v(*centre));
                        let (r0, r1) = ((cur - c).length(), (b - c).length());
                        if (r0 - r1).abs() > tol.max(1e-6 * r0) || r0 <= tol {
                            return Err(format!(
                                "path segment {i}: arc end is not on its circle \
                                 (radius {r0:.6} at the start, {r1:.6} at the end)"
                            ));
                        }
                        if (b - cur).length() <= tol {
                            return Err(format!(
                                "path segment {i}: an arc cannot be a full circle; use Circle"
                            ));
                        }
                        let ang = (cur - c).angle_to(b - c);
                        let sweep = if *ccw {
                            ang.rem_euclid(std::f64::consts::TAU)
                        } else {
                            -(-ang).rem_euclid(std::f64::consts::TAU)
                        };
                        (
                            Seg {
                                a: cur,
                                b,
                                bulge: (sweep / 4.0).tan(),
                            },
                            name,
                        )
                    }
                };
                if !finite(seg.b) {
                    return Err(format!("path segment {i}: point is not finite"));
                }
                if (seg.b - seg.a).length() <= tol {
                    return Err(format!("path segment {i} has zero length"));
                }
                cur = seg.b;
                segs.push(seg);
                names.push(name.clone());
            }
            let first = segs[0].a;
            if (cur - first).length() > tol {
                return Err(format!(
                    "path does not close: it ends at ({:.6}, {:.6}), not at its start",
                    cur.x, cur.y
                ));
            }
            let last = segs.len() - 1;
            segs[last].b = first;
            out.push(NamedLoop {
                segs,
                names,
                circle: false,
                label: String::new(),
            });
        }
        Contour::Repeat { count, step, of } => {
            if *count == 0 || *count > 10_000 {
                return Err("repeat count must be 1..=10000".into());
            }
            let mut one = Vec::new();
            expand(of, tol, &mut one)?;
            for k in 0..*count {
                let off = v(*step) * k as f64;
                for l in &one {
                    let mut l = l.clone();
                    for s in &mut l.segs {
                        s.a += off;
                        s.b += off;
                    }
                    out.push(l);
                }
            }
        }
    }
    Ok(())
}

/// Fills in side names in the order the user wrote the contour: `e{k}`
/// (outer) or `{label}.e{k}` (holes); a full circle is `side` or `{label}`.
fn name_sides(l: &mut NamedLoop) {
    let label = l.label.clone();
    for (k, n) in l.names.iter_mut().enumerate() {
        if n.is_none() {
            *n = Some(match (l.circle, label.is_empty()) {
                (true, true) => "side".to_string(),
                (true, false) => label.clone(),
                (false, true) => format!("e{k}"),
                (false, false) => format!("{label}.e{k}"),
            });
        }
    }
}

fn loops_touch(a: &[Seg], b: &[Seg], tol: f64) -> bool {
    for s in a {
        let (alo, ahi) = s.bounds();
        for t in b {
            let (blo, bhi) = t.bounds();
            if alo.x > bhi.x + tol
                || blo.x > ahi.x + tol
                || alo.y > bhi.y + tol
                || blo.y > ahi.y + tol
            {
                continue;
            }
            let r = pline_seg_intr(
                s.vertex_a(),
                cavalier_contours::polyline::PlineVertex::new(s.b.x, s.b.y, 0.0),
                t.vertex_a(),
                cavalier_contours::polyline::PlineVertex::new(t.b.x, t.b.y, 0.0),
                tol,
            );
            if !matches!(r, PlineSegIntr::NoIntersect) {
                return true;
            }
        }
    }
    false
}

fn check_loop(l: &NamedLoop, what: &str, tol: f64) -> Result<(), String> {
    if l.segs.len() < 2 {
        return Err(format!("{what} has fewer than two segments"));
    }
    let area = loop_area(&l.segs);
    let (lo, hi) = loop_bounds(&l.segs);
    let size = (hi - lo).length();
    if !area.is_finite() || area.abs() <= tol * size.max(tol) {
        return Err(format!("{what} has zero area"));
    }
    let pl = to_pline(&l.segs);
    if pl.scan_for_self_intersect() {
        return Err(format!("{what} intersects itself"));
    }
    Ok(())
}

/// Expands and validates a profile: loops closed and simple, non-zero
/// area, holes strictly inside the outer loop and apart from each other.
pub fn build_region(p: &Profile, tol: f64) -> Result<Region2, String> {
    let mut outer = Vec::new();
    expand(&p.outer, tol, &mut outer)?;
    if outer.len() != 1 {
        return Err("the outer contour must be a single loop (no Repeat)".into());
    }
    let mut outer = outer.pop().expect("one loop");
    name_sides(&mut outer);
    check_loop(&outer, "outer contour", tol)?;
    if loop_area(&outer.segs) < 0.0 {
        outer.reverse();
    }
    let mut holes = Vec::new();
    for (j, h) in p.holes.iter().enumerate() {
        let mut loops = Vec::new();
        expand(h, tol, &mut loops).map_err(|e| format!("hole {j}: {e}"))?;
        let n = loops.len();
        for (k, mut l) in loops.into_iter().enumerate() {
            l.label = if n == 1 {
                format!("h{j}")
            } else {
                format!("h{j}.{k}")
            };
            name_sides(&mut l);
            holes.push((j, l));
        }
    }
    let outer_pl = to_pline(&outer.segs);
    let mut out_holes: Vec<NamedLoop> = Vec::new();
    for (k, (j, mut h)) in holes.into_iter().enumerate() {
        check_loop(&h, &format!("hole {j}"), tol)?;
        if loop_area(&h.segs) > 0.0 {
            h.reverse();
        }
        if loops_touch(&h.segs, &outer.segs, tol) {
            return Err(format!(
                "hole {j} touches or crosses the outer contour (make it a notch in the outer contour)"
            ));
        }
        if winding(&outer_pl, h.segs[0].a) == 0 {
            return Err(format!("hole {j} lies outside the outer contour"));
        }
        for (i, other) in out_holes.iter().enumerate() {
            if loops_touch(&h.segs, &other.segs, tol)
                || winding(&to_pline(&other.segs), h.segs[0].a) != 0
                || winding(&to_pline(&h.segs), other.segs[0].a) != 0
            {
                return Err(format!("hole loops {i} and {k} overlap or touch"));
            }
        }
        out_holes.push(h);
    }
    Ok(Region2 {
        outer,
        holes: out_holes,
    })
}
