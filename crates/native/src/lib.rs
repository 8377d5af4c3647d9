//! Native part descriptions in RON for 2.5D thin-walled parts, built into
//! the same [`thinplan_brep::Brep`] a STEP file gives.
//!
//! A part is a union of prisms that touch but never overlap: a 2D profile of
//! lines and true arcs in a frame, extruded along the frame normal. Webs,
//! ribs, flanges, fillets and bosses are all prisms; holes and cut-outs are
//! holes and notches in their profiles. [`NativePart::build`] turns the
//! union into one closed, manifold, consistently oriented solid with shared
//! edges and merged coplanar faces, and checks its exact volume against the
//! profile areas. See the crate README for the format and the method.

use std::path::Path;

use glam::DVec3;
use thinplan_brep::{Brep, Frame};

mod arrange;
mod build;
pub mod check;
mod error;
mod geom2;
mod geom3;
pub mod labels;
pub mod mass;
pub mod model;
mod overlap;
mod profile;

pub use error::NativeError;
pub use labels::{ConnectionKind, ConnectionLabel, FeatureKind, FeatureLabel, Labels, WallRole};
pub use model::{Contour, FrameSpec, PartSpec, PrismSpec, Profile, Segment};

use build::PrismGeo;

/// Relative tolerance of the construction (times the part size, mm).
pub const REL_TOL: f64 = 1e-6;

/// A parsed and validated native part.
#[derive(Debug, Clone)]
pub struct NativePart {
    spec: PartSpec,
    origin: String,
    prisms: Vec<PrismGeo>,
    tol: f64,
}

fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

fn read(path: &Path) -> Result<String, NativeError> {
    std::fs::read_to_string(path).map_err(|source| NativeError::Io {
        origin: path.display().to_string(),
        source,
    })
}

/// Reads, parses and validates a part file.
pub fn load_part(path: &Path) -> Result<NativePart, NativeError> {
    let text = read(path)?;
    parse_part(&text, &path.display().to_string())
}

/// Parses and validates a part given as text; `origin` names it in errors.
pub fn parse_part(text: &str, origin: &str) -> Result<NativePart, NativeError> {
    let spec: PartSpec = ron_options()
        .from_str(text)
        .map_err(|e| NativeError::from_ron(origin, e))?;
    NativePart::from_spec(spec, origin)
}

/// Reads and validates a labels file (`NAME.labels.ron`).
pub fn load_labels(path: &Path) -> Result<Labels, NativeError> {
    let origin = path.display().to_string();
    let text = read(path)?;
    parse_labels(&text, &origin)
}

/// Parses and validates labels given as text.
pub fn parse_labels(text: &str, origin: &str) -> Result<Labels, NativeError> {
    let labels: Labels = ron_options()
        .from_str(text)
        .map_err(|e| NativeError::from_ron(origin, e))?;
    labels.validate().map_err(|reason| NativeError::BadLabels {
        origin: origin.to_string(),
        reason,
    })?;
    Ok(labels)
}

/// The labels of a part file: inline in the part, else `NAME.labels.ron`
/// beside `NAME.part.ron`; `Ok(None)` when there are none.
pub fn load_part_labels(part_path: &Path) -> Result<Option<Labels>, NativeError> {
    let part = load_part(part_path)?;
    if let Some(l) = part.labels() {
        return Ok(Some(l.clone()));
    }
    let file = part_path
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or_default();
    let stem = file.strip_suffix(".part.ron").unwrap_or(file);
    let beside = part_path.with_file_name(format!("{stem}.labels.ron"));
    if beside.exists() {
        load_labels(&beside).map(Some)
    } else {
        Ok(None)
    }
}

fn v3(p: (f64, f64, f64)) -> DVec3 {
    DVec3::new(p.0, p.1, p.2)
}

