//! MFCAD face accuracy (see `crates/recognise/MFCAD.md`).

use std::path::{Path, PathBuf};

use thinplan_brep::Brep;
use thinplan_recognise::mfcad::{score_mfcad_depressions_with, score_mfcad_with, MfcadScore};

fn data() -> Option<PathBuf> {
    thinplan_testdata::data_dir("mfcad")
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

/// The full orchestrator (walls, then depressions on all faces), up = +z.
#[test]
fn mfcad_face_accuracy() {
    let Some(dir) = data() else { return };
    let s = score_mfcad_with(&dir, read);
    show(&s);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert_eq!(s.parts, 100);
    // Walls and depressions share faces; a face scores as the depression
    // holding it. 6 faces stay stock by "the wall wins": in 0-6-10-12-19 a
    // through step whose floor is a web's face and whose side is a 1.26 mm
    // flange's side (an L section: the space beside a wall on its web), and
    // in 2-6-6-13-14-23 a rectangular passage whose four sides are all sides
    // of thin walls (the bore of a square tube; reported as a warning).
    assert_eq!(s.correct, 2231, "{}", s.overall());
    assert_eq!(s.faces - s.correct, 6);
}
