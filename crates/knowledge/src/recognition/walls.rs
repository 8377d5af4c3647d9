//! Wall recognition thresholds (`knowledge/recognition_walls.ron`).

use serde::{Deserialize, Serialize};

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
        let mut out = Vec::new();
        let pos = [
            ("max_thickness", self.max_thickness),
            ("min_height_to_thickness", self.min_height_to_thickness),
            (
                "careful_height_to_thickness",
                self.careful_height_to_thickness,
            ),
            (
                "min_base_width_to_thickness",
                self.min_base_width_to_thickness,
            ),
            ("distance_tolerance", self.distance_tolerance),
            ("angle_tolerance_deg", self.angle_tolerance_deg),
        ];
        for (name, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                out.push(format!("{name} must be a positive number, is {v}"));
            }
        }
        if !(self.max_base_thickness.is_finite() && self.max_base_thickness >= 0.0) {
            out.push(format!(
                "max_base_thickness must be 0 or positive, is {}",
                self.max_base_thickness
            ));
        }
        if self.careful_height_to_thickness < self.min_height_to_thickness {
            out.push("careful_height_to_thickness is below min_height_to_thickness".into());
        }
        if self.angle_tolerance_deg >= 10.0 {
            out.push("angle_tolerance_deg must be below 10".into());
        }
        if self.distance_tolerance >= self.max_thickness {
            out.push("distance_tolerance must be below max_thickness".into());
        }
        out
    }
}