impl NativePart {
    /// Validates a spec: ids, frames, extents, profiles, overlaps, labels.
    pub fn from_spec(spec: PartSpec, origin: &str) -> Result<NativePart, NativeError> {
        let bad = |prism: &str, reason: String| NativeError::BadPrism {
            origin: origin.to_string(),
            prism: prism.to_string(),
            reason,
        };
        if spec.prisms.is_empty() {
            return Err(bad("-", "the part has no prisms".into()));
        }
        // Size of the part, for the tolerance.
        let mut scale: f64 = 1.0;
        for p in &spec.prisms {
            let o = v3(p.frame.origin);
            scale = scale.max(o.abs().max_element());
            scale = scale.max(p.extent.0.abs()).max(p.extent.1.abs());
        }
        let mut ids = std::collections::BTreeSet::new();
        let mut frames = Vec::new();
        for p in &spec.prisms {
            if p.id.is_empty() || p.id.contains(['.', ' ', '\t', '\n']) {
                return Err(bad(
                    &p.id,
                    "ids must be non-empty, without dots or spaces".into(),
                ));
            }
            if !ids.insert(p.id.as_str()) {
                return Err(bad(&p.id, "duplicate prism id".into()));
            }
            let (o, x, y) = (v3(p.frame.origin), v3(p.frame.x_dir), v3(p.frame.y_dir));
            if !(o.is_finite() && x.is_finite() && y.is_finite()) {
                return Err(bad(&p.id, "frame values must be finite".into()));
            }
            let (lx, ly) = (x.length(), y.length());
            if lx < 1e-12 || ly < 1e-12 {
                return Err(bad(&p.id, "frame x_dir and y_dir must be non-zero".into()));
            }
            let (x, y) = (x / lx, y / ly);
            if x.dot(y).abs() > 1e-9 {
                return Err(bad(
                    &p.id,
                    "frame x_dir and y_dir must be perpendicular".into(),
                ));
            }
            let (e0, e1) = p.extent;
            if !(e0.is_finite() && e1.is_finite()) || e1 - e0 <= 0.0 {
                return Err(bad(
                    &p.id,
                    format!("extent ({e0}, {e1}) must have to > from"),
                ));
            }
            frames.push(Frame {
                origin: o,
                x,
                y,
                z: x.cross(y),
            });
        }
        // Profile sizes join the scale before profiles are validated.
        for p in &spec.prisms {
            scale = scale.max(contour_scale(&p.profile.outer));
        }
        let tol = REL_TOL * scale;
        let mut prisms = Vec::new();
        for (p, frame) in spec.prisms.iter().zip(frames) {
            let region = profile::build_region(&p.profile, tol).map_err(|reason| {
                NativeError::BadProfile {
                    origin: origin.to_string(),
                    prism: p.id.clone(),
                    reason,
                }
            })?;
            let caps = p
                .cap_names
                .clone()
                .unwrap_or_else(|| ("bottom".into(), "top".into()));
            prisms.push(PrismGeo {
                id: p.id.clone(),
                frame,
                e0: p.extent.0,
                e1: p.extent.1,
                region,
                caps,
            });
        }
        overlap::check_overlaps(origin, &prisms, tol)?;
        if let Some(l) = &spec.labels {
            l.validate().map_err(|reason| NativeError::BadLabels {
                origin: origin.to_string(),
                reason,
            })?;
        }
        Ok(NativePart {
            spec,
            origin: origin.to_string(),
            prisms,
            tol,
        })
    }

    pub fn name(&self) -> &str {
        &self.spec.name
    }

    pub fn spec(&self) -> &PartSpec {
        &self.spec
    }

    /// Inline labels, if the part file carries them.
    pub fn labels(&self) -> Option<&Labels> {
        self.spec.labels.as_ref()
    }

    /// The geometric tolerance used (mm).
    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Sum of prism volumes from the profile areas (mm³).
    pub fn expected_volume(&self) -> f64 {
        self.prisms.iter().map(PrismGeo::volume).sum()
    }

    /// Builds and checks the B-rep: closed, manifold, connected, with the
    /// exact volume equal to [`Self::expected_volume`] within 1e-6 relative.
    pub fn build(&self) -> Result<Brep, NativeError> {
        let brep = build::build(&self.origin, &self.spec.name, &self.prisms, self.tol)?;
        let v = mass::volume(&brep);
        let e = self.expected_volume();
        if (v - e).abs() > 1e-6 * e.abs().max(1e-9) {
            return Err(NativeError::VolumeMismatch {
                origin: self.origin.clone(),
                brep: v,
                expected: e,
            });
        }
        Ok(brep)
    }
}

fn contour_scale(c: &Contour) -> f64 {
    let m = |p: (f64, f64)| p.0.abs().max(p.1.abs());
    let r = match c {
        Contour::Rect { min, max } | Contour::RoundedRect { min, max, .. } => m(*min).max(m(*max)),
        Contour::Circle { centre, radius } => m(*centre) + radius.abs(),
        Contour::Slot { from, to, width } => m(*from).max(m(*to)) + width.abs(),
        Contour::Polygon { points, .. } => points.iter().map(|p| m(*p)).fold(0.0, f64::max),
        Contour::Path { start, segments } => segments
            .iter()
            .map(|s| match s {
                Segment::Line { to, .. } | Segment::Arc { to, .. } | Segment::Bulge { to, .. } => {
                    m(*to)
                }
            })
            .fold(m(*start), f64::max),
        Contour::Repeat { count, step, of } => contour_scale(of) + m(*step) * *count as f64,
    };
    if r.is_finite() {
        r
    } else {
        0.0
    }
}
