//! Pocket profile files: one pocket (outer loop, islands) and its tool, as JSON or RON.
//!
//! ```json
//! {
//!   "name": "pentagon",                  // optional (default: "pocket")
//!   "tool_diameter": 12.0,               // mm
//!   "stepover": 4.8,                     // optional, default 0.4 × tool
//!   "finish_stepover": 1.2,              // optional, default 0.1 × tool
//!   "field": "poisson",                  // optional: "poisson" | "eigen"
//!   "outer": [[x, y, bulge], ...],       // closed loop, bulge = tan(sweep/4) of the arc to the
//!                                         // next vertex (0 or omitted: a line: [x, y])
//!   "islands": [[[x, y, bulge], ...]]    // optional
//! }
//! ```
//! The same structure in RON (`.ron` files): `(tool_diameter: 12.0, outer: [(0.0, 0.0, 0.0), …])`
//! with tuples for vertices.

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use serde::Deserialize;

use crate::{Field, Pocket, PocketParams};

/// A vertex: `[x, y]` (line to the next vertex) or `[x, y, bulge]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Vertex {
    Xy(f64, f64),
    Xyb(f64, f64, f64),
}

impl Vertex {
    fn xyb(&self) -> (f64, f64, f64) {
        match *self {
            Vertex::Xy(x, y) => (x, y, 0.0),
            Vertex::Xyb(x, y, b) => (x, y, b),
        }
    }
}

/// The file contents.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PocketProfile {
    #[serde(default)]
    pub name: Option<String>,
    pub tool_diameter: f64,
    #[serde(default)]
    pub stepover: Option<f64>,
    #[serde(default)]
    pub finish_stepover: Option<f64>,
    #[serde(default)]
    pub field: Option<Field>,
    pub outer: Vec<Vertex>,
    #[serde(default)]
    pub islands: Vec<Vec<Vertex>>,
}

fn to_pline(vs: &[Vertex], what: &str) -> Result<Polyline<f64>, String> {
    if vs.len() < 2 {
        return Err(format!(
            "{what}: needs at least 2 vertices, has {}",
            vs.len()
        ));
    }
    let mut pl = Polyline::new_closed();
    for (i, v) in vs.iter().enumerate() {
        let (x, y, b) = v.xyb();
        if !(x.is_finite() && y.is_finite() && b.is_finite()) || b.abs() > 1e3 {
            return Err(format!(
                "{what}: vertex {i} is not finite (or bulge out of range)"
            ));
        }
        pl.add(x, y, b);
    }
    // drop a repeated closing vertex
    let n = pl.vertex_count();
    if n > 2 {
        let (a, z) = (pl.at(0), pl.at(n - 1));
        if (a.x - z.x).abs() < 1e-12 && (a.y - z.y).abs() < 1e-12 {
            pl.remove_last();
        }
    }
    if pl.scan_for_self_intersect() {
        return Err(format!("{what}: the profile intersects itself"));
    }
    if pl.area().abs() < 1e-12 {
        return Err(format!("{what}: zero area"));
    }
    Ok(pl)
}

impl PocketProfile {
    /// Parse JSON, or RON when `ron` is true.
    pub fn parse(text: &str, ron: bool) -> Result<PocketProfile, String> {
        if ron {
            ron::from_str(text).map_err(|e| format!("bad RON: {e}"))
        } else {
            serde_json::from_str(text).map_err(|e| format!("bad JSON: {e}"))
        }
    }

    /// The pocket and its parameters, validated (finite coordinates, no self-intersection,
    /// parameters in range).
    pub fn build(&self) -> Result<(Pocket, PocketParams), String> {
        let outer = to_pline(&self.outer, "outer")?;
        let islands = self
            .islands
            .iter()
            .enumerate()
            .map(|(i, vs)| to_pline(vs, &format!("island {i}")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut params = PocketParams::for_tool(self.tool_diameter);
        if let Some(s) = self.stepover {
            params.stepover = s;
        }
        if let Some(f) = self.finish_stepover {
            params.finish_stepover = f;
        } else {
            params.finish_stepover = params.finish_stepover.min(params.stepover);
        }
        if let Some(f) = self.field {
            params.field = f;
        }
        params.validate().map_err(|e| e.to_string())?;
        let name = self.name.clone().unwrap_or_else(|| "pocket".into());
        Ok((Pocket::with_islands(name, outer, islands), params))
    }
}
