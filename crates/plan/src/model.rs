//! The plan data model: one serialisable value that every stage reads and extends.
//!
//! Ids are small integers assigned in a deterministic order by the stage that
//! creates the entity; collections are `Vec`s in id order or `BTreeMap`s, so
//! the serialised plan is byte-for-byte reproducible.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The schema version this build writes. Older versions are migrated on load
/// (see [`crate::io::migrate`]).
pub const SCHEMA_VERSION: u32 = 3;

macro_rules! id_type {
    ($(#[$m:meta])* $name:ident, $prefix:literal) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }
    };
}

id_type!(
    /// A stiffness feature (wall, hole, cut-out, chamfer …).
    StiffnessFeatureId,
    "SF"
);
id_type!(
    /// A machining feature (a removal volume owned by a stiffness feature).
    MachiningFeatureId,
    "MF"
);
id_type!(
    /// An operation (a tool path with its tool and conditions).
    OperationId,
    "OP"
);

/// The whole plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    pub schema_version: u32,
    pub part: PartRef,
    pub setup: Setup,
    /// Which stages have run, in pipeline order; a later stage's output is
    /// valid only if every earlier stage is listed.
    pub stages_done: Vec<Stage>,
    pub stiffness_features: Vec<StiffnessFeature>,
    pub connections: Vec<Connection>,
    pub stiffness_constraints: Vec<Constraint<StiffnessFeatureId>>,
    pub machining_features: Vec<MachiningFeature>,
    pub machining_constraints: Vec<Constraint<MachiningFeatureId>>,
    pub operations: Vec<Operation>,
    /// Final operation order (ids into `operations`).
    pub operation_order: Vec<OperationId>,
    /// Decisions that were considered and refused (e.g. a sequencing rule
    /// that would have created a cycle), so a planner can ask why not.
    pub refusals: Vec<Refusal>,
    /// Free-form metadata (knowledge version, tool versions …), ordered.
    pub notes: BTreeMap<String, String>,
    /// Stage 9: the program replayed on the in-process stock, the verdict.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<crate::verification::Verification>,
}

/// The pipeline stages, in order (DESIGN.md, "The pipeline").
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    Import,
    Setup,
    Recognise,
    Connect,
    Sequence,
    Determine,
    Resolve,
    Operations,
    Order,
    Verify,
    Output,
}

impl Stage {
    pub const ALL: [Stage; 11] = [
        Stage::Import,
        Stage::Setup,
        Stage::Recognise,
        Stage::Connect,
        Stage::Sequence,
        Stage::Determine,
        Stage::Resolve,
        Stage::Operations,
        Stage::Order,
        Stage::Verify,
        Stage::Output,
    ];
}

/// Where the part came from, with a content hash so a plan can tell when
/// its part file has changed underneath it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartRef {
    /// Path as given by the user (or `builtin:NAME` for a bundled sample).
    pub source: String,
    pub format: PartFormat,
    /// SHA-256 of the file bytes, lower-case hex.
    pub sha256: String,
    /// Length unit declared by the file; geometry is always in mm.
    pub declared_units: String,
    pub summary: PartSummary,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartFormat {
    Step,
    Native,
}

/// Facts about the imported B-rep, recorded so a plan can be checked
/// against its part without re-reading it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSummary {
    pub solids: usize,
    pub faces: usize,
    /// Axis-aligned extent in mm.
    pub bbox: [f64; 3],
    /// mm³
    pub volume: f64,
}

/// The part's placement on the machine and the resources used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Setup {
    /// The spindle axis (tool pointing down it) in part coordinates:
    /// what is "up" for this set-up.
    pub up: DVec3,
    pub machine: String,
    pub tool_set: String,
    pub material: String,
    pub provenance: Provenance,
}

