//! The stage on a plan: `run`, `apply_to` and `from_plan`.

mod common;

use common::*;
use thinplan_knowledge::Knowledge;
use thinplan_plan::*;
use thinplan_sequence::{run, try_add, Sequencing};

fn plan() -> Plan {
    let setup = Setup {
        up: UP,
        machine: "hsm_5axis".into(),
        tool_set: "endmills_12_20".into(),
        material: "al7075".into(),
        provenance: Provenance::new(ProvenanceSource::Default, "setup.default"),
    };
    let part = PartRef {
        source: "test:thesis_part".into(),
        format: PartFormat::Native,
        sha256: "00".repeat(32),
        declared_units: "mm".into(),
        summary: PartSummary {
            solids: 1,
            faces: 0,
            bbox: [0.0; 3],
            volume: 0.0,
        },
    };
    let mut plan = Plan::new(part, setup);
    let (features, connections) = thesis_part();
    plan.stiffness_features = features;
    plan.connections = connections;
    plan.stages_done.extend([Stage::Recognise, Stage::Connect]);
    plan
}

#[test]
fn the_stage_writes_into_the_plan_and_reads_back() {
    let k = Knowledge::builtin().unwrap();
    let mut p = plan();
    // A stale refusal of this stage and a later stage's output go away.
    p.refusals.push(Refusal {
        stage: Stage::Sequence,
        rule: "stale".into(),
        reason: "stale".into(),
        provenance: Provenance::new(ProvenanceSource::User, "stale"),
    });
    p.stages_done.push(Stage::Sequence);
    p.stages_done.push(Stage::Determine);
    let s = run(&p, &k);
    assert_eq!(s.constraints.len(), 6);
    s.clone().apply_to(&mut p);
    assert_eq!(
        p.stages_done,
        [
            Stage::Import,
            Stage::Setup,
            Stage::Recognise,
            Stage::Connect,
            Stage::Sequence
        ]
    );
    assert_eq!(p.stiffness_constraints, s.constraints);
    assert_eq!(p.refusals, s.refusals);
    assert_eq!(Sequencing::from_plan(&p), s);

    // An edit through the plan's own record.
    let mut back = Sequencing::from_plan(&p);
    let edit = Constraint {
        first: id(1),
        second: id(2),
        kind: ConstraintKind::Before,
        priority: 0,
        provenance: Provenance::new(ProvenanceSource::User, "user.edit"),
    };
    assert!(try_add(&mut back, edit).is_err());
}
