//! Rules whose priorities would make a cycle, and the edit API.

mod common;

use common::*;
use thinplan_plan::{Constraint, ConstraintKind, Provenance, ProvenanceSource, Stage};
use thinplan_sequence::{order, sequence, try_add};

/// Three rules around a cycle: flange before its wall, the web before the
/// ribs on it, ribs before flanges; priorities given.
fn cyclic_rules(flange: i32, web: i32, rib: i32) -> String {
    format!(
        r#"(rules: [
            (id: "flange_first", priority: {flange},
             when: All([First(Role([Flange])), Related(FirstOnSecond)]), then: Before),
            (id: "web_before_ribs", priority: {web},
             when: All([First(Role([Web])), Second(Role([Rib])), Related(SecondOnFirst)]), then: Before),
            (id: "ribs_before_flanges", priority: {rib},
             when: All([First(Role([Rib])), Second(Role([Flange]))]), then: Before),
        ])"#
    )
}

#[test]
fn the_weaker_rule_of_a_cycle_is_refused_with_the_cycle() {
    let (features, connections) = thesis_part();
    // Rib-before-flange weakest: SF3 → SF2 and SF4 → SF2 would close cycles.
    let s = sequence(
        &features,
        &connections,
        UP,
        &rules(&cyclic_rules(30, 20, 10)),
    );
    assert!(has(&s, 2, ConstraintKind::Before, 1, "flange_first"));
    assert!(has(&s, 1, ConstraintKind::Before, 3, "web_before_ribs"));
    assert!(has(&s, 1, ConstraintKind::Before, 4, "web_before_ribs"));
    assert_eq!(s.constraints.len(), 3);
    let reasons: Vec<&str> = s.refusals.iter().map(|r| r.reason.as_str()).collect();
    assert_eq!(
        reasons,
        [
            "SF3 before SF2 would close the cycle SF3 → SF2 (this rule) \
             → SF1 (sequencing.flange_first) → SF3 (sequencing.web_before_ribs)",
            "SF4 before SF2 would close the cycle SF4 → SF2 (this rule) \
             → SF1 (sequencing.flange_first) → SF4 (sequencing.web_before_ribs)",
        ]
    );
    for r in &s.refusals {
        assert_eq!(r.rule, "sequencing.ribs_before_flanges");
        assert_eq!(r.stage, Stage::Sequence);
        assert_eq!(r.provenance.values["priority"], 10.0);
    }

    // Swap priorities: now flange-first is the weakest and is refused.
    let s = sequence(
        &features,
        &connections,
        UP,
        &rules(&cyclic_rules(10, 20, 30)),
    );
    assert!(has(&s, 3, ConstraintKind::Before, 2, "ribs_before_flanges"));
    assert!(has(&s, 4, ConstraintKind::Before, 2, "ribs_before_flanges"));
    assert!(has(&s, 1, ConstraintKind::Before, 3, "web_before_ribs"));
    assert_eq!(s.refusals.len(), 1, "{:#?}", s.refusals);
    assert_eq!(s.refusals[0].rule, "sequencing.flange_first");
    assert_eq!(
        s.refusals[0].reason,
        "SF2 before SF1 would close the cycle SF2 → SF1 (this rule) \
         → SF3 (sequencing.web_before_ribs) → SF2 (sequencing.ribs_before_flanges)"
    );
}

#[test]
fn a_direct_reversal_of_a_stronger_rule_is_refused() {
    let (features, connections) = thesis_part();
    let k = rules(
        r#"(rules: [
            (id: "flange_first", priority: 2,
             when: All([First(Role([Flange])), Related(FirstOnSecond)]), then: Before),
            (id: "wall_first", priority: 1,
             when: All([Second(Role([Flange])), Related(SecondOnFirst)]), then: Before),
        ])"#,
    );
    let s = sequence(&features, &connections, UP, &k);
    assert_eq!(s.refusals.len(), 1);
    assert_eq!(
        s.refusals[0].reason,
        "SF1 before SF2 reverses a stronger constraint and would close the cycle \
         SF1 → SF2 (this rule) → SF1 (sequencing.flange_first)"
    );
}

