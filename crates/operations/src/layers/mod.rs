//! The modular pattern of one machining feature: method and tool choice,
//! the tool-centre region, z-levels, rest passes, boundary passes, entries.
//!
//! A feature is planned in bands of its depth (`shank`): each band
//! (`band`) takes a method and tool (`tool_choice`), the tool-centre region
//! (`region`, following sloped faces: `slopes`), the boundary passes along
//! the product and the rest region inside them (`boundary`), the rest
//! pattern of every z-level (`rest_region`, `parallel`), the levels' and
//! bottom layer's operations (`levels`, `entries`), and the rest passes
//! with smaller tools (`rest_passes`); every operation passes the safety
//! net (`safety_net`) before it is kept.

mod band;
mod boundary;
mod entries;
mod levels;
mod parallel;
mod plan_view;
mod region;
mod rest_passes;
mod rest_region;
mod safety_net;
mod shank;
mod slopes;
mod tool_choice;

use cavalier_contours::polyline::PlineSource;
use glam::{DVec2, DVec3};
use thinplan_knowledge::{Knowledge, Machine, Material, Tool, ToolSet};
use thinplan_plan::{Adjacency, MachiningFeature, Provenance, Schedule};

use crate::geom::{adjacency_edges, pline_from_edges, Edge2};
use crate::path::LMove;

pub(crate) use shank::feature_operations;

/// What planning a feature needs: the knowledge, the set-up's tools,
/// material and machine, and the top of the stock (global height).
pub(crate) struct Env<'a> {
    pub k: &'a Knowledge,
    pub tools: &'a ToolSet,
    pub material: &'a Material,
    pub machine: &'a Machine,
    pub limits: thinplan_feeds::MachineLimits,
    pub global_top: f64,
    /// Set for stage 7's second pass: plan only the feature's orphan wall
    /// stretches, those no operation of the first pass cut (the orphan
    /// rest pass of `rest_passes`).
    pub orphans: Option<&'a crate::coverage::Coverage>,
}

impl<'a> Env<'a> {
    /// The same environment with another tool set.
    pub fn clone_with_tools<'b>(&self, tools: &'b ToolSet) -> Env<'b>
    where
        'a: 'b,
    {
        Env {
            k: self.k,
            tools,
            material: self.material,
            machine: self.machine,
            limits: self.limits.clone(),
            global_top: self.global_top,
            orphans: self.orphans,
        }
    }
}

/// An operation in the feature's local frame.
pub(crate) struct LocalOp {
    pub method: String,
    pub tool: String,
    pub rpm: f64,
    pub feed_rough: f64,
    pub feed_finish: f64,
    pub feed_boundary: f64,
    pub feed_link: f64,
    pub start: DVec3,
    pub moves: Vec<LMove>,
    /// When stage 8 runs it (rest passes after their feature or at the end).
    pub schedule: Schedule,
    pub provenance: Provenance,
}

/// A feature's operations, with what it says about them and the material
/// it leaves.
#[derive(Default)]
pub(crate) struct Made {
    pub ops: Vec<LocalOp>,
    pub warnings: Vec<String>,
    /// Material of this feature no tool of the tool set can reach (product
    /// corners tighter than the smallest tool), with the reason and an
    /// estimate of its volume (mm³).
    pub unreachable: Vec<(String, f64)>,
    /// Where the tool centre may go (sampled polygons of the tool-centre region).
    pub reach: Vec<Vec<DVec2>>,
}

impl Made {
    /// Another piece's operations, warnings and material added to these.
    pub(crate) fn absorb(&mut self, other: Made) {
        self.ops.extend(other.ops);
        self.warnings.extend(other.warnings);
        self.unreachable.extend(other.unreachable);
        self.reach.extend(other.reach);
    }
}

/// How a refusal for lack of any tool that fits starts (stage 7 reports it
/// as unreachable material, rule `operations.unreachable`).
pub(crate) const NO_TOOL_FITS: &str = "unreachable: no tool of the set-up's tool set fits";
/// The start of a refusal for material below every fitting tool's reach.
const NO_TOOL_REACHES: &str = "unreachable: no tool of the set-up's tool set reaches";

/// Whether a refusal leaves material no tool of the set can cut (not a
/// planning failure).
pub(crate) fn is_unreachable(reason: &str) -> bool {
    reason.starts_with(NO_TOOL_FITS) || reason.starts_with(NO_TOOL_REACHES)
}

/// How far below the top of the stock `t` may cut: its stickout less the
/// holder clearance, so its holder's face stays above the highest stock
/// it could meet (the top of the stock bounds it everywhere).
fn tool_reach(env: &Env, t: &Tool) -> f64 {
    t.stickout - env.k.methods.holder_clearance
}

/// The depth of local height `z` of `f` below the top of the stock.
fn depth_below_top(env: &Env, f: &MachiningFeature, z: f64) -> f64 {
    let up_off = f
        .shape
        .frame
        .origin
        .dot(f.shape.frame.z.normalize_or_zero());
    env.global_top - up_off - z
}

/// A feature's loops (outer first, then the holes), each edge with its
/// adjacency (`adjacency_edges`).
type Loops = Vec<(Vec<Edge2>, Vec<Adjacency>)>;

/// Sampling step (mm) for containment checks and polygons.
const STEP: f64 = 0.25;
/// Distance slack for "on the product offset" (mm).
const EPS: f64 = 1e-6;

/// The feature's region area (mm²): outer loop less holes.
pub(crate) fn region_area(f: &MachiningFeature) -> f64 {
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let mut a = 0.0;
    for (k, (es, _)) in edges.iter().enumerate() {
        if es.len() < 2 {
            continue;
        }
        let s = pline_from_edges(es, true).area().abs();
        a += if k == 0 { s } else { -s };
    }
    a.max(0.0)
}
