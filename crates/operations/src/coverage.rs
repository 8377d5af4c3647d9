//! Where operations have already cut: the test behind dropping wall rest
//! passes other operations made redundant, and behind finishing the product
//! wall stretches no operation came beside (orphan stretches).
//!
//! A smaller disc at a tool-centre position is covered when it lies, within
//! a slack, inside the disc of some cutting move whose tip ran at or below
//! its height. Arcs are split into chords whose sagitta is at most
//! [`SAGITTA`], each with its disc shrunk by that much, so coverage is never
//! claimed wrongly.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_knowledge::ToolSet;
use thinplan_plan::{Operation, Region3};

use crate::geom::dist_point_seg;
use crate::links::View;
use crate::path::{arc_sweep, Kind, LMove};

/// Largest sagitta of the chords an arc is split into (mm).
const SAGITTA: f64 = 2e-3;
/// Side of the plan-view buckets (mm).
const BUCKET: f64 = 5.0;

/// The cutting moves of a set of operations in plan view along the
/// set-up's spindle axis, bucketed.
pub(crate) struct Coverage {
    view: View,
    /// (from, to, highest tip, disc radius)
    /// (from, to, height, radius, flute length)
    segs: Vec<(DVec2, DVec2, f64, f64, f64)>,
    grid: BTreeMap<(i64, i64), Vec<usize>>,
}

fn key(p: DVec2) -> (i64, i64) {
    ((p.x / BUCKET).floor() as i64, (p.y / BUCKET).floor() as i64)
}

