//! Stage 9's thresholds (`verification.ron`): how finely the program is
//! replayed and what makes a plan incomplete or unsafe.

use serde::{Deserialize, Serialize};

/// The name of the verification file at the knowledge root.
pub const VERIFICATION_FILE: &str = "verification.ron";

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerificationKnowledge {
    /// Z-map cell size, mm.
    pub cell: f64,
    /// Gouge and cut tolerance, mm.
    pub tolerance: f64,
    /// How near a part face may pass to a cell centre and still not be
    /// judged there, and how near the tool's edge a cut may lie and still
    /// not count as a plunge or shank contact, mm: the part's tessellation
    /// error, not `tolerance`.
    pub wall_tolerance: f64,
    /// The replays' grids, each where its cells start as a fraction of a
    /// cell past the blank's corner (`[0, 1)`): the first one's leftover
    /// is reported; every grid's problems count, so a fin narrower than a
    /// cell one grid misses the next may see.
    pub grid_shifts: Vec<f64>,
    /// Missed material above which a plan is incomplete, mm³.
    pub max_missed_mm3: f64,
    /// Material no tool of the program reaches above which a plan is
    /// incomplete, mm³.
    pub max_unreachable_mm3: f64,
    /// Steepest descent into material a feed move may make, degrees.
    pub max_descent_deg: f64,
    /// Most material one steeper descent may remove before it counts as a
    /// plunge into solid stock (the tool's rim grazing a cut's edge), mm³.
    pub max_plunge_mm3: f64,
    /// Replays at most (each after removing failing operations).
    pub max_rounds: u32,
    /// Replays more, after `max_rounds`, that only remove operations whose
    /// problems remain (each confirmed by the next): a program that leaves
    /// material rather than none. Problems left after them make the plan
    /// unsafe.
    #[serde(default = "default_removal_rounds")]
    pub max_removal_rounds: u32,
    /// Post-processor id whose program is replayed.
    pub post: String,
}

fn default_removal_rounds() -> u32 {
    4
}

impl VerificationKnowledge {
    /// Values out of range, as `(field, reason)`: each bounds the replay's
    /// work or keeps a verdict meaningful.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        let mut range = |name: &'static str, v: f64, lo: f64, hi: f64| {
            if !(v.is_finite() && v >= lo && v <= hi) {
                out.push((
                    name,
                    format!("`{name}` is {v}; it must lie in [{lo}, {hi}]"),
                ));
            }
        };
        // Below 0.02 mm a 1 m part needs 2.5e9 cells.
        range("cell", self.cell, 0.02, 5.0);
        range("tolerance", self.tolerance, 0.001, 1.0);
        // Above `tolerance` a tool could cut into a wall unseen.
        range("wall_tolerance", self.wall_tolerance, 0.0, self.tolerance);
        range("max_missed_mm3", self.max_missed_mm3, 0.0, 1e12);
        range("max_unreachable_mm3", self.max_unreachable_mm3, 0.0, 1e12);
        range("max_descent_deg", self.max_descent_deg, 1.0, 90.0);
        range("max_plunge_mm3", self.max_plunge_mm3, 0.0, 1e6);
        range("max_rounds", self.max_rounds as f64, 1.0, 20.0);
        range(
            "max_removal_rounds",
            self.max_removal_rounds as f64,
            0.0,
            20.0,
        );
        if self.grid_shifts.is_empty() || self.grid_shifts.len() > 4 {
            out.push((
                "grid_shifts",
                format!(
                    "`grid_shifts` has {} grids; it needs 1 to 4 (each is a whole replay)",
                    self.grid_shifts.len()
                ),
            ));
        }
        for &g in &self.grid_shifts {
            if !(g.is_finite() && (0.0..1.0).contains(&g)) {
                out.push((
                    "grid_shifts",
                    format!("a grid shift is {g}; each must lie in [0, 1) (a fraction of a cell)"),
                ));
            }
        }
        out
    }
}
