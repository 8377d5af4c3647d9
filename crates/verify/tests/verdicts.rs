//! Stage 9 on cases made to fail: a tool that cuts wider than the one the
//! paths were planned for gouges; knowledge whose flutes are shorter than
//! the levels are deep makes the shank cut. Each failing operation is taken
//! out with its problem, none is left in the program, and the verdict says
//! the plan is not complete.

use std::sync::atomic::AtomicBool;

use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{ProblemKind, Stage, Verdict};

fn to_order(name: &str, k: Knowledge) -> Session {
    let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
    s.run_to(Stage::Order, &AtomicBool::new(false), |_| {})
        .expect("plans through stage 8");
    s
}

fn with_tools(mut k: Knowledge, f: impl Fn(&mut thinplan_knowledge::Tool)) -> Knowledge {
    for set in k.tool_sets.values_mut() {
        for t in &mut set.tools {
            f(t);
        }
    }
    k
}

/// Paths planned for the set's tools, replayed with every tool 2 mm wider
/// (a tool larger than the knowledge says): the program gouges the part.
#[test]
fn a_wider_tool_than_planned_gouges_and_its_operations_are_removed() {
    let mut s = to_order("tall_rib", load_knowledge(None).unwrap());
    s.knowledge = with_tools(s.knowledge.clone(), |t| {
        t.diameter += 2.0;
        t.shank_diameter += 2.0;
    });
    s.run_stage(Stage::Verify).expect("verifies");
    let v = s.plan.verification.as_ref().unwrap();
    let gouges = v
        .removed
        .iter()
        .filter(|r| r.problem.kind == ProblemKind::Gouge)
        .count();
    assert!(gouges > 0, "no gouge found: {:?}", v.removed.len());
    assert_ne!(v.verdict, Verdict::Safe);
    if v.verdict == Verdict::Incomplete {
        assert!(v.problems.is_empty());
    }
    // Every removal is a refusal of stage 9 naming the operation.
    for r in &v.removed {
        assert!(s
            .plan
            .refusals
            .iter()
            .any(|x| x.stage == Stage::Verify && x.reason.contains(&r.operation.to_string())));
    }
}

/// The 72 mm rib with flutes of 4 mm: levels deeper than the flutes make
/// the shank cut; those operations go, and the plan says it is incomplete.
#[test]
fn flutes_shorter_than_the_cut_make_shank_contact_and_the_plan_incomplete() {
    let mut s = to_order("tall_rib", load_knowledge(None).unwrap());
    s.knowledge = with_tools(s.knowledge.clone(), |t| t.flute_length = 4.0);
    s.run_stage(Stage::Verify).expect("verifies");
    let v = s.plan.verification.as_ref().unwrap();
    assert!(
        v.removed
            .iter()
            .any(|r| r.problem.kind == ProblemKind::ShankContact),
        "{:?}",
        v.removed.iter().map(|r| r.problem.kind).collect::<Vec<_>>()
    );
    assert_ne!(v.verdict, Verdict::Safe);
}

/// The unchanged plan verifies with nothing removed, in one replay, and
/// verifying again gives the same bytes.
#[test]
fn the_bundled_tall_rib_verifies_clean_and_deterministically() {
    let mut s = to_order("tall_rib", load_knowledge(None).unwrap());
    s.run_stage(Stage::Verify).expect("verifies");
    let first = serde_json::to_vec(&s.plan).unwrap();
    let v = s.plan.verification.as_ref().unwrap();
    assert!(v.removed.is_empty() && v.problems.is_empty(), "{v:?}");
    assert_eq!(v.rounds, 1);
    s.run_stage(Stage::Verify).expect("verifies again");
    assert_eq!(first, serde_json::to_vec(&s.plan).unwrap());
}
