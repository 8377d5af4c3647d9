//! Pocket tool paths for high-speed milling of thin-walled parts.
//!
//! * [`offset_path`]: the conventional parallel-offset baseline (cavalier_contours offsets of the
//!   pocket by the tool radius, then inward by the stepover until empty; rings linked innermost
//!   to outermost with short straight links, each ring counter-clockwise = down milling in a
//!   pocket with an M3 spindle; the last ring is the finishing pass on the tool-offset boundary).
//! * [`curvilinear_path`]: Bieterman & Sandstrom's curvilinear spiral: mesh the tool-offset
//!   region, solve −Δu = 1 (or the principal Dirichlet eigenfunction) with linear finite
//!   elements, pick contour levels outward from the maximum so that the measured gap between
//!   successive contours never exceeds the stepover, spiral orbit to orbit by winding angle,
//!   smooth, then finish on the offset boundary. Falls back to the offset path (reported as
//!   [`Method::OffsetFallback`]) when a contour is not star-shaped about the centre, the region
//!   splits or the pocket has islands.
//! * [`bench::bench_pockets`]: both paths (and FreeCAD Adaptive when available) timed with the
//!   project's feed schedule on a family of pockets over L/D.
//! * [`engagement::engagement_stats`]: the tool's engagement angle and radial engagement along
//!   any path, measured by replaying it over uncut stock.

pub mod bench;
pub mod contour;
pub mod engagement;
pub mod fem;
pub mod geom;
pub mod inset;
pub mod offset;
pub mod profile;
pub mod spiral;
pub mod svg;
pub mod timing;
pub mod zigzag;

use cavalier_contours::polyline::{PlineOrientation, PlineSource, Polyline};
use glam::DVec2;
use serde::{Deserialize, Serialize};

pub use bench::{bench_pockets, BenchConfig, BenchRow};
pub use fem::Field;
pub use offset::{offset_path, offset_path_gap_matched, offset_path_sharp};
pub use profile::PocketProfile;
pub use spiral::curvilinear_path;
pub use svg::pocket_svg;
pub use zigzag::zigzag_path;

/// Errors of pocket path generation.
#[derive(Debug, Clone, PartialEq)]
pub enum PocketError {
    /// Tool, stepover or finishing stepover out of range.
    BadParams(String),
    /// The pocket profile is unusable (open, empty, self-intersecting …).
    BadProfile(String),
    /// The tool does not fit into the pocket.
    ToolDoesNotFit,
    /// Meshing failed.
    Mesh(String),
    /// The sparse solve failed.
    Solver(String),
}

impl std::fmt::Display for PocketError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PocketError::BadParams(s) => write!(f, "bad pocketing parameters: {s}"),
            PocketError::BadProfile(s) => write!(f, "bad pocket profile: {s}"),
            PocketError::ToolDoesNotFit => write!(f, "the tool does not fit into the pocket"),
            PocketError::Mesh(s) => write!(f, "meshing failed: {s}"),
            PocketError::Solver(s) => write!(f, "PDE solve failed: {s}"),
        }
    }
}

impl std::error::Error for PocketError {}

/// A closed pocket profile: outer boundary (lines and arcs as bulges) and optional islands.
#[derive(Debug, Clone)]
pub struct Pocket {
    pub name: String,
    pub outer: Polyline<f64>,
    pub islands: Vec<Polyline<f64>>,
}

impl Pocket {
    /// A pocket without islands. The outer loop is made counter-clockwise.
    pub fn new(name: impl Into<String>, outer: Polyline<f64>) -> Self {
        Self::with_islands(name, outer, Vec::new())
    }

    /// A pocket with islands; the outer loop is made counter-clockwise, islands clockwise.
    pub fn with_islands(
        name: impl Into<String>,
        mut outer: Polyline<f64>,
        mut islands: Vec<Polyline<f64>>,
    ) -> Self {
        use cavalier_contours::polyline::PlineSourceMut;
        if outer.orientation() == PlineOrientation::Clockwise {
            outer.invert_direction_mut();
        }
        for isl in &mut islands {
            if isl.orientation() == PlineOrientation::CounterClockwise {
                isl.invert_direction_mut();
            }
        }
        Pocket {
            name: name.into(),
            outer,
            islands,
        }
    }

    /// Characteristic size L: the larger side of the outer loop's bounding box.
    pub fn size(&self) -> f64 {
        self.outer
            .extents()
            .map(|e| (e.max_x - e.min_x).max(e.max_y - e.min_y))
            .unwrap_or(0.0)
    }

    fn validate(&self) -> Result<(), PocketError> {
        if !self.outer.is_closed() || self.outer.vertex_count() < 2 {
            return Err(PocketError::BadProfile(
                "outer profile must be closed with ≥ 2 vertices".into(),
            ));
        }
        if self.outer.area().abs() < 1e-9 {
            return Err(PocketError::BadProfile(
                "outer profile has zero area".into(),
            ));
        }
        Ok(())
    }
}

