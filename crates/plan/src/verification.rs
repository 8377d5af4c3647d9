//! Stage 9's result: the program replayed on the in-process stock and the
//! verdict a driver acts on (write the program or not, which exit code).

use serde::{Deserialize, Serialize};

use crate::model::{Operation, OperationId, Provenance};

/// What the verification found, worst first: `Unsafe` wins over
/// `Incomplete`, which wins over `Safe`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// No problem, and no material left that a tool of the set could take.
    Safe,
    /// No safety problem, but material is left (each with why).
    Incomplete,
    /// A move gouges, plunges, rubs with the shank or hits with the holder:
    /// the program must not run and is not written.
    Unsafe,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Safe => "safe",
            Verdict::Incomplete => "incomplete",
            Verdict::Unsafe => "unsafe",
        }
    }
}

/// A kind of safety problem in the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// Stock left below the part's surface.
    Gouge,
    /// A rapid move that removes material.
    RapidThroughStock,
    /// A feed move down into material steeper than the entry limit.
    PlungeIntoStock,
    /// Material cut above the flutes.
    ShankContact,
    /// Stock above the holder's face within its radius.
    HolderCollision,
    /// A cut with the spindle stopped.
    SpindleOff,
}

impl ProblemKind {
    pub fn name(self) -> &'static str {
        match self {
            ProblemKind::Gouge => "gouge",
            ProblemKind::RapidThroughStock => "rapid through stock",
            ProblemKind::PlungeIntoStock => "plunge into solid stock",
            ProblemKind::ShankContact => "shank contact",
            ProblemKind::HolderCollision => "holder collision",
            ProblemKind::SpindleOff => "cut with the spindle stopped",
        }
    }
}

/// One safety problem, with the operation whose move made it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Problem {
    pub kind: ProblemKind,
    pub operation: Option<OperationId>,
    /// Line of the program (as the verification posted it).
    pub line: Option<usize>,
    /// Where, part coordinates (x, y, and the height after the cut).
    pub at: [f64; 3],
    /// How deep (gouge below the part, depth of the plunge or of the cut
    /// column, holder penetration), mm.
    pub depth_mm: f64,
    pub volume_mm3: f64,
}

/// Why material is left.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LeftReason {
    /// A tool the program used could have taken it.
    Missed,
    /// No tool the program used reaches the part there (corners smaller
    /// than the smallest corner radius, slots narrower than the tool).
    Unreachable,
    /// No tool reaches the part there, but one could have taken some off
    /// the top.
    AboveReach,
}

impl LeftReason {
    pub fn name(self) -> &'static str {
        match self {
            LeftReason::Missed => "missed",
            LeftReason::Unreachable => "no tool reaches",
            LeftReason::AboveReach => "above what no tool reaches",
        }
    }
}

/// Material the program leaves, by reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeftMaterial {
    pub reason: LeftReason,
    pub volume_mm3: f64,
    /// The thickest column left, mm, and where (x, y).
    pub worst_mm: f64,
    pub at: Option<[f64; 2]>,
    pub patches: usize,
}

/// An operation the verification took out of the program, and why. The
/// operation itself is kept here (not in the plan's operations, which are
/// the program) so that verifying again starts from what stage 8 planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RemovedOperation {
    pub operation: OperationId,
    /// The first problem it made (its kind, line and place).
    pub problem: Problem,
    pub round: u32,
    pub removed: Operation,
}

/// How the verification planned an operation again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Replan {
    /// A feed plunge: every straight fed descent became a ramp from where
    /// it starts.
    RampedEntries,
    /// Its shank or holder met material that still stood: moved to the end
    /// of the program, when every other operation has cut.
    RunLast,
    /// A rapid met stock: its links go over the top of the stock again,
    /// as stage 7 planned them, not at stage 8's lowered heights.
    LinksOverTop,
}

/// An operation the verification planned again, with the operation as
/// stage 8 left it, so that verifying again starts from that.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplannedOperation {
    pub operation: OperationId,
    /// The problem that made it be planned again.
    pub problem: Problem,
    pub how: Replan,
    pub round: u32,
    pub planned: Operation,
}

/// Stage 9's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Verification {
    pub verdict: Verdict,
    /// Problems left in the program as it stands (empty unless unsafe).
    pub problems: Vec<Problem>,
    /// Material left, by reason (reasons with nothing left are omitted).
    pub left: Vec<LeftMaterial>,
    /// Operations removed from the order because they made a problem.
    pub removed: Vec<RemovedOperation>,
    /// Operations planned again (they stay in the program unless also in
    /// `removed`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub replanned: Vec<ReplannedOperation>,
    /// Links stage 8 lowered that the verification sent over the top (the
    /// operation before them changed), restored when it is run again.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub planned_links: std::collections::BTreeMap<OperationId, f64>,
    /// The order stage 8 gave, before any removal (restored when the
    /// verification is run again).
    pub planned_order: Vec<OperationId>,
    /// Replays made (the last one is the program as it stands).
    pub rounds: u32,
    pub cell_mm: f64,
    pub tolerance_mm: f64,
    /// The knowledge block and the thresholds used.
    pub provenance: Provenance,
}

impl Verification {
    /// Volume left for `reason`, mm³ (0 when none).
    pub fn left_mm3(&self, reason: LeftReason) -> f64 {
        self.left
            .iter()
            .filter(|l| l.reason == reason)
            .map(|l| l.volume_mm3)
            .sum()
    }
}
