//! Reading RON knowledge files with errors that point at file, line and column.

use std::path::{Path, PathBuf};

use miette::{Diagnostic, NamedSource, SourceSpan};
use serde::de::DeserializeOwned;

/// One problem found in the knowledge, with where it is.
#[derive(Debug, thiserror::Error, Diagnostic)]
pub enum KnowledgeError {
    #[error("{path}: cannot read: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error("{path}:{line}:{column}: {reason}")]
    #[diagnostic(code(thinplan::knowledge::syntax))]
    Syntax {
        path: PathBuf,
        line: usize,
        column: usize,
        reason: String,
        #[source_code]
        src: NamedSource<String>,
        #[label("here")]
        span: SourceSpan,
    },
    #[error("{path}: {reason}")]
    #[diagnostic(code(thinplan::knowledge::invalid))]
    Invalid { path: PathBuf, reason: String },
    /// A value that parses but is outside its allowed range (or breaks a
    /// rule between values), pointed at like a syntax error.
    #[error("{path}:{line}:{column}: {reason}")]
    #[diagnostic(code(thinplan::knowledge::value))]
    Value {
        path: PathBuf,
        line: usize,
        column: usize,
        reason: String,
        #[source_code]
        src: NamedSource<String>,
        #[label("this value")]
        span: SourceSpan,
    },
}

impl KnowledgeError {
    /// The file the problem is in.
    pub fn path(&self) -> &Path {
        match self {
            KnowledgeError::Read { path, .. }
            | KnowledgeError::Syntax { path, .. }
            | KnowledgeError::Invalid { path, .. }
            | KnowledgeError::Value { path, .. } => path,
        }
    }

    /// A value problem in `text` (the file at `path`), located by its path.
    pub fn at_value(path: &Path, text: &str, problem: crate::check::Problem) -> KnowledgeError {
        let (line, column, offset) = crate::check::locate(text, &problem.at);
        KnowledgeError::Value {
            path: path.to_path_buf(),
            line,
            column,
            reason: problem.message,
            src: NamedSource::new(path.display().to_string(), text.to_string()),
            span: SourceSpan::from((offset, 0)),
        }
    }
}

/// Byte offset of a 1-based line and column in `text`.
fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let mut offset = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            let col_bytes: usize = l
                .chars()
                .take(column.saturating_sub(1))
                .map(char::len_utf8)
                .sum();
            return (offset + col_bytes).min(text.len());
        }
        offset += l.len();
    }
    text.len()
}

/// Parses RON text into `T`; `path` names the origin in errors.
pub fn parse_ron<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, KnowledgeError> {
    // Optional fields may be written without `Some(…)`, as knowledge engineers expect.
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<T>(text)
        .map_err(|e| {
            let (line, column) = (e.span.start.line, e.span.start.col);
            let offset = offset_of(text, line, column);
            KnowledgeError::Syntax {
                path: path.to_path_buf(),
                line,
                column,
                reason: e.code.to_string(),
                src: NamedSource::new(path.display().to_string(), text.to_string()),
                span: SourceSpan::from((offset, 0)),
            }
        })
}

/// Reads and parses one RON file.
pub fn load_ron<T: DeserializeOwned>(path: &Path) -> Result<T, KnowledgeError> {
    let text = std::fs::read_to_string(path).map_err(|e| KnowledgeError::Read {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    parse_ron(&text, path)
}

/// The `.ron` files of a directory, sorted by name (deterministic).
pub fn ron_files(dir: &Path) -> Result<Vec<PathBuf>, KnowledgeError> {
    let rd = std::fs::read_dir(dir).map_err(|e| KnowledgeError::Read {
        path: dir.to_path_buf(),
        reason: e.to_string(),
    })?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    Ok(files)
}
