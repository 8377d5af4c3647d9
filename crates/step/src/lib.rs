//! Tolerant reader of the subset of ISO 10303 (STEP) that thinplan needs.
//!
//! * [`p21`]: a fast, bounded, hand-written Part 21 parser (any entity).
//! * [`read_step_bytes`] / [`read_step_file`]: build a [`thinplan_brep::Brep`]
//!   in millimetres from the B-rep solids (and surface models) of AP203/AP214/
//!   AP242 files, honouring the declared length and plane-angle units and
//!   expanding assemblies into one placed solid per instance.
//! * [`write_step`]: the way back, a STEP AP214 file from a B-rep.
//!
//! The reader never panics on any input; hostile input ends in a
//! [`StepError`] bounded by [`Limits`].

use std::fmt;
use std::path::{Path, PathBuf};

mod build;
mod check;
pub mod p21;
pub mod write;

pub use write::write_step;

/// What a file gave: the B-rep in millimetres and facts about the file.
#[derive(Debug, Clone)]
pub struct StepModel {
    pub brep: thinplan_brep::Brep,
    /// The declared length unit: "mm", "m", "cm", "inch", "foot" …
    pub units: String,
    /// The schema named in `FILE_SCHEMA` (e.g. `AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }`).
    pub schema: String,
    /// Non-fatal problems: unsupported curve kinds replaced by polylines,
    /// missing unit declarations, …
    pub warnings: Vec<String>,
}

/// Bounds on the work a read may do; hostile input ends in an error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest accepted input, in bytes.
    pub max_bytes: usize,
    /// Most entity instances in the data section(s).
    pub max_entities: usize,
    /// Deepest nesting of parameter lists, and of followed references
    /// (assembly levels, curves built on curves …).
    pub max_depth: usize,
    /// Budget for building: entities visited plus B-rep elements produced
    /// (assembly expansion can multiply the input).
    pub max_work: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_bytes: 512 << 20,
            max_entities: 20_000_000,
            max_depth: 128,
            max_work: 500_000_000,
        }
    }
}

/// Where in the file an error is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Place {
    /// The entity (`#id`), when the error is about one.
    pub id: Option<u64>,
    /// 1-based.
    pub line: usize,
    /// 1-based.
    pub column: usize,
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.id {
            Some(id) => write!(f, "#{id} (line {}, column {})", self.line, self.column),
            None => write!(f, "line {}, column {}", self.line, self.column),
        }
    }
}

/// The reason a read failed.
#[derive(Debug, thiserror::Error)]
pub enum StepErrorKind {
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    #[error("syntax error at {place}: {reason}")]
    Syntax { place: Place, reason: String },
    #[error("limit exceeded at {place}: {reason}")]
    Limit { place: Place, reason: String },
    #[error("{place} refers to #{target} which does not exist")]
    Dangling { place: Place, target: u64 },
    #[error("cyclic reference at {place}: {chain}")]
    Cyclic { place: Place, chain: String },
    #[error("{place} {entity}: {reason}")]
    WrongParameter {
        place: Place,
        entity: String,
        reason: String,
    },
    #[error("{place} {entity}: unsupported: {reason}")]
    Unsupported {
        place: Place,
        entity: String,
        reason: String,
    },
    #[error("no solid in this file ({reason})")]
    NoSolid { reason: String },
    /// A shell that is not closed or not consistently oriented: the reason
    /// names its edges and faces by `#id`.
    #[error("{place} {entity}: not a closed solid: {reason}")]
    NotClosed {
        place: Place,
        entity: String,
        reason: String,
    },
}

impl StepErrorKind {
    /// The place the error names, if any.
    pub fn place(&self) -> Option<&Place> {
        match self {
            StepErrorKind::Syntax { place, .. }
            | StepErrorKind::Limit { place, .. }
            | StepErrorKind::Dangling { place, .. }
            | StepErrorKind::Cyclic { place, .. }
            | StepErrorKind::WrongParameter { place, .. }
            | StepErrorKind::Unsupported { place, .. }
            | StepErrorKind::NotClosed { place, .. } => Some(place),
            StepErrorKind::Io(_) | StepErrorKind::NoSolid { .. } => None,
        }
    }
}

/// A failed read: the file (when there is one) and the reason with its place.
#[derive(Debug)]
pub struct StepError {
    pub file: Option<PathBuf>,
    pub kind: StepErrorKind,
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.file {
            Some(p) => write!(f, "{}: {}", p.display(), self.kind),
            None => write!(f, "{}", self.kind),
        }
    }
}

impl std::error::Error for StepError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            StepErrorKind::Io(e) => Some(e),
            _ => None,
        }
    }
}

impl From<StepErrorKind> for StepError {
    fn from(kind: StepErrorKind) -> Self {
        StepError { file: None, kind }
    }
}

/// Reads a STEP file with the default [`Limits`].
pub fn read_step_file(path: &Path) -> Result<StepModel, StepError> {
    read_step_file_with(path, &Limits::default())
}

/// Reads a STEP file within `limits`. Its size is checked before it is
/// read, and the read stops past the limit (a file that grows meanwhile).
pub fn read_step_file_with(path: &Path, limits: &Limits) -> Result<StepModel, StepError> {
    use std::io::Read;
    let with_file = |kind: StepErrorKind| StepError {
        file: Some(path.to_path_buf()),
        kind,
    };
    let too_big = |len: u64| {
        with_file(StepErrorKind::Limit {
            place: Place {
                id: None,
                line: 1,
                column: 1,
            },
            reason: format!(
                "file is {len} bytes, more than the limit of {} bytes",
                limits.max_bytes
            ),
        })
    };
    let file = std::fs::File::open(path).map_err(|e| with_file(e.into()))?;
    let meta = file.metadata().map_err(|e| with_file(e.into()))?;
    if meta.len() > limits.max_bytes as u64 {
        return Err(too_big(meta.len()));
    }
    let cap = limits.max_bytes as u64 + 1;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(cap)
        .read_to_end(&mut bytes)
        .map_err(|e| with_file(e.into()))?;
    if bytes.len() > limits.max_bytes {
        return Err(too_big(bytes.len() as u64));
    }
    read_step_bytes(&bytes, limits).map_err(|e| with_file(e.kind))
}

/// Reads STEP data from memory.
pub fn read_step_bytes(bytes: &[u8], limits: &Limits) -> Result<StepModel, StepError> {
    let ex = p21::parse(
        bytes,
        p21::ParseLimits {
            max_bytes: limits.max_bytes,
            max_entities: limits.max_entities,
            max_depth: limits.max_depth.max(1),
        },
    )
    .map_err(|e| {
        let place = Place {
            id: None,
            line: e.line,
            column: e.column,
        };
        if e.limit {
            StepErrorKind::Limit {
                place,
                reason: e.reason,
            }
        } else {
            StepErrorKind::Syntax {
                place,
                reason: e.reason,
            }
        }
    })?;
    let schema = ex.schema();
    let mut warnings = ex.warnings.clone();
    let out = build::build(&ex, limits)?;
    warnings.extend(out.warnings);
    Ok(StepModel {
        brep: out.brep,
        units: out.units,
        schema,
        warnings,
    })
}
