//! The thesis's five rules (§4.2.2) on a hand-built part: each expected
//! constraint is checked against the rule's meaning.

mod common;

use common::*;
use glam::DVec3;
use thinplan_plan::{ConstraintKind::*, StiffnessKind, WallRole};
use thinplan_sequence::{order, sequence};

#[test]
fn the_five_rules_on_a_web_with_flange_ribs_hole_and_cutout() {
    let (features, connections) = thesis_part();
    let s = sequence(&features, &connections, UP, &repo_rules());

    // A flange before the wall it is on.
    assert!(has(&s, 2, Before, 1, "flange_before_wall"), "{s:#?}");
    // Depressions simultaneous with their wall: the hole with its rib, the
    // cut-out with its flange.
    assert!(has(&s, 5, Simultaneous, 3, "depression_with_wall"));
    assert!(has(&s, 6, Simultaneous, 2, "depression_with_wall"));
    // The horizontal rib with its wall (simultaneous).
    assert!(has(&s, 4, Simultaneous, 1, "horizontal_rib_with_wall"));
    // The vertical rib before its wall (support is kept: no other rib before it).
    assert!(has(&s, 3, Before, 1, "vertical_rib_before_wall"));
    // Higher before lower: the flange (bottom z = 100) before the vertical
    // rib (bottom z = 0); flange before web is already implied.
    assert!(has(&s, 2, Before, 3, "higher_before_lower"));
    assert_eq!(s.constraints.len(), 6, "{:#?}", s.constraints);

    // The horizontal rib (bottom z = 49) lies higher than the web and the
    // vertical rib, but it is machined with the web (stronger rule): higher-
    // before-lower is refused for both, the second with the cycle it closes.
    assert_eq!(s.refusals.len(), 2, "{:#?}", s.refusals);
    let with_web = &s.refusals[0];
    assert_eq!(with_web.rule, "sequencing.higher_before_lower");
    assert!(
        with_web.reason.starts_with("SF4 before SF1"),
        "{}",
        with_web.reason
    );
    assert!(
        with_web.reason.contains("simultaneous"),
        "{}",
        with_web.reason
    );
    let cycle = &s.refusals[1];
    assert_eq!(cycle.rule, "sequencing.higher_before_lower");
    assert_eq!(
        cycle.reason,
        "SF4 before SF3 would close the cycle SF4 → SF3 (this rule) \
         → SF1 (sequencing.vertical_rib_before_wall) \
         ≡ SF4 (simultaneous, sequencing.horizontal_rib_with_wall)"
    );
    let ids: Vec<f64> = cycle
        .provenance
        .values
        .iter()
        .filter(|(k, _)| k.starts_with("cycle."))
        .map(|(_, v)| *v)
        .collect();
    assert_eq!(ids, vec![4.0, 3.0, 1.0, 4.0]);
    assert_eq!(cycle.provenance.values["first"], 4.0);
    assert_eq!(cycle.provenance.values["second"], 3.0);

    assert_eq!(
        s.groups,
        vec![vec![id(1), id(4)], vec![id(2), id(6)], vec![id(3), id(5)]]
    );

    // Provenance: rule id, priority and the values used.
    let higher = s
        .constraints
        .iter()
        .find(|c| c.provenance.rule == "sequencing.higher_before_lower")
        .unwrap();
    assert_eq!(higher.priority, 10);
    let v = &higher.provenance.values;
    assert_eq!(v["priority"], 10.0);
    assert!((v["first.bottom"] - 100.0).abs() < 1e-9);
    assert!((v["second.bottom"] - 0.0).abs() < 1e-9);
    assert!((v["higher_by"] - 100.0).abs() < 1e-9);
    assert_eq!(v["by_more_than"], 1.0);
    let vertical = s
        .constraints
        .iter()
        .find(|c| c.provenance.rule == "sequencing.vertical_rib_before_wall")
        .unwrap();
    assert!((vertical.provenance.values["junction_elevation_deg"] - 90.0).abs() < 1e-9);
    assert_eq!(
        vertical.provenance.values["unless.leaves_before_second"],
        0.0
    );
    for c in &s.constraints {
        assert!(c.provenance.values.contains_key("priority"));
        assert!(!c.provenance.note.is_empty());
    }

    // The order: flange group, vertical rib group, then web with its rib.
    let o = order(&features, &s);
    assert_eq!(o, [2, 6, 3, 5, 1, 4].map(id));
    assert!(position(&o, 2) < position(&o, 1), "flange before web");
    assert!(position(&o, 3) < position(&o, 1), "vertical rib before web");
}

