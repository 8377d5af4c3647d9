//! Method and tool choice for a band: the method the feature's adjacency
//! selects, and the tool by the method's rule that fits the smallest
//! product corner (read from the tessellated walls' chords), has room in
//! the feature and reaches its floor, with the cutting conditions for it.
//! A tool that reaches only part of the depth cuts what it reaches and the
//! rest is refused.

use thinplan_knowledge::{Method, MethodKnowledge, SidesMatch, Tool, ToolChoice};
use thinplan_plan::{Adjacency, MachiningFeature};

use super::region::Geometry;
use super::{depth_below_top, region_area, tool_reach, Env, Loops, NO_TOOL_FITS, NO_TOOL_REACHES};
use crate::geom::{adjacency_edges, Edge2};

/// The feature's loops, how its sides match the product, and the method of
/// the knowledge that applies to it; `Err` for a degenerate feature or
/// where no method applies.
pub(super) fn method_for<'k>(
    f: &MachiningFeature,
    mk: &'k MethodKnowledge,
) -> Result<(Loops, SidesMatch, &'k Method), String> {
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    if edges[0].0.len() < 2 {
        return Err("its profile has fewer than two vertices".into());
    }
    if f.shape.z_max.partial_cmp(&f.shape.z_min) != Some(std::cmp::Ordering::Greater) {
        return Err(format!(
            "empty depth range [{}, {}]",
            f.shape.z_min, f.shape.z_max
        ));
    }
    let sides = sides_class(&edges);
    let bottom_product = f.bottom_adjacency == Adjacency::Product;
    let m = mk
        .for_feature(bottom_product, sides)
        .ok_or_else(|| format!("no method applies (sides {sides:?})"))?;
    Ok((edges, sides, m))
}

/// The band's tool and its geometry.
pub(super) struct Chosen<'a> {
    pub(super) tool: &'a Tool,
    pub(super) g: Geometry,
    /// The smallest product corner's radius, where the feature has product
    /// corners.
    pub(super) corner: Option<f64>,
    /// The refusal for the product corners tighter than every tool, where
    /// there are such corners: the material in them stays.
    pub(super) corners_left: Option<String>,
}

/// The feature's tool: by the method's rule, of a kind it allows, smaller
/// than the smallest product corner, and reaching the feature's floor
/// (else the one that reaches deepest), the first that `fits` (has a
/// tool-centre region).
pub(super) fn choose_tool<'a>(
    f: &MachiningFeature,
    env: &Env<'a>,
    m: &Method,
    edges: &[(Vec<Edge2>, Vec<Adjacency>)],
    fits: impl Fn(&'a Tool) -> Option<Geometry>,
    warnings: &mut Vec<String>,
) -> Result<Chosen<'a>, String> {
    let mut cands: Vec<&'a Tool> = env
        .tools
        .tools
        .iter()
        .filter(|t| m.tool.kinds.contains(&t.kind))
        .collect();
    if cands.is_empty() {
        return Err(format!(
            "{NO_TOOL_FITS} (none of the kinds {:?} the method allows)",
            m.tool.kinds
        ));
    }
    // By the method's rule on the diameter; among tools of one diameter
    // the shortest stickout first (the stiffest that reaches: a long-reach
    // tool only where a standard one does not reach).
    let by_size = |a: &&Tool, b: &&Tool| {
        a.diameter
            .total_cmp(&b.diameter)
            .then_with(|| b.stickout.total_cmp(&a.stickout))
            .then_with(|| b.id.cmp(&a.id))
    };
    cands.sort_by(by_size);
    if m.tool.choice == ToolChoice::LargestThatFits {
        cands.reverse();
    } else {
        cands.sort_by(|a, b| {
            a.diameter
                .total_cmp(&b.diameter)
                .then_with(|| a.stickout.total_cmp(&b.stickout))
                .then_with(|| a.id.cmp(&b.id))
        });
    }
    let corner = smallest_product_corner(edges);
    let mut corners_left = None;
    if let (Some(ratio), Some(rho)) = (m.tool.corner_ratio, corner) {
        let small: Vec<&Tool> = cands
            .iter()
            .copied()
            .filter(|t| t.diameter / 2.0 <= ratio * rho)
            .collect();
        if small.is_empty() {
            // The smallest tool leaves the least in those corners.
            cands.sort_by(|a, b| {
                a.diameter
                    .total_cmp(&b.diameter)
                    .then_with(|| a.stickout.total_cmp(&b.stickout))
                    .then_with(|| a.id.cmp(&b.id))
            });
            warnings.push(format!(
                "{}: no tool is smaller than its smallest product corner (radius {rho:.3} mm); \
                 the smallest that fits is used and material stays in those corners",
                f.id
            ));
            let needs = if rho > 0.0 {
                format!("; needs D <= {:.3} mm", 2.0 * ratio * rho)
            } else {
                "; a sharp corner: no end mill reaches it".into()
            };
            corners_left = Some(format!(
                "unreachable: product corners of {} tighter than any tool (smallest corner \
                 radius {rho:.3} mm, smallest tool radius {:.3} mm): the material in them \
                 stays{needs}",
                f.id,
                cands[0].diameter / 2.0
            ));
        } else {
            cands = small;
        }
    }
    let need = depth_below_top(env, f, f.shape.z_min);
    let (reaching, short): (Vec<&Tool>, Vec<&Tool>) = cands
        .iter()
        .copied()
        .partition(|t| tool_reach(env, t) >= need - 1e-9);
    let fits = |t: &'a Tool| fits(t).map(|g| (t, g));
    let mut short = short;
    // Deepest reach first: the most of the feature is cut.
    short.sort_by(|a, b| tool_reach(env, b).total_cmp(&tool_reach(env, a)));
    let (tool, g) = reaching
        .iter()
        .find_map(|t| fits(t))
        .or_else(|| short.iter().find_map(|t| fits(t)))
        .ok_or_else(|| {
            let smallest = cands
                .iter()
                .map(|t| t.diameter)
                .fold(f64::INFINITY, f64::min);
            format!(
                "{NO_TOOL_FITS} (the smallest, D {smallest:.3} mm, has no room at its radius \
                 from the product and the free space)"
            )
        })?;
    Ok(Chosen {
        tool,
        g,
        corner,
        corners_left,
    })
}

