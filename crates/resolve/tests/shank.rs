//! Shank access: a feature standing beside another, within the
//! tool's reach across its non-product edges and higher than a flute length
//! above its bottom, is machined first.

use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{MachiningFeature, Plan, Stage};
use thinplan_resolve::{RULE_REMAINING, RULE_SHANK};

fn planned(name: &str) -> Session {
    planned_with(name, load_knowledge(None).expect("builtin knowledge"))
}

fn planned_with(name: &str, k: Knowledge) -> Session {
    let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
    s.run_to(Stage::Resolve, &Default::default(), |_| {})
        .expect("plans");
    s
}

fn describe(plan: &Plan) {
    for f in &plan.machining_features {
        println!(
            "{} owner {} z {:.1}->{:.1} rule {} {}",
            f.id,
            f.owner,
            f.shape.z_max,
            f.shape.z_min,
            f.provenance.rule,
            f.provenance.note.chars().take(80).collect::<String>()
        );
    }
    for c in &plan.machining_constraints {
        if c.provenance.rule == RULE_SHANK {
            println!("  {} before {}: {}", c.first, c.second, c.provenance.note);
        }
    }
    for r in &plan.refusals {
        if r.rule == RULE_SHANK {
            println!("  refused: {}", r.reason);
        }
    }
}

#[test]
#[ignore]
fn print_shank_constraints() {
    let name = std::env::var("SAMPLE").unwrap_or("tall_rib".into());
    describe(&planned(&name).plan);
}

/// Every bundled sample (a new one is covered without editing here).
fn samples() -> Vec<&'static str> {
    thinplan_import::SAMPLES.iter().map(|(n, _)| *n).collect()
}

fn outer(f: &MachiningFeature) -> Vec<[f64; 2]> {
    f.shape
        .region
        .outer
        .vertices
        .iter()
        .map(|v| [v.x, v.y])
        .collect()
}

fn point_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Plan-view distance between two outer contours (vertex to edge both
/// ways; exact for polygons that do not cross).
fn distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let one_way = |a: &[[f64; 2]], b: &[[f64; 2]]| {
        a.iter()
            .flat_map(|&p| (0..b.len()).map(move |i| point_segment(p, b[i], b[(i + 1) % b.len()])))
            .fold(f64::INFINITY, f64::min)
    };
    one_way(a, b).min(one_way(b, a))
}

fn reaches(plan: &Plan, a: usize, b: usize) -> bool {
    reaches_by(plan, a, b, |_| true)
}

/// Whether `a` comes before `b` through the constraints `keep` accepts.
fn reaches_by(
    plan: &Plan,
    a: usize,
    b: usize,
    keep: impl Fn(&thinplan_plan::Constraint<thinplan_plan::MachiningFeatureId>) -> bool,
) -> bool {
    let n = plan.machining_features.len();
    let mut succ = vec![Vec::new(); n];
    for c in plan.machining_constraints.iter().filter(|c| keep(c)) {
        succ[c.first.0 as usize].push(c.second.0 as usize);
    }
    let mut seen = vec![false; n];
    let mut stack = vec![a];
    while let Some(v) = stack.pop() {
        if v == b {
            return true;
        }
        for &w in &succ[v] {
            if !seen[w] {
                seen[w] = true;
                stack.push(w);
            }
        }
    }
    false
}

/// tall_rib: the remaining material around the rib's steps (92 → 20, owned
/// by the web) stands beside the first large step (92 → 56): a Ø20's shank
/// (flutes 30 mm) cutting the step's bottom would rub it, so it comes first,
/// with the rule's provenance.
#[test]
fn tall_rib_remaining_material_comes_before_the_step_it_stands_beside() {
    let s = planned("tall_rib");
    let mf = &s.plan.machining_features;
    let rest = mf
        .iter()
        .find(|f| f.provenance.rule == RULE_REMAINING && f.shape.z_min < 21.0)
        .expect("remaining material down to the web");
    let step = mf
        .iter()
        .filter(|f| {
            f.provenance.values.get("large") == Some(&1.0) && (f.shape.z_max - 92.0).abs() < 1e-6
        })
        .min_by_key(|f| f.id)
        .expect("the first large step");
    assert!(
        rest.shape.z_max - step.shape.z_min > 30.0,
        "the rest must stand higher than the Ø20's flutes above the step's bottom"
    );
    assert!(
        reaches(&s.plan, rest.id.0 as usize, step.id.0 as usize),
        "{} (remaining) is not before {} (step)",
        rest.id,
        step.id
    );
    let c = s
        .plan
        .machining_constraints
        .iter()
        .find(|c| c.provenance.rule == RULE_SHANK && c.first == rest.id && c.second == step.id)
        .expect("a shank-access constraint orders them");
    let v = &c.provenance.values;
    assert!((v["top_of_first"] - rest.shape.z_max).abs() < 1e-6);
    assert!((v["bottom_of_second"] - step.shape.z_min).abs() < 1e-6);
    assert!(v["top_of_first"] > v["bottom_of_second"] + v["flute_length"]);
    assert!(v["overlap_area"] > 0.0);
    // Without the rule nothing orders them (the rule is what does).
    let mut k = load_knowledge(None).expect("builtin knowledge");
    k.interference.shank_access = false;
    let off = planned_with("tall_rib", k);
    assert!(!reaches(&off.plan, rest.id.0 as usize, step.id.0 as usize));
}

