//! Depressions (holes, cut-outs, slots, notches, pockets, steps) and details
//! (chamfers, fillets).

use std::collections::BTreeSet;

use glam::DVec3;
use thinplan_brep::{Brep, EdgeAdjacency, FaceId};
use thinplan_knowledge::DepressionRecognition;
use thinplan_plan::StiffnessFeature;

/// Finds depressions and details among the faces walls did not claim
/// (ids are assigned by the caller).
pub fn find_depressions(
    _brep: &Brep,
    _adjacency: &[EdgeAdjacency],
    _up: DVec3,
    _k: &DepressionRecognition,
    _claimed: &BTreeSet<FaceId>,
    _warnings: &mut Vec<String>,
) -> Vec<StiffnessFeature> {
    Vec::new()
}
