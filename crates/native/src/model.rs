//! The RON part format (serde types). See the crate README for an example.

use serde::{Deserialize, Serialize};

use crate::labels::Labels;

/// A 2D point or vector in a prism's profile plane, `(x, y)` in mm.
pub type P2 = (f64, f64);
/// A 3D point or vector, `(x, y, z)` in mm.
pub type P3 = (f64, f64, f64);

/// A part: a union of prisms that touch but never overlap.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Part")]
pub struct PartSpec {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub prisms: Vec<PrismSpec>,
    /// Ground-truth stiffness features (may also live in `NAME.labels.ron`).
    #[serde(default)]
    pub labels: Option<Labels>,
}

/// A 2D profile in a frame, extruded along the frame normal over `extent`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Prism")]
pub struct PrismSpec {
    /// Unique id; face names start with it (`rib1.top`, `web.e2` …).
    pub id: String,
    #[serde(default)]
    pub frame: FrameSpec,
    /// `(from, to)` along the normal `x_dir × y_dir`, measured from the origin.
    pub extent: (f64, f64),
    pub profile: Profile,
    /// Names of the caps at `extent.0` and `extent.1`; default `("bottom", "top")`.
    #[serde(default)]
    pub cap_names: Option<(String, String)>,
}

/// Where the profile plane lies: profile `(u, v)` maps to
/// `origin + u·x_dir + v·y_dir`; the extrusion direction is `x_dir × y_dir`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Frame")]
pub struct FrameSpec {
    #[serde(default = "zero3")]
    pub origin: P3,
    #[serde(default = "unit_x")]
    pub x_dir: P3,
    #[serde(default = "unit_y")]
    pub y_dir: P3,
}

impl Default for FrameSpec {
    fn default() -> Self {
        FrameSpec {
            origin: zero3(),
            x_dir: unit_x(),
            y_dir: unit_y(),
        }
    }
}

fn zero3() -> P3 {
    (0.0, 0.0, 0.0)
}
fn unit_x() -> P3 {
    (1.0, 0.0, 0.0)
}
fn unit_y() -> P3 {
    (0.0, 1.0, 0.0)
}

/// An outer contour with holes. Orientation is free: outer loops are made
/// counter-clockwise and holes clockwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub outer: Contour,
    #[serde(default)]
    pub holes: Vec<Contour>,
}

/// A closed contour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Contour {
    /// Axis-aligned rectangle; sides e0..e3 = bottom, right, top, left.
    Rect { min: P2, max: P2 },
    /// Rectangle with all four corners rounded by `radius`.
    RoundedRect { min: P2, max: P2, radius: f64 },
    /// Full circle (one closed edge per cap, one cylindrical face).
    Circle { centre: P2, radius: f64 },
    /// Obround slot between two centres.
    Slot { from: P2, to: P2, width: f64 },
    /// Polygon, corners rounded by `radius` (0 = sharp); sides e0.. follow the points.
    Polygon {
        points: Vec<P2>,
        #[serde(default)]
        radius: f64,
    },
    /// General path of lines and arcs; must end where it starts.
    Path { start: P2, segments: Vec<Segment> },
    /// `count` copies of `of`, each shifted by `step` (holes only).
    Repeat {
        count: usize,
        step: P2,
        of: Box<Contour>,
    },
}

/// One piece of a [`Contour::Path`]. `name` names the side face it makes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Segment {
    Line {
        to: P2,
        #[serde(default)]
        name: Option<String>,
    },
    /// Circular arc about `centre`, counter-clockwise when `ccw`.
    Arc {
        to: P2,
        centre: P2,
        ccw: bool,
        #[serde(default)]
        name: Option<String>,
    },
    /// Circular arc given by its bulge (tan of a quarter of the signed sweep).
    Bulge {
        to: P2,
        bulge: f64,
        #[serde(default)]
        name: Option<String>,
    },
}