/// A feature cut short where its tool does not reach its floor.
pub(super) struct CutShort {
    /// The feature down to the deepest height the tool reaches: its floor
    /// then faces the rest of the feature.
    pub(super) feature: MachiningFeature,
    /// The refusal for what lies below, and that volume (mm³).
    pub(super) left: (String, f64),
}

/// Where `tool` does not reach the feature's floor: the feature cut short
/// (the refusal is also a warning). `None` where it reaches the floor,
/// `Err` where it reaches none of the feature.
pub(super) fn clamped_to_reach(
    env: &Env,
    f: &MachiningFeature,
    tool: &Tool,
    warnings: &mut Vec<String>,
) -> Result<Option<CutShort>, String> {
    let need = depth_below_top(env, f, f.shape.z_min);
    let reach = tool_reach(env, tool);
    if reach >= need - 1e-9 {
        return Ok(None);
    }
    let z_reach = f.shape.z_min + (need - reach);
    let why = format!(
        "{NO_TOOL_REACHES}: {} below {z_reach:.3}, {need:.1} mm below the top of the stock: \
         the tool of the set that fits and reaches deepest, {} (D {:.3} mm), reaches \
         {reach:.1} mm; needs D <= {:.3} mm with {need:.1} mm reach (stickout {:.1} mm)",
        f.id,
        tool.id,
        tool.diameter,
        tool.diameter,
        need + env.k.methods.holder_clearance
    );
    if z_reach >= f.shape.z_max - 1e-6 {
        return Err(why);
    }
    let area = region_area(f);
    let mut c = f.clone();
    c.shape.z_min = z_reach;
    c.bottom_adjacency = Adjacency::Feature;
    warnings.push(format!("{}: {why}", f.id));
    let left = area * (z_reach - f.shape.z_min);
    Ok(Some(CutShort {
        feature: c,
        left: (why, left),
    }))
}

/// How the feature's sides meet the product: none, all or some of them.
fn sides_class(edges: &[(Vec<Edge2>, Vec<Adjacency>)]) -> SidesMatch {
    let all: Vec<Adjacency> = edges.iter().flat_map(|(_, a)| a.iter().copied()).collect();
    let p = all.iter().filter(|a| **a == Adjacency::Product).count();
    if p == 0 {
        SidesMatch::Open
    } else if p == all.len() {
        SidesMatch::Closed
    } else {
        SidesMatch::PartiallyOpen
    }
}

