//! Stage 3: the connection graph (base–leaf and crossing) in the set-up frame.

use glam::DVec3;
use thinplan_brep::{Brep, EdgeAdjacency};
use thinplan_knowledge::WallRecognition;
use thinplan_plan::{Connection, StiffnessFeature};

pub fn connect(
    _brep: &Brep,
    _adjacency: &[EdgeAdjacency],
    _up: DVec3,
    _features: &[StiffnessFeature],
    _k: &WallRecognition,
) -> Vec<Connection> {
    Vec::new()
}
