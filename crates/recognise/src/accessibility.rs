//! Tool-access directions a machine can reach for each stiffness feature
//! (thesis §5.4.3, §6.1.3: the two main sides of a wall are accessed
//! separately).
//!
//! Candidates: a wall's two side normals (`±axis`); a depression along its
//! axis, both ways when it goes through the wall it is in (holes, cut-outs,
//! slots, notches), one way (`+axis`, the opening) for pockets and steps, and
//! for details (chamfers, fillets) the directions of the faces they blend are
//! not known here, so both ways along their axis. Each candidate is
//! expressed in the machine frame, where `up` is the machine's +z, and kept
//! when [`Machine::reaches`] it. Only the tilt from `up` matters to
//! `reaches`, so the rotation about `up` is immaterial.

use glam::{DQuat, DVec3};
use thinplan_brep::Brep;
use thinplan_knowledge::Machine;
use thinplan_plan::{StiffnessFeature, StiffnessKind};

/// The directions (unit vectors, part coordinates, pointing from the
/// feature towards the spindle) from which `machine` can reach `feature`
/// with the part placed so that `up` is the machine's +z.
pub fn access_directions(
    _brep: &Brep,
    feature: &StiffnessFeature,
    up: DVec3,
    machine: &Machine,
) -> Vec<DVec3> {
    let up = up.try_normalize().unwrap_or(DVec3::Z);
    let Some(axis) = feature.axis.try_normalize() else {
        return Vec::new();
    };
    let candidates: Vec<DVec3> = match feature.kind {
        StiffnessKind::Pocket | StiffnessKind::Step => vec![axis],
        _ => vec![axis, -axis],
    };
    let to_machine = DQuat::from_rotation_arc(up, DVec3::Z);
    candidates
        .into_iter()
        .filter(|d| machine.reaches(to_machine * *d))
        .collect()
}
