//! Helpers the CLI's test binaries share.

use std::path::{Path, PathBuf};

/// Copies the directory tree `from` to `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let target = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &target);
        } else {
            std::fs::copy(&p, &target).unwrap();
        }
    }
}

/// A copy of the knowledge at `knowledge` in `d/knowledge` with one more
/// file, `tools/NAME.ron` holding `text`; returns the copy's path.
#[allow(dead_code)]
pub fn knowledge_with_tool_set(d: &Path, knowledge: &Path, name: &str, text: &str) -> PathBuf {
    let k = d.join("knowledge");
    copy_dir(knowledge, &k);
    std::fs::write(k.join(format!("tools/{name}.ron")), text).unwrap();
    k
}
