//! The `recognize --json` contract and the SVG picture.

use thinplan_brep::Brep;

use crate::Recognition;

/// `{"features": [...], "connections": [...]}` as documented in docs/CLI.md.
pub fn to_json(_r: &Recognition, _brep: &Brep) -> serde_json::Value {
    serde_json::json!({ "features": [], "connections": [] })
}