/// Pocketing parameters (mm).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PocketParams {
    /// Tool diameter.
    pub tool_diameter: f64,
    /// Maximum radial stepover of the roughing orbits (0 < stepover ≤ tool diameter).
    pub stepover: f64,
    /// Radial engagement of the finishing pass on the tool-offset boundary (0 ≤ f ≤ stepover).
    pub finish_stepover: f64,
    /// Target mesh edge length for the PDE; default stepover / 3.
    pub mesh_size: Option<f64>,
    /// PDE generating the contours.
    pub field: Field,
    /// Laplacian smoothing passes over the spiral (kept only if the gap stays ≤ stepover).
    pub smoothing_passes: usize,
    /// Blend of the PDE field with the distance to the roughing boundary, α ∈ [0, 1]: the
    /// contours are those of w = (1 − α)·u/max u + α·d/max d. 0 = the pure PDE field
    /// (Bieterman); 1 = parallel offsets. Near the boundary the distance term evens out the
    /// spacing of the contours (−Δu = 1's gradient is small at corners and pocket ends).
    #[serde(default)]
    pub distance_blend: f64,
}

impl PocketParams {
    /// Roughing stepover 40 % of the tool, finishing 10 %.
    pub fn for_tool(tool_diameter: f64) -> Self {
        PocketParams {
            tool_diameter,
            stepover: 0.4 * tool_diameter,
            finish_stepover: 0.1 * tool_diameter,
            mesh_size: None,
            field: Field::Poisson,
            smoothing_passes: 4,
            distance_blend: 0.0,
        }
    }

    pub(crate) fn validate(&self) -> Result<(), PocketError> {
        let d = self.tool_diameter;
        if !(d.is_finite() && d > 0.0) {
            return Err(PocketError::BadParams("tool diameter must be > 0".into()));
        }
        if !(self.stepover > 0.0 && self.stepover <= d) {
            return Err(PocketError::BadParams(
                "stepover must be in (0, tool diameter]".into(),
            ));
        }
        if !(0.0..=1.0).contains(&self.distance_blend) {
            return Err(PocketError::BadParams(
                "distance blend must be in [0, 1]".into(),
            ));
        }
        if !(self.finish_stepover >= 0.0 && self.finish_stepover <= self.stepover) {
            return Err(PocketError::BadParams(
                "finishing stepover must be in [0, stepover]".into(),
            ));
        }
        Ok(())
    }

    /// Point spacing used when sampling arcs and spirals for timing.
    pub(crate) fn sample_step(&self) -> f64 {
        (self.stepover / 4.0).min(self.tool_diameter / 8.0)
    }
}

/// How a path was generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    Offset,
    Curvilinear,
    /// A spiral through the contours of the distance to the roughing boundary (parallel
    /// offsets), wound about the distance's ridge: the curvilinear construction with the
    /// offsets' even spacing, for elongated pockets (a slot).
    OffsetSpiral,
    OffsetFallback,
    /// Rectilinear passes joined along the roughing boundary ([`zigzag::zigzag_path`]): a
    /// baseline, never chosen for a pocket.
    Zigzag,
}

impl Method {
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Offset => "offset",
            Method::Curvilinear => "curvilinear",
            Method::OffsetSpiral => "offset-spiral",
            Method::OffsetFallback => "offset-fallback",
            Method::Zigzag => "zigzag",
        }
    }
}

/// A helix the tool descends on before a path: its tool-centre circle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HelixEntry {
    pub center: DVec2,
    /// Tool-centre radius (mm); the hole it clears has radius `radius` + D/2.
    pub radius: f64,
}

/// A pocketing tool path (tool-centre points in the pocket plane), roughing then finishing.
#[derive(Debug, Clone)]
pub struct PocketPath {
    pub method: Method,
    /// One continuous path: roughing orbits, then the finishing pass on the tool-offset
    /// boundary, closed back to its start.
    pub points: Vec<DVec2>,
    /// Index in `points` where the finishing pass starts.
    pub finish_start: usize,
    /// Max measured gap between successive orbits / rings (symmetric Hausdorff distance).
    pub max_gap: f64,
    /// The contours (curvilinear) or offset rings (offset) the path was built from.
    pub contours: Vec<Vec<DVec2>>,
    /// Spiral centre (argmax u) for curvilinear paths.
    pub center: Option<DVec2>,
    /// Why the curvilinear method fell back to offsets.
    pub fallback_reason: Option<String>,
    /// Which spiral was kept and why (curvilinear vs offset spiral: the shorter), for
    /// provenance.
    pub choice: Option<String>,
    /// The tool-offset boundary ∂Ω (finishing pass loop).
    pub boundary: Vec<DVec2>,
}

