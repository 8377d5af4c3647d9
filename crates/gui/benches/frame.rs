//! Per-frame CPU cost of the application with 1 M tool-path segments and
//! 10 000 machining-feature volumes loaded (the budget: under 10 ms).
//!
//! `cargo bench -p thinplan-gui --bench frame` (headless, software GL). It
//! prints the first frame (scene built and uploaded once), then the mean and
//! worst of steady frames while the camera orbits: the application's own
//! work plus egui's layout and tessellation (`Harness::step`), and, apart,
//! a full software-rendered frame (llvmpipe rasterises on the CPU, so that
//! number is an upper bound no GPU machine sees).

use std::time::{Duration, Instant};

use eframe::egui::Vec2;
use egui_kittest::Harness;
use glam::DVec3;
use thinplan_gui::{AppState, Entity, ThinplanApp};
use thinplan_plan::{
    MachiningFeatureId, Operation, OperationId, PathMove, Plan, Prism, PrismFrame, ProfileLoop,
    ProfileVertex, Provenance, ProvenanceSource, Region, Region3,
};

const FEATURES: usize = 10_000;
const SEGMENTS: usize = 1_000_000;
const OPERATIONS: usize = 100;

fn big_plan(base: &Plan) -> Plan {
    let mut plan = base.clone();
    let template = plan
        .machining_features
        .first()
        .cloned()
        .expect("a machining feature");
    plan.machining_features.clear();
    plan.machining_constraints.clear();
    plan.operations.clear();
    let owner = plan
        .stiffness_features
        .first()
        .map(|f| f.id)
        .expect("a feature");
    let side = (FEATURES as f64).sqrt().ceil() as usize;
    for i in 0..FEATURES {
        let (x, y) = ((i % side) as f64 * 3.0, (i / side) as f64 * 3.0);
        let v = |x: f64, y: f64| ProfileVertex { x, y, bulge: 0.0 };
        // Cloned from a real feature so the bench follows the model's fields.
        let mut f = template.clone();
        f.id = MachiningFeatureId(i as u32);
        f.owner = owner;
        f.shape = Prism {
            frame: PrismFrame {
                origin: DVec3::new(x, y, 0.0),
                x: DVec3::X,
                z: DVec3::Z,
            },
            region: Region {
                outer: ProfileLoop {
                    vertices: vec![v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)],
                },
                holes: vec![],
            },
            z_min: 0.0,
            z_max: 1.0 + (i % 7) as f64 * 0.2,
        };
        plan.machining_features.push(f);
    }
    let per_op = SEGMENTS / OPERATIONS;
    let regions = [
        Region3::Boundary,
        Region3::FullCut,
        Region3::Rest,
        Region3::Link,
    ];
    for o in 0..OPERATIONS {
        let z = 2.0 + o as f64 * 0.05;
        let moves = (0..per_op)
            .map(|k| {
                let row = k / 200;
                let col = k % 200;
                let x = if row % 2 == 0 { col } else { 199 - col } as f64 * 1.5;
                PathMove {
                    to: DVec3::new(x, row as f64 * 0.6, z),
                    arc: None,
                    feed: 3000.0,
                    region: regions[(k / 50) % regions.len()],
                }
            })
            .collect();
        plan.operations.push(Operation {
            id: OperationId(o as u32),
            feature: MachiningFeatureId(o as u32),
            method: "bench".into(),
            tool: "t".into(),
            tool_axis: DVec3::Z,
            spindle_rpm: 20000.0,
            start: DVec3::new(0.0, 0.0, z + 5.0),
            moves,
            schedule: Default::default(),
            provenance: Provenance::new(ProvenanceSource::User, "bench"),
            link_z: None,
        });
    }
    plan
}

/// Median and worst in ms: the median, because on a shared 2-core
/// machine a few frames land behind other processes.
fn stats(v: &[Duration]) -> (f64, f64) {
    let mut ms: Vec<f64> = v.iter().map(|d| d.as_secs_f64() * 1e3).collect();
    ms.sort_by(f64::total_cmp);
    let median = ms[ms.len() / 2];
    let worst = ms.last().copied().unwrap_or(0.0);
    (median, worst)
}

/// One frame's CPU work: the application and egui's layout, then the
/// tessellation of what it painted.
fn frame(h: &mut Harness<'_, ThinplanApp>) -> Duration {
    let t = Instant::now();
    h.step();
    let shapes = h.output().shapes.clone();
    let _ = h.ctx.tessellate(shapes, 1.0);
    t.elapsed()
}

fn main() {
    let mut state = AppState::open_default("builtin:tall_rib");
    state.run_all();
    state.wait_job();
    let plan = big_plan(state.plan().expect("plan"));
    let segments: usize = plan.operations.iter().map(|o| o.moves.len()).sum();
    assert!(state.replace_plan(plan));
    let mut h = Harness::builder()
        .with_size(Vec2::new(1400.0, 900.0))
        .wgpu()
        .build_eframe(move |cc| ThinplanApp::from_state(cc, state));
    // A selected machining feature puts the network view on the 10 000-node level.
    h.state_mut()
        .state
        .select(Some(Entity::Machining(MachiningFeatureId(5000))));

    let t = Instant::now();
    h.step();
    let first_step = t.elapsed();
    let t = Instant::now();
    h.render().expect("render");
    let first_render = t.elapsed();

    let n = 100;
    let mut steps = Vec::new();
    for _ in 0..n {
        h.state_mut().viewport.camera.yaw += 0.02;
        steps.push(frame(&mut h));
    }
    // The network panned every frame: its shapes are rebuilt each time.
    let mut panned = Vec::new();
    for _ in 0..n {
        h.state_mut().network.offset.x += 1.0;
        panned.push(frame(&mut h));
    }
    let reused = h.state().network.reused;
    // The same with the network view on the stiffness level (a few nodes):
    // what the 10 000-node network drawing costs.
    h.state_mut().state.select(Some(Entity::Part));
    h.state_mut().network.level = thinplan_gui::network::Level::Stiffness;
    h.step();
    let mut small = Vec::new();
    for _ in 0..n {
        h.state_mut().viewport.camera.yaw += 0.02;
        small.push(frame(&mut h));
    }
    let mut renders = Vec::new();
    for _ in 0..5 {
        h.state_mut().viewport.camera.yaw += 0.02;
        h.step();
        let t = Instant::now();
        h.render().expect("render");
        renders.push(t.elapsed());
    }
    let scene = h.state().viewport.scene();
    println!(
        "loaded: {} machining features, {} tool-path segments ({} line vertices, {} triangles)",
        FEATURES,
        segments,
        scene.lines.len(),
        scene.indices.len() / 3
    );
    println!(
        "first frame: ui {:.1} ms (scene built once), software render + upload {:.1} ms",
        first_step.as_secs_f64() * 1e3,
        first_render.as_secs_f64() * 1e3
    );
    let (m, w) = stats(&steps);
    println!("steady frame CPU (app + egui layout/tessellation), {n} frames, camera orbiting, network on the 10 000-node level: median {m:.2} ms, worst {w:.2} ms");
    let (m, w) = stats(&panned);
    println!("  the same with the network panned every frame (its shapes rebuilt): median {m:.2} ms, worst {w:.2} ms");
    let (m, w) = stats(&small);
    println!("  the same with the network on the stiffness level (a few nodes): median {m:.2} ms, worst {w:.2} ms");
    println!("  network frames drawn from the previous frame's shapes: {reused}");
    let (m, w) = stats(&renders);
    println!("full software-rendered frame (llvmpipe, GPU work on the CPU): median {m:.1} ms, worst {w:.1} ms");
}