/// Why an entity exists: the rule or knowledge block that made it, with
/// the values it used; `User` for manual edits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    pub source: ProvenanceSource,
    /// Rule, block or recogniser id, e.g. `sequencing.flange_before_wall`.
    pub rule: String,
    /// The values the decision used, by name, ordered.
    pub values: BTreeMap<String, f64>,
    pub note: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProvenanceSource {
    Default,
    Import,
    Recogniser,
    Knowledge,
    User,
}

impl Provenance {
    pub fn new(source: ProvenanceSource, rule: impl Into<String>) -> Self {
        Provenance {
            source,
            rule: rule.into(),
            values: BTreeMap::new(),
            note: String::new(),
        }
    }

    pub fn with_value(mut self, name: impl Into<String>, value: f64) -> Self {
        self.values.insert(name.into(), value);
        self
    }
}

/// A 2D segment of a profile: straight, or a true arc given by its bulge
/// (tan of a quarter of the swept angle; positive = counter-clockwise),
/// the convention of cavalier_contours and DXF.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileVertex {
    pub x: f64,
    pub y: f64,
    /// 0 for a straight segment to the next vertex.
    pub bulge: f64,
}

/// A closed loop of profile vertices (implicitly closed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileLoop {
    pub vertices: Vec<ProfileVertex>,
}

impl ProfileLoop {
    /// A loop of straight edges through `points`, in order.
    pub fn polygon(points: &[[f64; 2]]) -> Self {
        ProfileLoop {
            vertices: points
                .iter()
                .map(|p| ProfileVertex {
                    x: p[0],
                    y: p[1],
                    bulge: 0.0,
                })
                .collect(),
        }
    }
}

/// A planar region: one outer loop (counter-clockwise) and holes (clockwise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    pub outer: ProfileLoop,
    pub holes: Vec<ProfileLoop>,
}

/// A frame given by origin, x direction and z direction (the sweep / tool-access
/// axis); y = z × x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrismFrame {
    pub origin: DVec3,
    pub x: DVec3,
    pub z: DVec3,
}

/// The one shape representation of features (DESIGN.md, "Representation"):
/// a planar region in a frame, swept along the frame's z over `[z_min, z_max]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prism {
    pub frame: PrismFrame,
    pub region: Region,
    pub z_min: f64,
    pub z_max: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StiffnessKind {
    Wall,
    Hole,
    Cutout,
    Slot,
    Notch,
    Pocket,
    Step,
    Chamfer,
    Fillet,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallRole {
    Web,
    Rib,
    Flange,
}

/// A stiffness feature: an element of the part's stiffness (wall) or
/// something that weakens or shapes it (depression, detail).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StiffnessFeature {
    pub id: StiffnessFeatureId,
    pub kind: StiffnessKind,
    pub role: Option<WallRole>,
    /// Part faces that make up the feature.
    pub faces: Vec<usize>,
    /// Wall normal or depression axis, in part coordinates.
    pub axis: DVec3,
    pub thickness: Option<f64>,
    pub height: f64,
    pub length: f64,
    pub diameter: Option<f64>,
    pub shape: Option<Prism>,
    /// Tool-access directions the machine can reach for this feature.
    pub access: Vec<DVec3>,
    pub provenance: Provenance,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConnectionKind {
    BaseLeaf,
    Crossing,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Connection {
    pub base: StiffnessFeatureId,
    pub leaf: StiffnessFeatureId,
    pub kind: ConnectionKind,
    pub provenance: Provenance,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintKind {
    /// `first` is machined before `second`.
    Before,
    /// `first` and `second` are machined together (interleaved).
    Simultaneous,
}

/// A sequence constraint between two features of the same level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constraint<Id> {
    pub first: Id,
    pub second: Id,
    pub kind: ConstraintKind,
    pub priority: i32,
    pub provenance: Provenance,
}

/// What a face of a machining feature borders (DESIGN.md stage 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Adjacency {
    Product,
    Open,
    Feature,
}

/// A removal volume owned by a stiffness feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachiningFeature {
    pub id: MachiningFeatureId,
    pub owner: StiffnessFeatureId,
    pub shape: Prism,
    /// Adjacency per profile edge of the outer loop (edge i runs from
    /// vertex i to vertex i + 1).
    pub side_adjacency: Vec<Adjacency>,
    /// Adjacency per edge of each hole (island), in `shape.region.holes` order.
    pub hole_adjacency: Vec<Vec<Adjacency>>,
    pub bottom_adjacency: Adjacency,
    /// What made the feature (stage 5); later stages select on it.
    #[serde(default)]
    pub origin: FeatureOrigin,
    /// The part covers the feature from the tool side (stage 6): it cannot
    /// be machined in this set-up.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub access_blocked: bool,
    /// Where product faces beside the feature slope (sloped slabs, stage
    /// 6): how far each product edge's face lies beyond it at the slab's
    /// bottom and top. Absent where every product face is vertical.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slopes: Option<EdgeSlopes>,
    pub provenance: Provenance,
}

