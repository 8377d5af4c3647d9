use std::sync::atomic::AtomicBool;

use thinplan_pipeline::{load_knowledge, make_setup, ErrorKind, Session, SetupRequest};
use thinplan_plan::Stage;

fn session(source: &str) -> Session {
    let k = load_knowledge(None).expect("builtin knowledge");
    let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
    Session::open(source, setup, k).expect("opens")
}

#[test]
fn runs_stages_in_order_with_progress() {
    let mut s = session("builtin:tall_rib");
    let mut seen = Vec::new();
    s.run_all(|st| seen.push(st)).expect("plans");
    assert_eq!(
        seen,
        vec![
            Stage::Recognise,
            Stage::Sequence,
            Stage::Determine,
            Stage::Resolve,
            Stage::Operations,
            Stage::Order,
            Stage::Verify
        ]
    );
    assert!(s.plan.verification.is_some());
    assert!(s.plan.stages_done.contains(&Stage::Determine));
    assert!(!s.plan.machining_features.is_empty());
}

#[test]
fn rerunning_a_stage_drops_later_results() {
    let mut s = session("builtin:tall_rib");
    s.run_all(|_| {}).expect("plans");
    s.run_stage(Stage::Sequence).expect("sequence again");
    assert!(!s.plan.stages_done.contains(&Stage::Determine));
    assert!(s.plan.machining_features.is_empty());
    assert_eq!(s.next_stage(), Some(Stage::Determine));
}

#[test]
fn cancel_stops_before_the_next_stage() {
    let mut s = session("builtin:tall_rib");
    let err = s
        .run_to(Stage::Determine, &AtomicBool::new(true), |_| {})
        .unwrap_err();
    assert_eq!(err.kind, ErrorKind::Cancelled);
    assert!(!s.plan.stages_done.contains(&Stage::Recognise));
}

#[test]
fn a_stage_needs_its_predecessors() {
    let mut s = session("builtin:tall_rib");
    let err = s.run_stage(Stage::Determine).unwrap_err();
    assert_eq!(err.kind, ErrorKind::Stage);
}

#[test]
fn bad_inputs_are_named() {
    let k = load_knowledge(None).unwrap();
    let req = SetupRequest {
        machine: Some("nope".into()),
        ..Default::default()
    };
    let e = make_setup(&req, &k).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Knowledge);
    assert!(e.message.contains("nope"), "{}", e.message);
    let setup = make_setup(&SetupRequest::default(), &k).unwrap();
    let e = Session::open("/no/such/part.step", setup, k).err().unwrap();
    assert_eq!(e.kind, ErrorKind::Input);
    assert!(e.message.contains("/no/such/part.step"), "{}", e.message);
}

/// A plan through every stage saves and loads back to the same bytes.
#[test]
fn a_full_plan_round_trips_through_its_file() {
    let mut s = session("builtin:tall_rib");
    s.run_all(|_| {}).expect("plans");
    let dir = std::env::temp_dir().join(format!("thinplan-rt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.plan.json");
    thinplan_plan::save(&s.plan, &path).unwrap();
    let back = thinplan_plan::load(&path).unwrap();
    let (a, b) = (
        thinplan_plan::io::to_bytes(&s.plan),
        thinplan_plan::io::to_bytes(&back),
    );
    if a != b {
        let (a, b) = (String::from_utf8_lossy(&a), String::from_utf8_lossy(&b));
        let i = a
            .chars()
            .zip(b.chars())
            .position(|(x, y)| x != y)
            .unwrap_or(0);
        panic!(
            "differs at {i}: {:?} vs {:?}",
            &a[i.saturating_sub(80)..(i + 80).min(a.len())],
            &b[i.saturating_sub(80)..(i + 80).min(b.len())]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Verifying again starts from what stage 8 planned: operations the last
/// verification removed come back, and the verdict is made afresh.
#[test]
fn verifying_again_restores_removed_operations() {
    let mut s = session("builtin:tall_rib");
    s.run_all(|_| {}).expect("plans");
    let planned = s.plan.verification.as_ref().unwrap().planned_order.clone();
    // As if the verification had taken the first operation out.
    let first = s.plan.operation_order.remove(0);
    let at = s
        .plan
        .operations
        .iter()
        .position(|o| o.id == first)
        .unwrap();
    let op = s.plan.operations.remove(at);
    let v = s.plan.verification.as_mut().unwrap();
    v.removed.push(thinplan_plan::RemovedOperation {
        operation: first,
        problem: thinplan_plan::Problem {
            kind: thinplan_plan::ProblemKind::PlungeIntoStock,
            operation: Some(first),
            line: None,
            at: [0.0; 3],
            depth_mm: 1.0,
            volume_mm3: 1.0,
        },
        round: 1,
        removed: op,
    });
    s.run_stage(Stage::Verify).expect("verify again");
    let v = s.plan.verification.as_ref().unwrap();
    assert_eq!(v.planned_order, planned);
    assert!(s.plan.operations.iter().any(|o| o.id == first));
    assert_eq!(
        s.plan.operation_order.len() + v.removed.len(),
        planned.len()
    );
}