#[test]
fn simultaneous_is_refused_for_features_already_ordered() {
    let (features, connections) = thesis_part();
    let k = rules(
        r#"(rules: [
            (id: "flange_first", priority: 2,
             when: All([First(Role([Flange])), Related(FirstOnSecond)]), then: Before),
            (id: "together", priority: 1,
             when: All([First(Role([Flange])), Second(Role([Web]))]), then: Simultaneous),
        ])"#,
    );
    let s = sequence(&features, &connections, UP, &k);
    assert_eq!(s.refusals.len(), 1);
    assert_eq!(
        s.refusals[0].reason,
        "SF2 simultaneous with SF1 contradicts a stronger constraint: they are already \
         ordered (SF2 → SF1 (sequencing.flange_first))"
    );
    assert!(s.groups.is_empty());
}

fn user(
    first: u32,
    kind: ConstraintKind,
    second: u32,
) -> Constraint<thinplan_plan::StiffnessFeatureId> {
    Constraint {
        first: id(first),
        second: id(second),
        kind,
        priority: 1000,
        provenance: Provenance::new(ProvenanceSource::User, "user.edit"),
    }
}

#[test]
fn try_add_refuses_cycles_with_the_cycle_and_accepts_the_rest() {
    let (mut features, connections) = thesis_part();
    let mut s = sequence(&features, &connections, UP, &repo_rules());
    let before = s.clone();

    // Web before flange reverses flange-before-web.
    let r = try_add(&mut s, user(1, ConstraintKind::Before, 2)).unwrap_err();
    assert_eq!(r.rule, "user.edit");
    assert_eq!(
        r.reason,
        "SF1 before SF2 reverses a stronger constraint and would close the cycle \
         SF1 → SF2 (this rule) → SF1 (sequencing.flange_before_wall)"
    );
    // The horizontal rib (with the web) before the hole (with the vertical
    // rib, which is before the web): a cycle through two groups.
    let r = try_add(&mut s, user(4, ConstraintKind::Before, 5)).unwrap_err();
    assert_eq!(
        r.reason,
        "SF4 before SF5 would close the cycle SF4 → SF5 (this rule) \
         ≡ SF3 (simultaneous, sequencing.depression_with_wall) \
         → SF1 (sequencing.vertical_rib_before_wall) \
         ≡ SF4 (simultaneous, sequencing.horizontal_rib_with_wall)"
    );
    // Within a group.
    let r = try_add(&mut s, user(1, ConstraintKind::Before, 4)).unwrap_err();
    assert!(r.reason.contains("machined simultaneously"), "{}", r.reason);
    // Already ordered.
    let r = try_add(&mut s, user(3, ConstraintKind::Simultaneous, 2)).unwrap_err();
    assert!(r.reason.contains("already ordered"), "{}", r.reason);
    assert_eq!(s.constraints, before.constraints);
    assert_eq!(s.groups, before.groups);
    assert_eq!(s.refusals.len(), before.refusals.len() + 4);

    // Accepted: a new feature first, and two features joined.
    features.push(wall(
        7,
        thinplan_plan::WallRole::Rib,
        glam::DVec3::Y,
        glam::DVec3::new(41.0, 150.0, 0.0),
        -glam::DVec3::X,
        40.0,
        100.0,
        2.0,
    ));
    try_add(&mut s, user(7, ConstraintKind::Before, 2)).unwrap();
    try_add(&mut s, user(7, ConstraintKind::Simultaneous, 3)).unwrap_err(); // 7 → 2 → 3
    try_add(&mut s, user(6, ConstraintKind::Simultaneous, 5)).unwrap_err(); // {2,6} → {3,5}
    try_add(&mut s, user(4, ConstraintKind::Simultaneous, 1)).unwrap(); // already one group
    assert_eq!(s.constraints.len(), before.constraints.len() + 1);
    let o = order(&features, &s);
    assert_eq!(o, [7, 2, 6, 3, 5, 1, 4].map(id));
    // 7 is before 2: they cannot be joined; a free feature 8 can.
    try_add(&mut s, user(7, ConstraintKind::Simultaneous, 2)).unwrap_err();
    let mut f8 = features[6].clone();
    f8.id = id(8);
    features.push(f8);
    try_add(&mut s, user(8, ConstraintKind::Simultaneous, 2)).unwrap();
    assert_eq!(s.groups[1], vec![id(2), id(6), id(8)]);
    assert_eq!(order(&features, &s), [7, 2, 6, 8, 3, 5, 1, 4].map(id));
}
