//! Values that parse but would panic, hang or print `F0` are refused, each
//! at its file:line:column like a syntax error (the knowledge-sanity issue).

use std::path::{Path, PathBuf};

use thinplan_knowledge::*;

fn repo_knowledge() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge")
}

/// A copy of the repository's knowledge in a fresh temporary directory.
fn copy_of_knowledge(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("thinplan-ranges-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    for sub in ITEM_FOLDERS {
        std::fs::create_dir_all(d.join(sub)).unwrap();
        for e in std::fs::read_dir(repo_knowledge().join(sub)).unwrap() {
            let p = e.unwrap().path();
            std::fs::copy(&p, d.join(sub).join(p.file_name().unwrap())).unwrap();
        }
    }
    for name in ROOT_FILES {
        std::fs::copy(repo_knowledge().join(name), d.join(name)).unwrap();
    }
    d
}

/// Replaces the first `from` by `to` in `file` of a copy, loads it and
/// returns every message with the 1-based line and column of the value.
fn broken(tag: &str, file: &str, edits: &[(&str, &str)], at: &str) -> (Vec<String>, usize, usize) {
    let d = copy_of_knowledge(tag);
    let f = d.join(file);
    let mut text = std::fs::read_to_string(&f).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{file} has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    std::fs::write(&f, &text).unwrap();
    // The value of the first `at` (a `name: value`) after the edits.
    let line = text.lines().position(|l| l.contains(at)).unwrap();
    let l = text.lines().nth(line).unwrap();
    let col = l[..l.find(at).unwrap()].chars().count() + at.find(": ").unwrap() + 3;
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let _ = std::fs::remove_dir_all(&d);
    (
        errors.iter().map(|e| e.to_string()).collect(),
        line + 1,
        col,
    )
}

/// One value made bad: the message names the file, the value's line and
/// column, the field, the value and the range.
fn refused(tag: &str, file: &str, from: &str, to: &str, needle: &str) {
    let (all, line, col) = broken(tag, file, &[(from, to)], to);
    let name = Path::new(file).file_name().unwrap().to_string_lossy();
    let place = format!("{name}:{line}:{col}: ");
    assert!(
        all.iter()
            .any(|m| m.contains(&*place) && m.contains(needle)),
        "no `{place}…{needle}` in {all:#?}"
    );
}

#[test]
fn zero_flutes_are_refused_at_their_line() {
    refused(
        "flutes",
        "tools/endmills_12_20.ron",
        "flutes: 2",
        "flutes: 0",
        "tool `em12` in set `endmills_12_20`: flutes 0 must lie in 1..=16",
    );
}

#[test]
fn a_tiny_rest_stepover_is_refused_at_its_line() {
    refused(
        "stepover",
        "methods.ron",
        "stepover: 0.6",
        "stepover: 0.000001",
        "method `partially_open_product_floor`: rest.stepover 0.000001 must lie in [0.01, 1]",
    );
}

#[test]
fn a_tiny_rest_depth_is_refused_at_its_line() {
    refused(
        "depth",
        "methods.ron",
        "depth: 0.5",
        "depth: 0.0001",
        "rest.depth 0.0001 must lie in [0.01, 10]",
    );
}

#[test]
fn zero_cutting_speed_and_feed_are_refused_at_their_lines() {
    refused(
        "vc",
        "materials/al7075.ron",
        "cutting_speed: 1000.0",
        "cutting_speed: 0.0",
        "material `al7075`: cutting.cutting_speed 0 must lie in [1, 10000]",
    );
    refused(
        "fz",
        "materials/al7075.ron",
        "feed_per_tooth_roughing: 0.22",
        "feed_per_tooth_roughing: 0.0",
        "cutting.feed_per_tooth_roughing 0 must lie in [0.001, 2]",
    );
    refused(
        "link",
        "methods.ron",
        "link_feed_factor: 1.0",
        "link_feed_factor: 0.0",
        "link_feed_factor 0 must lie in [0.01, 10]",
    );
}

