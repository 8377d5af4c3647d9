//! Ground-truth stiffness-feature labels, for scoring recognition.

use serde::{Deserialize, Serialize};

/// Expected stiffness features and connections of one part.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Labels {
    /// The part name these labels belong to (may be empty inside a part file).
    #[serde(default)]
    pub part: String,
    pub features: Vec<FeatureLabel>,
    #[serde(default)]
    pub connections: Vec<ConnectionLabel>,
}

/// One expected stiffness feature. Lengths in mm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Feature")]
pub struct FeatureLabel {
    pub id: String,
    pub kind: FeatureKind,
    /// Walls only.
    #[serde(default)]
    pub role: Option<WallRole>,
    #[serde(default)]
    pub thickness: Option<f64>,
    #[serde(default)]
    pub height: Option<f64>,
    #[serde(default)]
    pub length: Option<f64>,
    /// Walls: the wall normal (thickness direction); holes and slots: the
    /// through direction; fillets: the fillet axis. A unit vector.
    #[serde(default)]
    pub axis: Option<(f64, f64, f64)>,
    /// Round holes only.
    #[serde(default)]
    pub diameter: Option<f64>,
    /// Names of B-rep faces that belong to the feature (e.g. `rib1.top`).
    #[serde(default)]
    pub faces: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureKind {
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallRole {
    Web,
    Rib,
    Flange,
}

/// `leaf` stands on / lies in `base` (`base_leaf`), or the two cross.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Connection")]
pub struct ConnectionLabel {
    pub base: String,
    pub leaf: String,
    pub kind: ConnectionKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConnectionKind {
    BaseLeaf,
    Crossing,
}

impl Labels {
    /// Checks ids are unique, connections refer to features, axes are unit.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = std::collections::BTreeSet::new();
        for f in &self.features {
            if f.id.is_empty() {
                return Err("a feature has an empty id".into());
            }
            if !seen.insert(f.id.as_str()) {
                return Err(format!("duplicate feature id `{}`", f.id));
            }
            if f.role.is_some() && f.kind != FeatureKind::Wall {
                return Err(format!("feature `{}`: only walls have a role", f.id));
            }
            if let Some((x, y, z)) = f.axis {
                let l = (x * x + y * y + z * z).sqrt();
                if (l - 1.0).abs() > 1e-6 {
                    return Err(format!("feature `{}`: axis is not a unit vector", f.id));
                }
            }
            for (what, v) in [
                ("thickness", f.thickness),
                ("height", f.height),
                ("length", f.length),
                ("diameter", f.diameter),
            ] {
                if let Some(v) = v {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(format!("feature `{}`: {what} must be > 0", f.id));
                    }
                }
            }
        }
        for c in &self.connections {
            for id in [&c.base, &c.leaf] {
                if !seen.contains(id.as_str()) {
                    return Err(format!("connection refers to unknown feature `{id}`"));
                }
            }
            if c.base == c.leaf {
                return Err(format!("connection of `{}` with itself", c.base));
            }
        }
        Ok(())
    }
}
