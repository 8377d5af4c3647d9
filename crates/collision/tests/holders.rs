use glam::DVec3;
use thinplan_collision::{check, check_holders, collisions_json, Against, ToolPart};
use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{
    Operation, OperationId, PathMove, Plan, Provenance, ProvenanceSource, Region3,
};

fn planned(name: &str, k: Knowledge) -> Session {
    let setup = make_setup(&SetupRequest::default(), &k).expect("default set-up");
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
    s.run_all(|_| {}).expect("plans through stage 8");
    s
}

/// The built-in knowledge with the Ø20's stickout shortened, so that its
/// holder (Ø50, from the stickout up) comes down beside a 72 mm rib.
fn short_stickout(stickout: f64) -> Knowledge {
    let mut k = load_knowledge(None).unwrap();
    for set in k.tool_sets.values_mut() {
        for t in &mut set.tools {
            if t.id == "em20" {
                t.stickout = stickout;
            }
        }
    }
    k
}

fn mv(to: [f64; 3], region: Region3) -> PathMove {
    PathMove {
        to: DVec3::from_array(to),
        arc: None,
        feed: if region == Region3::Rapid {
            0.0
        } else {
            1000.0
        },
        region,
    }
}

#[test]
fn a_short_stickout_brings_the_holder_onto_the_rib_of_a_handmade_path() {
    let k = short_stickout(40.0);
    let s = planned("tall_rib", k.clone());
    // The part only: one operation of our own beside the rib (y 19.5–20.5,
    // top at z 92), 11 mm from its face.
    let mut plan = Plan::new(s.plan.part.clone(), s.plan.setup.clone());
    plan.operations.push(Operation {
        id: OperationId(0),
        feature: thinplan_plan::MachiningFeatureId(0),
        method: "test".into(),
        tool: "em20".into(),
        tool_axis: DVec3::Z,
        spindle_rpm: 10_000.0,
        start: DVec3::new(80.0, 31.5, 150.0),
        moves: vec![
            // Holder bottom stays at 100 and above: clear.
            mv([80.0, 31.5, 60.0], Region3::Rapid),
            // Down to 40: the holder (from 80 up, radius 25) meets the rib.
            mv([80.0, 31.5, 40.0], Region3::Link),
            mv([140.0, 31.5, 40.0], Region3::Rest),
            mv([80.0, 31.5, 150.0], Region3::Rapid),
        ],
        provenance: Provenance::new(ProvenanceSource::User, "test"),
    });
    plan.operation_order = vec![OperationId(0)];
    let c = check_holders(&plan, &k, &s.brep);
    let holder: Vec<_> = c.iter().filter(|c| c.what == ToolPart::Holder).collect();
    assert!(!holder.is_empty(), "{c:?}");
    let first = holder[0];
    assert_eq!((first.operation, first.move_index), (OperationId(0), 1));
    assert_eq!(first.against, Against::Part);
    // 25 − 11 mm radially; lowest point of move 1: holder bottom at 80,
    // rib top at 92.
    assert!((first.penetration - 14.0).abs() < 1e-6, "{first:?}");
    assert!((first.lift - 12.0).abs() < 1e-6, "{first:?}");
    assert!((first.position.z - 40.0).abs() < 1e-6, "{first:?}");
    // Move 2 runs along the rib at that height: hit too; the rapid out is
    // checked as well (it rises past the rib).
    assert!(holder.iter().any(|c| c.move_index == 2));
    assert!(!c.iter().any(|c| c.move_index == 0), "{c:?}");
    // The shank (radius 10 from 30 to 40 above the tip) stays 1 mm away.
    assert!(!c.iter().any(|c| c.what == ToolPart::Shank), "{c:?}");
    let j = collisions_json(&c);
    assert_eq!(j[0]["what"], "holder");
    assert_eq!(j[0]["operation"], "OP0");
    assert_eq!(j[0]["against"], "part");
}

#[test]
fn a_short_stickout_is_found_in_the_planned_tall_rib() {
    let stickout = 40.0;
    let k = short_stickout(stickout);
    let s = planned("tall_rib", k.clone());
    let c = check_holders(&s.plan, &k, &s.brep);
    // Independently: the first move in the order whose tip goes below the
    // rib's top less the stickout, with the em20, beside the rib.
    let rib_top = 92.0;
    let mut expected = None;
    'ops: for id in &s.plan.operation_order {
        let op = s.plan.operations.iter().find(|o| o.id == *id).unwrap();
        if op.tool != "em20" {
            continue;
        }
        for (i, m) in op.moves.iter().enumerate() {
            if m.to.z + stickout < rib_top - 1e-3 {
                expected = Some((*id, i));
                break 'ops;
            }
        }
    }
    let expected = expected.expect("some move goes deep enough");
    let first = c
        .iter()
        .find(|c| c.what == ToolPart::Holder && c.against == Against::Part)
        .expect("the holder hits the rib");
    assert_eq!((first.operation, first.move_index), expected, "{c:?}");
}

/// The bundled samples as planned today: holder collisions are a failure;
/// shank collisions (with material no operation removes) are printed so the
/// numbers stay visible.
#[test]
fn planned_samples_have_no_holder_collision() {
    let mut failures = Vec::new();
    for (name, _) in thinplan_import::SAMPLES {
        let k = load_knowledge(None).unwrap();
        let s = planned(name, k.clone());
        let r = check(&s.plan, &k, &s.brep);
        let holder = r
            .collisions
            .iter()
            .filter(|c| c.what == ToolPart::Holder)
            .count();
        let mut against: std::collections::BTreeMap<String, usize> = Default::default();
        for c in &r.collisions {
            *against
                .entry(format!("{} {} {}", c.operation, c.what.name(), c.against))
                .or_default() += 1;
        }
        println!(
            "{name}: {} operation(s), {} piece(s), {} collision(s) ({holder} holder): {against:?}; unchecked {:?}",
            s.plan.operations.len(),
            r.pieces,
            r.collisions.len(),
            r.unchecked
        );
        if holder > 0 {
            failures.push(format!("{name}: {holder} holder collision(s)"));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

#[test]
fn deterministic() {
    let k = load_knowledge(None).unwrap();
    let s = planned("wing_rib", k.clone());
    let a = collisions_json(&check_holders(&s.plan, &k, &s.brep));
    let b = collisions_json(&check_holders(&s.plan, &k, &s.brep));
    assert_eq!(a.to_string(), b.to_string());
}
