//! Wall recognition thresholds (`knowledge/recognition_walls.ron`).

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallRecognition {
    /// Two opposite faces at most this far apart (mm) can form a thin wall.
    pub max_thickness: f64,
    /// A wall is thin when its height / thickness is at least this (for a
    /// web, height is its smaller in-plane extent).
    pub min_height_to_thickness: f64,
    /// Above this height / thickness ratio a wall needs special care
    /// (Sandvik's 15:1 for aluminium).
    pub careful_height_to_thickness: f64,
    /// A plate normal to the spindle axis that is not thin itself, at most
    /// this thick (mm), is still kept as a web when a thin wall stands on
    /// it: it is the base the thin walls are connected to (the clamped end
    /// of the cantilever). 0 turns the rule off.
    pub max_base_thickness: f64,
    /// Such a base must be a plate: its smaller in-plane extent (or mean
    /// width) at least this many times its thickness.
    pub min_base_width_to_thickness: f64,
    /// Distance tolerance for coplanarity and coaxiality, mm.
    pub distance_tolerance: f64,
    /// Angle tolerance for parallel and perpendicular faces, degrees.
    pub angle_tolerance_deg: f64,
}

impl WallRecognition {
    /// Problems with the values (empty when fine).
    pub fn validate(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `recognition_walls.ron`.
    pub fn checks(&self, c: &mut Checks) {
        let ratio = Range::above(0.0, 1000.0);
        let fields: [(&'static str, f64, Range, &str); 6] = [
            (
                "max_thickness",
                self.max_thickness,
                Range::above(0.0, 1000.0),
                " mm",
            ),
            (
                "min_height_to_thickness",
                self.min_height_to_thickness,
                ratio,
                "",
            ),
            (
                "careful_height_to_thickness",
                self.careful_height_to_thickness,
                ratio,
                "",
            ),
            (
                "max_base_thickness",
                self.max_base_thickness,
                Range::closed(0.0, 10_000.0),
                " mm (0: off)",
            ),
            (
                "min_base_width_to_thickness",
                self.min_base_width_to_thickness,
                ratio,
                "",
            ),
            (
                "angle_tolerance_deg",
                self.angle_tolerance_deg,
                Range::open(0.0, 10.0),
                "°",
            ),
        ];
        for (name, v, r, unit) in fields {
            c.range(at![name], "", name, v, r, unit);
        }
        // A tolerance at least as large as the walls it should tell apart
        // would merge them.
        let hi = if self.max_thickness.is_finite() && self.max_thickness > 0.0 {
            self.max_thickness.min(1.0)
        } else {
            1.0
        };
        c.range(
            at!["distance_tolerance"],
            "",
            "distance_tolerance",
            self.distance_tolerance,
            Range::open(0.0, hi),
            " mm (below max_thickness)",
        );
        if self.careful_height_to_thickness < self.min_height_to_thickness {
            c.push(
                at!["careful_height_to_thickness"],
                format!(
                    "careful_height_to_thickness {} is below min_height_to_thickness {}",
                    self.careful_height_to_thickness, self.min_height_to_thickness
                ),
            );
        }
    }
}
