//! Material covered by features that get no operation.
//!
//! A feature that gets no operation (no tool fits it, another set-up
//! reaches it, the safety net refused its paths) leaves its material
//! standing, and so does every feature below it that is reached only
//! through it. But a feature is rarely covered whole: a sliver in a pocket
//! corner covers a square millimetre of the web below, not the web. The
//! feature below is therefore planned on what of it lies outside the
//! covering features' footprints; that footprint becomes stock the tool
//! keeps out of (a product-like edge: no overhang) and is reported as
//! unreachable, and the covering features stand as shank obstacles.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use std::collections::{BTreeMap, BTreeSet};

use thinplan_plan::{MachiningFeature, Plan};

use crate::free::{self, Obstacle, Shapes};
use crate::layers;

/// For each feature, the features above it that get no operation.
pub(crate) struct Covering {
    /// Per feature: the features without operations that cover it from
    /// the tool side, directly or through others.
    pub(crate) by: Vec<BTreeSet<usize>>,
    /// Per feature: why, as the first of them gave it (the reason, and
    /// whether its material is unreachable in this set-up).
    pub(crate) reason: Vec<Option<(String, bool)>>,
}

impl Covering {
    pub(crate) fn new(n: usize) -> Self {
        Covering {
            by: vec![BTreeSet::new(); n],
            reason: vec![None; n],
        }
    }

    /// One pass down the accessibility constraints: a feature is covered by
    /// what covers the feature above it, and by that feature too where it
    /// gets no operation (`skipped`, or an error in `made`). A feature whose
    /// covering grows is reset in `made`, to be planned again. Whether any
    /// grew.
    pub(crate) fn spread(
        &mut self,
        plan: &Plan,
        skipped: &BTreeMap<usize, (String, bool)>,
        made: &mut [Option<Result<layers::Made, String>>],
    ) -> bool {
        let mut changed = false;
        for c in &plan.machining_constraints {
            if c.provenance.rule != "interference.accessibility" {
                continue;
            }
            let (a, b) = (c.first.0 as usize, c.second.0 as usize);
            if skipped.contains_key(&b) {
                continue;
            }
            let a_fails = skipped.contains_key(&a) || matches!(made[a], Some(Err(_)));
            let mut add = self.by[a].clone();
            if a_fails {
                add.insert(a);
            }
            if add.is_subset(&self.by[b]) {
                continue;
            }
            if self.reason[b].is_none() {
                // Below material no tool reaches, the same holds.
                let unreachable = match (&skipped.get(&a), &made[a]) {
                    (Some((_, u)), _) => *u,
                    (None, Some(Err(e))) => layers::is_unreachable(e),
                    _ => self.reason[a].as_ref().is_some_and(|r| r.1),
                };
                let first = if a_fails {
                    c.first
                } else {
                    plan.machining_features[*self.by[a].iter().next().expect("not a subset")].id
                };
                let reason = if unreachable {
                    format!("unreachable: {first} above it is")
                } else {
                    format!("{first} above it gets no operation")
                };
                self.reason[b] = Some((reason, unreachable));
            }
            self.by[b].extend(add);
            made[b] = None;
            changed = true;
        }
        changed
    }
}

fn area(shapes: &Shapes) -> f64 {
    shapes.iter().map(|s| free::shape_area(s)).sum()
}

/// The union of the features' plan-view regions.
pub(crate) fn footprint<'a>(features: impl IntoIterator<Item = &'a MachiningFeature>) -> Shapes {
    let mut out: Shapes = Vec::new();
    for g in features {
        let clip = free::filled(&free::region(g));
        out = out.overlay_as::<i64>(&clip, OverlayRule::Union, FillRule::NonZero);
    }
    out
}

/// `shapes` less `keep`.
pub(crate) fn less(shapes: &Shapes, keep: &Shapes) -> Shapes {
    if keep.is_empty() {
        return shapes.clone();
    }
    free::without_slits(shapes.overlay_as::<i64>(keep, OverlayRule::Difference, FillRule::NonZero))
}

