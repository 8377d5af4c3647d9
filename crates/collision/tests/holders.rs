use glam::DVec3;
use thinplan_collision::{check, check_holders, collisions_json, Against, ToolPart};
use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::{
    Operation, OperationId, PathMove, Plan, Provenance, ProvenanceSource, Region3,
};

fn planned(name: &str, k: Knowledge) -> Session {
    planned_with(name, k, None)
}

/// The short-stickout cases are about the Ø12/Ø20 set's em20 (holder Ø50).
const SET: Option<&str> = Some("endmills_12_20");

fn planned_with(name: &str, k: Knowledge, tool_set: Option<&str>) -> Session {
    let req = SetupRequest {
        tool_set: tool_set.map(str::to_string),
        ..SetupRequest::default()
    };
    let setup = make_setup(&req, &k).expect("set-up");
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
    // Stage 8's program as it stands: the verification would take out the
    // operations these tests look for.
    s.run_to(
        thinplan_plan::Stage::Order,
        &std::sync::atomic::AtomicBool::new(false),
        |_| {},
    )
    .expect("plans through stage 8");
    s
}

/// Paths planned for the em20 as the knowledge gives it, verified with its
/// stickout shortened (a tool shrunk in deeper than the knowledge says):
/// the operations whose holder comes down on the stock are taken out of
/// the program, each with the holder collision that made it go, and none
/// is left in it. (Planned with the short stickout, the em20 is not chosen
/// for the levels it does not reach.)
#[test]
fn the_verification_takes_out_operations_whose_holder_hits_the_stock() {
    let k = short_stickout(40.0);
    let mut s = planned_with("tall_rib", load_knowledge(None).unwrap(), SET);
    s.knowledge = k.clone();
    s.run_stage(thinplan_plan::Stage::Verify).expect("verifies");
    let v = s.plan.verification.as_ref().unwrap();
    let holder = v
        .removed
        .iter()
        .filter(|r| r.problem.kind == thinplan_plan::ProblemKind::HolderCollision)
        .count();
    assert!(holder > 0, "{:?}", v.removed);
    assert_ne!(v.verdict, thinplan_plan::Verdict::Safe);
    let left = check(&s.plan, &k, &s.brep);
    assert!(
        !left.collisions.iter().any(|c| c.what == ToolPart::Holder),
        "holder collisions left in the program"
    );
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
    let s = planned_with("tall_rib", k.clone(), SET);
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
        schedule: Default::default(),
        provenance: Provenance::new(ProvenanceSource::User, "test"),
        link_z: None,
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
    // Planned for the em20 as the knowledge gives it, checked with the
    // short stickout.
    let s = planned_with("tall_rib", load_knowledge(None).unwrap(), SET);
    let c = check_holders(&s.plan, &k, &s.brep);
    // Independently: the first move in the order whose tip goes below the
    // rib's top less the stickout, with the em20, beside the rib or the
    // steps (as tall as the rib) that still stand.
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
    // The remaining material around the rib's steps runs first (the shank
    // rule), beside the steps that still stand as tall as the rib: the
    // holder's first hit may be one of them rather than the rib itself.
    let first = c
        .iter()
        .find(|c| c.what == ToolPart::Holder)
        .expect("the holder hits the rib or the steps beside it");
    assert!(
        c.iter()
            .any(|c| c.what == ToolPart::Holder && c.against == Against::Part),
        "the holder hits the rib somewhere: {c:?}"
    );
    assert_eq!((first.operation, first.move_index), expected, "{c:?}");
}

