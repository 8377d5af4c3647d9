//! Interference knowledge is data: broken files are refused with their
//! place, and changing the rules changes the plan as it should.

use std::path::{Path, PathBuf};

use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{make_setup, Session, SetupRequest};
use thinplan_plan::Stage;

fn copy_knowledge(tag: &str) -> PathBuf {
    let from = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge");
    let to = std::env::temp_dir().join(format!("thinplan-resolve-k-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&to);
    copy(&from, &to);
    to
}

fn copy(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}

fn edit(dir: &Path, from: &str, to: &str) {
    let f = dir.join("interference.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    assert!(text.contains(from), "{from}");
    std::fs::write(&f, text.replacen(from, to, 1)).unwrap();
}

fn errors(dir: &Path) -> String {
    Knowledge::load_dir(dir)
        .expect_err("refused")
        .iter()
        .map(|e| format!("{e:?} {e}"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_misspelt_selector_names_file_line_and_column() {
    let d = copy_knowledge("misspelt");
    edit(
        &d,
        "select: Block(block: \"wall_steps\", large: Some(false))",
        "select: Blok(block: \"wall_steps\", large: Some(false))",
    );
    let e = errors(&d);
    assert!(e.contains("interference.ron"), "{e}");
    assert!(e.contains("Blok"), "{e}");
    // The line of the misspelt variant (1-based) appears in the message.
    let text = std::fs::read_to_string(d.join("interference.ron")).unwrap();
    let line = text.lines().position(|l| l.contains("Blok")).unwrap() + 1;
    assert!(e.contains(&format!("{line}:")), "line {line} not in {e}");
}

#[test]
fn an_unknown_block_a_missing_field_and_bad_numbers_are_refused() {
    let d = copy_knowledge("unknown-block");
    edit(&d, "block: \"web_face_mill\"", "block: \"web_face_mil\"");
    let e = errors(&d);
    assert!(
        e.contains("web_face_mil") && e.contains("no strategy"),
        "{e}"
    );

    let d = copy_knowledge("missing");
    edit(&d, "tie_break: ThinnerOwner,", "");
    let e = errors(&d);
    assert!(e.contains("tie_break"), "{e}");

    let d = copy_knowledge("numbers");
    edit(
        &d,
        "sloped_slab_thickness: 0.5",
        "sloped_slab_thickness: -1.0",
    );
    edit(
        &d,
        "remaining_owners: [Depression, Web, NearestWall]",
        "remaining_owners: []",
    );
    let e = errors(&d);
    assert!(
        e.contains("sloped_slab_thickness") && e.contains("remaining_owners"),
        "{e}"
    );

    // Shallow slabs: a contact spacing that is not positive, a minimum
    // above the largest thickness.
    let d = copy_knowledge("shallow");
    edit(
        &d,
        "shallow_slabs: Some((along_face: 0.5, min_thickness: 0.05))",
        "shallow_slabs: Some((along_face: 0.0, min_thickness: 0.6))",
    );
    let e = errors(&d);
    assert!(
        e.contains("shallow_slabs.along_face") && e.contains("shallow_slabs.min_thickness"),
        "{e}"
    );
    // Left out: every sloped slab is `sloped_slab_thickness` (older files).
    let d = copy_knowledge("no-shallow");
    edit(
        &d,
        "shallow_slabs: Some((along_face: 0.5, min_thickness: 0.05)),",
        "",
    );
    let k = Knowledge::load_dir(&d).expect("loads without it");
    assert!(k.interference.shallow_slabs.is_none());
}

/// Volume of the features of stage-5 rule `large` (1: large steps, 0: small).
fn step_volume(k: Knowledge, large: f64) -> (f64, usize) {
    let setup = make_setup(&SetupRequest::default(), &k).unwrap();
    let mut s = Session::open("builtin:crossing_ribs", setup, k).unwrap();
    s.run_to(Stage::Resolve, &Default::default(), |_| {})
        .unwrap();
    let v = s
        .plan
        .machining_features
        .iter()
        .filter(|f| f.provenance.values.get("large") == Some(&large))
        .map(thinplan_pipeline::report::feature_volume)
        .sum();
    (v, s.plan.machining_features.len())
}

#[test]
fn the_keep_order_decides_who_keeps_an_overlap() {
    let default = Knowledge::load_dir(&copy_knowledge("default")).unwrap();
    let d = copy_knowledge("reversed");
    // Large steps first: they now keep the overlaps the small ones kept.
    edit(&d, "id: \"small_steps\"", "id: \"small_steps_x\"");
    let text = std::fs::read_to_string(d.join("interference.ron")).unwrap();
    let swapped = text
        .replacen("large: Some(false)", "large: Some(TMP)", 1)
        .replacen("large: Some(true)", "large: Some(false)", 1)
        .replacen("large: Some(TMP)", "large: Some(true)", 1);
    std::fs::write(d.join("interference.ron"), swapped).unwrap();
    let reversed = Knowledge::load_dir(&d).unwrap();
    let (large_default, _) = step_volume(default.clone(), 1.0);
    let (large_reversed, _) = step_volume(reversed.clone(), 1.0);
    let (small_default, _) = step_volume(default, 0.0);
    let (small_reversed, _) = step_volume(reversed, 0.0);
    assert!(
        large_reversed > large_default + 1.0,
        "{large_reversed} vs {large_default}"
    );
    assert!(
        small_reversed < small_default - 1.0,
        "{small_reversed} vs {small_default}"
    );
}

#[test]
fn narrow_remaining_joins_names_blocks_that_exist() {
    let d = copy_knowledge("joins");
    edit(
        &d,
        "narrow_remaining_joins: [Block(block: \"web_face_mill\", large: None)]",
        "narrow_remaining_joins: [Block(block: \"web_face_mil\", large: None)]",
    );
    let e = errors(&d);
    assert!(
        e.contains("narrow_remaining_joins")
            && e.contains("web_face_mil")
            && e.contains("no strategy"),
        "{e}"
    );
    let text = std::fs::read_to_string(d.join("interference.ron")).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("web_face_mil\""))
        .unwrap()
        + 1;
    assert!(e.contains(&format!("{line}:")), "line {line} not in {e}");
    // Empty: narrow remaining material stays a feature of its own.
    let d = copy_knowledge("no-joins");
    edit(
        &d,
        "narrow_remaining_joins: [Block(block: \"web_face_mill\", large: None)]",
        "narrow_remaining_joins: []",
    );
    let k = Knowledge::load_dir(&d).expect("loads with none");
    assert!(k.interference.narrow_remaining_joins.is_empty());
}
