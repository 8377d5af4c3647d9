//! An operation's cutting conditions edited by hand: spindle speed and the
//! feed of each kind of move (boundary, full cut, rest, link), checked
//! against the machine's limits from the knowledge, with the machining time
//! recomputed by `thinplan-feeds` as stage 7 does.
//!
//! Stepover and depth of cut are not edited here: they shape the tool path,
//! which stage 7 builds from the method in `knowledge/methods.ron` for a
//! whole machining feature and cannot rebuild for one operation from the
//! plan (the plan records the path, not the method's inputs).

use glam::DVec3;
use thinplan_feeds::MachineLimits;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{Operation, PathMove, Plan, ProvenanceSource, Region3};

/// The kinds of moves that carry a cutting feed, in the order shown.
pub const FEED_REGIONS: [Region3; 4] = [
    Region3::Boundary,
    Region3::FullCut,
    Region3::Rest,
    Region3::Link,
];

pub fn region_name(r: Region3) -> &'static str {
    match r {
        Region3::Boundary => "boundary",
        Region3::FullCut => "full cut",
        Region3::Rest => "rest",
        Region3::Rapid => "rapid",
        Region3::Link => "link",
    }
}

/// The machine's limits the conditions are checked against.
#[derive(Debug, Clone)]
pub struct Limits {
    pub machine: String,
    pub spindle_max_rpm: f64,
    /// The fastest any axis moves, mm/min: no feed can be faster.
    pub feed_max_mm_min: f64,
    /// The tool's flutes, for the feed per tooth (`None`: tool unknown).
    pub flutes: Option<u32>,
    /// The tool's diameter, mm, for the cutting speed.
    pub tool_diameter: Option<f64>,
    /// The material's recommended cutting data (shown beside the values,
    /// a recommendation rather than a limit).
    pub cutting: Option<thinplan_knowledge::CuttingData>,
    pub motion: MachineLimits,
}

/// The limits for `op` under the plan's set-up.
pub fn limits(plan: &Plan, k: &Knowledge, op: &Operation) -> Result<Limits, String> {
    let m = k.machine(&plan.setup.machine).ok_or_else(|| {
        format!(
            "the set-up's machine `{}` is not in knowledge {}",
            plan.setup.machine, k.origin
        )
    })?;
    let tool = k
        .tool_set(&plan.setup.tool_set)
        .and_then(|s| s.tools.iter().find(|t| t.id == op.tool));
    let v_max = [m.x.v_max, m.y.v_max, m.z.v_max];
    Ok(Limits {
        machine: m.id.clone(),
        spindle_max_rpm: m.spindle_max_rpm,
        feed_max_mm_min: v_max.iter().copied().fold(0.0, f64::max) * 60.0,
        flutes: tool.map(|t| t.flutes),
        tool_diameter: tool.map(|t| t.diameter),
        cutting: k.material(&plan.setup.material).map(|m| m.cutting.clone()),
        motion: MachineLimits {
            v_max,
            a_max: [m.x.a_max, m.y.a_max, m.z.a_max],
            a_centripetal: m.a_centripetal,
            corner_angle_deg: k.methods.corner_angle_deg,
        },
    })
}

/// The lowest and highest feed (mm/min) of each kind of move `op` has.
pub fn feeds(op: &Operation) -> Vec<(Region3, f64, f64)> {
    FEED_REGIONS
        .iter()
        .filter_map(|&r| {
            let mut it = op.moves.iter().filter(|m| m.region == r).map(|m| m.feed);
            let first = it.next()?;
            let (lo, hi) = it.fold((first, first), |(lo, hi), f| (lo.min(f), hi.max(f)));
            Some((r, lo, hi))
        })
        .collect()
}

/// Feed per tooth (mm) at `feed` mm/min.
pub fn feed_per_tooth(feed: f64, rpm: f64, flutes: u32) -> f64 {
    feed / (rpm * flutes.max(1) as f64)
}

/// Cutting speed (m/min) of a tool of `diameter` mm at `rpm`.
pub fn cutting_speed(diameter: f64, rpm: f64) -> f64 {
    std::f64::consts::PI * diameter * rpm / 1000.0
}

/// Sets the spindle speed; refused outside (0, the machine's maximum].
pub fn set_spindle(op: &mut Operation, rpm: f64, l: &Limits) -> Result<(), String> {
    if !(rpm.is_finite() && rpm > 0.0) {
        return Err(format!(
            "spindle speed must be a positive number, not {rpm}"
        ));
    }
    if rpm > l.spindle_max_rpm {
        return Err(format!(
            "spindle speed {rpm:.0} rpm is above machine `{}`'s {:.0} rpm",
            l.machine, l.spindle_max_rpm
        ));
    }
    if op.spindle_rpm == rpm {
        return Ok(());
    }
    let was = op.spindle_rpm;
    op.spindle_rpm = rpm;
    mark_edited(
        op,
        "gui.edit.spindle",
        &format!("spindle {was:.0} → {rpm:.0} rpm"),
    );
    op.provenance.values.insert("spindle_rpm".into(), rpm);
    Ok(())
}

