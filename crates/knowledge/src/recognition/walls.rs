//! Wall recognition thresholds (`knowledge/recognition_walls.ron`).

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallRecognition {
    /// Two opposite faces at most this far apart (mm) can form a wall.
    pub max_thickness: f64,
    /// A wall is thin when its height / thickness is at least this.
    pub min_height_to_thickness: f64,
    /// Above this height / thickness ratio a wall needs special care
    /// (Sandvik's 15:1 for aluminium).
    pub careful_height_to_thickness: f64,
    /// Distance tolerance for coplanarity and coaxiality, mm.
    pub distance_tolerance: f64,
    /// Angle tolerance for parallel and perpendicular faces, degrees.
    pub angle_tolerance_deg: f64,
}
