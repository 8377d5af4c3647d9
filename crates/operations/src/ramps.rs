//! Entries into stock (DESIGN.md "Entries and reach"; the thesis's HSM
//! demands): no feed move goes straight down into material. Stage 7 plans a
//! level's entry as a feed descent into space it takes to be cleared; where
//! the in-process stock (stage 8's height map, which errs towards material)
//! still stands under the tool there, the descent is split into a descent
//! in air to just above that stock and a zig-zag ramp along the move that
//! follows it, no steeper than the method's entry angle. The ramp stays in
//! the plan-view footprint of that following move, which the level cuts
//! anyway, so it reaches nothing the level would not.

use glam::DVec3;
use thinplan_plan::{ArcMove, PathMove, Region3};

use crate::links::View;

/// Most ramp passes one entry may take; beyond, the descent is left as it
/// is and the verification refuses it with its operation.
pub(crate) const MAX_PASSES: usize = 400;

/// Shortest stretch of the following move a ramp runs along, mm.
pub(crate) const MIN_RUN: f64 = 0.5;

/// Air above the stock where the ramp starts, mm.
pub(crate) const RAMP_START_CLEARANCE: f64 = 0.2;

/// One piece of the path a ramp runs along: a straight line or an arc
/// about an axis along up, from `from`, measured by its plan-view length.
enum Piece {
    Line {
        from: DVec3,
        dir: DVec3,
        len: f64,
    },
    Arc {
        from: DVec3,
        centre: DVec3,
        axis: DVec3,
        ccw: bool,
        u0: DVec3,
        r: f64,
        len: f64,
    },
}

impl Piece {
    fn of(from: DVec3, m: &PathMove, view: &View) -> Option<Piece> {
        let up = view.up();
        match &m.arc {
            None => {
                let flat = (m.to - from).reject_from(up);
                let len = flat.length();
                (len > 1e-9).then(|| Piece::Line {
                    from,
                    dir: flat / len,
                    len,
                })
            }
            Some(arc) => {
                let axis = arc.axis.normalize_or_zero();
                if axis.dot(up).abs() < 1.0 - 1e-9 {
                    return None;
                }
                let u0 = (from - arc.centre).reject_from(axis);
                let u1 = (m.to - arc.centre).reject_from(axis);
                let r = u0.length();
                if r < 1e-6 {
                    return None;
                }
                let theta = axis.dot(u0.cross(u1)).atan2(u0.dot(u1));
                let ccw = !arc.clockwise;
                let tau = std::f64::consts::TAU;
                let sweep = if ccw {
                    if theta > 1e-12 {
                        theta
                    } else {
                        theta + tau
                    }
                } else if theta < -1e-12 {
                    -theta
                } else {
                    tau - theta
                };
                Some(Piece::Arc {
                    from,
                    centre: arc.centre,
                    axis,
                    ccw,
                    u0,
                    r,
                    len: r * sweep,
                })
            }
        }
    }

    fn len(&self) -> f64 {
        match self {
            Piece::Line { len, .. } | Piece::Arc { len, .. } => *len,
        }
    }

    /// The plan position `s` along it (height as at its start).
    fn at(&self, s: f64) -> DVec3 {
        match self {
            Piece::Line { from, dir, .. } => *from + *dir * s,
            Piece::Arc {
                from,
                centre,
                axis,
                ccw,
                u0,
                r,
                ..
            } => {
                let phi = if *ccw { s / r } else { -s / r };
                let p = *centre + *u0 * phi.cos() + axis.cross(*u0) * phi.sin();
                p + *axis * (*from - p).dot(*axis)
            }
        }
    }

    /// The move to `s` along it at height `z`, travelling backwards or not.
    fn to(&self, s: f64, backwards: bool, z: f64, like: &PathMove, view: &View) -> PathMove {
        let p = self.at(s);
        let arc = match self {
            Piece::Line { .. } => None,
            Piece::Arc {
                centre, axis, ccw, ..
            } => Some(ArcMove {
                centre: *centre,
                axis: *axis,
                clockwise: *ccw == backwards,
            }),
        };
        PathMove {
            to: p + view.up() * (z - view.z(p)),
            arc,
            feed: like.feed,
            region: Region3::FullCut,
        }
    }
}