/// Sets the feed of every `region` move of `op` and recomputes its time.
/// Refused: a feed that is not positive and finite, faster than any axis
/// of the machine, a kind of move the operation lacks, or one whose moves
/// carry different feeds (they cannot be told apart by hand).
pub fn set_feed(op: &mut Operation, region: Region3, feed: f64, l: &Limits) -> Result<(), String> {
    let name = region_name(region);
    if !(feed.is_finite() && feed > 0.0) {
        return Err(format!("{name} feed must be a positive number, not {feed}"));
    }
    if feed > l.feed_max_mm_min {
        return Err(format!(
            "{name} feed {feed:.0} mm/min is faster than any axis of machine `{}` moves ({:.0} mm/min)",
            l.machine, l.feed_max_mm_min
        ));
    }
    let Some(&(_, lo, hi)) = feeds(op).iter().find(|(r, _, _)| *r == region) else {
        return Err(format!("{} has no {name} moves", op.id));
    };
    if lo != hi {
        return Err(format!(
            "the {name} moves of {} have feeds from {lo:.0} to {hi:.0} mm/min: not one value to edit",
            op.id
        ));
    }
    if lo == feed {
        return Ok(());
    }
    for m in op.moves.iter_mut().filter(|m| m.region == region) {
        m.feed = feed;
    }
    mark_edited(
        op,
        "gui.edit.feed",
        &format!("{name} feed {lo:.0} → {feed:.0} mm/min"),
    );
    let key = match region {
        Region3::Boundary => Some("feed_boundary_mm_min"),
        Region3::FullCut | Region3::Rest => Some("feed_rough_mm_min"),
        _ => None,
    };
    if let Some(key) = key.filter(|k| op.provenance.values.contains_key(*k)) {
        op.provenance.values.insert(key.into(), feed);
    }
    let t = time_s(op, &l.motion);
    op.provenance.values.insert("time_s".into(), t);
    Ok(())
}

/// Marks the operation's conditions as edited by hand, keeping what stage
/// 7 recorded (pattern, stepovers, layers: reports read them) and saying
/// what changed.
fn mark_edited(op: &mut Operation, rule: &str, what: &str) {
    let p = &mut op.provenance;
    if p.source != ProvenanceSource::User {
        p.note = format!("{}; made by {}", p.note, p.rule);
    }
    p.source = ProvenanceSource::User;
    p.rule = rule.into();
    p.note = format!("{}; edited by hand: {what}", p.note);
}

/// The machining time of `op` (s) under `limits`, the moves sampled every
/// millimetre in a frame whose z is the tool axis, each cutting point
/// capped at its move's feed and rapids at the fastest axis.
pub fn time_s(op: &Operation, limits: &MachineLimits) -> f64 {
    let z = op.tool_axis.normalize_or(DVec3::Z);
    let (x, y) = z.any_orthonormal_pair();
    let local = |p: DVec3| DVec3::new(p.dot(x), p.dot(y), p.dot(z));
    let rapid = limits.v_max.iter().copied().fold(0.0, f64::max);
    let mut pts = vec![local(op.start)];
    let mut caps = Vec::new();
    let mut from = op.start;
    for m in &op.moves {
        let cap = if m.region == Region3::Rapid {
            rapid
        } else {
            m.feed / 60.0
        };
        for p in move_points(from, m, 1.0) {
            pts.push(local(p));
            caps.push(cap);
        }
        from = m.to;
    }
    if caps.is_empty() {
        return 0.0;
    }
    thinplan_feeds::schedule_polyline(&pts, &caps, limits).total_time
}

/// Points along a move (end included, start not): a straight move is its
/// end; an arc is sampled every `step` mm about its centre and axis, the
/// height along the axis interpolated (helices), a full turn when it ends
/// where it starts.
fn move_points(from: DVec3, m: &PathMove, step: f64) -> Vec<DVec3> {
    let Some(a) = &m.arc else {
        return vec![m.to];
    };
    let axis = a.axis.normalize_or(DVec3::Z);
    let u = from - a.centre;
    let v = m.to - a.centre;
    let (h0, h1) = (u.dot(axis), v.dot(axis));
    let (u, v) = (u - axis * h0, v - axis * h1);
    let r = u.length();
    if r < 1e-12 {
        return vec![m.to];
    }
    let mut sweep = axis.dot(u.cross(v)).atan2(u.dot(v));
    if a.clockwise {
        if sweep >= -1e-12 {
            sweep -= std::f64::consts::TAU;
        }
    } else if sweep <= 1e-12 {
        sweep += std::f64::consts::TAU;
    }
    let e1 = u / r;
    let e2 = axis.cross(e1);
    let n = (r * sweep.abs() / step).ceil().max(2.0) as usize;
    (1..=n)
        .map(|j| {
            let t = j as f64 / n as f64;
            let ang = sweep * t;
            a.centre + (e1 * ang.cos() + e2 * ang.sin()) * r + axis * (h0 + (h1 - h0) * t)
        })
        .chain(std::iter::once(m.to))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::ArcMove;

    #[test]
    fn a_quarter_arc_is_sampled_on_its_circle_and_the_right_way_round() {
        let m = PathMove {
            to: DVec3::new(0.0, 10.0, 2.0),
            arc: Some(ArcMove {
                centre: DVec3::ZERO,
                axis: DVec3::Z,
                clockwise: false,
            }),
            feed: 100.0,
            region: Region3::Rest,
        };
        let pts = move_points(DVec3::new(10.0, 0.0, 0.0), &m, 1.0);
        // A quarter of a 10 mm circle, 15.7 mm: 16 points and the end.
        assert_eq!(pts.len(), 17);
        for p in &pts {
            assert!((p.truncate().length() - 10.0).abs() < 1e-9, "{p}");
            assert!(
                p.x >= -1e-9 && p.y >= -1e-9,
                "counter-clockwise stays in the first quadrant"
            );
        }
        assert!((pts[pts.len() - 2].z - 2.0).abs() < 1e-9);
        let cw = PathMove {
            arc: Some(ArcMove {
                clockwise: true,
                ..m.arc.unwrap()
            }),
            ..m.clone()
        };
        let pts = move_points(DVec3::new(10.0, 0.0, 0.0), &cw, 1.0);
        // Three quarters the other way round.
        assert!(pts.len() > 45);
        assert!(pts.iter().any(|p| p.x < -9.0));
    }
}