impl PocketPath {
    /// Path length (mm).
    pub fn length(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// Number of turns of the roughing part (before `finish_start`): full windings about the
    /// centre for a spiral (the last, full orbit on the roughing boundary included), rings for
    /// an offset path.
    pub fn roughing_turns(&self) -> usize {
        match self.center {
            Some(c) => {
                let mut acc = 0.0;
                for w in self.points[..self.finish_start.min(self.points.len())].windows(2) {
                    let (a, b) = (w[0] - c, w[1] - c);
                    if a.length_squared() > 1e-18 && b.length_squared() > 1e-18 {
                        acc += a.perp_dot(b).atan2(a.dot(b));
                    }
                }
                (acc / std::f64::consts::TAU - 1e-3).ceil().max(0.0) as usize
            }
            None => self.contours.len().saturating_sub(1),
        }
    }

    /// For a spiral: a lower bound on [`Self::roughing_turns`] for any spiral about this centre
    /// with the same first turn whose gap between successive turns is ≤ `stepover`:
    /// ⌈(R_max − ρ₁) / stepover⌉ + 1, R_max the largest distance from the centre to the roughing
    /// boundary, ρ₁ the largest of the first turn. (Each point of a turn is within the gap of
    /// the previous turn, so a turn reaches at most one stepover farther from the centre than
    /// the one before; + 1 for the first turn.) `None` for offset paths and for the offset
    /// spiral (wound about a segment, not about `center`: the bound does not apply).
    pub fn turns_lower_bound(&self, stepover: f64) -> Option<usize> {
        if self.method != Method::Curvilinear {
            return None;
        }
        let c = self.center?;
        let rough = self.contours.last()?;
        let rmax = rough.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
        let mut acc = 0.0;
        let mut rho1: f64 = 0.0;
        for w in self.points[..self.finish_start.min(self.points.len())].windows(2) {
            let (a, b) = (w[0] - c, w[1] - c);
            if a.length_squared() > 1e-18 && b.length_squared() > 1e-18 {
                acc += a.perp_dot(b).atan2(a.dot(b));
            }
            if acc > std::f64::consts::TAU {
                break;
            }
            rho1 = rho1.max(b.length());
        }
        Some(((rmax - rho1) / stepover - 1e-9).ceil().max(0.0) as usize + 1)
    }

    /// This path entered by a helix about its first point (a spiral's centre) of the first of
    /// `radii` (tool-centre radius ρ, mm, largest first) whose circle lies inside ∂Ω at least ρ
    /// from it (stage 7's fit rule), starting where the path first leaves that circle: the
    /// tool positions inside it lie in the hole the helix clears (radius ρ + R), so they would
    /// cut nothing. The rest of the path is unchanged, so the helix and it cover what the
    /// whole path covered. `None` where no radius fits, ∂Ω is missing, or the path does not
    /// leave the circle before its finishing pass.
    pub fn after_centred_helix(&self, radii: &[f64]) -> Option<(PocketPath, HelixEntry)> {
        let c = *self.points.first()?;
        if self.boundary.len() < 3 {
            return None;
        }
        let idx = geom::SegIndex::new(&[&self.boundary], true);
        let rho = radii.iter().copied().find(|&rho| {
            rho.is_finite()
                && rho > 0.0
                && geom::point_in_loop(c, &self.boundary)
                && idx.nearest(c) >= rho + 1e-6
        })?;
        let i = self.points.iter().position(|p| p.distance(c) > rho)?;
        if i >= self.finish_start {
            return None;
        }
        // where the segment into points[i] crosses the circle: |a + t(b − a) − c| = ρ, the
        // root in (0, 1] (a inside, b outside)
        let (a, b) = (self.points[i - 1], self.points[i]);
        let (u, v) = (a - c, b - a);
        let (qa, qb, qc) = (
            v.length_squared(),
            2.0 * u.dot(v),
            u.length_squared() - rho * rho,
        );
        let t = ((-qb + (qb * qb - 4.0 * qa * qc).max(0.0).sqrt()) / (2.0 * qa)).clamp(0.0, 1.0);
        let q = c + (u + t * v).normalize_or_zero() * rho;
        let mut points = Vec::with_capacity(self.points.len() - i + 1);
        points.push(q);
        points.extend_from_slice(&self.points[i..]);
        Some((
            PocketPath {
                points,
                finish_start: self.finish_start - i + 1,
                ..self.clone()
            },
            HelixEntry {
                center: c,
                radius: rho,
            },
        ))
    }

    /// Largest distance between consecutive points.
    pub fn max_step(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .fold(0.0, f64::max)
    }
}
