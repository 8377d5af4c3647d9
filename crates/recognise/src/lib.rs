//! Stages 2 and 3: recognise stiffness features in the B-rep, in the set-up
//! frame, and connect them.
//!
//! Walls are found first, then depressions on all faces: walls and
//! depressions may share faces. When geometry can be read two ways (the
//! space between ribs as pockets, thesis figure 5.8) the wall wins: a face
//! set whose faces all belong to walls (apart from corner blends) is no
//! depression (see `depressions`). Ids are assigned here, in a deterministic
//! order, after both recognisers ran.

use glam::DVec3;
use thinplan_brep::Brep;
use thinplan_knowledge::{Knowledge, Machine};
use thinplan_plan::{Connection, StiffnessFeature, StiffnessFeatureId};

pub mod accessibility;
pub mod connect;
pub mod depressions;
pub mod mfcad;
pub mod report;
pub mod walls;

/// The result of recognition: features with stable ids and their connections.
#[derive(Debug, Clone, PartialEq)]
pub struct Recognition {
    pub features: Vec<StiffnessFeature>,
    pub connections: Vec<Connection>,
    /// Things the recognisers noticed and could not decide, for the planner.
    pub warnings: Vec<String>,
}

/// Recognises the stiffness features of `brep` with the spindle along `up`
/// (part coordinates) and connects them.
pub fn recognise(brep: &Brep, up: DVec3, k: &Knowledge, machine: &Machine) -> Recognition {
    let adjacency = thinplan_brep::edge_adjacency(brep);
    let mut warnings = Vec::new();
    let mut features = walls::find_walls(brep, &adjacency, up, &k.wall_recognition, &mut warnings);
    let depressions = depressions::find_depressions(
        brep,
        &adjacency,
        up,
        &k.depression_recognition,
        &features,
        &mut warnings,
    );
    features.extend(depressions);
    assign_ids(&mut features);
    for f in &mut features {
        f.access = accessibility::access_directions(brep, f, up, machine);
    }
    let connections = connect::connect(brep, &adjacency, up, &features, &k.wall_recognition);
    Recognition {
        features,
        connections,
        warnings,
    }
}

/// Orders features deterministically (kind, then smallest face index) and
/// numbers them from 0 in that order.
fn assign_ids(features: &mut [StiffnessFeature]) {
    for f in features.iter_mut() {
        f.faces.sort_unstable();
        f.faces.dedup();
    }
    features.sort_by(|a, b| {
        (a.kind as u8, a.faces.first().copied()).cmp(&(b.kind as u8, b.faces.first().copied()))
    });
    for (i, f) in features.iter_mut().enumerate() {
        f.id = StiffnessFeatureId(i as u32);
    }
}
