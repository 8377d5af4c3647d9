//! Remaining material too narrow for the set-up's smallest tool, cut with
//! what it borders: a shape that holds no disc of the tool's radius has no
//! pass of its own, so it joins the piece of a selected feature
//! (`interference.narrow_remaining_joins`) it borders longest in its slab
//! (such as a sliver in a web's corner fillet).

use crate::section::{self, Shapes};
use crate::{bbox_of, overlaps};

/// How far apart (mm) a narrow shape's vertex and a piece's may be and
/// still be one point: the last bits of two overlays' arithmetic.
const SNAP: f64 = 1e-9;

/// A claim's piece in one slab: the claim, its plan-view box, its shapes.
pub(crate) type Taken = (usize, [f64; 4], Shapes);

/// Whether no disc of `radius` fits anywhere in `s`.
fn narrow(s: &Shapes, radius: f64) -> bool {
    section::offset(s, -radius).is_empty()
}

/// The piece among `taken` that `one` borders longest, measured as the
/// area a thin band around it overlaps (a band as wide as a sliver is
/// long); `None` when it borders none by more than a sliver.
fn longest_border(one: &Shapes, taken: &[Taken], sliver_area: f64) -> Option<usize> {
    let grown = section::offset(one, sliver_area.sqrt());
    let bb = bbox_of(&grown);
    taken
        .iter()
        .enumerate()
        .filter(|(_, (_, tb, _))| overlaps(tb, &bb))
        .map(|(i, (_, _, t))| (i, section::area(&section::intersection(&grown, t))))
        .filter(|(_, a)| *a > sliver_area)
        .fold(None::<(usize, f64)>, |b, (i, a)| match b {
            Some((_, ba)) if ba >= a => b,
            _ => Some((i, a)),
        })
        .map(|(i, _)| i)
}

fn grow(t: &mut Taken, one: &Shapes) {
    // The shape and the piece come from different overlays: their shared
    // edge may differ in the last bits, which the union keeps as a crack
    // between two shapes.
    let one = section::snap_to(one, &t.2, SNAP);
    t.2 = section::union(&t.2, &one);
    t.1 = bbox_of(&t.2);
}

/// Joins each remaining shape that holds no disc of `radius` (nothing of
/// it is left inset by the radius) to the claimed piece it borders longest
/// in the slab: cut with that piece, it needs no tool of its own. Returns
/// the claims that grew, with the area each took.
pub(crate) fn join_narrow(
    keep: &mut Shapes,
    taken: &mut [Taken],
    radius: f64,
    sliver_area: f64,
) -> Vec<(usize, f64)> {
    let mut grew = Vec::new();
    let mut still = Vec::new();
    for shape in std::mem::take(keep) {
        let one = vec![shape];
        if !narrow(&one, radius) {
            still.extend(one);
            continue;
        }
        match longest_border(&one, taken, sliver_area) {
            Some(i) => {
                grow(&mut taken[i], &one);
                grew.push((taken[i].0, section::area(&one)));
            }
            None => still.extend(one),
        }
    }
    *keep = still;
    grew
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A strip beside a claimed piece joins it when it holds no disc of
        /// the radius, and stays remaining material when it does; the area
        /// is kept either way.
        #[test]
        fn a_strip_joins_its_neighbour_exactly_when_no_tool_fits_in_it(
            width in 0.2f64..8.0,
            radius in 0.5f64..4.0,
            length in 10.0f64..60.0,
        ) {
            prop_assume!((width - 2.0 * radius).abs() > 0.05);
            let web = section::rect([0.0, width], [length, width + 20.0]);
            let strip = section::rect([0.0, 0.0], [length, width]);
            let mut keep = strip.clone();
            let mut taken = vec![(7, bbox_of(&web), web.clone())];
            let grew = join_narrow(&mut keep, &mut taken, radius, 1e-4);
            let narrow = width < 2.0 * radius;
            prop_assert_eq!(keep.is_empty(), narrow);
            prop_assert_eq!(grew.len(), usize::from(narrow));
            let total = section::area(&keep) + section::area(&taken[0].2);
            prop_assert!((total - length * (width + 20.0)).abs() < 1e-6 * total);
            if narrow {
                prop_assert_eq!(grew[0].0, 7);
                prop_assert_eq!(taken[0].2.len(), 1, "one piece after the join");
            }
        }
    }

    /// A narrow shape that borders no claimed piece stays remaining; one
    /// between two joins the one it borders longest.
    #[test]
    fn a_narrow_shape_joins_the_piece_it_borders_longest_or_none() {
        let alone = section::rect([100.0, 100.0], [130.0, 101.0]);
        let long = section::rect([0.0, 1.0], [30.0, 20.0]);
        let short = section::rect([0.0, -5.0], [10.0, 0.0]);
        let strip = section::rect([0.0, 0.0], [30.0, 1.0]);
        let mut keep: Shapes = alone.iter().chain(&strip).cloned().collect();
        let mut taken = vec![
            (1, bbox_of(&short), short.clone()),
            (2, bbox_of(&long), long.clone()),
        ];
        let grew = join_narrow(&mut keep, &mut taken, 3.0, 1e-4);
        assert_eq!(grew.len(), 1);
        assert_eq!(grew[0].0, 2);
        assert!((grew[0].1 - 30.0).abs() < 1e-6);
        assert!(section::same_region(&keep, &alone, 1e-6));
        assert!(section::same_region(&taken[0].2, &short, 1e-6));
    }

    /// Remaining material and a piece from different overlays, their
    /// shared edge differing in the last bits (coordinates as a fillet's
    /// sliver and its web layer came out of stage 6 on a generated frame):
    /// the join makes one shape of them, not two with a crack.
    #[test]
    fn a_join_across_an_edge_that_differs_in_the_last_bits_is_one_shape() {
        let web = vec![vec![vec![
            [96.04289761511117, 61.36321033939421],
            [97.7, 61.2],
            [97.7, 69.7],
            [91.0, 69.7],
            [91.0, 63.0],
        ]]];
        let crescent = vec![vec![
            [97.7, 61.2],
            [96.0428976151112, 61.3632103393942],
            [96.8, 61.25],
            [97.4, 61.204],
        ]];
        let mut keep: Shapes = vec![crescent];
        let mut taken = vec![(4, bbox_of(&web), web.clone())];
        let grew = join_narrow(&mut keep, &mut taken, 3.0, 1e-6);
        assert_eq!(grew.len(), 1);
        assert!(keep.is_empty());
        assert_eq!(taken[0].2.len(), 1, "one shape: {:?}", taken[0].2);
    }
}
