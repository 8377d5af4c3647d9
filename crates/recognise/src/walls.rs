//! Walls: pairs of opposite faces a small distance apart.

use glam::DVec3;
use thinplan_brep::{Brep, EdgeAdjacency};
use thinplan_knowledge::WallRecognition;
use thinplan_plan::StiffnessFeature;

/// Finds the walls of the part (ids are assigned by the caller).
pub fn find_walls(
    _brep: &Brep,
    _adjacency: &[EdgeAdjacency],
    _up: DVec3,
    _k: &WallRecognition,
    _warnings: &mut Vec<String>,
) -> Vec<StiffnessFeature> {
    Vec::new()
}