/// Smallest concave product corner radius: product arcs whose centre lies on
/// the region's side, and sharp convex vertices between two product edges.
fn smallest_product_corner(edges: &[(Vec<Edge2>, Vec<Adjacency>)]) -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut note = |v: f64| best = Some(best.map_or(v, |b: f64| b.min(v)));
    for (es, adj) in edges {
        let n = es.len();
        // The region lies left of every edge (ccw outer, cw holes): a left
        // turn between two product edges is a concave corner of the part.
        // Negative: a right turn, or an edge that is not product (either
        // ends a run of chords).
        let turn = |i: usize| {
            let j = (i + 1) % n;
            if adj[i] != Adjacency::Product || adj[j] != Adjacency::Product {
                return -1.0;
            }
            let (t1, t2) = (es[i].tangents().1, es[j].tangents().0);
            t1.perp_dot(t2).atan2(t1.dot(t2))
        };
        for i in 0..n {
            if adj[i] == Adjacency::Product {
                if let Some((r, _)) = es[i].arc() {
                    if es[i].bulge > 0.0 {
                        note(r);
                    }
                }
            }
        }
        let turns: Vec<f64> = (0..n).map(turn).collect();
        let lengths: Vec<f64> = es.iter().map(Edge2::length).collect();
        for r in corner_radii(&turns, &lengths) {
            note(r);
        }
    }
    best
}

/// The largest turn between two chords of one tessellated arc: twice the
/// sections' mesh turn per segment (`thinplan_brep::TessParams::angle`,
/// 0.2 rad). A steeper left turn is a sharp corner of the part.
const CHORD_TURN_MAX: f64 = 0.4;

/// A chord run ends at a link this many times longer than the link beside
/// it: a fillet's chords are alike, the wall tangent to two fillets is not.
const CHORD_LINK_RATIO: f64 = 3.0;

/// The concave corners' radii along a closed chain: `turns[i]` is the turn
/// from edge i to edge i + 1 (left positive; negative also where an edge
/// is not product), `lengths[i]` edge i's length. A left turn steeper than
/// [`CHORD_TURN_MAX`] is a sharp corner (0). Gentler left turns, with
/// straight junctions between them, are the chords of a tessellated fillet,
/// split where one link between turns is [`CHORD_LINK_RATIO`] times longer
/// than a link beside it; each fillet of two turns or more gives its
/// radius: its chords' length over the turns (the first and last, at the
/// tangent points, are half a chord's), a little under the true radius as
/// chords are shorter than their arcs. A lone gentle turn is sharp (0).
fn corner_radii(turns: &[f64], lengths: &[f64]) -> Vec<f64> {
    let n = turns.len();
    let straight = |t: f64| t.abs() <= 1e-6;
    let chordal = |t: f64| t > 1e-6 && t <= CHORD_TURN_MAX;
    let mut out: Vec<f64> = turns
        .iter()
        .filter(|t| **t > CHORD_TURN_MAX)
        .map(|_| 0.0)
        .collect();
    // Runs start after a junction that is neither chordal nor straight.
    let Some(start) = (0..n).find(|&i| !chordal(turns[i]) && !straight(turns[i])) else {
        // Every junction chordal or straight: a round hole's wall.
        let total: f64 = turns.iter().filter(|t| **t > 0.0).sum();
        if total > 1e-9 {
            out.push(lengths.iter().sum::<f64>() / total);
        }
        return out;
    };
    // (turns, links between consecutive turns) of each run.
    let mut runs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let (mut cur, mut links) = (Vec::new(), Vec::new());
    let mut since = 0.0;
    for s in 1..=n {
        let i = (start + s) % n;
        let t = turns[i];
        if chordal(t) {
            if !cur.is_empty() {
                links.push(since + lengths[i]);
            }
            since = 0.0;
            cur.push(t);
        } else if straight(t) && !cur.is_empty() {
            since += lengths[i];
        } else if !cur.is_empty() {
            runs.push((std::mem::take(&mut cur), std::mem::take(&mut links)));
            since = 0.0;
        }
    }
    if !cur.is_empty() {
        runs.push((cur, links));
    }
    for (turns, links) in runs {
        // A link much longer than a link beside it is a wall between two
        // fillets: the run splits there.
        let wall = |j: usize| {
            let longer = |k: Option<&f64>| k.is_some_and(|l| links[j] > CHORD_LINK_RATIO * l);
            longer(j.checked_sub(1).and_then(|k| links.get(k))) || longer(links.get(j + 1))
        };
        let mut from = 0;
        for k in 0..turns.len() {
            if k + 1 < turns.len() && !wall(k) {
                continue;
            }
            // Turns from..=k, joined by links from..k: one fillet; a lone
            // turn is read as sharp (a boolean's polyline kink, a noisy
            // vertex).
            if k == from {
                out.push(0.0);
            } else {
                // The end turns are at the tangent points (half a chord's
                // turn each): the chords subtend all the turns.
                let total: f64 = turns[from..=k].iter().sum();
                if total > 1e-9 {
                    out.push(links[from..k].iter().sum::<f64>() / total);
                }
            }
            from = k + 1;
        }
    }
    out
}

