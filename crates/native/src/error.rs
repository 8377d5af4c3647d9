//! Errors: every one names the part file (its origin) and, where it can,
//! the prism and the reason. Nothing in this crate panics on bad input.

/// What went wrong reading, validating or building a native part.
#[derive(Debug, thiserror::Error)]
pub enum NativeError {
    /// The file could not be read.
    #[error("{origin}: cannot read the file: {source}")]
    Io {
        origin: String,
        #[source]
        source: std::io::Error,
    },
    /// RON syntax error or a field/variant the format does not know
    /// (`deny_unknown_fields`), with 1-based line and column.
    #[error("{origin}:{line}:{column}: {message}")]
    Syntax {
        origin: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A profile that cannot bound a region: not closed, self-intersecting,
    /// zero area, an arc whose end is not on its circle, holes crossing …
    #[error("{origin}: prism `{prism}`: bad profile: {reason}")]
    BadProfile {
        origin: String,
        prism: String,
        reason: String,
    },
    /// A prism whose frame or extent is unusable, or a duplicate id.
    #[error("{origin}: prism `{prism}`: {reason}")]
    BadPrism {
        origin: String,
        prism: String,
        reason: String,
    },
    /// Two prisms share interior volume (they may only touch).
    #[error("{origin}: prisms `{a}` and `{b}` overlap: {reason}")]
    Overlap {
        origin: String,
        a: String,
        b: String,
        reason: String,
    },
    /// Valid input this builder does not handle (e.g. prisms at 60° to each other).
    #[error("{origin}: unsupported: {reason}")]
    Unsupported { origin: String, reason: String },
    /// The union is not a closed, connected, manifold solid (open shell,
    /// an edge shared by four faces, prisms that do not touch …).
    #[error("{origin}: the built shell is not a valid solid: {reason}")]
    InvalidShell { origin: String, reason: String },
    /// The B-rep volume differs from the sum of the prism volumes.
    #[error("{origin}: volume check failed: B-rep {brep:.6} mm³, prisms {expected:.6} mm³")]
    VolumeMismatch {
        origin: String,
        brep: f64,
        expected: f64,
    },
    /// A labels file that refers to nothing or repeats ids.
    #[error("{origin}: labels: {reason}")]
    BadLabels { origin: String, reason: String },
}

impl NativeError {
    /// A short machine-readable kind, handy in tests and CLI output.
    pub fn kind(&self) -> &'static str {
        match self {
            NativeError::Io { .. } => "io",
            NativeError::Syntax { .. } => "syntax",
            NativeError::BadProfile { .. } => "bad_profile",
            NativeError::BadPrism { .. } => "bad_prism",
            NativeError::Overlap { .. } => "overlap",
            NativeError::Unsupported { .. } => "unsupported",
            NativeError::InvalidShell { .. } => "invalid_shell",
            NativeError::VolumeMismatch { .. } => "volume_mismatch",
            NativeError::BadLabels { .. } => "bad_labels",
        }
    }

    pub(crate) fn from_ron(origin: &str, e: ron::error::SpannedError) -> NativeError {
        NativeError::Syntax {
            origin: origin.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        }
    }
}
