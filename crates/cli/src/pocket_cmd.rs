//! `thinplan bench pockets` and `thinplan pocket`: thin drivers of
//! `thinplan-pocketing`.

use std::path::Path;

/// Prints the pocket benchmark table (or JSON rows with `json`).
pub fn bench_pockets(_json: bool) -> Result<(), String> {
    Err("not built yet".into())
}

/// Plans one pocket from a profile file; writes the SVG and/or JSON.
pub fn pocket(_profile: &Path, _svg: Option<&Path>, _json: bool) -> Result<(), String> {
    Err("not built yet".into())
}
