//! Independent checks on every sample part: the thesis's
//! sequencing rules as the connections and roles call for them (§4.2.2),
//! each wall's step approach top-down and alternating (figure 4.1) and sized
//! within the allowed deflection (§4.1.2), flanges before their web except
//! where a shank would rub (figure 4.6), and large-hole halves in order
//! (figure 4.8). Everything expected is read from the part's recognised
//! features and the features' own geometry, not from the code under test.

mod common;

use common::*;
use thinplan_determine::RULE_CARRIED_SHANK;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{
    ConnectionKind, ConstraintKind, MachiningFeature, Plan, Stage, StiffnessFeatureId,
    StiffnessKind, WallRole,
};
use thinplan_sizing::{deflection, MillingMode, Sizes, Wall};

fn samples() -> impl Iterator<Item = &'static str> {
    thinplan_import::SAMPLES.iter().map(|(name, _)| *name)
}

fn has_before(plan: &Plan, first: StiffnessFeatureId, second: StiffnessFeatureId) -> bool {
    plan.stiffness_constraints
        .iter()
        .any(|c| c.kind == ConstraintKind::Before && (c.first, c.second) == (first, second))
}

/// The simultaneous groups: a union-find over `Simultaneous` constraints
/// (an implied one is not recorded again).
fn group_of(plan: &Plan, id: StiffnessFeatureId) -> u32 {
    let mut parent: Vec<u32> = (0..plan.stiffness_features.len() as u32).collect();
    fn root(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            x = p[x as usize];
        }
        x
    }
    for c in &plan.stiffness_constraints {
        if c.kind == ConstraintKind::Simultaneous {
            let (a, b) = (root(&mut parent, c.first.0), root(&mut parent, c.second.0));
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    root(&mut parent, id.0)
}

/// A sequencing refusal about this pair (the reason names both).
fn refused(plan: &Plan, a: StiffnessFeatureId, b: StiffnessFeatureId) -> bool {
    plan.refusals.iter().any(|r| {
        r.stage == Stage::Sequence
            && r.reason.starts_with(&format!("{a} "))
            && r.reason.contains(&format!(" {b}"))
    })
}

/// "A flange before the wall it is on" and "depressions simultaneous with
/// their wall", wherever the recogniser connected a flange or a depression
/// to the wall it stands on or lies in.
#[test]
fn every_sample_sequences_flanges_before_and_depressions_with_their_wall() {
    let k = Knowledge::builtin().unwrap();
    let (mut flanges, mut depressions) = (0, 0);
    for name in samples() {
        let (plan, _, _) = planned(name, &k);
        let sf =
            |id: StiffnessFeatureId| plan.stiffness_features.iter().find(|s| s.id == id).unwrap();
        for c in plan
            .connections
            .iter()
            .filter(|c| c.kind == ConnectionKind::BaseLeaf)
        {
            let (base, leaf) = (sf(c.base), sf(c.leaf));
            if base.kind != StiffnessKind::Wall {
                continue;
            }
            if leaf.role == Some(WallRole::Flange) {
                assert!(
                    has_before(&plan, leaf.id, base.id) || refused(&plan, leaf.id, base.id),
                    "{name}: flange {} before the wall {} it is on",
                    leaf.id,
                    base.id
                );
                flanges += 1;
            }
            let depression = matches!(
                leaf.kind,
                StiffnessKind::Hole
                    | StiffnessKind::Cutout
                    | StiffnessKind::Slot
                    | StiffnessKind::Notch
                    | StiffnessKind::Pocket
                    | StiffnessKind::Step
            );
            if depression {
                assert!(
                    group_of(&plan, leaf.id) == group_of(&plan, base.id)
                        || refused(&plan, leaf.id, base.id),
                    "{name}: depression {} with its wall {}",
                    leaf.id,
                    base.id
                );
                depressions += 1;
            }
        }
    }
    println!("{flanges} flange connections, {depressions} depressions checked");
    assert!(flanges >= 4 && depressions >= 10);
}

/// Figure 4.1 on every wall of every sample: on each side the features go
/// top-down, and a small feature comes after every large feature of the
/// other side that starts above its bottom and before every one below it,
/// so the two sides alternate.
#[test]
fn every_samples_walls_step_down_alternating_sides() {
    let k = Knowledge::builtin().unwrap();
    let (mut pairs, mut walls) = (0, 0);
    for name in samples() {
        let (_, _, d) = planned(name, &k);
        let reach = Reach::of(&d);
        let steps = by_rule(&d, "strategies.wall_steps");
        let owners: std::collections::BTreeSet<_> = steps.iter().map(|f| f.owner).collect();
        for owner in owners {
            walls += 1;
            let mine: Vec<&MachiningFeature> =
                steps.iter().copied().filter(|f| f.owner == owner).collect();
            let span = |f: &MachiningFeature| (v(f, "depth_from"), v(f, "depth_to"));
            for a in &mine {
                for b in &mine {
                    if a.id == b.id {
                        continue;
                    }
                    let ((af, at), (bf, bt)) = (span(a), span(b));
                    if v(a, "side") == v(b, "side") {
                        if at <= bf + 1e-9 {
                            assert!(
                                reach.precedes(a.id, b.id),
                                "{name} {owner}: {} above {} on one side",
                                a.id,
                                b.id
                            );
                            pairs += 1;
                        }
                    } else if v(a, "large") == 1.0 && v(b, "large") == 0.0 {
                        if af < bt - 1e-9 {
                            assert!(
                                reach.precedes(a.id, b.id),
                                "{name} {owner}: large {} before small {}",
                                a.id,
                                b.id
                            );
                        } else {
                            assert!(
                                reach.precedes(b.id, a.id),
                                "{name} {owner}: small {} before the large {} below it",
                                b.id,
                                a.id
                            );
                        }
                        pairs += 1;
                    }
                }
            }
        }
    }
    println!("{walls} walls, {pairs} ordered pairs checked");
    assert!(walls >= 20, "{walls}");
}

/// Appendix A's model, computed here from each wall's recognised size and
/// the sizes the feature records: within the allowed deflection everywhere.
#[test]
fn every_samples_step_sizes_keep_the_deflection_within_the_allowed_value() {
    let k = Knowledge::builtin().unwrap();
    let e = k
        .material(thinplan_knowledge::DEFAULT_MATERIAL)
        .unwrap()
        .youngs_modulus;
    let (mut checked, mut short_walls) = (0, 0);
    for name in samples() {
        let (plan, _, d) = planned(name, &k);
        for f in by_rule(&d, "strategies.wall_steps") {
            let sf = plan
                .stiffness_features
                .iter()
                .find(|s| s.id == f.owner)
                .unwrap();
            let wall = Wall {
                length: sf.length,
                thickness: sf.thickness.unwrap(),
                height: sf.height,
            };
            let sizes = Sizes {
                b_rf: v(f, "b_rf"),
                h: v(f, "h"),
                big_h: v(f, "big_h"),
            };
            let delta = deflection(&wall, &sizes, &k.sizing, e, MillingMode::Peripheral);
            assert!(
                delta <= k.sizing.allowed_deflection + 1e-12,
                "{name} {}: {delta}",
                f.id
            );
            // Beside large cut-outs (figure 4.7(c)) the wall is a short one,
            // as long as the ligament and as tall as the cut-out.
            if let (Some(lig), Some(depth)) = (
                f.provenance.values.get("ligament_length"),
                f.provenance.values.get("cutout_depth"),
            ) {
                if v(f, "depth_to") <= depth + 1e-9 {
                    let short = Wall {
                        length: *lig,
                        thickness: wall.thickness,
                        height: *depth,
                    };
                    let d2 = deflection(&short, &sizes, &k.sizing, e, MillingMode::Peripheral);
                    assert!(
                        d2 <= k.sizing.allowed_deflection + 1e-12,
                        "{name} {} beside cut-outs: {d2}",
                        f.id
                    );
                    short_walls += 1;
                }
            }
            assert!(
                (v(f, "deflection") - delta).abs() <= 1e-9 * delta.max(1.0),
                "{name} {}: recorded {} vs {delta}",
                f.id,
                v(f, "deflection")
            );
            checked += 1;
        }
    }
    println!("{checked} wall features, {short_walls} beside large cut-outs");
    assert!(checked >= 150 && short_walls > 0, "{checked} {short_walls}");
}

/// "A flange before the wall it is on", carried to the machining features:
/// every feature of the flange and every one of the wall are ordered, and a
/// wall feature goes first only where it stands higher than the tool set's
/// shortest flute above the flange feature's bottom (the shank would rub it
/// otherwise), by the recorded yield rule.
#[test]
fn every_samples_flange_features_precede_their_walls_except_where_a_shank_would_rub() {
    let k = Knowledge::builtin().unwrap();
    let (mut after, mut early) = (0, 0);
    for name in samples() {
        let (plan, _, d) = planned(name, &k);
        let reach = Reach::of(&d);
        let rise = k
            .tool_set(&plan.setup.tool_set)
            .unwrap()
            .tools
            .iter()
            .map(|t| t.flute_length)
            .fold(f64::INFINITY, f64::min);
        let of = |id: StiffnessFeatureId| -> Vec<&MachiningFeature> {
            d.features.iter().filter(|f| f.owner == id).collect()
        };
        for c in plan.stiffness_constraints.iter().filter(|c| {
            c.kind == ConstraintKind::Before && c.provenance.rule == "sequencing.flange_before_wall"
        }) {
            for f in of(c.first) {
                for w in of(c.second) {
                    let (fw, wf) = (reach.precedes(f.id, w.id), reach.precedes(w.id, f.id));
                    assert!(fw != wf, "{name}: {} and {} ordered one way", f.id, w.id);
                    if wf {
                        assert!(
                            z_span(w).1 > z_span(f).0 + rise,
                            "{name}: {} goes before the flange's {} though it stands below \
                             the flute",
                            w.id,
                            f.id
                        );
                        early += 1;
                    } else {
                        after += 1;
                    }
                }
            }
        }
        // Each yield is recorded with the heights it used.
        for c in d
            .constraints
            .iter()
            .filter(|c| c.provenance.rule == RULE_CARRIED_SHANK)
        {
            let (w, f) = (
                &d.features[c.first.0 as usize],
                &d.features[c.second.0 as usize],
            );
            assert_eq!(c.provenance.values["flute_length"], rise);
            assert!(
                z_span(w).1 > z_span(f).0 + rise,
                "{name}: {} → {}",
                w.id,
                f.id
            );
        }
    }
    println!("{after} wall features after the flange's, {early} before");
    assert!(after > 0 && early > 0);
}

/// Figure 4.8 on every sample with large holes: an upper hole half comes
/// after every wall step above the separation line and before every one
/// below it; a lower piece after a step that exposed it and before the
/// steps below it.
#[test]
fn every_samples_large_hole_halves_come_in_order() {
    let k = Knowledge::builtin().unwrap();
    let mut holes_seen = 0;
    for name in samples() {
        let (_, _, d) = planned(name, &k);
        let reach = Reach::of(&d);
        let holes = by_rule(&d, "strategies.large_holes");
        for hf in &holes {
            let walls: Vec<_> = by_rule(&d, "strategies.wall_steps")
                .into_iter()
                .filter(|w| w.owner.0 as f64 == v(hf, "wall"))
                .collect();
            assert!(!walls.is_empty(), "{name} {}", hf.id);
            let line_depth = v(hf, "separation_depth");
            let (from, to) = (v(hf, "depth_from"), v(hf, "depth_to"));
            let upper = to <= line_depth + 1e-6;
            for w in &walls {
                let (wf, wt) = (v(w, "depth_from"), v(w, "depth_to"));
                if upper {
                    if wt <= line_depth + 1e-6 {
                        assert!(
                            reach.precedes(w.id, hf.id),
                            "{name}: {} before {}",
                            w.id,
                            hf.id
                        );
                    } else {
                        assert!(
                            reach.precedes(hf.id, w.id),
                            "{name}: {} before {}",
                            hf.id,
                            w.id
                        );
                    }
                } else if wf >= to - 1e-6 {
                    assert!(
                        reach.precedes(hf.id, w.id),
                        "{name}: {} before {}",
                        hf.id,
                        w.id
                    );
                }
            }
            if !upper {
                assert!(walls
                    .iter()
                    .any(|w| v(w, "depth_to") >= to - 1e-6 && reach.precedes(w.id, hf.id)));
                assert!(from >= line_depth - 1e-6);
            }
            holes_seen += 1;
        }
    }
    assert!(holes_seen >= 8, "{holes_seen}");
}
