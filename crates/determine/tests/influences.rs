//! Independent checks of the influence blocks (thesis §4.1.3): large holes
//! (figure 4.8), cut-outs (figure 4.7) and connected walls (figure 4.6), on
//! the sample parts, measured from the part's own geometry.

mod common;

use std::collections::BTreeSet;

use common::*;
use thinplan_brep::Surface;
use thinplan_determine::{Determination, RULE_CARRIED_SHANK};
use thinplan_knowledge::{Block, Knowledge};
use thinplan_plan::{MachiningFeature, StiffnessKind, WallRole};
use thinplan_sizing::{MillingMode, Wall};

fn set_holes(k: &mut Knowledge, f: impl Fn(&mut thinplan_knowledge::LargeHoles)) {
    for s in &mut k.strategies.strategies {
        for b in &mut s.blocks {
            if let Block::LargeHoles(h) = b {
                f(h);
            }
        }
    }
}

#[test]
fn the_step_separation_line_lies_two_tool_diameters_below_the_highest_hole_top() {
    let k = Knowledge::builtin().unwrap();
    let (_, brep, d) = planned("wall_holes", &k);
    // From the B-rep: the holes are the cylinders across the wall (axis y).
    let tops: Vec<f64> = brep
        .faces
        .iter()
        .filter_map(|f| match &f.surface {
            Surface::Cylinder { frame, radius } if frame.z.y.abs() > 0.99 => {
                Some(frame.origin.z + radius)
            }
            _ => None,
        })
        .collect();
    assert_eq!(tops.len(), 4, "wall_holes has four holes");
    let highest = tops.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let part_top = brep
        .vertices
        .iter()
        .map(|p| p.point.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let d_tool = k.sizing.preferred_tool_diameter;
    let line = highest - 2.0 * d_tool;
    // The line as the plan has it (the part measure above, within 0.05).
    let planned_line = part_top - v(by_rule(&d, "strategies.large_holes")[0], "separation_depth");
    println!("hole top z = {highest}, line z = {line}, part top z = {part_top}");
    let walls = by_rule(&d, "strategies.wall_steps");
    let holes = by_rule(&d, "strategies.large_holes");
    assert_eq!(walls.len() + holes.len(), d.features.len());
    // Every hole is large (25 mm > 1.5 · 12 mm): an upper half each, from
    // its top down to the line.
    let uppers: Vec<_> = holes
        .iter()
        .filter(|f| (z_span(f).1 - highest).abs() < 0.1)
        .collect();
    assert_eq!(uppers.len(), 4);
    for u in &uppers {
        assert_eq!(v(u, "hole_diameter"), 25.0);
        assert_eq!(v(u, "large"), 1.0);
        // The recognised hole is a polygon with its corners on the circle,
        // so its top may lie a little below the circle's (0.035 mm here).
        assert!((z_span(u).0 - line).abs() < 0.05, "{:?}", z_span(u));
        assert!((v(u, "separation_depth") - (part_top - line)).abs() < 0.05);
    }
    // A wall step boundary on the line, on both sides of the wall.
    for side in [1.0, -1.0] {
        assert!(
            walls
                .iter()
                .any(|w| v(w, "side") == side && (z_span(w).0 - planned_line).abs() < 1e-6),
            "no step ends on the line on side {side}"
        );
        assert!(walls
            .iter()
            .any(|w| v(w, "side") == side && (z_span(w).1 - planned_line).abs() < 1e-6));
    }
    // No wall step crosses the line.
    for w in &walls {
        let (lo, hi) = z_span(w);
        assert!(
            !(lo < planned_line - 1e-6 && hi > planned_line + 1e-6),
            "{} crosses",
            w.id
        );
    }
}

#[test]
fn the_knowledge_constants_move_the_line_and_decide_what_is_large() {
    let k = Knowledge::builtin().unwrap();
    let (_, _, base) = planned("wall_holes", &k);
    let depth = |d: &Determination| v(by_rule(d, "strategies.large_holes")[0], "separation_depth");
    // One tool diameter instead of two: the line 12 mm higher.
    let mut k1 = k.clone();
    set_holes(&mut k1, |h| h.separation_in_tool_diameters = 1.0);
    let (_, _, d1) = planned("wall_holes", &k1);
    assert!((depth(&base) - depth(&d1) - 12.0).abs() < 1e-6);
    assert_ne!(base, d1);
    // Large only above 3 · D = 36 mm: the 25 mm holes are small, machined
    // whole as soon as exposed, and the wall has no line.
    let mut k2 = k.clone();
    set_holes(&mut k2, |h| h.large_above_tool_diameters = 3.0);
    let (_, _, d2) = planned("wall_holes", &k2);
    let holes = by_rule(&d2, "strategies.large_holes");
    assert_eq!(holes.len(), 4);
    for h in &holes {
        assert_eq!(v(h, "large"), 0.0);
        assert!(!h.provenance.values.contains_key("separation_depth"));
    }
    // Dropping the block: no hole features, the wall as before.
    let mut k3 = k.clone();
    for s in &mut k3.strategies.strategies {
        s.blocks.retain(|b| !matches!(b, Block::LargeHoles(_)));
    }
    assert!(k3.strategies.problems().is_empty());
    let (_, _, d3) = planned("wall_holes", &k3);
    assert!(by_rule(&d3, "strategies.large_holes").is_empty());
    println!(
        "wall_holes: {} features with the line, {} without the block",
        base.features.len(),
        d3.features.len()
    );
}

#[test]
fn small_cutouts_sit_between_the_step_that_exposes_them_and_the_next() {
    let k = Knowledge::builtin().unwrap();
    let (plan, _, d) = planned("wing_rib", &k);
    let cuts = by_rule(&d, "strategies.cutouts");
    assert_eq!(cuts.len(), 4, "the four stringer cut-outs");
    for c in &cuts {
        assert_eq!(v(c, "large"), 0.0);
        let sf = plan
            .stiffness_features
            .iter()
            .find(|s| s.id == c.owner)
            .unwrap();
        assert_eq!(sf.kind, StiffnessKind::Cutout);
        // Its wall's steps, in their order.
        let wall = v(c, "wall") as u32;
        let steps: Vec<_> = d
            .features
            .iter()
            .filter(|f| f.owner.0 == wall && f.provenance.rule == "strategies.wall_steps")
            .collect();
        // The first step reaching the cut-out's bottom comes before it …
        let exposing = steps
            .iter()
            .position(|s| v(s, "depth_to") >= v(c, "depth_to") - 1e-6)
            .unwrap();
        assert!(precedes(&d, steps[exposing].id, c.id));
        // … and the next one after it; no step in between.
        if let Some(next) = steps.get(exposing + 1) {
            assert!(precedes(&d, c.id, next.id));
        }
        for s in &steps[..exposing] {
            assert!(precedes(&d, s.id, c.id));
        }
    }
}

#[test]
fn large_cutouts_resize_the_wall_beside_them_and_take_the_larger_height() {
    let k = Knowledge::builtin().unwrap();
    let (_, brep, d) = planned("flange_cutouts", &k);
    let cuts = by_rule(&d, "strategies.cutouts");
    assert_eq!(cuts.len(), 3);
    // Ligament from the geometry: the cut-outs' straight sides (planes
    // across x) and the flange's ends.
    let top = brep
        .vertices
        .iter()
        .map(|p| p.point.z)
        .fold(f64::NEG_INFINITY, f64::max);
    for c in &cuts {
        assert_eq!(v(c, "large"), 1.0, "15 mm deep > h = 12 mm");
        let (lo, hi) = z_span(c);
        assert!(hi >= top - 1e-6);
        assert!((v(c, "cutout_depth") - (top - lo)).abs() < 1e-6);
        assert!((v(c, "ligament_length") - 34.0).abs() < 1e-6);
    }
    // The flange's steps beside the cut-outs were sized again (smaller H)
    // than the steps below them.
    let steps = by_rule(&d, "strategies.wall_steps");
    let depth = v(cuts[0], "cutout_depth");
    let wall = v(cuts[0], "wall") as u32;
    let (beside, below): (Vec<&MachiningFeature>, Vec<&MachiningFeature>) = steps
        .into_iter()
        .filter(|s| s.owner.0 == wall)
        .partition(|s| v(s, "depth_to") <= depth + 1e-6);
    assert!(!beside.is_empty() && !below.is_empty());
    assert!(beside.iter().all(|s| v(s, "big_h") < v(below[0], "big_h")));
    // Each cut-out piece after every step beside it.
    for c in &cuts {
        for s in &beside {
            assert!(precedes(&d, s.id, c.id));
        }
    }
    // With a threshold of 2 · h the cut-outs are small: no resizing, inserted
    // as soon as exposed.
    let mut k2 = k.clone();
    for s in &mut k2.strategies.strategies {
        for b in &mut s.blocks {
            if let Block::Cutouts(c) = b {
                c.large_deeper_than_h = 2.0;
                c.large_below_ligament_ratio = 0.0;
            }
        }
    }
    let (_, _, d2) = planned("flange_cutouts", &k2);
    let steps2 = by_rule(&d2, "strategies.wall_steps");
    let big_h: BTreeSet<u64> = steps2.iter().map(|s| v(s, "big_h") as u64).collect();
    assert_eq!(big_h.len(), 1, "one size over the whole flange");
    assert!(by_rule(&d2, "strategies.cutouts")
        .iter()
        .all(|c| v(c, "large") == 0.0));
    println!(
        "flange_cutouts: H beside the cut-outs {} vs {} below; small: {:?}",
        v(beside[0], "big_h"),
        v(below[0], "big_h"),
        big_h
    );
}

#[test]
fn a_flanges_features_are_no_wider_than_the_webs_permissible_height() {
    let k = Knowledge::builtin().unwrap();
    let e = k
        .material(thinplan_knowledge::DEFAULT_MATERIAL)
        .unwrap()
        .youngs_modulus;
    for (name, factor) in [
        ("flange_cutouts", 1.0),
        ("flange_web_slot", 1.0),
        ("wing_rib", 1.0),
        ("flange_web_slot", 0.1),
    ] {
        let mut k = k.clone();
        for s in &mut k.strategies.strategies {
            for b in &mut s.blocks {
                if let Block::ConnectedWalls(c) = b {
                    c.width_in_web_big_h = factor;
                }
            }
        }
        let (plan, _, d) = planned(name, &k);
        let (mut checked, mut local) = (0, 0);
        for f in by_rule(&d, "strategies.wall_steps") {
            let sf = plan
                .stiffness_features
                .iter()
                .find(|s| s.id == f.owner)
                .unwrap();
            if sf.role != Some(WallRole::Flange) {
                continue;
            }
            // The web it stands on, sized by me as a wall (face milling).
            let web = plan
                .connections
                .iter()
                .filter(|c| c.leaf == sf.id)
                .filter_map(|c| plan.stiffness_features.iter().find(|w| w.id == c.base))
                .find(|w| w.role == Some(WallRole::Web))
                .unwrap();
            let ws = thinplan_sizing::size_wall(
                &Wall {
                    length: web.length,
                    thickness: web.thickness.unwrap(),
                    height: web.height,
                },
                &k.sizing,
                e,
                MillingMode::Face,
            )
            .unwrap();
            assert_eq!(v(f, "web_big_h"), ws.big_h);
            let at_foot = (v(f, "depth_to") - sf.height).abs() < 1e-6;
            let cap = factor * ws.big_h;
            if at_foot || v(f, "local") == 0.0 {
                assert!(v(f, "width") <= cap + 1e-9, "{name} {}", f.id);
            }
            if cap < v(f, "b_rf") {
                // The cap is below B_RF: the flange keeps its support above
                // its foot (applied locally, figure 4.6).
                assert_eq!(v(f, "local"), 1.0);
                if !at_foot {
                    assert_eq!(v(f, "width"), v(f, "b_rf"));
                } else {
                    assert_eq!(v(f, "width"), cap);
                    local += 1;
                }
            }
            checked += 1;
        }
        assert!(checked > 0, "{name}");
        assert_eq!(local > 0, factor < 1.0, "{name} ×{factor}");
        println!("{name} ×{factor}: {checked} flange features checked, {local} capped at the foot");
    }
}

/// "A flange before the wall it is on" (§4.2.2) carried over to the
/// machining features, on flange_web_slot (a 35 mm flange on its web): the
/// web's face-milling layers that stand higher than the tool set's shortest
/// flute above a flange feature's bottom go before it (a shank cutting the
/// flange's narrow steps would rub them: shank collisions), every
/// other web layer after it, so the two interleave top-down. Without the
/// knowledge's `shank_access` the whole flange goes first.
#[test]
fn a_flange_precedes_its_web_except_the_layers_a_shank_would_rub() {
    let k = Knowledge::builtin().unwrap();
    let (plan, _, d) = planned("flange_web_slot", &k);
    let rise = k
        .tool_set(&plan.setup.tool_set)
        .unwrap()
        .tools
        .iter()
        .map(|t| t.flute_length)
        .fold(f64::INFINITY, f64::min);
    let role = |f: &MachiningFeature| {
        plan.stiffness_features
            .iter()
            .find(|s| s.id == f.owner)
            .unwrap()
            .role
    };
    let of = |d: &Determination, r: WallRole| -> Vec<MachiningFeature> {
        d.features
            .iter()
            .filter(|f| role(f) == Some(r))
            .cloned()
            .collect()
    };
    let (flange, web) = (of(&d, WallRole::Flange), of(&d, WallRole::Web));
    assert!(
        flange.len() >= 2 && web.len() >= 3,
        "{} {}",
        flange.len(),
        web.len()
    );
    let (mut early, mut late) = (0, 0);
    for f in &flange {
        let f_bottom = z_span(f).0;
        for w in &web {
            // Every web layer spans the web beside the flange: only the
            // height decides.
            if z_span(w).1 > f_bottom + rise + 1e-9 {
                assert!(precedes(&d, w.id, f.id), "{} before {}", w.id, f.id);
                early += 1;
            } else {
                assert!(precedes(&d, f.id, w.id), "{} before {}", f.id, w.id);
                late += 1;
            }
        }
    }
    println!("{early} web layers early, {late} after the flange feature");
    assert!(early > 0 && late > 0);
    let yielded: Vec<_> = d
        .constraints
        .iter()
        .filter(|c| c.provenance.rule == RULE_CARRIED_SHANK)
        .collect();
    assert!(!yielded.is_empty());
    for c in yielded {
        assert_eq!(c.provenance.values["flute_length"], rise);
        let (w, f) = (
            &d.features[c.first.0 as usize],
            &d.features[c.second.0 as usize],
        );
        assert_eq!(role(w), Some(WallRole::Web));
        assert_eq!(role(f), Some(WallRole::Flange));
        assert!(z_span(w).1 > z_span(f).0 + rise);
    }

    let mut off = k.clone();
    off.interference.shank_access = false;
    let (_, _, d2) = planned("flange_web_slot", &off);
    let (flange, web) = (of(&d2, WallRole::Flange), of(&d2, WallRole::Web));
    for f in &flange {
        for w in &web {
            assert!(precedes(&d2, f.id, w.id), "{} before {}", f.id, w.id);
        }
    }
    assert!(!d2
        .constraints
        .iter()
        .any(|c| c.provenance.rule == RULE_CARRIED_SHANK));
}
