use std::path::{Path, PathBuf};

use thinplan_knowledge::*;

fn repo_knowledge() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge")
}

#[test]
fn repository_knowledge_loads_and_equals_the_embedded_copy() {
    let dir = Knowledge::load_dir(&repo_knowledge()).unwrap();
    let builtin = Knowledge::builtin().unwrap();
    assert_eq!(dir.machines, builtin.machines);
    assert_eq!(dir.tool_sets, builtin.tool_sets);
    assert_eq!(dir.materials, builtin.materials);
    assert_eq!(dir.sizing, builtin.sizing);
    // Everything else too (the whole value but its origin).
    let mut same = builtin.clone();
    same.origin = dir.origin.clone();
    assert_eq!(dir, same);
    assert!(dir.machine(DEFAULT_MACHINE).is_some());
    let tools = dir.tool_set(DEFAULT_TOOL_SET).unwrap();
    let mut diameters: Vec<f64> = tools.tools.iter().map(|t| t.diameter).collect();
    diameters.sort_by(f64::total_cmp);
    diameters.dedup();
    assert_eq!(diameters, vec![6.0, 8.0, 10.0, 12.0, 16.0, 20.0]);
    assert_eq!(
        dir.material(DEFAULT_MATERIAL).unwrap().youngs_modulus,
        71000.0
    );
}

fn copy_of_knowledge(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("thinplan-knowledge-{tag}-{}", std::process::id()));
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