#[test]
fn the_hole_in_a_rib_reads_its_level_from_the_arcs() {
    // Only the hole's arcs reach z = 65; a higher-than rule on depressions
    // with a 64.9 threshold must see it lie higher than the web bottom (0).
    let (features, connections) = thesis_part();
    let k = rules(
        r#"(rules: [(
            id: "probe", priority: 1,
            when: All([First(Kind([Hole])), Second(Role([Web])), Higher(level: Bottom, by_more_than: 64.9)]),
            then: Before,
        )])"#,
    );
    let s = sequence(&features, &connections, UP, &k);
    assert!(has(&s, 5, Before, 1, "probe"));
    let k = rules(
        r#"(rules: [(
            id: "probe", priority: 1,
            when: All([First(Kind([Hole])), Second(Role([Web])), Higher(level: Bottom, by_more_than: 65.1)]),
            then: Before,
        )])"#,
    );
    assert!(sequence(&features, &connections, UP, &k)
        .constraints
        .is_empty());
}

#[test]
fn a_wall_keeps_its_support_when_many_vertical_ribs_stand_on_it() {
    // Three vertical ribs on the web: the first two (by id) go before it,
    // the third would leave the web without support and is refused.
    let (x, y) = (DVec3::X, DVec3::Y);
    let mut features = vec![wall(1, WallRole::Web, x, DVec3::ZERO, y, 200.0, 100.0, 2.0)];
    let mut connections = vec![];
    for (n, at) in [(2, 40.0), (3, 100.0), (4, 160.0)] {
        features.push(wall(
            n,
            WallRole::Rib,
            y,
            DVec3::new(41.0, at, 0.0),
            -x,
            40.0,
            100.0,
            2.0,
        ));
        connections.push(base_leaf(1, n));
    }
    let s = sequence(&features, &connections, UP, &repo_rules());
    assert!(has(&s, 2, Before, 1, "vertical_rib_before_wall"));
    assert!(has(&s, 3, Before, 1, "vertical_rib_before_wall"));
    assert!(!s.constraints.iter().any(|c| c.first == id(4)));
    assert_eq!(s.refusals.len(), 1, "{:#?}", s.refusals);
    let r = &s.refusals[0];
    assert_eq!(r.rule, "sequencing.vertical_rib_before_wall");
    assert!(r.reason.contains("unless-condition holds"), "{}", r.reason);
    assert_eq!(r.provenance.values["unless.leaves_before_second"], 2.0);
}

#[test]
fn depressions_of_every_kind_go_with_their_wall_but_details_do_not() {
    let (x, y) = (DVec3::X, DVec3::Y);
    let mut features = vec![wall(1, WallRole::Web, x, DVec3::ZERO, y, 200.0, 100.0, 2.0)];
    let mut connections = vec![];
    let kinds = [
        StiffnessKind::Hole,
        StiffnessKind::Cutout,
        StiffnessKind::Slot,
        StiffnessKind::Notch,
        StiffnessKind::Pocket,
        StiffnessKind::Step,
        StiffnessKind::Chamfer,
    ];
    for (i, kind) in kinds.iter().enumerate() {
        let n = i as u32 + 2;
        features.push(depression(
            n,
            *kind,
            DVec3::new(-1.0, 10.0 * n as f64, 50.0),
            x,
            y,
            5.0,
            5.0,
            2.0,
        ));
        connections.push(base_leaf(1, n));
    }
    let s = sequence(&features, &connections, UP, &repo_rules());
    for n in 2..=7 {
        assert!(has(&s, n, Simultaneous, 1, "depression_with_wall"), "SF{n}");
    }
    assert!(!s
        .constraints
        .iter()
        .any(|c| c.first == id(8) || c.second == id(8)));
    assert_eq!(s.groups, vec![(1..=7).map(id).collect::<Vec<_>>()]);
}

#[test]
fn a_flange_on_a_floor_web_goes_first_and_ribs_on_it_run_horizontally() {
    // The recogniser's convention: a web normal to up at the bottom, a
    // flange standing at its edge, a rib standing inside. Both meet the web
    // along a horizontal line: the rib goes with the web; the flange before.
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let features = vec![
        wall(
            1,
            WallRole::Web,
            z,
            DVec3::new(0.0, 0.0, 1.0),
            x,
            100.0,
            100.0,
            2.0,
        ),
        wall(
            2,
            WallRole::Flange,
            y,
            DVec3::new(100.0, 1.0, 2.0),
            -x,
            100.0,
            40.0,
            2.0,
        ),
        wall(
            3,
            WallRole::Rib,
            y,
            DVec3::new(100.0, 50.0, 2.0),
            -x,
            100.0,
            40.0,
            2.0,
        ),
    ];
    let connections = vec![base_leaf(1, 2), base_leaf(1, 3)];
    let s = sequence(&features, &connections, UP, &repo_rules());
    assert!(has(&s, 2, Before, 1, "flange_before_wall"));
    assert!(has(&s, 3, Simultaneous, 1, "horizontal_rib_with_wall"));
    assert!(!has(&s, 3, Before, 1, "vertical_rib_before_wall"));
}
