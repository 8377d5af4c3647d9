//! Headless UI tests (egui_kittest, software GL through `.cargo/config.toml`'s
//! `WGPU_BACKEND = "gl"`): the main workflow driven through the widgets,
//! and snapshots of the main views compared within a tolerance.
//! `UPDATE_SNAPSHOTS=1 cargo test -p thinplan-gui` rewrites the pictures.

use eframe::egui::Vec2;
use egui_kittest::kittest::Queryable as _;
use egui_kittest::{Harness, SnapshotOptions};
use thinplan_gui::{relations, Entity, ThinplanApp};
use thinplan_plan::{ConstraintKind, Stage, StiffnessKind};

fn harness(source: &str) -> Harness<'static, ThinplanApp> {
    let source = source.to_string();
    let mut h = Harness::builder()
        .with_size(Vec2::new(1400.0, 900.0))
        .wgpu()
        .build_eframe(move |cc| ThinplanApp::new(cc, &source));
    h.run_steps(2);
    h
}

fn run_all(h: &mut Harness<'static, ThinplanApp>) {
    h.get_by_label("Run all").click();
    h.run_steps(1);
    assert!(h.state().state.is_running() || h.state().state.plan().is_some());
    h.state_mut().state.wait_job();
    h.run_steps(3);
}

fn plan_bytes(h: &Harness<'static, ThinplanApp>) -> Vec<u8> {
    thinplan_plan::io::to_bytes(h.state().state.plan().expect("a plan"))
}

#[test]
fn main_workflow_select_refuse_undo_redo() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().expect("plan").clone();
    assert!(
        plan.stages_done.contains(&Stage::Determine),
        "{}",
        h.state().state.message
    );
    assert!(!plan.machining_features.is_empty());

    // Select a wall in the tree: the 3D and network views show it selected.
    let wall = plan
        .stiffness_features
        .iter()
        .find(|f| f.kind == StiffnessKind::Wall)
        .expect("a wall");
    let e = Entity::Stiffness(wall.id);
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(2);
    let app = h.state();
    assert_eq!(app.state.selection, Some(e));
    assert_eq!(app.viewport.drawn_selected(), vec![e]);
    assert_eq!(app.network.drawn_selected, vec![e]);

    // A constraint that would close a cycle is refused and the label shows.
    let c = plan
        .stiffness_constraints
        .iter()
        .find(|c| c.kind == ConstraintKind::Before)
        .expect("wing_rib has a before constraint")
        .clone();
    let before = plan_bytes(&h);
    let ok = h
        .state_mut()
        .state
        .add_constraint(c.second, c.first, ConstraintKind::Before);
    assert!(!ok);
    h.get_by_label(&relations::name(&plan, Entity::Stiffness(c.second)))
        .click();
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("refused:").count() >= 1);
    assert!(plan_bytes(&h) == before, "a refused edit changes nothing");

    // An edit through the inspector, then undo and redo restore the plan exactly.
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(2);
    // The form holds the current thickness: setting it again changes nothing.
    h.get_by_label("Set thickness").click();
    h.run_steps(1);
    assert!(plan_bytes(&h) == before, "a no-op edit changes nothing");
    let t = wall.thickness.unwrap_or(1.0) + 0.5;
    assert!(h.state_mut().state.set_thickness(wall.id, t));
    h.run_steps(2);
    let edited = plan_bytes(&h);
    assert!(edited != before);
    let edited_plan = h.state().state.plan().unwrap().clone();
    assert!(
        !edited_plan.stages_done.contains(&Stage::Sequence),
        "downstream invalidated"
    );
    assert!(
        edited_plan.stages_done.contains(&Stage::Recognise),
        "upstream kept"
    );
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before, "plans differ");
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "plans differ");
    // Re-running recomputes the invalidated stages.
    run_all(&mut h);
    assert!(h
        .state()
        .state
        .plan()
        .unwrap()
        .stages_done
        .contains(&Stage::Determine));
    // ... and undo still walks back through all of it.
    while h.state_mut().state.undo() {}
    assert_eq!(
        h.state().state.plan().unwrap().stages_done,
        vec![Stage::Import, Stage::Setup]
    );
}