impl Coverage {
    /// Every non-rapid move of `ops`, with its tool's radius from `tools`
    /// (an unknown tool covers nothing).
    pub(crate) fn new<'a>(
        ops: impl IntoIterator<Item = &'a Operation>,
        up: DVec3,
        tools: &ToolSet,
    ) -> Self {
        let view = View::new(up);
        let mut cov = Coverage {
            view,
            segs: Vec::new(),
            grid: BTreeMap::new(),
        };
        for o in ops {
            let t = tools.tools.iter().find(|t| t.id == o.tool);
            let r = t.map_or(0.0, |t| 0.5 * t.diameter);
            let flute = t.map_or(0.0, |t| t.flute_length);
            let mut from = o.start;
            for m in &o.moves {
                if m.region != Region3::Rapid {
                    let z = view.z(from).max(view.z(m.to));
                    let arc = m.arc.map(|arc| {
                        let ccw = if arc.axis.dot(view.up()) >= 0.0 {
                            !arc.clockwise
                        } else {
                            arc.clockwise
                        };
                        (view.xy(arc.centre), ccw)
                    });
                    cov.push_move(view.xy(from), view.xy(m.to), arc, z, (r, flute));
                }
                from = m.to;
            }
        }
        cov
    }

    /// The cutting moves of operations in a feature's local frame (plan
    /// view along its z), each with its tool's radius.
    pub(crate) fn local<'a>(ops: impl IntoIterator<Item = (&'a [LMove], DVec3, f64, f64)>) -> Self {
        let mut cov = Coverage {
            view: View::new(DVec3::Z),
            segs: Vec::new(),
            grid: BTreeMap::new(),
        };
        for (moves, start, r, flute) in ops {
            let mut from = start;
            for m in moves {
                if m.kind != Kind::Rapid {
                    let z = from.z.max(m.to.z);
                    cov.push_move(from.truncate(), m.to.truncate(), m.arc, z, (r, flute));
                }
                from = m.to;
            }
        }
        cov
    }

    /// A line from `a` to `b`, or an arc about `arc.0` (counter-clockwise
    /// when `arc.1`), in plan view, its tip at most at `z`.
    fn push_move(
        &mut self,
        a: DVec2,
        b: DVec2,
        arc: Option<(DVec2, bool)>,
        z: f64,
        (r, flute): (f64, f64),
    ) {
        if r <= 0.0 {
            return;
        }
        match arc {
            None => self.push(a, b, z, (r, flute)),
            Some((c, ccw)) => {
                let ra = a.distance(c);
                let sweep = arc_sweep(a, b, c, ccw);
                // chord angle with sagitta SAGITTA: 2 acos(1 − s/r)
                let step = if ra > SAGITTA {
                    2.0 * (1.0 - SAGITTA / ra).acos()
                } else {
                    std::f64::consts::PI
                };
                let k = (sweep.abs() / step).ceil().max(1.0) as usize;
                let a0 = (a - c).to_angle();
                let mut p = a;
                for j in 1..=k {
                    let q = if j == k {
                        b
                    } else {
                        c + ra * DVec2::from_angle(a0 + sweep * j as f64 / k as f64)
                    };
                    self.push(p, q, z, (r - SAGITTA, flute));
                    p = q;
                }
            }
        }
    }

    fn push(&mut self, a: DVec2, b: DVec2, z: f64, (r, flute): (f64, f64)) {
        if r <= 0.0 {
            return;
        }
        let (lo, hi) = (
            key(a.min(b) - DVec2::splat(r)),
            key(a.max(b) + DVec2::splat(r)),
        );
        for i in lo.0..=hi.0 {
            for j in lo.1..=hi.1 {
                self.grid.entry((i, j)).or_default().push(self.segs.len());
            }
        }
        self.segs.push((a, b, z, r, flute));
    }

    /// Whether a disc of radius `r` about `p` (part coordinates, the tip at
    /// `p`'s height) lies within `slack` inside the disc of a move whose
    /// tip ran no higher and whose flutes reached that height (above them
    /// the shank would have met the material, not cut it).
    pub(crate) fn covers(&self, p: DVec3, r: f64, slack: f64) -> bool {
        let (c, z) = (self.view.xy(p), self.view.z(p));
        self.grid.get(&key(c)).is_some_and(|list| {
            list.iter().any(|&q| {
                let (p0, p1, zq, rq, flute) = self.segs[q];
                zq <= z + 1e-6
                    && z <= zq + flute + 1e-6
                    && dist_point_seg(c, p0, p1) <= rq - r + slack
            })
        })
    }

    /// The plan-view position and height of a part point.
    pub(crate) fn view(&self) -> &View {
        &self.view
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::{ArcMove, MachiningFeatureId, OperationId, PathMove, Provenance};

    fn op(tool: &str, start: DVec3, moves: Vec<PathMove>) -> Operation {
        Operation {
            id: OperationId(0),
            feature: MachiningFeatureId(0),
            method: "m".into(),
            tool: tool.into(),
            tool_axis: DVec3::Z,
            spindle_rpm: 1000.0,
            start,
            moves,
            link_z: None,
            schedule: Default::default(),
            provenance: Provenance::new(thinplan_plan::ProvenanceSource::Knowledge, "t"),
        }
    }

    fn tools() -> ToolSet {
        let k = thinplan_knowledge::Knowledge::builtin().unwrap();
        k.tool_sets.values().next().unwrap().clone()
    }

    #[test]
    fn a_straight_pass_covers_smaller_discs_inside_it_at_or_above_its_height() {
        let ts = tools();
        let big = ts
            .tools
            .iter()
            .max_by(|a, b| a.diameter.total_cmp(&b.diameter))
            .unwrap();
        let rq = big.diameter / 2.0;
        let mv = |to: DVec3| PathMove {
            to,
            arc: None,
            feed: 100.0,
            region: Region3::Boundary,
        };
        let o = op(
            &big.id,
            DVec3::new(0.0, 0.0, 5.0),
            vec![mv(DVec3::new(50.0, 0.0, 5.0))],
        );
        let cov = Coverage::new([&o], DVec3::Z, &ts);
        let r = 2.0;
        // inside, at the edge within the slack, outside, before the start
        assert!(cov.covers(DVec3::new(25.0, rq - r - 0.01, 5.0), r, 0.0));
        assert!(cov.covers(DVec3::new(25.0, rq - r + 0.05, 5.0), r, 0.1));
        assert!(!cov.covers(DVec3::new(25.0, rq - r + 0.2, 5.0), r, 0.1));
        assert!(!cov.covers(DVec3::new(-rq, 0.0, 5.0), r, 0.0));
        // a disc below the pass is not covered; above it is, as far as
        // the flutes reach, and no further: there the shank met it
        assert!(!cov.covers(DVec3::new(25.0, 0.0, 4.0), r, 0.0));
        assert!(cov.covers(DVec3::new(25.0, 0.0, 6.0), r, 0.0));
        let top = 5.0 + big.flute_length;
        assert!(cov.covers(DVec3::new(25.0, 0.0, top - 0.01), r, 0.0));
        assert!(!cov.covers(DVec3::new(25.0, 0.0, top + 0.01), r, 0.0));
    }

    #[test]
    fn an_arc_covers_what_its_true_circle_covers_and_not_its_chord() {
        let ts = tools();
        let t = &ts.tools[0];
        let rq = t.diameter / 2.0;
        // a half circle of radius 20 about the origin, counter-clockwise
        // seen from +z, from (20, 0) to (−20, 0)
        let o = op(
            &t.id,
            DVec3::new(20.0, 0.0, 0.0),
            vec![PathMove {
                to: DVec3::new(-20.0, 0.0, 0.0),
                arc: Some(ArcMove {
                    centre: DVec3::ZERO,
                    axis: DVec3::Z,
                    clockwise: false,
                }),
                feed: 100.0,
                region: Region3::Boundary,
            }],
        );
        let cov = Coverage::new([&o], DVec3::Z, &ts);
        let r = 0.5 * rq;
        for deg in [10.0f64, 45.0, 90.0, 135.0, 170.0] {
            let u = DVec2::from_angle(deg.to_radians());
            // on the circle, just inside the reach, and beyond it
            let on = 20.0 * u;
            assert!(cov.covers(on.extend(0.0), r, 0.0), "{deg}°");
            let near = (20.0 + rq - r - 0.01) * u;
            assert!(cov.covers(near.extend(0.0), r, 0.0), "{deg}°");
            let far = (20.0 + rq - r + 0.01) * u;
            assert!(!cov.covers(far.extend(0.0), r, 0.0), "{deg}°");
        }
        // the lower half was never cut
        assert!(!cov.covers(DVec3::new(0.0, -20.0, 0.0), r, 0.0));
    }
}