/// Cutting conditions: spindle speed and feeds (mm/min) for a tool.
pub(super) fn conditions(env: &Env, tool: &Tool) -> (f64, f64, f64) {
    let c = &env.material.cutting;
    let rpm = (1000.0 * c.cutting_speed / (std::f64::consts::PI * tool.diameter))
        .min(env.machine.spindle_max_rpm);
    let vmax = 60.0 * env.machine.x.v_max.min(env.machine.y.v_max);
    let z = tool.flutes as f64;
    (
        rpm,
        (c.feed_per_tooth_roughing * z * rpm).min(vmax),
        (c.feed_per_tooth_finishing * z * rpm).min(vmax),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A pocket's corner chain as the mesh sections give it: a wall, a
    /// fillet of radius `r` in `k` chords (each optionally split in two by
    /// a collinear vertex), another wall turning 90° in all, and a sharp
    /// 90° corner closing nothing (turns and lengths only).
    fn filleted(r: f64, k: usize, wall: f64, split: bool) -> (Vec<f64>, Vec<f64>) {
        let step = std::f64::consts::FRAC_PI_2 / k as f64;
        let chord = 2.0 * r * (0.5 * step).sin();
        // Edge 0: the first wall; then the chords; then the second wall.
        let mut lengths = vec![wall];
        let mut turns = vec![0.5 * step];
        for c in 0..k {
            if split {
                lengths.extend([0.3 * chord, 0.7 * chord]);
                turns.push(0.0);
            } else {
                lengths.push(chord);
            }
            turns.push(if c + 1 == k { 0.5 * step } else { step });
        }
        lengths.push(wall);
        // The second wall meets the first one's start at a sharp corner.
        turns.push(std::f64::consts::FRAC_PI_2);
        (turns, lengths)
    }

    proptest! {
        /// A tessellated fillet reads as its radius (within 3 %), the sharp
        /// corner as 0, whatever the chord count, wall length and collinear
        /// splits.
        #[test]
        fn a_fillets_chords_give_its_radius_and_a_sharp_corner_zero(
            r in 1.0f64..20.0,
            k in 8usize..40,
            wall in 5.0f64..200.0,
            split in any::<bool>(),
        ) {
            let (turns, lengths) = filleted(r, k, wall, split);
            let mut radii = corner_radii(&turns, &lengths);
            radii.sort_by(f64::total_cmp);
            prop_assert_eq!(radii.len(), 2, "{:?}", radii);
            prop_assert_eq!(radii[0], 0.0);
            prop_assert!((radii[1] - r).abs() <= 0.03 * r, "{} for {}", radii[1], r);
        }

        /// Two fillets joined by a wall tangent to both stay two fillets:
        /// the wall is no chord.
        #[test]
        fn a_wall_between_two_fillets_is_not_a_chord(
            r in 1.0f64..20.0,
            k in 8usize..30,
            wall in 20.0f64..200.0,
        ) {
            let (mut turns, mut lengths) = filleted(r, k, wall, false);
            // Replace the sharp corner by a second fillet.
            turns.pop();
            let (t2, l2) = filleted(r, k, wall, false);
            turns.extend(&t2[..t2.len() - 1]);
            lengths.extend(&l2[1..]);
            turns.push(-1.0);
            let radii = corner_radii(&turns, &lengths);
            prop_assert_eq!(radii.len(), 2, "{:?}", radii);
            for x in radii {
                prop_assert!((x - r).abs() <= 0.03 * r, "{} for {}", x, r);
            }
        }
    }
}
