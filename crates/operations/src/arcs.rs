//! Runs of straight moves whose points lie on one circle become one arc.
//!
//! A pass offset from a section that follows a round face through many
//! points on its circle keeps those points: hundreds of G1 moves a few
//! hundredths of a millimetre long round every fillet where one arc would
//! do. A run of such moves at one height, of one kind, whose
//! points all lie on a circle is written as that circle's arc (G2/G3): the
//! arc passes through every point of the run and leaves no chord by more
//! than [`MAX_BULGE`], so the tool's path moves by no more than that.

use glam::{DVec2, DVec3};

use crate::path::LMove;

/// How far (mm) a run's points may lie off the circle through its first,
/// middle and last points.
const ON_CIRCLE: f64 = 1e-7;
/// How far (mm) the arc may stand off any chord it replaces.
const MAX_BULGE: f64 = 1e-3;
/// Fewest straight moves worth one arc.
const MIN_RUN: usize = 3;
/// Radii (mm) beyond which a run is taken for a straight line.
const MAX_RADIUS: f64 = 1e4;

/// `moves` from `start` with every run of at least [`MIN_RUN`] straight
/// moves on one circle replaced by its arc.
pub(crate) fn fit(start: DVec3, moves: Vec<LMove>) -> Vec<LMove> {
    let mut out: Vec<LMove> = Vec::with_capacity(moves.len());
    let mut from = start;
    let mut i = 0;
    while i < moves.len() {
        let n = run_end(from, &moves[i..]);
        if n >= MIN_RUN {
            let pts: Vec<DVec2> = std::iter::once(from.truncate())
                .chain(moves[i..i + n].iter().map(|m| m.to.truncate()))
                .collect();
            if let Some((c, ccw)) = circle_of(&pts) {
                let last = moves[i + n - 1];
                out.push(LMove {
                    to: last.to,
                    arc: Some((c, ccw)),
                    kind: last.kind,
                });
                from = last.to;
                i += n;
                continue;
            }
        }
        from = moves[i].to;
        out.push(moves[i]);
        i += 1;
    }
    out
}

/// How many of `moves` from `from` are straight moves of one kind at
/// `from`'s height whose points stay on one circle turning one way.
fn run_end(from: DVec3, moves: &[LMove]) -> usize {
    let level = |m: &LMove| m.arc.is_none() && m.to.z == from.z;
    let Some(first) = moves.first().filter(|m| level(m)) else {
        return 0;
    };
    let mut pts = vec![from.truncate()];
    let mut best = 0;
    for (k, m) in moves.iter().enumerate() {
        if !level(m) || m.kind != first.kind {
            break;
        }
        pts.push(m.to.truncate());
        if k + 1 >= MIN_RUN {
            if circle_of(&pts).is_none() {
                break;
            }
            best = k + 1;
        }
    }
    best
}

/// The circle through `pts` (its centre and whether it turns
/// counter-clockwise) when every point lies on it, they turn one way round
/// it by less than a full turn, and no chord is farther than
/// [`MAX_BULGE`] from the arc.
fn circle_of(pts: &[DVec2]) -> Option<(DVec2, bool)> {
    let n = pts.len();
    let (a, b, c) = (pts[0], pts[n / 2], pts[n - 1]);
    let centre = circumcentre(a, b, c)?;
    let r = (a - centre).length();
    if !(r.is_finite() && r < MAX_RADIUS) {
        return None;
    }
    let mut turn = 0.0;
    let mut sign = 0.0;
    for w in pts.windows(2) {
        let (p, q) = (w[0] - centre, w[1] - centre);
        if (q.length() - r).abs() > ON_CIRCLE || (p.length() - r).abs() > ON_CIRCLE {
            return None;
        }
        let d = p.perp_dot(q).atan2(p.dot(q));
        if d == 0.0 || (sign != 0.0 && d.signum() != sign) {
            return None;
        }
        sign = d.signum();
        // Sagitta of the chord on the circle.
        if r * (1.0 - (0.5 * d).cos()) > MAX_BULGE {
            return None;
        }
        turn += d.abs();
    }
    (turn < std::f64::consts::TAU - 1e-9).then_some((centre, sign > 0.0))
}

