//! Depression and detail recognition thresholds
//! (`knowledge/recognition_depressions.ron`).

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range};

/// The kinds of depressions and details the recogniser may report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum DepressionKind {
    Hole,
    Cutout,
    Slot,
    Notch,
    Pocket,
    Step,
    Chamfer,
    Fillet,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepressionRecognition {
    /// Distance tolerance, mm.
    pub distance_tolerance: f64,
    /// Angle tolerance, degrees.
    pub angle_tolerance_deg: f64,
    /// A chamfer is a planar face at most this wide (mm) between two faces
    /// it is inclined to.
    pub max_chamfer_width: f64,
    /// A chamfer on the envelope (cutting off an edge of the stock) may also
    /// be up to this fraction of its length wide.
    #[serde(default = "default_max_chamfer_width_ratio")]
    pub max_chamfer_width_ratio: f64,
    /// A fillet is a concave or convex cylindrical blend of at most this radius, mm.
    pub max_fillet_radius: f64,
    /// A chamfer is inclined to its neighbours by at least this angle and at
    /// most 90° minus it, degrees.
    #[serde(default = "default_min_chamfer_incline_deg")]
    pub min_chamfer_incline_deg: f64,
    /// Profile corners within this many degrees of 90° count as right angles
    /// (rectangular profiles, rectangular blind steps).
    #[serde(default = "default_right_angle_tolerance_deg")]
    pub right_angle_tolerance_deg: f64,
    /// A through opening whose outline is two parallel straight sides joined
    /// by two ends (round or straight) is a slot when its length (along the
    /// sides) is at least this many times its width (between them); a
    /// shorter one, or a round one, is a hole.
    #[serde(default = "default_min_slot_length_to_width")]
    pub min_slot_length_to_width: f64,
    /// The kinds to recognise, in priority order: when a face set can be read
    /// as two kinds (e.g. a narrow inclined face: chamfer or slanted step) the
    /// kind listed first wins; a kind left out is not recognised (its faces
    /// stay plain part faces).
    #[serde(default = "default_priority")]
    pub priority: Vec<DepressionKind>,
}

fn default_max_chamfer_width_ratio() -> f64 {
    0.75
}

fn default_min_chamfer_incline_deg() -> f64 {
    5.0
}

fn default_right_angle_tolerance_deg() -> f64 {
    1.0
}

fn default_min_slot_length_to_width() -> f64 {
    2.0
}

fn default_priority() -> Vec<DepressionKind> {
    use DepressionKind::*;
    vec![Hole, Pocket, Slot, Cutout, Notch, Step, Chamfer, Fillet]
}

impl DepressionRecognition {
    /// Problems with the values (empty when fine).
    pub fn problems(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `recognition_depressions.ron`.
    pub fn checks(&self, c: &mut Checks) {
        let fields: [(&'static str, f64, Range, &str); 8] = [
            (
                "distance_tolerance",
                self.distance_tolerance,
                Range::open(0.0, 1.0),
                " mm",
            ),
            (
                "angle_tolerance_deg",
                self.angle_tolerance_deg,
                Range::open(0.0, 10.0),
                "°",
            ),
            (
                "max_chamfer_width",
                self.max_chamfer_width,
                Range::above(0.0, 1000.0),
                " mm",
            ),
            (
                "max_chamfer_width_ratio",
                self.max_chamfer_width_ratio,
                Range::above(0.0, 10.0),
                "",
            ),
            (
                "max_fillet_radius",
                self.max_fillet_radius,
                Range::above(0.0, 10_000.0),
                " mm",
            ),
            (
                "min_chamfer_incline_deg",
                self.min_chamfer_incline_deg,
                Range::open(0.0, 45.0),
                "°",
            ),
            (
                "right_angle_tolerance_deg",
                self.right_angle_tolerance_deg,
                Range::open(0.0, 45.0),
                "°",
            ),
            (
                "min_slot_length_to_width",
                self.min_slot_length_to_width,
                Range::closed(1.0, 1000.0),
                "",
            ),
        ];
        for (name, v, r, unit) in fields {
            c.range(at![name], "", name, v, r, unit);
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, k) in self.priority.iter().enumerate() {
            if !seen.insert(*k) {
                c.push(at!["priority", i], format!("priority lists {k:?} twice"));
            }
        }
    }

    /// Whether `kind` is enabled.
    pub fn recognises(&self, kind: DepressionKind) -> bool {
        self.priority.contains(&kind)
    }

    /// Rank of `kind` in the priority list (lower wins); disabled kinds last.
    pub fn rank(&self, kind: DepressionKind) -> usize {
        self.priority
            .iter()
            .position(|k| *k == kind)
            .unwrap_or(usize::MAX)
    }
}