/// What made a machining feature: the knowledge rule and the feature's role
/// in its step. Stages select on these typed fields; the provenance beside
/// them explains the decision and is never read back.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureOrigin {
    /// The knowledge rule that made it (`strategies.<block>`, an influence
    /// block); empty for a feature made by hand.
    pub rule: String,
    /// The large (`true`) or small (`false`) feature of a step (thesis
    /// §4.1.2); `None` for a feature that is not one side of a step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub large: Option<bool>,
}

/// When stage 8 runs an operation, relative to the order of the features.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Schedule {
    /// With its feature, in the features' order.
    #[default]
    WithFeature,
    /// A rest pass: after its feature's other operations, grouped by tool
    /// with the other rest passes, but before any operation whose feature
    /// lies below it (that tool's shank would pass up through what the rest
    /// pass has still to cut).
    AfterFeature,
    /// At the end of the program: a pass planned as if every other feature
    /// were gone (wall stretches no operation of their own features reached,
    /// a wall rest pass with the feature's own tool).
    AtEnd {
        /// Stage 7 drops the pass when other operations already cut every
        /// point of its boundary to within this much (mm); `None`: never.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        covered_within_mm: Option<f64>,
    },
}

impl Schedule {
    pub fn is_with_feature(&self) -> bool {
        *self == Schedule::WithFeature
    }
}

/// The product faces beside a machining feature's edges, sampled at
/// `heights` of the set-up frame (ascending; the region's edges are the
/// section at one of them, where every offset is 0): how far the face lies
/// beyond each edge at each height, mm (away from the region: positive
/// where the face recedes, negative where the product reaches into the
/// region). Linear in between; taken as vertical below the first height
/// and above the last. Non-product edges carry no offsets (empty).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeSlopes {
    pub heights: Vec<f64>,
    /// Per edge of the outer loop: an offset per height, or none.
    pub side: Vec<Vec<f64>>,
    /// Per edge of each hole, in `shape.region.holes` order.
    pub holes: Vec<Vec<Vec<f64>>>,
}

impl EdgeSlopes {
    /// Why the samples cannot be used (a hand-edited plan file): heights
    /// not finite and strictly ascending, or an edge's offsets not one
    /// finite number per height. `None` when they can.
    pub fn unusable(&self) -> Option<String> {
        let h = &self.heights;
        if h.is_empty() || h.iter().any(|z| !z.is_finite()) || h.windows(2).any(|w| w[0] >= w[1]) {
            return Some(format!(
                "heights {h:?} are not finite and strictly ascending"
            ));
        }
        let all = self.side.iter().chain(self.holes.iter().flatten());
        for (i, o) in all.enumerate() {
            if !o.is_empty() && (o.len() != h.len() || o.iter().any(|v| !v.is_finite())) {
                return Some(format!(
                    "edge {i}'s offsets {o:?} are not one finite number per height"
                ));
            }
        }
        None
    }