fn circumcentre(a: DVec2, b: DVec2, c: DVec2) -> Option<DVec2> {
    let (ab, ac) = (b - a, c - a);
    let d = 2.0 * ab.perp_dot(ac);
    if d.abs() < 1e-12 {
        return None;
    }
    let (l1, l2) = (ab.length_squared(), ac.length_squared());
    let u = DVec2::new(ac.y * l1 - ab.y * l2, ab.x * l2 - ac.x * l1) / d;
    Some(a + u)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::{move_points, Kind};
    use proptest::prelude::*;

    fn line(to: DVec3) -> LMove {
        LMove {
            to,
            arc: None,
            kind: Kind::Boundary,
        }
    }

    /// The largest distance from any point of `b`'s path to `a`'s polyline.
    fn off(start: DVec3, a: &[LMove], b: &[LMove]) -> f64 {
        let poly: Vec<DVec2> = std::iter::once(start)
            .chain(a.iter().map(|m| m.to))
            .map(|p| p.truncate())
            .collect();
        let mut from = start;
        let mut worst: f64 = 0.0;
        for m in b {
            for p in move_points(from, m, 0.02) {
                let d = poly
                    .windows(2)
                    .map(|w| crate::geom::dist_point_seg(p.truncate(), w[0], w[1]))
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d);
            }
            from = m.to;
        }
        worst
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Points on a circle become one arc that ends where the run ends
        /// and stays within the bulge of the old path; a straight tail
        /// stays straight.
        #[test]
        fn points_on_a_circle_become_one_arc_near_the_old_path(
            r in 0.5f64..50.0,
            a0 in -3.0f64..3.0,
            sweep in 0.3f64..4.5,
            n in 4usize..200,
            ccw in any::<bool>(),
        ) {
            let c = DVec2::new(3.0, -2.0);
            let s = if ccw { 1.0 } else { -1.0 };
            let at = |k: usize| {
                let t = a0 + s * sweep * k as f64 / n as f64;
                (c + r * DVec2::from_angle(t)).extend(5.0)
            };
            // A chord no longer than the bulge allows.
            prop_assume!(r * (1.0 - (0.5 * sweep / n as f64).cos()) <= MAX_BULGE);
            let start = at(0);
            let mut moves: Vec<LMove> = (1..=n).map(|k| line(at(k))).collect();
            let tail = at(n) + DVec3::new(1.0, 1.0, 0.0);
            moves.push(line(tail));
            let fitted = fit(start, moves.clone());
            prop_assert_eq!(fitted.len(), 2);
            prop_assert_eq!(fitted[0].to, at(n));
            let (centre, turns_ccw) = fitted[0].arc.expect("an arc");
            prop_assert!((centre - c).length() < 1e-6);
            prop_assert_eq!(turns_ccw, ccw);
            prop_assert!(fitted[1].arc.is_none());
            prop_assert!(off(start, &moves, &fitted) <= MAX_BULGE + 1e-9);
        }

        /// Points off any one circle (a zig-zag, a polygon's corners) stay
        /// straight moves.
        #[test]
        fn a_polyline_off_every_circle_is_left_alone(
            pts in proptest::collection::vec((0.0f64..20.0, 0.0f64..20.0), 3..30),
        ) {
            let moves: Vec<LMove> = pts
                .iter()
                .map(|&(x, y)| line(DVec3::new(x, y, 1.0)))
                .collect();
            let start = DVec3::new(-1.0, -1.0, 1.0);
            let fitted = fit(start, moves.clone());
            prop_assert!(off(start, &moves, &fitted) <= MAX_BULGE + 1e-9);
            prop_assert_eq!(fitted.last().map(|m| m.to), moves.last().map(|m| m.to));
        }
    }

    /// Moves at other heights or of another kind end a run.
    #[test]
    fn a_change_of_height_or_kind_ends_the_run() {
        let c = DVec2::ZERO;
        let at = |k: usize, z: f64| (c + 5.0 * DVec2::from_angle(k as f64 * 0.01)).extend(z);
        let mut moves: Vec<LMove> = (1..=5).map(|k| line(at(k, 2.0))).collect();
        moves.push(line(at(6, 1.0)));
        let mut rest = line(at(7, 1.0));
        rest.kind = Kind::Rest;
        moves.push(rest);
        let fitted = fit(at(0, 2.0), moves);
        assert_eq!(fitted.len(), 3);
        assert!(fitted[0].arc.is_some() && fitted[1].arc.is_none() && fitted[2].arc.is_none());
    }
}
