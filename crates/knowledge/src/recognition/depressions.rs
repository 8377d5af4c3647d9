//! Depression and detail recognition thresholds
//! (`knowledge/recognition_depressions.ron`).

use serde::{Deserialize, Serialize};

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
    /// A fillet is a concave or convex cylindrical blend of at most this radius, mm.
    pub max_fillet_radius: f64,
}
