//! Stage 0, import: a part file (STEP or native RON) or a bundled sample
//! becomes a B-rep in millimetres plus the [`PartRef`] a plan records.
//!
//! Native parts go through the same B-rep as STEP parts; nothing downstream
//! can tell them apart except by `PartRef::format`.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};
use thinplan_brep::Brep;
use thinplan_plan::{PartFormat, PartRef, PartSummary};

mod samples;
pub use samples::{sample, SAMPLES};

/// The default part `thinplan plan` uses with no argument.
pub const DEFAULT_SAMPLE: &str = "wing_rib";

#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: cannot read part file: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Step(#[from] thinplan_step::StepError),
    #[error(transparent)]
    Native(#[from] thinplan_native::NativeError),
    #[error("{path}: unknown part format (expected .step/.stp or .part.ron)")]
    UnknownFormat { path: PathBuf },
    #[error("no bundled sample named `{name}` (known: {known})")]
    UnknownSample { name: String, known: String },
}

/// An imported part: its B-rep and what a plan records about it.
#[derive(Debug, Clone)]
pub struct ImportedPart {
    pub brep: Brep,
    pub part: PartRef,
    pub warnings: Vec<String>,
}

/// The format a path names, by extension.
pub fn format_of(path: &Path) -> Option<PartFormat> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".step") || name.ends_with(".stp") || name.ends_with(".p21") {
        Some(PartFormat::Step)
    } else if name.ends_with(".ron") {
        Some(PartFormat::Native)
    } else {
        None
    }
}

/// Reads a part: a file path, or `builtin:NAME` for a bundled sample.
pub fn import(source: &str) -> Result<ImportedPart, ImportError> {
    if let Some(name) = source.strip_prefix("builtin:") {
        return import_sample(name);
    }
    let path = Path::new(source);
    let format = format_of(path).ok_or_else(|| ImportError::UnknownFormat {
        path: path.to_path_buf(),
    })?;
    let bytes = std::fs::read(path).map_err(|source| ImportError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    match format {
        PartFormat::Step => {
            let model = thinplan_step::read_step_file(path)?;
            Ok(finish(
                model.brep,
                source,
                format,
                &bytes,
                model.units,
                model.warnings,
            ))
        }
        PartFormat::Native => {
            let text = String::from_utf8_lossy(&bytes);
            let part = thinplan_native::parse_part(&text, source)?;
            let brep = part.build()?;
            Ok(finish(brep, source, format, &bytes, "mm".into(), vec![]))
        }
    }
}

/// Reads a bundled sample part by name.
pub fn import_sample(name: &str) -> Result<ImportedPart, ImportError> {
    let text = sample(name).ok_or_else(|| ImportError::UnknownSample {
        name: name.to_string(),
        known: SAMPLES
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(", "),
    })?;
    let source = format!("builtin:{name}");
    let part = thinplan_native::parse_part(text, &source)?;
    let brep = part.build()?;
    Ok(finish(
        brep,
        &source,
        PartFormat::Native,
        text.as_bytes(),
        "mm".into(),
        vec![],
    ))
}

fn finish(
    brep: Brep,
    source: &str,
    format: PartFormat,
    bytes: &[u8],
    units: String,
    warnings: Vec<String>,
) -> ImportedPart {
    let summary = summarise(&brep);
    let sha256 = Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    ImportedPart {
        part: PartRef {
            source: source.to_string(),
            format,
            sha256,
            declared_units: units,
            summary,
        },
        brep,
        warnings,
    }
}

/// Solids, faces, extent and volume of a B-rep.
pub fn summarise(brep: &Brep) -> PartSummary {
    let e = brep.bbox().extent();
    PartSummary {
        solids: brep.solids.len(),
        faces: brep.faces.len(),
        bbox: [e.x, e.y, e.z],
        volume: brep.volume(),
    }
}
