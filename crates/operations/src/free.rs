//! Where a tool may be around a feature: the space that is not product at
//! any height of the feature, reconstructed from the resolved plan itself.
//!
//! After stage 6 the machining features and the part fill the blank
//! exactly, so at a height z the product in plan view is the blank minus
//! every feature spanning z. A feature's own adjacency only tells about its
//! edges; an `open` edge may face a narrow strip already cut beside a wall,
//! and a tool overhanging it would reach the wall. The tool-centre region is
//! therefore also kept inside this free space eroded by the tool radius.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use thinplan_plan::{MachiningFeature, Plan, ProfileLoop};

/// Shapes: each an outer contour then holes.
pub(crate) type Shapes = Vec<Vec<Vec<[f64; 2]>>>;

/// The blank's plan-view box in the set-up frame, as stage 6 recorded it.
pub(crate) fn blank_rect(plan: &Plan) -> Option<[f64; 4]> {
    let get = |k: &str| plan.notes.get(k).and_then(|v| v.parse::<f64>().ok());
    Some([
        get("resolve.blank_min_x")?,
        get("resolve.blank_min_y")?,
        get("resolve.blank_max_x")?,
        get("resolve.blank_max_y")?,
    ])
}

fn contour(l: &ProfileLoop) -> Vec<[f64; 2]> {
    // Resolved features have straight edges; arcs (bulges) are taken as
    // chords here, which only matters for synthetic plans.
    l.vertices.iter().map(|v| [v.x, v.y]).collect()
}

pub(crate) fn region(f: &MachiningFeature) -> Vec<Vec<[f64; 2]>> {
    let mut c = vec![contour(&f.shape.region.outer)];
    c.extend(f.shape.region.holes.iter().map(contour));
    c
}

/// Contours (outer loops and holes, any orientation) as shapes, holes
/// where loops nest (even-odd).
pub(crate) fn filled(contours: &[Vec<[f64; 2]>]) -> Shapes {
    contours.overlay_as::<i64>(
        &Vec::<Vec<[f64; 2]>>::new(),
        OverlayRule::Subject,
        FillRule::EvenOdd,
    )
}

/// The area of one shape (an outer contour then holes), mm².
pub(crate) fn shape_area(shape: &[Vec<[f64; 2]>]) -> f64 {
    let ring = |c: &Vec<[f64; 2]>| {
        let n = c.len();
        ((0..n)
            .map(|i| c[i][0] * c[(i + 1) % n][1] - c[(i + 1) % n][0] * c[i][1])
            .sum::<f64>()
            / 2.0)
            .abs()
    };
    shape
        .iter()
        .enumerate()
        .map(|(k, c)| if k == 0 { ring(c) } else { -ring(c) })
        .sum()
}

/// The free space around `plan.machining_features[i]` within `margin` of it:
/// points that are no product at any height of the feature (inside another
/// feature or the feature itself at every height, or outside the blank).
/// `None` when the plan is not resolved (no blank recorded) or the features
/// do not share one frame.
pub(crate) fn free_space(plan: &Plan, i: usize, margin: f64) -> Option<Shapes> {
    space(plan, i, margin, |_| true)
}

/// The space already cut around `plan.machining_features[i]` within `margin`
/// of it when it is cut: outside the blank, the feature itself, and every
/// feature before it in the machining order (the features stage 6 calls
/// open across an edge), at every height of the feature.
/// `pos`: each feature's place in the machining order
/// (`precedence::machining_positions`).
pub(crate) fn removed_space(plan: &Plan, i: usize, margin: f64, pos: &[usize]) -> Option<Shapes> {
    space(plan, i, margin, |j| pos[j] < pos[i])
}

