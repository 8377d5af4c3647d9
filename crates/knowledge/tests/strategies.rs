//! `strategies.ron`: the blocks as the thesis has them, and broken files.

use std::path::{Path, PathBuf};

use thinplan_knowledge::*;

fn text() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge/strategies.ron"),
    )
    .unwrap()
}

#[test]
fn ribs_and_flanges_choose_a_side_then_step_webs_face_mill() {
    let k = Knowledge::builtin().unwrap();
    let wall = k.strategies.for_role(StrategyRole::Rib).unwrap();
    assert_eq!(k.strategies.for_role(StrategyRole::Flange), Some(wall));
    assert!(matches!(wall.blocks[0], Block::SideChoice(_)));
    // The influences of connected features, read before the steps.
    assert!(matches!(wall.blocks[1], Block::ConnectedWalls(_)));
    assert!(matches!(wall.blocks[2], Block::Cutouts(_)));
    match &wall.blocks[3] {
        Block::LargeHoles(h) => {
            // §4.1.3 "Holes": large above 1.5 · D, the line 2 · D below the top.
            assert_eq!(h.large_above_tool_diameters, 1.5);
            assert_eq!(h.separation_in_tool_diameters, 2.0);
        }
        b => panic!("{b:?}"),
    }
    assert!(matches!(wall.blocks.last(), Some(Block::WallSteps(_))));
    let web = k.strategies.for_role(StrategyRole::Web).unwrap();
    assert!(matches!(web.blocks[0], Block::WebFaceMill(_)));
}

#[test]
fn a_misspelt_block_names_file_line_and_column() {
    let broken = text().replace("WallSteps((", "WallStep((");
    let line = broken
        .lines()
        .position(|l| l.contains("WallStep(("))
        .unwrap()
        + 1;
    let e = parse_ron::<StrategyKnowledge>(&broken, &PathBuf::from("strategies.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("strategies.ron"), "{e}");
    assert!(e.contains(&format!("{line}:")), "line {line} in {e}");
}

#[test]
fn side_choice_after_the_steps_and_bad_numbers_are_refused() {
    let mut k: StrategyKnowledge = parse_ron(&text(), &PathBuf::from("strategies.ron")).unwrap();
    assert!(k.problems().is_empty(), "{:?}", k.problems());
    let last = k.strategies[0].blocks.len() - 1;
    k.strategies[0].blocks.swap(0, last);
    if let Block::WebFaceMill(f) = &mut k.strategies[1].blocks[0] {
        f.layer_depth = 0.0;
    }
    let p = k.problems();
    assert!(
        p.iter().any(|m| m.contains("comes after the wall steps")),
        "{p:?}"
    );
    assert!(p.iter().any(|m| m.contains("layer_depth 0")), "{p:?}");
    k.strategies[1].roles.push(StrategyRole::Rib);
    assert!(k
        .problems()
        .iter()
        .any(|m| m.contains("already has strategy")));
}

#[test]
fn influences_after_the_steps_on_webs_or_with_bad_numbers_are_refused() {
    let mut k: StrategyKnowledge = parse_ron(&text(), &PathBuf::from("strategies.ron")).unwrap();
    let blocks = &mut k.strategies[0].blocks;
    let holes = blocks.remove(3);
    blocks.push(holes);
    if let Block::Cutouts(c) = &mut blocks[2] {
        c.large_deeper_than_h = -1.0;
    }
    if let Block::ConnectedWalls(c) = blocks[1].clone() {
        k.strategies[1].blocks.push(Block::ConnectedWalls(c));
    }
    let p = k.problems();
    assert!(
        p.iter()
            .any(|m| m.contains("`large_holes` comes after the wall steps")),
        "{p:?}"
    );
    assert!(
        p.iter().any(|m| m.contains("large_deeper_than_h -1")),
        "{p:?}"
    );
    assert!(
        p.iter()
            .any(|m| m.contains("applies to standing walls, not webs")),
        "{p:?}"
    );
}
