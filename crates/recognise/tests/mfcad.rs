//! MFCAD face accuracy (see `crates/recognise/MFCAD.md`).

use std::path::Path;

use thinplan_recognise::mfcad::score_mfcad_with;

#[test]
fn mfcad_face_accuracy() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mfcad");
    if !dir.is_dir() {
        println!("skipped: {} is missing", dir.display());
        return;
    }
    let s = score_mfcad_with(&dir, |p| {
        thinplan_step::read_step_file(p)
            .map(|m| m.brep)
            .map_err(|e| e.to_string())
    });
    println!("{}", s.table());
    println!("{}", s.confusion_table());
    println!(
        "wall-claimed faces: {} ({} of them feature faces)",
        s.wall_claimed_faces, s.wall_claimed_feature_faces
    );
    for m in &s.misses {
        println!("miss: {m}");
    }
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert_eq!(s.parts, 100);
}
