//! Tool-path building blocks in a feature's local frame (x, y in the
//! profile plane, z along the tool axis): moves, rounded corners, ramp and
//! helix entries, transits.

use glam::{DVec2, DVec3};

use crate::geom::{inside, segment_inside};

/// What a move does; decides its region tag and its cutting conditions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Rest region, roughing conditions.
    Rest,
    /// Full-cut region (slot), roughing feed per tooth, reduced depth.
    FullCut,
    /// Boundary region along product edges.
    Boundary,
    /// A pass of the product-adjacent bottom layer: finishing conditions.
    BottomFinish,
    /// A feed move through cleared space (descending into a cleared level).
    Link,
    /// A rapid move above the feature.
    Rapid,
}

impl Kind {
    pub fn cuts(self) -> bool {
        matches!(
            self,
            Kind::Rest | Kind::FullCut | Kind::Boundary | Kind::BottomFinish
        )
    }
}

/// One move in local coordinates; an arc turns about `centre` (local xy).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LMove {
    pub to: DVec3,
    /// Centre and counter-clockwise (seen from +z).
    pub arc: Option<(DVec2, bool)>,
    pub kind: Kind,
}

/// A 2D path element: a straight line or an arc to `to`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seg2 {
    pub to: DVec2,
    pub arc: Option<(DVec2, bool)>,
}

/// Points along a 2D segment starting at `from` (end included, start not).
pub fn seg_points(from: DVec2, s: &Seg2, step: f64) -> Vec<DVec2> {
    match s.arc {
        None => {
            let k = (from.distance(s.to) / step).ceil().max(1.0) as usize;
            (1..=k)
                .map(|j| from.lerp(s.to, j as f64 / k as f64))
                .collect()
        }
        Some((c, ccw)) => {
            let r = (from - c).length();
            let sweep = arc_sweep(from, s.to, c, ccw);
            let a0 = (from - c).to_angle();
            let k = (r * sweep.abs() / step).ceil().max(2.0) as usize;
            (1..=k)
                .map(|j| c + r * DVec2::from_angle(a0 + sweep * j as f64 / k as f64))
                .collect()
        }
    }
}

/// Signed sweep (radians) from `a` to `b` about `c`, positive counter-clockwise;
/// a full circle when `a == b`.
pub fn arc_sweep(a: DVec2, b: DVec2, c: DVec2, ccw: bool) -> f64 {
    let mut d = (b - c).to_angle() - (a - c).to_angle();
    if ccw {
        while d <= 1e-12 {
            d += std::f64::consts::TAU;
        }
    } else {
        while d >= -1e-12 {
            d -= std::f64::consts::TAU;
        }
    }
    d
}

/// Length of a 3D move from `from`.
pub fn move_length(from: DVec3, m: &LMove) -> f64 {
    match m.arc {
        None => from.distance(m.to),
        Some((c, ccw)) => {
            let r = (from.truncate() - c).length();
            let sweep = arc_sweep(from.truncate(), m.to.truncate(), c, ccw);
            let h = r * sweep.abs();
            (h * h + (m.to.z - from.z).powi(2)).sqrt()
        }
    }
}

/// Points along a move (end included, start not), z interpolated.
pub fn move_points(from: DVec3, m: &LMove, step: f64) -> Vec<DVec3> {
    let s = Seg2 {
        to: m.to.truncate(),
        arc: m.arc,
    };
    let pts = seg_points(from.truncate(), &s, step);
    let n = pts.len() as f64;
    pts.into_iter()
        .enumerate()
        .map(|(j, p)| p.extend(from.z + (m.to.z - from.z) * (j as f64 + 1.0) / n))
        .collect()
}

/// A polyline with its sharp turns rounded by arcs of radius up to `rho`
/// (smaller where the neighbouring segments are short).
pub fn rounded(points: &[DVec2], rho: f64) -> Vec<Seg2> {
    let mut out = Vec::new();
    let n = points.len();
    if n < 2 {
        return out;
    }
    let mut cur = points[0];
    for i in 1..n {
        let b = points[i];
        if i + 1 == n || rho <= 0.0 {
            out.push(Seg2 { to: b, arc: None });
            cur = b;
            continue;
        }
        let a = cur;
        let c = points[i + 1];
        let (l1, l2) = (a.distance(b), b.distance(c));
        if l1 < 1e-9 || l2 < 1e-9 {
            out.push(Seg2 { to: b, arc: None });
            cur = b;
            continue;
        }
        let u1 = (b - a) / l1;
        let u2 = (c - b) / l2;
        let turn = u1.perp_dot(u2).atan2(u1.dot(u2));
        if turn.abs() < 1e-3 || turn.abs() > std::f64::consts::PI - 1e-6 {
            out.push(Seg2 { to: b, arc: None });
            cur = b;
            continue;
        }
        let half = (turn.abs() / 2.0).tan();
        let t = (rho * half).min(0.5 * l1).min(0.5 * l2);
        let rr = t / half;
        let p1 = b - u1 * t;
        let p2 = b + u2 * t;
        let ccw = turn > 0.0;
        let centre = p1 + if ccw { u1.perp() } else { -u1.perp() } * rr;
        out.push(Seg2 { to: p1, arc: None });
        out.push(Seg2 {
            to: p2,
            arc: Some((centre, ccw)),
        });
        cur = p2;
    }
    out
}