/// The level's own moves from the descent's end, as pieces, until `max`
/// of plan length (or the path rises or is left).
fn chain(to: DVec3, next: &[PathMove], max: f64, view: &View) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut at = to;
    let mut total = 0.0;
    for m in next {
        // The level's own path, its ramp down included; not a move that
        // climbs back above the descent's end (a link).
        if total >= max || m.region == Region3::Rapid || view.z(m.to) > view.z(to) + 1e-6 {
            break;
        }
        let Some(p) = Piece::of(at, m, view) else {
            break;
        };
        total += p.len();
        out.push(p);
        at = m.to;
    }
    out
}

/// The moves along `chain` from plan length `s0` to `s1` (either way), the
/// height going linearly from `z0` to `z1`.
fn travel(
    chain: &[Piece],
    s0: f64,
    s1: f64,
    z0: f64,
    z1: f64,
    like: &PathMove,
    view: &View,
) -> Vec<PathMove> {
    let mut out = Vec::new();
    let backwards = s1 < s0;
    let (lo, hi) = (s0.min(s1), s0.max(s1));
    let z_at = |s: f64| {
        if (s1 - s0).abs() < 1e-12 {
            z1
        } else {
            z0 + (z1 - z0) * (s - s0) / (s1 - s0)
        }
    };
    let mut start = 0.0;
    let mut parts: Vec<(usize, f64, f64)> = Vec::new();
    for (k, p) in chain.iter().enumerate() {
        let end = start + p.len();
        let a = lo.max(start);
        let b = hi.min(end);
        if b > a + 1e-12 {
            parts.push((k, a - start, b - start));
        }
        start = end;
    }
    if backwards {
        parts.reverse();
    }
    for (k, a, b) in parts {
        let piece_start = chain[..k].iter().map(Piece::len).sum::<f64>();
        let end = if backwards { a } else { b };
        out.push(chain[k].to(end, backwards, z_at(piece_start + end), like, view));
    }
    out
}

