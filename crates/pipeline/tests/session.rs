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
            Stage::Order
        ]
    );
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