/// Builds a path move by move, remembering where the tool is.
pub struct Builder {
    pub moves: Vec<LMove>,
    pub pos: DVec3,
    pub start: DVec3,
}

impl Builder {
    pub fn new(start: DVec3) -> Self {
        Builder {
            moves: Vec::new(),
            pos: start,
            start,
        }
    }

    pub fn line(&mut self, to: DVec3, kind: Kind) {
        if to.distance_squared(self.pos) < 1e-18 {
            return;
        }
        self.moves.push(LMove {
            to,
            arc: None,
            kind,
        });
        self.pos = to;
    }

    pub fn arc(&mut self, to: DVec3, centre: DVec2, ccw: bool, kind: Kind) {
        self.moves.push(LMove {
            to,
            arc: Some((centre, ccw)),
            kind,
        });
        self.pos = to;
    }

    /// Follows 2D segments at height `z`.
    pub fn follow(&mut self, segs: &[Seg2], z: f64, kind: Kind) {
        for s in segs {
            match s.arc {
                None => self.line(s.to.extend(z), kind),
                Some((c, ccw)) => {
                    if s.to.distance_squared(self.pos.truncate()) < 1e-18 && self.pos.z == z {
                        continue;
                    }
                    self.arc(s.to.extend(z), c, ccw, kind)
                }
            }
        }
    }
}

/// The geometry a transit needs: where the tool centre may go, and heights.
pub struct Space<'a> {
    /// The tool-centre region, sampled.
    pub centre_region: &'a [Vec<DVec2>],
    /// Where rapids down end (local z): the top of the stock, air above.
    pub z_top: f64,
    /// Height of links that leave the tool-centre region.
    pub safe_z: f64,
    pub step: f64,
    /// Whether a tool centre at a point keeps clear of the product (the
    /// safety net's own test): the sampled region's chords cut into the
    /// arcs round product corners by their sagitta, so a link inside the
    /// samples is also held to it. `None`: the samples alone.
    pub clear: Option<&'a dyn Fn(DVec3) -> bool>,
}

impl Space<'_> {
    /// Whether a straight link from `a` to `b` at height `z` keeps clear
    /// of the product at the points the safety net samples it.
    pub fn line_clear(&self, a: DVec2, b: DVec2, z: f64) -> bool {
        let Some(clear) = self.clear else {
            return true;
        };
        let s = Seg2 { to: b, arc: None };
        seg_points(a, &s, self.step)
            .into_iter()
            .chain([a])
            .all(|p| clear(p.extend(z)))
    }

    /// Moves the tool to `to` at the cleared height `z_clear` (the top of the
    /// z-level about to be cut): through cleared space inside the
    /// tool-centre region when it can, else over the safe height.
    pub fn transit(&self, b: &mut Builder, to: DVec2, z_clear: f64) {
        let here = b.pos.truncate();
        let inside_here = inside(here, self.centre_region);
        if here.distance(to) < 1e-9 {
            b.line(to.extend(z_clear), Kind::Link);
            return;
        }
        if inside_here
            && b.pos.z <= z_clear + 1e-9
            && segment_inside(here, to, self.centre_region, self.step)
            && self.line_clear(here, to, z_clear)
        {
            b.line(here.extend(z_clear), Kind::Link);
            b.line(to.extend(z_clear), Kind::Link);
            return;
        }
        b.line(here.extend(self.safe_z), Kind::Rapid);
        b.line(to.extend(self.safe_z), Kind::Rapid);
        b.line(to.extend(self.z_top), Kind::Rapid);
        b.line(to.extend(z_clear), Kind::Link);
    }
}

