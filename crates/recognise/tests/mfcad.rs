//! MFCAD face accuracy (see `crates/recognise/MFCAD.md`).

use std::path::{Path, PathBuf};

use thinplan_brep::Brep;
use thinplan_recognise::mfcad::{score_mfcad_depressions_with, score_mfcad_with, MfcadScore};

fn data() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mfcad");
    if dir.is_dir() {
        Some(dir)
    } else {
        println!("skipped: {} is missing", dir.display());
        None
    }
}

fn read(p: &Path) -> Result<Brep, String> {
    thinplan_step::read_step_file(p)
        .map(|m| m.brep)
        .map_err(|e| e.to_string())
}

fn show(s: &MfcadScore) {
    println!("{}", s.table());
    println!("{}", s.confusion_table());
    println!(
        "wall-claimed faces: {} ({} of them feature faces)",
        s.wall_claimed_faces, s.wall_claimed_feature_faces
    );
    for m in &s.misses {
        println!("miss: {m}");
    }
}

/// The depression recogniser alone (nothing claimed by walls).
#[test]
fn mfcad_depressions_face_accuracy() {
    let Some(dir) = data() else { return };
    let s = score_mfcad_depressions_with(&dir, read);
    show(&s);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert_eq!(s.parts, 100);
    assert_eq!(s.faces, 2237);
    for (class, (ok, n)) in &s.per_class {
        assert_eq!(ok, n, "{class}: {ok}/{n}");
    }
    assert_eq!(s.correct, s.faces);
}

/// The full orchestrator (walls first), up = +z.
#[test]
fn mfcad_face_accuracy() {
    let Some(dir) = data() else { return };
    let s = score_mfcad_with(&dir, read);
    show(&s);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert_eq!(s.parts, 100);
    // Below the depressions-alone 100 % only by the faces the wall
    // recogniser claims (thin slabs between features read as walls).
    assert!(s.overall() >= 0.89, "{}", s.overall());
}