/// The union of the feature, the features `include` admits and the air
/// outside the blank, at every height of the feature.
fn space(plan: &Plan, i: usize, margin: f64, include: impl Fn(usize) -> bool) -> Option<Shapes> {
    let blank = blank_rect(plan)?;
    let f = &plan.machining_features[i];
    let fb = f.plan_box();
    let near = |g: &MachiningFeature| {
        let b = g.plan_box();
        b[0] <= fb[2] + margin
            && fb[0] <= b[2] + margin
            && b[1] <= fb[3] + margin
            && fb[1] <= b[3] + margin
    };
    let eps = 1e-9;
    let (lo, hi) = (f.shape.z_min, f.shape.z_max);
    let mut others = Vec::new();
    for (j, g) in plan.machining_features.iter().enumerate() {
        if j == i || !near(g) {
            continue;
        }
        if !f.same_frame(g) {
            return None;
        }
        if g.shape.z_max > lo + eps && g.shape.z_min < hi - eps && include(j) {
            others.push(g);
        }
    }
    let mut breaks = vec![lo, hi];
    for g in &others {
        for z in [g.shape.z_min, g.shape.z_max] {
            if z > lo + eps && z < hi - eps {
                breaks.push(z);
            }
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup_by(|a, b| (*a - *b).abs() < eps);
    let window = [
        fb[0] - margin,
        fb[1] - margin,
        fb[2] + margin,
        fb[3] + margin,
    ];
    let rect = |b: [f64; 4]| vec![vec![[b[0], b[1]], [b[2], b[1]], [b[2], b[3]], [b[0], b[3]]]];
    // Outside the blank is air.
    let outside: Shapes =
        rect(window).overlay_as::<i64>(&rect(blank), OverlayRule::Difference, FillRule::NonZero);
    let mut free: Option<Shapes> = None;
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        let mut cover: Vec<Vec<[f64; 2]>> = region(f);
        for g in &others {
            if g.shape.z_min <= a + eps && g.shape.z_max >= b - eps {
                cover.extend(region(g));
            }
        }
        let cover: Shapes = cover.overlay_as::<i64>(
            &Vec::<Vec<[f64; 2]>>::new(),
            OverlayRule::Subject,
            FillRule::NonZero,
        );
        free = Some(match free {
            None => cover,
            Some(prev) => prev.overlay_as::<i64>(&cover, OverlayRule::Intersect, FillRule::NonZero),
        });
    }
    let free = free.unwrap_or_default();
    let free: Shapes = free.overlay_as::<i64>(&outside, OverlayRule::Union, FillRule::NonZero);
    Some(without_slits(free))
}

/// The shapes without zero-width slits and spikes: where two features'
/// shared edges differ in the last bits the union keeps a crack that is no
/// product, yet the safety net would keep the tool r from it.
pub(crate) fn without_slits(shapes: Shapes) -> Shapes {
    let tiny = 1e-6;
    let clean = |c: &Vec<[f64; 2]>| -> Vec<[f64; 2]> {
        let mut pts = c.clone();
        loop {
            let n = pts.len();
            if n < 3 {
                return pts;
            }
            let drop = (0..n).find(|&i| {
                let (a, b, q) = (pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
                let (u, v) = ([b[0] - a[0], b[1] - a[1]], [q[0] - b[0], q[1] - b[1]]);
                let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
                if lu < tiny || lv < tiny {
                    return true;
                }
                // A spike: out and straight back.
                let cross = (u[0] * v[1] - u[1] * v[0]) / (lu * lv);
                let dot = (u[0] * v[0] + u[1] * v[1]) / (lu * lv);
                cross.abs() < 1e-9 && dot < 0.0
            });
            match drop {
                Some(i) => {
                    pts.remove(i);
                }
                None => return pts,
            }
        }
    };
    let area = |c: &Vec<[f64; 2]>| {
        let n = c.len();
        (0..n)
            .map(|i| c[i][0] * c[(i + 1) % n][1] - c[(i + 1) % n][0] * c[i][1])
            .sum::<f64>()
            / 2.0
    };
    shapes
        .into_iter()
        .filter_map(|shape| {
            let mut out: Vec<Vec<[f64; 2]>> = Vec::new();
            for (k, c) in shape.iter().enumerate() {
                let c = clean(c);
                if c.len() >= 3 && area(&c).abs() > tiny {
                    out.push(c);
                } else if k == 0 {
                    return None;
                }
            }
            Some(out)
        })
        .collect()
}

/// A machining feature that may still stand beside a feature when that
/// feature is cut: its plan-view region (feature frame) and its top.
#[derive(Debug, Clone)]
pub(crate) struct Obstacle {
    pub id: thinplan_plan::MachiningFeatureId,
    pub region: Vec<Vec<[f64; 2]>>,
    pub top: f64,
}

/// Features whose material may still stand when `plan.machining_features[i]`
/// is cut (no chain of `Before` constraints or shank edges puts them
/// first), within `margin` of it in plan view, in its frame, and reaching
/// higher than `rise` above its bottom: where the tool cuts lower than a
/// flute length below such a feature's top, its shank must keep out of it.
pub(crate) fn shank_obstacles(
    plan: &Plan,
    i: usize,
    margin: f64,
    rise: f64,
    edges: &[(
        thinplan_plan::MachiningFeatureId,
        thinplan_plan::MachiningFeatureId,
    )],
) -> Vec<Obstacle> {
    use thinplan_plan::ConstraintKind;
    let f = &plan.machining_features[i];
    let n = plan.machining_features.len();
    // Ancestors of i: removed before i is cut, whatever order stage 8 picks.
    let mut preds: Vec<Vec<usize>> = vec![Vec::new(); n];
    let before_edges = plan
        .machining_constraints
        .iter()
        .filter(|c| c.kind == ConstraintKind::Before)
        .map(|c| (c.first, c.second))
        .chain(edges.iter().copied());
    for (a, b) in before_edges {
        let (a, b) = (a.0 as usize, b.0 as usize);
        if a < n && b < n {
            preds[b].push(a);
        }
    }
    let mut before = vec![false; n];
    let mut stack = vec![i];
    while let Some(v) = stack.pop() {
        for &p in &preds[v] {
            if !before[p] {
                before[p] = true;
                stack.push(p);
            }
        }
    }
    let mut out = Vec::new();
    for (j, g) in plan.machining_features.iter().enumerate() {
        if j == i || before[j] || !f.shank_neighbour(g, margin, rise) {
            continue;
        }
        out.push(Obstacle {
            id: g.id,
            region: region(g),
            top: g.shape.z_max,
        });
    }
    out
}

/// The free space less the obstacles' regions (each an outer contour and
/// holes; taken one at a time so one's hole never cancels another's area).
pub(crate) fn without(free: &Shapes, obstacles: &[&Obstacle]) -> Shapes {
    let mut out = free.clone();
    for o in obstacles {
        let clip = filled(&o.region);
        out = out.overlay_as::<i64>(&clip, OverlayRule::Difference, FillRule::NonZero);
    }
    without_slits(out)
}