/// Ramps from `z_from` down to `z_to` back and forth along the polyline
/// `prefix` (starting at the tool's position), never steeper than `angle`;
/// ends at the prefix start at `z_to`. `None` when the prefix is too short.
pub fn ramp(
    b: &mut Builder,
    prefix: &[DVec2],
    z_from: f64,
    z_to: f64,
    angle_rad: f64,
    min_len: f64,
    kind: Kind,
) -> Option<()> {
    let dz = z_from - z_to;
    if dz <= 1e-12 {
        return Some(());
    }
    let len: f64 = prefix.windows(2).map(|w| w[0].distance(w[1])).sum();
    if len < min_len {
        return None;
    }
    let need = dz / angle_rad.tan();
    // Legs of the full prefix (or the part needed), alternating direction;
    // the slope is spread evenly so no leg is steeper than the angle.
    let leg = len.min(need);
    let legs = (need / leg).ceil().max(1.0) as usize;
    // A ramp of hundreds of legs is no entry: refuse rather than drill.
    if legs > 400 {
        return None;
    }
    let pts = cut_prefix(prefix, leg);
    let per_leg = dz / legs as f64;
    let mut z = z_from;
    for l in 0..legs {
        let seq: Vec<DVec2> = if l % 2 == 0 {
            pts[1..].to_vec()
        } else {
            pts.iter().rev().skip(1).copied().collect()
        };
        let total: f64 = leg;
        let mut acc = 0.0;
        let mut prev = b.pos.truncate();
        for p in seq {
            acc += prev.distance(p);
            prev = p;
            b.line(p.extend(z - per_leg * (acc / total).min(1.0)), kind);
        }
        z -= per_leg;
    }
    // Back to the start at full depth (flat) when the last leg ended away.
    if legs % 2 == 1 {
        for p in pts.iter().rev().skip(1) {
            b.line(p.extend(z_to), kind);
        }
    }
    Some(())
}

/// The first `len` of a polyline.
fn cut_prefix(p: &[DVec2], len: f64) -> Vec<DVec2> {
    let mut out = vec![p[0]];
    let mut acc = 0.0;
    for w in p.windows(2) {
        let d = w[0].distance(w[1]);
        if acc + d >= len - 1e-12 {
            let t = ((len - acc) / d).clamp(0.0, 1.0);
            out.push(w[0].lerp(w[1], t));
            return out;
        }
        acc += d;
        out.push(w[1]);
    }
    out
}

/// A helix of radius `rho` about `centre` from `z_from` to `z_to`, starting
/// and ending at `centre + (rho, 0)`, then a flat circle at `z_to`; slope
/// never steeper than `angle`. Counter-clockwise when `ccw`.
#[allow(clippy::too_many_arguments)]
pub fn helix(
    b: &mut Builder,
    centre: DVec2,
    rho: f64,
    start_angle: f64,
    z_from: f64,
    z_to: f64,
    angle_rad: f64,
    ccw: bool,
    kind: Kind,
) {
    let start = centre + DVec2::from_angle(start_angle) * rho;
    let opposite = centre - DVec2::from_angle(start_angle) * rho;
    let dz = z_from - z_to;
    let per_turn = std::f64::consts::TAU * rho * angle_rad.tan();
    let turns = (dz / per_turn).ceil().max(1.0) as usize;
    let half = dz / (2 * turns) as f64;
    let mut z = z_from;
    for _ in 0..turns {
        z -= half;
        b.arc(opposite.extend(z), centre, ccw, kind);
        z -= half;
        b.arc(start.extend(z), centre, ccw, kind);
    }
    b.arc(opposite.extend(z_to), centre, ccw, kind);
    b.arc(start.extend(z_to), centre, ccw, kind);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A centre region whose samples round a product corner at (0, 0) by a
    /// 1 mm chord: a link along the chord is inside the samples but 42 µm
    /// closer to the corner than the tool's 3 mm radius at its middle. A link along it goes over the top where
    /// the safety net's test says so, and stays a link where it does not.
    #[test]
    fn a_link_inside_the_samples_but_into_a_corner_goes_over_the_top() {
        let r: f64 = 3.0;
        let a: f64 = 1.0 / r; // a 1 mm chord on the radius
        let (p, q) = (
            DVec2::new(r * (a / 2.0).cos(), -r * (a / 2.0).sin()),
            DVec2::new(r * (a / 2.0).cos(), r * (a / 2.0).sin()),
        );
        let region = vec![vec![
            DVec2::new(p.x - 0.01, -20.0),
            DVec2::new(20.0, -20.0),
            DVec2::new(20.0, 20.0),
            DVec2::new(q.x - 0.01, 20.0),
        ]];
        let corner = DVec2::ZERO;
        let net = |x: DVec3| x.truncate().distance(corner) >= r - 1e-6;
        let lenient = |_: DVec3| true;
        let run = |clear: &dyn Fn(DVec3) -> bool| {
            let space = Space {
                centre_region: &region,
                z_top: 10.0,
                safe_z: 20.0,
                step: 0.25,
                clear: Some(clear),
            };
            let mut b = Builder::new(p.extend(0.0));
            space.transit(&mut b, q, 0.0);
            b.moves.iter().any(|m| m.kind == Kind::Rapid)
        };
        assert!(run(&net), "the link cut the corner");
        assert!(!run(&lenient), "a clear link went over the top");
    }
}