/// What of `f` lies outside `keep`: each piece a feature of its own (same
/// id and heights), its edges classified against `free` and `removed`
/// (which the caller has already cleared of `keep`, so edges along it are
/// product-like: the tool keeps out), and the area of `f` under `keep`.
pub(crate) fn uncovered(
    f: &MachiningFeature,
    keep: &Shapes,
    free: &Shapes,
    removed: &Shapes,
) -> (Vec<MachiningFeature>, f64) {
    let own = free::filled(&free::region(f));
    let rest = less(&own, keep);
    let covered = (area(&own) - area(&rest)).max(0.0);
    // `less` dropped the slivers (`free::without_slits`).
    let pieces = rest
        .iter()
        .map(|s| crate::rest::rebuilt(f, s, free, removed))
        .collect();
    (pieces, covered)
}

/// The covering features as shank obstacles: their material stands while
/// the feature below is cut.
pub(crate) fn obstacles<'a>(
    plan: &Plan,
    covering: impl IntoIterator<Item = &'a usize>,
) -> Vec<Obstacle> {
    covering
        .into_iter()
        .map(|&j| {
            let g = &plan.machining_features[j];
            Obstacle {
                id: g.id,
                region: free::region(g),
                top: g.shape.z_max,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    fn feature(r: Vec<[f64; 2]>) -> MachiningFeature {
        let open = vec![Adjacency::Open; r.len()];
        crate::rest::test_feature(1, &r, open, (0.0, 2.0))
    }

    /// A 1 × 1 sliver in the corner of a 10 × 10 web: the web is planned
    /// on the 99 mm² outside it, the edges along the sliver are product-like
    /// (the tool keeps out), the ones along the cut space stay open.
    #[test]
    fn a_corner_sliver_keeps_one_square_out_of_the_web() {
        let web = feature(rect(0.0, 0.0, 10.0, 10.0));
        let sliver = feature(rect(0.0, 0.0, 1.0, 1.0));
        let keep = footprint([&sliver]);
        let all: Shapes = vec![vec![rect(-5.0, -5.0, 15.0, 15.0)]];
        let free = less(&all, &keep);
        let (pieces, covered) = uncovered(&web, &keep, &free, &free);
        assert!((covered - 1.0).abs() < 1e-6, "{covered}");
        assert_eq!(pieces.len(), 1);
        let p = &pieces[0];
        let a = crate::layers::region_area(p);
        assert!((a - 99.0).abs() < 1e-6, "{a}");
        let product = p
            .side_adjacency
            .iter()
            .filter(|a| **a == Adjacency::Product)
            .count();
        assert_eq!(product, 2, "{:?}", p.side_adjacency);
        assert_eq!(p.side_adjacency.len(), 6);
    }

    /// A cover across the middle splits the feature into two pieces.
    #[test]
    fn a_cover_across_the_middle_leaves_two_pieces() {
        let web = feature(rect(0.0, 0.0, 10.0, 4.0));
        let bar = feature(rect(4.0, -1.0, 6.0, 5.0));
        let keep = footprint([&bar]);
        let all: Shapes = vec![vec![rect(-5.0, -5.0, 15.0, 15.0)]];
        let free = less(&all, &keep);
        let (pieces, covered) = uncovered(&web, &keep, &free, &free);
        assert_eq!(pieces.len(), 2);
        assert!((covered - 8.0).abs() < 1e-6, "{covered}");
    }

    /// A cover over all of it leaves nothing to plan.
    #[test]
    fn a_whole_cover_leaves_nothing() {
        let web = feature(rect(0.0, 0.0, 10.0, 4.0));
        let lid = feature(rect(-1.0, -1.0, 11.0, 5.0));
        let keep = footprint([&lid]);
        let all: Shapes = vec![vec![rect(-5.0, -5.0, 15.0, 15.0)]];
        let free = less(&all, &keep);
        let (pieces, covered) = uncovered(&web, &keep, &free, &free);
        assert!(pieces.is_empty());
        assert!((covered - 40.0).abs() < 1e-6, "{covered}");
    }
}