/// A straight feed descent to `to` at the plan point of `from`, into stock
/// standing up to `stock_top`, as moves from `from`: down in air to just
/// above the stock, then passes back and forth along the level's moves that
/// follow (`next`, at most `max_run` of them), each dropping at most
/// `tan(angle)` of its length, ending at `to`. `None` when the level gives
/// no room or the ramp would need more than [`MAX_PASSES`] passes.
pub(crate) fn ramp_entry(
    from: DVec3,
    to: DVec3,
    stock_top: f64,
    next: &[PathMove],
    angle_deg: f64,
    max_run: f64,
    view: &View,
) -> Option<Vec<PathMove>> {
    if !(angle_deg > 0.0 && angle_deg <= 89.0) {
        return None;
    }
    let like = next.first()?;
    let z_to = view.z(to);
    let top = (stock_top + RAMP_START_CLEARANCE).min(view.z(from));
    if top <= z_to + 1e-9 {
        return None;
    }
    let chain = chain(to, next, max_run, view);
    let run = chain.iter().map(Piece::len).sum::<f64>().min(max_run);
    if run < MIN_RUN {
        return None;
    }
    let drop_per_pass = run * angle_deg.to_radians().tan();
    let passes = ((top - z_to) / drop_per_pass).ceil().max(1.0);
    if passes > MAX_PASSES as f64 {
        return None;
    }
    let passes = passes as usize;
    let step = (top - z_to) / passes as f64;
    let mut out = Vec::with_capacity(passes + 2);
    if top < view.z(from) - 1e-9 {
        out.push(PathMove {
            to: to + view.up() * (top - z_to),
            arc: None,
            feed: like.feed,
            region: Region3::Rapid,
        });
    }
    for k in 1..=passes {
        let forward = k % 2 == 1;
        let (s0, s1) = if forward { (0.0, run) } else { (run, 0.0) };
        let z0 = top - step * (k - 1) as f64;
        out.extend(travel(&chain, s0, s1, z0, z0 - step, like, view));
    }
    if passes % 2 == 1 {
        // Back along the level to where the level's own moves begin.
        out.extend(travel(&chain, run, 0.0, z_to, z_to, like, view));
    }
    // The last move ends exactly where the level begins.
    if let Some(last) = out.last_mut() {
        last.to = to;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn next(to: DVec3) -> PathMove {
        PathMove {
            to,
            arc: None,
            feed: 1000.0,
            region: Region3::Rest,
        }
    }

    #[test]
    fn a_ramp_never_descends_steeper_than_its_angle_and_ends_at_the_level() {
        let view = View::new(DVec3::Z);
        let from = DVec3::new(0.0, 0.0, 25.0);
        let to = DVec3::new(0.0, 0.0, 3.0);
        for (top, angle, run) in [(13.0, 3.0, 40.0), (13.0, 10.0, 5.0), (3.2, 2.0, 100.0)] {
            let moves = ramp_entry(
                from,
                to,
                top,
                &[next(DVec3::new(run, 0.0, 3.0))],
                angle,
                50.0,
                &view,
            )
            .unwrap();
            assert_eq!(moves.last().unwrap().to, to);
            let mut p = from;
            for m in &moves {
                let d = m.to - p;
                let flat = d.truncate().length();
                if m.region != Region3::Rapid {
                    assert!(
                        d.z >= -flat * angle.to_radians().tan() - 1e-9,
                        "{d:?} steeper than {angle}°"
                    );
                    assert!(m.to.x >= -1e-9 && m.to.x <= run.min(50.0) + 1e-9);
                    assert!(m.to.y.abs() < 1e-9);
                } else {
                    // Only in air: above the stock.
                    assert!(m.to.z >= top - 1e-9);
                }
                p = m.to;
            }
        }
    }

    #[test]
    fn a_ramp_along_an_arc_stays_on_its_circle() {
        let view = View::new(DVec3::Z);
        let c = DVec3::new(10.0, 0.0, 0.0);
        let to = DVec3::new(0.0, 0.0, 3.0);
        for clockwise in [false, true] {
            let next = PathMove {
                to: DVec3::new(20.0, 0.0, 3.0),
                arc: Some(ArcMove {
                    centre: c,
                    axis: DVec3::Z,
                    clockwise,
                }),
                feed: 1000.0,
                region: Region3::Rest,
            };
            let moves = ramp_entry(
                to + DVec3::Z * 22.0,
                to,
                13.0,
                std::slice::from_ref(&next),
                3.0,
                48.0,
                &view,
            )
            .unwrap();
            assert_eq!(moves.last().unwrap().to, to);
            for m in moves.iter().filter(|m| m.region != Region3::Rapid) {
                let r = (m.to - c).truncate().length();
                assert!((r - 10.0).abs() < 1e-9, "{r}");
                // Forward passes turn the way the arc does (y < 0 when
                // clockwise seen from above, starting at the circle's left).
                if m.to.distance(to) > 1e-6 && m.arc.unwrap().clockwise == clockwise {
                    assert!(if clockwise {
                        m.to.y >= -1e-9
                    } else {
                        m.to.y <= 1e-9
                    });
                }
            }
        }
    }

    /// A level that begins with a short move: the ramp runs on along the
    /// moves after it, and stays on the level's path.
    #[test]
    fn a_ramp_runs_along_several_short_moves() {
        let view = View::new(DVec3::Z);
        let to = DVec3::new(0.0, 0.0, 3.0);
        let path = [
            next(DVec3::new(0.1, 0.0, 3.0)),
            next(DVec3::new(0.1, 10.0, 3.0)),
            next(DVec3::new(20.0, 10.0, 3.0)),
        ];
        let moves = ramp_entry(to + DVec3::Z * 20.0, to, 9.0, &path, 5.0, 24.0, &view).unwrap();
        assert_eq!(moves.last().unwrap().to, to);
        let on_path = |p: DVec3| {
            (p.y.abs() < 1e-9 && p.x <= 0.1 + 1e-9)
                || ((p.x - 0.1).abs() < 1e-9 && p.y <= 10.0 + 1e-9)
                || ((p.y - 10.0).abs() < 1e-9 && p.x <= 20.0 + 1e-9)
        };
        let mut p = to + DVec3::Z * 20.0;
        for m in &moves {
            if m.region != Region3::Rapid {
                assert!(on_path(m.to), "{:?} leaves the level's path", m.to);
                let d = m.to - p;
                assert!(d.z >= -d.truncate().length() * 5f64.to_radians().tan() - 1e-9);
            }
            p = m.to;
        }
    }

    #[test]
    fn no_room_or_no_stock_gives_no_ramp() {
        let view = View::new(DVec3::Z);
        let from = DVec3::new(0.0, 0.0, 25.0);
        let to = DVec3::new(0.0, 0.0, 3.0);
        let short = next(DVec3::new(0.1, 0.0, 3.0));
        assert!(ramp_entry(from, to, 13.0, &[short], 3.0, 50.0, &view).is_none());
        let long = next(DVec3::new(30.0, 0.0, 3.0));
        assert!(ramp_entry(from, to, 2.0, std::slice::from_ref(&long), 3.0, 50.0, &view).is_none());
        // 22 mm at 0.01° over 30 mm: more passes than allowed.
        assert!(ramp_entry(from, to, 25.0, &[long], 0.01, 50.0, &view).is_none());
    }
}
