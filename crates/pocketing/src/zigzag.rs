//! Rectilinear (direction-parallel, zigzag) pocketing: the baseline of Bieterman's time-saving
//! chart ("Machining Time Savings of Curvilinear Vs. Rectilinear", `shared/seeds/000_…`).
//!
//! Straight passes across the roughing region, at most one stepover apart, joined by links that
//! follow the roughing boundary (so no scallop is left at the pass ends), then the finishing
//! pass on the tool-offset boundary ∂Ω, as every other path here ends. Every pass end turns by
//! about 90°, where the feed schedule stops the tool: the cost Bieterman's curvilinear path
//! avoids.

use glam::DVec2;

use crate::geom::sample_pline;
use crate::offset::{append_loop_from_nearest, offset_loops, sample_level};
use crate::{Method, Pocket, PocketError, PocketParams, PocketPath};

/// Where a scan line crosses a closed loop: segment index and the point.
#[derive(Debug, Clone, Copy)]
struct Crossing {
    seg: usize,
    point: DVec2,
}

/// The crossings of the horizontal line `y` with the closed loop `lp`, sorted by x.
fn crossings(lp: &[DVec2], y: f64) -> Vec<Crossing> {
    let n = lp.len();
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b) = (lp[i], lp[(i + 1) % n]);
        // half-open in y so that a vertex on the line counts once
        if (a.y > y) != (b.y > y) {
            let t = (y - a.y) / (b.y - a.y);
            out.push(Crossing {
                seg: i,
                point: a + (b - a) * t,
            });
        }
    }
    out.sort_by(|p, q| p.point.x.total_cmp(&q.point.x));
    out
}

/// The shorter way along the closed loop `lp` from crossing `a` to crossing `b`, endpoints
/// excluded (the vertices in between, in travel order).
fn boundary_link(lp: &[DVec2], a: Crossing, b: Crossing) -> Vec<DVec2> {
    let n = lp.len();
    // forward (loop order): vertices a.seg+1 ..= b.seg
    let fwd: Vec<DVec2> = {
        let mut v = Vec::new();
        let mut i = a.seg;
        while i != b.seg {
            i = (i + 1) % n;
            v.push(lp[i]);
        }
        v
    };
    // backward: vertices a.seg, a.seg-1, …, b.seg+1
    let bwd: Vec<DVec2> = {
        let mut v = Vec::new();
        let mut i = a.seg;
        while i != b.seg {
            v.push(lp[i]);
            i = (i + n - 1) % n;
        }
        v
    };
    let len = |v: &[DVec2]| {
        let mut p = a.point;
        let mut l = 0.0;
        for &q in v {
            l += p.distance(q);
            p = q;
        }
        l + p.distance(b.point)
    };
    if len(&fwd) <= len(&bwd) {
        fwd
    } else {
        bwd
    }
}

fn push(path: &mut Vec<DVec2>, p: DVec2) {
    if path.last().is_none_or(|q| q.distance_squared(p) > 1e-18) {
        path.push(p);
    }
}

/// Zigzag pocketing with passes at `angle` (radians from +x): passes evenly spaced at the
/// largest spacing ≤ the stepover between the roughing region's extremes, sampled at the
/// generators' sample step, alternating in direction and joined along the roughing boundary
/// (R + f in from the wall); then the finishing pass on ∂Ω (R in), counter-clockwise.
///
/// Needs one roughing loop that every pass crosses in one interval (a convex pocket, or one
/// convex across the pass direction); otherwise `BadProfile`. `max_gap` is the pass spacing.
pub fn zigzag_path(
    pocket: &Pocket,
    params: &PocketParams,
    angle: f64,
) -> Result<PocketPath, PocketError> {
    params.validate()?;
    pocket.validate()?;
    if !pocket.islands.is_empty() {
        return Err(PocketError::BadProfile(
            "the zigzag baseline takes pockets without islands".into(),
        ));
    }
    let r = params.tool_diameter / 2.0;
    let f = params.finish_stepover;
    let step = params.sample_step();
    let finish = offset_loops(pocket, r);
    if finish.is_empty() {
        return Err(PocketError::ToolDoesNotFit);
    }
    let finish = sample_level(&finish, step);
    let rough = offset_loops(pocket, r + f.max(0.0));
    let rough = if rough.is_empty() {
        finish.clone()
    } else {
        rough
            .iter()
            .map(|p| sample_pline(p, step, 3f64.to_radians()))
            .filter(|p| p.len() >= 3)
            .collect()
    };
    if rough.len() != 1 || finish.len() != 1 {
        return Err(PocketError::BadProfile(format!(
            "the zigzag baseline needs one roughing loop, found {}",
            rough.len()
        )));
    }
    // work in a frame whose x runs along the passes
    let (dir, back) = (DVec2::from_angle(-angle), DVec2::from_angle(angle));
    let lp: Vec<DVec2> = rough[0].iter().map(|&p| dir.rotate(p)).collect();
    let (ymin, ymax) = lp
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.y), b.max(p.y))
        });
    let height = ymax - ymin;
    let n = ((height / params.stepover).ceil() as usize).max(1);
    let h = height / n as f64;
    // the extreme passes a hair inside, so that each meets the loop in an interval
    let eps = 1e-9 * (height + pocket.size());
    let mut path: Vec<DVec2> = Vec::new();
    let mut prev_end: Option<Crossing> = None;
    for k in 0..=n {
        let y = (ymin + h * k as f64).clamp(ymin + eps, ymax - eps);
        let xs = crossings(&lp, y);
        if xs.len() != 2 {
            return Err(PocketError::BadProfile(format!(
                "a zigzag pass at {:.3} mm meets the roughing boundary {} times (needs 2)",
                y - ymin,
                xs.len()
            )));
        }
        let (start, end) = if k % 2 == 0 {
            (xs[0], xs[1])
        } else {
            (xs[1], xs[0])
        };
        if let Some(pe) = prev_end {
            for q in boundary_link(&lp, pe, start) {
                push(&mut path, q);
            }
        }
        let len = start.point.distance(end.point);
        let m = ((len / step).ceil() as usize).max(1);
        for j in 0..=m {
            push(&mut path, start.point.lerp(end.point, j as f64 / m as f64));
        }
        prev_end = Some(end);
    }
    let mut points: Vec<DVec2> = path.into_iter().map(|p| back.rotate(p)).collect();
    let finish_start = points.len();
    append_loop_from_nearest(&mut points, &finish[0]);
    Ok(PocketPath {
        method: Method::Zigzag,
        points,
        finish_start,
        max_gap: h.max(f),
        contours: vec![rough[0].clone()],
        center: None,
        fallback_reason: None,
        choice: Some(format!(
            "zigzag at {:.0}°, {} passes {:.3} mm apart",
            angle.to_degrees(),
            n + 1,
            h
        )),
        boundary: finish[0].clone(),
    })
}