#[test]
fn nan_and_infinity_are_refused() {
    refused(
        "nan",
        "machines/hsm_5axis.ron",
        "a_centripetal: 5000.0",
        "a_centripetal: NaN",
        "machine `hsm_5axis`: a_centripetal NaN must lie in (0, 200000]",
    );
    refused(
        "inf",
        "recognition_walls.ron",
        "max_thickness: 8.0",
        "max_thickness: inf",
        "max_thickness inf must lie in (0, 1000]",
    );
}

#[test]
fn a_negative_diameter_is_refused_at_its_line() {
    refused(
        "diameter",
        "tools/endmills_12_20.ron",
        "diameter: 12.0",
        "diameter: -12.0",
        "diameter -12 must lie in [0.2, 250]",
    );
}

#[test]
fn values_in_every_root_file_point_at_their_line() {
    let cases = [
        (
            "sizing.ron",
            "finishing_depth_of_cut: 1.5",
            "finishing_depth_of_cut: 0.0",
            "`peripheral.finishing_depth_of_cut` 0 must lie in [0.01, 1000]",
        ),
        (
            "interference.ron",
            "sliver_area: 0.0001",
            "sliver_area: -1.0",
            "`sliver_area` -1 must lie in [0, 1000000]",
        ),
        (
            "strategies.ron",
            "layer_depth: 4.0",
            "layer_depth: 0.0",
            "block `web_face_mill`: layer_depth 0 must lie in [0.01, 1000]",
        ),
        (
            "strategies.ron",
            "max_tilt_deg: 25.84",
            "max_tilt_deg: 95.0",
            "block `web_face_mill`: max_tilt_deg 95 must lie in [0, 89]",
        ),
        (
            "sequencing.ron",
            "within_deg: 20.0",
            "within_deg: 70.0",
            "`Junction.within_deg` must lie in 0..=45 degrees, not 70",
        ),
        (
            "recognition_depressions.ron",
            "max_fillet_radius: 20.0",
            "max_fillet_radius: -1.0",
            "max_fillet_radius -1 must lie in (0, 10000]",
        ),
        (
            "posts/linuxcnc.ron",
            "chord_tolerance: 0.005",
            "chord_tolerance: -1.0",
            "post `linuxcnc`: arcs.chord_tolerance must be a positive number",
        ),
    ];
    for (i, (file, from, to, needle)) in cases.into_iter().enumerate() {
        refused(&format!("root{i}"), file, from, to, needle);
    }
}

#[test]
fn every_problem_of_one_file_is_reported_in_one_run() {
    let (all, _, _) = broken(
        "many",
        "tools/endmills_12_20.ron",
        &[
            ("flutes: 2", "flutes: 0"),
            ("stickout: 80.0", "stickout: 20.0"),
            ("holder_diameter: 50.0", "holder_diameter: 10.0"),
        ],
        "flutes: 0",
    );
    assert_eq!(all.len(), 3, "{all:#?}");
    assert!(all
        .iter()
        .any(|m| m.contains("stickout 20 must lie in [30, 1000]")));
    assert!(all
        .iter()
        .any(|m| m.contains("holder_diameter 10 must lie in [20, 1000]")));
}

#[test]
fn feeds_that_would_print_f0_are_refused() {
    let (all, line, col) = broken(
        "f0",
        "materials/al7075.ron",
        &[
            ("cutting_speed: 1000.0", "cutting_speed: 1.0"),
            (
                "feed_per_tooth_finishing: 0.12",
                "feed_per_tooth_finishing: 0.001",
            ),
        ],
        "feed_per_tooth_finishing: 0.001",
    );
    let place = format!("al7075.ron:{line}:{col}: ");
    assert!(
        all.iter()
            .any(|m| m.contains(&place) && m.contains("would print F0") && m.contains("`em20`")),
        "{all:#?}"
    );
}

