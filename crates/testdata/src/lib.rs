//! Where the external test data lives. Real STEP files from outside the
//! project (MFCAD, AAGNet) are never copied into the repository; tests find
//! them here, in order:
//!
//! 1. `$THINPLAN_DATA` (a directory holding `mfcad/` and `aagnet/`),
//! 2. `../shared/data` beside the repository root,
//! 3. `/work/shared/data`.
//!
//! Tests that need the data print a note and pass vacuously when none is
//! found, so the suite still runs on a developer's machine without it; with
//! `CI` set (`.ci/run` sets it) a missing file or peer fails the test
//! instead ([`missing`]), so a CI machine without them cannot go green.

use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
}

/// The external data directory, if present.
pub fn shared_data() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("THINPLAN_DATA").map(PathBuf::from),
        Some(repo_root().join("../shared/data")),
        Some(PathBuf::from("/work/shared/data")),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|p| p.join("mfcad").is_dir() || p.join("aagnet").is_dir())
}

/// Reports test data or a peer program that is not there: a note and a
/// vacuous pass on a developer's machine, a failure when `CI` is set.
pub fn missing(what: &str) {
    if std::env::var_os("CI").is_some_and(|v| !v.is_empty()) {
        panic!("{what} is missing, and CI must not skip the test that needs it");
    }
    eprintln!("note: {what} is missing; skipped");
}

/// A sub-directory of the external data (`"mfcad"`, `"aagnet"`), if present;
/// reports it [`missing`] otherwise.
pub fn data_dir(name: &str) -> Option<PathBuf> {
    let d = shared_data().map(|d| d.join(name)).filter(|d| d.is_dir());
    if d.is_none() {
        missing(&format!(
            "external test data `{name}` (set THINPLAN_DATA or place it at ../shared/data)"
        ));
    }
    d
}

/// Sorted `.step` files of a data sub-directory (empty when absent).
pub fn step_files(name: &str) -> Vec<PathBuf> {
    let Some(d) = data_dir(name) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&d)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "step"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}