#[test]
fn syntax_error_names_file_line_and_column() {
    let d = copy_of_knowledge("syntax");
    let f = d.join("materials/al7075.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    // Line 5 of the file is `youngs_modulus: 71000.0,`; break its value.
    let line = text
        .lines()
        .position(|l| l.contains("youngs_modulus"))
        .unwrap()
        + 1;
    std::fs::write(&f, text.replace("71000.0", "seventy")).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    assert_eq!(errors.len(), 1, "{errors:?}");
    let msg = errors[0].to_string();
    assert!(msg.contains("al7075.ron"), "{msg}");
    assert!(msg.contains(&format!(":{line}:")), "{msg}");
}

#[test]
fn unknown_field_is_refused_with_its_name() {
    let d = copy_of_knowledge("unknown");
    let f = d.join("machines/hsm_5axis.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    std::fs::write(&f, text.replace("spindle_power_kw", "spindle_powr_kw")).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let msg = errors[0].to_string();
    assert!(
        msg.contains("spindle_powr_kw") && msg.contains("hsm_5axis.ron"),
        "{msg}"
    );
}

#[test]
fn all_problems_are_reported_in_one_run() {
    let d = copy_of_knowledge("many");
    // A duplicate machine id, a syntax error in a material, a bad tool value.
    std::fs::copy(
        d.join("machines/hsm_5axis.ron"),
        d.join("machines/copy.ron"),
    )
    .unwrap();
    std::fs::write(d.join("materials/broken.ron"), "( id: \"x\", ").unwrap();
    let t = d.join("tools/endmills_12_20.ron");
    let text = std::fs::read_to_string(&t).unwrap();
    std::fs::write(&t, text.replacen("diameter: 12.0", "diameter: -12.0", 1)).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let all: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert!(
        all.iter().any(|m| m.contains("duplicate id `hsm_5axis`")),
        "{all:?}"
    );
    assert!(all.iter().any(|m| m.contains("broken.ron:")), "{all:?}");
    assert!(
        all.iter()
            .any(|m| m.contains("diameter -12 must lie in [0.2, 250]")),
        "{all:?}"
    );
}

#[test]
fn machine_reach_follows_its_kinematics() {
    let k = Knowledge::builtin().unwrap();
    let mut m = k.machine(DEFAULT_MACHINE).unwrap().clone();
    let side = glam::DVec3::X;
    let under = -glam::DVec3::Z;
    assert!(m.reaches(glam::DVec3::Z));
    assert!(m.reaches(side));
    assert!(!m.reaches(under));
    m.kinematics = Kinematics::ThreeAxis;
    assert!(m.reaches(glam::DVec3::Z));
    assert!(!m.reaches(side));
}

#[test]
fn sizing_holds_the_table_a2_constants() {
    let s = Knowledge::load_dir(&repo_knowledge()).unwrap().sizing;
    assert_eq!(s.allowed_deflection, 0.01);
    assert_eq!(s.effective_length_factor, 4.0);
    assert_eq!(s.max_milling_force, 200.0);
    assert_eq!(s.preferred_tool_diameter, 12.0);
    assert_eq!(s.initial_height_ratio, 2);
    let p = &s.peripheral;
    assert_eq!(p.danger_zone_factor, 0.75);
    assert_eq!(p.finishing_width_of_cut, 2.0);
    assert_eq!(p.roughing_stepover, 0.75);
    assert_eq!(p.finishing_depth_of_cut, 1.5);
    assert_eq!(p.initial_finishing_cuts_in_h, 8);
    assert_eq!(p.min_cuts_in_width, 2);
    let f = &s.face;
    assert_eq!(f.danger_zone_factor, 0.5);
    assert_eq!(f.finishing_depth_of_cut, 2.0);
    assert_eq!(f.roughing_depth_of_cut, 4.0);
    assert_eq!(
        f.finishing_width_of_cut_factor * 12.0 + f.finishing_width_of_cut_extra,
        7.0
    );
    assert_eq!(f.initial_finishing_cuts_in_h, 3);
    assert_eq!(f.min_cuts_in_width, 3);
    assert!(s.tall_wall.is_some());
    assert!(s.problems().is_empty(), "{:?}", s.problems());
}

#[test]
fn bad_sizing_values_are_refused_with_clear_messages() {
    let d = copy_of_knowledge("sizing-values");
    let f = d.join(SIZING_FILE);
    let text = std::fs::read_to_string(&f).unwrap();
    let text = text
        .replace("allowed_deflection: 0.01", "allowed_deflection: -0.01")
        .replace("roughing_stepover: 0.75", "roughing_stepover: 1.5")
        .replace("max_big_h_over_h: 3.0", "max_big_h_over_h: 1.5");
    std::fs::write(&f, text).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let all: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(all.len(), 3, "{all:?}");
    assert!(
        all.iter()
            .any(|m| m.contains("`allowed_deflection` -0.01 must lie in (0, 10]")),
        "{all:?}"
    );
    assert!(
        all.iter()
            .any(|m| m.contains("`peripheral.roughing_stepover` 1.5") && m.contains("[0.01, 1]")),
        "{all:?}"
    );
    assert!(
        all.iter()
            .any(|m| m.contains("`initial_height_ratio` (2) exceeds")),
        "{all:?}"
    );
    assert!(all.iter().all(|m| m.contains("sizing")), "{all:?}");
}

#[test]
fn sizing_syntax_and_unknown_fields_point_at_the_file() {
    let d = copy_of_knowledge("sizing-syntax");
    let f = d.join(SIZING_FILE);
    let text = std::fs::read_to_string(&f).unwrap();
    std::fs::write(&f, text.replace("max_milling_force", "max_miling_force")).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let msg = errors[0].to_string();
    assert!(
        msg.contains("max_miling_force") && msg.contains("sizing.ron:"),
        "{msg}"
    );
}

#[test]
fn a_directory_without_a_root_file_is_refused_naming_it() {
    for name in ROOT_FILES {
        let d = copy_of_knowledge(&format!("absent-{name}"));
        std::fs::remove_file(d.join(name)).unwrap();
        let errors = Knowledge::load_dir(&d).unwrap_err();
        assert_eq!(errors.len(), 1, "{errors:?}");
        let msg = errors[0].to_string();
        assert!(msg.contains(&format!("missing {name}")), "{msg}");
    }
}

#[test]
fn tall_wall_rule_reads_the_test_10_remark() {
    let rule = Knowledge::builtin().unwrap().sizing.tall_wall.unwrap();
    // 48 mm wall, h = 12: not tall, H = 4·h allowed.
    assert!(rule.allows(48.0, 12.0, 48.0));
    // 72 mm wall, h = 12: tall; H = 36 (3·h) allowed, H = 48 (4·h) not.
    assert!(rule.allows(72.0, 12.0, 36.0));
    assert!(!rule.allows(72.0, 12.0, 48.0));
    // H = H_w is left to the bending model.
    assert!(rule.allows(60.0, 12.0, 60.0));
}

#[test]
fn both_posts_load_and_linuxcnc_is_the_default() {
    let k = Knowledge::builtin().unwrap();
    assert!(k.post(DEFAULT_POST).is_some());
    assert_eq!(k.posts.keys().collect::<Vec<_>>(), ["fanuc", "linuxcnc"]);
    for p in k.posts.values() {
        assert!(p.problems().is_empty(), "{:?}", p.problems());
    }
}

#[test]
fn a_directory_without_posts_still_loads() {
    let d = copy_of_knowledge("no-posts");
    std::fs::remove_dir_all(d.join("posts")).unwrap();
    let k = Knowledge::load_dir(&d).unwrap();
    assert!(k.posts.is_empty());
}

#[test]
fn a_misspelt_post_block_variant_names_file_line_and_column() {
    let d = copy_of_knowledge("post-variant");
    let f = d.join("posts/fanuc.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("Raw(\"O0001\")"))
        .unwrap()
        + 1;
    std::fs::write(&f, text.replace("Raw(\"O0001\")", "Raww(\"O0001\")")).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    assert_eq!(errors.len(), 1, "{errors:?}");
    let msg = errors[0].to_string();
    assert!(msg.contains("fanuc.ron"), "{msg}");
    assert!(msg.contains(&format!(":{line}:")), "{msg}");
    assert!(msg.contains("Raww"), "{msg}");
}

#[test]
fn an_unknown_post_placeholder_names_the_file_post_and_field() {
    let d = copy_of_knowledge("post-placeholder");
    let f = d.join("posts/linuxcnc.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    let text = text
        .replace("T{tool} M6", "T{tol} M6")
        // An operation placeholder where only program ones are known.
        .replace("Code(\"M2\")", "Code(\"M2 {rpm}\")")
        .replace("chord_tolerance: 0.005", "chord_tolerance: -1.0");
    std::fs::write(&f, text).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let all: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(all.len(), 3, "{all:?}");
    assert!(
        all.iter()
            .all(|m| m.contains("linuxcnc.ron") && m.contains("post `linuxcnc`")),
        "{all:?}"
    );
    assert!(
        all.iter()
            .any(|m| m.contains("tool_change[0]") && m.contains("unknown placeholder `{tol}`")),
        "{all:?}"
    );
    assert!(
        all.iter().any(|m| m.contains("program_end[0]")
            && m.contains("`{rpm}`")
            && m.contains("known only in")),
        "{all:?}"
    );
    assert!(all.iter().any(|m| m.contains("chord_tolerance")), "{all:?}");
}

#[test]
fn an_unknown_post_field_and_a_duplicate_post_id_are_refused() {
    let d = copy_of_knowledge("post-field");
    let f = d.join("posts/fanuc.ron");
    let text = std::fs::read_to_string(&f).unwrap();
    std::fs::write(&f, text.replace("feed_decimals", "feed_decimal")).unwrap();
    std::fs::copy(d.join("posts/linuxcnc.ron"), d.join("posts/linuxcnc2.ron")).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let all: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert!(
        all.iter()
            .any(|m| m.contains("fanuc.ron:") && m.contains("feed_decimal")),
        "{all:?}"
    );
    assert!(
        all.iter()
            .any(|m| m.contains("linuxcnc2.ron") && m.contains("duplicate id `linuxcnc`")),
        "{all:?}"
    );
}

#[test]
fn broken_methods_are_refused_with_every_problem() {
    let d = copy_of_knowledge("methods");
    let f = d.join(METHODS_FILE);
    let text = std::fs::read_to_string(&f).unwrap();
    // Half the tool diameter is the most a tool may cross into a neighbour;
    // a plunge (0°) is no entry; the closed-pocket method removed leaves
    // closed profiles without a method.
    // A rest pass needs a positive corner-radius gain, a wall rest pass a
    // positive thickness, and a method without product sides (no boundary
    // region) no wall rest pass.
    let open_method = "            boundary: None,\n            rest: (stepover: 0.6, depth: 0.5),\n            full_cut: Never,\n            mirror_layers: WhenOddPasses,\n            bottom_layer: None,\n";
    assert!(
        text.contains(open_method),
        "the `open` method's block moved"
    );
    let broken = text
        .replacen("feature: 0.5", "feature: 0.8", 1)
        .replacen("Ramp(angle_deg: 3.0)", "Ramp(angle_deg: 0.0)", 1)
        .replacen("min_corner_gain: 0.1", "min_corner_gain: -0.1", 1)
        .replacen("min_left: 0.1", "min_left: 0.0", 1)
        .replacen("fit_scales: [1.0, 0.5, 0.25]", "fit_scales: [0.5, 1.0]", 1)
        .replacen("run_off_radius: 0.25", "run_off_radius: 0.0", 1)
        .replacen(
            open_method,
            &format!(
                "{open_method}            wall_rest: Some((min_left: 0.1, run_up: Circular(radius: 0.25), run_last: true)),\n"
            ),
            1,
        );
    let cut = broken.find("id: \"closed_pocket\"").unwrap();
    let start = broken[..cut].rfind("        (").unwrap();
    let end = broken.rfind("    ],").unwrap();
    let broken = format!("{}{}", &broken[..start], &broken[end..]);
    std::fs::write(&f, broken).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let all: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    let text = all.join("\n");
    assert!(text.contains("overhang.feature 0.8"), "{text}");
    assert!(text.contains("entry angle 0°"), "{text}");
    assert!(text.contains("Closed sides"), "{text}");
    assert!(text.contains("min_corner_gain -0.1"), "{text}");
    assert!(
        text.contains(
            "fit_scales [0.5, 1.0] must be one or more fractions in (0, 1], largest first"
        ),
        "{text}"
    );
    assert!(
        text.contains("run_off_radius 0 must lie in (0, 10]"),
        "{text}"
    );
    assert!(
        text.contains("wall_rest min_left 0 must lie in (0, 100]"),
        "{text}"
    );
    assert!(
        text.contains("method `open`: a wall_rest finishes product walls"),
        "{text}"
    );
    assert!(text.contains("methods.ron"), "{text}");
}

#[test]
fn a_misspelt_method_field_names_the_file() {
    let d = copy_of_knowledge("methods-field");
    let f = d.join(METHODS_FILE);
    let text = std::fs::read_to_string(&f).unwrap();
    std::fs::write(&f, text.replacen("corner_rounding:", "corner_roundin:", 1)).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    let text: String = errors.iter().map(|e| format!("{e:?} {e}")).collect();
    assert!(text.contains("corner_roundin"), "{text}");
    assert!(text.contains("methods.ron"), "{text}");
}

#[test]
fn every_adjacency_finds_a_method() {
    let k = Knowledge::builtin().unwrap();
    for bottom in [true, false] {
        for sides in [
            SidesMatch::Open,
            SidesMatch::PartiallyOpen,
            SidesMatch::Closed,
        ] {
            assert!(k.methods.for_feature(bottom, sides).is_some());
        }
    }
    assert!(k.methods.problems().is_empty());
}
