//! Reads every real file of the shared data sets and checks the result.

mod common;

use thinplan_step::{p21, read_step_file};

fn check_dir(name: &str, expect_units: Option<&[&str]>) {
    let Some(dir) = thinplan_testdata::data_dir(name) else {
        return;
    };
    let dir = dir.as_path();
    let Ok(rd) = std::fs::read_dir(dir) else {
        thinplan_testdata::missing(&dir.display().to_string());
        return;
    };
    let mut files: Vec<_> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "step" || e == "stp"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no STEP files in {}", dir.display());
    let mut failures = Vec::new();
    for path in &files {
        let model = match read_step_file(path) {
            Ok(m) => m,
            Err(e) => {
                failures.push(format!("{e}"));
                continue;
            }
        };
        let b = &model.brep;
        if b.solids.is_empty() {
            failures.push(format!("{}: no solid", path.display()));
        }
        if let Some(u) = expect_units {
            if !u.contains(&model.units.as_str()) {
                failures.push(format!("{}: units {}", path.display(), model.units));
            }
        }
        // Faces read == ADVANCED_FACE entities listed by the solids' shells.
        let bytes = std::fs::read(path).unwrap();
        let ex = p21::parse(
            &bytes,
            p21::ParseLimits {
                max_bytes: 1 << 30,
                max_entities: 1 << 26,
                max_depth: 64,
            },
        )
        .unwrap();
        let mut listed = 0;
        let mut advanced = 0;
        for e in &ex.entities {
            let parts = ex.parts_of(e);
            let name = ex.name(parts[0].name);
            if name == "CLOSED_SHELL" {
                if let p21::Value::List(l) = ex.args(&parts[0])[1] {
                    listed += l.len as usize;
                }
            }
            if name == "ADVANCED_FACE" {
                advanced += 1;
            }
        }
        if b.faces.len() != listed || b.faces.len() != advanced {
            failures.push(format!(
                "{}: {} faces read, {listed} listed by shells, {advanced} ADVANCED_FACE",
                path.display(),
                b.faces.len()
            ));
        }
        let solid_faces: usize = (0..b.solids.len()).map(|s| b.solid_faces(s).count()).sum();
        assert_eq!(solid_faces, b.faces.len(), "{}", path.display());
        for p in common::check_brep(b).into_iter().take(5) {
            failures.push(format!("{}: {p}", path.display()));
        }
        for f in &b.faces {
            assert!(!f.loops.is_empty());
        }
    }
    assert!(
        failures.is_empty(),
        "{} problems:\n{}",
        failures.len(),
        failures.join("\n")
    );
    println!("{}: {} files read", dir.display(), files.len());
}

#[test]
fn mfcad_all_files() {
    check_dir("mfcad", Some(&["mm", "m"]));
}

#[test]
fn aagnet_all_files() {
    check_dir("aagnet", Some(&["mm", "m"]));
}

#[test]
fn mfcad_face_names_kept() {
    let Some(dir) = thinplan_testdata::data_dir("mfcad") else {
        return;
    };
    let path = &dir.join("0-0-0-0-13-23.step");
    if !path.exists() {
        thinplan_testdata::missing(&path.display().to_string());
        return;
    }
    let m = read_step_file(path).unwrap();
    assert_eq!(m.units, "mm");
    assert!(m.schema.starts_with("AUTOMOTIVE_DESIGN"));
    let names: Vec<&str> = m.brep.faces.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names.len(), 12);
    assert_eq!(names[0], "1");
    // The labels file maps face names to classes; every name is present.
    let labels = std::fs::read_to_string(path.with_extension("labels.json")).unwrap_or_default();
    for n in &names {
        assert!(
            labels.contains(&format!("\"{n}\"")),
            "face name {n} not in labels"
        );
    }
}