    /// How far the face beyond an edge with `offsets` lies beyond it at
    /// height `z` (mm; see the type). 0 for an edge with none.
    pub fn beyond(&self, offsets: &[f64], z: f64) -> f64 {
        let h = &self.heights;
        if offsets.len() != h.len() || h.is_empty() {
            return 0.0;
        }
        if z <= h[0] {
            return offsets[0];
        }
        for i in 1..h.len() {
            if z <= h[i] {
                let t = (z - h[i - 1]) / (h[i] - h[i - 1]).max(1e-12);
                return offsets[i - 1] + (offsets[i] - offsets[i - 1]) * t;
            }
        }
        offsets[h.len() - 1]
    }
}

impl MachiningFeature {
    /// The plan-view box [x0, y0, x1, y1] of the outer loop's vertices
    /// (arcs as chords).
    pub fn plan_box(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for v in &self.shape.region.outer.vertices {
            b[0] = b[0].min(v.x);
            b[1] = b[1].min(v.y);
            b[2] = b[2].max(v.x);
            b[3] = b[3].max(v.y);
        }
        b
    }

    /// Whether two features share one frame (their plan-view coordinates
    /// compare).
    pub fn same_frame(&self, other: &MachiningFeature) -> bool {
        let (fa, fb) = (&self.shape.frame, &other.shape.frame);
        (fa.origin - fb.origin).length() < 1e-9
            && (fa.x - fb.x).length() < 1e-9
            && (fa.z - fb.z).length() < 1e-9
    }