#[test]
fn a_neck_must_be_thinner_than_the_cutter_and_end_below_the_holder() {
    refused(
        "neck",
        "tools/alu_hsm.ron",
        "neck_diameter: 5.7",
        "neck_diameter: 6.5",
        "tool `lr6_r05_30` in set `alu_hsm`: neck_diameter 6.5 must lie in (0, 6)",
    );
    refused(
        "reach",
        "tools/alu_hsm.ron",
        "reach: 30.0",
        "reach: 60.0",
        "reach 60 must lie in [9, 48]",
    );
    let (all, line, col) = broken(
        "reach-alone",
        "tools/alu_hsm.ron",
        &[("            neck_diameter: 5.7,\n", "")],
        "reach: 30.0",
    );
    let place = format!("alu_hsm.ron:{line}:{col}: ");
    assert!(
        all.iter()
            .any(|m| m.contains(&place) && m.contains("a reach needs its neck_diameter")),
        "{all:#?}"
    );
}

#[test]
fn the_aluminium_set_is_the_default() {
    let k = Knowledge::load_dir(&repo_knowledge()).unwrap();
    assert_eq!(DEFAULT_TOOL_SET, "alu_hsm");
    let set = k.tool_set("alu_hsm").unwrap();
    let mut ds: Vec<f64> = set
        .tools
        .iter()
        .filter(|t| t.neck_diameter.is_none() && t.kind != ToolKind::BallEndMill)
        .map(|t| t.diameter)
        .collect();
    ds.sort_by(f64::total_cmp);
    assert_eq!(ds, [6.0, 8.0, 10.0, 12.0, 16.0, 20.0]);
    let reaches: Vec<(f64, f64)> = set
        .tools
        .iter()
        .filter_map(|t| t.reach.map(|r| (t.diameter, r)))
        .collect();
    assert_eq!(
        reaches,
        [(6.0, 30.0), (8.0, 40.0), (10.0, 50.0), (12.0, 65.0)]
    );
    assert!(set.tools.iter().any(|t| t.kind == ToolKind::BallEndMill));
}

#[test]
fn the_radius_profile_steps_from_cutter_to_neck_shank_and_holder() {
    let k = Knowledge::builtin().unwrap();
    let set = k.tool_set("alu_hsm").unwrap();
    let t = set.tools.iter().find(|t| t.id == "lr6_r05_30").unwrap();
    assert_eq!(
        t.radius_profile(),
        [(9.0, 3.0), (30.0, 2.85), (48.0, 3.0), (168.0, 10.5)]
    );
    assert_eq!(t.radius_at(-1.0), 0.0);
    assert_eq!(t.radius_at(5.0), 3.0);
    assert_eq!(t.radius_at(20.0), 2.85);
    assert_eq!(t.radius_at(40.0), 3.0);
    assert_eq!(t.radius_at(48.0), 10.5);
    assert_eq!(t.radius_at(500.0), 10.5);
    // Without a neck the shank follows the flutes.
    let em = set.tools.iter().find(|t| t.id == "em12_r1").unwrap();
    assert_eq!(
        em.radius_profile(),
        [(26.0, 6.0), (45.0, 6.0), (125.0, 12.0)]
    );
}

#[test]
fn a_grid_shift_outside_a_cell_is_refused_at_its_line() {
    refused(
        "grid_shift",
        "verification.ron",
        "grid_shifts: [0.0, 0.45]",
        "grid_shifts: [0.0, 1.5]",
        "a grid shift is 1.5; each must lie in [0, 1)",
    );
}

#[test]
fn no_replay_grid_is_refused_at_its_line() {
    refused(
        "no_grid",
        "verification.ron",
        "grid_shifts: [0.0, 0.45]",
        "grid_shifts: []",
        "`grid_shifts` has 0 grids; it needs 1 to 4",
    );
}