#[test]
fn cycle_refusal_names_the_cycle_and_add_remove_are_undoable() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let before = plan_bytes(&h);
    let c = plan
        .stiffness_constraints
        .iter()
        .find(|c| c.kind == ConstraintKind::Before)
        .expect("a before constraint")
        .clone();
    let st = &mut h.state_mut().state;
    assert!(!st.add_constraint(c.second, c.first, ConstraintKind::Before));
    let refusal = st.refusal.clone().unwrap();
    assert!(
        refusal.contains(&c.first.to_string()) && refusal.contains(&c.second.to_string()),
        "{refusal}"
    );
    // Removing a constraint invalidates determine and is undoable.
    let i = plan
        .stiffness_constraints
        .iter()
        .position(|x| *x == c)
        .unwrap();
    assert!(st.remove_constraint(i));
    assert!(!st.plan().unwrap().stages_done.contains(&Stage::Determine));
    assert!(st.undo());
    assert!(thinplan_plan::io::to_bytes(st.plan().unwrap()) == before);
}

#[test]
fn simulation_and_save_open() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    h.get_by_label("Sequence simulation").click();
    h.run_steps(2);
    assert_eq!(h.state().state.sim_step, Some(0));
    assert!(
        h.query_all_by_label_contains("deflection").count() >= 1 || {
            // tall_rib's first feature may be no wall step; the read-out names the cut.
            h.query_all_by_label_contains("cutting").count() >= 1
        }
    );
    let dir = std::env::temp_dir().join(format!("thinplan-gui-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.plan.json");
    let before = plan_bytes(&h);
    assert!(h.state_mut().state.save_plan(&path));
    assert!(
        h.state_mut().state.open_plan(&path),
        "{}",
        h.state().state.message
    );
    assert!(plan_bytes(&h) == before, "plans differ");
    let _ = std::fs::remove_dir_all(&dir);
}

fn snapshot_options() -> SnapshotOptions {
    // Software GL is deterministic on one machine; the tolerance absorbs
    // font hinting and rasteriser differences between Mesa versions.
    SnapshotOptions::new()
        .threshold(2.0)
        .max_failed_pixels(2000)
}

#[test]
fn snapshots_of_the_main_views() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let wall = plan
        .stiffness_features
        .iter()
        .find(|f| f.kind == StiffnessKind::Wall)
        .unwrap();
    let e = Entity::Stiffness(wall.id);
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(3);
    let mut results = egui_kittest::SnapshotResults::new();
    results.add(h.try_snapshot_options("gui_main", &snapshot_options()));
    // The simulation at a wall step, so the deflection read-out shows.
    let order = relations::machining_order(&plan);
    let k = {
        let st = &h.state().state;
        let knowledge = st.knowledge().unwrap();
        (order.len() / 2..order.len())
            .chain(0..order.len() / 2)
            .find(|&i| relations::deflection_at(&plan, knowledge, &order, i).is_some())
            .expect("a wall step")
    };
    h.state_mut().state.select(None);
    h.state_mut().simulate = true;
    h.state_mut().sim_index = k;
    h.run_steps(3);
    results.add(h.try_snapshot_options("gui_simulation", &snapshot_options()));
    results.unwrap();
}

#[test]
fn knowledge_errors_are_listed_with_their_place_and_nothing_is_lost() {
    let mut h = harness("builtin:tall_rib");
    let dir = std::env::temp_dir().join(format!("thinplan-gui-knowledge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // A copy of the built-in knowledge with one broken file.
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge");
    copy_dir(&src, &dir);
    std::fs::write(
        dir.join("sizing.ron"),
        "(\n  allowed_deflection: oops,\n)\n",
    )
    .unwrap();
    let before = plan_bytes(&h);
    let st = &mut h.state_mut().state;
    assert!(!st.load_knowledge(Some(&dir)));
    assert!(
        st.knowledge_status
            .errors
            .iter()
            .any(|e| e.contains("sizing.ron:2:")),
        "{:?}",
        st.knowledge_status.errors
    );
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("sizing.ron:2:").count() >= 1);
    assert!(plan_bytes(&h) == before, "a failed load changes nothing");
    // The built-in copy loads again.
    assert!(h.state_mut().state.load_knowledge(None));
    let _ = std::fs::remove_dir_all(&dir);
}

fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            std::fs::create_dir_all(&target).unwrap();
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}