/// Every shank-access constraint, checked independently: the first stands
/// within a tool diameter of the second in plan view (the reach zone's
/// width) and higher than that tool's flute length above its bottom.
#[test]
fn shank_constraints_are_neighbours_standing_above_the_flutes() {
    let k = load_knowledge(None).expect("builtin knowledge");
    let set = k
        .tool_set(&make_setup(&SetupRequest::default(), &k).unwrap().tool_set)
        .expect("tool set")
        .clone();
    let widest = set.tools.iter().map(|t| t.diameter).fold(0.0, f64::max);
    let mut seen = 0;
    for name in samples() {
        let s = planned(name);
        let mf = &s.plan.machining_features;
        for c in &s.plan.machining_constraints {
            if c.provenance.rule != RULE_SHANK {
                continue;
            }
            seen += 1;
            let (n, f) = (&mf[c.first.0 as usize], &mf[c.second.0 as usize]);
            let d = distance(&outer(n), &outer(f));
            assert!(
                d <= widest + 1e-6,
                "{name}: {} is {d:.2} mm from {}",
                n.id,
                f.id
            );
            let flute = c.provenance.values["flute_length"];
            assert!(
                set.tools.iter().any(|t| t.flute_length == flute),
                "{name}: flute length {flute} of no tool"
            );
            assert!(
                n.shape.z_max > f.shape.z_min + flute,
                "{name}: {} does not stand above {}'s flutes",
                n.id,
                f.id
            );
        }
    }
    assert!(seen > 0, "no sample has a shank-access constraint");
}

/// The step features on the two sides of a wall are kept apart by the wall
/// (the reach zone never grows across product): the rule never orders one
/// side's step against the other side's.
#[test]
fn opposite_sides_of_a_wall_are_not_constrained() {
    for name in samples() {
        let s = planned(name);
        let mf = &s.plan.machining_features;
        for c in &s.plan.machining_constraints {
            if c.provenance.rule != RULE_SHANK {
                continue;
            }
            let (n, f) = (&mf[c.first.0 as usize], &mf[c.second.0 as usize]);
            let (sn, sf) = (
                n.provenance.values.get("side"),
                f.provenance.values.get("side"),
            );
            if let (Some(a), Some(b)) = (sn, sf) {
                assert!(
                    !(n.owner == f.owner && a != b),
                    "{name}: {} and {} lie on opposite sides of {}",
                    n.id,
                    f.id,
                    n.owner
                );
            }
        }
        // The samples do have such pairs, close across the wall and high
        // enough: tall_rib's steps on side B beside its large steps on A.
        let across = mf.iter().any(|n| {
            mf.iter().any(|f| {
                n.owner == f.owner
                    && matches!(
                        (n.provenance.values.get("side"), f.provenance.values.get("side")),
                        (Some(a), Some(b)) if a != b
                    )
                    && n.shape.z_max > f.shape.z_min + 30.0
                    && distance(&outer(n), &outer(f)) < 12.0
            })
        });
        if name == "tall_rib" {
            assert!(across, "tall_rib has no tall pair across its rib");
        }
    }
}

/// The knowledge switch: without it, no shank-access constraint.
#[test]
fn the_switch_turns_the_rule_off() {
    let mut k = load_knowledge(None).expect("builtin knowledge");
    k.interference.shank_access = false;
    let s = planned_with("tall_rib", k);
    assert!(s
        .plan
        .machining_constraints
        .iter()
        .all(|c| c.provenance.rule != RULE_SHANK));
    assert!(s.plan.refusals.iter().all(|r| r.rule != RULE_SHANK));
}

/// A shank request is refused and recorded only where another rule stands
/// in the way (a chain of other rules' constraints puts the second first);
/// where this rule's own earlier constraints already decided the pair, the
/// request is dropped silently. Checked on every sample, independently of
/// the graph inside resolve.
#[test]
fn shank_refusals_are_recorded_only_against_other_rules() {
    let mut recorded = 0;
    for name in samples() {
        let s = planned(name);
        let plan = &s.plan;
        let by_others =
            |a: usize, b: usize| reaches_by(plan, a, b, |c| c.provenance.rule != RULE_SHANK);
        for r in plan.refusals.iter().filter(|r| r.rule == RULE_SHANK) {
            let first = r.provenance.values["first"] as usize;
            let second = r.provenance.values["second"] as usize;
            assert!(
                by_others(second, first),
                "{name}: {} is recorded, but only this rule orders MF{second} before MF{first}",
                r.reason
            );
            recorded += 1;
        }
    }
    // The flange steps under web layers: the sequencing rule wins there.
    assert!(recorded > 0, "no refusal on any sample");
}
