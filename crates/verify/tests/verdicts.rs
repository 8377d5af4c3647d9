//! Stage 9 on cases made to fail: a tool that cuts wider than the one the
//! paths were planned for gouges; knowledge whose flutes are shorter than
//! the levels are deep makes the shank cut. Each failing operation is taken
//! out with its problem, none is left in the program, and the verdict says
//! the plan is not complete.

use std::sync::atomic::AtomicBool;

use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{ProblemKind, Region3, Replan, Stage, Verdict};

fn to_order(name: &str, k: Knowledge) -> Session {
    to_order_with(name, k, None)
}

fn to_order_with(name: &str, k: Knowledge, tool_set: Option<&str>) -> Session {
    let req = SetupRequest {
        tool_set: tool_set.map(str::to_string),
        ..SetupRequest::default()
    };
    let setup = make_setup(&req, &k).expect("set-up");
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
    // Each was first sent to the end of the program (where the rib's own
    // levels still stand over the flutes), then removed.
    assert!(
        v.replanned
            .iter()
            .any(|r| r.how == Replan::RunLast && r.problem.kind == ProblemKind::ShankContact),
        "{:?}",
        v.replanned
            .iter()
            .map(|r| (r.how, r.problem.kind))
            .collect::<Vec<_>>()
    );
    assert!(
        v.problems.is_empty(),
        "nothing unsafe is left: {:?}",
        v.problems
    );
    assert!(
        v.removed
            .iter()
            .any(|r| r.problem.kind == ProblemKind::ShankContact),
        "{:?}",
        v.removed.iter().map(|r| r.problem.kind).collect::<Vec<_>>()
    );
    assert_ne!(v.verdict, Verdict::Safe);
}

/// The unchanged plan, with the Ø12/Ø20 set whose long stickouts reach the
/// web from the top, verifies with nothing removed, in one replay, and
/// verifying again gives the same bytes.
#[test]
fn the_bundled_tall_rib_verifies_clean_and_deterministically() {
    let mut s = to_order_with(
        "tall_rib",
        load_knowledge(None).unwrap(),
        Some("endmills_12_20"),
    );
    s.run_stage(Stage::Verify).expect("verifies");
    let first = serde_json::to_vec(&s.plan).unwrap();
    let v = s.plan.verification.as_ref().unwrap();
    assert!(v.removed.is_empty() && v.problems.is_empty(), "{v:?}");
    assert!(v.replanned.is_empty());
    assert_eq!(v.rounds, 1);
    s.run_stage(Stage::Verify).expect("verifies again");
    assert_eq!(first, serde_json::to_vec(&s.plan).unwrap());
}

/// Stage 8 planned with a plunge allowance far above the verification's
/// (its map then turns no descent into a ramp), verified with the
/// knowledge's: the replay finds the feed plunges into stock, and those
/// operations are planned again, every fed descent a ramp (straight only
/// as a rapid in the air above the stock); nothing unsafe is left. Verifying again starts from stage 8's
/// operations (the replanned ones are restored first) and gives the same
/// bytes.
#[test]
fn plunges_the_replay_finds_are_planned_again_as_ramps() {
    let k = load_knowledge(None).unwrap();
    let mut lax = k.clone();
    lax.verification.max_plunge_mm3 = 1.0e6;
    let mut s = to_order("tall_rib", lax);
    s.knowledge = k;
    let planned = s.plan.operations.clone();
    s.run_stage(Stage::Verify).expect("verifies");
    let first = serde_json::to_vec(&s.plan).unwrap();
    let v = s.plan.verification.as_ref().unwrap();
    assert!(v.problems.is_empty(), "{:?}", v.problems);
    assert_ne!(v.verdict, Verdict::Unsafe);
    let ramped: Vec<_> = v
        .replanned
        .iter()
        .filter(|r| r.how == Replan::RampedEntries)
        .collect();
    let mut kept = 0;
    for r in ramped {
        assert_eq!(r.problem.kind, ProblemKind::PlungeIntoStock);
        assert_eq!(
            Some(&r.planned),
            planned.iter().find(|o| o.id == r.operation)
        );
        // Kept, or removed when it failed again.
        let Some(now) = s.plan.operations.iter().find(|o| o.id == r.operation) else {
            assert!(v.removed.iter().any(|x| x.operation == r.operation));
            continue;
        };
        kept += 1;
        assert!(now.provenance.values["entries_ramped_on_replay"] >= 1.0);
        // No straight fed descent is left in it.
        let mut pos = now.start;
        for m in &now.moves {
            let straight_down = m.arc.is_none()
                && (m.to.truncate() - pos.truncate()).length() < 1e-9
                && m.to.z < pos.z - 1e-6;
            let fed = m.region != Region3::Rapid && m.feed > 0.0;
            assert!(!(straight_down && fed), "{pos} → {}", m.to);
            pos = m.to;
        }
    }
    assert!(kept > 0, "no operation kept with ramps");
    s.run_stage(Stage::Verify).expect("verifies again");
    assert_eq!(first, serde_json::to_vec(&s.plan).unwrap());
}

