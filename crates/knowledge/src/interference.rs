//! Interference knowledge (thesis §5.4.2, §6.2.3), read from
//! `knowledge/interference.ron` by stage 6 (`thinplan-resolve`): which of
//! two machining features that claim the same volume keeps it, who owns
//! the remaining material, and how finely non-prismatic parts are sliced.

use serde::{Deserialize, Serialize};

/// The name of the interference file at the knowledge root.
pub const INTERFERENCE_FILE: &str = "interference.ron";

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterferenceKnowledge {
    /// Who keeps a volume claimed by several machining features: a feature
    /// takes the rank of the first rule that selects it; a lower rank keeps
    /// the overlap (the feature that needs most care). Features no rule
    /// selects come last.
    pub keep_order: Vec<KeepRule>,
    /// Between two features of the same rank.
    pub tie_break: TieBreak,
    /// Who owns material that no machining feature claims, tried in order.
    pub remaining_owners: Vec<RemainingOwner>,
    /// Largest slab thickness (mm) where the part has faces that are neither
    /// vertical nor horizontal (its section changes within a slab there).
    pub sloped_slab_thickness: f64,
    /// Pieces smaller than this (mm² in plan view) are dropped as slivers
    /// (their volume is reported).
    pub sliver_area: f64,
    /// Sequence a feature before every feature it covers from the
    /// tool-access side (it blocks their tool access).
    pub accessibility: bool,
    /// Sequence a feature before every feature it stands beside, within a
    /// tool's reach across the other's non-product edges, higher than the
    /// tool's flute length above the other's bottom (the shank would rub
    /// it).
    pub shank_access: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeepRule {
    pub id: String,
    pub select: FeatureSelector,
    #[serde(default)]
    pub note: String,
}

/// Which machining features a rule speaks of.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FeatureSelector {
    /// Made by the strategy block `block` (its id in `strategies.ron`);
    /// with `large`, only the large (`Some(true)`) or small (`Some(false)`)
    /// step features.
    Block { block: String, large: Option<bool> },
    /// Every feature.
    Any,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TieBreak {
    /// The feature owned by the thinner wall keeps the overlap.
    ThinnerOwner,
    /// The feature made first (lower id) keeps it.
    FirstMade,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RemainingOwner {
    /// A depression (hole, cut-out, pocket …) whose shape holds the piece.
    Depression,
    /// The web under the piece (its outline holds the piece in plan view).
    Web,
    /// The nearest wall.
    NearestWall,
}

impl InterferenceKnowledge {
    /// Problems a parser cannot see (block ids are checked against the
    /// strategies by the knowledge loader).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        for r in &self.keep_order {
            if !seen.insert(r.id.as_str()) {
                out.push(format!("duplicate keep_order rule id `{}`", r.id));
            }
        }
        if !(self.sloped_slab_thickness.is_finite() && self.sloped_slab_thickness > 0.0) {
            out.push(format!(
                "`sloped_slab_thickness` must be a positive number, not {}",
                self.sloped_slab_thickness
            ));
        }
        if !(self.sliver_area.is_finite() && self.sliver_area >= 0.0) {
            out.push(format!(
                "`sliver_area` must be zero or positive, not {}",
                self.sliver_area
            ));
        }
        if self.remaining_owners.is_empty() {
            out.push("`remaining_owners` is empty: remaining material would have no owner".into());
        }
        out
    }
}
