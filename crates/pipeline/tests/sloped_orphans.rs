//! Stage 7's second pass beside sloped faces. In flange_cutouts the R8
//! bottoms of the cut-outs in the 2 mm flange are cut in slabs, each from
//! beside the flange; at the first two cut-outs the web's pocket beyond
//! y = 13 still stands when the lowest slabs are cut, so their tools come
//! from the flange's outer side alone and the middle of the flange's
//! thickness stays. The second pass must take those slabs again from the
//! inner side, run after every feature, keep off the round bottoms, and cut
//! lower there than any first-pass operation (by more than the stock
//! simulation's 0.05 mm tolerance). The part's geometry is the
//! sample's own definition, written here (`part_top`), not the planner's.

mod common;

use common::cutting_centres;
use glam::DVec2;
use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::Operation;

/// Cut-out centres along x; the R8 bottoms' centres stand at z = 33.
const CUTOUTS: [f64; 3] = [50.0, 100.0, 150.0];

/// The flange's top at `x` (the flange lies in y 0..2): 40, less the
/// U-shaped cut-outs 16 wide with R8 bottoms centred at z = 33.
fn part_top(x: f64) -> f64 {
    for c in CUTOUTS {
        let d = (x - c).abs();
        if d < 8.0 {
            return 33.0 - (64.0 - d * d).sqrt();
        }
    }
    40.0
}

fn is_orphan(o: &Operation) -> bool {
    o.provenance.values.get("orphan_stretches") == Some(&1.0)
}

#[test]
fn slabs_beside_round_bottoms_left_mid_flange_are_taken_again_from_inside() {
    let k = load_knowledge(None).unwrap();
    // The situation above arises with the Ø12/Ø20 set: wider than the
    // flange's cut-outs' slabs, they reach them from beside the flange.
    let req = SetupRequest {
        tool_set: Some("endmills_12_20".into()),
        ..SetupRequest::default()
    };
    let setup = make_setup(&req, &k).unwrap();
    let mut s = Session::open("builtin:flange_cutouts", setup, k.clone()).unwrap();
    s.run_all(|_| {}).unwrap();
    let plan = &s.plan;
    let tools = k.tool_set(&plan.setup.tool_set).unwrap();
    let sloped: Vec<&Operation> = plan
        .operations
        .iter()
        .filter(|o| {
            is_orphan(o)
                && plan.machining_features[o.feature.0 as usize]
                    .slopes
                    .is_some()
        })
        .collect();
    assert!(
        !sloped.is_empty(),
        "no second-pass operation beside a sloped face"
    );

    // After every feature's own operations.
    let at = |o: &Operation| {
        plan.operation_order
            .iter()
            .position(|id| *id == o.id)
            .expect("in the order")
    };
    let last_first_pass = plan
        .operations
        .iter()
        .filter(|o| !thinplan_operations::runs_last(o))
        .map(at)
        .max()
        .unwrap();
    for o in &sloped {
        assert!(thinplan_operations::runs_last(o), "OP{}", o.id.0);
        assert!(
            at(o) > last_first_pass,
            "OP{} runs before a feature's own",
            o.id.0
        );
    }

    // Off the round bottoms: every point of the tool's lower surface (flat
    // disc and corner torus) over the flange at or above its top there.
    for o in &sloped {
        let t = tools.tools.iter().find(|t| t.id == o.tool).unwrap();
        let (r, rc) = (0.5 * t.diameter, t.corner_radius);
        let centres = cutting_centres(o);
        assert!(!centres.is_empty());
        for c in &centres {
            for i in 0..=24 {
                let rho = r * i as f64 / 24.0;
                let lift = if rho > r - rc {
                    let u = rho - (r - rc);
                    rc - (rc * rc - u * u).max(0.0).sqrt()
                } else {
                    0.0
                };
                for j in 0..72 {
                    let a = std::f64::consts::TAU * j as f64 / 72.0;
                    let q = c.truncate() + rho * DVec2::new(a.cos(), a.sin());
                    if (0.0..=2.0).contains(&q.y) {
                        assert!(
                            c.z + lift >= part_top(q.x) - 1e-3,
                            "OP{} at {c:?} cuts the flange at {q:?}: {} below its top",
                            o.id.0,
                            part_top(q.x) - c.z - lift
                        );
                    }
                }
            }
        }
        // From the inner side: the web's side of the flange.
        assert!(
            centres.iter().all(|c| c.y > 2.0),
            "OP{} not wholly on the inner side",
            o.id.0
        );
    }

    // Lower than any other operation over the middle of the flange's
    // thickness, beside the first two cut-outs' lowest points.
    let lowest = |ops: &mut dyn Iterator<Item = &Operation>, p: DVec2| {
        ops.flat_map(|o| {
            let r = 0.5
                * tools
                    .tools
                    .iter()
                    .find(|t| t.id == o.tool)
                    .unwrap()
                    .diameter;
            cutting_centres(o)
                .into_iter()
                .filter(move |c| c.truncate().distance(p) <= r)
                .map(|c| c.z)
        })
        .fold(f64::INFINITY, f64::min)
    };
    for c in &CUTOUTS[..2] {
        for dx in [-1.1, 1.1] {
            let p = DVec2::new(c + dx, 1.5);
            let second = lowest(&mut sloped.iter().copied(), p);
            let first = lowest(&mut plan.operations.iter().filter(|o| !is_orphan(o)), p);
            // by more than the stock simulation's tolerance
            assert!(
                second < first - 0.05,
                "at {p:?}: the second pass reaches {second}, the first {first}"
            );
        }
    }
}