/// The bundled samples as planned today: no holder or shank collision at
/// all (printed, so the numbers stay visible). Until stage 5 let the
/// flange-before-web order give way to shanks, flange_cutouts had 128 shank
/// collisions, flange_web_slot 75 and wing_rib 82: a flange's narrow lower
/// step cut before the web layers standing over it.
#[test]
fn planned_samples_have_no_holder_or_shank_collision() {
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
        let shank = r.collisions.len() - holder;
        if shank > 0 {
            failures.push(format!("{name}: {shank} shank collision(s)"));
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

/// Distance from `p` to the loops of `b` in plan view.
fn boundary_distance(b: &thinplan_collision::Body, p: glam::DVec2) -> f64 {
    let mut d = f64::INFINITY;
    for lp in &b.loops {
        for i in 0..lp.len() {
            let (a, c) = (lp[i], lp[(i + 1) % lp.len()]);
            let ac = c - a;
            let t = ((p - a).dot(ac) / ac.length_squared().max(1e-300)).clamp(0.0, 1.0);
            d = d.min((a + ac * t).distance(p));
        }
    }
    d
}

/// A short tool whose holder comes down into a tall machining feature that
/// is still in the stock: found and named; with that feature's operation
/// run first, the same path is clean.
#[test]
fn a_short_holder_hits_a_tall_unremoved_feature_and_not_once_it_is_removed() {
    let mut k = load_knowledge(None).unwrap();
    let s = planned("tall_rib", k.clone());
    let frame = thinplan_collision::setup_frame(s.plan.setup.up);
    // The feature reaching highest (then the tallest): nothing is above it.
    let (f, body) = s
        .plan
        .machining_features
        .iter()
        .filter_map(|f| Some((f, thinplan_collision::feature_body(f, &frame).ok()?)))
        .max_by(|(_, a), (_, b)| {
            a.z_hi
                .total_cmp(&b.z_hi)
                .then((a.z_hi - a.z_lo).total_cmp(&(b.z_hi - b.z_lo)))
        })
        .expect("tall_rib has machining features");
    // The point deepest inside it on a 40 × 40 grid over its bounding box.
    let (mid, room) = (0..=40 * 41)
        .map(|n| {
            let t = glam::DVec2::new((n % 41) as f64, (n / 41) as f64) / 40.0;
            body.lo + (body.hi - body.lo) * t
        })
        .filter(|p| body.contains(*p))
        .map(|p| (p, boundary_distance(&body, p)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a point inside");
    assert!(room > 2.0, "{}: only {room} mm inside", f.id);
    // A tool with no shank (flutes up to the holder) and a holder that fits
    // inside the feature in plan view: only the feature can be hit.
    let stickout = 10.0;
    let holder_r = (0.5 * room).min(5.0);
    let set = s.plan.setup.tool_set.clone();
    let tools = &mut k.tool_sets.get_mut(&set).unwrap().tools;
    let mut short = tools[0].clone();
    short.id = "short".into();
    short.flute_length = stickout;
    short.stickout = stickout;
    short.holder_diameter = 2.0 * holder_r;
    short.holder_length = 30.0;
    tools.push(short);
    // The holder's bottom 1 mm into the feature's top, axis at `mid`.
    let tip_z = body.z_hi - 1.0 - stickout;
    let world = |x: f64, y: f64, z: f64| frame.to_world(DVec3::new(x, y, z));
    let other = s
        .plan
        .machining_features
        .iter()
        .find(|g| g.id != f.id)
        .expect("another feature")
        .id;
    let op = |id: u32, feature, moves: Vec<PathMove>| Operation {
        id: OperationId(id),
        feature,
        method: "test".into(),
        tool: "short".into(),
        tool_axis: s.plan.setup.up,
        spindle_rpm: 10_000.0,
        start: world(mid.x, mid.y, body.z_hi + 100.0),
        moves,
        schedule: Default::default(),
        provenance: Provenance::new(ProvenanceSource::User, "test"),
        link_z: None,
    };
    let down = |p: DVec3| mv(p.to_array(), Region3::Link);
    let mut plan = Plan::new(s.plan.part.clone(), s.plan.setup.clone());
    plan.machining_features = s.plan.machining_features.clone();
    // OP0 belongs to another feature and dips beside nothing but `f`;
    // OP1 is `f`'s own operation (a move in the air: removal is by order).
    plan.operations = vec![
        op(
            0,
            other,
            vec![
                down(world(mid.x, mid.y, tip_z)),
                mv(
                    world(mid.x, mid.y, body.z_hi + 100.0).to_array(),
                    Region3::Rapid,
                ),
            ],
        ),
        op(
            1,
            f.id,
            vec![mv(
                world(mid.x, mid.y, body.z_hi + 50.0).to_array(),
                Region3::Rapid,
            )],
        ),
    ];
    // Every other feature is removed before (its own air operation first),
    // so only `f` is left to hit.
    let mut order = Vec::new();
    for (n, g) in s.plan.machining_features.iter().enumerate() {
        if g.id != f.id && g.id != other {
            let id = 2 + n as u32;
            plan.operations.push(op(
                id,
                g.id,
                vec![mv(
                    world(mid.x, mid.y, body.z_hi + 50.0).to_array(),
                    Region3::Rapid,
                )],
            ));
            order.push(OperationId(id));
        }
    }
    plan.operation_order = order
        .iter()
        .copied()
        .chain([OperationId(0), OperationId(1)])
        .collect();
    let r = check(&plan, &k, &s.brep);
    assert!(r.unchecked.is_empty(), "{:?}", r.unchecked);
    // The move down and the rapid back up (it starts inside) both hit it,
    // nothing else is hit.
    assert_eq!(r.collisions.len(), 2, "{:?}", r.collisions);
    assert!(r
        .collisions
        .iter()
        .all(|c| c.operation == OperationId(0) && c.against == Against::Feature(f.id)));
    let c = &r.collisions[0];
    // The axis is `room` inside the feature: the holder overlaps it by its
    // radius plus that.
    assert!((c.penetration - (holder_r + room)).abs() < 1e-6, "{c:?}");
    assert_eq!(
        (c.operation, c.move_index, c.what, c.against),
        (OperationId(0), 0, ToolPart::Holder, Against::Feature(f.id))
    );
    assert!((c.lift - 1.0).abs() < 1e-6, "{c:?}");
    assert_eq!(
        collisions_json(&r.collisions)[0]["against"],
        f.id.to_string()
    );
    // Refused (no operation in the order removes it, as for
    // `operations.unreachable`): it stays in the stock for every later
    // operation.
    plan.operation_order = order.iter().copied().chain([OperationId(0)]).collect();
    assert_eq!(check(&plan, &k, &s.brep).collisions, r.collisions);
    // The feature's operation first: the same path is clean.
    plan.operation_order = order
        .into_iter()
        .chain([OperationId(1), OperationId(0)])
        .collect();
    let r = check(&plan, &k, &s.brep);
    assert!(r.collisions.is_empty(), "{:?}", r.collisions);
}