/// Stage 9's remedy for a rapid that met stock: every rapid link of the
/// operation that travels across below the top goes up to it, across and
/// straight down to where it ended; its cutting moves are untouched.
#[test]
fn links_raised_over_the_top_keep_every_cut_and_every_link_end() {
    let mut s = to_order("tall_rib", load_knowledge(None).unwrap());
    let top = s.brep.bbox().max.z + s.knowledge.methods.safe_clearance;
    let is_rapid = |m: &thinplan_plan::PathMove| m.region == thinplan_plan::Region3::Rapid;
    let low_across = |o: &thinplan_plan::Operation| {
        let mut pos = o.start;
        o.moves.iter().any(|m| {
            let across = is_rapid(m) && (m.to.truncate() - pos.truncate()).length() > 1e-9;
            let low = m.to.z < top - 1e-9;
            pos = m.to;
            across && low
        })
    };
    let op = s
        .plan
        .operations
        .iter()
        .find(|o| low_across(o))
        .cloned()
        .expect("an operation with a lowered link");
    let n = thinplan_operations::links::raise_links(&mut s.plan, &s.knowledge, op.id, top)
        .expect("raises");
    assert!(n > 0);
    let now = s.plan.operations.iter().find(|o| o.id == op.id).unwrap();
    assert!(!low_across(now), "a rapid still crosses below {top}");
    let cuts = |o: &thinplan_plan::Operation| {
        o.moves
            .iter()
            .filter(|m| !is_rapid(m))
            .cloned()
            .collect::<Vec<_>>()
    };
    assert_eq!(cuts(&op), cuts(now));
    // Each cut starts where it started before.
    let starts = |o: &thinplan_plan::Operation| {
        let mut pos = o.start;
        let mut out = Vec::new();
        for m in &o.moves {
            if !is_rapid(m) {
                out.push(pos);
            }
            pos = m.to;
        }
        out
    };
    assert_eq!(starts(&op), starts(now));
    assert_eq!(now.provenance.values["links_raised_on_replay"], n as f64);
}

/// The rounds that only remove: with one replay and none after it, the
/// operations of the set's largest tools, replayed 2 mm wider than
/// planned, are found gouging, but nothing confirms a program without
/// them: unsafe, no program. With removal rounds after it, each removal is
/// confirmed by the next replay: incomplete, no problem left, the smaller
/// tools' operations kept.
#[test]
fn removal_rounds_confirm_a_program_without_the_failing_operations() {
    let run = |removal_rounds: u32| {
        let mut s = to_order("wing_rib", load_knowledge(None).unwrap());
        s.knowledge = with_tools(s.knowledge.clone(), |t| {
            if t.diameter > 15.0 {
                t.diameter += 2.0;
                t.shank_diameter += 2.0;
            }
        });
        s.knowledge.verification.max_rounds = 1;
        s.knowledge.verification.max_removal_rounds = removal_rounds;
        s.run_stage(Stage::Verify).expect("verifies");
        s.plan.verification.clone().unwrap()
    };
    let none = run(0);
    assert_eq!(none.verdict, Verdict::Unsafe);
    assert_eq!(none.rounds, 1);
    let some = run(4);
    assert_eq!(some.verdict, Verdict::Incomplete, "{:?}", some.problems);
    assert!(some.problems.is_empty());
    assert!(
        some.rounds > 1 && some.rounds <= 5,
        "{} {:?}",
        some.rounds,
        some.removed.len()
    );
    assert!(!some.removed.is_empty());
    assert!(some.removed.len() < some.planned_order.len());
}
