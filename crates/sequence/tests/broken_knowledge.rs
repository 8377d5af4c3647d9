//! A catalogue of broken `sequencing.ron` files: each is refused with the
//! file and line:column (syntax and shape, from the parser) or the rule id
//! (checks the parser cannot make).

mod common;

use std::path::Path;

use common::*;
use thinplan_knowledge::{parse_ron, Knowledge, KnowledgeError, SequencingKnowledge};

const PATH: &str = "knowledge/sequencing.ron";

/// The repository file with `from` replaced by `to` (exactly once).
fn broken(from: &str, to: &str) -> String {
    let text = repo_sequencing_text();
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
    text.replacen(from, to, 1)
}

/// 1-based line of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// Parses and expects a syntax error; returns (line, column, message).
fn syntax_error(text: &str) -> (usize, usize, String) {
    match parse_ron::<SequencingKnowledge>(text, Path::new(PATH)) {
        Err(e @ KnowledgeError::Syntax { .. }) => {
            let KnowledgeError::Syntax { line, column, .. } = &e else {
                unreachable!()
            };
            let msg = e.to_string();
            assert!(
                msg.starts_with(&format!("{PATH}:{line}:{column}: ")),
                "{msg}"
            );
            eprintln!("{msg}");
            (*line, *column, msg)
        }
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

#[test]
fn a_misspelt_action_names_the_variant_and_its_place() {
    let text = broken(
        "then: Simultaneous,\n            note: \"a depression",
        "then: Simultanous,\n            note: \"a depression",
    );
    let (line, column, msg) = syntax_error(&text);
    assert_eq!(line, line_of(&text, "Simultanous"));
    assert!(column > 1);
    assert!(msg.contains("Simultanous"), "{msg}");
}

#[test]
fn a_misspelt_condition_atom_names_it() {
    let text = broken("Higher(level: Bottom", "Highr(level: Bottom");
    let (line, _, msg) = syntax_error(&text);
    assert_eq!(line, line_of(&text, "Highr"));
    assert!(msg.contains("Highr"), "{msg}");
}

#[test]
fn a_misspelt_role_names_it() {
    let text = broken("First(Role([Flange]))", "First(Role([Flang]))");
    let (line, _, msg) = syntax_error(&text);
    assert_eq!(line, line_of(&text, "Flang]"));
    assert!(msg.contains("Flang"), "{msg}");
}

#[test]
fn an_unknown_field_names_it() {
    let text = broken("priority: 30,", "priority: 30,\n            weight: 2,");
    let (line, _, msg) = syntax_error(&text);
    assert_eq!(line, line_of(&text, "weight"));
    assert!(msg.contains("weight"), "{msg}");
}

#[test]
fn an_unknown_field_in_an_atom_names_it() {
    let text = broken(
        "Junction(runs: Vertical, within_deg: 20.0)",
        "Junction(runs: Vertical, within: 20.0)",
    );
    let (line, _, msg) = syntax_error(&text);
    assert_eq!(line, line_of(&text, "within: 20.0"));
    assert!(msg.contains("within"), "{msg}");
}

#[test]
fn a_missing_field_names_it() {
    let text = broken("            priority: 40,\n", "");
    let (line, _, msg) = syntax_error(&text);
    assert!(msg.contains("priority"), "{msg}");
    // The parser points at the end of the rule that lacks it.
    let rule = line_of(&text, "id: \"depression_with_wall\"");
    assert!(
        line >= rule && line <= rule + 12,
        "line {line}, rule at {rule}"
    );
}

#[test]
fn a_duplicate_priority_names_both_rules() {
    let text = broken("priority: 40,", "priority: 50,");
    let k: SequencingKnowledge = parse_ron(&text, Path::new(PATH)).unwrap();
    let p = k.problems();
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].contains("`depression_with_wall`"), "{}", p[0]);
    assert!(p[0].contains("duplicate priority 50"), "{}", p[0]);
    assert!(p[0].contains("`flange_before_wall`"), "{}", p[0]);
}

#[test]
fn a_duplicate_id_names_it() {
    let text = broken(
        "id: \"horizontal_rib_with_wall\"",
        "id: \"depression_with_wall\"",
    );
    let k: SequencingKnowledge = parse_ron(&text, Path::new(PATH)).unwrap();
    let p = k.problems();
    assert_eq!(p, ["rule `depression_with_wall`: duplicate id"]);
}

#[test]
fn out_of_range_numbers_and_empty_lists_name_the_rule() {
    let text = broken("by_more_than: 1.0", "by_more_than: -1.0")
        .replace(
            "within_deg: 20.0),\n            ]),\n            then: Simultaneous",
            "within_deg: 70.0),\n            ]),\n            then: Simultaneous",
        )
        .replace("at_least: 2", "at_least: 0")
        .replace("First(Depression)", "First(Kind([]))");
    let k: SequencingKnowledge = parse_ron(&text, Path::new(PATH)).unwrap();
    let p = k.problems();
    assert_eq!(p.len(), 4, "{p:#?}");
    assert!(
        p[0].starts_with("rule `depression_with_wall`: `Kind([])`"),
        "{}",
        p[0]
    );
    assert!(
        p[1].starts_with("rule `horizontal_rib_with_wall`: `Junction.within_deg`"),
        "{}",
        p[1]
    );
    assert!(
        p[2].starts_with("rule `vertical_rib_before_wall`: `SecondHasLeavesBefore.at_least`"),
        "{}",
        p[2]
    );
    assert!(
        p[3].starts_with("rule `higher_before_lower`: `Higher.by_more_than`"),
        "{}",
        p[3]
    );
}

/// Through the loader: every problem of a knowledge directory in one run,
/// naming the sequencing file.
#[test]
fn the_loader_reports_sequencing_problems_naming_the_file() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge");
    let d = std::env::temp_dir().join(format!("thinplan-sequencing-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    for sub in ["machines", "tools", "materials"] {
        std::fs::create_dir_all(d.join(sub)).unwrap();
        for e in std::fs::read_dir(repo.join(sub)).unwrap() {
            let p = e.unwrap().path();
            std::fs::copy(&p, d.join(sub).join(p.file_name().unwrap())).unwrap();
        }
    }
    for name in thinplan_knowledge::ROOT_FILES {
        std::fs::copy(repo.join(name), d.join(name)).unwrap();
    }
    let k = Knowledge::load_dir(&d).unwrap();
    assert_eq!(k.sequencing, repo_rules());

    std::fs::write(
        d.join("sequencing.ron"),
        broken("priority: 40,", "priority: 50,"),
    )
    .unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    assert_eq!(errors.len(), 1);
    let msg = errors[0].to_string();
    assert!(msg.contains("sequencing.ron"), "{msg}");
    assert!(msg.contains("duplicate priority 50"), "{msg}");

    let text = broken(
        "then: Before,\n            note: \"top-down",
        "then: Befor,\n            note: \"top-down",
    );
    std::fs::write(d.join("sequencing.ron"), &text).unwrap();
    let errors = Knowledge::load_dir(&d).unwrap_err();
    assert_eq!(errors.len(), 1);
    let msg = errors[0].to_string();
    let line = line_of(&text, "Befor,");
    assert!(
        msg.starts_with(&format!("{}:{line}:", d.join("sequencing.ron").display())),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
