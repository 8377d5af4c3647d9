//! Every real STEP file in ../shared/data reads with the same solids, faces by
//! kind, extent and volume as OpenCASCADE reports for it
//! (`tests/oracle/occ_reference.json`, written by `tools/oracle/occ_inspect.py`).

use std::path::{Path, PathBuf};

use serde_json::Value;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn data_files() -> Vec<PathBuf> {
    let mut files = thinplan_testdata::step_files("mfcad");
    files.extend(thinplan_testdata::step_files("aagnet"));
    files
}

fn rel_close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-9)
}

#[test]
fn real_files_match_opencascade() {
    let files = data_files();
    if files.is_empty() {
        return;
    }
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(repo().join("tests/oracle/occ_reference.json")).unwrap(),
    )
    .unwrap();
    let mut failures = Vec::new();
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let Some(r) = reference.get(&name) else {
            failures.push(format!("{name}: no reference entry"));
            continue;
        };
        let part = match thinplan_import::import(path.to_str().unwrap()) {
            Ok(p) => p,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let s = &part.part.summary;
        let want_solids = r["solids"].as_u64().unwrap() as usize;
        if s.solids != want_solids {
            failures.push(format!("{name}: solids {} vs OCC {want_solids}", s.solids));
        }
        let want_faces = r["unique_faces"].as_u64().or(r["faces"].as_u64()).unwrap() as usize;
        if s.faces != want_faces {
            failures.push(format!("{name}: faces {} vs OCC {want_faces}", s.faces));
        }
        let kinds = serde_json::to_value(part.brep.face_kind_counts()).unwrap();
        for k in [
            "plane", "cylinder", "cone", "sphere", "torus", "bspline", "other",
        ] {
            let ours = kinds[k].as_u64().unwrap();
            let theirs = r["faces_by_kind"][k].as_u64().unwrap_or(0);
            if ours != theirs {
                failures.push(format!("{name}: {k} faces {ours} vs OCC {theirs}"));
            }
        }
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            let theirs = r["bbox"][i].as_f64().unwrap();
            if !rel_close(s.bbox[i], theirs, 1e-3) {
                failures.push(format!(
                    "{name}: extent {axis} {:.6} vs OCC {theirs:.6}",
                    s.bbox[i]
                ));
            }
        }
        let theirs = r["volume"].as_f64().unwrap();
        if !rel_close(s.volume, theirs, 1e-3) {
            failures.push(format!("{name}: volume {:.6} vs OCC {theirs:.6}", s.volume));
        }
        if part.part.declared_units != r["units"].as_str().unwrap_or("") {
            failures.push(format!(
                "{name}: units {} vs {}",
                part.part.declared_units, r["units"]
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} files differ from OpenCASCADE:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    eprintln!("{} files agree with OpenCASCADE", files.len());
}
