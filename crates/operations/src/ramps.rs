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
pub(crate) const RAMP_START_CLEARANCE: f64 = 0.5;

/// The move a ramp runs along, from the descent's end: a straight line or
/// an arc about an axis along up, measured by its plan-view length.
enum Along {
    Line {
        dir: DVec3,
        len: f64,
    },
    Arc {
        centre: DVec3,
        axis: DVec3,
        ccw: bool,
        u0: DVec3,
        r: f64,
        len: f64,
    },
}

impl Along {
    fn of(to: DVec3, next: &PathMove, view: &View) -> Option<Along> {
        let up = view.up();
        match &next.arc {
            None => {
                let flat = (next.to - to).reject_from(up);
                let len = flat.length();
                (len > 1e-9).then(|| Along::Line {
                    dir: flat / len,
                    len,
                })
            }
            Some(arc) => {
                let axis = arc.axis.normalize_or_zero();
                if axis.dot(up).abs() < 1.0 - 1e-9 {
                    return None;
                }
                let u0 = (to - arc.centre).reject_from(axis);
                let u1 = (next.to - arc.centre).reject_from(axis);
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
                Some(Along::Arc {
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
            Along::Line { len, .. } | Along::Arc { len, .. } => *len,
        }
    }

    /// The plan position `s` along it (z as at `to`).
    fn at(&self, to: DVec3, s: f64) -> DVec3 {
        match self {
            Along::Line { dir, .. } => to + *dir * s,
            Along::Arc {
                centre,
                axis,
                ccw,
                u0,
                r,
                ..
            } => {
                let phi = if *ccw { s / r } else { -s / r };
                let p = *centre + *u0 * phi.cos() + axis.cross(*u0) * phi.sin();
                p + *axis * (to - p).dot(*axis)
            }
        }
    }

    /// The move from `s0` to `s1` along it, ending at height `z`.
    fn piece(
        &self,
        to: DVec3,
        s1: f64,
        backwards: bool,
        z: f64,
        next: &PathMove,
        view: &View,
    ) -> PathMove {
        let p = self.at(to, s1);
        let end = p + view.up() * (z - view.z(p));
        let arc = match self {
            Along::Line { .. } => None,
            Along::Arc {
                centre, axis, ccw, ..
            } => Some(ArcMove {
                centre: *centre,
                axis: *axis,
                clockwise: *ccw == backwards,
            }),
        };
        PathMove {
            to: end,
            arc,
            feed: next.feed,
            region: next.region,
        }
    }
}

/// A straight feed descent to `to` at the plan point of `from`, into stock
/// standing up to `stock_top`, as moves from `from`: down in air to just
/// above the stock, then passes back and forth along `next` (from `to`
/// towards its end, at most `max_run` of it), each dropping at most
/// `tan(angle)` of its length, ending at `to`. `None` when the following
/// move gives no room or the ramp would need more than [`MAX_PASSES`]
/// passes.
pub(crate) fn ramp_entry(
    from: DVec3,
    to: DVec3,
    stock_top: f64,
    next: &PathMove,
    angle_deg: f64,
    max_run: f64,
    view: &View,
) -> Option<Vec<PathMove>> {
    if !(angle_deg > 0.0 && angle_deg <= 89.0) {
        return None;
    }
    let z_to = view.z(to);
    let top = (stock_top + RAMP_START_CLEARANCE).min(view.z(from));
    if top <= z_to + 1e-9 {
        return None;
    }
    let along = Along::of(to, next, view)?;
    let run = along.len().min(max_run);
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
            feed: next.feed,
            region: Region3::Rapid,
        });
    }
    for k in 1..=passes {
        let forward = k % 2 == 1;
        let s1 = if forward { run } else { 0.0 };
        out.push(along.piece(to, s1, !forward, top - step * k as f64, next, view));
    }
    if passes % 2 == 1 {
        // Back along the level to where the level's own moves begin.
        out.push(along.piece(to, 0.0, true, z_to, next, view));
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
                &next(DVec3::new(run, 0.0, 3.0)),
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
            let moves =
                ramp_entry(to + DVec3::Z * 22.0, to, 13.0, &next, 3.0, 48.0, &view).unwrap();
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

    #[test]
    fn no_room_or_no_stock_gives_no_ramp() {
        let view = View::new(DVec3::Z);
        let from = DVec3::new(0.0, 0.0, 25.0);
        let to = DVec3::new(0.0, 0.0, 3.0);
        let short = next(DVec3::new(0.1, 0.0, 3.0));
        assert!(ramp_entry(from, to, 13.0, &short, 3.0, 50.0, &view).is_none());
        let long = next(DVec3::new(30.0, 0.0, 3.0));
        assert!(ramp_entry(from, to, 2.0, &long, 3.0, 50.0, &view).is_none());
        // 22 mm at 0.01° over 30 mm: more passes than allowed.
        assert!(ramp_entry(from, to, 25.0, &long, 0.01, 50.0, &view).is_none());
    }
}