    /// Whether `g` stands within `margin` of this feature in plan view (same
    /// frame, boxes compared) and higher than `rise` above its bottom: the
    /// shank of a tool with flutes `rise` long cutting here may meet it.
    pub fn shank_neighbour(&self, g: &MachiningFeature, margin: f64, rise: f64) -> bool {
        if !self.same_frame(g) || g.shape.z_max <= self.shape.z_min + rise {
            return false;
        }
        let (a, b) = (self.plan_box(), g.plan_box());
        b[0] <= a[2] + margin
            && a[0] <= b[2] + margin
            && b[1] <= a[3] + margin
            && a[1] <= b[3] + margin
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region3 {
    Boundary,
    FullCut,
    Rest,
    Rapid,
    Link,
}

/// One move of a tool path: straight or a circular arc about `centre`
/// (in the plane normal to `axis`), with its feed in mm/min (0 for rapids).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathMove {
    pub to: DVec3,
    pub arc: Option<ArcMove>,
    pub feed: f64,
    pub region: Region3,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArcMove {
    pub centre: DVec3,
    pub axis: DVec3,
    pub clockwise: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Operation {
    pub id: OperationId,
    pub feature: MachiningFeatureId,
    pub method: String,
    pub tool: String,
    /// Tool axis (pointing from tip to spindle) in part coordinates.
    pub tool_axis: DVec3,
    pub spindle_rpm: f64,
    pub start: DVec3,
    pub moves: Vec<PathMove>,
    /// When stage 8 runs it relative to the features' order.
    #[serde(default, skip_serializing_if = "Schedule::is_with_feature")]
    pub schedule: Schedule,
    pub provenance: Provenance,
    /// Where stage 8 planned the link from the previous operation (same
    /// tool) on the in-process stock: the height along up (part
    /// coordinates) of the straight rapid from that operation's end to
    /// `start`, both at this height. `None`: the post links over its
    /// clearance height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link_z: Option<f64>,
}

/// A decision the planner considered and did not take.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Refusal {
    pub stage: Stage,
    pub rule: String,
    pub reason: String,
    pub provenance: Provenance,
}

impl Plan {
    /// A new plan for an imported part with a default set-up; nothing else run.
    pub fn new(part: PartRef, setup: Setup) -> Self {
        Plan {
            schema_version: SCHEMA_VERSION,
            part,
            setup,
            stages_done: vec![Stage::Import, Stage::Setup],
            stiffness_features: Vec::new(),
            connections: Vec::new(),
            stiffness_constraints: Vec::new(),
            machining_features: Vec::new(),
            machining_constraints: Vec::new(),
            operations: Vec::new(),
            operation_order: Vec::new(),
            refusals: Vec::new(),
            notes: BTreeMap::new(),
            verification: None,
        }
    }

    /// Drops the results of `stage` and every stage after it, so that an
    /// edit upstream never leaves stale downstream results behind.
    pub fn invalidate_from(&mut self, stage: Stage) {
        self.stages_done.retain(|s| *s < stage);
        if stage <= Stage::Recognise {
            self.stiffness_features.clear();
        }
        if stage <= Stage::Connect {
            self.connections.clear();
        }
        if stage <= Stage::Sequence {
            self.stiffness_constraints.clear();
        }
        if stage <= Stage::Determine {
            self.machining_features.clear();
            self.machining_constraints.clear();
        }
        if stage <= Stage::Operations {
            self.operations.clear();
        }
        if stage <= Stage::Verify {
            // Operations the verification removed come back: they are
            // judged again with the program they belong to.
            if let Some(v) = self.verification.take() {
                if stage == Stage::Verify {
                    self.operation_order = v.planned_order;
                    self.operations
                        .extend(v.removed.into_iter().map(|r| r.removed));
                    // Last first: the first replan of an operation holds
                    // it as stage 8 left it.
                    for r in v.replanned.into_iter().rev() {
                        if let Some(o) = self.operations.iter_mut().find(|o| o.id == r.operation) {
                            *o = r.planned;
                        }
                    }
                    // Last: an operation kept or replanned after its link
                    // was sent over the top holds it without the link.
                    for (id, z) in v.planned_links {
                        if let Some(o) = self.operations.iter_mut().find(|o| o.id == id) {
                            o.link_z = Some(z);
                        }
                    }
                    self.operations.sort_by_key(|o| o.id);
                }
            }
        }
        if stage <= Stage::Order {
            self.operation_order.clear();
        }
        self.refusals.retain(|r| r.stage < stage);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sloped_face_is_linear_between_samples_and_vertical_beyond() {
        let s = EdgeSlopes {
            heights: vec![1.0, 1.5, 2.0, 3.0],
            side: Vec::new(),
            holes: Vec::new(),
        };
        let o = [-0.5, 0.0, 0.5, 2.5];
        let cases = [
            (0.0, -0.5),
            (1.0, -0.5),
            (1.25, -0.25),
            (1.5, 0.0),
            (1.75, 0.25),
            (2.5, 1.5),
            (3.0, 2.5),
            (9.0, 2.5),
        ];
        for (z, want) in cases {
            assert!((s.beyond(&o, z) - want).abs() < 1e-12, "z {z}");
        }
        // An edge without offsets (not product, or a vertical face).
        assert_eq!(s.beyond(&[], 1.2), 0.0);
        assert_eq!(s.unusable(), None);
    }

    #[test]
    fn hand_edited_samples_are_refused_with_the_reason() {
        let ok = EdgeSlopes {
            heights: vec![1.0, 2.0],
            side: vec![vec![0.0, 0.5], Vec::new()],
            holes: vec![vec![vec![-0.5, 0.0]]],
        };
        assert_eq!(ok.unusable(), None);
        let mut bad = ok.clone();
        bad.heights = vec![2.0, 1.0];
        assert!(bad.unusable().unwrap().contains("ascending"));
        let mut bad = ok.clone();
        bad.heights = vec![1.0, f64::NAN];
        assert!(bad.unusable().is_some());
        let mut bad = ok.clone();
        bad.side[0] = vec![0.0];
        assert!(bad.unusable().unwrap().contains("edge 0"));
        let mut bad = ok;
        bad.holes[0][0][1] = f64::INFINITY;
        assert!(bad.unusable().unwrap().contains("edge 2"));
    }
}
