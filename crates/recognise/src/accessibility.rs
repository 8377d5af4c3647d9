//! Tool-access directions a machine can reach for each stiffness feature.

use glam::DVec3;
use thinplan_brep::Brep;
use thinplan_knowledge::Machine;
use thinplan_plan::StiffnessFeature;

/// The directions (unit vectors, part coordinates, pointing from the
/// feature towards the spindle) from which `machine` can reach `feature`
/// with the part placed so that `up` is the machine's +z.
pub fn access_directions(
    _brep: &Brep,
    _feature: &StiffnessFeature,
    _up: DVec3,
    _machine: &Machine,
) -> Vec<DVec3> {
    Vec::new()
}
