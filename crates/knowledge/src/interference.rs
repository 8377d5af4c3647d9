//! Interference knowledge (thesis §5.4.2, §6.2.3), read from
//! `knowledge/interference.ron` by stage 6 (`thinplan-resolve`): which of
//! two machining features that claim the same volume keeps it, who owns
//! the remaining material, and how finely non-prismatic parts are sliced.

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range};

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
    /// Thinner slabs where sloped faces are shallow (absent: every sloped
    /// slab is `sloped_slab_thickness`).
    #[serde(default)]
    pub shallow_slabs: Option<ShallowSlabs>,
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
    /// Remaining material too narrow for the set-up's smallest tool
    /// (nothing of it is left inset by the tool's radius) is cut with the
    /// piece it borders longest in the same slab among the features these
    /// select, instead of becoming a feature no tool enters on its own
    /// (the strip a web's layers leave beside its floor fillets). Empty:
    /// narrow remaining material stays a feature of its own.
    pub narrow_remaining_joins: Vec<FeatureSelector>,
}

/// Slab thickness by the slope of the faces a slab crosses: a slab ends
/// where a tool's contacts on the face would lie `along_face` apart, so at
/// most `along_face · sin α` thick on a face at α from horizontal, and
/// never thinner than `min_thickness`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShallowSlabs {
    pub along_face: f64,
    pub min_thickness: f64,
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
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `interference.ron`. Slabs at
    /// least 0.01 mm thick keep a 1 m high part under 10⁵ slabs.
    pub fn checks(&self, c: &mut Checks) {
        let mut seen = std::collections::BTreeSet::new();
        for (i, r) in self.keep_order.iter().enumerate() {
            if !seen.insert(r.id.as_str()) {
                c.push(
                    at!["keep_order", i, "id"],
                    format!("duplicate keep_order rule id `{}`", r.id),
                );
            }
        }
        c.range(
            at!["sloped_slab_thickness"],
            "",
            "`sloped_slab_thickness`",
            self.sloped_slab_thickness,
            Range::closed(0.01, 1000.0),
            " mm",
        );
        if let Some(sh) = &self.shallow_slabs {
            c.range(
                at!["shallow_slabs", "along_face"],
                "",
                "`shallow_slabs.along_face`",
                sh.along_face,
                Range::above(0.0, 1000.0),
                " mm",
            );
            let hi = if self.sloped_slab_thickness.is_finite() {
                self.sloped_slab_thickness.max(0.01)
            } else {
                0.01
            };
            c.range(
                at!["shallow_slabs", "min_thickness"],
                "",
                "`shallow_slabs.min_thickness`",
                sh.min_thickness,
                Range::closed(0.01, hi),
                " mm (at most `sloped_slab_thickness`)",
            );
        }
        c.range(
            at!["sliver_area"],
            "",
            "`sliver_area`",
            self.sliver_area,
            Range::closed(0.0, 1e6),
            " mm²",
        );
        if self.remaining_owners.is_empty() {
            c.push(
                at!["remaining_owners"],
                "`remaining_owners` is empty: remaining material would have no owner".into(),
            );
        }
    }
}
