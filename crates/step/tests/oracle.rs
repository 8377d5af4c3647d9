//! Cross-check against the OpenCASCADE oracle numbers in `tests/oracle/`
//! (solids, faces by kind, units, bounding box). Skips when absent.

use std::path::{Path, PathBuf};

use serde_json::Value;
use thinplan_step::read_step_file;

fn oracle_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/oracle")
}

fn find(name: &str, dirs: &[PathBuf]) -> Option<PathBuf> {
    dirs.iter().map(|d| d.join(name)).find(|p| p.exists())
}

fn compare(reference: &Path, dirs: &[PathBuf]) {
    let Ok(text) = std::fs::read_to_string(reference) else {
        println!("note: {} is missing; skipped", reference.display());
        return;
    };
    let json: Value = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    let mut problems = Vec::new();
    for (name, r) in json.as_object().unwrap() {
        if name.starts_with('_') {
            continue;
        }
        let Some(path) = find(name, dirs) else {
            continue;
        };
        let m = match read_step_file(&path) {
            Ok(m) => m,
            Err(e) => {
                problems.push(format!("{e}"));
                continue;
            }
        };
        let b = &m.brep;
        let k = b.face_kind_counts();
        let get = |key: &str| r[key].as_u64().unwrap_or(u64::MAX) as usize;
        let fk = &r["faces_by_kind"];
        let kinds = |key: &str| fk[key].as_u64().unwrap_or(u64::MAX) as usize;
        if b.solids.len() != get("solids") || b.faces.len() != get("faces") {
            problems.push(format!(
                "{name}: {} solids {} faces, OCC {} {}",
                b.solids.len(),
                b.faces.len(),
                get("solids"),
                get("faces")
            ));
        }
        let ours = [
            k.plane, k.cylinder, k.cone, k.sphere, k.torus, k.bspline, k.other,
        ];
        let theirs = [
            "plane", "cylinder", "cone", "sphere", "torus", "bspline", "other",
        ]
        .map(kinds);
        if ours != theirs {
            problems.push(format!("{name}: kinds {ours:?}, OCC {theirs:?}"));
        }
        if r["units"].as_str() != Some(m.units.as_str()) {
            problems.push(format!("{name}: units {}, OCC {}", m.units, r["units"]));
        }
        // Our vertex box lies inside OCC's geometric box; for all-planar
        // parts the two are the same.
        let v3 = |key: &str| {
            let a = r[key].as_array().unwrap();
            glam::DVec3::new(
                a[0].as_f64().unwrap(),
                a[1].as_f64().unwrap(),
                a[2].as_f64().unwrap(),
            )
        };
        let (omin, omax) = (v3("bbox_min"), v3("bbox_max"));
        let tol = 1e-6 * (omax - omin).length().max(1.0);
        let mut vmin = glam::DVec3::splat(f64::INFINITY);
        let mut vmax = glam::DVec3::splat(f64::NEG_INFINITY);
        for v in &b.vertices {
            vmin = vmin.min(v.point);
            vmax = vmax.max(v.point);
        }
        let inside = vmin.cmpge(omin - tol).all() && vmax.cmple(omax + tol).all();
        let planar = k.plane == b.faces.len();
        let same =
            (vmin - omin).abs().max_element() < tol && (vmax - omax).abs().max_element() < tol;
        if !inside || (planar && !same) {
            problems.push(format!(
                "{name}: vertex box {vmin}..{vmax}, OCC {omin}..{omax}"
            ));
        }
        checked += 1;
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    println!("{}: {checked} files agree with OCC", reference.display());
}

#[test]
fn real_files_agree_with_occ() {
    let dirs: Vec<PathBuf> = ["mfcad", "aagnet"]
        .iter()
        .filter_map(|d| thinplan_testdata::data_dir(d))
        .collect();
    compare(&oracle_dir().join("occ_reference.json"), &dirs);
}

#[test]
fn oracle_unit_files_agree_with_occ() {
    let dir = oracle_dir().join("units");
    compare(
        &dir.join("occ_units_reference.json"),
        std::slice::from_ref(&dir),
    );
}
